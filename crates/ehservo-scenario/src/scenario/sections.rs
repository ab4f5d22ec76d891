//! The sections of a scenario file, one type each, every key at the
//! paper's Fig. 2 value by default.

use ehservo_sim::plant::{PhysicalSpec, UncertaintySpec};
use ehservo_sim::simulation::{Mode, SolverKind};
use serde::{Deserialize, Serialize};

/// `[simulation]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SimulationCfg {
    /// Horizon T (s), a whole number of steps. Default 10.
    pub horizon: f64,
    /// Step h (s); the sample period in sampled mode. Default 0.01 (the paper).
    pub step: f64,
    /// `"sampled"` (default) or `"continuous"`.
    pub mode: Mode,
    /// Plant RK4 sub-steps per sample in sampled mode. Default 1.
    pub substeps: u32,
    /// End of the transient t_s for the metrics (s). Default 2.
    pub settle: f64,
    /// |θ| beyond which a run counts as diverged (rad). Default 1.
    pub theta_limit: f64,
    /// x(0) = (θ, θ̇, θ̈). Default 0.
    #[serde(with = "ehservo_sim::triple")]
    #[schemars(with = "[f64; 3]")]
    pub x0: [f64; 3],
    /// Sampled mode: apply each command one sample after the measurement
    /// it was computed from (a controller that takes a period to compute).
    /// Default false.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub computation_delay: bool,
    /// How the plant is integrated between samples: `"rk4"` (default,
    /// fixed step with `substeps`), `"dopri5"` (Dormand–Prince 5(4)) or
    /// `"bs32"` (Bogacki–Shampine 3(2)), both with error control, sampled
    /// mode only (docs/solvers.md).
    #[serde(skip_serializing_if = "is_rk4")]
    pub solver: SolverKind,
    /// Adaptive solvers: the relative tolerance, in (0, 1). Default 1e-6.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rtol: Option<f64>,
    /// Adaptive solvers: the absolute tolerance, >= 0: one number for
    /// every plant state, or one per plant state in the state's SI unit
    /// (docs/solvers.md lists each plant's states). Default 1e-9.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub atol: Option<AtolCfg>,
    /// Adaptive solvers: the largest step (s), at most `step`. Default
    /// `step` (the sample period).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_step: Option<f64>,
}

fn is_rk4(k: &SolverKind) -> bool {
    *k == SolverKind::Rk4
}

/// `simulation.atol`: one number, or one per plant state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum AtolCfg {
    /// The same for every state.
    Scalar(f64),
    /// One per plant state, in the state's order and SI unit.
    PerState(Vec<f64>),
}

impl Default for SimulationCfg {
    fn default() -> Self {
        Self {
            horizon: 10.0,
            step: 0.01,
            mode: Mode::Sampled,
            substeps: 1,
            settle: 2.0,
            theta_limit: 1.0,
            x0: [0.0; 3],
            computation_delay: false,
            solver: SolverKind::Rk4,
            rtol: None,
            atol: None,
            max_step: None,
        }
    }
}

/// `[uncertainty]`: the true variation. The paper's keys (`a_bias`,
/// `a_random`, `b_bias`, `b_random`, `b_reference`) are the third-order
/// family's, at the Fig. 2 case by default (`a_bias = 1`, `b_bias = 0.5`);
/// another plant refuses them and varies by `[uncertainty.physical]` alone
/// (`ehservo_sim::uncertainty`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct UncertaintyCfg {
    /// Bias fraction of α_i = |ā_i| (default 1, the Fig. 2 case).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub a_bias: Option<f64>,
    /// Random fraction of α_i (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub a_random: Option<f64>,
    /// Bias fraction of β = b_reference·|b̄| (default 0.5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub b_bias: Option<f64>,
    /// Random fraction of β (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub b_random: Option<f64>,
    /// The size the b fractions refer to, as a multiple of b̄ (default 0.5: β).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub b_reference: Option<f64>,
    /// Seed of the random signal. Default 0.
    pub seed: u64,
    /// Hold period of the random signal (s). Default 0.01.
    pub hold: f64,
    /// `[uncertainty.physical]`: bias and random fractions of mass, bulk
    /// modulus, leakage, supply pressure, friction and load.
    #[serde(skip_serializing_if = "PhysicalSpec::is_none")]
    pub physical: PhysicalSpec,
}

impl Default for UncertaintyCfg {
    fn default() -> Self {
        Self {
            a_bias: None,
            a_random: None,
            b_bias: None,
            b_random: None,
            b_reference: None,
            seed: 0,
            hold: 0.01,
            physical: PhysicalSpec::default(),
        }
    }
}

