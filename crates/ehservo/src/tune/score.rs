//! One evaluation of the objective: a candidate's parameters set on every
//! scenario × draw, run, and scored (e_max plus the penalties).

use super::{Objective, Scale, Tune};
use crate::freq::stability::Stability;
use crate::metrics::Metrics;
use crate::scenario::Loop;

/// One run of a candidate: its metrics and, for a linear law whose run was
/// acceptable, its loop's computed stability.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// The run's metrics.
    pub metrics: Metrics,
    /// The loop's computed margins (None: a nonlinear law, margins not
    /// asked, or a run already rejected).
    pub stability: Option<Stability>,
}

impl Tune {
    /// The overrides of one evaluation of `values`: one list per
    /// scenario × draw.
    pub(super) fn sets(&self, values: &[f64]) -> Vec<Vec<(String, toml::Value)>> {
        self.sets_of(Some(values))
    }

    /// [`Tune::sets`] of `values`, or of the kind's default parameters.
    pub(super) fn sets_of(&self, values: Option<&[f64]>) -> Vec<Vec<(String, toml::Value)>> {
        let mut out = Vec::new();
        for _ in &self.scenarios {
            for d in 0..self.file.draws {
                let mut sets = vec![(
                    "controller.kind".to_string(),
                    toml::Value::String(self.kind.into()),
                )];
                for (r, &v) in self.params.iter().zip(values.unwrap_or(&[])) {
                    sets.push((format!("controller.{}", r.key), toml::Value::Float(v)));
                }
                if self.file.draws > 1 {
                    sets.push(("uncertainty.seed".into(), toml::Value::Integer(d as i64)));
                }
                out.push(sets);
            }
        }
        out
    }

    pub(super) fn build_run(
        &self,
        run: usize,
        sets: &[(String, toml::Value)],
    ) -> Result<Loop, crate::scenario::ScenarioError> {
        let i = run / self.file.draws as usize;
        self.scenarios[i].with_values_on(self.tables[i].clone(), sets)
    }

    /// The searched parameters' values at the kind's defaults on the first
    /// scenario: given in its `[controller]`, or derived by the kind's
    /// design there ([`Loop::designed`]); a key with neither (a kind that
    /// does not report its derivation) is left out.
    pub fn default_values(&self) -> Vec<(String, f64)> {
        let Some(Ok(lp)) = self.sets_of(None).first().map(|s| self.build_run(0, s)) else {
            return Vec::new();
        };
        let given = lp
            .table()
            .ok()
            .and_then(|t| t.get("controller").and_then(|c| c.as_table()).cloned())
            .unwrap_or_default();
        let designed = lp.designed();
        self.params
            .iter()
            .filter_map(|r| {
                let v = match given.get(&r.key) {
                    Some(toml::Value::Float(x)) => Some(*x),
                    Some(toml::Value::Integer(i)) => Some(*i as f64),
                    _ => designed.iter().find(|(k, _)| *k == r.key).map(|p| p.1),
                };
                v.map(|v| (r.key.clone(), v))
            })
            .collect()
    }

    /// The parameter values of a point of the search space.
    pub fn values(&self, p: &[f64]) -> Vec<f64> {
        self.params
            .iter()
            .zip(p)
            .map(|(r, &x)| match r.scale {
                Scale::Log => 10f64.powf(x).clamp(r.low, r.high),
                Scale::Linear => x.clamp(r.low, r.high),
            })
            .collect()
    }

    /// The evaluation of every scenario × draw at `values` (None where the
    /// controller refused them).
    pub fn evaluate(&self, values: &[f64]) -> Vec<Option<Evaluation>> {
        self.evaluate_sets(&self.sets(values))
    }

    fn evaluate_sets(&self, sets: &[Vec<(String, toml::Value)>]) -> Vec<Option<Evaluation>> {
        sets.iter()
            .enumerate()
            .map(|(i, sets)| {
                self.build_run(i, sets)
                    .ok()
                    .map(|lp| self.evaluate_loop(&lp))
            })
            .collect()
    }

    /// One run of `lp` and, when its run is acceptable and margins are
    /// asked, its loop's computed stability ([`crate::freq::stability`];
    /// None for a nonlinear law).
    pub fn evaluate_loop(&self, lp: &Loop) -> Evaluation {
        let metrics = crate::run::run_metrics(lp, &mut |_| {}).1;
        let acceptable =
            !metrics.diverged && metrics.e_max.is_some() && self.rejections(&metrics).is_empty();
        let stability = (acceptable && self.file.reject.asks_margins())
            .then(|| crate::freq::stability::computed(lp))
            .flatten();
        Evaluation { metrics, stability }
    }

    /// Whether the tuned kind is a linear law (its margins are computed):
    /// a kind `ehservo freq` has a linear model of.
    pub fn is_linear(&self) -> bool {
        let (Some(cfg), Some(lp)) = (
            crate::scenario::ControllerCfg::default_of(self.kind),
            self.scenarios.first(),
        ) else {
            return false;
        };
        crate::freq::controllers::controller_model(&cfg, lp.design()).is_some()
    }

    /// Why a loop's computed stability rejects it (`[reject]`'s margins),
    /// or None.
    pub fn margin_rejection(&self, s: Option<&Stability>) -> Option<String> {
        let r = &self.file.reject;
        s?.short_of(r.gain_margin_db, r.phase_margin_deg)
    }

    /// A run's findings that reject a candidate ([`super::Reject`]):
    /// unbounded, an end stop hit, a sustained oscillation, a saturation
    /// share above `reject.saturation_share`. Empty: acceptable.
    pub fn rejections(&self, m: &Metrics) -> Vec<crate::behaviour::Finding> {
        m.behaviour
            .findings_with(m.diverged, self.file.reject.saturation_share)
    }

    /// One run's score: e_max (in the axis's unit, ° or mm) plus the
    /// penalties; +∞ when unbounded, refused, undefined, or rejected
    /// ([`Tune::rejections`], [`Tune::margin_rejection`]).
    pub fn score(&self, ev: Option<&Evaluation>) -> f64 {
        let Some(ev) = ev else {
            return f64::INFINITY;
        };
        if self.margin_rejection(ev.stability.as_ref()).is_some() {
            return f64::INFINITY;
        }
        let m = &ev.metrics;
        let (Some(e), false) = (m.e_max, m.diverged) else {
            return f64::INFINITY;
        };
        if !self.rejections(m).is_empty() {
            return f64::INFINITY;
        }
        let p = &self.file.penalty;
        let mut s = e;
        if p.chattering > 0.0 {
            s += p.chattering * m.chattering.unwrap_or(f64::INFINITY);
        }
        if let Some(l) = p.u_limit {
            s += p.u_excess * (m.u_max.unwrap_or(f64::INFINITY) - l).max(0.0);
        }
        if s.is_nan() {
            f64::INFINITY
        } else {
            s
        }
    }

    /// The objective at parameter `values`.
    pub fn objective(&self, values: &[f64]) -> f64 {
        self.objective_of(Some(values))
    }

    /// The objective at `values`, or at the kind's default parameters.
    pub fn objective_of(&self, values: Option<&[f64]>) -> f64 {
        let scores: Vec<f64> = self
            .evaluate_sets(&self.sets_of(values))
            .iter()
            .map(|m| self.score(m.as_ref()))
            .collect();
        match self.file.objective {
            Objective::Mean => scores.iter().sum::<f64>() / scores.len() as f64,
            Objective::Worst => scores.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}
