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
mod closed_loop;
pub mod json_schema;
mod overrides;
mod plants;
mod reference;
mod registry;
mod sections;
mod solver;
pub(crate) mod tagged;

pub use build::MAX_DRAWS;
pub use closed_loop::{Loop, LoopPlant, LoopVisit, Typed};
pub use ehservo_sim::error::{KeyError, Reason};
pub use overrides::{apply_override, line_col, parse_value, set_path};
pub use plants::{AnyPlant, PlantCfg, PlantVisit, DEFAULT_MODEL};
pub use reference::{
    read_csv, AnyReference, ComponentCfg, CsvError, ReferenceCfg, ReferenceKind, Table,
    DEFAULT_AMPLITUDE_DEG,
};
pub use registry::{ControllerCfg, ControllerConfig, Visit, DEFAULT_KIND};
pub use sections::{
    AtolCfg, EstimatorCfg, FaultCfg, OutputCfg, SafeCommandCfg, SimulationCfg, SurfaceCfg,
    UncertaintyCfg,
};
pub use solver::{DEFAULT_ATOL, DEFAULT_RTOL};

use ehservo_core::servo::Load;
use ehservo_sim::actuator::ActuatorConfig;
use ehservo_sim::sensor::SensorConfig;
use overrides::{clean_path, first_line, locate};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::Path;
use tagged::{section_error, table_error};

/// A bad scenario: which file, which key, where, and why. Every one is
/// bad input (exit code 2); [`Reason`] says which kind.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioError {
    /// The file (or `<--set>` / `<string>`).
    pub file: String,
    /// The key path, e.g. `plant.params.Jt` (empty when the file as a whole is at fault).
    pub key: String,
    /// 1-based line and column, when known.
    pub line_col: Option<(usize, usize)>,
    /// Why.
    pub reason: Reason,
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

impl ScenarioError {
    /// The key error `e`, in `file`, without a position.
    pub fn in_file(file: impl Into<String>, e: KeyError) -> Self {
        Self {
            file: file.into(),
            key: e.key,
            line_col: None,
            reason: e.reason,
        }
    }
}

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
    /// What reading the file with its `--set`s did that the user should
    /// know of, one line each (the keys a `--set controller.kind=K`
    /// dropped): the command line prints them. Not a key.
    #[serde(skip)]
    pub notes: Vec<String>,
}

/// Largest number of steps a scenario may ask for: 2·10⁷ (200 s at 10 µs;
/// about 6 GB of trace.csv without `output.decimate`). A guard against a
/// mistyped step, not a physical limit.
pub const MAX_STEPS: u64 = 20_000_000;

