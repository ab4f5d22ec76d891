//! The Δb question (docs/paper-notes.md N11), stated in the report: what the
//! text's convention and the hypothesis that fits the printed numbers give
//! in every case.
//!
//! Readings come in pairs that differ only by `uncertainty.b_reference=1.0`
//! (b fractions of b̄ itself, so "50 % of b" is Δb = β) against the default
//! 0.5 (fractions of β, the text's "100 % and 50 % of bias": Δb = 0.5β).

use super::doc::{Block, Doc};
use super::manifest::{ClaimKind, Manifest};
use super::Reproduction;

const BFULL: &str = "uncertainty.b_reference=1.0";

/// (reading with the text's convention, reading with Δb = β) pairs.
pub fn pairs(m: &Manifest) -> Vec<(&str, &str)> {
    let mut v = Vec::new();
    for full in m
        .reading
        .iter()
        .filter(|r| r.set.iter().any(|s| s == BFULL))
    {
        let rest: Vec<&String> = full.set.iter().filter(|s| *s != BFULL).collect();
        if let Some(text) = m.reading.iter().find(|r| {
            r.refine.key == full.refine.key
                && r.set.len() == rest.len()
                && r.set.iter().zip(&rest).all(|(a, b)| a == *b)
        }) {
            v.push((text.id.as_str(), full.id.as_str()));
        }
    }
    v
}

fn e_max(rep: &Reproduction, reading: &str, case: &str) -> String {
    rep.runs
        .iter()
        .find(|r| r.reading == reading && r.case == case)
        .map(
            |r| match (r.metrics.base.diverged_at_s, r.metrics.base.e_max) {
                (Some(t), _) => format!("unbounded at {t:.2} s"),
                (None, Some(e)) => format!("{e:.4}°"),
                _ => "—".into(),
            },
        )
        .unwrap_or_else(|| "—".into())
}

/// The report's section on the Δb question.
pub(super) fn section(d: &mut Doc, m: &Manifest, rep: &Reproduction) {
    let pairs = pairs(m);
    if pairs.is_empty() {
        return;
    }
    d.push(Block::Heading(2, "The Δb question".into()));
    d.push(Block::Para(
        "The text defines the variation of the Fig. 2 case as \"100 % and 50 % of bias\", i.e. Δa_i = α_i and \
Δb = 0.5β: percentages of the bounds α_i = |ā_i|, β = 0.5|b̄|. Read with the same convention, the caption's \
\"100 % bias except 50 % bias of parameter b\" is Δb = 0.5β too; that is SPEC's reading and the scenario files' \
default. Δb = β (50 % of b̄ itself, `uncertainty.b_reference = 1`) is a *hypothesis*: it is not what the text \
says, but it is the variation under which the paper's absolute numbers (0.08° in Fig. 2, 0.05° for γ1 = 200) \
come out. It changes every case that has a b variation, not only Fig. 2: Fig. 3's \"40 % bias\" becomes \
Δb = 0.4·b̄ = 0.8β, Fig. 8's half bias, half random becomes b̄(0.25 + 0.25r). Converged max |e| after the \
transient under both:"
            .into(),
    ));
    let mut head = vec!["case".to_string(), "paper".to_string()];
    for (a, b) in &pairs {
        head.push(format!("`{a}` (Δb = 0.5β)"));
        head.push(format!("`{b}` (Δb = β)"));
    }
    let rows = m
        .case
        .iter()
        .map(|c| {
            let paper = m
                .claim
                .iter()
                .find(|k| {
                    k.case == c.id
                        && k.kind == ClaimKind::Approx
                        && k.metric.as_deref() == Some("e_max_deg")
                })
                .and_then(|k| k.value)
                .map(|v| format!("{v}°"))
                .unwrap_or_default();
            let mut row = vec![format!("`{}`", c.id), paper];
            for (a, b) in &pairs {
                row.push(e_max(rep, a, &c.id));
                row.push(e_max(rep, b, &c.id));
            }
            row
        })
        .collect();
    d.push(Block::Table(head, rows));
}
