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
//! and column when TOML gives them) and the reason. See docs/guide/scenarios.md for the
//! full list of keys; [`Scenario::default`] is the paper's Fig. 2 case.

mod build;
pub mod json_schema;
mod overrides;
mod plants;
mod reference;
mod registry;
mod sections;

pub use build::Setup;
pub use overrides::{apply_override, line_col, parse_value, set_path};
pub use plants::{AnyPlant, PlantCfg, PlantVisit, DEFAULT_MODEL};
pub use reference::{
    read_csv, AnyReference, ComponentCfg, ReferenceCfg, ReferenceKind, Table, DEFAULT_AMPLITUDE_DEG,
};
pub use registry::{ControllerCfg, ControllerConfig, Visit, DEFAULT_KIND};
pub use sections::{
    EstimatorCfg, FaultCfg, OutputCfg, SafeCommandCfg, SimulationCfg, SurfaceCfg, UncertaintyCfg,
};

use ehservo_core::servo::Load;
use ehservo_sim::actuator::ActuatorConfig;
use ehservo_sim::sensor::SensorConfig;
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

/// A whole scenario. Every field has the paper's Fig. 2 value by default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Scenario {
    /// Name of the case (defaults to the file's stem).
    pub name: String,
    /// Free text.
    pub description: String,
    /// Horizon, step, mode.
    pub simulation: SimulationCfg,
    /// The plant: `model` (default `"third-order"`) and that model's keys.
    pub plant: PlantCfg,
    /// The third-order family's load torque: `Tl = amplitude·sin(wavenumber·θ)`,
    /// optional `[load.friction]` (the paper's `2·sin 4θ` N·m when absent).
    /// A cylinder's loads are in `[plant.load]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load: Option<Load>,
    /// True parameter variation: the paper's Δa_i = |ā_i|·(a_bias +
    /// a_random·r_i), Δb = b_reference·b̄·(b_bias + b_random·r_b) (the
    /// third-order family), and `[uncertainty.physical]` (any plant); r
    /// uniform on [−1, 1] held over `hold`.
    pub uncertainty: UncertaintyCfg,
    /// Desired trajectory: `kind` (default `"sine"`) and its keys.
    pub reference: ReferenceCfg,
    /// Switching surface.
    pub surface: SurfaceCfg,
    /// Controller: `kind` and that kind's parameters.
    pub controller: ControllerCfg,
    /// The valve between controller and plant (identity unless given).
    #[serde(skip_serializing_if = "ActuatorConfig::is_identity")]
    pub actuator: ActuatorConfig,
    /// What the controller measures (exact unless given).
    pub sensor: SensorConfig,
    /// What estimates the channels the sensors do not measure.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimator: Option<EstimatorCfg>,
    /// The sampled loop's response to a bad measurement.
    pub fault: FaultCfg,
    /// Output options.
    pub output: OutputCfg,
    /// The directory of the scenario file (set by [`Scenario::load`]): a
    /// relative `reference.file` is read from it. Not a key.
    #[serde(skip)]
    pub base_dir: Option<std::path::PathBuf>,
}

/// Largest number of steps a scenario may ask for: 2·10⁷ (200 s at 10 µs;
/// about 6 GB of trace.csv without `output.decimate`). A guard against a
/// mistyped step, not a physical limit.
pub const MAX_STEPS: u64 = 20_000_000;

impl Scenario {
    /// Reads, parses, overrides and validates a scenario file.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Scenario, ScenarioError> {
        let file = path.display().to_string();
        let text = crate::input::read_text(path).map_err(|reason| ScenarioError {
            file: file.clone(),
            key: String::new(),
            line_col: None,
            reason: format!("the scenario file {reason}"),
        })?;
        let dir = path.parent().map(Path::to_path_buf);
        let mut s = Self::parse_in(&text, &file, overrides, dir)?;
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

    /// Parses TOML text, applies `key.path=value` overrides, validates. A
    /// relative `reference.file` is read from the working directory.
    pub fn parse_with(
        text: &str,
        file: &str,
        overrides: &[String],
    ) -> Result<Scenario, ScenarioError> {
        Self::parse_in(text, file, overrides, None)
    }

