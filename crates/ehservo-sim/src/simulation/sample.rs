//! What the loop hands out: one logged [`Sample`] per `t_k`, and, for the
//! run, its [`Outcome`] and the [`Stop`] that ended it.

pub use crate::plant::MAX_STATES;
use ehservo_core::control::Signal;
use ehservo_core::math::DR;
use serde::{Deserialize, Serialize};

/// Most parts a controller may log per sample.
pub const MAX_PARTS: usize = 32;

/// One logged sample at `t_k`: the true plant, the command, and the
/// controller's parts as named signals.
///
/// ```
/// use ehservo_sim::core::control::sliding::SlidingParts;
/// use ehservo_sim::core::control::Signals;
/// use ehservo_sim::simulation::Sample;
///
/// // A sliding-mode law's parts, logged as the loop logs them.
/// let parts = SlidingParts { sigma: 45.0, sigma_delta: 42.5, ..SlidingParts::default() };
/// let mut s = Sample { signals: SlidingParts::<f64>::SIGNALS, ..Sample::default() };
/// parts.write(&mut s.values);
/// // Read by key, knowing nothing of the controller.
/// assert_eq!(s.get("sigma"), Some(45.0));
/// assert_eq!(s.part("sigma_delta"), 42.5);
/// // A key this controller does not have: None, or 0 for `part`.
/// assert_eq!((s.get("p"), s.part("p")), (None, 0.0));
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Sample index k.
    pub k: u64,
    /// t_k (s).
    pub t: f64,
    /// z = (θd, θ̇d, θ̈d, θ⃛d).
    pub z: [f64; 4],
    /// The true x = (θ, θ̇, θ̈).
    pub x: [f64; 3],
    /// The controller's command u (V).
    pub u: f64,
    /// What the plant receives after the actuator (V).
    pub u_plant: f64,
    /// Tracking error e = θd − θ (rad).
    pub e: f64,
    /// The law's flags ([`ehservo_core::control::flags`]).
    pub flags: u8,
    /// The controller's signals, in the order of `values`.
    pub signals: &'static [Signal],
    /// Their values (the first `signals.len()`).
    pub values: [f64; MAX_PARTS],
    /// What the controller was given as x: the measured channels after
    /// the sensors, the others from the estimator.
    pub x_ctrl: [f64; 3],
    /// The estimator's (θ̂, θ̂̇, θ̂̈); zero without one.
    pub x_est: [f64; 3],
    /// The spool position (V), before the dead band and the null bias.
    pub spool: f64,
    /// The plant's physical states ([`Plant::STATES`](crate::plant::Plant::STATES)), when the
    /// simulation is asked for them ([`Simulation::log_states`](super::Simulation::log_states)).
    pub states: [f64; MAX_STATES],
}

impl Default for Sample {
    fn default() -> Self {
        Self {
            k: 0,
            t: 0.0,
            z: [0.0; 4],
            x: [0.0; 3],
            u: 0.0,
            u_plant: 0.0,
            e: 0.0,
            flags: 0,
            signals: &[],
            values: [0.0; MAX_PARTS],
            x_ctrl: [0.0; 3],
            x_est: [0.0; 3],
            spool: 0.0,
            states: [0.0; MAX_STATES],
        }
    }
}

impl Sample {
    /// θd in degrees.
    pub fn theta_d_deg(&self) -> f64 {
        self.z[0] / DR
    }
    /// θ in degrees.
    pub fn theta_deg(&self) -> f64 {
        self.x[0] / DR
    }
    /// e in degrees.
    pub fn e_deg(&self) -> f64 {
        self.e / DR
    }
    /// The index of signal `key` among this sample's signals.
    pub fn index_of(&self, key: &str) -> Option<usize> {
        self.signals.iter().position(|s| s.key == key)
    }
    /// A controller signal by key (`"sigma"`, `"wphi"`, `"p"`).
    pub fn get(&self, key: &str) -> Option<f64> {
        self.index_of(key).map(|i| self.values[i])
    }
    /// A controller signal by key, 0 when this controller has none.
    pub fn part(&self, key: &str) -> f64 {
        self.get(key).unwrap_or(0.0)
    }
    /// Every logged number is finite. Branch-free: `0·v` is ±0 for a
    /// finite `v` and NaN for ±∞ or NaN, so the sum is 0 exactly when all
    /// are finite (as `ehservo_core::rk4::axpy_results_finite`).
    #[cfg(test)]
    pub(super) fn is_finite(&self) -> bool {
        self.finite_with(self.signals.len())
    }