impl UncertaintyCfg {
    /// The paper's keys by name, with what the table gives of them.
    pub fn paper_keys(&self) -> [(&'static str, Option<f64>); 5] {
        [
            ("a_bias", self.a_bias),
            ("a_random", self.a_random),
            ("b_bias", self.b_bias),
            ("b_random", self.b_random),
            ("b_reference", self.b_reference),
        ]
    }

    /// The spec for a plant of the third-order family (`paper`: the Fig. 2
    /// case where a key is not given) or of another (the paper's form all
    /// zero).
    pub fn resolve(&self, paper: bool) -> UncertaintySpec {
        let d = if paper {
            UncertaintySpec::default()
        } else {
            UncertaintySpec::NONE
        };
        UncertaintySpec {
            a_bias: self.a_bias.unwrap_or(d.a_bias),
            a_random: self.a_random.unwrap_or(d.a_random),
            b_bias: self.b_bias.unwrap_or(d.b_bias),
            b_random: self.b_random.unwrap_or(d.b_random),
            b_reference: self.b_reference.unwrap_or(d.b_reference),
            seed: self.seed,
            hold: self.hold,
            physical: self.physical,
        }
    }
}

/// `[surface]`: either `poles` (three real, negative) or `p` = [p1, p2, p3].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SurfaceCfg {
    /// Poles of the sliding dynamics (default −20, −30, −40).
    #[serde(with = "ehservo_sim::triple::option")]
    #[schemars(with = "Option<[f64; 3]>")]
    pub poles: Option<[f64; 3]>,
    /// Coefficients (p1, p2, p3) of (10).
    #[serde(with = "ehservo_sim::triple::option")]
    #[schemars(with = "Option<[f64; 3]>")]
    pub p: Option<[f64; 3]>,
}

/// `[fault]`: what the sampled loop does with a measurement it cannot
/// trust (non-finite, or beyond `measurement_limit`): it commands its safe
/// value and leaves the controller state alone (the core's
/// `SampledController`). The valve range it clamps to is `actuator.limit`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct FaultCfg {
    /// `"hold-last"` (default: the last good command) or `"zero"`.
    pub safe_command: SafeCommandCfg,
    /// |θ|, |θ̇|, |θ̈| beyond these are sensor faults (rad, rad/s, rad/s²).
    #[serde(
        skip_serializing_if = "Option::is_none",
        with = "ehservo_sim::triple::option"
    )]
    #[schemars(with = "Option<[f64; 3]>")]
    pub measurement_limit: Option<[f64; 3]>,
}

impl Default for FaultCfg {
    fn default() -> Self {
        Self {
            safe_command: SafeCommandCfg::HoldLast,
            measurement_limit: None,
        }
    }
}

impl FaultCfg {
    /// Nothing set.
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// `fault.safe_command`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum SafeCommandCfg {
    /// Hold the last good command.
    HoldLast,
    /// Command zero.
    Zero,
}

/// `[output]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct OutputCfg {
    /// Write every n-th sample to `trace.csv` (metrics use every sample). Default 1.
    pub decimate: u32,
    /// Write `trace.png`. Default true.
    pub plot: bool,
}

impl Default for OutputCfg {
    fn default() -> Self {
        Self {
            decimate: 1,
            plot: true,
        }
    }
}

/// `[estimator]`: what estimates the channels of x that `sensor.measured`
/// leaves out, from the measured θ, at the controller's rate (sampled mode).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum EstimatorCfg {
    /// Levant's robust exact differentiator of second order.
    Levant {
        /// Bound L on |θ⃛| of the motion (rad/s³).
        lipschitz: f64,
        /// Sub-steps of the differentiator per sample, the input interpolated
        /// linearly between samples. Default 1 (Livne & Levant's
        /// second-order-corrected step, see `ehservo_core::estimate`).
        #[serde(default = "default_levant_substeps")]
        substeps: u32,
    },
    /// Luenberger observer on the nominal linear model.
    Luenberger {
        /// Continuous-time observer poles (rad/s, real, negative).
        poles: [f64; 3],
    },
    /// Steady-state Kalman filter on the nominal linear model.
    Kalman {
        /// Intensity q of the white jerk driving the model ((rad/s³)²·s).
        process_noise: f64,
        /// Variance of the θ measurement (rad²); default sensor.noise[0]².
        #[serde(default, skip_serializing_if = "Option::is_none")]
        measurement_noise: Option<f64>,
    },
}

fn default_levant_substeps() -> u32 {
    1
}

impl EstimatorCfg {
    /// The scenario spelling of the kind.
    pub fn kind(&self) -> &'static str {
        match self {
            EstimatorCfg::Levant { .. } => "levant",
            EstimatorCfg::Luenberger { .. } => "luenberger",
            EstimatorCfg::Kalman { .. } => "kalman",
        }
    }
}
