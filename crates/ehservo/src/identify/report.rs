//! What `identify` writes into `--out` (staged, then renamed):
//!
//! - `identified.toml`: the scenario (rotary data), ready for `run`,
//!   `tune` and `league`;
//! - `identify.json`: every estimate with its standard error, interval and
//!   status, the derived quantities, NRMSE on estimation and validation
//!   files, the residual tests, the bounds of A1, the settings;
//! - `frf.csv`: the nonparametric estimates and the fitted models'
//!   responses (one row per experiment and frequency);
//! - `fit.csv`: measured and simulated positions (one row per experiment
//!   and sample, estimation files first);
//! - `frf.png`/`.svg`, `fit.png`/`.svg`, `residuals.png`/`.svg`.

use super::frf::{bode, Frf};
use super::{oe, Outcome};
use crate::output::{Staging, SOFTWARE};
use crate::plot::{Dash, Figure, Panel, Series};
use anyhow::{Context, Result};
use realfft::num_complex::Complex64;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

/// A number for a CSV cell: never NaN or infinity (an empty cell instead,
/// which pandas and MATLAB read as missing).
fn cell(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// Whether the grey-box is the paper's rotary model, whose response
/// frf.csv gives (a linear axis's grey-box, the prior's cylinder, is
/// nonlinear and has no one response: `ehservo freq` on the identified
/// scenario measures it).
fn rotary_greybox(o: &Outcome) -> bool {
    o.greybox.is_some() && o.experiments[0].axis == super::data::Axis::Rotary
}

/// The fitted models' responses at the estimate's frequencies (the
/// zero-order-hold discrete response of the effective third order).
fn model_responses(o: &Outcome, i: usize, f: &[f64]) -> Vec<(&'static str, Vec<Complex64>)> {
    let h = o.experiments[i].h;
    let mut out = Vec::new();
    let a = super::effective_linear(
        &o.linear,
        o.linear_model.load_terms,
        o.linear_model.wavenumber,
    );
    out.push((
        "linear",
        oe::discrete_response([a[0], a[1], a[2]], a[3], h, f),
    ));
    if let Some(g) = o.greybox.as_ref().filter(|_| rotary_greybox(o)) {
        let nk = super::greybox::KEYS.len();
        let (p, l) = super::greybox::from_vec(&g.fit.values()[..nk], &o.prior.model().load);
        let e = super::greybox::effective(&p, &l);
        let b = ehservo_core::servo::NominalModel::new(p, l).b_at_rest();
        out.push(("greybox", oe::discrete_response(e, b, h, f)));
    }
    out
}

fn frf_csv(o: &Outcome) -> String {
    let unit = o.experiments[0].axis.unit();
    let mut s = String::new();
    let has_ind = o.frf.iter().any(|f| f.1.is_some());
    let mut head = vec![
        "experiment",
        "f_Hz",
        "h1_gain_dB",
        "h1_phase_deg",
        "h1_coherence",
    ];
    if has_ind {
        head.extend([
            "indirect_gain_dB",
            "indirect_phase_deg",
            "indirect_coherence",
        ]);
    }
    head.extend(["linear_gain_dB", "linear_phase_deg"]);
    if rotary_greybox(o) {
        head.extend(["greybox_gain_dB", "greybox_phase_deg"]);
    }
    let _ = writeln!(s, "{}", head.join(","));
    let _ = unit;
    for (i, (h1, ind)) in o.frf.iter().enumerate() {
        let (g1, p1) = bode(&h1.h);
        let ib = ind.as_ref().map(|f| bode(&f.h));
        let models: Vec<(Vec<f64>, Vec<f64>)> = model_responses(o, i, &h1.f_hz)
            .iter()
            .map(|(_, r)| bode(r))
            .collect();
        for k in 0..h1.f_hz.len() {
            let mut row = vec![
                format!("{}", i + 1),
                cell(h1.f_hz[k]),
                cell(g1[k]),
                cell(p1[k]),
                cell(h1.coherence[k]),
            ];
            if has_ind {
                match (&ib, ind) {
                    (Some((g, p)), Some(f)) => {
                        row.extend([cell(g[k]), cell(p[k]), cell(f.coherence[k])])
                    }
                    _ => row.extend([String::new(), String::new(), String::new()]),
                }
            }
            for (g, p) in &models {
                row.extend([cell(g[k]), cell(p[k])]);
            }
            let _ = writeln!(s, "{}", row.join(","));
        }
    }
    s
}

fn fit_csv(o: &Outcome) -> String {
    let unit = o.experiments[0].axis.unit();
    let mut s = String::new();
    let mut head = vec![
        "experiment".to_string(),
        "role".to_string(),
        "t_s".to_string(),
        "u_V".to_string(),
        format!("y_{unit}"),
        format!("y_linear_{unit}"),
    ];
    if o.greybox.is_some() {
        head.push(format!("y_greybox_{unit}"));
    }
    let _ = writeln!(s, "{}", head.join(","));
    let groups = [
        ("estimation", &o.experiments, &o.linear.estimation),
        ("validation", &o.validation, &o.linear.validation),
    ];
    for (gi, (role, exps, lin)) in groups.iter().enumerate() {
        for (i, e) in exps.iter().enumerate() {
            let g = o.greybox.as_ref().map(|g| {
                if gi == 0 {
                    &g.estimation[i]
                } else {
                    &g.validation[i]
                }
            });
            for k in 0..e.len() {
                let mut row = vec![
                    format!("{}", i + 1),
                    role.to_string(),
                    cell(e.t0 + k as f64 * e.h),
                    cell(e.u.values[k]),
                    cell(e.y.values[k]),
                    cell(lin[i].sim.y.get(k).copied().unwrap_or(f64::NAN)),
                ];
                if let Some(g) = g {
                    row.push(cell(g.sim.y.get(k).copied().unwrap_or(f64::NAN)));
                }
                let _ = writeln!(s, "{}", row.join(","));
            }
        }
    }
    s
}

fn json(o: &Outcome, opts: &super::Options) -> serde_json::Value {
    let files = |exps: &[super::data::Experiment]| -> Vec<serde_json::Value> {
        exps.iter()
            .map(|e| {
                serde_json::json!({
                    "file": e.file,
                    "rows": e.len(),
                    "period_s": e.h,
                    "t0_s": e.t0,
                    "axis": e.axis,
                    "columns": {
                        "input": e.u.column,
                        "output": e.y.column,
                        "reference": e.reference.as_ref().map(|c| &c.column),
                        "pressure": e.pressure.as_ref().map(|c| &c.column),
                        "velocity": e.velocity.as_ref().map(|c| &c.column),
                    },
                })
            })
            .collect()
    };
    let frf: Vec<serde_json::Value> = o
        .frf
        .iter()
        .enumerate()
        .map(|(i, (h1, ind))| {
            serde_json::json!({
                "experiment": i + 1,
                "window": "Hann (periodic)",
                "overlap": 0.5,
                "detrend": "linear, per segment",
                "segment_samples": h1.segment,
                "averages": h1.averages,
                "resolution_Hz": h1.f_hz.first(),
                "methods": if ind.is_some() { vec!["H1", "indirect"] } else { vec!["H1"] },
            })
        })
        .collect();
    serde_json::json!({
        "software": SOFTWARE,
        "estimation": files(&o.experiments),
        "validation": files(&o.validation),
        "axis": o.experiments[0].axis,
        "settings": {
            "columns": opts.map,
            "period_tolerance": opts.read.tolerance,
            "identifiability_threshold": opts.fit.ident_threshold,
            "max_evaluations": opts.fit.max_evaluations,
            "residual_lags": opts.lags,
            "load_terms": opts.load_terms,
            "load_wavenumber": o.linear_model.wavenumber,
            "prior": opts.prior.as_ref().map(|p| p.display().to_string()),
            "set": opts.set,
            "fix": opts.fix,
            "bootstrap": opts.bootstrap,
            "seed": opts.seed,
        },
        "frf": frf,
        "linear": o.linear,
        "greybox": o.greybox,
        "bounds": o.bounds,
        "scenario": o.scenario.as_ref().map(|_| "identified.toml"),
        "notes": o.notes,
    })
}

/// log10 of the positive frequencies (the plots' x axis).
fn lg(f: &[f64]) -> Vec<f64> {
    f.iter().map(|v| v.log10()).collect()
}

fn frf_figure(o: &Outcome) -> Figure {
    let (h1, ind): &(Frf, Option<Frf>) = &o.frf[0];
    let x = lg(&h1.f_hz);
    let (g1, p1) = bode(&h1.h);
    let unit = o.experiments[0].axis.unit();
    let mut gain = vec![Series::new("H1 (Welch)", x.clone(), g1, 0).dash(Dash::Points)];
    let mut phase = vec![Series::new("H1 (Welch)", x.clone(), p1, 0).dash(Dash::Points)];
    if let Some(f) = ind {
        let (g, p) = bode(&f.h);
        gain.push(Series::new("indirect (from r)", x.clone(), g, 4).dash(Dash::Points));
        phase.push(Series::new("indirect (from r)", x.clone(), p, 4).dash(Dash::Points));
    }
    for (j, (name, r)) in model_responses(o, 0, &h1.f_hz).into_iter().enumerate() {
        let (g, p) = bode(&r);
        gain.push(Series::new(format!("{name} model"), x.clone(), g, 1 + j));
        phase.push(Series::new(format!("{name} model"), x.clone(), p, 1 + j));
    }
    let coh = vec![Series::new("γ² (H1)", x.clone(), h1.coherence.clone(), 0)];
    Figure {
        title: format!(
            "{}: frequency response, Welch (Hann, {} samples, 50 % overlap, {} averages)",
            o.experiments[0].file, h1.segment, h1.averages
        ),
        rows: 3,
        cols: 1,
        size: (1100, 1000),
        panels: vec![
            Panel {
                title: "gain".into(),
                x_label: "log10 f (Hz)".into(),
                y_label: format!("gain (dB re 1 {unit}/V)"),
                series: gain,
                ..Default::default()
            },
            Panel {
                title: "phase".into(),
                x_label: "log10 f (Hz)".into(),
                y_label: "phase (deg)".into(),
                series: phase,
                ..Default::default()
            },
            Panel {
                title: "coherence".into(),
                x_label: "log10 f (Hz)".into(),
                y_label: "γ² (–)".into(),
                series: coh,
                y_range: Some((0.0, 1.05)),
                ..Default::default()
            },
        ],
        footer: String::new(),
    }
}

fn fit_figure(o: &Outcome) -> Figure {
    let unit = o.experiments[0].axis.unit();
    let mut panels = Vec::new();
    let mut add = |title: String,
                   e: &super::data::Experiment,
                   lin: &super::ExperimentFit,
                   g: Option<&super::ExperimentFit>| {
        let t = e.times();
        let mut s = vec![
            Series::new("measured", t.clone(), e.y.values.clone(), 9),
            Series::new(
                format!("linear ({:.1} % fit)", lin.fit_pct),
                t.clone(),
                lin.sim.y.clone(),
                1,
            )
            .dash(Dash::Dashed),
        ];
        if let Some(g) = g {
            s.push(
                Series::new(
                    format!("grey-box ({:.1} % fit)", g.fit_pct),
                    t,
                    g.sim.y.clone(),
                    2,
                )
                .dash(Dash::DashDot),
            );
        }
        panels.push(Panel {
            title,
            x_label: "t (s)".into(),
            y_label: format!("y ({unit})"),
            series: s,
            ..Default::default()
        });
    };
    add(
        format!("estimation: {}", o.experiments[0].file),
        &o.experiments[0],
        &o.linear.estimation[0],
        o.greybox.as_ref().map(|g| &g.estimation[0]),
    );
    if let Some(v) = o.validation.first() {
        add(
            format!("validation: {}", v.file),
            v,
            &o.linear.validation[0],
            o.greybox.as_ref().map(|g| &g.validation[0]),
        );
    }
    let rows = panels.len();
    Figure {
        title: "measured against simulated output (the model driven by the logged command)".into(),
        rows,
        cols: 1,
        size: (1100, 420 * rows as u32),
        panels,
        footer: String::new(),
    }
}

fn residual_figure(o: &Outcome) -> Figure {
    let best = o.greybox.as_ref().unwrap_or(&o.linear);
    let t = &best.estimation[0].residual_tests;
    let m = t.lags as f64;
    let lags: Vec<f64> = (1..=t.lags).map(|k| k as f64).collect();
    let cl: Vec<f64> = (-(t.lags as isize)..=t.lags as isize)
        .map(|k| k as f64)
        .collect();
    let band = |x: &[f64]| {
        Series::band(
            "99 % band",
            x.to_vec(),
            vec![-t.band_99; x.len()],
            vec![t.band_99; x.len()],
            7,
        )
    };
    Figure {
        title: format!(
            "{} model residuals on {}",
            best.model, o.experiments[0].file
        ),
        rows: 2,
        cols: 1,
        size: (1000, 800),
        panels: vec![
            Panel {
                title: format!(
                    "autocorrelation (Ljung–Box Q = {:.1}, χ²({}) 95 % = {:.1}: {})",
                    t.ljung_box_q,
                    t.lags,
                    t.chi2_95,
                    if t.white { "white" } else { "not white" }
                ),
                x_label: "lag (samples)".into(),
                y_label: "r_e (–)".into(),
                series: vec![
                    band(&lags),
                    Series::new("r_e(τ)", lags.clone(), t.autocorrelation.clone(), 0)
                        .dash(Dash::Points),
                ],
                x_range: Some((0.0, m + 1.0)),
                ..Default::default()
            },
            Panel {
                title: format!(
                    "cross-correlation with the input ({})",
                    if t.independent_of_input {
                        "inside the band"
                    } else {
                        "outside the band"
                    }
                ),
                x_label: "lag (samples, > 0: input leads)".into(),
                y_label: "r_eu (–)".into(),
                series: vec![
                    band(&cl),
                    Series::new("r_eu(τ)", cl.clone(), t.cross_correlation.clone(), 1)
                        .dash(Dash::Points),
                ],
                ..Default::default()
            },
        ],
        footer: String::new(),
    }
}

/// Writes every output of `o` into `out` (staged; nothing is left on failure).
pub fn write(o: &Outcome, opts: &super::Options, out: &Path, plots: bool) -> Result<Vec<PathBuf>> {
    let stage = Staging::new(out)?;
    let dir = stage.path().to_path_buf();
    let mut files = Vec::new();
    let mut put = |name: &str, text: &str| -> Result<()> {
        let p = dir.join(name);
        fs::write(&p, text).with_context(|| format!("writing {}", p.display()))?;
        files.push(out.join(name));
        Ok(())
    };
    if let Some(s) = &o.scenario {
        put("identified.toml", &s.to_toml())?;
    }
    put(
        "identify.json",
        &(serde_json::to_string_pretty(&json(o, opts))? + "\n"),
    )?;
    put("frf.csv", &frf_csv(o))?;
    put("fit.csv", &fit_csv(o))?;
    if plots {
        for (name, fig) in [
            ("frf", frf_figure(o)),
            ("fit", fit_figure(o)),
            ("residuals", residual_figure(o)),
        ] {
            fig.png(&dir.join(format!("{name}.png")))?;
            fig.svg(&dir.join(format!("{name}.svg")))?;
            files.push(out.join(format!("{name}.png")));
            files.push(out.join(format!("{name}.svg")));
        }
    }
    stage.commit()?;
    Ok(files)
}

/// Why a fit stopped, in words.
pub fn stop_reason(f: &super::fit::FitReport) -> String {
    match f.termination.as_str() {
        _ if f.diverged => "the model diverged at its start".into(),
        "LostPatience" => "out of evaluations (--max-evaluations)".into(),
        t => format!("stopped: {t}"),
    }
}

/// The models that did not converge, with why: empty when every fit did.
pub fn not_converged(o: &Outcome) -> Vec<String> {
    std::iter::once(&o.linear)
        .chain(o.greybox.as_ref())
        .filter(|r| !r.fit.converged)
        .map(|r| {
            format!(
                "the {} fit did not converge ({}, after {} evaluations)",
                r.model,
                stop_reason(&r.fit),
                r.fit.evaluations
            )
        })
        .collect()
}

/// A few lines for the terminal.
pub fn summary(o: &Outcome) -> String {
    let mut s = String::new();
    let unit = o.experiments[0].axis.unit();
    for r in std::iter::once(&o.linear).chain(o.greybox.as_ref()) {
        if !r.fit.converged {
            // Not a result: where it stopped is in identify.json.
            let _ = writeln!(
                s,
                "{} model: DID NOT CONVERGE ({}, after {} evaluations, start: {}): no estimates (where it stopped: identify.json)",
                r.model,
                stop_reason(&r.fit),
                r.fit.evaluations,
                r.start
            );
            continue;
        }
        let _ = writeln!(
            s,
            "{} model ({} evaluations, start: {}):",
            r.model, r.fit.evaluations, r.start
        );
        for e in &r.fit.estimates {
            let status = match e.status {
                super::fit::Status::Free => match (e.se, e.relative_se) {
                    (Some(se), Some(rel)) => format!("± {se:.4e} ({:.2} %)", 100.0 * rel.abs()),
                    (Some(se), None) => format!("± {se:.4e}"),
                    _ => "(no standard error)".into(),
                },
                super::fit::Status::Fixed => "fixed".into(),
                super::fit::Status::Unidentifiable => "UNIDENTIFIABLE: held at its prior".into(),
            };
            if e.status != super::fit::Status::Fixed || !e.nuisance {
                if e.status == super::fit::Status::Fixed && r.model == "greybox" {
                    continue;
                }
                let _ = writeln!(
                    s,
                    "  {:<16} {:>14.6e} {:<12} {status}",
                    e.key, e.value, e.unit
                );
            }
        }
        for d in &r.derived {
            let _ = writeln!(
                s,
                "  {:<16} {:>14.6e} {:<12} {}",
                d.key,
                d.value,
                d.unit,
                d.se.map_or(String::new(), |se| format!("± {se:.4e}"))
            );
        }
        for (role, fits) in [("estimation", &r.estimation), ("validation", &r.validation)] {
            for f in fits.iter() {
                let t = &f.residual_tests;
                let _ = writeln!(
                    s,
                    "  {role} {}: fit {:.2} % (NRMSE {:.3} %), residual RMS {:.3e} {unit}, residuals {} (Q {:.1} vs {:.1}), {} of the input",
                    f.file,
                    f.fit_pct,
                    f.nrmse_pct,
                    f.residual_rms,
                    if t.white { "white" } else { "NOT white" },
                    t.ljung_box_q,
                    t.chi2_95,
                    if t.independent_of_input { "independent" } else { "NOT independent" }
                );
            }
        }
    }
    if let Some(b) = &o.bounds {
        let _ = writeln!(
            s,
            "bounds of A1 ({}, {} model): bound_a = {:.4} (α_i/|ā_i| = {:.4}, {:.4}, {:.4}{}), bound_b = {:.4}",
            b.method,
            b.model,
            b.bound_a,
            b.fractions[0],
            b.fractions[1],
            b.fractions[2],
            if b.counted.iter().all(|c| *c) { String::new() } else { format!("; counted {:?}", b.counted) },
            b.bound_b
        );
    }
    for n in &o.notes {
        let _ = writeln!(s, "note: {n}");
    }
    s
}
