//! Converged results: every case is run at successively refined
//! discretisations until its metrics stop moving.
//!
//! A reading fixes the *model* of the paper's simulation (the controller
//! sampled at 0.01 s with the control held, or evaluated in every RK4 stage;
//! the b convention) and one discretisation parameter (`refine.key`: the
//! plant's RK4 sub-steps per sample, or the step) with a ladder of values
//! (`refine.levels`), the first of which is the paper's set-up as printed.
//!
//! For each case the ladder is climbed until two successive levels agree on
//! the divergence status and on every metric the claims use (and
//! `e_max_deg`), within `max(rtol·|m|, atol[metric])`, with at least
//! `min_levels` levels run. The result is the finest level run; its
//! numerical margin per metric is the larger of
//! - the change from the previous level (the discretisation error of the
//!   coarser level, so a conservative bound on the finer one's for any
//!   convergent scheme in its asymptotic range), and
//! - the change when θ(0) is perturbed by `perturbation` rad (round-off
//!   level): the spread a second, equally correct implementation may see
//!   where the loop is sensitive to round-off.
//!
//! The first level's distance from the result is its discretisation error:
//! the report shows it, and labels the printed set-up "unconverged" where it
//! exceeds the tolerance.

use super::derived::CaseMetrics;
use super::doc::{Block, Doc};
use super::manifest::{Manifest, Reading};
use super::Reproduction;
use crate::scenario::Loop;
use anyhow::Result;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// `[convergence]` of the manifest: when two levels agree.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Tolerance {
    /// Relative tolerance on every metric.
    pub rtol: f64,
    /// Absolute floor per metric (metrics that tend to 0 under refinement,
    /// e.g. a sliding mode's error, converge in absolute terms only).
    pub atol: BTreeMap<String, f64>,
    /// Fewest levels run before convergence may be declared (≥ 2).
    pub min_levels: usize,
    /// Perturbation of θ(0) (rad) for the round-off margin.
    pub perturbation: f64,
    /// Slack on the divergence time: two diverged levels agree when their
    /// times differ by at most `rtol·t + time_slack` (s).
    pub time_slack: f64,
}

impl Default for Tolerance {
    fn default() -> Self {
        Self {
            rtol: 0.01,
            atol: BTreeMap::new(),
            min_levels: 3,
            perturbation: 1e-12,
            time_slack: 0.02,
        }
    }
}

impl Tolerance {
    /// The tolerance on `metric` at the value `v`.
    pub fn of(&self, metric: &str, v: f64) -> f64 {
        (self.rtol * v.abs()).max(self.atol.get(metric).copied().unwrap_or(0.0))
    }

    pub(super) fn check(&self, levels: usize, reading: &str) -> Result<()> {
        if !(self.rtol > 0.0 && self.rtol < 1.0) {
            crate::bad_input!(
                "[convergence] rtol: must be in (0, 1) (got {:?})",
                self.rtol
            );
        }
        for (k, v) in &self.atol {
            if !super::derived::is_metric(k) {
                crate::bad_input!("[convergence] atol: unknown metric `{k}`");
            }
            if !(v.is_finite() && *v >= 0.0) {
                crate::bad_input!("[convergence] atol.{k}: must be finite and ≥ 0 (got {v:?})");
            }
        }
        if self.min_levels < 2 {
            crate::bad_input!(
                "[convergence] min_levels: must be at least 2 (got {})",
                self.min_levels
            );
        }
        if levels < self.min_levels {
            crate::bad_input!(
                "reading `{reading}`: refine.levels has {levels} values, fewer than min_levels = {}",
                self.min_levels
            );
        }
        if !(self.perturbation.is_finite() && self.perturbation >= 0.0) {
            crate::bad_input!("[convergence] perturbation: must be finite and ≥ 0");
        }
        if !(self.time_slack.is_finite() && self.time_slack >= 0.0) {
            crate::bad_input!("[convergence] time_slack: must be finite and ≥ 0");
        }
        Ok(())
    }
}

/// One level of the ladder, run.
#[derive(Debug, Clone, Serialize)]
pub struct LevelRun {
    /// The value of `refine.key`.
    pub value: f64,
    /// What it measured.
    pub metrics: CaseMetrics,
}

