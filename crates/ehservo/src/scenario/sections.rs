//! The sections of a scenario file, one type each, every key at the
//! paper's Fig. 2 value by default.

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
    pub x0: [f64; 3],
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
        }
    }
}

/// `[plant]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlantCfg {
    /// `"third-order"` (default) or `"physical"`.
    pub model: PlantModel,
    /// `[plant.params]`: the physical parameters, SI.
    pub params: ParamsCfg,
}

impl Default for PlantCfg {
    fn default() -> Self {
        Self {
            model: PlantModel::ThirdOrder,
            params: ParamsCfg::default(),
        }
    }
}

/// `[plant.params]`, SI units, by the paper's symbol.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
#[allow(non_snake_case)]
pub struct ParamsCfg {
    /// Supply pressure (Pa).
    pub Ps: f64,
    /// Bulk modulus (Pa).
    pub beta_e: f64,
    /// Compressed volume (m³).
    pub Vt: f64,
    /// Flow-pressure coefficient (m³/(s·Pa)).
    pub Kce: f64,
    /// Motor displacement (m³/rad).
    pub Dm: f64,
    /// Inertia (N·m·s²).
    pub Jt: f64,
    /// Viscous damping (N·m·s).
    pub Bm: f64,
    /// Servovalve gain (m/V).
    pub Kv: f64,
    /// Spring gradient (N·m/rad).
    pub G: f64,
    /// Density (kg/m³).
    pub rho: f64,
    /// Discharge coefficient.
    pub Cd: f64,
    /// Area gradient (m).
    pub Ag: f64,
}

impl Default for ParamsCfg {
    fn default() -> Self {
        let p = ServoParams::paper();
        Self {
            Ps: p.ps,
            beta_e: p.beta_e,
            Vt: p.vt,
            Kce: p.kce,
            Dm: p.dm,
            Jt: p.jt,
            Bm: p.bm,
            Kv: p.kv,
            G: p.g,
            rho: p.rho,
            Cd: p.cd,
            Ag: p.ag,
        }
    }
}

impl ParamsCfg {
    /// As the core's parameter struct.
    pub fn to_servo(&self) -> ServoParams {
        ServoParams {
            ps: self.Ps,
            beta_e: self.beta_e,
            vt: self.Vt,
            kce: self.Kce,
            dm: self.Dm,
            jt: self.Jt,
            bm: self.Bm,
            kv: self.Kv,
            g: self.G,
            rho: self.rho,
            cd: self.Cd,
            ag: self.Ag,
        }
    }
}

/// `[load]`: `Tl = amplitude·sin(wavenumber·θ)` plus optional friction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LoadCfg {
    /// A (N·m). Default 2.
    pub amplitude: f64,
    /// k (1/rad). Default 4.
    pub wavenumber: f64,
    /// `[load.friction]`: Coulomb/Stribeck/viscous friction (off unless given).
    pub friction: Option<FrictionCfg>,
}

impl Default for LoadCfg {
    fn default() -> Self {
        Self {
            amplitude: 2.0,
            wavenumber: 4.0,
            friction: None,
        }
    }
}

/// `[load.friction]`. The defaults are illustrative, not from the paper.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FrictionCfg {
    /// Coulomb level Tc (N·m). Default 0.2.
    pub coulomb: f64,
    /// Break-away level Ts (N·m). Default 0.3.
    pub stiction: f64,
    /// Stribeck velocity (rad/s). Default 0.05.
    pub stribeck_velocity: f64,
    /// Extra viscous coefficient (N·m·s). Default 0.
    pub viscous: f64,
    /// Sign regularisation velocity (rad/s). Default 0.005.
    pub smoothing: f64,
}

impl Default for FrictionCfg {
    fn default() -> Self {
        Self {
            coulomb: 0.2,
            stiction: 0.3,
            stribeck_velocity: 0.05,
            viscous: 0.0,
            smoothing: 0.005,
        }
    }
}

/// `[uncertainty]`: Δa_i = |ā_i|·(a_bias + a_random·r_i),
/// Δb = b_reference·b̄·(b_bias + b_random·r_b), r uniform on [−1, 1] held over `hold`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct UncertaintyCfg {
    /// Default 1 (the paper's 100% bias).
    pub a_bias: f64,
    /// Default 0.
    pub a_random: f64,
    /// Default 0.5 (the paper's Δb = 0.5β).
    pub b_bias: f64,
    /// Default 0.
    pub b_random: f64,
    /// What the b fractions are fractions of, as a multiple of b̄:
    /// 0.5 (β = 0.5|b̄|, the text's "Δb = 0.5β", SPEC) or 1 (b̄ itself, the
    /// Fig. 2 caption's "50 % bias of parameter b"). Default 0.5.
    pub b_reference: f64,
    /// Seed of the random part. Default 0.
    pub seed: u64,
    /// Hold period of the random part (s). Default 0.01.
    pub hold: f64,
}

impl Default for UncertaintyCfg {
    fn default() -> Self {
        Self {
            a_bias: 1.0,
            a_random: 0.0,
            b_bias: 0.5,
            b_random: 0.0,
            b_reference: 0.5,
            seed: 0,
            hold: 0.01,
        }
    }
}

/// `[reference]`: θd = amplitude·sin(2π·f·t).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReferenceCfg {
    /// Default 5°.
    pub amplitude_deg: f64,
    /// Default 1 Hz.
    pub frequency_hz: f64,
}

impl Default for ReferenceCfg {
    fn default() -> Self {
        Self {
            amplitude_deg: 5.0,
            frequency_hz: 1.0,
        }
    }
}

/// `[surface]`: either `poles` (three real, negative) or `p` = [p1, p2, p3].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct SurfaceCfg {
    /// Poles of the sliding dynamics (default −20, −30, −40).
    pub poles: Option<[f64; 3]>,
    /// Coefficients (p1, p2, p3) of (10).
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
    #[serde(skip_serializing_if = "Option::is_none")]
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