    /// As [`Scenario::parse_with`], for a file in `base_dir`.
    pub fn parse_in(
        text: &str,
        file: &str,
        overrides: &[String],
        base_dir: Option<std::path::PathBuf>,
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
            if let Some(other) = other_format(text, file) {
                return err(String::new(), None, other);
            }
            let key = clean_path(&e.path().to_string());
            let inner = e.into_inner();
            if key == "controller" {
                return controller_error(text, file);
            }
            if key == "plant" {
                return plant_error(text, file);
            }
            let lc = inner.span().map(|s| line_col(text, s.start));
            err(key, lc, first_line(inner.message()))
        })?;
        // serde reads a fixed-size array from the first elements of a longer
        // one: compare every array of the file with what was read.
        if let (Ok(raw), Ok(typed)) = (
            toml::from_str::<toml::Table>(text),
            toml::Table::try_from(&scenario),
        ) {
            if let Some((key, reason)) = array_lengths(&raw, &typed, "") {
                let lc = locate(text, &key);
                return Err(err(key, lc, reason));
            }
        }
        let mut scenario = if overrides.is_empty() {
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
            let plant = table.get("plant").cloned();
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
                let key = clean_path(&e.path().to_string());
                match (key.as_str(), controller, plant) {
                    ("controller", Some(toml::Value::Table(t)), _) => {
                        controller_table_error(t, &after, None)
                    }
                    ("plant", _, Some(toml::Value::Table(t))) => plant_table_error(t, &after, None),
                    _ => ScenarioError {
                        file: after.clone(),
                        key,
                        line_col: None,
                        reason: first_line(&e.into_inner().to_string()),
                    },
                }
            })?
        };
        scenario.base_dir = base_dir;
        scenario.validate().map_err(|(key, reason)| {
            // A key set by --set is blamed on the flag, not on the file's
            // line; any other key, when flags were given, on the file as
            // changed by them, without a line (the flag may be the cause:
            // `--set simulation.step=0.003` breaks the file's horizon).
            let flagged = overrides.iter().any(|o| {
                let path = o.split_once('=').map_or(o.as_str(), |(p, _)| p).trim();
                path == key
                    || key.starts_with(&format!("{path}."))
                    || path.starts_with(&format!("{key}."))
            });
            if flagged {
                ScenarioError {
                    file: "--set".into(),
                    key,
                    line_col: None,
                    reason,
                }
            } else if overrides.is_empty() {
                let lc = locate(text, &key);
                err(key, lc, reason)
            } else {
                ScenarioError {
                    file: format!("{file} (after --set)"),
                    key,
                    line_col: None,
                    reason,
                }
            }
        })?;
        Ok(scenario)
    }

    /// An error in this scenario (no file position: it was already parsed).
    fn error(&self, key: String, reason: String) -> ScenarioError {
        ScenarioError {
            file: self.name.clone(),
            key,
            line_col: None,
            reason,
        }
    }

    /// The scenario's sections built and checked together: the one place
    /// that turns a scenario into what a simulation is made of.
    pub fn setup(&self) -> Result<Setup, ScenarioError> {
        Setup::new(self).map_err(|(key, reason)| self.error(key, reason))
    }

    /// Every check that serde's types cannot express. Returns the key path
    /// and the reason of the first failure.
    pub fn validate(&self) -> Result<(), (String, String)> {
        Setup::new(self).map(|_| ())
    }

    /// This scenario as TOML, with the plant family's defaults written
    /// out (the third-order family's `[load]` and the paper's
    /// `[uncertainty]` keys): what `ehservo check` prints, and a file that
    /// reads back as the same scenario.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(&self.resolved_table()).unwrap_or_default()
    }

    /// [`Scenario::table`] with the family's defaults filled in (see
    /// [`Scenario::to_toml`]).
    pub fn resolved_table(&self) -> toml::Table {
        let mut t = toml::Table::try_from(self).unwrap_or_default();
        if self.plant.paper_uncertainty() {
            if let Ok(u) = toml::Table::try_from(self.uncertainty_spec()) {
                t.insert("uncertainty".into(), toml::Value::Table(u));
            }
        }
        if self.plant.uses_load() {
            if let Ok(l) = toml::Table::try_from(self.load_model()) {
                t.insert("load".into(), toml::Value::Table(l));
            }
        }
        // The keys in the order a reader expects: serde's struct order.
        let order = [
            "name",
            "description",
            "simulation",
            "plant",
            "load",
            "uncertainty",
            "reference",
            "surface",
            "controller",
            "actuator",
            "sensor",
            "estimator",
            "fault",
            "output",
        ];
        let mut out = toml::Table::new();
        for k in order {
            if let Some(v) = t.remove(k) {
                out.insert(k.into(), v);
            }
        }
        out.extend(t);
        out
    }
}

impl Scenario {
    /// This scenario with some keys set to new values (each a dotted path
    /// and a TOML value), validated. Cheaper than re-parsing text: used by
    /// sweeps for every run.
    pub fn with_values(&self, values: &[(String, toml::Value)]) -> Result<Scenario, ScenarioError> {
        self.with_values_built(values).map(|(s, _)| s)
    }

