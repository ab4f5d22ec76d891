//! The paper's figures, rebuilt from the runs of the chosen reading: the
//! same panels, signals, units (degrees where the paper uses them) and line
//! styles as the paper's captions describe.

use super::breaking::Boundary;
use crate::plot::{Dash, Figure, Panel, Series};
use crate::run::RunResult;
use crate::simulation::Sample;
use std::collections::BTreeMap;

/// Longest series drawn; longer ones are reduced by min/max per bucket, which
/// keeps every peak (an SVG with 60 000 points per line helps nobody).
const MAX_POINTS: usize = 4000;

fn series(
    label: &str,
    trace: &[Sample],
    f: impl Fn(&Sample) -> f64,
    color: usize,
    dash: Dash,
) -> Series {
    let (x, y) = decimate(trace, &f);
    Series::new(label, x, y, color).dash(dash)
}

fn decimate(trace: &[Sample], f: &dyn Fn(&Sample) -> f64) -> (Vec<f64>, Vec<f64>) {
    if trace.len() <= MAX_POINTS {
        return (
            trace.iter().map(|s| s.t).collect(),
            trace.iter().map(f).collect(),
        );
    }
    let buckets = MAX_POINTS / 2;
    let per = trace.len().div_ceil(buckets);
    let (mut x, mut y) = (
        Vec::with_capacity(MAX_POINTS),
        Vec::with_capacity(MAX_POINTS),
    );
    for chunk in trace.chunks(per) {
        let (mut imin, mut imax) = (0, 0);
        for (i, s) in chunk.iter().enumerate() {
            if f(s) < f(&chunk[imin]) {
                imin = i;
            }
            if f(s) > f(&chunk[imax]) {
                imax = i;
            }
        }
        let (a, b) = if imin <= imax {
            (imin, imax)
        } else {
            (imax, imin)
        };
        x.push(chunk[a].t);
        y.push(f(&chunk[a]));
        if b != a {
            x.push(chunk[b].t);
            y.push(f(&chunk[b]));
        }
    }
    (x, y)
}

fn panel(title: &str, y_label: &str, series: Vec<Series>) -> Panel {
    Panel {
        title: title.into(),
        x_label: "t (s)".into(),
        y_label: y_label.into(),
        series,
        log_y: false,
    }
}

/// A panel of u(t) (V).
fn u_panel(title: &str, t: &[Sample]) -> Panel {
    panel(title, "u (V)", vec![series("", t, |s| s.u, 0, Dash::Solid)])
}

/// A panel of σ(t) (rad/s²).
fn sigma_panel(title: &str, t: &[Sample]) -> Panel {
    panel(
        title,
        "σ (rad/s²)",
        vec![series("", t, |s| s.part("sigma"), 0, Dash::Solid)],
    )
}

fn status(r: &RunResult) -> String {
    match r.outcome.diverged {
        Some(d) => format!(" — unbounded at t = {:.2} s", d.t),
        None => String::new(),
    }
}

fn e_deg(s: &Sample) -> f64 {
    s.e_deg()
}

/// A figure with its file stem and caption.
pub struct PaperFigure {
    /// File stem (`fig2` → fig2.png, fig2.svg).
    pub stem: String,
    /// Caption for the report.
    pub caption: String,
    /// The figure.
    pub figure: Figure,
}