/// A case under a reading, refined until converged.
#[derive(Debug, Clone, Serialize)]
pub struct Estimate {
    /// The levels run, coarsest (the printed set-up) first.
    pub levels: Vec<LevelRun>,
    /// The finest level with θ(0) perturbed.
    pub perturbed: CaseMetrics,
    /// The last two levels agree within the tolerance on every checked
    /// metric and the status.
    pub converged: bool,
    /// The metrics the convergence test used.
    pub checked: Vec<String>,
    /// Those of them (and `"status"`, the divergence status) on which the
    /// last two levels still differ by more than the tolerance.
    pub unconverged: Vec<String>,
}

fn metric_agrees(tol: &Tolerance, name: &str, a: Option<f64>, b: Option<f64>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => (a - b).abs() <= tol.of(name, b),
        _ => false,
    }
}

/// Where two runs differ beyond `tol`: `"status"` (bounded against
/// unbounded, or divergence times apart) or the names of `metrics`.
pub fn disagreements(
    tol: &Tolerance,
    a: &CaseMetrics,
    b: &CaseMetrics,
    metrics: &[String],
) -> Vec<String> {
    match (a.base.diverged_at_s, b.base.diverged_at_s) {
        (Some(ta), Some(tb)) if (ta - tb).abs() <= tol.rtol * tb + tol.time_slack => Vec::new(),
        (None, None) => metrics
            .iter()
            .filter(|m| !metric_agrees(tol, m, a.get(m), b.get(m)))
            .cloned()
            .collect(),
        _ => vec!["status".into()],
    }
}

/// Whether two runs agree within `tol` on the status and on `metrics`.
pub fn agree(tol: &Tolerance, a: &CaseMetrics, b: &CaseMetrics, metrics: &[String]) -> bool {
    disagreements(tol, a, b, metrics).is_empty()
}

impl Estimate {
    /// The result: the finest level run.
    pub fn best(&self) -> &CaseMetrics {
        &self.levels.last().expect("at least one level").metrics
    }

    /// The refinement value of the result.
    pub fn best_value(&self) -> f64 {
        self.levels.last().expect("at least one level").value
    }

    fn previous(&self) -> Option<&CaseMetrics> {
        let n = self.levels.len();
        (n >= 2).then(|| &self.levels[n - 2].metrics)
    }

    /// The numerical margin of `metric`: max(|m_L − m_{L−1}|, |m_L − m_pert|),
    /// None where it is undefined in any of the three runs.
    pub fn margin(&self, metric: &str) -> Option<f64> {
        let m = self.best().get(metric)?;
        let p = self.perturbed.get(metric)?;
        let d = match self.previous() {
            Some(prev) => (m - prev.get(metric)?).abs(),
            None => f64::INFINITY,
        };
        Some(d.max((m - p).abs()))
    }

    /// Whether `metric` (or `"status"`) converged.
    pub fn converged_on(&self, metric: &str) -> bool {
        !self
            .unconverged
            .iter()
            .any(|m| m == metric || m == "status")
    }

    /// The divergence status is the same at the last two levels and under
    /// the perturbation.
    pub fn status_stable(&self) -> bool {
        let d = self.best().base.diverged;
        self.previous().is_some_and(|p| p.base.diverged == d) && self.perturbed.base.diverged == d
    }

    /// |m(printed set-up) − m(result)|, None where undefined in either.
    pub fn literal_error(&self, metric: &str) -> Option<f64> {
        Some((self.levels[0].metrics.get(metric)? - self.best().get(metric)?).abs())
    }

    /// Whether the printed set-up (the first level) agrees with the result
    /// within the tolerance.
    pub fn literal_converged(&self, tol: &Tolerance) -> bool {
        agree(tol, &self.levels[0].metrics, self.best(), &self.checked)
    }
}

/// The metrics the claims use on `case` (always with `e_max_deg`).
pub fn checked_metrics(m: &Manifest, case: &str) -> Vec<String> {
    let mut v = vec!["e_max_deg".to_string()];
    for c in &m.claim {
        if c.case == case || c.other.as_deref() == Some(case) {
            if let Some(x) = &c.metric {
                if !v.contains(x) {
                    v.push(x.clone());
                }
            }
        }
    }
    v
}

/// The overrides of `reading` at the refinement `value`.
pub fn set_at(r: &Reading, value: f64) -> Vec<String> {
    let mut set = r.set.clone();
    set.push(format!(
        "{}={}",
        r.refine.key,
        format_value(&r.refine.key, value)
    ));
    set
}

