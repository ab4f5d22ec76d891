//! `[plant] model = "fmu"`: a plant from another tool, an FMI 2.0 or 3.0
//! co-simulation FMU (docs/guide/plant-fmu.md).
//!
//! The scenario names the FMU (`path`, relative to the scenario file) and
//! the mapping: the input that takes the command (`command`, V), the
//! outputs that are the position, velocity and acceleration, an optional
//! load input, and start values for named parameters. The axis follows
//! from the position output's unit in `modelDescription.xml`: `m` or `mm`
//! make a linear axis, `rad` or `deg` a rotary one; each output is scaled
//! to the axis's SI unit (m, rad) from its own unit, and a unit that is
//! not one of those is refused.
//!
//! **How a co-simulation FMU steps** ([`Plant::STEPS_ITSELF`]): the
//! simulator's held-command integration (`Held`) hands the plant the whole
//! sample period h with the actuator's output held, and the plant calls
//! `fmi3DoStep(t_k, h)` (FMI 2.0: `fmi2DoStep`) once; the FMU integrates the period with its own
//! solver and sub-steps. [`Plant::deriv`] is then never used, so the
//! adaptive solvers and the continuous mode, which need it, are refused.
//!
//! **One instance per plant clone**: a clone starts with no instance, and
//! [`Plant::initial_state`] (a run's first call) instantiates and
//! initialises one. A sweep's workers each run their own clone, so the
//! runs are the same on any number of threads.
//!
//! **A failing FMU** (a status other than OK or Warning, or
//! `terminateSimulation`) ends the run as a result
//! ([`Plant::failed`]: `DivergenceReason::PlantFailed`), with the FMU's
//! message on stderr.

mod binary;
mod binary2;
mod describe;

use binary::{Binary, FmuError, Instance};
use binary2::{Binary2, Instance2};
use describe::{Description, Variable};
use ehservo_core::control::Signal;
use ehservo_core::servo::{Load, NominalModel, ServoParams};
use ehservo_sim::axis::Axis;
use ehservo_sim::error::KeyError;
use ehservo_sim::plant::{Draw, Plant, PlantConfig, PlantContext, UncertaintySpec};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// An initialised co-simulation instance of either FMI version.
trait FmuInstance: Send + std::fmt::Debug {
    /// Sets Float64 (FMI 2.0: Real) variables.
    fn set(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), FmuError>;
    /// Gets Float64 (Real) variables into `out`.
    fn get(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), FmuError>;
    /// One communication step from `t` over `h`.
    fn step(&mut self, t: f64, h: f64) -> Result<(), FmuError>;
}

/// A loaded co-simulation binary of either FMI version.
#[derive(Debug)]
enum AnyBinary {
    V3(Arc<Binary>),
    V2(Arc<Binary2>),
}

/// Which of the FMU's interfaces the plant uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Interface {
    /// Co-simulation: `doStep` over each sample period.
    Cs,
    /// Model exchange: not read yet (refused with a reason).
    Me,
}

/// `[plant] model = "fmu"`'s keys.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct FmuCfg {
    /// The FMU file, relative to the scenario file's directory.
    pub path: String,
    /// `"cs"` or `"me"`; not given: co-simulation when the FMU has it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interface: Option<Interface>,
    /// The input variable that takes the command u (V).
    pub command: String,
    /// The output variable that is the position (m, mm, rad or deg).
    pub position: String,
    /// The output that is the velocity (its unit the position's per s);
    /// not given: 0 to the sensors, which then derive it (an estimator).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity: Option<String>,
    /// The output that is the acceleration (the position's unit per s²);
    /// not given: 0 to the sensors, as the velocity.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub acceleration: Option<String>,
    /// An input that takes an external load (N on a linear axis, N.m on
    /// a rotary one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load_force: Option<String>,
    /// Start values of Float64 parameters, by name.
    pub parameters: BTreeMap<String, f64>,
    /// `[plant.nominal]`: the third-order model the controller is designed
    /// on (the paper's physical parameters; default the paper's), with
    /// the scenario's `[load]` as its d(x) (none if not given).
    pub nominal: ServoParams,
    /// The axis, read from the FMU as the scenario is parsed
    /// ([`FmuCfg::resolve`]).
    #[serde(skip)]
    #[schemars(skip)]
    pub resolved_axis: Option<Axis>,
}

/// The axis and SI scale of a position unit.
fn position_unit(unit: &str) -> Option<(Axis, f64)> {
    match unit {
        "m" => Some((Axis::Linear, 1.0)),
        "mm" => Some((Axis::Linear, 1e-3)),
        "rad" => Some((Axis::Rotary, 1.0)),
        "deg" => Some((Axis::Rotary, std::f64::consts::PI / 180.0)),
        _ => None,
    }
}

