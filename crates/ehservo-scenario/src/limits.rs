//! The work a command may ask for, counted before any of it is done.
//!
//! One run is counted in *evaluations*: a law evaluation, an RK4 step of
//! the plant, a sub-step of an estimator. A sampled run of N steps with
//! `simulation.substeps` = m and an estimator of `substeps` = e makes
//! N·(1 + m + e) of them; a continuous run 4·N (the law in each RK4 stage).
//! The paper's Fig. 2 (10 s at 10 ms, sampled) is 2·10³ evaluations and runs
//! in 0.59 ms (BENCHMARKS.md, `fig2/sampled_0.01_run`): about 0.3 µs each.
//!
//! - A run: at most [`MAX_RUN_WORK`] = 4·10⁸ evaluations (a minute or two).
//! - A tune or a league: at most [`MAX_BATCH_WORK`] = 10¹² evaluations in all
//!   (about 80 core-hours), every run counted with a fixed
//!   [`RUN_OVERHEAD`] for building it; the message names the key that asks
//!   for most of it and the figure asked.
//!
//! Every planned count (samples, settling samples, segments, frequencies,
//! evaluations) is made from its float figure by [`count_from_f64`], which
//! refuses a figure that is not finite, negative, or above [`MAX_COUNT`]
//! with the key that asked and the figure; counts are then multiplied and
//! summed with saturating arithmetic ([`work_of`], [`saturating_sum`]), so
//! a sum never wraps round below a limit.

use crate::scenario::{EstimatorCfg, Scenario};
use crate::simulation::Mode;
use ehservo_sim::error::KeyError;

/// Most evaluations one run may ask for (checked by `Setup::new`, through
/// [`check_run`]).
pub const MAX_RUN_WORK: f64 = 4.0e8;

/// Most evaluations one tune or one league may ask for, every run counted:
/// 10¹², about 3·10⁵ s (80 hours) of one core at 0.3 µs an evaluation.
pub const MAX_BATCH_WORK: f64 = 1.0e12;

/// What building one run costs besides its evaluations, in evaluations: a
/// set-up made from a TOML table with overrides takes some hundred
/// microseconds, a few hundred evaluations (1000 is counted).
pub const RUN_OVERHEAD: f64 = 1.0e3;

/// The largest count a plan may hold: 2⁵³ ≈ 9.0·10¹⁵, the largest
/// integer below which every integer is exact in an f64 (so the count and
/// its figure agree), far beyond every work limit.
pub const MAX_COUNT: f64 = 9_007_199_254_740_992.0;

/// Why a figure is no count.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Uncountable {
    /// NaN or infinite.
    #[error("not a finite number")]
    NotFinite,
    /// Below zero.
    #[error("negative")]
    Negative,
    /// Above [`MAX_COUNT`].
    #[error("more than 2^53 (9.0e15), the most a plan can count")]
    TooLarge,
}

/// A count that cannot be planned: the key (or flag) that asked for it,
/// what is counted and the figure asked.
///
/// ```
/// use ehservo_scenario::limits::{count_from_f64, Uncountable};
/// assert_eq!(count_from_f64("--settle", "settling samples", 200.0), Ok(200));
/// let e = count_from_f64("--settle", "settling samples", 1e302).unwrap_err();
/// assert_eq!((e.key.as_str(), e.why), ("--settle", Uncountable::TooLarge));
/// assert_eq!(
///     e.to_string(),
///     "1.000e302 settling samples asked: more than 2^53 (9.0e15), the most a plan can count"
/// );
/// ```
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{value:.3e} {what} asked: {why}")]
pub struct CountError {
    /// The key or flag that asked.
    pub key: String,
    /// What is counted (`settling samples`).
    pub what: &'static str,
    /// The figure asked.
    pub value: f64,
    /// Why it is no count.
    pub why: Uncountable,
}

impl From<CountError> for KeyError {
    fn from(e: CountError) -> Self {
        KeyError::new(e.key.clone(), e.to_string())
    }
}

/// The count of a whole-number figure `value` (already rounded as the
/// plan wants it), asked for by `key`: refused when not finite, negative,
/// or above [`MAX_COUNT`].
pub fn count_from_f64(key: &str, what: &'static str, value: f64) -> Result<u64, CountError> {
    let why = if !value.is_finite() {
        Uncountable::NotFinite
    } else if value < 0.0 {
        Uncountable::Negative
    } else if value > MAX_COUNT {
        Uncountable::TooLarge
    } else {
        // In [0, 2⁵³]: exact, no saturation.
        return Ok(value as u64);
    };
    Err(CountError {
        key: key.to_string(),
        what,
        value,
        why,
    })
}

/// The evaluations of `samples` samples of `per_sample` evaluations each,
/// saturating at `u64::MAX` (beyond every limit) instead of wrapping.
pub fn work_of(samples: u64, per_sample: u64) -> u64 {
    samples.saturating_mul(per_sample)
}

/// The sum of counts, saturating at `u64::MAX` instead of wrapping.
pub fn saturating_sum(counts: impl IntoIterator<Item = u64>) -> u64 {
    counts.into_iter().fold(0, u64::saturating_add)
}

