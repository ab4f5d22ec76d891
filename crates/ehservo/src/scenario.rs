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

use crate::plant::UncertaintySpec;
use crate::sim::{Mode, SimConfig};
use ehservo_core::control::nnvsc::{MuRule, NnVscParams};
use ehservo_core::control::vsc::{Switching, VscParams};
use ehservo_core::error::ParamError;
use ehservo_core::rbf::Rbf;
use ehservo_core::reference::Sine;
use ehservo_core::servo::{Friction, Load, ServoParams};
use ehservo_core::surface::SwitchingSurface;
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

/// Which controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ControllerKind {
    /// Theorem 1 with sgn(σ).
    Vsc,
    /// Theorem 1 with sat(σ/μ) (Remark 2).
    VscSat,
    /// Theorem 3.
    Nnvsc,
}

impl ControllerKind {
    /// The scenario spelling.
    pub fn as_str(&self) -> &'static str {
        match self {
            ControllerKind::Vsc => "vsc",
            ControllerKind::VscSat => "vsc-sat",
            ControllerKind::Nnvsc => "nnvsc",
        }
    }
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
    /// Controller.
    pub controller: ControllerCfg,
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

/// `controller.mu_rule`: how the NNBVSC's boundary layer μ(t) is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MuRuleCfg {
    /// SPEC §5 (Remark 7): μ = (α − ᾱ)‖E‖ε2/c. The default.
    Remark7,
    /// The printed (33), negative; for measuring the erratum only.
    #[serde(rename = "literal-33")]
    Literal33,
    /// μ = 0.
    Zero,
}

/// `[controller]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControllerCfg {
    /// `"nnvsc"` (default), `"vsc"` or `"vsc-sat"`.
    pub kind: ControllerKind,
    /// Bound the controller knows on Δa_i: α_i = bound_a·|ā_i|. Default 1.
    pub bound_a: f64,
    /// Bound the controller knows on Δb: β = bound_b·|b̄|. Default 0.5.
    pub bound_b: f64,
    /// γ1. Default 100.
    pub gamma1: f64,
    /// η. Default 0.25.
    pub eta: f64,
    /// α. Default 250.
    pub alpha: f64,
    /// ᾱ. Default 5.
    pub alpha_bar: f64,
    /// Wmax. Default 4.
    pub w_max: f64,
    /// ε0. Default 0.1.
    pub eps0: f64,
    /// ε1. Default 0.1.
    pub eps1: f64,
    /// ε2. Default 0.01.
    pub eps2: f64,
    /// h (H = h·I). Default 1.
    pub h: f64,
    /// Boundary-layer width of `vsc-sat` (rad/s²). Default 1.
    pub mu: f64,
    /// NNBVSC boundary-layer rule: `"remark7"` (default, SPEC §5),
    /// `"literal-33"` (the printed, negative (33)) or `"zero"`.
    pub mu_rule: MuRuleCfg,
    /// `[controller.rbf]`.
    pub rbf: RbfCfg,
}

impl Default for ControllerCfg {
    fn default() -> Self {
        let p = NnVscParams::paper();
        Self {
            kind: ControllerKind::Nnvsc,
            bound_a: 1.0,
            bound_b: p.bound_b,
            gamma1: p.gamma1,
            eta: p.eta,
            alpha: p.alpha,
            alpha_bar: p.alpha_bar,
            w_max: p.w_max,
            eps0: p.eps0,
            eps1: p.eps1,
            eps2: p.eps2,
            h: p.h,
            mu: 1.0,
            mu_rule: MuRuleCfg::Remark7,
            rbf: RbfCfg::default(),
        }
    }
}

/// `[controller.rbf]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RbfCfg {
    /// δ. Default 0.5.
    pub width: f64,
    /// Grid levels per axis. Default [−1, −0.5, 0, 0.5, 1].
    pub levels: [f64; 5],
    /// Normalising scales of x1, x2, x3 (rad, rad/s, rad/s²).
    /// Default (6.25°, 12.5π °/s, 25π² °/s²) in radians.
    pub scale: [f64; 3],
}

impl Default for RbfCfg {
    fn default() -> Self {
        let r = Rbf::paper();
        Self {
            width: r.width(),
            levels: r.levels(),
            scale: r.scale(),
        }
    }
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

/// 1-based line and column of a byte offset in `text`.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before
        .rsplit('\n')
        .next()
        .map(|l| l.chars().count())
        .unwrap_or(0)
        + 1;
    (line, col)
}

