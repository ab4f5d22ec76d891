//! Regression tests of the paper's reproduction (issue 3).
//!
//! Each band is around a value measured with this code (and, for Fig. 2,
//! cross-checked to 1e-9 against the independent NumPy implementation in
//! `tests/it/independent.rs`). The runs are deterministic, so the bands are
//! tight: ±1 % admits floating-point reordering and nothing else — a change
//! to an equation, a reading or a default moves these figures by far more.
//! The qualitative tests check the paper's claims as `ehservo reproduce`
//! scores them (docs/paper-notes.md P1–P6 discusses each).

use ehservo::metrics::Metrics;
use ehservo::reproduce::derived::CaseMetrics;
use ehservo::run::{run, Keep};
use ehservo::scenario::Loop;
use std::path::Path;

fn paper(file: &str, set: &[&str]) -> Loop {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper")
        .join(file);
    Loop::load(&p, &set).unwrap()
}

fn metrics(file: &str, set: &[&str]) -> Metrics {
    run(&paper(file, set), Keep::Nothing).metrics
}

fn case(file: &str, set: &[&str]) -> CaseMetrics {
    let s = paper(file, set);
    let r = run(&s, Keep::Every(1));
    let net = r.metrics.w_norm_max.is_some();
    CaseMetrics::from_trace(r.metrics, &r.trace, s.settle(), s.horizon(), 1.0, net)
}

fn within(what: &str, v: Option<f64>, want: f64, rel: f64) {
    let v = v.unwrap_or_else(|| panic!("{what}: undefined"));
    assert!(
        (v - want).abs() <= rel * want,
        "{what}: measured {v}, band {want} ± {:.1} %",
        100.0 * rel
    );
}

/// Continuous at 1 ms (converged for the NNBVSC cases: the 2.5 ms and
/// 1.25 ms levels of the report agree to 1e-4), b fractions of b̄.
const CHOSEN: [&str; 3] = [
    "simulation.mode=continuous",
    "simulation.step=0.001",
    "uncertainty.b_reference=1",
];

#[test]
fn default_reading_figures() {
    // Sampled at 0.01 s, one RK4 step per sample, Δb = 0.5β (SPEC's reading).
    within("fig2 e_max", metrics("fig2.toml", &[]).e_max, 0.2091, 0.01);
    within(
        "γ1 = 200 e_max",
        metrics("gamma1-200.toml", &[]).e_max,
        0.1070,
        0.01,
    );
    within("η = 0 e_max", metrics("eta0.toml", &[]).e_max, 0.0191, 0.01);
    within(
        "(ε0, ε1) = (1, 0.5)",
        metrics("eps-1-0.5.toml", &[]).e_max,
        0.2063,
        0.01,
    );
    within(
        "(ε0, ε1) = (5, 2)",
        metrics("eps-5-2.toml", &[]).e_max,
        0.1939,
        0.01,
    );
    within("fig8 e_max", metrics("fig8.toml", &[]).e_max, 0.2646, 0.01);
    // The traditional VSC diverges: at 40 % bias after 1.77 s, on the Fig. 2
    // case after 0.09 s (the latter also in the independent implementation).
    assert_eq!(metrics("fig3.toml", &[]).diverged_at_s, Some(1.77));
    assert_eq!(metrics("vsc-fig2.toml", &[]).diverged_at_s, Some(0.09));
}

#[test]
fn the_continuous_reading_with_db_beta_gives_the_papers_fig2_and_fig4_numbers() {
    // Paper: 0.08° and 0.05°. Measured 0.0757° and 0.0449°.
    let f2 = metrics("fig2.toml", &CHOSEN).e_max;
    within("fig2 e_max (chosen reading)", f2, 0.0757, 0.01);
    within(
        "fig2 e_max against the paper's 0.08° ± 25 %",
        f2,
        0.08,
        0.25,
    );
    let g = metrics("gamma1-200.toml", &CHOSEN).e_max;
    within("γ1 = 200 e_max (chosen reading)", g, 0.0449, 0.01);
    within("γ1 = 200 against the paper's 0.05° ± 25 %", g, 0.05, 0.25);
    // η = 0: smaller than Fig. 2 as the paper says, but not the paper's 0.05°.
    within(
        "η = 0 e_max (chosen reading)",
        metrics("eta0.toml", &CHOSEN).e_max,
        0.0115,
        0.01,
    );
}