impl Scenario {
    /// Reads and parses a scenario file and applies the `key.path=value`
    /// overrides; returns it with the file's text. Not checked beyond
    /// the keys' types: [`Loop::load`] reads and builds.
    pub fn read(path: &Path, overrides: &[String]) -> Result<(Scenario, String), ScenarioError> {
        let file = path.display().to_string();
        let text = crate::input::read_text(path).map_err(|reason| ScenarioError {
            file: file.clone(),
            key: String::new(),
            line_col: None,
            reason: Reason::Other(format!("the scenario file {reason}")),
        })?;
        let dir = path.parent().map(Path::to_path_buf);
        let mut s = Self::parse_in(&text, &file, overrides, dir)?;
        if s.name.is_empty() {
            s.name = path
                .file_stem()
                .map(|x| x.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scenario".into());
        }
        Ok((s, text))
    }

    /// Parses TOML text of `file` in `base_dir` (a relative
    /// `reference.file` is read from it) and applies `key.path=value`
    /// overrides. Not checked beyond the keys' types: [`Loop::parse_in`]
    /// parses and builds.
    pub fn parse_in(
        text: &str,
        file: &str,
        overrides: &[String],
        base_dir: Option<std::path::PathBuf>,
    ) -> Result<Scenario, ScenarioError> {
        let err = |key: String, line_col, reason: Reason| ScenarioError {
            file: file.to_string(),
            key,
            line_col,
            reason,
        };
        // Pass 1, from the text: errors carry a key path and a position.
        let de = toml::Deserializer::parse(text).map_err(|e| {
            let lc = e.span().map(|s| line_col(text, s.start));
            err(String::new(), lc, Reason::Syntax(first_line(e.message())))
        })?;
        let scenario: Scenario = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = clean_path(&e.path().to_string());
            let inner = e.into_inner();
            if key == "controller" {
                return section_error::<ControllerCfg>(text, file);
            }
            if key == "plant" {
                return section_error::<PlantCfg>(text, file);
            }
            let lc = inner.span().map(|s| line_col(text, s.start));
            err(key, lc, Reason::Serde(first_line(inner.message())))
        })?;
        // serde reads a fixed-size array from the first elements of a longer
        // one: compare every array of the file with what was read.
        if let (Ok(raw), Ok(typed)) = (
            toml::from_str::<toml::Table>(text),
            toml::Table::try_from(&scenario),
        ) {
            if let Some(e) = array_lengths(&raw, &typed, "") {
                let lc = locate(text, &e.key);
                return Err(err(e.key, lc, e.reason));
            }
        }
        let mut scenario = if overrides.is_empty() {
            scenario
        } else {
            Self::overridden(text, file, overrides)?
        };
        scenario.base_dir = base_dir;
        #[cfg(feature = "fmu-import")]
        if let PlantCfg::Fmu(c) = &mut scenario.plant {
            // The axis is the FMU's (its position's unit): read it now, so
            // that every reader of the scenario knows it.
            c.resolve(scenario.base_dir.as_deref())
                .map_err(|e| ScenarioError {
                    file: file.to_string(),
                    line_col: locate(text, &e.key),
                    key: e.key,
                    reason: e.reason,
                })?;
        }
        Ok(scenario)
    }

    /// Pass 2 of [`Scenario::parse_in`]: the overrides applied to the
    /// document, which is read again.
    fn overridden(text: &str, file: &str, overrides: &[String]) -> Result<Scenario, ScenarioError> {
        let mut table: toml::Table = toml::from_str(text).map_err(|e| ScenarioError {
            file: file.to_string(),
            key: String::new(),
            line_col: None,
            reason: Reason::Syntax(first_line(e.message())),
        })?;
        let notes = switch_kinds(&mut table, overrides);
        for o in overrides {
            apply_override(&mut table, o).map_err(|e| ScenarioError::in_file("--set", e))?;
        }
        let after = format!("{file} (after --set)");
        let mut s = Self::from_table(table, &after)?;
        s.notes.extend(notes);
        Ok(s)
    }

    /// The scenario of a TOML table (named `file` in errors).
    fn from_table(table: toml::Table, file: &str) -> Result<Scenario, ScenarioError> {
        let controller = table.get("controller").cloned();
        let plant = table.get("plant").cloned();
        serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
            let key = clean_path(&e.path().to_string());
            match (key.as_str(), controller, plant) {
                ("controller", Some(toml::Value::Table(t)), _) => {
                    table_error::<ControllerCfg>(t, file, None)
                }
                ("plant", _, Some(toml::Value::Table(t))) => table_error::<PlantCfg>(t, file, None),
                _ => ScenarioError {
                    file: file.to_string(),
                    key,
                    line_col: None,
                    reason: Reason::Serde(first_line(&e.into_inner().to_string())),
                },
            }
        })
    }

    /// An error of this scenario's key (no file position: it was already
    /// parsed; its name stands for the file).
    pub(crate) fn error(&self, e: KeyError) -> ScenarioError {
        ScenarioError::in_file(self.name.clone(), e)
    }

    /// This scenario checked and built ([`Loop::new`]).
    pub fn validate(self) -> Result<Loop, ScenarioError> {
        Loop::new(self)
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
    /// This scenario as a TOML table: what [`Scenario::with_values_on`]
    /// starts from.
    pub fn table(&self) -> Result<toml::Table, ScenarioError> {
        toml::Table::try_from(self).map_err(|e| self.error(KeyError::new("", e.to_string())))
    }

    /// This scenario with some keys set to new values (each a dotted path
    /// and a TOML value), from `table`, which must be this scenario's own
    /// [`Scenario::table`]. Not built: [`Loop::with_values_on`] builds it.
    pub fn with_values_on(
        &self,
        mut table: toml::Table,
        values: &[(String, toml::Value)],
    ) -> Result<Scenario, ScenarioError> {
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
            set_path(&mut table, k, v.clone()).map_err(|e| self.error(e))?;
        }
        let mut s = Self::from_table(table, &self.name)?;
        s.base_dir.clone_from(&self.base_dir);
        Ok(s)
    }
}

