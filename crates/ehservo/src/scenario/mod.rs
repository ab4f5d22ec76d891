//! Scenario files: TOML, every parameter defaulting to the paper's value.
//!
//! The Fig. 2 case is just:
//!
//! ```toml
//! name = "fig2"
//! ```
//!
//! and any key can be set in the file or overridden on the command line with
//! `--set key.path=value`. Unknown keys, wrong types and non-physical values
//! are rejected with a [`ScenarioError`] naming the file, the key (with line
//! and column when TOML gives them) and the reason. See the README for the
//! full list of keys; [`Scenario::default`] is the paper's Fig. 2 case.

mod build;
mod overrides;
mod registry;

pub use build::Setup;
pub use overrides::{apply_override, line_col, parse_value, set_path};
pub use registry::{ControllerCfg, ControllerConfig, Visit, DEFAULT_KIND};

use ehservo_core::servo::ServoParams;
use ehservo_sim::actuator::ActuatorConfig;
use ehservo_sim::sensor::SensorConfig;
use ehservo_sim::simulation::Mode;
use overrides::{clean_path, first_line, locate};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::Path;

/// A bad scenario: which file, which key, where, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioError {
    /// The file (or `<--set>` / `<string>`).
    pub file: String,
    /// The key path, e.g. `plant.params.Jt` (empty when the file as a whole is at fault).
    pub key: String,
    /// 1-based line and column, when known.
    pub line_col: Option<(usize, usize)>,
    /// Why.
    pub reason: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some((l, c)) = self.line_col {
            write!(f, ":{l}:{c}")?;
        }
        if self.key.is_empty() {
            write!(f, ": {}", self.reason)
        } else {
            write!(f, ": `{}`: {}", self.key, self.reason)
        }
    }
}

impl std::error::Error for ScenarioError {}

/// The paper's plant model choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlantModel {
    /// Eq. (8)–(9) in (θ, θ̇, θ̈).
    ThirdOrder,
    /// Eqs. (1)–(6) in (θ, θ̇, Pl).
    Physical,
}

/// A whole scenario. Every field has the paper's Fig. 2 value by default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Scenario {
    /// Name of the case (defaults to the file's stem).
    pub name: String,
    /// Free text.
    pub description: String,
    /// Horizon, step, mode.
    pub simulation: SimulationCfg,
    /// Model and physical parameters.
    pub plant: PlantCfg,
    /// Load torque.
    pub load: LoadCfg,
    /// True parameter variation.
    pub uncertainty: UncertaintyCfg,
    /// Desired trajectory.
    pub reference: ReferenceCfg,
    /// Switching surface.
    pub surface: SurfaceCfg,
    /// Controller: `kind` and that kind's parameters.
    pub controller: ControllerCfg,
    /// The valve between controller and plant (identity unless given).
    #[serde(skip_serializing_if = "ActuatorConfig::is_identity")]
    pub actuator: ActuatorConfig,
    /// What the controller measures (exact unless given).
    #[serde(skip_serializing_if = "SensorConfig::is_identity")]
    pub sensor: SensorConfig,
    /// The sampled loop's response to a bad measurement.
    #[serde(skip_serializing_if = "FaultCfg::is_default")]
    pub fault: FaultCfg,
    /// Output options.
    pub output: OutputCfg,
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

/// Largest number of steps a scenario may ask for: 2·10⁷ (200 s at 10 µs;
/// about 6 GB of trace.csv without `output.decimate`). A guard against a
/// mistyped step, not a physical limit.
pub const MAX_STEPS: u64 = 20_000_000;