/// Line and column of the value of `key` (a dotted path) in `text`, when
/// the file sets it (a default has no position).
fn locate(text: &str, key: &str) -> Option<(usize, usize)> {
    let root = toml::de::DeTable::parse(text).ok()?;
    let mut segs = key.split('.');
    let first = segs.next()?;
    let mut cur = root
        .get_ref()
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == first)
        .map(|(_, v)| v)?;
    for seg in segs {
        cur = cur.get_ref().get(seg)?;
    }
    Some(line_col(text, cur.span().start))
}

/// Strips toml's own location prefix and snippet from a message.
fn first_line(msg: &str) -> String {
    msg.lines()
        .find(|l| !l.trim().is_empty())
        .unwrap_or(msg)
        .trim()
        .to_string()
}

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
            let key = e.path().to_string();
            let inner = e.into_inner();
            let lc = inner.span().map(|s| line_col(text, s.start));
            err(clean_path(&key), lc, first_line(inner.message()))
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
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
                ScenarioError {
                    file: format!("{file} (after --set)"),
                    key: clean_path(&e.path().to_string()),
                    line_col: None,
                    reason: first_line(&e.into_inner().to_string()),
                }
            })?
        };
        scenario.validate().map_err(|(key, reason)| {
            let lc = locate(text, &key);
            err(key, lc, reason)
        })?;
        Ok(scenario)
    }

    /// Every check that serde's types cannot express. Returns the key path
    /// and the reason of the first failure.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let sim = &self.simulation;
        let bad = |k: &str, r: String| Err((k.to_string(), r));
        if !(sim.step.is_finite() && sim.step > 0.0) {
            return bad(
                "simulation.step",
                format!("must be finite and > 0 (got {})", sim.step),
            );
        }
        if !(sim.horizon.is_finite() && sim.horizon > 0.0) {
            return bad(
                "simulation.horizon",
                format!("must be finite and > 0 (got {})", sim.horizon),
            );
        }
        let n = sim.horizon / sim.step;
        if n > MAX_STEPS as f64 {
            return bad(
                "simulation.step",
                format!("horizon/step = {n:.3e} steps exceeds the limit of {MAX_STEPS}"),
            );
        }
        if (n - n.round()).abs() > 1e-6 * n.max(1.0) || n.round() < 1.0 {
            return bad(
                "simulation.horizon",
                format!(
                    "must be a whole number of steps: {} / {} = {n}",
                    sim.horizon, sim.step
                ),
            );
        }
        if sim.substeps == 0 || sim.substeps > 10_000 {
            return bad(
                "simulation.substeps",
                format!("must be in 1..=10000 (got {})", sim.substeps),
            );
        }
        // settle ≥ horizon is allowed: the windowed metrics are then absent.
        if !(sim.settle.is_finite() && sim.settle >= 0.0) {
            return bad(
                "simulation.settle",
                format!("must be finite and >= 0 (got {})", sim.settle),
            );
        }
        if !(sim.theta_limit.is_finite() && sim.theta_limit > 0.0) {
            return bad(
                "simulation.theta_limit",
                format!("must be finite and > 0 (got {})", sim.theta_limit),
            );
        }
        if let Some(v) = sim.x0.iter().find(|v| !v.is_finite()) {
            return bad("simulation.x0", format!("must be finite (got {v})"));
        }
        if sim.x0[0].abs() > sim.theta_limit {
            return bad(
                "simulation.x0",
                "θ(0) is beyond simulation.theta_limit".into(),
            );
        }

        self.plant
            .params
            .to_servo()
            .validate()
            .map_err(|e| param_err("plant.params", e))?;
        self.load_model().validate().map_err(|e| {
            let prefix = if matches!(e.name, "amplitude" | "wavenumber") {
                "load"
            } else {
                "load.friction"
            };
            param_err(prefix, e)
        })?;

        let u = &self.uncertainty;
        for (k, v) in [
            ("uncertainty.a_bias", u.a_bias),
            ("uncertainty.a_random", u.a_random),
            ("uncertainty.b_bias", u.b_bias),
            ("uncertainty.b_random", u.b_random),
        ] {
            if !v.is_finite() {
                return bad(k, format!("must be finite (got {v})"));
            }
        }
        if !(u.hold.is_finite() && u.hold > 0.0) {
            return bad(
                "uncertainty.hold",
                format!("must be finite and > 0 (got {})", u.hold),
            );
        }
        if !(u.b_reference.is_finite() && u.b_reference > 0.0) {
            return bad(
                "uncertainty.b_reference",
                format!("must be finite and > 0 (got {})", u.b_reference),
            );
        }
        // The true b must stay positive: 1 + b_ref·(b_bias ± b_random) > 0.
        if 1.0 + u.b_reference * (u.b_bias - u.b_random.abs()) <= 0.0 {
            return bad(
                "uncertainty.b_bias",
                "the true b = b̄·(1 + b_reference·(b_bias + b_random·r)) must stay > 0 (Assumption A1)"
                    .into(),
            );
        }

        let r = &self.reference;
        if !(r.amplitude_deg.is_finite() && r.amplitude_deg >= 0.0) {
            return bad(
                "reference.amplitude_deg",
                format!("must be finite and >= 0 (got {})", r.amplitude_deg),
            );
        }
        if r.amplitude_deg.to_radians() >= sim.theta_limit {
            return bad(
                "reference.amplitude_deg",
                "the reference reaches simulation.theta_limit: every run would count as diverged"
                    .into(),
            );
        }
        if !(r.frequency_hz.is_finite() && r.frequency_hz > 0.0) {
            return bad(
                "reference.frequency_hz",
                format!("must be finite and > 0 (got {})", r.frequency_hz),
            );
        }

        self.surface()?;
        self.rbf().map_err(|e| param_err("controller", e))?;
        match self.controller.kind {
            ControllerKind::Nnvsc => self
                .nnvsc_params()
                .validate()
                .map_err(|e| param_err("controller", e))?,
            ControllerKind::Vsc | ControllerKind::VscSat => {
                let p = self.vsc_params();
                if !(p.bound_a.is_finite() && p.bound_a >= 0.0) {
                    return bad(
                        "controller.bound_a",
                        format!("must be finite and >= 0 (got {})", p.bound_a),
                    );
                }
                if !(p.bound_b.is_finite() && (0.0..1.0).contains(&p.bound_b)) {
                    return bad(
                        "controller.bound_b",
                        format!(
                            "must be in [0, 1) (Assumption A1: β < b̄) (got {})",
                            p.bound_b
                        ),
                    );
                }
                if let Switching::Saturation { mu } = p.switching {
                    if !(mu.is_finite() && mu > 0.0) {
                        return bad(
                            "controller.mu",
                            format!("must be finite and > 0 (got {mu})"),
                        );
                    }
                }
            }
        }
        if self.output.decimate == 0 {
            return bad("output.decimate", "must be >= 1".into());
        }
        Ok(())
    }

    /// The switching surface from `poles` or `p`.
    pub fn surface(&self) -> Result<SwitchingSurface, (String, String)> {
        match (self.surface.poles, self.surface.p) {
            (Some(_), Some(_)) => Err((
                "surface".into(),
                "give either `poles` or `p`, not both".into(),
            )),
            (Some(poles), None) => {
                SwitchingSurface::from_poles(poles).map_err(|e| param_err("surface", e))
            }
            (None, Some(p)) => SwitchingSurface::try_new(p).map_err(|e| {
                let (_, r) = param_err("surface", e);
                ("surface.p".into(), r)
            }),
            (None, None) => Ok(SwitchingSurface::paper()),
        }
    }

    /// The load model.
    pub fn load_model(&self) -> Load {
        Load {
            amplitude: self.load.amplitude,
            wavenumber: self.load.wavenumber,
            friction: self.load.friction.map(|f| Friction {
                coulomb: f.coulomb,
                stiction: f.stiction,
                stribeck_velocity: f.stribeck_velocity,
                viscous: f.viscous,
                smoothing: f.smoothing,
            }),
        }
    }

    /// The reference.
    pub fn reference(&self) -> Sine {
        Sine::from_deg_hz(self.reference.amplitude_deg, self.reference.frequency_hz)
    }

    /// The network.
    pub fn rbf(&self) -> Result<Rbf, ParamError> {
        let r = &self.controller.rbf;
        Rbf::try_new(r.levels, r.width, r.scale)
    }

    /// The NNBVSC gains.
    pub fn nnvsc_params(&self) -> NnVscParams {
        let c = &self.controller;
        NnVscParams {
            gamma1: c.gamma1,
            eta: c.eta,
            alpha: c.alpha,
            alpha_bar: c.alpha_bar,
            w_max: c.w_max,
            eps0: c.eps0,
            eps1: c.eps1,
            eps2: c.eps2,
            h: c.h,
            bound_b: c.bound_b,
            mu_rule: match c.mu_rule {
                MuRuleCfg::Remark7 => MuRule::Remark7,
                MuRuleCfg::Literal33 => MuRule::Literal33,
                MuRuleCfg::Zero => MuRule::Zero,
            },
        }
    }

    /// The VSC gains.
    pub fn vsc_params(&self) -> VscParams {
        let c = &self.controller;
        VscParams {
            bound_a: c.bound_a,
            bound_b: c.bound_b,
            switching: match c.kind {
                ControllerKind::VscSat => Switching::Saturation { mu: c.mu },
                _ => Switching::Sign,
            },
        }
    }

    /// The true variation.
    pub fn uncertainty_spec(&self) -> UncertaintySpec {
        let u = &self.uncertainty;
        UncertaintySpec {
            a_bias: u.a_bias,
            a_random: u.a_random,
            b_bias: u.b_bias,
            b_random: u.b_random,
            b_reference: u.b_reference,
            seed: u.seed,
            hold: u.hold,
        }
    }

    /// The loop's settings.
    pub fn sim_config(&self) -> SimConfig {
        let s = &self.simulation;
        SimConfig {
            steps: (s.horizon / s.step).round() as u64,
            step: s.step,
            mode: s.mode,
            substeps: s.substeps,
            theta_limit: s.theta_limit,
            x0: s.x0,
        }
    }

    /// This scenario as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }
}