fn format_value(key: &str, v: f64) -> String {
    if key.ends_with("substeps") {
        format!("{}", v as u64)
    } else {
        format!("{v:e}")
    }
}

/// Climbs the ladder of `reading` for the case file `file`.
pub fn estimate(
    dir: &Path,
    file: &str,
    r: &Reading,
    tol: &Tolerance,
    checked: Vec<String>,
    measure: &dyn Fn(&Loop) -> Result<CaseMetrics>,
) -> Result<Estimate> {
    let mut levels: Vec<LevelRun> = Vec::new();
    let mut unconverged = checked.clone();
    let mut last: Option<Loop> = None;
    for &value in &r.refine.levels {
        let s = Loop::load(&dir.join(file), &set_at(r, value)).map_err(anyhow::Error::from)?;
        let metrics = measure(&s)?;
        levels.push(LevelRun { value, metrics });
        last = Some(s);
        let n = levels.len();
        if n >= 2 {
            unconverged = disagreements(
                tol,
                &levels[n - 2].metrics,
                &levels[n - 1].metrics,
                &checked,
            );
        }
        if n >= tol.min_levels && unconverged.is_empty() {
            break;
        }
    }
    let mut s = last
        .expect("refine.levels is not empty (checked)")
        .scenario()
        .clone();
    s.simulation.x0[0] += tol.perturbation;
    let perturbed = measure(&Loop::new(s)?)?;
    Ok(Estimate {
        levels,
        perturbed,
        converged: unconverged.is_empty(),
        checked,
        unconverged,
    })
}

fn outcome(c: &CaseMetrics) -> String {
    match (c.base.diverged_at_s, c.base.e_max) {
        (Some(t), _) => format!("unbounded at {t:.2} s"),
        (None, Some(e)) => format!("{e:.4}°"),
        (None, None) => "—".into(),
    }
}

