//! The verification of a tune's choice: its parameters run again on every
//! scenario with a longer horizon (`verify.horizon_factor`) and over
//! `verify.draws` uncertainty draws, each run held to what a candidate
//! is held to ([`super::Reject`]: bounded, no end stop, no sustained
//! oscillation, not saturated beyond the share).

use super::Tune;
use crate::behaviour::verdict_cell;
use rayon::prelude::*;
use serde::Serialize;

/// One run of the verification.
#[derive(Debug, Clone, Serialize)]
pub struct VerifiedRun {
    /// The scenario's name.
    pub scenario: String,
    /// `uncertainty.seed` of the run (None: the scenario's own).
    pub seed: Option<u64>,
    /// Its horizon (s).
    pub horizon_s: f64,
    /// `bounded`, the findings joined by `+`, or `refused: why` when the
    /// scenario could not be built so.
    pub verdict: String,
    /// e_max after the transient (the axis's unit).
    pub e_max: Option<f64>,
    /// End-stop contacts (None: the plant has no stops).
    pub end_stop_contacts: Option<u64>,
    /// Share of samples at the command's limit.
    pub saturation_share: Option<f64>,
    /// The error's oscillation after the transient: amplitude (the axis's
    /// unit) and period (s), when there were cycles.
    pub oscillation_amplitude: Option<f64>,
    /// Its period (s).
    pub oscillation_period_s: Option<f64>,
    /// The loop's computed stability at the trim (a linear law's, when
    /// margins are asked: `[reject]`).
    pub stability: Option<crate::freq::stability::Stability>,
    /// The run passed: no finding, and margins (when computed) at least
    /// `[reject]`'s.
    pub passed: bool,
}

/// The verification of a tune's choice.
#[derive(Debug, Clone, Serialize)]
pub struct Verification {
    /// Each scenario's horizon times this.
    pub horizon_factor: f64,
    /// Draws per scenario.
    pub draws: u64,
    /// Every run passed.
    pub passed: bool,
    /// The runs, scenario-major.
    pub runs: Vec<VerifiedRun>,
}

impl Verification {
    /// One line: `passed: 6 of 6 runs …` or the runs that failed.
    pub fn summary(&self, unit: &str) -> String {
        let failed: Vec<String> = self
            .runs
            .iter()
            .filter(|r| !r.passed)
            .map(|r| {
                format!(
                    "{}{} ({}; e_max {}{unit}, saturation {}, end-stop contacts {}, oscillation {})",
                    r.scenario,
                    r.seed.map(|s| format!(" seed {s}")).unwrap_or_default(),
                    r.verdict,
                    opt(r.e_max, 4),
                    opt(r.saturation_share.map(|s| 100.0 * s), 1) + " %",
                    r.end_stop_contacts
                        .map(|c| c.to_string())
                        .unwrap_or_else(|| "—".into()),
                    match (r.oscillation_amplitude, r.oscillation_period_s) {
                        (Some(a), Some(p)) => format!("{a:.4}{unit} at {p:.4} s"),
                        _ => "—".into(),
                    }
                )
            })
            .collect();
        let worst = self
            .runs
            .iter()
            .filter_map(|r| r.e_max)
            .fold(None, |m: Option<f64>, e| Some(m.map_or(e, |m| m.max(e))));
        if failed.is_empty() {
            format!(
                "verification passed: {} of {} runs at {}× the horizon over {} draw(s) bounded, no end stop, no sustained oscillation, not saturated (worst e_max {}{unit}){}",
                self.runs.len(),
                self.runs.len(),
                self.horizon_factor,
                self.draws,
                opt(worst, 4),
                self.least_margins()
            )
        } else {
            format!(
                "verification FAILED: {} of {} runs at {}× the horizon over {} draw(s) failed: {}",
                failed.len(),
                self.runs.len(),
                self.horizon_factor,
                self.draws,
                failed.join("; ")
            )
        }
    }
}