/// The SI scale of `unit` as the `order`-th time derivative of a position
/// in `pos` (`"m/s"`, `"rad/s2"`, `"deg/s^2"`, …).
fn derivative_unit(unit: &str, pos: &str, order: u32) -> Option<f64> {
    let rest = unit.strip_prefix(pos)?.strip_prefix("/s")?;
    let ok = match order {
        1 => rest.is_empty(),
        _ => matches!(rest, "2" | "^2"),
    };
    ok.then(|| position_unit(pos).map(|(_, s)| s))?
}

/// A refusal of `plant.<key>`.
fn refuse(key: &str, reason: impl Into<String>) -> KeyError {
    KeyError::new(format!("plant.{key}"), reason.into())
}

/// The variable `name` of `key`, of type Float64 and one of `causalities`.
fn variable<'a>(
    d: &'a Description,
    key: &str,
    name: &str,
    causalities: &[&str],
) -> Result<&'a Variable, KeyError> {
    let v = d
        .find(name)
        .ok_or_else(|| refuse(key, format!("the FMU has no variable {name:?}")))?;
    if v.ty != "Float64" {
        return Err(refuse(
            key,
            format!("{name:?} is a {}, not a Float64", v.ty),
        ));
    }
    if !causalities.contains(&v.causality.as_str()) {
        return Err(refuse(
            key,
            format!(
                "{name:?} has causality {:?}, not {}",
                v.causality,
                causalities.join(" or ")
            ),
        ));
    }
    Ok(v)
}

impl FmuCfg {
    /// The FMU's file: `path` under the scenario's directory.
    fn file(&self, base_dir: Option<&Path>) -> Result<PathBuf, KeyError> {
        if self.path.is_empty() {
            return Err(refuse("path", "is required: the FMU file"));
        }
        Ok(match base_dir {
            Some(d) => d.join(&self.path),
            None => PathBuf::from(&self.path),
        })
    }

    /// Reads the axis from the FMU's position unit, as the scenario is
    /// parsed (every output's axis and unit follows from it).
    pub fn resolve(&mut self, base_dir: Option<&Path>) -> Result<(), KeyError> {
        let file = self.file(base_dir)?;
        let d = describe::peek(&file)
            .map_err(|r| refuse("path", format!("{}: {r}", file.display())))?;
        self.resolved_axis = Some(self.map(&d)?.axis);
        Ok(())
    }

    /// The mapping of the keys onto the FMU's variables, checked.
    fn map(&self, d: &Description) -> Result<Mapping, KeyError> {
        if !d.fmi_version.starts_with("3.") && !d.fmi_version.starts_with("2.") {
            return Err(refuse(
                "path",
                format!(
                    "the FMU is FMI {:?}: ehservo reads FMI 2.0 and 3.0",
                    d.fmi_version
                ),
            ));
        }
        let id = match (self.interface, &d.co_simulation) {
            (None | Some(Interface::Cs), Some(id)) => id.clone(),
            (Some(Interface::Cs), None) => {
                return Err(refuse(
                    "interface",
                    "the FMU has no co-simulation interface",
                ))
            }
            (Some(Interface::Me), _) | (None, None) => {
                return Err(refuse(
                    "interface",
                    "model exchange is not read yet: give an FMU with co-simulation",
                ))
            }
        };
        let pos = variable(d, "position", &self.position, &["output"])?;
        let pos_unit = pos.unit.clone().unwrap_or_default();
        let (axis, scale) = position_unit(&pos_unit).ok_or_else(|| {
            refuse(
                "position",
                format!(
                    "{:?} has unit {pos_unit:?}: the axis needs m or mm (linear) or rad or deg (rotary)",
                    pos.name
                ),
            )
        })?;
        let mut outputs = vec![(pos.value_reference, scale)];
        for (key, name, order) in [
            ("velocity", &self.velocity, 1),
            ("acceleration", &self.acceleration, 2),
        ] {
            let Some(name) = name else {
                outputs.push((u32::MAX, 0.0));
                continue;
            };
            let v = variable(d, key, name, &["output"])?;
            let unit = v.unit.clone().unwrap_or_default();
            let s = derivative_unit(&unit, &pos_unit, order).ok_or_else(|| {
                let want = if order == 1 { "/s" } else { "/s2" };
                refuse(
                    key,
                    format!("{name:?} has unit {unit:?}: expected {pos_unit}{want}"),
                )
            })?;
            outputs.push((v.value_reference, s));
        }
        let command = variable(d, "command", &self.command, &["input"])?.value_reference;
        let load = match &self.load_force {
            Some(n) => Some(variable(d, "load_force", n, &["input"])?.value_reference),
            None => None,
        };
        let mut starts = Vec::new();
        for (name, &value) in &self.parameters {
            let key = format!("parameters.{name}");
            let v = variable(d, &key, name, &["parameter"])?;
            if !value.is_finite() {
                return Err(refuse(&key, format!("must be finite (got {value})")));
            }
            starts.push((v.value_reference, value));
        }
        Ok(Mapping {
            model_identifier: id,
            axis,
            outputs,
            command,
            load,
            starts,
        })
    }
}