/// `--set controller.kind=K` (the last one, if several) to another
/// registered kind than the file's: the keys of the file's `[controller]`
/// that kind `K` does not take are dropped from `table` (kept: the keys
/// both kinds take, such as the sliding-mode kinds' shared table), so that
/// switching kinds from the command line does not fail on the old kind's
/// keys. Returns the line that names what was dropped, if anything. Other
/// `--set controller.*` values apply afterwards, and a key of the old kind
/// set that way is still refused. An unknown `K` is left to the loader's
/// error, which names the registered kinds. `--set reference.kind=K` is
/// alike for `[reference]` (its keys in either unit kept where K uses
/// them).
fn switch_kinds(table: &mut toml::Table, overrides: &[String]) -> Vec<String> {
    let controller = switch_kind(table, overrides, "controller", DEFAULT_KIND, |kind| {
        let keys = ControllerCfg::keys_of(kind)?;
        Some(Box::new(move |k: &str| keys.iter().any(|x| x == k)))
    });
    let reference = switch_kind(table, overrides, "reference", "sine", |kind| {
        let kind: reference::ReferenceKind =
            toml::Value::String(kind.to_string()).try_into().ok()?;
        Some(Box::new(move |k: &str| kind.takes(k)))
    });
    controller.into_iter().chain(reference).collect()
}

/// Which keys a kind of a `[section]` takes (`None`: no such kind).
type Takes = Box<dyn Fn(&str) -> bool>;

/// [`switch_kinds`] for one section.
fn switch_kind(
    table: &mut toml::Table,
    overrides: &[String],
    section: &str,
    default: &str,
    takes: impl Fn(&str) -> Option<Takes>,
) -> Option<String> {
    let flag = format!("{section}.kind");
    let new_kind = overrides.iter().rev().find_map(|o| {
        let (path, raw) = o.split_once('=')?;
        match parse_value(raw) {
            toml::Value::String(k) if path.trim() == flag => Some(k),
            _ => None,
        }
    })?;
    let takes = takes(&new_kind)?;
    let Some(toml::Value::Table(sec)) = table.get_mut(section) else {
        return None;
    };
    let old_kind = match sec.get("kind") {
        None => default.to_string(),
        Some(toml::Value::String(k)) => k.clone(),
        Some(_) => return None,
    };
    if old_kind == new_kind {
        return None;
    }
    let dropped: Vec<String> = sec.keys().filter(|k| !takes(k)).cloned().collect();
    if dropped.is_empty() {
        return None;
    }
    for k in &dropped {
        sec.remove(k);
    }
    Some(format!(
        "--set {flag}={new_kind}: dropped the file's {old_kind} key{} {} (kind {new_kind} does not take {})",
        if dropped.len() == 1 { "" } else { "s" },
        dropped.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", "),
        if dropped.len() == 1 { "it" } else { "them" },
    ))
}

/// The key error `e` of a scenario read from `text` of `file` with
/// `overrides`, placed: a key set by `--set` is blamed on the flag, not on
/// the file's line; any other key, when flags were given, on the file as
/// changed by them, without a line (the flag may be the cause:
/// `--set simulation.step=0.003` breaks the file's horizon).
pub(crate) fn placed(e: KeyError, text: &str, file: &str, overrides: &[String]) -> ScenarioError {
    let key = &e.key;
    let flagged = overrides.iter().any(|o| {
        let path = o.split_once('=').map_or(o.as_str(), |(p, _)| p).trim();
        path == key || key.starts_with(&format!("{path}.")) || path.starts_with(&format!("{key}."))
    });
    if flagged {
        ScenarioError::in_file("--set", e)
    } else if overrides.is_empty() {
        let lc = locate(text, key);
        ScenarioError {
            file: file.to_string(),
            key: e.key,
            line_col: lc,
            reason: e.reason,
        }
    } else {
        ScenarioError::in_file(format!("{file} (after --set)"), e)
    }
}

