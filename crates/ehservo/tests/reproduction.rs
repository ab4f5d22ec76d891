//! Regression tests of the paper's reproduction (issue 3).
//!
//! Each band is around a value measured with this code (and, for Fig. 2,
//! cross-checked to 1e-9 against the independent NumPy implementation in
//! `tests/independent.rs`). The runs are deterministic, so the bands are
//! tight: ±1 % admits floating-point reordering and nothing else — a change
//! to an equation, a reading or a default moves these figures by far more.
//! The qualitative tests check the paper's claims as `ehservo reproduce`
//! scores them (docs/paper-notes.md P1–P6 discusses each).

use ehservo::metrics::Metrics;
use ehservo::reproduce::derived::CaseMetrics;
use ehservo::run::{run, Keep};
use ehservo::scenario::Scenario;
use std::path::Path;

fn paper(file: &str, set: &[&str]) -> Scenario {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper")
        .join(file);
    Scenario::load(&p, &set).unwrap()
}

fn metrics(file: &str, set: &[&str]) -> Metrics {
    run(&paper(file, set), Keep::Nothing).unwrap().metrics
}

fn case(file: &str, set: &[&str]) -> CaseMetrics {
    let s = paper(file, set);
    let r = run(&s, Keep::Every(1)).unwrap();
    let net = r.metrics.w_norm_max.is_some();
    CaseMetrics::from_trace(
        r.metrics,
        &r.trace,
        s.simulation.settle,
        s.simulation.horizon,
        1.0,
        net,
    )
}

fn within(what: &str, v: Option<f64>, want: f64, rel: f64) {
    let v = v.unwrap_or_else(|| panic!("{what}: undefined"));
    assert!(
        (v - want).abs() <= rel * want,
        "{what}: measured {v}, band {want} ± {:.1} %",
        100.0 * rel
    );
}

/// The chosen reading of the report: continuous at 1 ms, b fractions of b̄.
const CHOSEN: [&str; 3] = [
    "simulation.mode=continuous",
    "simulation.step=0.001",
    "uncertainty.b_reference=1",
];

#[test]
fn default_reading_figures() {
    // Sampled at 0.01 s, one RK4 step per sample, Δb = 0.5β (SPEC's reading).
    within(
        "fig2 e_max",
        metrics("fig2.toml", &[]).e_max_deg,
        0.2091,
        0.01,
    );
    within(
        "γ1 = 200 e_max",
        metrics("gamma1-200.toml", &[]).e_max_deg,
        0.1070,
        0.01,
    );
    within(
        "η = 0 e_max",
        metrics("eta0.toml", &[]).e_max_deg,
        0.0191,
        0.01,
    );
    within(
        "(ε0, ε1) = (1, 0.5)",
        metrics("eps-1-0.5.toml", &[]).e_max_deg,
        0.2063,
        0.01,
    );
    within(
        "(ε0, ε1) = (5, 2)",
        metrics("eps-5-2.toml", &[]).e_max_deg,
        0.1939,
        0.01,
    );
    within(
        "fig8 e_max",
        metrics("fig8.toml", &[]).e_max_deg,
        0.2646,
        0.01,
    );
    // The traditional VSC diverges: at 40 % bias after 1.77 s, on the Fig. 2
    // case after 0.09 s (the latter also in the independent implementation).
    assert_eq!(metrics("fig3.toml", &[]).diverged_at_s, Some(1.77));
    assert_eq!(metrics("vsc-fig2.toml", &[]).diverged_at_s, Some(0.09));
}