#[test]
fn gains_and_variations_move_the_error_the_way_the_paper_says() {
    for reading in [&[][..], &CHOSEN[..]] {
        let f2 = metrics("fig2.toml", reading).e_max.unwrap();
        let g = metrics("gamma1-200.toml", reading).e_max.unwrap();
        let e0 = metrics("eta0.toml", reading).e_max.unwrap();
        let f8 = metrics("fig8.toml", reading).e_max.unwrap();
        assert!(g < f2, "{reading:?}: γ1 = 200 gives {g} ≥ Fig. 2's {f2}");
        assert!(e0 < f2, "{reading:?}: η = 0 gives {e0} ≥ Fig. 2's {f2}");
        assert!(f8 > f2, "{reading:?}: Fig. 8 gives {f8} ≤ Fig. 2's {f2}");
    }
}

#[test]
fn the_printed_sampled_setup_is_not_converged() {
    // Sampled at 0.01 s, Fig. 2, Δb = 0.5β: 1 RK4 sub-step per sample gives
    // 0.2091°, 2, 4 and 8 sub-steps 0.2127°, 0.2128°, 0.2128° — the plant
    // integration error of the printed set-up is 0.0037° (1.7 %), and the
    // converged value is reached at 4 sub-steps (RK4: the change from 2 to 4
    // is 1/16 of the change from 1 to 2, within 20 % for round-off).
    let e: Vec<f64> = [1, 2, 4, 8]
        .iter()
        .map(|n| {
            metrics("fig2.toml", &[&format!("simulation.substeps={n}")])
                .e_max
                .unwrap()
        })
        .collect();
    let (d1, d2, d3) = (e[1] - e[0], e[2] - e[1], e[3] - e[2]);
    assert!(
        d1.abs() > 0.003 && d1.abs() < 0.0045,
        "1 → 2 sub-steps: {d1}"
    );
    assert!(d2.abs() < d1.abs() / 4.0, "2 → 4: {d2} against {d1}");
    assert!(d3.abs() < 1e-4, "4 → 8: {d3}");
}