    /// The finiteness check with `n = signals.len()` given: the loop
    /// passes its controller's constant count, so that the check unrolls.
    /// The order of the sum does not change the verdict: four lanes.
    #[inline(always)]
    pub(super) fn finite_with(&self, n: usize) -> bool {
        let mut lane = [
            0.0 * self.u + 0.0 * self.x[1],
            0.0 * self.u_plant + 0.0 * self.x[2],
            0.0 * self.e + 0.0 * self.z[0],
            0.0 * self.x[0] + 0.0 * self.z[1],
        ];
        lane[0] += 0.0 * self.z[2];
        lane[1] += 0.0 * self.z[3];
        let values = self.values[..n].chunks_exact(4);
        let rest = values.remainder();
        for chunk in values {
            for (l, v) in lane.iter_mut().zip(chunk) {
                *l += 0.0 * v;
            }
        }
        for (l, v) in lane.iter_mut().zip(rest) {
            *l += 0.0 * v;
        }
        (lane[0] + lane[1]) + (lane[2] + lane[3]) == 0.0
    }
}

/// Why a run stopped before its horizon.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DivergenceReason {
    /// A plant or controller state became NaN or infinite.
    NonFiniteState,
    /// |θ| exceeded the limit.
    ThetaLimit,
    /// A cylinder's rod went past an end stop by more than the stop's
    /// stated penetration ([`crate::plant::Plant::beyond_stops`]).
    BeyondEndStop,
    /// The law returned a non-finite u, or a non-finite part of its law
    /// (σ, ‖E‖, WᵀΦ, …) that would have been logged.
    NonFiniteControl,
    /// An adaptive solver spent the run's step budget.
    SolverStepBudget,
    /// An adaptive solver's step fell below ten ulps of the time.
    SolverStepTooSmall,
    /// The plant's fastest rate λ (its [`crate::plant::Plant::stiffness`])
    /// needs more than [`crate::plant::MAX_REFINE`] RK4 steps a sub-step
    /// to be stable ([`crate::plant::resolvable`]): what RK4 would
    /// compute there is not the model's solution.
    TooStiff,
    /// The plant failed: an FMU returned an error status or panicked
    /// ([`crate::plant::Plant::failed`]; its message is on stderr).
    PlantFailed,
}

impl DivergenceReason {
    /// A short human sentence.
    pub fn describe(&self) -> &'static str {
        match self {
            DivergenceReason::NonFiniteState => "the state became non-finite",
            DivergenceReason::ThetaLimit => "|θ| exceeded the divergence limit",
            DivergenceReason::BeyondEndStop => {
                "the rod went past an end stop by more than the stop's stated penetration"
            }
            DivergenceReason::NonFiniteControl => {
                "the control law returned a non-finite value (u or one of its parts)"
            }
            DivergenceReason::SolverStepBudget => {
                "the adaptive solver spent the run's step budget (loosen rtol/atol)"
            }
            DivergenceReason::SolverStepTooSmall => {
                "the adaptive solver's step fell below ten ulps of the time"
            }
            DivergenceReason::TooStiff => {
                "the plant is stiffer than 4096 RK4 steps a sub-step can follow (raise simulation.substeps, or use solver = \"dopri5\")"
            }
            DivergenceReason::PlantFailed => {
                "the plant's FMU failed: an error status, or it asked to terminate (its message is on stderr)"
            }
        }
    }
}

/// The end of a diverged run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Divergence {
    /// When (s).
    pub t: f64,
    /// Why.
    pub reason: DivergenceReason,
}

/// Why a simulation stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stop {
    /// The last sample, at the horizon, was produced.
    Horizon,
    /// The run diverged, or the controller faulted (a non-finite command
    /// or state update), at the time and for the reason given.
    Diverged(Divergence),
}

/// What the loop reports besides the samples it logged.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Outcome {
    /// Samples produced.
    pub samples: u64,
    /// Set when the run ended early.
    pub diverged: Option<Divergence>,
    /// Samples at which the valve root of (2) was clamped in the law.
    pub valve_root_clamped: u64,
    /// Samples at which ‖E‖ = 0 was guarded.
    pub zero_error_norm: u64,
    /// Samples at which the command exceeded the valve range (clamped by
    /// the sampled loop or saturated by the actuator).
    pub saturated: u64,
    /// Samples at which the sampled loop refused a measurement and
    /// commanded its safe value.
    pub measurement_faults: u64,
    /// The adaptive solver's steps so far (zero under RK4).
    pub solver_steps: ehservo_core::solver::StepCounts,
}
