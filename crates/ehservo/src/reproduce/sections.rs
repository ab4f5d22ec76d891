//! The report's longer sections: findings, sensitivity and theory.

use super::claims::Status;
use super::derived::CaseMetrics;
use super::doc::{Block, Doc};
use super::manifest::Manifest;
use super::Reproduction;

fn e_max_text(c: &CaseMetrics) -> String {
    match (c.base.e_max, c.base.diverged_at_s) {
        (_, Some(t)) => format!("unbounded at {t:.2} s"),
        (Some(e), None) => format!("{e:.4}°"),
        (None, None) => "—".into(),
    }
}

pub(super) fn sensitivity_section(d: &mut Doc, m: &Manifest, rep: &Reproduction) {
    if rep.sensitivity.is_empty() {
        return;
    }
    d.push(Block::Heading(
        2,
        "How much each ambiguity moves the results".into(),
    ));
    d.push(Block::Para(format!(
        "Each variation is applied on top of the chosen reading (`{}`); e_max is max |e| after the transient \
window. The discussion is in `docs/paper-notes.md`.",
        rep.primary_reading
    )));
    let rel = |a: Option<f64>, b: f64| match a {
        Some(a) if a > 0.0 => format!("{:+.1} %", 100.0 * (b / a - 1.0)),
        _ => "—".into(),
    };
    let rows = rep
        .sensitivity
        .iter()
        .map(|r| {
            let q = m
                .sensitivity
                .iter()
                .find(|s| s.id == r.id)
                .map(|s| s.question.clone())
                .unwrap_or_default();
            let base = r.baseline.base.e_max;
            let (variant, change) = if r.seeds_e_max_deg.is_empty() {
                let change = match r.variant.base.e_max {
                    Some(b) if !r.variant.base.diverged => rel(base, b),
                    _ => "—".into(),
                };
                (e_max_text(&r.variant), change)
            } else {
                let mut v: Vec<f64> = r.seeds_e_max_deg.iter().flatten().copied().collect();
                v.sort_by(f64::total_cmp);
                let unbounded = r.seeds_e_max_deg.len() - v.len();
                if v.is_empty() {
                    ("all unbounded".into(), "—".into())
                } else {
                    let (lo, hi) = (v[0], v[v.len() - 1]);
                    let med = v[v.len() / 2];
                    let extra = if unbounded > 0 {
                        format!(", {unbounded} unbounded")
                    } else {
                        String::new()
                    };
                    (
                        format!(
                            "{} seeds: min {lo:.4}°, median {med:.4}°, max {hi:.4}°{extra}",
                            r.seeds_e_max_deg.len()
                        ),
                        format!("{} … {}", rel(base, lo), rel(base, hi)),
                    )
                }
            };
            vec![
                format!("`{}`: {q}", r.id),
                format!("`{}`", r.case),
                e_max_text(&r.baseline),
                variant,
                change,
            ]
        })
        .collect();
    d.push(Block::Table(
        vec![
            "variation".into(),
            "case".into(),
            "baseline e_max".into(),
            "with the variation".into(),
            "change".into(),
        ],
        rows,
    ));
}

/// Which claims hold in which readings, in a few lines. Readings in which
/// the NNBVSC of Fig. 2 itself diverges ("unstable") are set apart.
pub(super) fn findings(d: &mut Doc, m: &Manifest, rep: &Reproduction) {
    let stable: Vec<&str> = m
        .reading
        .iter()
        .filter(|r| {
            !rep.runs
                .iter()
                .any(|c| c.reading == r.id && c.case == "fig2" && c.metrics.base.diverged)
        })
        .map(|r| r.id.as_str())
        .collect();
    let unstable: Vec<String> = m
        .reading
        .iter()
        .filter(|r| !stable.contains(&r.id.as_str()))
        .map(|r| format!("`{}`", r.id))
        .collect();
    let (mut all, mut none, mut some) = (Vec::new(), Vec::new(), Vec::new());
    for (c, row) in m.claim.iter().zip(&rep.claims) {
        let agreeing: Vec<&str> = stable
            .iter()
            .copied()
            .filter(|r| row.verdicts[*r].status == Status::Agree)
            .collect();
        let line = format!("`{}` — {}", c.id, c.text);
        if agreeing.is_empty() {
            none.push(line);
        } else if agreeing.len() == stable.len() {
            all.push(line);
        } else {
            some.push(format!("{line} (agrees under: {})", agreeing.join(", ")));
        }
    }
    d.push(Block::Heading(2, "Findings".into()));
    let primary = &rep.primary_reading;
    let differ: Vec<String> = m
        .claim
        .iter()
        .zip(&rep.claims)
        .filter(|(_, row)| row.verdicts[primary].status != Status::Agree)
        .map(|(c, row)| format!("`{}` ({})", c.id, row.verdicts[primary].status.word()))
        .collect();
    d.push(Block::Para(format!(
        "Under the chosen reading `{primary}`, {} of {} claims agree; the others are {}.",
        rep.agreements[primary],
        m.claim.len(),
        if differ.is_empty() {
            "none".into()
        } else {
            differ.join(", ")
        }
    )));
    if !unstable.is_empty() {
        d.push(Block::Para(format!(
            "The NNBVSC of Fig. 2 diverges under {}: {} left out of the lists below.",
            unstable.join(", "),
            if unstable.len() == 1 {
                "that reading is"
            } else {
                "those readings are"
            }
        )));
    }
    for (title, list) in [
        ("Claims reproduced under **every** stable reading:", all),
        ("Claims that depend on the reading:", some),
        ("Claims that **no** reading reproduces:", none),
    ] {
        if !list.is_empty() {
            d.push(Block::Para(title.into()));
            d.push(Block::List(list));
        }
    }
}

