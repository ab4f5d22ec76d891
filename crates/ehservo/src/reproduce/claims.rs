//! Scoring the paper's claims against measured metrics.

use super::derived::{format_metric, CaseMetrics};
use super::manifest::{Claim, ClaimKind};
use serde::Serialize;
use std::collections::BTreeMap;

/// Outcome of a claim.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// The measurement agrees with the claim.
    Agree,
    /// It does not.
    Differ,
    /// It cannot be decided (a run diverged, a metric is undefined).
    Undetermined,
}

impl Status {
    /// Short word for tables.
    pub fn word(&self) -> &'static str {
        match self {
            Status::Agree => "agree",
            Status::Differ => "differ",
            Status::Undetermined => "undetermined",
        }
    }
}

/// A scored claim.
#[derive(Debug, Clone, Serialize)]
pub struct Verdict {
    /// Agree, differ or undetermined.
    pub status: Status,
    /// The measured figure, formatted.
    pub measured: String,
    /// How the measurement was compared.
    pub detail: String,
}

fn undetermined(why: String) -> Verdict {
    Verdict {
        status: Status::Undetermined,
        measured: "—".into(),
        detail: why,
    }
}

fn divergence(m: &CaseMetrics) -> String {
    match m.base.diverged_at_s {
        Some(t) => format!("unbounded at t = {t:.2} s"),
        None => "bounded".into(),
    }
}

/// Scores `claim` with the metrics of each case.
pub fn evaluate(claim: &Claim, results: &BTreeMap<String, CaseMetrics>) -> Verdict {
    let Some(m) = results.get(&claim.case) else {
        return undetermined(format!("case `{}` was not run", claim.case));
    };
    let other = claim.other.as_ref().and_then(|o| results.get(o));
    let metric = claim.metric.as_deref().unwrap_or("");
    let get = |c: &CaseMetrics, who: &str| -> Result<f64, Verdict> {
        c.get(metric).ok_or_else(|| {
            undetermined(if c.base.diverged {
                format!("`{who}` {}: {metric} undefined", divergence(c))
            } else {
                format!("{metric} undefined for `{who}`")
            })
        })
    };
    let status = |b: bool| if b { Status::Agree } else { Status::Differ };
    let fm = |v: f64| format_metric(metric, v);
    match claim.kind {
        ClaimKind::Bounded | ClaimKind::Unbounded => {
            let want_bounded = claim.kind == ClaimKind::Bounded;
            Verdict {
                status: status(m.base.diverged != want_bounded),
                measured: divergence(m),
                detail: if want_bounded {
                    "expects bounded"
                } else {
                    "expects unbounded"
                }
                .into(),
            }
        }
        ClaimKind::Approx | ClaimKind::AtLeast | ClaimKind::AtMost => {
            let v = match get(m, &claim.case) {
                Ok(v) => v,
                Err(u) => return u,
            };
            let target = claim.value.unwrap_or(f64::NAN);
            let (ok, detail) = match claim.kind {
                ClaimKind::Approx => {
                    let tol = claim.tol.unwrap_or(0.0);
                    (
                        (v - target).abs() <= tol * target.abs(),
                        format!(
                            "paper {} ± {:.0} %: measured/paper = {:.2}",
                            fm(target),
                            100.0 * tol,
                            v / target
                        ),
                    )
                }
                ClaimKind::AtLeast => (v >= target, format!("expects ≥ {}", fm(target))),
                _ => (v <= target, format!("expects ≤ {}", fm(target))),
            };
            Verdict {
                status: status(ok),
                measured: fm(v),
                detail,
            }
        }
        ClaimKind::Less | ClaimKind::Greater | ClaimKind::Ratio | ClaimKind::Similar => {
            let Some(o) = other else {
                return undetermined("the other case was not run".into());
            };
            let oname = claim.other.as_deref().unwrap_or("");
            let v = match get(m, &claim.case) {
                Ok(v) => v,
                Err(u) => return u,
            };
            let w = match get(o, oname) {
                Ok(w) => w,
                Err(u) => return u,
            };
            let measured = format!("{} vs {}", fm(v), fm(w));
            let (ok, detail) = match claim.kind {
                ClaimKind::Less => (v < w, format!("expects {} < {}", claim.case, oname)),
                ClaimKind::Greater => (v > w, format!("expects {} > {}", claim.case, oname)),
                ClaimKind::Ratio => {
                    let target = claim.value.unwrap_or(f64::NAN);
                    let tol = claim.tol.unwrap_or(0.0);
                    let r = v / w;
                    (
                        (r - target).abs() <= tol * target,
                        format!("ratio {r:.2}, paper {target} ± {:.0} %", 100.0 * tol),
                    )
                }
                _ => {
                    let tol = claim.tol.unwrap_or(0.0);
                    let r = v / w;
                    (
                        (r - 1.0).abs() <= tol,
                        format!("ratio {r:.2}, similar within ± {:.0} %", 100.0 * tol),
                    )
                }
            };
            Verdict {
                status: status(ok),
                measured,
                detail,
            }
        }
    }
}