    /// As [`Scenario::with_values`], also returning the [`Setup`] its
    /// validation built, so that a sweep runs it without building it again.
    pub fn with_values_built(
        &self,
        values: &[(String, toml::Value)],
    ) -> Result<(Scenario, Setup), ScenarioError> {
        self.with_values_built_on(self.table()?, values)
    }

    /// This scenario with `uncertainty.seed = seed`, and its set-up: what
    /// [`Scenario::with_values_built`] gives for that one value when this
    /// scenario survives its TOML round trip (a study checks that once),
    /// without the round trip (a Monte Carlo run over the seed alone).
    pub fn with_seed_built(&self, seed: u64) -> Result<(Scenario, Setup), ScenarioError> {
        let mut s = self.clone();
        s.uncertainty.seed = seed;
        let setup = s.setup()?; // s.name is self.name
        Ok((s, setup))
    }

    /// This scenario as a TOML table: what [`Scenario::with_values_built_on`]
    /// starts from.
    pub fn table(&self) -> Result<toml::Table, ScenarioError> {
        toml::Table::try_from(self).map_err(|e| self.error(String::new(), e.to_string()))
    }

    /// As [`Scenario::with_values_built`], from `table`, which must be this
    /// scenario's own [`Scenario::table`]: a sweep makes it once, not once
    /// for every run.
    pub fn with_values_built_on(
        &self,
        mut table: toml::Table,
        values: &[(String, toml::Value)],
    ) -> Result<(Scenario, Setup), ScenarioError> {
        let fail = |key: String, reason: String| self.error(key, reason);
        // A study may switch `controller.kind`. Between kinds with the same
        // keys (nnvsc, vsc, vsc-sat) the base's values carry over; to a kind
        // with other keys the table starts from that kind's defaults (the
        // study's own `controller.*` values then apply on top).
        let new_kind = values.iter().rev().find_map(|(k, v)| match v {
            toml::Value::String(kind) if k.trim() == "controller.kind" => Some(kind.as_str()),
            _ => None,
        });
        if let Some(fresh) = new_kind
            .filter(|k| *k != self.controller.kind())
            .and_then(ControllerCfg::default_of)
        {
            let keys =
                |c: &ControllerCfg| -> Vec<String> { c.to_table().keys().cloned().collect() };
            if keys(&fresh)
                != keys(&ControllerCfg::default_of(self.controller.kind()).unwrap_or_default())
            {
                table.insert("controller".into(), toml::Value::Table(fresh.to_table()));
            }
        }
        // Likewise `reference.kind`: another kind starts from no keys.
        let new_ref = values.iter().rev().find_map(|(k, v)| match v {
            toml::Value::String(kind) if k.trim() == "reference.kind" => Some(kind.as_str()),
            _ => None,
        });
        if new_ref.is_some_and(|k| k != self.reference.kind.name()) {
            table.insert("reference".into(), toml::Value::Table(toml::Table::new()));
        }
        for (k, v) in values {
            set_path(&mut table, k, v.clone()).map_err(|(k, r)| fail(k, r))?;
        }
        let controller = table.get("controller").cloned();
        let plant = table.get("plant").cloned();
        let mut s: Scenario =
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
                let key = clean_path(&e.path().to_string());
                match (key.as_str(), controller, plant) {
                    ("controller", Some(toml::Value::Table(t)), _) => {
                        controller_table_error(t, &self.name, None)
                    }
                    ("plant", _, Some(toml::Value::Table(t))) => {
                        plant_table_error(t, &self.name, None)
                    }
                    _ => fail(key, first_line(&e.into_inner().to_string())),
                }
            })?;
        s.base_dir.clone_from(&self.base_dir);
        let setup = Setup::new(&s).map_err(|(k, r)| fail(k, r))?;
        Ok((s, setup))
    }
}