/// The keys as value references and scales.
#[derive(Debug, Clone)]
struct Mapping {
    model_identifier: String,
    axis: Axis,
    /// (value reference, SI scale) of x's three components; a scale of 0
    /// (and reference `u32::MAX`) for a component the FMU does not give.
    outputs: Vec<(u32, f64)>,
    command: u32,
    load: Option<u32>,
    starts: Vec<(u32, f64)>,
}

/// What every clone of a plant shares: the unpacked FMU and its binary.
#[derive(Debug)]
struct Shared {
    unpacked: describe::Unpacked,
    binary: AnyBinary,
    map: Mapping,
    name: String,
}

impl Shared {
    fn instance(&self) -> Result<Box<dyn FmuInstance>, FmuError> {
        let (token, res) = (&self.unpacked.description.token, self.unpacked.resources());
        let starts = &self.map.starts;
        Ok(match &self.binary {
            AnyBinary::V3(b) => Box::new(Instance::new(b, &self.name, token, &res, starts)?),
            AnyBinary::V2(b) => Box::new(Instance2::new(b, &self.name, token, &res, starts)?),
        })
    }
}

/// One clone's instance and whether it failed.
#[derive(Debug, Default)]
struct Slot {
    instance: Option<Box<dyn FmuInstance>>,
    failed: bool,
}

/// A plant that is an FMI 2.0 or 3.0 co-simulation FMU.
#[derive(Debug)]
pub struct FmuPlant {
    shared: Arc<Shared>,
    nominal: NominalModel,
    load: f64,
    slot: Mutex<Slot>,
}

impl Clone for FmuPlant {
    /// The same FMU with no instance yet: one instance per clone.
    fn clone(&self) -> Self {
        Self {
            shared: Arc::clone(&self.shared),
            nominal: self.nominal,
            load: self.load,
            slot: Mutex::new(Slot::default()),
        }
    }
}

impl FmuPlant {
    /// x in SI from the instance's outputs.
    fn read(&self, inst: &mut dyn FmuInstance) -> Result<[f64; 3], FmuError> {
        let mut x = [0.0; 3];
        for (i, &(vr, scale)) in self.shared.map.outputs.iter().enumerate() {
            if vr != u32::MAX {
                let mut v = [0.0];
                inst.get(&[vr], &mut v)?;
                x[i] = v[0] * scale;
            }
        }
        Ok(x)
    }

    /// Runs `f` on the instance; a failure marks the plant failed, says
    /// why on stderr and drops the instance.
    fn with<T>(
        &self,
        t: f64,
        f: impl FnOnce(&mut dyn FmuInstance) -> Result<T, FmuError>,
    ) -> Option<T> {
        let mut slot = self.slot.lock().unwrap_or_else(|p| p.into_inner());
        if slot.failed {
            return None;
        }
        let r = match slot.instance.as_deref_mut() {
            Some(inst) => f(inst),
            None => Err(FmuError {
                call: "the plant",
                status: "no instance",
                message: "the run did not initialise it".into(),
            }),
        };
        match r {
            Ok(v) => Some(v),
            Err(e) => {
                eprintln!("ehservo: the plant FMU failed at t = {t} s: {e}");
                slot.failed = true;
                slot.instance = None;
                None
            }
        }
    }
}

impl Plant for FmuPlant {
    type State = [f64; 3];
    type Variation = ();
    type Prepared = ();
    const STATES: &'static [Signal] = &[];
    const STEPS_ITSELF: bool = true;
    const EXTERNAL_LOAD: bool = true;

    fn axis(&self) -> Axis {
        self.shared.map.axis
    }

    fn initial_state(&self, _x0: [f64; 3], _v: &()) -> [f64; 3] {
        {
            let mut slot = self.slot.lock().unwrap_or_else(|p| p.into_inner());
            slot.instance = None;
            slot.failed = false;
            match self.shared.instance() {
                Ok(i) => slot.instance = Some(i),
                Err(e) => {
                    eprintln!("ehservo: the plant FMU failed to initialise: {e}");
                    slot.failed = true;
                }
            }
        }
        self.with(0.0, |inst| self.read(inst)).unwrap_or([0.0; 3])
    }

