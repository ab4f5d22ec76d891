//! The sections of a scenario file, one type each, every key at the
//! paper's Fig. 2 value by default.

use ehservo_core::cylinder::CylinderParams;
use ehservo_core::servo::ServoParams;
use ehservo_sim::simulation::Mode;
use serde::{Deserialize, Serialize};

/// The paper's plant model choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlantModel {
    /// Eq. (8)–(9) in (θ, θ̇, θ̈).
    ThirdOrder,
    /// Eqs. (1)–(6) in (θ, θ̇, Pl).
    Physical,
    /// A valve-controlled double-rod cylinder on a rack and pinion
    /// (`[plant.cylinder]`, docs/cylinder.md), in (y, ẏ, P1, P2).
    Cylinder,
}

impl PlantModel {
    /// The scenario's name of the model.
    pub fn as_str(&self) -> &'static str {
        match self {
            PlantModel::ThirdOrder => "third-order",
            PlantModel::Physical => "physical",
            PlantModel::Cylinder => "cylinder",
        }
    }
}

/// `[simulation]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    pub x0: [f64; 3],
    /// Sampled mode: apply each command one sample after the measurement
    /// it was computed from (a controller that takes a period to compute).
    /// Default false.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub computation_delay: bool,
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
        }
    }
}

/// `[plant]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlantCfg {
    /// `"third-order"` (default), `"physical"` or `"cylinder"`.
    pub model: PlantModel,
    /// `[plant.params]`: the physical parameters, SI, by the paper's symbol
    /// (`Ps`, `beta_e`, `Vt`, `Kce`, `Dm`, `Jt`, `Bm`, `Kv`, `G`, `rho`, `Cd`, `Ag`).
    pub params: ServoParams,
    /// `[plant.cylinder]`: the cylinder's parameters (`model = "cylinder"`
    /// only; the documented typical set when absent). The nominal model is
    /// then derived from them and `[plant.params]` must not be given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cylinder: Option<CylinderParams>,
}

impl Default for PlantCfg {
    fn default() -> Self {
        Self {
            model: PlantModel::ThirdOrder,
            params: ServoParams::paper(),
            cylinder: None,
        }
    }
}

/// `[surface]`: either `poles` (three real, negative) or `p` = [p1, p2, p3].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct SurfaceCfg {
    /// Poles of the sliding dynamics (default −20, −30, −40).
    #[serde(with = "ehservo_sim::triple::option")]
    pub poles: Option<[f64; 3]>,
    /// Coefficients (p1, p2, p3) of (10).
    #[serde(with = "ehservo_sim::triple::option")]
    pub p: Option<[f64; 3]>,
}

/// `[fault]`: what the sampled loop does with a measurement it cannot
/// trust (non-finite, or beyond `measurement_limit`): it commands its safe
/// value and leaves the controller state alone (the core's
/// `SampledController`). The valve range it clamps to is `actuator.limit`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FaultCfg {
    /// `"hold-last"` (default: the last good command) or `"zero"`.
    pub safe_command: SafeCommandCfg,
    /// |θ|, |θ̇|, |θ̈| beyond these are sensor faults (rad, rad/s, rad/s²).
    #[serde(
        skip_serializing_if = "Option::is_none",
        with = "ehservo_sim::triple::option"
    )]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SafeCommandCfg {
    /// Hold the last good command.
    HoldLast,
    /// Command zero.
    Zero,
}

/// `[output]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
