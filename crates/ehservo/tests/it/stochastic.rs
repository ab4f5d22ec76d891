//! Claims on random cases over many seeds (issue #12 item 4): quantiles,
//! the share in the band and the median verdict against hand-computed
//! values, and the manifest's `[stochastic]` table.

use ehservo::metrics::Metrics;
use ehservo::reproduce::derived::CaseMetrics;
use ehservo::reproduce::manifest::{Claim, ClaimKind, Manifest};
use ehservo::reproduce::stochastic::{distribution, judge, quantile, Band};

fn close(a: Option<f64>, b: f64) {
    let a = a.expect("defined");
    assert!((a - b).abs() < 1e-12, "{a} != {b}");
}

#[test]
fn quantiles_interpolate_between_order_statistics() {
    let v = [1.0, 2.0, 3.0, 4.0];
    // h = (n − 1)p = 1.5 → 2 + 0.5·(3 − 2)
    close(quantile(&v, 0.5), 2.5);
    // h = 0.15 → 1 + 0.15·1
    close(quantile(&v, 0.05), 1.15);
    // h = 2.85 → 3 + 0.85·1
    close(quantile(&v, 0.95), 3.85);
    close(quantile(&v, 0.0), 1.0);
    close(quantile(&v, 1.0), 4.0);
    close(quantile(&[7.0], 0.3), 7.0);
    assert_eq!(quantile(&[], 0.5), None);
}

#[test]
fn distribution_counts_undefined_seeds_outside_the_band() {
    let band = Band {
        lo: 0.12,
        hi: 0.20,
        strict: false,
    };
    let q = [Some(0.25), Some(0.15), None, Some(0.20), Some(0.10)];
    let d = distribution(&q, band, 1);
    assert_eq!((d.n, d.n_undefined, d.n_diverged), (5, 1, 1));
    // defined, sorted: 0.10 0.15 0.20 0.25; median h = 1.5 → 0.175
    close(d.median, 0.175);
    // p05: h = 0.15 → 0.10 + 0.15·0.05; p95: h = 2.85 → 0.20 + 0.85·0.05
    close(d.p05, 0.1075);
    close(d.p95, 0.2425);
    // in the band: 0.15 and 0.20 (closed) of all five seeds
    assert!((d.share_in_band - 0.4).abs() < 1e-15);
    // Half the seeds undefined: no median, no verdict.
    let d = distribution(&[Some(0.15), None], band, 1);
    assert_eq!(d.median, None);
    assert!((d.share_in_band - 0.5).abs() < 1e-15);
    // A strict band excludes its ends.
    let less = Band {
        lo: f64::NEG_INFINITY,
        hi: 0.0,
        strict: true,
    };
    assert!(!less.contains(0.0) && less.contains(-1e-9));
}

fn cm(e_max: Option<f64>, chattering: Option<f64>) -> CaseMetrics {
    let base: Metrics = serde_json::from_value(serde_json::json!({
        "e_max_deg": e_max,
        "chattering": chattering,
        "diverged": e_max.is_none(),
        "diverged_at_s": if e_max.is_none() { Some(1.0) } else { None },
        "samples": 1001,
    }))
    .unwrap();
    CaseMetrics::from(base)
}

fn claim(kind: ClaimKind, other: Option<&str>, metric: &str, value: Option<f64>) -> Claim {
    Claim {
        id: "c".into(),
        source: String::new(),
        text: String::new(),
        kind,
        case: "rand".into(),
        other: other.map(str::to_string),
        metric: Some(metric.into()),
        value,
        tol: Some(0.25),
        note: String::new(),
    }
}

#[test]
fn claims_are_judged_on_the_median_and_the_share() {
    // The random case's e_max over five seeds; seed 3 diverged.
    let e = [Some(0.10), Some(0.14), Some(0.21), None, Some(0.19)];
    let m = |case: &str, k: usize| -> Option<CaseMetrics> {
        match case {
            "rand" => Some(cm(e[k], e[k].map(|_| 0.01))),
            "fixed" => Some(cm(Some(0.08), Some(0.5))),
            _ => None,
        }
    };
    // approx 0.16 ± 25 %: band [0.12, 0.20]; defined 0.10 0.14 0.19 0.21,
    // median 0.165 (in), in band 0.14 and 0.19: 2 of 5.
    let a = judge(
        &claim(ClaimKind::Approx, None, "e_max_deg", Some(0.16)),
        5,
        &m,
    );
    close(a.dist.median, 0.165);
    assert!((a.dist.share_in_band - 0.4).abs() < 1e-15);
    assert!(a.agree);
    assert_eq!((a.dist.n_undefined, a.dist.n_diverged), (1, 1));
    assert_eq!(a.per_seed[3], None);

    // ratio to a fixed 0.08, 2 ± 25 %: ratios 1.25 1.75 2.625 — 2.375;
    // median (1.75 + 2.375)/2 = 2.0625 in [1.5, 2.5]; in band 1.75, 2.375.
    let r = judge(
        &claim(ClaimKind::Ratio, Some("fixed"), "e_max_deg", Some(2.0)),
        5,
        &m,
    );
    close(r.dist.median, 2.0625);
    assert!((r.dist.share_in_band - 0.4).abs() < 1e-15);
    assert!(r.agree);

    // less on chattering: 0.01 − 0.5 < 0 for every bounded seed.
    let l = judge(
        &claim(ClaimKind::Less, Some("fixed"), "chattering", None),
        5,
        &m,
    );
    close(l.dist.median, -0.49);
    assert!((l.dist.share_in_band - 0.8).abs() < 1e-15);
    assert!(l.agree);
    // greater: the opposite, never in the band.
    let g = judge(
        &claim(ClaimKind::Greater, Some("fixed"), "chattering", None),
        5,
        &m,
    );
    assert!(!g.agree && g.dist.share_in_band == 0.0);

    // bounded: 4 of 5 seeds bounded, median 1.
    let mut b = claim(ClaimKind::Bounded, None, "e_max_deg", None);
    b.metric = None;
    let b = judge(&b, 5, &m);
    assert!(b.agree);
    assert!((b.dist.share_in_band - 0.8).abs() < 1e-15);
    assert_eq!(b.dist.n_undefined, 0);

    // approx 0.30 ± 25 %: median 0.165 outside; no seed inside.
    let far = judge(
        &claim(ClaimKind::Approx, None, "e_max_deg", Some(0.30)),
        5,
        &m,
    );
    assert!(!far.agree && far.dist.share_in_band == 0.0);
}

fn manifest_with(stochastic: &str) -> anyhow::Result<Manifest> {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("manifest.toml");
    std::fs::write(
        &p,
        format!(
            "claim = []\n[[reading]]\nid = \"r\"\nlabel = \"r\"\nset = []\n\
             refine = {{ key = \"simulation.substeps\", levels = [1, 2, 4] }}\n\
             [[case]]\nid = \"fig8\"\nfile = \"fig8.toml\"\n{stochastic}"
        ),
    )
    .unwrap();
    Manifest::load(&p)
}

#[test]
fn the_manifest_sets_the_number_of_seeds() {
    let m = manifest_with("[stochastic]\nseeds = 12\n").unwrap();
    assert_eq!(m.stochastic.unwrap().seeds, 12);
    assert!(manifest_with("").unwrap().stochastic.is_none());
    for bad in ["seeds = 0", "seeds = 1001", "seed = 4"] {
        let e = manifest_with(&format!("[stochastic]\n{bad}\n"));
        assert!(e.is_err(), "{bad} accepted");
    }
}
