//! Scoring the paper's claims against measured metrics.

use super::convergence::Estimate;
use super::derived::{format_metric, CaseMetrics};
use super::manifest::{Claim, ClaimKind};
use serde::Serialize;
use std::collections::BTreeMap;

/// Outcome of a claim.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// The measurement agrees with the claim, by more than its numerical
    /// margin.
    Agree,
    /// It does not, by more than its numerical margin.
    Differ,
    /// The numerical margin (discretisation error, round-off sensitivity)
    /// straddles the claim's threshold, or the case did not converge: not
    /// counted as agreement.
    Undecided,
    /// It cannot be scored (a run diverged, a metric is undefined).
    Undetermined,
}

impl Status {
    /// Short word for tables.
    pub fn word(&self) -> &'static str {
        match self {
            Status::Agree => "agree",
            Status::Differ => "differ",
            Status::Undecided => "undecided",
            Status::Undetermined => "undetermined",
        }
    }
}

/// A scored claim.
#[derive(Debug, Clone, Serialize)]
pub struct Verdict {
    /// Agree, differ, undecided or undetermined.
    pub status: Status,
    /// The measured figure (± its numerical margin), formatted.
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

/// An interval [lo, hi] scored against a set: inside entirely (agree),
/// outside entirely (differ), or across its edge (undecided).
fn interval_status(lo: f64, hi: f64, inside: &dyn Fn(f64) -> bool) -> Status {
    match (inside(lo), inside(hi)) {
        (true, true) => Status::Agree,
        (false, false) => Status::Differ,
        _ => Status::Undecided,
    }
}

/// `v ± δ` scored against the band [a, b] (a ≤ b).
pub fn band_status(v: f64, d: f64, a: f64, b: f64) -> Status {
    let (lo, hi) = (v - d, v + d);
    if lo >= a && hi <= b {
        Status::Agree
    } else if hi < a || lo > b {
        Status::Differ
    } else {
        Status::Undecided
    }
}

/// A measured value with its numerical margin.
#[derive(Debug, Clone, Copy)]
struct Value {
    v: f64,
    d: f64,
}

/// Undecided when what `claim` reads (its metric, or the divergence status)
/// had not converged at the finest level of its case or its other case.
pub fn unconverged(claim: &Claim, results: &BTreeMap<String, Estimate>) -> Option<Verdict> {
    let metric = claim.metric.as_deref().unwrap_or("");
    let what = if metric.is_empty() { "status" } else { metric };
    [Some(claim.case.as_str()), claim.other.as_deref()]
        .into_iter()
        .flatten()
        .find_map(|who| {
            let e = results.get(who)?;
            (!e.converged_on(what)).then(|| Verdict {
                status: Status::Undecided,
                measured: format!("`{who}`: {}", fm_or_status(e.best(), metric)),
                detail: format!(
                    "`{who}`: {what} still moving at the finest level run ({} of them, last {})",
                    e.levels.len(),
                    e.best_value()
                ),
            })
        })
}

/// Scores `claim` with the converged estimate of each case. A claim on a
/// case that did not converge is undecided; otherwise the measured value ±
/// its margin (see `convergence`) must lie wholly on one side of the claim.
pub fn evaluate(claim: &Claim, results: &BTreeMap<String, Estimate>) -> Verdict {
    let Some(me) = results.get(&claim.case) else {
        return undetermined(format!("case `{}` was not run", claim.case));
    };
    let oe = claim.other.as_ref().and_then(|o| results.get(o));
    if let Some(v) = unconverged(claim, results) {
        return v;
    }
    match claim.kind {
        ClaimKind::Bounded | ClaimKind::Unbounded => bounded_verdict(claim, me),
        ClaimKind::Approx | ClaimKind::AtLeast | ClaimKind::AtMost => value_verdict(claim, me),
        ClaimKind::Less | ClaimKind::Greater | ClaimKind::Ratio | ClaimKind::Similar => {
            let Some(o) = oe else {
                return undetermined("the other case was not run".into());
            };
            pair_verdict(claim, me, o)
        }
    }
}

/// The claim's metric at a case's converged level with its margin, or the
/// undetermined verdict saying why there is none.
fn value_of(e: &Estimate, who: &str, metric: &str) -> Result<Value, Verdict> {
    let c = e.best();
    match (c.get(metric), e.margin(metric)) {
        (Some(v), Some(d)) => Ok(Value { v, d }),
        _ => Err(undetermined(if c.base.diverged {
            format!("`{who}` {}: {metric} undefined", divergence(c))
        } else {
            format!("{metric} undefined for `{who}` (or under the perturbation)")
        })),
    }
}

/// A value of `metric` as measured: `v ± d`, or `v` without a margin.
fn format_measured(metric: &str, x: Value) -> String {
    let fm = |v: f64| format_metric(metric, v);
    if x.d > 0.0 {
        format!("{} ± {}", fm(x.v), fm(x.d).trim_start_matches('+'))
    } else {
        fm(x.v)
    }
}

/// A bounded or unbounded claim: the case's divergence status, undecided
/// when it changes with the level or the perturbation.
fn bounded_verdict(claim: &Claim, me: &Estimate) -> Verdict {
    let m = me.best();
    let want_bounded = claim.kind == ClaimKind::Bounded;
    let status = if !me.status_stable() {
        Status::Undecided
    } else if m.base.diverged != want_bounded {
        Status::Agree
    } else {
        Status::Differ
    };
    Verdict {
        status,
        measured: divergence(m),
        detail: format!(
            "expects {}{}",
            if want_bounded { "bounded" } else { "unbounded" },
            if me.status_stable() {
                ""
            } else {
                "; the status changes with the level or the perturbation"
            }
        ),
    }
}

/// A claim on one case's value: about the paper's (within its tolerance),
/// at least or at most it.
fn value_verdict(claim: &Claim, me: &Estimate) -> Verdict {
    let metric = claim.metric.as_deref().unwrap_or("");
    let fm = |v: f64| format_metric(metric, v);
    let x = match value_of(me, &claim.case, metric) {
        Ok(x) => x,
        Err(u) => return u,
    };
    let target = claim.value.unwrap_or(f64::NAN);
    let (status, detail) = match claim.kind {
        ClaimKind::Approx => {
            let tol = claim.tol.unwrap_or(0.0) * target.abs();
            (
                band_status(x.v, x.d, target - tol, target + tol),
                format!(
                    "paper {} ± {:.0} %: measured/paper = {:.2}",
                    fm(target),
                    100.0 * claim.tol.unwrap_or(0.0),
                    x.v / target
                ),
            )
        }
        ClaimKind::AtLeast => (
            interval_status(x.v - x.d, x.v + x.d, &|v| v >= target),
            format!("expects ≥ {}", fm(target)),
        ),
        _ => (
            interval_status(x.v - x.d, x.v + x.d, &|v| v <= target),
            format!("expects ≤ {}", fm(target)),
        ),
    };
    Verdict {
        status,
        measured: format_measured(metric, x),
        detail,
    }
}

/// A claim comparing the case with the other: less, greater, a ratio
/// about the paper's, or similar (a ratio about 1).
fn pair_verdict(claim: &Claim, me: &Estimate, o: &Estimate) -> Verdict {
    let metric = claim.metric.as_deref().unwrap_or("");
    let oname = claim.other.as_deref().unwrap_or("");
    let x = match value_of(me, &claim.case, metric) {
        Ok(x) => x,
        Err(u) => return u,
    };
    let y = match value_of(o, oname, metric) {
        Ok(y) => y,
        Err(u) => return u,
    };
    let measured = format!(
        "{} vs {}",
        format_measured(metric, x),
        format_measured(metric, y)
    );
    // The difference x − y with margin δx + δy; the ratio x/y with
    // the first-order relative margin δx/|x| + δy/|y| (undecided
    // when either margin reaches its value).
    let diff = Value {
        v: x.v - y.v,
        d: x.d + y.d,
    };
    let ratio = || -> Option<Value> {
        let rel = x.d / x.v.abs() + y.d / y.v.abs();
        let r = x.v / y.v;
        (rel < 1.0 && r.is_finite()).then(|| Value {
            v: r,
            d: r.abs() * rel,
        })
    };
    let (status, detail) = match claim.kind {
        ClaimKind::Less => (
            interval_status(diff.v - diff.d, diff.v + diff.d, &|v| v < 0.0),
            format!("expects {} < {}", claim.case, oname),
        ),
        ClaimKind::Greater => (
            interval_status(diff.v - diff.d, diff.v + diff.d, &|v| v > 0.0),
            format!("expects {} > {}", claim.case, oname),
        ),
        kind => {
            let (target, what) = if kind == ClaimKind::Ratio {
                (claim.value.unwrap_or(f64::NAN), "paper")
            } else {
                (1.0, "similar:")
            };
            let tol = claim.tol.unwrap_or(0.0);
            match ratio() {
                Some(r) => (
                    band_status(r.v, r.d, target * (1.0 - tol), target * (1.0 + tol)),
                    format!(
                        "ratio {:.2} ± {:.2}, {what} {target} ± {:.0} %",
                        r.v,
                        r.d,
                        100.0 * tol
                    ),
                ),
                None => (
                    Status::Undecided,
                    "the margins reach the values: the ratio is not determined".into(),
                ),
            }
        }
    };
    Verdict {
        status,
        measured,
        detail,
    }
}

fn fm_or_status(c: &CaseMetrics, metric: &str) -> String {
    match c.get(metric) {
        Some(v) if !metric.is_empty() => format_metric(metric, v),
        _ => divergence(c),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_margin_across_the_band_edge_is_undecided() {
        // Band 0.08 ± 25 % = [0.06, 0.10].
        assert_eq!(band_status(0.08, 0.01, 0.06, 0.10), Status::Agree);
        assert_eq!(band_status(0.095, 0.01, 0.06, 0.10), Status::Undecided);
        assert_eq!(band_status(0.12, 0.01, 0.06, 0.10), Status::Differ);
        assert_eq!(band_status(0.04, 0.019, 0.06, 0.10), Status::Differ);
        assert_eq!(band_status(0.04, 0.021, 0.06, 0.10), Status::Undecided);
        // v < 0 with v ∈ [−0.1, 0.05]: undecided; [−0.3, −0.1]: agree.
        assert_eq!(interval_status(-0.1, 0.05, &|v| v < 0.0), Status::Undecided);
        assert_eq!(interval_status(-0.3, -0.1, &|v| v < 0.0), Status::Agree);
        assert_eq!(interval_status(0.1, 0.3, &|v| v < 0.0), Status::Differ);
    }
}