#[test]
fn the_traditional_vsc_sampled_with_a_converged_plant_is_bounded_but_does_not_track() {
    // Fig. 3 (40 % bias) and the Fig. 2 case: with one RK4 step per sample
    // the sampled sgn law diverges; with 2 or more sub-steps it stays bounded,
    // but its max |e| after 2 s is 13.1° (Fig. 3) and 10.3° (Fig. 2 case)
    // at 8 sub-steps: larger than the 5° reference itself.
    assert!(metrics("fig3.toml", &[]).diverged);
    for (file, want) in [("fig3.toml", 13.10), ("vsc-fig2.toml", 10.34)] {
        let m = metrics(file, &["simulation.substeps=8"]);
        assert!(!m.diverged, "{file}");
        within(file, m.e_max, want, 0.01);
        assert!(m.e_max.unwrap() > 5.0);
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
    // The paper's manifest and cases, with two readings and short ladders
    // (the shipped ones run for minutes; this checks the pipeline).
    let tmp = tempfile::tempdir().unwrap();
    let paper = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper");
    let dir = tmp.path().join("paper");
    std::fs::create_dir(&dir).unwrap();
    for e in std::fs::read_dir(&paper).unwrap() {
        let e = e.unwrap().path();
        std::fs::copy(&e, dir.join(e.file_name().unwrap())).unwrap();
    }
    let text = std::fs::read_to_string(paper.join("manifest.toml")).unwrap();
    let (a, b) = (
        text.find("# ---------------------------------------------------------------- readings")
            .unwrap(),
        text.find("# ---------------------------------------------------------------- cases")
            .unwrap(),
    );
    let readings = r#"
[[reading]]
id = "sampled"
label = "sampled"
set = ["simulation.mode=sampled", "simulation.step=0.01"]
refine = { key = "simulation.substeps", levels = [1, 2, 4] }

[[reading]]
id = "continuous-bfull"
label = "continuous, Δb = β"
set = ["simulation.mode=continuous", "uncertainty.b_reference=1.0"]
refine = { key = "simulation.step", levels = [0.005, 0.0025, 0.00125] }

[convergence]
rtol = 0.01
min_levels = 2
atol = { e_max_deg = 0.002, sigma_rms = 0.01, chattering = 0.01, w_drift = 0.001, e_hf_share = 0.005 }
"#;
    std::fs::write(
        dir.join("manifest.toml"),
        format!("{}{readings}{}", &text[..a], &text[b..]),
    )
    .unwrap();
    let out = tmp.path().join("rep");
    let opts = ehservo::reproduce::Options {
        paper_dir: dir,
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
        "## Convergence",
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
    // No NaN in the report's text. The embedded figures' base64 is left
    // out of the check: any three letters, "NaN" too, can appear in it.
    let text: String = html
        .split("data:image/png;base64,")
        .enumerate()
        .map(|(i, part)| match i {
            0 => part,
            _ => part.split_once('"').map_or("", |(_, rest)| rest),
        })
        .collect();
    assert!(
        text.len() < html.len() / 2,
        "the figures' base64 is left out"
    );
    assert!(!md.contains("NaN") && !text.contains("NaN"));
    // Every reading has its boundary searches, and every case its ladder.
    assert_eq!(rep.vsc_breaking.len(), 2 * rep.agreements.len());
    assert_eq!(rep.nn_margin.len(), rep.agreements.len());
    for r in &rep.runs {
        assert!(r.estimate.levels.len() >= 2, "{} {}", r.case, r.reading);
    }
    // Bounded is not tracking: sampled at 0.01 s with a converged plant and
    // the Fig. 2 bounds (R1), the VSC stays bounded over the whole scan but
    // never keeps max |e| below 0.5° (10 % of 5°): about 5.5° at zero bias.
    let b = rep
        .vsc_breaking
        .iter()
        .find(|b| {
            b.reading == "sampled"
                && b.bias_reading == Some(ehservo::reproduce::breaking::BiasReading::R1)
        })
        .unwrap();
    assert_eq!(b.found.bounded.first_fail, None);
    assert_eq!(b.found.tracking.first_fail, Some(0.0));
    assert_eq!(b.found.tracking.last_pass, None);
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
        .e_max;
    assert_eq!(st.cases[0].e_max_deg[1], single);
    let ids: Vec<&str> = st.claims.iter().map(|c| c.claim.as_str()).collect();
    assert_eq!(ids, ["fig8-emax", "fig8-twice", "fig8-smooth"]);
    assert!(md.contains("## Claims on random cases, over many seeds"));
    assert!(out.join("figures/fig8-seeds.png").is_file());
}

#[test]
fn the_continuous_vsc_is_an_ideal_sliding_mode() {
    // Fig. 3 (40 % bias), the sgn law in every RK4 stage: max |e| after 2 s
    // measured 0.0035° at h = 78.1 µs and 0.0017° at 39.1 µs. A sliding
    // mode's chattering amplitude is first order in the step, so halving h
    // halves the error (ratio 2; the band 1.6–2.5 admits the discrete
    // switching pattern), and it is far below the NNBVSC's 0.21° (P4).
    let at = |h: f64| {
        metrics(
            "fig3.toml",
            &[
                "simulation.mode=continuous",
                &format!("simulation.step={h:e}"),
            ],
        )
        .e_max
        .unwrap()
    };
    let (a, b) = (at(0.01 / 128.0), at(0.01 / 256.0));
    assert!((1.6..2.5).contains(&(a / b)), "{a} / {b}");
    assert!(a < 0.005, "{a}");
}

#[test]
fn the_fig2_run_violates_a5_and_leaves_remark_6s_set() {
    // Remark 6 with Wmax = 4 bounds ‖W‖ by about 10 (4 + 6.05 over Ω); the
    // run reaches 72. (19) with (21)–(22) needs ‖W̄‖ ≥ max (|Δ| − ε1)/‖Φ‖ − ε0,
    // measured 327 along this run (P8): far above Wmax = 4, so the band is
    // loose — anything over 100 shows the assumption fails.
    let s = paper("fig2.toml", &[]);
    let r = run(&s, Keep::Every(1));
    let d = ehservo::analysis::diagnostics(s.scenario(), &r.trace).unwrap();
    let w = &d.weights;
    assert!(!w.a5_holds);
    assert!(w.w_bar_required > 100.0, "{}", w.w_bar_required);
    assert!(w.w_norm_max > 50.0 && w.remark6_left_at_s.is_some());
    assert!(w.remark6_bound_at_w_max.unwrap() < 11.0);
}

#[test]
fn the_b_question_pairs_the_readings_that_differ_only_in_b() {
    let m = ehservo::reproduce::manifest::Manifest::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper/manifest.toml"),
    )
    .unwrap();
    assert_eq!(
        ehservo::reproduce::b_question::pairs(&m),
        vec![
            ("sampled", "sampled-bfull"),
            ("continuous", "continuous-bfull")
        ]
    );
}