impl Verification {
    /// `; least margins 8.1 dB, 52.3° (computed)` over the runs whose
    /// loop has them, or nothing.
    fn least_margins(&self) -> String {
        let least = |f: fn(&crate::freq::stability::Stability) -> Option<f64>| {
            self.runs
                .iter()
                .filter_map(|r| r.stability.as_ref().and_then(f))
                .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.min(x))))
        };
        if self.runs.iter().all(|r| r.stability.is_none()) {
            return String::new();
        }
        format!(
            "; least margins {} dB, {}° (computed at the trim; — : no crossover)",
            opt(least(|s| s.gain_margin_db), 2),
            opt(least(|s| s.phase_margin_deg), 1)
        )
    }
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "—".into(), |x| format!("{x:.digits$}"))
}

impl Tune {
    /// The draws of the verification: `verify.draws`, by default the
    /// tune's `draws` and at least 3.
    pub fn verify_draws(&self) -> u64 {
        self.file.verify.draws.unwrap_or(self.file.draws.max(3))
    }

    /// Runs `values` (None: the kind's defaults) on every scenario at
    /// `verify.horizon_factor` times its horizon over the verification's
    /// draws, in parallel, collected in order.
    pub fn verify(&self, values: Option<&[f64]>) -> Verification {
        let draws = self.verify_draws();
        let factor = self.file.verify.horizon_factor;
        let jobs: Vec<(usize, Option<u64>)> = (0..self.scenarios.len())
            .flat_map(|i| (0..draws).map(move |d| (i, (draws > 1).then_some(d))))
            .collect();
        let runs: Vec<VerifiedRun> = jobs
            .par_iter()
            .map(|&(i, seed)| self.verify_one(i, seed, factor, values))
            .collect();
        Verification {
            horizon_factor: factor,
            draws,
            passed: runs.iter().all(|r| r.passed),
            runs,
        }
    }

    fn verify_one(
        &self,
        i: usize,
        seed: Option<u64>,
        factor: f64,
        values: Option<&[f64]>,
    ) -> VerifiedRun {
        let sc = &self.scenarios[i];
        let horizon = sc.horizon() * factor;
        let mut sets = vec![(
            "controller.kind".to_string(),
            toml::Value::String(self.kind.into()),
        )];
        for (r, &v) in self.params.iter().zip(values.unwrap_or(&[])) {
            sets.push((format!("controller.{}", r.key), toml::Value::Float(v)));
        }
        sets.push(("simulation.horizon".into(), toml::Value::Float(horizon)));
        if let Some(s) = seed {
            sets.push(("uncertainty.seed".into(), toml::Value::Integer(s as i64)));
        }
        let mut run = VerifiedRun {
            scenario: sc.name().to_string(),
            seed,
            horizon_s: horizon,
            verdict: String::new(),
            e_max: None,
            end_stop_contacts: None,
            saturation_share: None,
            oscillation_amplitude: None,
            oscillation_period_s: None,
            stability: None,
            passed: false,
        };
        match sc.with_values_on(self.tables[i].clone(), &sets) {
            Err(e) => run.verdict = format!("refused: `{}`: {}", e.key, e.reason),
            Ok(lp) => {
                let ev = self.evaluate_loop(&lp);
                let m = ev.metrics;
                let findings = self.rejections(&m);
                let b = &m.behaviour;
                let osc = b.oscillation.filter(|o| o.cycles > 0);
                let short = self.margin_rejection(ev.stability.as_ref());
                run.verdict = match &short {
                    Some(why) if findings.is_empty() => format!("margins: {why}"),
                    _ => verdict_cell(&findings),
                };
                run.stability = ev.stability;
                run.e_max = m.e_max;
                run.end_stop_contacts = b.end_stops.map(|e| e.contacts);
                run.saturation_share = b.saturation_share;
                run.oscillation_amplitude = osc.map(|o| o.amplitude);
                run.oscillation_period_s = osc.and_then(|o| o.period_s);
                run.passed = findings.is_empty() && m.e_max.is_some() && short.is_none();
            }
        }
        run
    }
}