/// Builds every figure whose cases are present in `runs`.
pub fn paper_figures(runs: &BTreeMap<String, RunResult>, reading_label: &str) -> Vec<PaperFigure> {
    let mut out = Vec::new();
    let get = |id: &str| runs.get(id);
    let size2x2 = (1400, 1000);

    if let Some(r) = get("fig2") {
        let t = &r.trace;
        out.push(PaperFigure {
            stem: "fig2".into(),
            caption: format!(
                "Fig. 2 — NNBVSC, 100 % a_i bias, Δb = 0.5β, Tl = 2 sin 4θ ({reading_label}){}",
                status(r)
            ),
            figure: Figure {
                title: format!(
                    "Fig. 2: NNBVSC, p = (90, 2600, 24000), η = 0.25, ᾱ = 5, γ1 = 100{}",
                    status(r)
                ),
                rows: 2,
                cols: 2,
                size: size2x2,
                panels: vec![
                    panel(
                        "(a) θd (···) and θ (—)",
                        "angle (deg)",
                        vec![
                            series("θd", t, |s| s.theta_d_deg(), 1, Dash::Dotted),
                            series("θ", t, |s| s.theta_deg(), 0, Dash::Solid),
                        ],
                    ),
                    u_panel("(b) u(t)", t),
                    sigma_panel("(c) σ(t)", t),
                    panel(
                        "(d) Σ Δa_i x_i − Δb u_eq + d − ξ (---) and WᵀΦ (—)",
                        "(rad/s³)",
                        vec![
                            series(
                                "uncertainty (19)",
                                t,
                                |s| s.part("uncertainty"),
                                1,
                                Dash::Dashed,
                            ),
                            series("WᵀΦ", t, |s| s.part("wphi"), 0, Dash::Solid),
                        ],
                    ),
                ],
            },
        });
    }

    if let Some(r) = get("fig3") {
        let t = &r.trace;
        out.push(PaperFigure {
            stem: "fig3".into(),
            caption: format!(
                "Fig. 3 — traditional VSC, 40 % bias, Tl = 2 sin 4θ ({reading_label}){}",
                status(r)
            ),
            figure: Figure {
                title: format!(
                    "Fig. 3: traditional VSC (Theorem 1), 40 % bias{}",
                    status(r)
                ),
                rows: 3,
                cols: 1,
                size: (1200, 1100),
                panels: vec![
                    panel(
                        "(a) θd − θ",
                        "e (deg)",
                        vec![series("", t, e_deg, 0, Dash::Solid)],
                    ),
                    u_panel("(b) u(t)", t),
                    sigma_panel("(c) σ(t)", t),
                ],
            },
        });
    }

    let fig4: Vec<(&str, &str, Dash)> = vec![
        ("fig2", "γ1 = 100, η = 0.25 (—)", Dash::Solid),
        ("gamma1-200", "γ1 = 200, η = 0.25 (---)", Dash::Dashed),
        ("eta0", "γ1 = 100, η = 0 (-·-)", Dash::DashDot),
    ];
    if fig4.iter().all(|(id, _, _)| runs.contains_key(*id)) {
        let s: Vec<Series> = fig4
            .iter()
            .enumerate()
            .map(|(i, (id, label, dash))| series(label, &runs[*id].trace, e_deg, i, *dash))
            .collect();
        out.push(PaperFigure {
            stem: "fig4".into(),
            caption: format!(
                "Fig. 4 — tracking error of the NNBVSC for three settings ({reading_label})"
            ),
            figure: Figure {
                title: "Fig. 4: tracking error θd − θ of the NNBVSC, Fig. 2 case".into(),
                rows: 1,
                cols: 1,
                size: (1200, 600),
                panels: vec![panel("θd − θ", "e (deg)", s)],
            },
        });
    }

    if let Some(r) = get("gamma1-200") {
        let mut s = vec![series("γ1 = 200", &r.trace, |s| s.u, 0, Dash::Solid)];
        if let Some(f2) = get("fig2") {
            s.push(series(
                "γ1 = 100 (Fig. 2(b))",
                &f2.trace,
                |s| s.u,
                1,
                Dash::Dashed,
            ));
        }
        out.push(PaperFigure {
            stem: "fig5".into(),
            caption: format!(
                "Fig. 5 — control input with γ1 = 200 (Fig. 2(b) dashed for comparison) ({reading_label}){}",
                status(r)
            ),
            figure: Figure {
                title: "Fig. 5: control input of the NNBVSC, Fig. 2 case with γ1 = 200".into(),
                rows: 1,
                cols: 1,
                size: (1200, 600),
                panels: vec![panel("u(t)", "u (V)", s)],
            },
        });
    }

    let fig6: Vec<(&str, &str, Dash)> = vec![
        ("abar5", "η = 0.25, ᾱ = 5 (—)", Dash::Solid),
        ("eta0-long", "η = 0, ᾱ = 5 (---)", Dash::Dashed),
        ("eta0-abar0", "η = 0, ᾱ = 0 (-·-)", Dash::DashDot),
        ("eta05", "η = 0.5, ᾱ = 5 (-··-)", Dash::Dotted),
    ];
    if fig6.iter().all(|(id, _, _)| runs.contains_key(*id)) {
        let mk = |f: fn(&Sample) -> f64| -> Vec<Series> {
            fig6.iter()
                .enumerate()
                .map(|(i, (id, label, dash))| series(label, &runs[*id].trace, f, i, *dash))
                .collect()
        };
        out.push(PaperFigure {
            stem: "fig6".into(),
            caption: format!(
                "Fig. 6 — typical weights w_1 and w_128 for four (η, ᾱ) settings ({reading_label})"
            ),
            figure: Figure {
                title: "Fig. 6: typical weights of the NNBVSC, Fig. 2 case".into(),
                rows: 2,
                cols: 1,
                size: (1200, 1000),
                panels: vec![
                    panel("(a) w_1(t)", "w_1", mk(|s| s.part("w_1"))),
                    panel("(b) w_128(t)", "w_128", mk(|s| s.part("w_128"))),
                ],
            },
        });
    }

    let fig7: Vec<(&str, &str, Dash)> = vec![
        ("abar5", "ᾱ = 5 (—)", Dash::Solid),
        ("abar50", "ᾱ = 50 (---)", Dash::Dashed),
        ("abar150", "ᾱ = 150 (-·-)", Dash::DashDot),
        ("abar220", "ᾱ = 220 (-··-)", Dash::Dotted),
    ];
    if fig7.iter().all(|(id, _, _)| runs.contains_key(*id)) {
        let s: Vec<Series> = fig7
            .iter()
            .enumerate()
            .map(|(i, (id, label, dash))| {
                series(label, &runs[*id].trace, |s| s.part("w_128"), i, *dash)
            })
            .collect();
        out.push(PaperFigure {
            stem: "fig7".into(),
            caption: format!(
                "Fig. 7 — typical weight w_128 for four dead-zone sizes ᾱ ({reading_label})"
            ),
            figure: Figure {
                title: "Fig. 7: w_128 of the NNBVSC, Fig. 2 case, for four ᾱ".into(),
                rows: 1,
                cols: 1,
                size: (1200, 600),
                panels: vec![panel("w_128(t)", "w_128", s)],
            },
        });
    }

    if let (Some(f2), Some(f8)) = (get("fig2"), get("fig8")) {
        out.push(PaperFigure {
            stem: "fig8".into(),
            caption: format!(
                "Fig. 8 — Fig. 2 case (—) and half bias, half random variation (-·-) ({reading_label}){}",
                status(f8)
            ),
            figure: Figure {
                title: "Fig. 8: NNBVSC under bias (—) and half bias, half random (-·-) variation".into(),
                rows: 2,
                cols: 1,
                size: (1200, 1000),
                panels: vec![
                    panel(
                        "(a) θd − θ",
                        "e (deg)",
                        vec![
                            series("Fig. 2 case", &f2.trace, e_deg, 0, Dash::Solid),
                            series("half bias, half random", &f8.trace, e_deg, 1, Dash::DashDot),
                        ],
                    ),
                    panel(
                        "(b) u(t)",
                        "u (V)",
                        vec![
                            series("Fig. 2 case", &f2.trace, |s| s.u, 0, Dash::Solid),
                            series("half bias, half random", &f8.trace, |s| s.u, 1, Dash::DashDot),
                        ],
                    ),
                ],
            },
        });
    }
    out
}