/// The first array of `raw` whose length differs from the same key's in
/// `typed`: its key path and the reason.
fn array_lengths(raw: &toml::Table, typed: &toml::Table, prefix: &str) -> Option<KeyError> {
    raw.iter().find_map(|(k, v)| {
        let key = format!("{prefix}{k}");
        match (v, typed.get(k)?) {
            (toml::Value::Array(a), toml::Value::Array(b)) if a.len() != b.len() => Some(
                KeyError::new(key, format!("expected {} values, got {}", b.len(), a.len())),
            ),
            (toml::Value::Table(a), toml::Value::Table(b)) => {
                array_lengths(a, b, &format!("{key}."))
            }
            _ => None,
        }
    })
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    /// `--set controller.kind=K` from a file of another kind: the file's
    /// keys that K does not take are dropped and named in one note, the
    /// keys both take kept; a key of the old kind set along with the
    /// switch is still refused, and an unknown K named as before.
    #[test]
    fn set_controller_kind_drops_the_old_kinds_keys() {
        let set = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let pid =
            "[controller]\nkind = \"pid\"\nkp = 26.0\nki = 0.6\nkd = 0.0\nfeedforward = false\n";
        let s = Scenario::parse_in(pid, "f.toml", &set(&["controller.kind=arc"]), None).unwrap();
        assert_eq!(s.controller.kind(), "arc");
        let arc = ControllerCfg::keys_of("arc").unwrap();
        let gone: Vec<&str> = ["kp", "ki", "kd", "feedforward"]
            .into_iter()
            .filter(|k| !arc.iter().any(|a| a == k))
            .collect();
        assert!(!gone.is_empty());
        assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
        let note = &s.notes[0];
        assert!(
            note.starts_with("--set controller.kind=arc: dropped the file's pid keys"),
            "{note}"
        );
        for k in ["kp", "ki", "kd", "feedforward"] {
            assert_eq!(
                note.contains(&format!("`{k}`")),
                gone.contains(&k),
                "{k}: {note}"
            );
        }
        // Without the switch nothing is dropped.
        let s = Scenario::parse_in(pid, "f.toml", &set(&["controller.kp=1"]), None).unwrap();
        assert!(s.notes.is_empty());
        // An old kind's key set with the switch is the user's: refused.
        let e = Scenario::parse_in(
            pid,
            "f.toml",
            &set(&["controller.kind=arc", "controller.kp=1"]),
            None,
        )
        .unwrap_err();
        assert_eq!(e.key, "controller.kp");
        // The sliding-mode kinds share their table: a value carries over.
        let nn = "[controller]\ngamma1 = 200.0\n";
        let s = Scenario::parse_in(nn, "f.toml", &set(&["controller.kind=vsc"]), None).unwrap();
        assert_eq!(s.controller.kind(), "vsc");
        assert!(s.notes.is_empty());
        assert_eq!(s.controller.to_table()["gamma1"].as_float(), Some(200.0));
        // An unknown kind: the registry's error, naming the kinds.
        let e =
            Scenario::parse_in(pid, "f.toml", &set(&["controller.kind=lqr"]), None).unwrap_err();
        assert_eq!(e.key, "controller.kind");
        assert!(e.reason.to_string().contains("nnvsc"), "{e}");
        // Every kind's keys include its defaults' (the schema is complete).
        for &k in ControllerCfg::KINDS {
            let keys = ControllerCfg::keys_of(k).unwrap();
            for d in ControllerCfg::default_of(k).unwrap().to_table().keys() {
                assert!(keys.contains(d), "{k}: {d}");
            }
        }
    }

    #[test]
    fn empty_file_is_the_paper_fig2_case() {
        let lp = Loop::parse("").unwrap();
        let s = lp.scenario();
        assert_eq!(s.controller.kind(), "nnvsc");
        assert_eq!(s.simulation.step, 0.01);
        assert_eq!(lp.stages().uncertainty.a_bias, 1.0);
        assert_eq!(lp.stages().uncertainty.b_bias, 0.5);
        assert_eq!(lp.design().surface.p(), [90.0, 2600.0, 24000.0]);
        assert_eq!(lp.sim().steps, 1000);
    }

    #[test]
    fn overrides_apply_and_are_typed() {
        let lp = Loop::parse_with(
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
        let s = lp.scenario();
        let c = s
            .controller
            .get::<ehservo_core::control::sliding::VscConfig>();
        assert_eq!(c.map(|c| c.0.gamma1), Some(200.0));
        assert_eq!(s.controller.kind(), "vsc");
        assert_eq!(s.simulation.mode, ehservo_sim::simulation::Mode::Continuous);
        assert_eq!(lp.sim().steps, 10_000);
        // (s + 10)(s + 20)(s + 30) = s³ + 60 s² + 1100 s + 6000.
        assert_eq!(lp.design().surface.p(), [60.0, 1100.0, 6000.0]);
    }

    fn err(text: &str) -> ScenarioError {
        Loop::parse_with(text, "bad.toml", &[]).unwrap_err()
    }

    #[test]
    fn errors_name_the_key_and_the_reason() {
        let e = err("[plant.params]\nJt = -1.0\n");
        assert_eq!(e.key, "plant.params.Jt");
        assert_eq!(e.line_col, Some((2, 6)));
        assert!(e.reason.to_string().contains("> 0"), "{e}");

        let e = err("[controller]\ngama1 = 3\n");
        assert_eq!(e.key, "controller.gama1");
        assert!(e.reason.to_string().contains("unknown field"), "{e}");
        assert_eq!(e.line_col.map(|l| l.0), Some(2));

        let e = err("[simulation]\nstep = \"fast\"\n");
        assert_eq!(e.key, "simulation.step");
        assert!(e.reason.to_string().contains("invalid type"), "{e}");

        let e = err("[simulation]\nhorizon = 10.005\n");
        assert_eq!(e.key, "simulation.horizon");
        assert!(e.reason.to_string().contains("whole number"), "{e}");

        let e = err("[surface]\npoles = [-20, 30, -40]\n");
        assert_eq!(e.key, "surface.poles");

        let e = err("[plant]\nmodel = \"fourth-order\"\n");
        assert_eq!(e.key, "plant.model");

        let e = err("[simulation\nstep = 1\n");
        assert!(matches!(e.reason, Reason::Syntax(_)), "{e}");
        assert!(e.to_string().contains("syntax"), "{e}");
        assert_eq!(e.line_col.map(|l| l.0), Some(1));

        let e = Loop::parse_with("", "t.toml", &["controller.nope=1".into()]).unwrap_err();
        assert_eq!(e.key, "controller.nope");
    }

    /// `reference.kind` by `--set` and by a study's values: another kind
    /// starts from no keys, so the sine's defaults do not leak into it.
    #[test]
    fn reference_kind_can_be_overridden() {
        let lp = Loop::parse_with(
            "",
            "t.toml",
            &[
                "reference.kind=step".into(),
                "reference.prefilter_tau=0.05".into(),
            ],
        )
        .unwrap();
        assert_eq!(lp.scenario().reference.kind, ReferenceKind::Step);
        assert_eq!(lp.scenario().reference.frequency_hz, None);
        let base_loop = Loop::parse("").unwrap();
        let lp = base_loop
            .with_values(&[
                ("reference.kind".into(), toml::Value::String("ramp".into())),
                ("reference.slope_deg_per_s".into(), toml::Value::Float(1.0)),
                ("reference.prefilter_tau".into(), toml::Value::Float(0.1)),
            ])
            .unwrap();
        assert_eq!(lp.scenario().reference.kind, ReferenceKind::Ramp);
        assert!(lp.reference().as_sine().is_none());
        assert_eq!(lp.period(), 1.0);
        let base = base_loop.scenario();
        // The paper's scenario reads, writes and builds as before.
        assert_eq!(*base, Scenario::default());
        assert!(base
            .to_toml()
            .contains("[reference]\namplitude_deg = 5.0\nfrequency_hz = 1.0\n"));
    }
}
