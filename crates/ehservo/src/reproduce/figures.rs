//! The paper's figures, rebuilt from the runs of the chosen reading: the
//! same panels, signals, units (degrees where the paper uses them) and line
//! styles as the paper's captions describe.
//!
//! Every figure states, in its footer, the reading its runs were made under
//! and the size of the b variation of its cases, both taken from the loaded
//! scenarios (never from the paper's captions). Long oscillating signals
//! (the 60 s weights of Figs. 6–7) are drawn as an envelope per reference
//! period (min–max shaded, mean as a line) beside a zoom on the last
//! periods; a diverging run is clipped to its bounded part and marked.

use super::breaking::Boundary;
use super::manifest::Reading;
use crate::output::{a_variation, b_convention, b_size, clip_diverged, num, panel};
use crate::plot::{Dash, Figure, Panel, Series};
use crate::run::RunResult;
use crate::scenario::Scenario;
use crate::simulation::Sample;
use ehservo_sim::plant::UncertaintySpec;
use std::collections::BTreeMap;

/// Longest series drawn; longer ones are reduced by min/max per bucket, which
/// keeps every peak (an SVG with 60 000 points per line helps nobody).
const MAX_POINTS: usize = 4000;

/// What the figures' runs were made under.
pub struct FigureContext<'a> {
    /// The reading (manifest entry).
    pub reading: &'a Reading,
    /// The scenario of every case, under that reading.
    pub scenarios: BTreeMap<String, &'a Scenario>,
}

impl FigureContext<'_> {
    /// The footer of a figure made from `cases`: the reading, then the b
    /// variation (per case where the cases differ) and its convention.
    fn footer(&self, cases: &[&str]) -> String {
        let found: Vec<(&str, &Scenario)> = cases
            .iter()
            .filter_map(|c| self.scenarios.get(*c).map(|s| (*c, *s)))
            .collect();
        // The converged level each case was run at.
        let level = per_case(&found, |s| {
            let sim = &s.simulation;
            match sim.mode {
                ehservo_sim::simulation::Mode::Sampled => format!(
                    "sampled every {} s, {} RK4 sub-step{}",
                    sim.step,
                    sim.substeps,
                    if sim.substeps == 1 { "" } else { "s" }
                ),
                ehservo_sim::simulation::Mode::Continuous => {
                    format!("continuous, RK4 step {:e} s", sim.step)
                }
            }
        });
        let b = per_case(&found, |s| b_size(&s.uncertainty_spec()));
        let mut conventions: Vec<String> = Vec::new();
        for (_, s) in &found {
            let conv = b_convention(&s.uncertainty_spec());
            if !conventions.contains(&conv) {
                conventions.push(conv);
            }
        }
        format!(
            "Reading {}: {}\nConverged level: {level}\nTrue b variation: {b} ({})",
            self.reading.id,
            self.reading.label,
            conventions.join("; ")
        )
    }

    fn uncertainty(&self, case: &str) -> Option<UncertaintySpec> {
        self.scenarios.get(case).map(|s| s.uncertainty_spec())
    }

    /// One reference period (s) of a case (1 s if unknown).
    fn period(&self, case: &str) -> f64 {
        self.scenarios
            .get(case)
            .map(|s| s.reference.base_frequency_hz(s.simulation.horizon))
            .filter(|f| *f > 0.0)
            .map_or(1.0, |f| 1.0 / f)
    }
}

/// `text` of every case: the one text when all cases share it, else
/// "a, b: text; c: other text".
fn per_case(cases: &[(&str, &Scenario)], text: impl Fn(&Scenario) -> String) -> String {
    let mut groups: Vec<(String, Vec<&str>)> = Vec::new();
    for (c, s) in cases {
        let t = text(s);
        match groups.iter_mut().find(|(g, _)| *g == t) {
            Some((_, cs)) => cs.push(c),
            None => groups.push((t, vec![c])),
        }
    }
    match groups.as_slice() {
        [] => String::new(),
        [(t, _)] => t.clone(),
        _ => groups
            .iter()
            .map(|(t, cs)| format!("{}: {t}", cs.join(", ")))
            .collect::<Vec<_>>()
            .join("; "),
    }
}

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

/// Min, max and mean of `f` over consecutive windows of `window` seconds,
/// at each window's centre.
struct Envelope {
    n: Vec<usize>,
    t: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    mean: Vec<f64>,
}