/// The evaluations of one run of `s` (whose step, horizon and sub-steps
/// are valid): N·(1 + m + e) sampled, 4·N continuous.
pub fn run_evaluations(s: &Scenario) -> f64 {
    let sim = &s.simulation;
    let steps = (sim.horizon / sim.step).round();
    match sim.mode {
        Mode::Sampled => steps * (1.0 + f64::from(sim.substeps) + estimator_substeps(s)),
        Mode::Continuous => 4.0 * steps,
    }
}

/// The steps (accepted and rejected) an adaptive solver of `stages`
/// evaluations a step may take in one run of `s`: what is left of
/// [`MAX_RUN_WORK`] after the law's and the estimator's evaluations
/// ([`run_evaluations`]), divided by `stages`. A run that needs more stops
/// there with `solver-step-budget`, as a result.
pub fn adaptive_step_budget(s: &Scenario, stages: usize) -> u64 {
    let left = (MAX_RUN_WORK - run_evaluations(s)).max(0.0);
    (left / stages.max(1) as f64).floor() as u64
}

/// The estimator's sub-steps per sample (0 without a sub-stepped estimator).
fn estimator_substeps(s: &Scenario) -> f64 {
    match &s.estimator {
        Some(EstimatorCfg::Levant { substeps, .. }) => f64::from(*substeps),
        _ => 0.0,
    }
}

/// The evaluations of one sample of a built loop (as [`run_evaluations`]
/// counts them per step).
pub fn sample_evaluations(
    sim: &crate::simulation::SimConfig,
    stages: &crate::simulation::Stages,
) -> u64 {
    let est = match &stages.estimator {
        Some(ehservo_sim::estimator::AnyEstimator::Levant(l)) => u64::from(l.substeps()),
        _ => 0,
    };
    match sim.mode {
        Mode::Sampled => 1 + u64::from(sim.substeps) + est,
        Mode::Continuous => 4,
    }
}

/// The largest |θ|, |θ̇|, |θ̈| a run may start from or be bounded by
/// (`simulation.x0`, `simulation.theta_limit`): 1e300 (rad, rad/s,
/// rad/s²). A trace writes them in degrees (×57.3), which overflows
/// beyond 3e306; the sensors' bias and noise have the same bound.
pub const MAX_MAGNITUDE: f64 = ehservo_sim::sensor::MAX_MAGNITUDE;

/// Refuses a run of more than [`MAX_RUN_WORK`] evaluations: the key is the
/// multiplier that asks for most (the estimator's sub-steps, the plant's
/// sub-steps, or the horizon), the reason the figure. Also refuses a
/// finite x0 or θ limit beyond [`MAX_MAGNITUDE`] (the non-finite ones are
/// refused by their own checks).
pub fn check_run(s: &Scenario) -> Result<(), KeyError> {
    let sim = &s.simulation;
    let huge = |v: f64| v.is_finite() && v.abs() > MAX_MAGNITUDE;
    if huge(sim.theta_limit) {
        return Err(KeyError::new(
            "simulation.theta_limit",
            format!(
                "must be at most 1e300 rad (beyond, θ in degrees overflows; got {:e})",
                sim.theta_limit
            ),
        ));
    }
    if let Some(v) = sim.x0.iter().find(|v| huge(**v)) {
        return Err(KeyError::new(
            "simulation.x0",
            format!(
                "must be within ±1e300 (rad, rad/s, rad/s²: beyond, the trace in degrees overflows; got {v:e})"
            ),
        ));
    }
    let work = run_evaluations(s);
    if work <= MAX_RUN_WORK {
        return Ok(());
    }
    let sim = &s.simulation;
    let steps = (sim.horizon / sim.step).round();
    let est = estimator_substeps(s);
    let key = if sim.mode == Mode::Continuous {
        "simulation.horizon"
    } else if est > f64::from(sim.substeps) {
        "estimator.substeps"
    } else if sim.substeps > 1 {
        "simulation.substeps"
    } else {
        "simulation.horizon"
    };
    let per = match sim.mode {
        Mode::Sampled if est > 0.0 => format!(
            "(1 + {} plant sub-steps + {est} estimator sub-steps)",
            sim.substeps
        ),
        Mode::Sampled => format!("(1 + {} sub-steps)", sim.substeps),
        Mode::Continuous => "4 (the law in each RK4 stage)".to_string(),
    };
    Err(KeyError::new(
        key,
        format!(
            "{steps:.3e} steps × {per} is about {work:.2e} evaluations, more than the limit of \
             {MAX_RUN_WORK:.0e} for one run (minutes of computing): lower the horizon or the sub-steps"
        ),
    ))
}

/// The work of a batch of runs (a tune, a league), by the key that asks
/// for each part.
#[derive(Debug, Clone, Default)]
pub struct Batch {
    parts: Vec<(String, f64, String)>,
}

