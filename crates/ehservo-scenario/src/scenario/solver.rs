//! `simulation.solver` and its keys (`rtol`, `atol`, `max_step`): checked
//! and made into the sampled loop's adaptive solver.

use super::{AtolCfg, Scenario};
use ehservo_core::solver::rosenbrock23::MAX_DIM;
use ehservo_sim::error::KeyError;
use ehservo_sim::simulation::{AdaptiveConfig, Atol, Mode, MAX_ATOL};

/// The default relative tolerance of an adaptive solver.
pub const DEFAULT_RTOL: f64 = 1e-6;
/// The default absolute tolerance of an adaptive solver (every state).
pub const DEFAULT_ATOL: f64 = 1e-9;
/// The smallest relative tolerance, 10 ulps of 1 (2.22e-15): a step's
/// rounding alone is of the order of an ulp of the state, so a finer
/// rtol is never met where atol does not dominate. Hairer & Wanner's
/// RADAU5 (radau5.f, "CHECK IF TOLERANCES ARE O.K.") refuses
/// RTOL ≤ 10·UROUND the same way.
pub const MIN_RTOL: f64 = 10.0 * f64::EPSILON;

fn bad<T>(key: &str, reason: impl Into<ehservo_sim::error::Reason>) -> Result<T, KeyError> {
    Err(KeyError::new(key, reason))
}

/// The adaptive solver of `s` (`None` for `"rk4"`), for a plant of
/// `plant_dim` states; refused with the key and the reason: an adaptive
/// key with rk4, rtol outside (0, 1), an atol negative, not finite or a
/// list of the wrong length, a max_step not in (0, step], sub-steps or the
/// continuous mode with an adaptive solver.
pub(super) fn adaptive(s: &Scenario, plant_dim: usize) -> Result<Option<AdaptiveConfig>, KeyError> {
    let sim = &s.simulation;
    let Some(scheme) = sim.solver.scheme() else {
        let given = [
            ("simulation.rtol", sim.rtol.is_some()),
            ("simulation.atol", sim.atol.is_some()),
            ("simulation.max_step", sim.max_step.is_some()),
        ];
        if let Some((key, _)) = given.iter().find(|g| g.1) {
            return bad(
                key,
                "is an adaptive solver's key, and solver = \"rk4\" has a fixed step (simulation.substeps): set solver = \"dopri5\", \"bs32\" or \"rosenbrock23\", or remove it",
            );
        }
        return Ok(None);
    };
    let name = sim.solver.as_str();
    if sim.mode == Mode::Continuous {
        return bad(
            "simulation.solver",
            format!("\"{name}\" runs in the sampled mode only (the law inside an adaptive solver's stages is not implemented): set mode = \"sampled\" or solver = \"rk4\""),
        );
    }
    if sim.substeps != 1 {
        return bad(
            "simulation.substeps",
            format!(
                "is rk4's: solver = \"{name}\" chooses its own steps (bound them with max_step)"
            ),
        );
    }
    let rtol = sim.rtol.unwrap_or(DEFAULT_RTOL);
    if !(rtol > 0.0 && rtol < 1.0) {
        return bad(
            "simulation.rtol",
            format!("must be in (0, 1) (got {rtol:e})"),
        );
    }
    if rtol < MIN_RTOL {
        return bad(
            "simulation.rtol",
            format!("must be at least 10 ulps, {MIN_RTOL:.3e}: a step's rounding alone is of the order of 1 ulp of the state, so a finer tolerance is never met (got {rtol:e})"),
        );
    }
    let atol = match &sim.atol {
        None => Atol::scalar(DEFAULT_ATOL),
        Some(AtolCfg::Scalar(a)) => Atol::scalar(*a),
        Some(AtolCfg::PerState(v)) => {
            if v.len() != plant_dim || v.len() > MAX_ATOL {
                return bad(
                    "simulation.atol",
                    format!(
                        "a per-state list must hold one value per plant state: plant.model = \"{}\" has {plant_dim}, the list {}",
                        s.plant.model(),
                        v.len()
                    ),
                );
            }
            Atol::per_state(v).map_err(|e| KeyError::param("simulation", e))?
        }
    };
    if let Some(a) = atol
        .values()
        .iter()
        .find(|a| !(a.is_finite() && **a >= 0.0))
    {
        return bad(
            "simulation.atol",
            format!("must be finite and >= 0 (got {a:e})"),
        );
    }
    let max_step = sim.max_step.unwrap_or(sim.step);
    if !(max_step.is_finite() && max_step > 0.0) {
        return bad(
            "simulation.max_step",
            format!("must be finite and > 0 (got {max_step:e})"),
        );
    }
    if max_step > sim.step {
        return bad(
            "simulation.max_step",
            format!(
                "must be at most the sample period simulation.step = {:?} s (no step crosses a sample; got {max_step:?} s)",
                sim.step
            ),
        );
    }
    if scheme.needs_jacobian() && plant_dim + 2 > MAX_DIM {
        return bad(
            "simulation.solver",
            format!(
                "\"{name}\" factors a matrix of the plant's and the actuator's states, at most {MAX_DIM}: plant.model = \"{}\" has {}",
                s.plant.model(),
                plant_dim + 2
            ),
        );
    }
    let budget = crate::limits::adaptive_step_budget(s, scheme.evaluations(plant_dim + 2));
    // Every sample takes at least ⌈step/max_step⌉ steps: a max_step that
    // plans more steps than the budget is refused before any work, not
    // found out as `solver-step-budget` after it.
    let samples = crate::limits::count_from_f64(
        "simulation.horizon",
        "samples",
        (sim.horizon / sim.step).round(),
    );
    let per_sample = crate::limits::count_from_f64(
        "simulation.max_step",
        "steps a sample",
        (sim.step / max_step).ceil(),
    );
    let least = match (samples, per_sample) {
        (Ok(n), Ok(m)) => crate::limits::work_of(n, m),
        _ => u64::MAX,
    };
    if least > budget {
        return bad(
            "simulation.max_step",
            format!(
                "{max_step:e} s makes at least {:.3e} steps of the {budget} a run may take (the run limit of 4e8 evaluations, {} a step, less the law's): raise max_step to at least {:.3e} s",
                (sim.horizon / max_step).ceil(),
                scheme.evaluations(plant_dim + 2),
                sim.horizon / (budget.max(1) as f64)
            ),
        );
    }
    AdaptiveConfig::try_new(sim.solver, rtol, atol, max_step, budget)
        .map(Some)
        .map_err(|e| KeyError::param("simulation", e))
}
