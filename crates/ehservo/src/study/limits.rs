//! A sweep's work, counted before any of it is done: each run from the
//! base scenario with the run's values of the keys that change its
//! evaluations, against [`MAX_BATCH_WORK`] (the counting of one run is
//! [`crate::limits`]).

use crate::limits::{run_evaluations, Batch, MAX_BATCH_WORK, MAX_RUN_WORK, RUN_OVERHEAD};
use crate::scenario::{EstimatorCfg, Scenario};
use crate::simulation::Mode;

/// The keys that change a run's evaluations (the others change only what
/// each evaluation computes).
const WORK_KEYS: [&str; 5] = [
    "simulation.horizon",
    "simulation.step",
    "simulation.substeps",
    "simulation.mode",
    "estimator.substeps",
];

/// Refuses a sweep of runs `range` of a study beyond [`MAX_BATCH_WORK`]
/// evaluations (a shard is counted alone: `--shard K/N` splits the work).
/// Each run is counted from the base scenario with the run's values of the
/// keys that change its evaluations ([`WORK_KEYS`]); a value that does not
/// read as such counts as the base's (its run then reports its error).
pub fn check_study(
    plan: &super::Plan,
    range: std::ops::Range<u64>,
) -> Result<(), crate::error::InputError> {
    let mut keys: Vec<String> = plan.axes.iter().flat_map(|(a, _)| a.keys()).collect();
    if let Some(mc) = &plan.study.monte_carlo {
        keys.extend(mc.draw.iter().map(|d| d.key.clone()));
    }
    let varied = keys.iter().any(|k| WORK_KEYS.contains(&k.trim()));
    // A run beyond a run's own limit (or with an invalid step) is refused
    // by its validation and costs nothing.
    let of = |s: &Scenario| match run_evaluations(s) {
        e if e.is_finite() && e <= MAX_RUN_WORK => e,
        _ => 0.0,
    };
    let runs = (range.end - range.start) as f64;
    let mut b = Batch::default();
    if !varied {
        b.add("runs", runs, of(plan.base.scenario()), String::new());
    } else {
        let base = plan.base.scenario();
        let mut s = base.clone();
        for i in range {
            let (_, sets, _) = plan.run_values(i);
            s.simulation = base.simulation.clone();
            s.estimator = base.estimator;
            for (k, v) in &sets {
                set_work_key(&mut s, k.trim(), v);
            }
            b.add("runs", 1.0, of(&s), String::new());
        }
    }
    let total = b.total();
    if total <= MAX_BATCH_WORK {
        return Ok(());
    }
    let key = if plan.study.monte_carlo.is_some() {
        "monte_carlo.runs"
    } else {
        "axis"
    };
    Err(crate::error::InputError::key(
        &plan.file,
        key,
        format!(
            "{runs} runs of about {:.2e} evaluations each are {total:.2e} evaluations, more than the limit of {MAX_BATCH_WORK:.0e} for one sweep (about {:.0} core-hours): split it with --shard K/N (each shard is counted alone) or ask for less",
            total / runs.max(1.0) - RUN_OVERHEAD,
            MAX_BATCH_WORK * 0.3e-6 / 3600.0
        ),
    ))
}

/// Sets one of [`WORK_KEYS`] on `s` from a study's value, if it reads as one.
fn set_work_key(s: &mut Scenario, key: &str, v: &toml::Value) {
    let num = v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
    let sim = &mut s.simulation;
    match key {
        "simulation.horizon" => sim.horizon = num.unwrap_or(sim.horizon),
        "simulation.step" => sim.step = num.unwrap_or(sim.step),
        "simulation.substeps" => {
            if let Some(n) = v.as_integer().and_then(|i| u32::try_from(i).ok()) {
                sim.substeps = n;
            }
        }
        "simulation.mode" => match v.as_str() {
            Some("sampled") => sim.mode = Mode::Sampled,
            Some("continuous") => sim.mode = Mode::Continuous,
            _ => {}
        },
        "estimator.substeps" => {
            if let (Some(EstimatorCfg::Levant { substeps, .. }), Some(n)) = (
                &mut s.estimator,
                v.as_integer().and_then(|i| u32::try_from(i).ok()),
            ) {
                *substeps = n;
            }
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// tests/bad-input-study/31: 2·10⁶ runs of 1000·(1 + 9999) = 10⁷
    /// evaluations (+10³) = 2.0e13, refused whole; its shard 0/40 (5·10⁴
    /// runs, 5.0e11) is within the limit.
    #[test]
    fn a_study_is_counted_per_shard() {
        let f = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/bad-input-study/31-work-beyond-limit.toml");
        let plan = super::super::Plan::load(&f).unwrap();
        let e = check_study(&plan, 0..plan.runs).unwrap_err().to_string();
        assert!(e.contains("2.00e13 evaluations"), "{e}");
        assert!(check_study(&plan, plan.shard_range(0, 40)).is_ok());
    }
}