#[test]
fn the_chosen_reading_gives_the_papers_fig2_and_fig4_numbers() {
    // Paper: 0.08° and 0.05°. Measured 0.0757° and 0.0449°.
    let f2 = metrics("fig2.toml", &CHOSEN).e_max_deg;
    within("fig2 e_max (chosen reading)", f2, 0.0757, 0.01);
    within(
        "fig2 e_max against the paper's 0.08° ± 25 %",
        f2,
        0.08,
        0.25,
    );
    let g = metrics("gamma1-200.toml", &CHOSEN).e_max_deg;
    within("γ1 = 200 e_max (chosen reading)", g, 0.0449, 0.01);
    within("γ1 = 200 against the paper's 0.05° ± 25 %", g, 0.05, 0.25);
    // η = 0: smaller than Fig. 2 as the paper says, but not the paper's 0.05°.
    within(
        "η = 0 e_max (chosen reading)",
        metrics("eta0.toml", &CHOSEN).e_max_deg,
        0.0115,
        0.01,
    );
}

#[test]
fn gains_and_variations_move_the_error_the_way_the_paper_says() {
    for reading in [&[][..], &CHOSEN[..]] {
        let f2 = metrics("fig2.toml", reading).e_max_deg.unwrap();
        let g = metrics("gamma1-200.toml", reading).e_max_deg.unwrap();
        let e0 = metrics("eta0.toml", reading).e_max_deg.unwrap();
        let f8 = metrics("fig8.toml", reading).e_max_deg.unwrap();
        assert!(g < f2, "{reading:?}: γ1 = 200 gives {g} ≥ Fig. 2's {f2}");
        assert!(e0 < f2, "{reading:?}: η = 0 gives {e0} ≥ Fig. 2's {f2}");
        assert!(f8 > f2, "{reading:?}: Fig. 8 gives {f8} ≤ Fig. 2's {f2}");
    }
}

#[test]
fn the_traditional_vsc_diverges_only_with_the_coarse_step() {
    // The paper: unbounded on the Fig. 2 case. True when the law is sampled
    // at 0.01 s with one RK4 step per sample (either b reading) …
    assert!(metrics("vsc-fig2.toml", &[]).diverged);
    assert!(metrics("vsc-fig2.toml", &["uncertainty.b_reference=1"]).diverged);
    // … but the same law evaluated continuously at 1 ms stays bounded
    // (docs/paper-notes.md P3): a finding, kept here so it cannot change silently.
    assert!(!metrics("vsc-fig2.toml", &CHOSEN).diverged);
}

#[test]
fn weights_stay_bounded_with_eta_and_drift_without() {
    // 60 s runs. η = 0.25: ‖W‖ on a periodic orbit, no growth over the second
    // half (|w_drift| < 0.1 %); η = ᾱ = 0: ‖W‖ keeps growing (w_drift > 1 %
    // in the default reading, measured +12 %).
    for reading in [&[][..], &["uncertainty.b_reference=1"][..]] {
        let bounded = case("abar5.toml", reading);
        let drift = case("eta0-abar0.toml", reading);
        let b = bounded.w_drift.unwrap();
        let d = drift.w_drift.unwrap();
        assert!(b.abs() < 1e-3, "{reading:?}: η = 0.25 drift {b}");
        assert!(d > 0.01, "{reading:?}: η = ᾱ = 0 drift {d}");
        assert!(drift.base.w_norm_final.unwrap() > 2.0 * bounded.base.w_norm_final.unwrap());
    }
}

#[test]
fn the_nnbvsc_control_is_smoother_than_the_traditional_vsc() {
    // Compared where the VSC stays bounded (continuous at 1 ms): c[u] of the
    // NNBVSC (measured 0.0063) against the VSC's (0.53) at 40 % bias.
    let nn = metrics("fig2.toml", &CHOSEN).chattering.unwrap();
    let vsc = metrics("fig3.toml", &CHOSEN).chattering.unwrap();
    assert!(nn * 10.0 < vsc, "NNBVSC c[u] {nn}, VSC c[u] {vsc}");
}