pub(super) fn theory_section(d: &mut Doc, rep: &Reproduction) {
    let Some((_, a)) = rep.theory.first() else {
        return;
    };
    d.push(Block::Heading(
        2,
        "What the theory says of the Fig. 2 case (`ehservo analyze`)".into(),
    ));
    let s = &a.surface;
    let mut items = vec![
        format!(
            "Plant: ā = ({:.5}, {:.4}, {:.5}), b̄ = {:.2} s⁻³V⁻¹ at Pl = 0; open-loop poles {:.4e}, {:.4} ± j{:.4}.",
            a.a_nominal[0],
            a.a_nominal[1],
            a.a_nominal[2],
            a.b_at_rest,
            a.open_loop_poles[0].re,
            a.open_loop_poles[1].re,
            a.open_loop_poles[1].im.abs()
        ),
        format!(
            "Theorem 2: K2 = {:.4}, K1 = {} (checked on an independent grid: {}), bound K2/K1 = {:.4e}. {}",
            s.k2,
            s.k1.value.map(|v| format!("{v:.4}")).unwrap_or("∞".into()),
            if s.k1.verified { "verified" } else { "not verified" },
            s.alpha_bound,
            s.verdict
        ),
    ];
    if let Some(w) = &a.weights {
        items.push(format!("Remark 6: {}", w.note));
    }
    if let Some(dg) = &rep.fig2_diagnostics {
        items.push(format!(
            "Along the Fig. 2 run (reading `{}`): condition 4) of Theorem 3 holds at {:.1} % of the samples (left half {:.1} %, right half α‖E‖ < c/γ1 + ᾱ‖E‖ {:.1} %: it needs ‖E‖ ≈ 1e-4); {:.1} % of the samples are in the dead zone. The paper's runs illustrate the controller, not the theorem's guarantee.",
            rep.primary_reading,
            100.0 * dg.condition4,
            100.0 * dg.condition4_left,
            100.0 * dg.condition4_right,
            100.0 * dg.dead_zone
        ));
        items.push(format!(
            "Assumption A5 and Remark 6 along the same run: {}",
            dg.weights.note
        ));
    }
    d.push(Block::List(items));
    d.push(Block::Para(
        "The linearised closed loop (W = 0, σΔ = σ) under each reading: the fast σ eigenvalue and whether the \
simulation scheme is stable on it (continuous: RK4's |R(hλ)| < 1; sampled: the one-sample map's spectral radius < 1)."
            .into(),
    ));
    let rows = rep
        .theory
        .iter()
        .map(|(r, a)| {
            let l = &a.closed_loop;
            vec![
                format!("`{r}`"),
                l.sigma_gain
                    .map(|g| format!("{g:.1}"))
                    .unwrap_or("—".into()),
                l.fast.map(|f| format!("{f:.1} s⁻¹")).unwrap_or("—".into()),
                l.growth.map(|g| format!("{g:.4}")).unwrap_or("—".into()),
                match l.stable {
                    Some(true) => "stable".into(),
                    Some(false) => "UNSTABLE".into(),
                    None => "—".into(),
                },
            ]
        })
        .collect();
    d.push(Block::Table(
        vec![
            "reading".into(),
            "σ-loop gain b/(b̄ − β)·γ1".into(),
            "fast eigenvalue".into(),
            "growth per step".into(),
            "scheme".into(),
        ],
        rows,
    ));
}