impl Batch {
    /// Adds `runs` runs of `evaluations` each, asked for by `key`, described
    /// (for the message) as `what`.
    pub fn add(&mut self, key: &str, runs: f64, evaluations: f64, what: String) {
        let work = runs * (evaluations + RUN_OVERHEAD);
        self.parts.push((key.to_string(), work, what));
    }

    /// The evaluations of the whole batch.
    pub fn total(&self) -> f64 {
        self.parts.iter().map(|p| p.1).sum()
    }

    /// Refuses a batch beyond [`MAX_BATCH_WORK`]: `(key, reason)` naming the
    /// key of the largest part, what it asks for and the total.
    pub fn check(&self, command: &str) -> Result<(), KeyError> {
        let total = self.total();
        if total <= MAX_BATCH_WORK {
            return Ok(());
        }
        let (key, work, what) = self
            .parts
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .cloned()
            .unwrap_or_default();
        Err(KeyError::new(
            key,
            format!(
                "{what} is about {work:.2e} evaluations ({total:.2e} for the whole {command}), \
                 more than the limit of {MAX_BATCH_WORK:.0e} for one {command} (about {:.0} core-hours): \
                 ask for fewer",
                MAX_BATCH_WORK * 0.3e-6 / 3600.0
            ),
        ))
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // the counts are exact in doubles
mod tests {
    use super::*;

    /// Fig. 2: 10 s / 0.01 s = 1000 steps, sampled, one sub-step: 2000
    /// evaluations; a Levant differentiator of 10 sub-steps adds 10 000;
    /// continuous, 4000.
    #[test]
    fn evaluations_by_hand() {
        let mut s = crate::scenario::Loop::parse("name = \"x\"")
            .unwrap()
            .scenario()
            .clone();
        assert_eq!(run_evaluations(&s), 2000.0);
        s.estimator = Some(EstimatorCfg::Levant {
            lipschitz: 10.0,
            substeps: 10,
        });
        assert_eq!(run_evaluations(&s), 12_000.0);
        s.estimator = None;
        s.simulation.mode = Mode::Continuous;
        assert_eq!(run_evaluations(&s), 4000.0);
    }

    /// 1000 steps × (1 + 1 + 10⁶) ≈ 1.0e9 > 4e8: the estimator's sub-steps
    /// are named; at 10⁵ they are 1.0e8 and pass.
    #[test]
    fn an_estimator_s_sub_steps_count() {
        let mut s = crate::scenario::Loop::parse("name = \"x\"")
            .unwrap()
            .scenario()
            .clone();
        s.estimator = Some(EstimatorCfg::Levant {
            lipschitz: 10.0,
            substeps: 1_000_000,
        });
        let e = check_run(&s).unwrap_err();
        let (key, reason) = (e.key, e.reason.to_string());
        assert_eq!(key, "estimator.substeps");
        assert!(reason.contains("1.00e9"), "{reason}");
        s.estimator = Some(EstimatorCfg::Levant {
            lipschitz: 10.0,
            substeps: 100_000,
        });
        assert!(check_run(&s).is_ok());
    }

    /// A count is the figure itself up to 2⁵³; beyond, and for the
    /// non-finite and negative figures, the key and the figure come back.
    #[test]
    fn counts_are_refused_with_their_key_and_figure() {
        assert_eq!(count_from_f64("k", "samples", 0.0), Ok(0));
        assert_eq!(count_from_f64("k", "samples", MAX_COUNT), Ok(1 << 53));
        for (v, why) in [
            (f64::NAN, Uncountable::NotFinite),
            (f64::INFINITY, Uncountable::NotFinite),
            (-1.0, Uncountable::Negative),
            (MAX_COUNT * 2.0, Uncountable::TooLarge),
            (1e300, Uncountable::TooLarge),
        ] {
            let e = count_from_f64("--settle", "samples", v).unwrap_err();
            assert_eq!((e.key.as_str(), e.why), ("--settle", why), "{v}");
            assert!(v.is_nan() || e.value == v);
            let k = KeyError::from(e);
            assert_eq!(k.key, "--settle");
        }
        // u64::MAX · 2 and (u64::MAX − 1) + 2 saturate instead of wrapping
        // to u64::MAX − 1 and 0.
        assert_eq!(work_of(u64::MAX, 2), u64::MAX);
        assert_eq!(saturating_sum([u64::MAX - 1, 2]), u64::MAX);
        assert_eq!(saturating_sum([3, 4]), 7);
    }

    /// 10⁶ runs of 2000 evaluations (+1000 each) = 3e9: fine; 10⁹ of them
    /// = 3e12 > 1e12: refused, naming the key.
    #[test]
    fn a_batch_is_counted_and_refused_by_its_largest_part() {
        let mut b = Batch::default();
        b.add("budget", 1e6, 2000.0, "x".into());
        assert_eq!(b.total(), 3e9);
        assert!(b.check("tune").is_ok());
        b.add("draws", 1e9, 2000.0, "many draws".into());
        let e = b.check("tune").unwrap_err();
        let (key, reason) = (e.key, e.reason.to_string());
        assert_eq!(key, "draws");
        assert!(
            reason.starts_with("many draws is about 3.00e12"),
            "{reason}"
        );
    }
}