/// The report's convergence section: every case under every reading, the
/// printed set-up against the converged result.
pub(super) fn section(d: &mut Doc, m: &Manifest, rep: &Reproduction) {
    let tol = &m.convergence;
    d.push(Block::Heading(
        2,
        "Convergence: every case at successively refined discretisations".into(),
    ));
    let atol: Vec<String> = tol.atol.iter().map(|(k, v)| format!("{k} {v}")).collect();
    d.push(Block::Para(format!(
        "Each case is run at the reading's printed set-up (one RK4 step of 0.01 s), then with twice the plant \
sub-steps (sampled readings) or half the step (continuous readings), until two successive levels agree on the \
divergence status and on every metric its claims use, within max({} %·|m|, atol) (atol: {}), after at least {} \
levels. Claims are scored on the finest level run, with a margin: the larger of the change from the previous \
level and the change when θ(0) is perturbed by {:e} rad (round-off level). A claim whose measured value ± margin \
straddles its threshold, or whose metric is still moving at the finest level, is *undecided* and not counted as \
agreement. \"printed set-up\" is level 0; its error is its distance from the converged value.",
        100.0 * tol.rtol,
        if atol.is_empty() { "none".into() } else { atol.join(", ") },
        tol.min_levels,
        tol.perturbation
    )));
    let literal_off = rep
        .runs
        .iter()
        .filter(|r| !r.estimate.literal_converged(tol))
        .count();
    let unconverged: Vec<String> = rep
        .runs
        .iter()
        .filter(|r| !r.estimate.converged)
        .map(|r| {
            format!(
                "`{}` under `{}` ({})",
                r.case,
                r.reading,
                r.estimate.unconverged.join(", ")
            )
        })
        .collect();
    d.push(Block::Para(format!(
        "The printed set-up is unconverged (off the converged result by more than the tolerance) in {literal_off} \
of {} case runs. {}",
        rep.runs.len(),
        if unconverged.is_empty() {
            "Every case converged within its ladder.".to_string()
        } else {
            format!(
                "Still moving at the finest level (claims on these metrics are undecided): {}.",
                unconverged.join("; ")
            )
        }
    )));
    let rows = rep
        .runs
        .iter()
        .map(|r| {
            let e = &r.estimate;
            let reading = m.reading.iter().find(|x| x.id == r.reading);
            let key = reading.map(|x| x.refine.key.as_str()).unwrap_or("");
            let best = e.best();
            let converged = match (best.base.e_max, e.margin("e_max_deg")) {
                (Some(v), Some(dv)) => format!("{v:.4}° ± {dv:.4}"),
                _ => outcome(best),
            };
            vec![
                format!("`{}`", r.case),
                format!("`{}`", r.reading),
                outcome(&e.levels[0].metrics),
                converged,
                format!(
                    "{} = {} ({} levels)",
                    key.trim_start_matches("simulation."),
                    e.best_value(),
                    e.levels.len()
                ),
                match e.literal_error("e_max_deg") {
                    Some(x) => format!("{x:.4}°"),
                    None if e.levels[0].metrics.base.diverged != best.base.diverged => {
                        "status differs".into()
                    }
                    None => "—".into(),
                },
                if e.converged {
                    if e.literal_converged(tol) {
                        "converged (the printed set-up too)".into()
                    } else {
                        "converged; printed set-up unconverged".into()
                    }
                } else {
                    format!("unconverged: {}", e.unconverged.join(", "))
                },
            ]
        })
        .collect();
    d.push(Block::Table(
        vec![
            "case".into(),
            "reading".into(),
            "printed set-up: max |e|".into(),
            "converged: max |e| ± margin".into(),
            "finest level".into(),
            "printed set-up's error".into(),
            "status".into(),
        ],
        rows,
    ));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::Metrics;

    fn cm(e: Option<f64>, diverged_at: Option<f64>) -> CaseMetrics {
        let base = Metrics {
            e_max: e,
            e_final: None,
            e_rms: None,
            u_max: None,
            u_rms: None,
            chattering: None,
            u_tv_per_s: None,
            w_norm_max: None,
            w_norm_final: None,
            dead_zone_fraction: None,
            diverged: diverged_at.is_some(),
            diverged_at_s: diverged_at,
            samples: 0,
            axis: Default::default(),
            behaviour: Default::default(),
        };
        CaseMetrics::from(base)
    }

    #[test]
    fn levels_agree_within_the_relative_or_the_absolute_tolerance() {
        let mut tol = Tolerance::default();
        let m = vec!["e_max_deg".to_string()];
        // 1 % of 0.2 is 0.002.
        assert!(agree(
            &tol,
            &cm(Some(0.2019), None),
            &cm(Some(0.2), None),
            &m
        ));
        assert!(!agree(
            &tol,
            &cm(Some(0.2021), None),
            &cm(Some(0.2), None),
            &m
        ));
        // A sliding error tending to 0 converges only with a floor.
        assert!(!agree(
            &tol,
            &cm(Some(0.0011), None),
            &cm(Some(0.0006), None),
            &m
        ));
        tol.atol.insert("e_max_deg".into(), 1e-3);
        assert!(agree(
            &tol,
            &cm(Some(0.0011), None),
            &cm(Some(0.0006), None),
            &m
        ));
        // Bounded against unbounded never agree; undefined against defined neither.
        assert!(!agree(&tol, &cm(Some(0.2), None), &cm(None, Some(1.0)), &m));
        assert!(!agree(&tol, &cm(None, None), &cm(Some(0.2), None), &m));
        // Two divergences agree when their times do: 1 % + 0.02 s of 1.00 s.
        assert!(agree(
            &tol,
            &cm(None, Some(1.029)),
            &cm(None, Some(1.0)),
            &m
        ));
        assert!(!agree(
            &tol,
            &cm(None, Some(1.031)),
            &cm(None, Some(1.0)),
            &m
        ));
    }

    #[test]
    fn the_margin_is_the_larger_of_the_level_change_and_the_perturbation() {
        let e = Estimate {
            levels: vec![
                LevelRun {
                    value: 1.0,
                    metrics: cm(Some(0.30), None),
                },
                LevelRun {
                    value: 2.0,
                    metrics: cm(Some(0.25), None),
                },
                LevelRun {
                    value: 4.0,
                    metrics: cm(Some(0.24), None),
                },
            ],
            perturbed: cm(Some(0.21), None),
            converged: false,
            checked: vec!["e_max_deg".into()],
            unconverged: vec!["e_max_deg".into()],
        };
        let close = |a: Option<f64>, b: f64| (a.unwrap() - b).abs() < 1e-12;
        assert!(close(e.margin("e_max_deg"), 0.03));
        assert!(close(e.literal_error("e_max_deg"), 0.06));
        assert!(e.status_stable());
        assert!(!e.literal_converged(&Tolerance::default()));
        let mut d = e.clone();
        d.perturbed = cm(None, Some(3.0));
        assert!(!d.status_stable());
        assert_eq!(d.margin("e_max_deg"), None);
    }
}
