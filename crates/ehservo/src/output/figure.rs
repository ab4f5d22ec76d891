//! A run's figure (`trace.png`) and what the paper's figures share with
//! it: the time-history panel, the clipping of a diverged run, and the
//! true variation in the paper's words (the figures' footers).

use crate::plot::{Dash, Figure, Mark, Panel, Series};
use crate::run::RunResult;
use crate::scenario::{Loop, Scenario};
use crate::simulation::Sample;
use ehservo_sim::axis::Axis;
use ehservo_sim::plant::UncertaintySpec;

/// β as a multiple of |b̄| (SPEC §2, the paper's reference size of the b
/// variation).
const BETA_OVER_B: f64 = 0.5;

/// A number with at most three decimals and no trailing zeros.
pub(crate) fn num(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// The size of the true b variation in the paper's terms, e.g. "Δb = β",
/// "Δb = 0.5β ± 0.5β random".
pub fn b_size(u: &UncertaintySpec) -> String {
    let beta = |f: f64| {
        let k = u.b_reference * f / BETA_OVER_B;
        if (k - 1.0).abs() < 1e-12 {
            "β".to_string()
        } else {
            format!("{}β", num(k))
        }
    };
    let mut s = format!("Δb = {}", beta(u.b_bias));
    if u.b_random != 0.0 {
        s.push_str(&format!(" ± {} random", beta(u.b_random.abs())));
    }
    s
}

/// The convention behind [`b_size`], e.g. "b_reference = 1: b fractions
/// of b̄".
pub fn b_convention(u: &UncertaintySpec) -> String {
    let of = if (u.b_reference - BETA_OVER_B).abs() < 1e-12 {
        "β = 0.5·b̄".to_string()
    } else if (u.b_reference - 1.0).abs() < 1e-12 {
        "b̄".to_string()
    } else {
        format!("{}·b̄", num(u.b_reference))
    };
    format!("b_reference = {}: b fractions of {of}", num(u.b_reference))
}

/// [`b_size`] and [`b_convention`]: "Δb = β (b_reference = 1: b fractions
/// of b̄)".
pub fn b_variation(u: &UncertaintySpec) -> String {
    format!("{} ({})", b_size(u), b_convention(u))
}

/// The a_i variation of a scenario, e.g. "100 % aᵢ bias".
pub fn a_variation(u: &UncertaintySpec) -> String {
    let mut s = format!("{} % aᵢ bias", num(100.0 * u.a_bias));
    if u.a_random != 0.0 {
        s.push_str(&format!(" + {} % random", num(100.0 * u.a_random)));
    }
    s
}

/// A time-history panel: t (s) against `y_label`.
pub(crate) fn panel(title: &str, y_label: &str, series: Vec<Series>) -> Panel {
    Panel {
        title: title.into(),
        x_label: "t (s)".into(),
        y_label: y_label.into(),
        series,
        ..Default::default()
    }
}

/// For a run that diverged: a y range around the bounded part of the
/// panel's lines (the 2–98 % quantiles of all their values, widened by half
/// their spread) and a mark at the divergence. The lines are clipped to the
/// range.
pub fn clip_diverged(p: &mut Panel, r: &RunResult) {
    let Some(d) = r.outcome.diverged else {
        return;
    };
    let mut v: Vec<f64> = p
        .series
        .iter()
        .flat_map(|s| s.y.iter().chain(s.lower.iter().flatten()))
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    if v.len() >= 10 {
        v.sort_by(f64::total_cmp);
        let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
        let (lo, hi) = (q(0.02), q(0.98));
        let m = 0.5 * (hi - lo).max(1e-12);
        p.y_range = Some((lo - m, hi + m));
    }
    p.marks.push(Mark {
        x: d.t,
        text: format!("unbounded at t = {:.2} s", d.t),
    });
}

/// The main time histories of a run: the paper's Fig. 2 panels.
pub fn trace_figure(lp: &Loop, run: &RunResult) -> Figure {
    let s = lp.scenario();
    let t: Vec<f64> = run.trace.iter().map(|x| x.t).collect();
    let col = |f: &dyn Fn(&Sample) -> f64| column(run, f);
    let mut title = format!(
        "{} — {} on the {} plant, {} h = {} s",
        s.name,
        s.controller.kind(),
        s.plant.model(),
        s.simulation.mode.as_str(),
        s.simulation.step
    );
    if let Some(d) = run.outcome.diverged {
        title.push_str(&format!(" — unbounded at t = {:.3} s", d.t));
    }
    let mut u_series = vec![Series::new("u", t.clone(), col(&|x| x.u), 0)];
    if !s.actuator.is_identity() {
        u_series.push(Series::new("valve", t.clone(), col(&|x| x.u_plant), 1).dash(Dash::Dashed));
    }
    let ax = lp.axis();
    let (sym, unit) = (ax.letter(), ax.unit());
    let theta = panel(
        &format!("(a) {sym}d (dotted) and {sym}"),
        &format!(
            "{} ({unit})",
            match ax {
                Axis::Linear => "position",
                _ => ax.quantity(),
            }
        ),
        vec![
            Series::new(
                format!("{sym}d"),
                t.clone(),
                col(&|x| ax.display(x.z[0])),
                1,
            )
            .dash(Dash::Dotted),
            Series::new(sym, t.clone(), col(&|x| ax.display(x.x[0])), 0),
        ],
    );
    let mut panels = vec![
        theta,
        error_panel(s, run, &t),
        panel("(c) control input u", "u (V)", u_series),
    ];
    panels.extend(seen_panel(s, run, &t));
    panels.extend(law_panels(run, &t, ax));
    // A diverged run: every time history is clipped to its bounded part,
    // and the divergence marked (the last steps would flatten the rest).
    if run.outcome.diverged.is_some() {
        for p in panels.iter_mut() {
            clip_diverged(p, run);
        }
    }
    let rows = panels.len().div_ceil(2);
    Figure {
        title,
        rows,
        cols: 2,
        size: (1400, 500 * rows as u32),
        panels,
        footer: variation_footer(lp),
    }
}

/// One value of every kept sample of a run.
fn column(run: &RunResult, f: &dyn Fn(&Sample) -> f64) -> Vec<f64> {
    run.trace.iter().map(f).collect::<Vec<f64>>()
}

/// Panel (b), the tracking error. The error after the transient is the
/// headline (e_max): the y axis is scaled to it and the transient clipped,
/// with t_s marked.
fn error_panel(s: &Scenario, run: &RunResult, t: &[f64]) -> Panel {
    let ax = run.metrics.axis;
    let (sym, unit) = (ax.letter(), ax.unit());
    let mut e_panel = panel(
        &match run.metrics.e_max {
            Some(e) => format!(
                "(b) tracking error e = {sym}d − {sym}; max |e| after {} s: {e:.4}{}",
                s.simulation.settle,
                ax.suffix()
            ),
            None => format!("(b) tracking error e = {sym}d − {sym}"),
        },
        &format!("e ({unit})"),
        vec![Series::new(
            "",
            t.to_vec(),
            column(run, &|x| ax.display(x.e)),
            0,
        )],
    );
    let settle = s.simulation.settle;
    let after: Vec<f64> = run
        .trace
        .iter()
        .filter(|x| x.t >= settle - 1e-9)
        .map(|x| ax.display(x.e))
        .filter(|v| v.is_finite())
        .collect();
    if run.outcome.diverged.is_none() && !after.is_empty() {
        let lo = after.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = after.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let m = 0.15 * (hi - lo).max(1e-9);
        e_panel.y_range = Some((lo - m, hi + m));
        e_panel.marks.push(Mark {
            x: settle,
            text: "transient ends".into(),
        });
    }
    e_panel
}

/// What the controller was given against the truth, when the sensors or
/// an estimator stand between: the acceleration, the hardest channel.
fn seen_panel(s: &Scenario, run: &RunResult, t: &[f64]) -> Option<Panel> {
    let exact_sensor = s.sensor.is_exact();
    if exact_sensor && s.estimator.is_none() {
        return None;
    }
    // x₂: the rod's acceleration on a force or pressure loop.
    let ax = run.metrics.axis.motion();
    let (sym, unit) = (ax.letter(), ax.unit());
    let source = match (&s.estimator, s.sensor.measured.has(2)) {
        (Some(e), false) => format!("estimated ({})", e.kind()),
        _ => "measured".to_string(),
    };
    Some(panel(
        &format!("{sym}̈: true and {source}, as the controller saw it"),
        &format!("{sym}̈ ({unit}/s²)"),
        vec![
            Series::new(
                "seen",
                t.to_vec(),
                column(run, &|x| ax.display(x.x_ctrl[2])),
                1,
            )
            .dash(Dash::Dashed),
            Series::new("true", t.to_vec(), column(run, &|x| ax.display(x.x[2])), 0),
        ],
    ))
}

/// The law's panels: for the sliding-mode laws the paper's Fig. 2 panels
/// (σ, the lumped uncertainty and its estimate, ‖W‖); for any other law
/// its parts in volts.
fn law_panels(run: &RunResult, t: &[f64], ax: Axis) -> Vec<Panel> {
    let col = |f: &dyn Fn(&Sample) -> f64| column(run, f);
    let t = t.to_vec();
    let signals = run.trace.first().map(|x| x.signals).unwrap_or(&[]);
    let has = |key: &str| signals.iter().any(|g| g.key == key);
    let mut panels = Vec::new();
    if has("sigma") && has("uncertainty") {
        let mut d_series = vec![Series::new(
            "Σ Δaᵢxᵢ − Δb·u(eq) + d − ξ",
            t.clone(),
            col(&|x| x.part("uncertainty")),
            1,
        )
        .dash(Dash::Dashed)];
        if run.metrics.w_norm_max.is_some() {
            d_series.push(Series::new("WᵀΦ", t.clone(), col(&|x| x.part("wphi")), 0));
        }
        panels.push(panel(
            "(d) switching function σ",
            &format!("σ ({})", ax.si_name("rad/s²")),
            vec![Series::new("", t.clone(), col(&|x| x.part("sigma")), 0)],
        ));
        panels.push(panel(
            "(e) lumped uncertainty (19) and its estimate",
            &format!("({})", ax.si_name("rad/s³")),
            d_series,
        ));
        if run.metrics.w_norm_max.is_some() {
            panels.push(panel(
                "(f) norm of the weights ‖W‖",
                "‖W‖",
                vec![Series::new("", t.clone(), col(&|x| x.part("w_norm")), 0)],
            ));
        }
    } else {
        let parts: Vec<Series> = signals
            .iter()
            .enumerate()
            .filter(|(_, g)| g.unit == "V" && !g.column.is_empty())
            .enumerate()
            .map(|(n, (i, g))| Series::new(g.key, t.clone(), col(&|x| x.values[i]), n))
            .collect();
        panels.push(panel("(d) the parts of the law", "(V)", parts));
    }
    panels
}

/// A figure's footer: the true variation as the scenario sets it.
pub fn variation_footer(lp: &Loop) -> String {
    let s = lp.scenario();
    let u = lp.stages().uncertainty;
    let physical = physical_variation(&u.physical);
    if s.plant.paper_uncertainty() {
        let paper = format!("True variation: {}, {}", a_variation(&u), b_variation(&u));
        match physical {
            None => paper,
            Some(p) => format!("{paper}; {p}"),
        }
    } else {
        format!(
            "True variation: {}",
            physical.unwrap_or_else(|| "none (the plant is its nominal model's physics)".into())
        )
    }
}

/// The physical variation in words (None when none is set).
fn physical_variation(p: &ehservo_sim::plant::PhysicalSpec) -> Option<String> {
    let parts: Vec<String> = ehservo_sim::plant::PhysicalSpec::KEYS
        .iter()
        .zip(p.spreads())
        .filter(|(_, s)| !s.is_none())
        .map(|(k, s)| {
            let mut t = format!("{k} ×(1 {:+.0} %", 100.0 * s.bias);
            if s.random != 0.0 {
                t.push_str(&format!(" ± {:.0} % random", 100.0 * s.random.abs()));
            }
            t.push(')');
            t
        })
        .collect();
    (!parts.is_empty()).then(|| parts.join(", "))
}