/// The first array of `raw` whose length differs from the same key's in
/// `typed`: its key path and the reason.
fn array_lengths(raw: &toml::Table, typed: &toml::Table, prefix: &str) -> Option<(String, String)> {
    raw.iter().find_map(|(k, v)| {
        let key = format!("{prefix}{k}");
        match (v, typed.get(k)?) {
            (toml::Value::Array(a), toml::Value::Array(b)) if a.len() != b.len() => {
                Some((key, format!("expected {} values, got {}", b.len(), a.len())))
            }
            (toml::Value::Table(a), toml::Value::Table(b)) => {
                array_lengths(a, b, &format!("{key}."))
            }
            _ => None,
        }
    })
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

/// The precise error of a `[plant]` table that did not deserialise: the
/// key inside it, with its position in `text` when there is one.
fn plant_table_error(table: toml::Table, file: &str, text: Option<&str>) -> ScenarioError {
    let (k, reason) = match PlantCfg::from_toml(table) {
        Err(e) => e,
        Ok(_) => (String::new(), "invalid plant table".into()),
    };
    let key = if k.is_empty() {
        "plant".to_string()
    } else {
        format!("plant.{k}")
    };
    let line_col = text.and_then(|t| locate(t, &key).or_else(|| locate(t, "plant")));
    ScenarioError {
        file: file.to_string(),
        key,
        line_col,
        reason,
    }
}

/// What a TOML file that does not read as a scenario is instead, from its
/// top-level keys (which a scenario never has), and the command that takes
/// it: the reason `ehservo run` gives for a study, tune, league file or the
/// reproduction's manifest, instead of "unknown field `axis`".
pub fn other_format(text: &str, file: &str) -> Option<String> {
    let t: toml::Table = toml::from_str(text).ok()?;
    let has = |k: &str| t.contains_key(k);
    let (what, key, command) =
        if let Some(k) = ["axis", "monte_carlo", "base"].into_iter().find(|k| has(k)) {
            ("a study", k, "ehservo sweep FILE --out DIR")
        } else if let Some(k) = ["tuning", "margin", "scenario"]
            .into_iter()
            .find(|k| has(k))
            .or_else(|| {
                t.get("controller")
                    .filter(|c| c.is_array())
                    .map(|_| "controller")
            })
        {
            ("a league suite", k, "ehservo league FILE --out DIR")
        } else if let Some(k) = ["scenarios", "budget", "particles", "penalty", "param"]
            .into_iter()
            .find(|k| has(k))
            .or_else(|| {
                t.get("controller")
                    .filter(|c| c.is_str())
                    .map(|_| "controller")
            })
        {
            ("a tune file", k, "ehservo tune FILE --out DIR")
        } else if let Some(k) = ["reading", "case", "claim", "convergence"]
            .into_iter()
            .find(|k| has(k))
        {
            (
                "the reproduction's manifest",
                k,
                "ehservo reproduce --paper-dir ITS-FOLDER",
            )
        } else {
            return None;
        };
    let shown = match t.get(key) {
        Some(toml::Value::Array(a)) if a.iter().all(toml::Value::is_table) => format!("[[{key}]]"),
        Some(toml::Value::Table(_)) => format!("[{key}]"),
        _ => format!("`{key}`"),
    };
    Some(format!(
        "this is {what} (it has {shown}), not a scenario: run it with `{}`",
        command.replace("FILE", file)
    ))
}

fn plant_error(text: &str, file: &str) -> ScenarioError {
    let table = toml::from_str::<toml::Table>(text)
        .ok()
        .and_then(|mut t| t.remove("plant"));
    match table {
        Some(toml::Value::Table(t)) => plant_table_error(t, file, Some(text)),
        _ => ScenarioError {
            file: file.to_string(),
            key: "plant".into(),
            line_col: locate(text, "plant"),
            reason: "must be a table".into(),
        },
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
        assert_eq!(s.uncertainty_spec().a_bias, 1.0);
        assert_eq!(s.uncertainty_spec().b_bias, 0.5);
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
        assert_eq!(s.simulation.mode, ehservo_sim::simulation::Mode::Continuous);
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

    /// `reference.kind` by `--set` and by a study's values: another kind
    /// starts from no keys, so the sine's defaults do not leak into it.
    #[test]
    fn reference_kind_can_be_overridden() {
        let s = Scenario::parse_with(
            "",
            "t.toml",
            &[
                "reference.kind=step".into(),
                "reference.prefilter_tau=0.05".into(),
            ],
        )
        .unwrap();
        assert_eq!(s.reference.kind, ReferenceKind::Step);
        assert_eq!(s.reference.frequency_hz, None);
        let base = Scenario::parse("").unwrap();
        let (s, setup) = base
            .with_values_built(&[
                ("reference.kind".into(), toml::Value::String("ramp".into())),
                ("reference.slope_deg_per_s".into(), toml::Value::Float(1.0)),
                ("reference.prefilter_tau".into(), toml::Value::Float(0.1)),
            ])
            .unwrap();
        assert_eq!(s.reference.kind, ReferenceKind::Ramp);
        assert!(setup.reference.as_sine().is_none());
        assert_eq!(setup.period, 1.0);
        // The paper's scenario reads, writes and builds as before.
        assert_eq!(base, Scenario::default());
        assert!(base
            .to_toml()
            .contains("[reference]\namplitude_deg = 5.0\nfrequency_hz = 1.0\n"));
    }
}