impl Scenario {
    /// Reads, parses, overrides and validates a scenario file.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Scenario, ScenarioError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ScenarioError {
            file: file.clone(),
            key: String::new(),
            line_col: None,
            reason: format!("cannot read the scenario file: {e}"),
        })?;
        let mut s = Self::parse_with(&text, &file, overrides)?;
        if s.name.is_empty() {
            s.name = path
                .file_stem()
                .map(|x| x.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scenario".into());
        }
        Ok(s)
    }

    /// Parses and validates TOML text (no overrides).
    pub fn parse(text: &str) -> Result<Scenario, ScenarioError> {
        Self::parse_with(text, "<string>", &[])
    }

    /// Parses TOML text, applies `key.path=value` overrides, validates.
    pub fn parse_with(
        text: &str,
        file: &str,
        overrides: &[String],
    ) -> Result<Scenario, ScenarioError> {
        let err = |key: String, line_col, reason: String| ScenarioError {
            file: file.to_string(),
            key,
            line_col,
            reason,
        };
        // Pass 1, from the text: errors carry a key path and a position.
        let de = toml::Deserializer::parse(text).map_err(|e| {
            let lc = e.span().map(|s| line_col(text, s.start));
            err(
                String::new(),
                lc,
                format!("TOML syntax error: {}", first_line(e.message())),
            )
        })?;
        let scenario: Scenario = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = clean_path(&e.path().to_string());
            let inner = e.into_inner();
            if key == "controller" {
                return controller_error(text, file);
            }
            let lc = inner.span().map(|s| line_col(text, s.start));
            err(key, lc, first_line(inner.message()))
        })?;
        let scenario = if overrides.is_empty() {
            scenario
        } else {
            // Pass 2: apply the overrides to the document and read it again.
            let mut table: toml::Table = toml::from_str(text).map_err(|e| {
                err(
                    String::new(),
                    None,
                    format!("TOML syntax error: {}", first_line(e.message())),
                )
            })?;
            for o in overrides {
                apply_override(&mut table, o).map_err(|(k, r)| ScenarioError {
                    file: "--set".into(),
                    key: k,
                    line_col: None,
                    reason: r,
                })?;
            }
            let after = format!("{file} (after --set)");
            let controller = table.get("controller").cloned();
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
                let key = clean_path(&e.path().to_string());
                match (key.as_str(), controller) {
                    ("controller", Some(toml::Value::Table(t))) => {
                        controller_table_error(t, &after, None)
                    }
                    _ => ScenarioError {
                        file: after.clone(),
                        key,
                        line_col: None,
                        reason: first_line(&e.into_inner().to_string()),
                    },
                }
            })?
        };
        scenario.validate().map_err(|(key, reason)| {
            let lc = locate(text, &key);
            err(key, lc, reason)
        })?;
        Ok(scenario)
    }

    /// The scenario's sections built and checked together: the one place
    /// that turns a scenario into what a simulation is made of.
    pub fn setup(&self) -> Result<Setup, ScenarioError> {
        Setup::new(self).map_err(|(key, reason)| ScenarioError {
            file: self.name.clone(),
            key,
            line_col: None,
            reason,
        })
    }

    /// Every check that serde's types cannot express. Returns the key path
    /// and the reason of the first failure.
    pub fn validate(&self) -> Result<(), (String, String)> {
        Setup::new(self).map(|_| ())
    }

    /// This scenario as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }
}

impl Scenario {
    /// This scenario with some keys set to new values (each a dotted path
    /// and a TOML value), validated. Cheaper than re-parsing text: used by
    /// sweeps for every run.
    pub fn with_values(&self, values: &[(String, toml::Value)]) -> Result<Scenario, ScenarioError> {
        let fail = |key: String, reason: String| ScenarioError {
            file: self.name.clone(),
            key,
            line_col: None,
            reason,
        };
        let mut table =
            toml::Table::try_from(self).map_err(|e| fail(String::new(), e.to_string()))?;
        for (k, v) in values {
            set_path(&mut table, k, v.clone()).map_err(|(k, r)| fail(k, r))?;
        }
        let controller = table.get("controller").cloned();
        let s: Scenario =
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
                let key = clean_path(&e.path().to_string());
                match (key.as_str(), controller) {
                    ("controller", Some(toml::Value::Table(t))) => {
                        controller_table_error(t, &self.name, None)
                    }
                    _ => fail(key, first_line(&e.into_inner().to_string())),
                }
            })?;
        s.validate().map_err(|(k, r)| fail(k, r))?;
        Ok(s)
    }
}

