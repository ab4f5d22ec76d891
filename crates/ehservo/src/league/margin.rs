//! The robustness margin: the largest scale of the margin scenario's keys
//! a controller stays bounded at, found by bisection.

use super::MarginCfg;
use crate::scenario::Loop;
use serde::Serialize;

/// A checked `[margin]`.
#[derive(Debug, Clone)]
pub struct Margin {
    /// As written.
    pub cfg: MarginCfg,
    pub(super) scenario: Loop,
    pub(super) table: toml::Table,
}

impl Margin {
    pub(super) fn build(
        &self,
        table: &toml::Table,
        x: f64,
    ) -> Result<Loop, crate::scenario::ScenarioError> {
        let mut tab = self.table.clone();
        tab.insert("controller".into(), toml::Value::Table(table.clone()));
        let sets: Vec<(String, toml::Value)> = self
            .cfg
            .keys
            .iter()
            .map(|k| (k.clone(), toml::Value::Float(self.cfg.scale * x)))
            .collect();
        self.scenario.with_values_on(tab, &sets)
    }

    /// Bisection steps at most (the two ends and the halvings).
    pub(super) fn steps(&self) -> u32 {
        2 + crate::bisection::halvings(self.cfg.low, self.cfg.high, self.cfg.tolerance)
    }

    /// Whether the run at x stays bounded.
    fn bounded(&self, table: &toml::Table, x: f64) -> bool {
        let Ok(lp) = self.build(table, x) else {
            return false;
        };
        let m = crate::run::run_metrics(&lp, &mut |_| {}).1;
        !m.diverged
            && m.e_max
                .is_some_and(|e| e.is_finite() && self.cfg.e_limit().is_none_or(|l| e <= l))
    }

    /// The margin of the controller with `table`.
    pub(super) fn bisect(
        &self,
        table: &toml::Table,
        progress: &indicatif::ProgressBar,
    ) -> MarginResult {
        let (lo, hi) = (self.cfg.low, self.cfg.high);
        let mut runs = 2;
        progress.inc(2);
        if self.bounded(table, hi) {
            return MarginResult {
                value: Some(hi),
                unbounded_at: None,
                at_least: true,
                below_low: false,
                runs,
            };
        }
        if !self.bounded(table, lo) {
            return MarginResult {
                value: None,
                unbounded_at: Some(lo),
                at_least: false,
                below_low: true,
                runs,
            };
        }
        let (lo, hi, n) = crate::bisection::bisect(lo, hi, self.cfg.tolerance, |mid| {
            progress.inc(1);
            Ok::<_, std::convert::Infallible>(self.bounded(table, mid))
        })
        .unwrap_or_else(|e| match e {});
        runs += n;
        MarginResult {
            value: Some(lo),
            unbounded_at: Some(hi),
            at_least: false,
            below_low: false,
            runs,
        }
    }
}

/// A controller's robustness margin.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct MarginResult {
    /// The largest bounded x found (None: `low` itself is unbounded).
    pub value: Option<f64>,
    /// The smallest unbounded x found (None: `high` is bounded); the
    /// margin lies between the two.
    pub unbounded_at: Option<f64>,
    /// `high` was bounded: the margin is at least `value`.
    pub at_least: bool,
    /// `low` was unbounded.
    pub below_low: bool,
    /// Runs made.
    pub runs: u32,
}

impl MarginResult {
    /// As a report cell: "1.23", "≥ 10", "< 0".
    pub fn text(&self, low: f64) -> String {
        match (self.value, self.at_least, self.below_low) {
            (_, _, true) => format!("< {low}"),
            (Some(v), true, _) => format!("≥ {v}"),
            (Some(v), false, _) => format!("{v:.3}"),
            (None, _, _) => "—".into(),
        }
    }
}