/// Line styles of the boundary figures, one per simulation reading of a panel.
const STYLES: [Dash; 4] = [Dash::Solid, Dash::Dashed, Dash::DashDot, Dash::Dotted];

fn bias_title(br: Option<super::breaking::BiasReading>) -> &'static str {
    use super::breaking::BiasReading;
    match br {
        Some(BiasReading::R1) => "R1 (controller keeps Fig. 2's bounds)",
        Some(BiasReading::R2) => "R2 (controller told the true size x)",
        None => "NNBVSC",
    }
}

/// A boundary search's legend entry: where it first diverges and how far
/// it tracks.
fn legend(b: &Boundary) -> String {
    let (bd, tr) = (&b.found.bounded, &b.found.tracking);
    let start = b.found.grid.start;
    let unbounded = match bd.first_fail {
        None => "bounded throughout".to_string(),
        Some(x) if (x - start).abs() < 1e-12 => "unbounded throughout".to_string(),
        Some(x) => format!("unbounded from {x:.3}"),
    };
    let tracking = match (tr.first_fail, tr.last_pass) {
        (None, _) => "tracks throughout".to_string(),
        (Some(_), None) => "never tracks".to_string(),
        (Some(x), Some(_)) => format!("tracks below {x:.3}"),
    };
    let nm = if bd.non_monotone || tr.non_monotone {
        " (non-monotone)"
    } else {
        ""
    };
    format!("{}: {unbounded}, {tracking}{nm}", b.reading)
}