fn envelope(trace: &[Sample], f: &dyn Fn(&Sample) -> f64, window: f64) -> Envelope {
    let mut e = Envelope {
        n: Vec::new(),
        t: Vec::new(),
        lo: Vec::new(),
        hi: Vec::new(),
        mean: Vec::new(),
    };
    let Some(t0) = trace.first().map(|s| s.t) else {
        return e;
    };
    // Window index of a sample; the tolerance puts t = k·window (rounded)
    // at the start of window k.
    let index = |t: f64| ((t - t0) / window + 1e-9).floor() as i64;
    let mut i = 0;
    while i < trace.len() {
        let k = index(trace[i].t);
        let j = i + trace[i..]
            .iter()
            .position(|s| index(s.t) != k)
            .unwrap_or(trace.len() - i);
        let vals: Vec<f64> = trace[i..j]
            .iter()
            .map(f)
            .filter(|v| v.is_finite())
            .collect();
        // A window cut short by the end of the run (the lone sample at
        // t = T) would draw a spurious step: windows of fewer than half the
        // first one's samples are left out.
        let full = e.n.first().copied().unwrap_or(vals.len());
        if !vals.is_empty() && 2 * vals.len() >= full {
            e.n.push(vals.len());
            e.t.push(t0 + (k as f64 + 0.5) * window);
            e.lo.push(vals.iter().copied().fold(f64::INFINITY, f64::min));
            e.hi.push(vals.iter().copied().fold(f64::NEG_INFINITY, f64::max));
            e.mean.push(vals.iter().sum::<f64>() / vals.len() as f64);
        }
        i = j;
    }
    e
}

/// The envelope of `f` over one case, as a shaded band and its mean line.
fn envelope_series(
    label: &str,
    trace: &[Sample],
    f: &dyn Fn(&Sample) -> f64,
    window: f64,
    color: usize,
    dash: Dash,
) -> [Series; 2] {
    let e = envelope(trace, f, window);
    [
        Series::band("", e.t.clone(), e.lo, e.hi, color),
        Series::new(label, e.t, e.mean, color).dash(dash),
    ]
}

/// The samples of the last `span` seconds.
fn tail(trace: &[Sample], span: f64) -> &[Sample] {
    let end = trace.last().map_or(0.0, |s| s.t);
    let from = trace.partition_point(|s| s.t < end - span - 1e-9);
    &trace[from..]
}

/// The samples with t ≤ `span`.
fn head(trace: &[Sample], span: f64) -> &[Sample] {
    &trace[..trace.partition_point(|s| s.t <= span + 1e-9)]
}

/// A panel of u(t) (V).
fn u_panel(title: &str, r: &RunResult) -> Panel {
    let mut p = panel(
        title,
        "u (V)",
        vec![series("", &r.trace, |s| s.u, 0, Dash::Solid)],
    );
    clip_diverged(&mut p, r);
    p
}