/// The precise error of a `[controller]` table that did not deserialise:
/// the key inside it, with its position in `text` when there is one.
fn controller_table_error(table: toml::Table, file: &str, text: Option<&str>) -> ScenarioError {
    let (k, reason) = match ControllerCfg::from_toml(table) {
        Err(e) => e,
        Ok(_) => (String::new(), "invalid controller table".into()),
    };
    let key = if k.is_empty() {
        "controller".to_string()
    } else {
        format!("controller.{k}")
    };
    let line_col = text.and_then(|t| locate(t, &key).or_else(|| locate(t, "controller")));
    ScenarioError {
        file: file.to_string(),
        key,
        line_col,
        reason,
    }
}

fn controller_error(text: &str, file: &str) -> ScenarioError {
    let table = toml::from_str::<toml::Table>(text)
        .ok()
        .and_then(|mut t| t.remove("controller"));
    match table {
        Some(toml::Value::Table(t)) => controller_table_error(t, file, Some(text)),
        _ => ScenarioError {
            file: file.to_string(),
            key: "controller".into(),
            line_col: locate(text, "controller"),
            reason: "must be a table".into(),
        },
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    #[test]
    fn empty_file_is_the_paper_fig2_case() {
        let s = Scenario::parse("").unwrap();
        assert_eq!(s.controller.kind(), "nnvsc");
        assert_eq!(s.simulation.step, 0.01);
        assert_eq!(s.uncertainty.a_bias, 1.0);
        assert_eq!(s.uncertainty.b_bias, 0.5);
        assert_eq!(s.surface().unwrap().p(), [90.0, 2600.0, 24000.0]);
        assert_eq!(s.sim_config().steps, 1000);
    }

    #[test]
    fn overrides_apply_and_are_typed() {
        let s = Scenario::parse_with(
            "name = \"x\"",
            "t.toml",
            &[
                "controller.gamma1=200".into(),
                "controller.kind=vsc".into(),
                "simulation.mode = continuous".into(),
                "simulation.step=1e-3".into(),
                "surface.poles=[-10, -20, -30]".into(),
            ],
        )
        .unwrap();
        let c = s
            .controller
            .get::<ehservo_core::control::sliding::VscConfig>();
        assert_eq!(c.map(|c| c.0.gamma1), Some(200.0));
        assert_eq!(s.controller.kind(), "vsc");
        assert_eq!(s.simulation.mode, Mode::Continuous);
        assert_eq!(s.sim_config().steps, 10_000);
        assert_eq!(s.surface().unwrap().p(), [60.0, 1100.0, 6000.0]);
    }

    fn err(text: &str) -> ScenarioError {
        Scenario::parse_with(text, "bad.toml", &[]).unwrap_err()
    }

    #[test]
    fn errors_name_the_key_and_the_reason() {
        let e = err("[plant.params]\nJt = -1.0\n");
        assert_eq!(e.key, "plant.params.Jt");
        assert_eq!(e.line_col, Some((2, 6)));
        assert!(e.reason.contains("> 0"), "{e}");

        let e = err("[controller]\ngama1 = 3\n");
        assert_eq!(e.key, "controller.gama1");
        assert!(e.reason.contains("unknown field"), "{e}");
        assert_eq!(e.line_col.map(|l| l.0), Some(2));

        let e = err("[simulation]\nstep = \"fast\"\n");
        assert_eq!(e.key, "simulation.step");
        assert!(e.reason.contains("invalid type"), "{e}");

        let e = err("[simulation]\nhorizon = 10.005\n");
        assert_eq!(e.key, "simulation.horizon");
        assert!(e.reason.contains("whole number"), "{e}");

        let e = err("[surface]\npoles = [-20, 30, -40]\n");
        assert_eq!(e.key, "surface.poles");

        let e = err("[plant]\nmodel = \"fourth-order\"\n");
        assert_eq!(e.key, "plant.model");

        let e = err("[simulation\nstep = 1\n");
        assert!(e.reason.contains("syntax"), "{e}");
        assert_eq!(e.line_col.map(|l| l.0), Some(1));

        let e = Scenario::parse_with("", "t.toml", &["controller.nope=1".into()]).unwrap_err();
        assert_eq!(e.key, "controller.nope");
    }
}