/// e_max (log) against the swept fraction: one panel per bias reading (rows:
/// R1, R2) and b reading (columns: Δb fractions of β = 0.5·b̄, or of b̄),
/// at most four simulation readings a panel, each its colour and dash (the
/// same reading keeps them across panels). A run that diverged leaves a gap
/// in its line and a marker in a strip above the curves, in the line's
/// colour; the horizontal dotted line is the tracking limit.
pub fn boundary_figure(stem: &str, title: &str, x_label: &str, bs: &[Boundary]) -> PaperFigure {
    let mut rows: Vec<Option<super::breaking::BiasReading>> = Vec::new();
    let mut cols: Vec<f64> = Vec::new();
    for b in bs {
        if !rows.contains(&b.bias_reading) {
            rows.push(b.bias_reading);
        }
        if !cols.iter().any(|c| (c - b.b_reference).abs() < 1e-12) {
            cols.push(b.b_reference);
        }
    }
    cols.sort_by(f64::total_cmp);
    let mut panels = Vec::new();
    for br in &rows {
        for &bref in &cols {
            let here: Vec<&Boundary> = bs
                .iter()
                .filter(|b| b.bias_reading == *br && (b.b_reference - bref).abs() < 1e-12)
                .collect();
            // The divergence strips sit below the lowest curve (the legend
            // takes the upper right).
            let low = here
                .iter()
                .flat_map(|b| b.found.scan.iter().filter_map(|p| p.e_max_deg))
                .chain(here.iter().map(|b| b.found.e_limit_deg))
                .filter(|e| e.is_finite() && *e > 0.0)
                .fold(f64::INFINITY, f64::min);
            let bottom = if low.is_finite() { 0.5 * low } else { 0.1 };
            let mut series = Vec::new();
            for (i, b) in here.iter().enumerate() {
                let x: Vec<f64> = b.found.scan.iter().map(|p| p.x).collect();
                let e: Vec<f64> = b
                    .found
                    .scan
                    .iter()
                    .map(|p| match p.diverged_at_s {
                        Some(_) => f64::NAN,
                        None => p.e_max_deg.unwrap_or(f64::NAN),
                    })
                    .collect();
                let label = legend(b);
                // A reading with no bounded run has no line: its strip takes
                // the legend entry.
                let no_line = e.iter().all(|v| !v.is_finite());
                let (line_label, strip_label) = if no_line {
                    (String::new(), label)
                } else {
                    (label, String::new())
                };
                series
                    .push(Series::new(line_label, x.clone(), e, i).dash(STYLES[i % STYLES.len()]));
                // The divergence strip: one row per reading below the curves.
                let strip = bottom / 1.5f64.powi(i as i32);
                let d: Vec<f64> = b
                    .found
                    .scan
                    .iter()
                    .map(|p| {
                        if p.diverged_at_s.is_some() {
                            strip
                        } else {
                            f64::NAN
                        }
                    })
                    .collect();
                series.push(Series::new(strip_label, x, d, i).dash(Dash::Points));
            }
            if let Some(b) = here.first() {
                let (x0, x1) = (
                    b.found.grid.start,
                    b.found.grid.start
                        + (b.found.grid.points.saturating_sub(1)) as f64 * b.found.grid.step,
                );
                series.push(
                    Series::new(
                        format!("tracking limit {}°", b.found.e_limit_deg),
                        vec![x0, x1],
                        vec![b.found.e_limit_deg; 2],
                        4,
                    )
                    .dash(Dash::Dotted),
                );
            }
            panels.push(Panel {
                title: format!(
                    "{}; Δb fractions of {} — bottom strips: diverged runs",
                    bias_title(*br),
                    if bref < 0.75 {
                        "β = 0.5·b̄ (text)"
                    } else {
                        "b̄ (caption)"
                    }
                ),
                x_label: x_label.into(),
                y_label: "max |e| after 2 s (deg, log)".into(),
                series,
                log_y: true,
            });
        }
    }
    let (nr, nc) = (rows.len().max(1), cols.len().max(1));
    PaperFigure {
        stem: stem.into(),
        caption: format!(
            "{title}: one panel per bias reading and b reading; a gap in a line and a marker in the bottom strips is a \
diverged run; dotted: the tracking limit"
        ),
        figure: Figure {
            title: title.into(),
            rows: nr,
            cols: nc,
            size: (900 * nc as u32, 120 + 480 * nr as u32),
            panels,
        },
    }
}