fn param_err(prefix: &str, e: ParamError) -> (String, String) {
    let name = e
        .name
        .strip_prefix("rbf.")
        .map(|n| format!("rbf.{n}"))
        .unwrap_or_else(|| e.name.to_string());
    let reason = if e.value.is_nan() {
        e.reason.to_string()
    } else {
        format!("{} (got {})", e.reason, e.value)
    };
    (format!("{prefix}.{name}"), reason)
}

/// serde_path_to_error writes `?` for the root and `a.b` for fields.
fn clean_path(p: &str) -> String {
    if p == "." || p == "?" {
        String::new()
    } else {
        p.to_string()
    }
}

/// Reads the value of a `key.path=value` override as a TOML value (`200`,
/// `1e-3`, `true`, `[1, 2, 3]`, `"text"`); a bare word that is not TOML
/// (`vsc`, `continuous`) is taken as a string.
pub fn parse_value(raw: &str) -> toml::Value {
    let raw = raw.trim();
    match toml::from_str::<toml::Table>(&format!("v = {raw}")) {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or(toml::Value::String(raw.to_string())),
        Err(_) => toml::Value::String(raw.to_string()),
    }
}

/// Sets `path` (dotted) to `value` in a TOML document, creating tables on
/// the way. Errors name the path and the reason.
pub fn set_path(
    table: &mut toml::Table,
    path: &str,
    value: toml::Value,
) -> Result<(), (String, String)> {
    let path = path.trim();
    if path.is_empty() || path.split('.').any(|p| p.trim().is_empty()) {
        return Err((path.to_string(), "empty key in key.path=value".into()));
    }
    let parts: Vec<&str> = path.split('.').map(str::trim).collect();
    let mut cur = table;
    for (i, part) in parts.iter().enumerate() {
        if i + 1 == parts.len() {
            cur.insert(part.to_string(), value);
            return Ok(());
        }
        let entry = cur
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = match entry {
            toml::Value::Table(t) => t,
            _ => {
                return Err((
                    parts[..=i].join("."),
                    "is a value, not a table: cannot set a key below it".into(),
                ))
            }
        };
    }
    Ok(())
}

/// Applies one `key.path=value` to a TOML document.
pub fn apply_override(table: &mut toml::Table, spec: &str) -> Result<(), (String, String)> {
    let (path, raw) = spec
        .split_once('=')
        .ok_or_else(|| (spec.to_string(), "expected key.path=value".to_string()))?;
    set_path(table, path, parse_value(raw))
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
        let s: Scenario =
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
                fail(
                    clean_path(&e.path().to_string()),
                    first_line(&e.into_inner().to_string()),
                )
            })?;
        s.validate().map_err(|(k, r)| fail(k, r))?;
        Ok(s)
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    #[test]
    fn empty_file_is_the_paper_fig2_case() {
        let s = Scenario::parse("").unwrap();
        assert_eq!(s.controller.kind, ControllerKind::Nnvsc);
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
        assert_eq!(s.controller.gamma1, 200.0);
        assert_eq!(s.controller.kind, ControllerKind::Vsc);
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