#[test]
fn reproduce_writes_the_whole_report() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("rep");
    let opts = ehservo::reproduce::Options {
        paper_dir: Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper"),
        out: out.clone(),
        progress: false,
        skip_boundaries: false,
        skip_figures: false,
        // The manifest's 400 seeds of Fig. 8 are for the report; a few
        // exercise the same path here.
        seeds: Some(8),
    };
    let rep = ehservo::reproduce::reproduce(&opts).unwrap();
    // The chosen reading is the one with the most agreements.
    let best = rep.agreements.values().max().unwrap();
    assert_eq!(rep.agreements[&rep.primary_reading], *best);
    for f in ["report.md", "report.html", "results.json", "claims.csv"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    for fig in [
        "fig2",
        "fig3",
        "fig4",
        "fig5",
        "fig6",
        "fig7",
        "fig8",
        "vsc-breaking",
        "nnvsc-margin",
    ] {
        for ext in ["png", "svg"] {
            let p = out.join("figures").join(format!("{fig}.{ext}"));
            assert!(p.is_file(), "{} missing", p.display());
        }
    }
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    for section in [
        "## Findings",
        "## The paper's claims, measured",
        "## How much each ambiguity",
        "## The traditional VSC's breaking point",
        "## The NNBVSC's margin",
    ] {
        assert!(md.contains(section), "{section} missing");
    }
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.contains("data:image/png;base64,"),
        "figures are embedded"
    );
    assert!(!md.contains("NaN") && !html.contains("NaN"));
    // The traditional VSC's breaking point under the literal sampled reading,
    // R1 (bounds of Fig. 2): first unbounded at 0.3744 (bracket
    // 0.3738–0.3744 from the 0.005 scan), against the paper's "bounded at
    // 40 %, unbounded above 45 %".
    let b = rep
        .vsc_breaking
        .iter()
        .find(|b| {
            b.reading == "sampled"
                && b.bias_reading == Some(ehservo::reproduce::breaking::BiasReading::R1)
        })
        .unwrap();
    within(
        "VSC breaking point (sampled, R1)",
        b.found.bounded.first_fail,
        0.3743,
        0.002,
    );
    // Bounded is not tracking: the sampled VSC never keeps max |e| below
    // 0.5° (10 % of 5°) under R1; its e_max at zero bias is 6.6°.
    assert_eq!(b.found.tracking.first_fail, Some(0.0));
    assert_eq!(b.found.tracking.last_pass, None);
    // With Δb = β the sampled R1 boundary is not monotone: first unbounded
    // at 0.329, bounded again at 0.333, unbounded for good above 0.344.
    let b = rep
        .vsc_breaking
        .iter()
        .find(|b| {
            b.reading == "sampled-bfull"
                && b.bias_reading == Some(ehservo::reproduce::breaking::BiasReading::R1)
        })
        .unwrap();
    assert!(b.found.bounded.non_monotone);
    within(
        "first unbounded (sampled-bfull, R1)",
        b.found.bounded.first_fail,
        0.329,
        0.005,
    );
    within(
        "last bounded (sampled-bfull, R1)",
        b.found.bounded.last_pass,
        0.344,
        0.005,
    );
    assert!(b.found.bounded.transitions.len() >= 3);

    // Fig. 8 over seeds 0..7 under the chosen reading: collected in seed
    // order, so seed 1 is the manifest's own fig8 run.
    let st = &rep.stochastic;
    assert_eq!(st.reading, rep.primary_reading);
    assert_eq!(st.cases.len(), 1);
    assert_eq!(st.cases[0].case, "fig8");
    assert_eq!(st.cases[0].e_max_deg.len(), 8);
    let single = rep
        .runs
        .iter()
        .find(|r| r.case == "fig8" && r.reading == rep.primary_reading)
        .unwrap()
        .metrics
        .base
        .e_max_deg;
    assert_eq!(st.cases[0].e_max_deg[1], single);
    let ids: Vec<&str> = st.claims.iter().map(|c| c.claim.as_str()).collect();
    assert_eq!(ids, ["fig8-emax", "fig8-twice", "fig8-smooth"]);
    assert!(md.contains("## Claims on random cases, over many seeds"));
    assert!(out.join("figures/fig8-seeds.png").is_file());
}