/// A panel of σ(t) (rad/s²).
fn sigma_panel(title: &str, r: &RunResult) -> Panel {
    let f = |s: &Sample| s.part("sigma");
    let mut p = panel(
        title,
        "σ (rad/s²)",
        vec![series("", &r.trace, f, 0, Dash::Solid)],
    );
    clip_diverged(&mut p, r);
    p
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
pub fn paper_figures(
    runs: &BTreeMap<String, RunResult>,
    ctx: &FigureContext<'_>,
) -> Vec<PaperFigure> {
    let mut out = Vec::new();
    let get = |id: &str| runs.get(id);
    let rid = &ctx.reading.id;
    let b_of = |case: &str| {
        ctx.uncertainty(case)
            .as_ref()
            .map(b_size)
            .unwrap_or_default()
    };
    let a_of = |case: &str| {
        ctx.uncertainty(case)
            .as_ref()
            .map(a_variation)
            .unwrap_or_default()
    };

    if let Some(r) = get("fig2") {
        let t = &r.trace;
        out.push(PaperFigure {
            stem: "fig2".into(),
            caption: format!(
                "Fig. 2 — NNBVSC, {}, {}, Tl = 2 sin 4θ (reading `{rid}`){}",
                a_of("fig2"),
                b_of("fig2"),
                status(r)
            ),
            figure: Figure {
                title: format!(
                    "Fig. 2: NNBVSC, p = (90, 2600, 24000), η = 0.25, ᾱ = 5, γ₁ = 100; {}{}",
                    b_of("fig2"),
                    status(r)
                ),
                rows: 2,
                cols: 2,
                size: (1400, 1000),
                footer: ctx.footer(&["fig2"]),
                panels: vec![
                    panel(
                        "(a) θd (···) and θ (—)",
                        "angle (deg)",
                        vec![
                            series("θd", t, |s| s.theta_d_deg(), 1, Dash::Dotted),
                            series("θ", t, |s| s.theta_deg(), 0, Dash::Solid),
                        ],
                    ),
                    u_panel("(b) u(t)", r),
                    sigma_panel("(c) σ(t)", r),
                    panel(
                        "(d) Σ Δaᵢxᵢ − Δb·u(eq) + d − ξ (---) and WᵀΦ (—)",
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
        let mut e = panel(
            "(a) θd − θ",
            "e (deg)",
            vec![series("", &r.trace, e_deg, 0, Dash::Solid)],
        );
        clip_diverged(&mut e, r);
        out.push(PaperFigure {
            stem: "fig3".into(),
            caption: format!(
                "Fig. 3 — traditional VSC, {}, {}, Tl = 2 sin 4θ (reading `{rid}`){}",
                a_of("fig3"),
                b_of("fig3"),
                status(r)
            ),
            figure: Figure {
                title: format!(
                    "Fig. 3: traditional VSC (Theorem 1), {}{}",
                    a_of("fig3"),
                    status(r)
                ),
                rows: 3,
                cols: 1,
                size: (1200, 1100),
                footer: ctx.footer(&["fig3"]),
                panels: vec![e, u_panel("(b) u(t)", r), sigma_panel("(c) σ(t)", r)],
            },
        });
    }

    let fig4: Vec<(&str, &str, Dash)> = vec![
        ("fig2", "γ₁ = 100, η = 0.25 (—)", Dash::Solid),
        ("gamma1-200", "γ₁ = 200, η = 0.25 (---)", Dash::Dashed),
        ("eta0", "γ₁ = 100, η = 0 (-·-)", Dash::DashDot),
    ];
    if fig4.iter().all(|(id, _, _)| runs.contains_key(*id)) {
        let s: Vec<Series> = fig4
            .iter()
            .enumerate()
            .map(|(i, (id, label, dash))| series(label, &runs[*id].trace, e_deg, i, *dash))
            .collect();
        let ids: Vec<&str> = fig4.iter().map(|f| f.0).collect();
        out.push(PaperFigure {
            stem: "fig4".into(),
            caption: format!(
                "Fig. 4 — tracking error of the NNBVSC for three settings, {} (reading `{rid}`)",
                b_of("fig2")
            ),
            figure: Figure {
                title: "Fig. 4: tracking error θd − θ of the NNBVSC, Fig. 2 case".into(),
                size: (1200, 650),
                footer: ctx.footer(&ids),
                panels: vec![panel("θd − θ", "e (deg)", s)],
                ..Default::default()
            },
        });
    }

    if let Some(r) = get("gamma1-200") {
        let zoom = 0.1;
        let mut full = vec![series("γ₁ = 200", &r.trace, |s| s.u, 0, Dash::Solid)];
        let mut near = vec![series(
            "γ₁ = 200",
            head(&r.trace, zoom),
            |s| s.u,
            0,
            Dash::Solid,
        )];
        if let Some(f2) = get("fig2") {
            full.push(series(
                "γ₁ = 100 (Fig. 2(b))",
                &f2.trace,
                |s| s.u,
                1,
                Dash::Dashed,
            ));
            near.push(series(
                "γ₁ = 100 (Fig. 2(b))",
                head(&f2.trace, zoom),
                |s| s.u,
                1,
                Dash::Dashed,
            ));
        }
        let mut full = panel("(a) u(t)", "u (V)", full);
        clip_diverged(&mut full, r);
        let mut near = panel(
            &format!("(b) the first {} s (every sample)", num(zoom)),
            "u (V)",
            near,
        );
        near.x_range = Some((0.0, zoom));
        out.push(PaperFigure {
            stem: "fig5".into(),
            caption: format!(
                "Fig. 5 — control input with γ₁ = 200 (Fig. 2(b) dashed for comparison), {}; (b) zooms on the first {} s, where the two differ (reading `{rid}`){}",
                b_of("gamma1-200"),
                num(zoom),
                status(r)
            ),
            figure: Figure {
                title: "Fig. 5: control input of the NNBVSC, Fig. 2 case with γ₁ = 200".into(),
                rows: 2,
                cols: 1,
                size: (1200, 900),
                footer: ctx.footer(&["gamma1-200", "fig2"]),
                panels: vec![full, near],
            },
        });
    }

    // Figs. 6 and 7: 60 s of weights oscillating at the reference frequency
    // — an envelope per period over the whole run, and every sample of the
    // last periods.
    let zoom_periods = 3.0;
    let weights = |cases: &[(&str, &str, Dash)],
                   key: &'static str,
                   name: &str,
                   letters: (&str, &str)|
     -> [Panel; 2] {
        let f = move |s: &Sample| s.part(key);
        let period = ctx.period(cases[0].0);
        let mut env = Vec::new();
        let mut last = Vec::new();
        for (i, (id, label, dash)) in cases.iter().enumerate() {
            let r = &runs[*id];
            env.extend(envelope_series(label, &r.trace, &f, period, i, *dash));
            last.push(series(
                label,
                tail(&r.trace, zoom_periods * period),
                f,
                i,
                *dash,
            ));
        }
        [
            panel(
                &format!(
                    "({}) {name}(t): min–max per {} s (shaded) and mean (line)",
                    letters.0,
                    num(period)
                ),
                name,
                env,
            ),
            panel(
                &format!(
                    "({}) {name}(t), the last {} s (every sample)",
                    letters.1,
                    num(zoom_periods * period)
                ),
                name,
                last,
            ),
        ]
    };

    let fig6: Vec<(&str, &str, Dash)> = vec![
        ("abar5", "η = 0.25, ᾱ = 5 (—)", Dash::Solid),
        ("eta0-long", "η = 0, ᾱ = 5 (---)", Dash::Dashed),
        ("eta0-abar0", "η = 0, ᾱ = 0 (-·-)", Dash::DashDot),
        ("eta05", "η = 0.5, ᾱ = 5 (···)", Dash::Dotted),
    ];
    if fig6.iter().all(|(id, _, _)| runs.contains_key(*id)) {
        let [a, b] = weights(&fig6, "w_1", "w₁", ("a", "b"));
        let [c, d] = weights(&fig6, "w_128", "w₁₂₈", ("c", "d"));
        let ids: Vec<&str> = fig6.iter().map(|f| f.0).collect();
        out.push(PaperFigure {
            stem: "fig6".into(),
            caption: format!(
                "Fig. 6 — typical weights w₁ and w₁₂₈ for four (η, ᾱ) settings, {}: envelope per reference period over the whole run, and the last periods in full (reading `{rid}`)",
                b_of("abar5")
            ),
            figure: Figure {
                title: "Fig. 6: typical weights of the NNBVSC, Fig. 2 case".into(),
                rows: 2,
                cols: 2,
                size: (1500, 1000),
                footer: ctx.footer(&ids),
                panels: vec![a, b, c, d],
            },
        });
    }

    let fig7: Vec<(&str, &str, Dash)> = vec![
        ("abar5", "ᾱ = 5 (—)", Dash::Solid),
        ("abar50", "ᾱ = 50 (---)", Dash::Dashed),
        ("abar150", "ᾱ = 150 (-·-)", Dash::DashDot),
        ("abar220", "ᾱ = 220 (···)", Dash::Dotted),
    ];
    if fig7.iter().all(|(id, _, _)| runs.contains_key(*id)) {
        let [a, b] = weights(&fig7, "w_128", "w₁₂₈", ("a", "b"));
        let ids: Vec<&str> = fig7.iter().map(|f| f.0).collect();
        out.push(PaperFigure {
            stem: "fig7".into(),
            caption: format!(
                "Fig. 7 — typical weight w₁₂₈ for four dead-zone sizes ᾱ, {}: envelope per reference period, and the last periods in full (reading `{rid}`)",
                b_of("abar5")
            ),
            figure: Figure {
                title: "Fig. 7: w₁₂₈ of the NNBVSC, Fig. 2 case, for four ᾱ".into(),
                rows: 1,
                cols: 2,
                size: (1500, 620),
                footer: ctx.footer(&ids),
                panels: vec![a, b],
            },
        });
    }

    if let (Some(f2), Some(f8)) = (get("fig2"), get("fig8")) {
        let mut e = panel(
            "(a) θd − θ",
            "e (deg)",
            vec![
                series("Fig. 2 case", &f2.trace, e_deg, 0, Dash::Solid),
                series("half bias, half random", &f8.trace, e_deg, 1, Dash::DashDot),
            ],
        );
        clip_diverged(&mut e, f8);
        let mut u = panel(
            "(b) u(t)",
            "u (V)",
            vec![
                series("Fig. 2 case", &f2.trace, |s| s.u, 0, Dash::Solid),
                series(
                    "half bias, half random",
                    &f8.trace,
                    |s| s.u,
                    1,
                    Dash::DashDot,
                ),
            ],
        );
        clip_diverged(&mut u, f8);
        out.push(PaperFigure {
            stem: "fig8".into(),
            caption: format!(
                "Fig. 8 — Fig. 2 case (—) and half bias, half random variation (-·-): {}, {} (reading `{rid}`){}",
                a_of("fig8"),
                b_of("fig8"),
                status(f8)
            ),
            figure: Figure {
                title: "Fig. 8: NNBVSC under bias (—) and half bias, half random (-·-) variation".into(),
                rows: 2,
                cols: 1,
                size: (1200, 1000),
                footer: ctx.footer(&["fig2", "fig8"]),
                panels: vec![e, u],
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
                        "b̄ (hypothesis Δb = β)"
                    }
                ),
                x_label: x_label.into(),
                y_label: "max |e| after 2 s (deg, log)".into(),
                series,
                log_y: true,
                ..Default::default()
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
            ..Default::default()
        },
    }
}