    fn measure(&self, _t: f64, s: &[f64; 3], _v: &()) -> [f64; 3] {
        *s
    }

    /// Never integrated ([`Plant::STEPS_ITSELF`]): zero.
    fn deriv(&self, _t: f64, _s: &[f64; 3], _u: f64, _v: &(), ds: &mut [f64; 3]) {
        *ds = [0.0; 3];
    }

    fn step_held(&self, t: f64, h: f64, u: f64, s: &mut [f64; 3]) {
        let map = &self.shared.map;
        if let Some(x) = self.with(t, |inst| {
            inst.set(&[map.command], &[u])?;
            if let Some(vr) = map.load {
                inst.set(&[vr], &[self.load])?;
            }
            inst.step(t, h)?;
            self.read(inst)
        }) {
            *s = x;
        }
    }

    fn failed(&self) -> bool {
        self.slot.lock().map(|s| s.failed).unwrap_or(true)
    }

    fn set_external_load(&mut self, load: f64) {
        self.load = load;
    }

    fn nominal(&self) -> &NominalModel {
        &self.nominal
    }

    fn variation(&self, _spec: &UncertaintySpec, _r: &Draw) {}

    /// Not known of an FMU (its equations are inside it): 0.
    fn lumped_uncertainty(
        &self,
        _s: &[f64; 3],
        _x: &[f64; 3],
        _u: f64,
        _ueq: f64,
        _b: f64,
        _v: &(),
    ) -> f64 {
        0.0
    }
}

impl PlantConfig for FmuCfg {
    const MODEL: &'static str = "fmu";
    const DOC: &'static str = "a plant from another tool: an FMI 2.0 or 3.0 co-simulation FMU";
    const PAPER_UNCERTAINTY: bool = false;
    const USES_LOAD: bool = true;
    type Plant = FmuPlant;

    fn axis(&self) -> Axis {
        self.resolved_axis.unwrap_or_default()
    }

    fn build(&self, ctx: &PlantContext) -> Result<FmuPlant, KeyError> {
        if ctx.uncertainty != UncertaintySpec::NONE {
            return Err(KeyError::new(
                "uncertainty",
                "an FMU plant takes no [uncertainty] yet: vary its plant.parameters",
            ));
        }
        self.nominal
            .validate()
            .map_err(|e| KeyError::param("plant.nominal", e))?;
        let file = self.file(ctx.base_dir.as_deref())?;
        let at = |r: String| refuse("path", format!("{}: {r}", file.display()));
        let unpacked = describe::unpack(&file).map_err(at)?;
        let map = self.map(&unpacked.description)?;
        let binary = unpacked.binary(&map.model_identifier).map_err(at)?;
        let binary = if unpacked.description.fmi_version.starts_with("2.") {
            AnyBinary::V2(Binary2::load(&binary).map_err(at)?)
        } else {
            AnyBinary::V3(Binary::load(&binary).map_err(at)?)
        };
        let shared = Shared {
            unpacked,
            binary,
            map,
            name: format!("ehservo-plant-{}", self.path),
        };
        // Instantiated and initialised once here, so that an FMU that
        // cannot be is refused before anything runs.
        shared
            .instance()
            .map_err(|e| refuse("path", format!("{}: {e}", file.display())))?;
        Ok(FmuPlant {
            shared: Arc::new(shared),
            nominal: NominalModel::new(self.nominal, ctx.load.unwrap_or_else(Load::none)),
            load: 0.0,
            slot: Mutex::new(Slot::default()),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_give_the_axis_and_the_si_scale() {
        assert_eq!(position_unit("mm"), Some((Axis::Linear, 1e-3)));
        assert_eq!(position_unit("rad"), Some((Axis::Rotary, 1.0)));
        // 1° = π/180 rad = 0.017453292519943295 rad.
        let (_, deg) = position_unit("deg").unwrap();
        assert!((deg - 0.017453292519943295).abs() < 1e-18);
        assert_eq!(position_unit("in"), None);
        assert_eq!(derivative_unit("mm/s", "mm", 1), Some(1e-3));
        assert_eq!(derivative_unit("rad/s2", "rad", 2), Some(1.0));
        assert_eq!(derivative_unit("m/s^2", "m", 2), Some(1.0));
        // The position's unit, not another axis's or order's.
        assert_eq!(derivative_unit("m/s", "mm", 1), None);
        assert_eq!(derivative_unit("rad/s", "rad", 2), None);
    }
}
