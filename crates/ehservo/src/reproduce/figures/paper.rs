//! The paper's figures, one function each (Figs. 2–8): the same panels,
//! signals and line styles as the paper's captions describe, from the runs
//! of one reading.

use super::traces::{e_deg, envelope_series, head, series, sigma_panel, status, tail, u_panel};
use super::{FigureContext, PaperFigure};
use crate::output::{clip_diverged, num, panel};
use crate::plot::{Dash, Figure, Panel, Series};
use crate::run::RunResult;
use crate::simulation::Sample;
use std::collections::BTreeMap;

/// Builds every figure whose cases are present in `runs`.
pub fn paper_figures(
    runs: &BTreeMap<String, RunResult>,
    ctx: &FigureContext<'_>,
) -> Vec<PaperFigure> {
    [fig2, fig3, fig4, fig5, fig6, fig7, fig8]
        .iter()
        .filter_map(|fig| fig(runs, ctx))
        .collect()
}

/// Fig. 2: the NNBVSC on the Fig. 2 case: θd and θ, u, σ, and the
/// uncertainty (19) against WᵀΦ.
fn fig2(runs: &BTreeMap<String, RunResult>, ctx: &FigureContext<'_>) -> Option<PaperFigure> {
    let rid = &ctx.reading.id;
    let r = runs.get("fig2")?;
    let t = &r.trace;
    Some(PaperFigure {
        stem: "fig2".into(),
        caption: format!(
            "Fig. 2 — NNBVSC, {}, {}, Tl = 2 sin 4θ (reading `{rid}`){}",
            ctx.a_of("fig2"),
            ctx.b_of("fig2"),
            status(r)
        ),
        figure: Figure {
            title: format!(
                "Fig. 2: NNBVSC, p = (90, 2600, 24000), η = 0.25, ᾱ = 5, γ₁ = 100; {}{}",
                ctx.b_of("fig2"),
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
    })
}

/// Fig. 3: the traditional VSC (Theorem 1): e, u and σ.
fn fig3(runs: &BTreeMap<String, RunResult>, ctx: &FigureContext<'_>) -> Option<PaperFigure> {
    let rid = &ctx.reading.id;
    let r = runs.get("fig3")?;
    let mut e = panel(
        "(a) θd − θ",
        "e (deg)",
        vec![series("", &r.trace, e_deg, 0, Dash::Solid)],
    );
    clip_diverged(&mut e, r);
    Some(PaperFigure {
        stem: "fig3".into(),
        caption: format!(
            "Fig. 3 — traditional VSC, {}, {}, Tl = 2 sin 4θ (reading `{rid}`){}",
            ctx.a_of("fig3"),
            ctx.b_of("fig3"),
            status(r)
        ),
        figure: Figure {
            title: format!(
                "Fig. 3: traditional VSC (Theorem 1), {}{}",
                ctx.a_of("fig3"),
                status(r)
            ),
            rows: 3,
            cols: 1,
            size: (1200, 1100),
            footer: ctx.footer(&["fig3"]),
            panels: vec![e, u_panel("(b) u(t)", r), sigma_panel("(c) σ(t)", r)],
        },
    })
}

/// Fig. 4: the NNBVSC's tracking error for three settings.
fn fig4(runs: &BTreeMap<String, RunResult>, ctx: &FigureContext<'_>) -> Option<PaperFigure> {
    let rid = &ctx.reading.id;
    let cases: Vec<(&str, &str, Dash)> = vec![
        ("fig2", "γ₁ = 100, η = 0.25 (—)", Dash::Solid),
        ("gamma1-200", "γ₁ = 200, η = 0.25 (---)", Dash::Dashed),
        ("eta0", "γ₁ = 100, η = 0 (-·-)", Dash::DashDot),
    ];
    if !cases.iter().all(|(id, _, _)| runs.contains_key(*id)) {
        return None;
    }
    let s: Vec<Series> = cases
        .iter()
        .enumerate()
        .map(|(i, (id, label, dash))| series(label, &runs[*id].trace, e_deg, i, *dash))
        .collect();
    let ids: Vec<&str> = cases.iter().map(|f| f.0).collect();
    Some(PaperFigure {
        stem: "fig4".into(),
        caption: format!(
            "Fig. 4 — tracking error of the NNBVSC for three settings, {} (reading `{rid}`)",
            ctx.b_of("fig2")
        ),
        figure: Figure {
            title: "Fig. 4: tracking error θd − θ of the NNBVSC, Fig. 2 case".into(),
            size: (1200, 650),
            footer: ctx.footer(&ids),
            panels: vec![panel("θd − θ", "e (deg)", s)],
            ..Default::default()
        },
    })
}

/// Fig. 5: the control input with γ₁ = 200 (Fig. 2(b) for comparison), and a
/// zoom on its first samples.
fn fig5(runs: &BTreeMap<String, RunResult>, ctx: &FigureContext<'_>) -> Option<PaperFigure> {
    let rid = &ctx.reading.id;
    let r = runs.get("gamma1-200")?;
    let zoom = 0.1;
    let mut full = vec![series("γ₁ = 200", &r.trace, |s| s.u, 0, Dash::Solid)];
    let mut near = vec![series(
        "γ₁ = 200",
        head(&r.trace, zoom),
        |s| s.u,
        0,
        Dash::Solid,
    )];
    if let Some(f2) = runs.get("fig2") {
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
    Some(PaperFigure {
        stem: "fig5".into(),
        caption: format!(
            "Fig. 5 — control input with γ₁ = 200 (Fig. 2(b) dashed for comparison), {}; (b) zooms on the first {} s, where the two differ (reading `{rid}`){}",
            ctx.b_of("gamma1-200"),
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
    })
}

/// Figs. 6 and 7: 60 s of weights oscillating at the reference frequency
/// — an envelope per period over the whole run, and every sample of the
/// last periods.
fn weights(
    runs: &BTreeMap<String, RunResult>,
    ctx: &FigureContext<'_>,
    cases: &[(&str, &str, Dash)],
    key: &'static str,
    name: &str,
    letters: (&str, &str),
) -> [Panel; 2] {
    let zoom_periods = 3.0;
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
}

/// Fig. 6: typical weights w₁ and w₁₂₈ for four (η, ᾱ) settings.
fn fig6(runs: &BTreeMap<String, RunResult>, ctx: &FigureContext<'_>) -> Option<PaperFigure> {
    let rid = &ctx.reading.id;
    let cases: Vec<(&str, &str, Dash)> = vec![
        ("abar5", "η = 0.25, ᾱ = 5 (—)", Dash::Solid),
        ("eta0-long", "η = 0, ᾱ = 5 (---)", Dash::Dashed),
        ("eta0-abar0", "η = 0, ᾱ = 0 (-·-)", Dash::DashDot),
        ("eta05", "η = 0.5, ᾱ = 5 (···)", Dash::Dotted),
    ];
    if !cases.iter().all(|(id, _, _)| runs.contains_key(*id)) {
        return None;
    }
    let [a, b] = weights(runs, ctx, &cases, "w_1", "w₁", ("a", "b"));
    let [c, d] = weights(runs, ctx, &cases, "w_128", "w₁₂₈", ("c", "d"));
    let ids: Vec<&str> = cases.iter().map(|f| f.0).collect();
    Some(PaperFigure {
        stem: "fig6".into(),
        caption: format!(
            "Fig. 6 — typical weights w₁ and w₁₂₈ for four (η, ᾱ) settings, {}: envelope per reference period over the whole run, and the last periods in full (reading `{rid}`)",
            ctx.b_of("abar5")
        ),
        figure: Figure {
            title: "Fig. 6: typical weights of the NNBVSC, Fig. 2 case".into(),
            rows: 2,
            cols: 2,
            size: (1500, 1000),
            footer: ctx.footer(&ids),
            panels: vec![a, b, c, d],
        },
    })
}

/// Fig. 7: the weight w₁₂₈ for four dead-zone sizes ᾱ.
fn fig7(runs: &BTreeMap<String, RunResult>, ctx: &FigureContext<'_>) -> Option<PaperFigure> {
    let rid = &ctx.reading.id;
    let cases: Vec<(&str, &str, Dash)> = vec![
        ("abar5", "ᾱ = 5 (—)", Dash::Solid),
        ("abar50", "ᾱ = 50 (---)", Dash::Dashed),
        ("abar150", "ᾱ = 150 (-·-)", Dash::DashDot),
        ("abar220", "ᾱ = 220 (···)", Dash::Dotted),
    ];
    if !cases.iter().all(|(id, _, _)| runs.contains_key(*id)) {
        return None;
    }
    let [a, b] = weights(runs, ctx, &cases, "w_128", "w₁₂₈", ("a", "b"));
    let ids: Vec<&str> = cases.iter().map(|f| f.0).collect();
    Some(PaperFigure {
        stem: "fig7".into(),
        caption: format!(
            "Fig. 7 — typical weight w₁₂₈ for four dead-zone sizes ᾱ, {}: envelope per reference period, and the last periods in full (reading `{rid}`)",
            ctx.b_of("abar5")
        ),
        figure: Figure {
            title: "Fig. 7: w₁₂₈ of the NNBVSC, Fig. 2 case, for four ᾱ".into(),
            rows: 1,
            cols: 2,
            size: (1500, 620),
            footer: ctx.footer(&ids),
            panels: vec![a, b],
        },
    })
}

/// Fig. 8: the Fig. 2 case against half bias, half random variation: e and u.
fn fig8(runs: &BTreeMap<String, RunResult>, ctx: &FigureContext<'_>) -> Option<PaperFigure> {
    let rid = &ctx.reading.id;
    let (f2, f8) = (runs.get("fig2")?, runs.get("fig8")?);
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
    Some(PaperFigure {
        stem: "fig8".into(),
        caption: format!(
            "Fig. 8 — Fig. 2 case (—) and half bias, half random variation (-·-): {}, {} (reading `{rid}`){}",
            ctx.a_of("fig8"),
            ctx.b_of("fig8"),
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
    })
}
