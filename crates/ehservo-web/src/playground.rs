//! What the page asks of the simulator, as plain Rust (the wasm-bindgen
//! wrappers in `lib.rs` only pass JSON through): the catalogue of scenarios
//! and controller kinds, the checks of the page's fields, a run, and the
//! scenario file that `ehservo run` accepts.
//!
//! A set-up is a base scenario (one of [`SCENARIOS`], by id) and a list of
//! overrides, each a dotted key and the text the user typed — the CLI's
//! `--set key=value`, read by the same [`parse_value`] and applied by the
//! same [`Scenario::with_values_built`].

use ehservo_scenario::core::control::{Config, Controller, Signals, Tunable};
use ehservo_scenario::metrics::Metrics;
use ehservo_scenario::run::{run_metrics, Decimate};
use ehservo_scenario::scenario::{
    parse_value, set_path, ControllerCfg, ControllerConfig, KeyError, Loop, Scenario,
    ScenarioError, Visit,
};
use ehservo_scenario::simulation::Sample;
use serde::Serialize;

/// A scenario file built into the page.
#[derive(Debug, Clone, Copy)]
pub struct BaseScenario {
    /// `paper/fig2`, `realistic/base`: its folder and stem.
    pub id: &'static str,
    /// Its path in the repository.
    pub path: &'static str,
    /// Its TOML text.
    pub text: &'static str,
}

/// Every scenario of `scenarios/paper` (but the manifest) and
/// `scenarios/realistic` (but the study files), embedded at build time (see `build.rs`).
pub static SCENARIOS: &[BaseScenario] = include!(concat!(env!("OUT_DIR"), "/scenarios.rs"));

/// The uncertainty keys the page offers, with their slider ranges. (A
/// controller's keys come from its kind's [`Config::TUNABLE`].)
pub const UNCERTAINTY: &[Tunable] = &[
    Tunable::linear("a_bias", 0.0, 3.0),
    Tunable::linear("a_random", 0.0, 2.0),
    Tunable::linear("b_bias", -1.0, 1.5),
    Tunable::linear("b_random", 0.0, 1.0),
];

/// The most samples a run sends back for plotting (every n-th sample
/// beyond; the metrics always see every sample).
pub const MAX_POINTS: u64 = 4000;

/// A parameter the page shows as a slider and a field.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Param {
    /// Its dotted key, as `--set` takes it (`controller.gamma1`).
    pub key: String,
    /// Its name inside its table (`gamma1`).
    pub name: &'static str,
    /// The low end of its range.
    pub low: f64,
    /// The high end.
    pub high: f64,
    /// Whether the slider is logarithmic.
    pub log: bool,
}

impl Param {
    fn of(table: &str, t: &Tunable) -> Self {
        Self {
            key: format!("{table}.{}", t.key),
            name: t.key,
            low: t.low,
            high: t.high,
            log: t.log,
        }
    }

    /// The range widened to hold the scenario's own value `base` (a
    /// declared range is where the slider explores; a scenario's value
    /// outside it, such as a cylinder's P gain of 11 162 V/m beyond the
    /// paper-scale 10⁴, stays valid). A log range keeps a positive low end.
    fn including(mut self, base: Option<f64>) -> Self {
        if let Some(b) = base.filter(|b| b.is_finite() && (!self.log || *b > 0.0)) {
            self.low = self.low.min(b);
            self.high = self.high.max(b);
        }
        self
    }
}

/// A signal of a controller's parts that traces write.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SignalInfo {
    /// Its key (`sigma`).
    pub key: &'static str,
    /// Its unit.
    pub unit: &'static str,
    /// What it is.
    pub doc: &'static str,
}

/// A controller kind as the page sees it.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct KindInfo {
    /// `controller.kind`.
    pub kind: &'static str,
    /// Its declared tunable parameters.
    pub params: Vec<Param>,
    /// The signals of its parts.
    pub signals: Vec<SignalInfo>,
}

struct Describe;

impl Visit for Describe {
    type Out = KindInfo;
    fn visit<K: ControllerConfig>(self, _cfg: &K) -> KindInfo {
        type Parts<K> = <<K as Config>::Controller as Controller>::Parts;
        KindInfo {
            kind: K::KIND,
            params: K::TUNABLE
                .iter()
                .map(|t| Param::of("controller", t))
                .collect(),
            signals: <Parts<K> as Signals>::SIGNALS
                .iter()
                .filter(|s| !s.column.is_empty())
                .map(|s| SignalInfo {
                    key: s.key,
                    unit: s.unit,
                    doc: s.doc,
                })
                .collect(),
        }
    }
}

/// A base scenario as the page lists it.
#[derive(Debug, Clone, Serialize)]
pub struct ScenarioInfo {
    /// Its id.
    pub id: &'static str,
    /// Its path in the repository.
    pub path: &'static str,
    /// Its `name`.
    pub name: String,
    /// Its `description`.
    pub description: String,
    /// Its controller kind.
    pub kind: &'static str,
    /// Its text.
    pub toml: &'static str,
}

/// Everything the page builds its controls from.
#[derive(Debug, Clone, Serialize)]
pub struct Catalog {
    /// The base scenarios.
    pub scenarios: Vec<ScenarioInfo>,
    /// Every registered controller kind.
    pub kinds: Vec<KindInfo>,
    /// The uncertainty parameters.
    pub uncertainty: Vec<Param>,
}

/// The catalogue.
pub fn catalog() -> Catalog {
    Catalog {
        scenarios: SCENARIOS
            .iter()
            .map(|b| {
                let lp = base(b);
                let s = lp.scenario();
                ScenarioInfo {
                    id: b.id,
                    path: b.path,
                    name: s.name.clone(),
                    description: s.description.clone(),
                    kind: s.controller.kind(),
                    toml: b.text,
                }
            })
            .collect(),
        kinds: kinds(),
        uncertainty: UNCERTAINTY
            .iter()
            .map(|t| Param::of("uncertainty", t))
            .collect(),
    }
}

/// Every registered kind, described.
pub fn kinds() -> Vec<KindInfo> {
    ControllerCfg::KINDS
        .iter()
        .filter_map(|k| ControllerCfg::default_of(k))
        .map(|c| c.visit(Describe))
        .collect()
}

fn base(b: &BaseScenario) -> Loop {
    let mut s = Scenario::parse_in(b.text, b.path, &[], None)
        .unwrap_or_else(|e| panic!("the embedded {} is valid: {e}", b.path));
    if s.name.is_empty() {
        s.name = b.id.rsplit('/').next().unwrap_or(b.id).to_string();
    }
    Loop::new(s).unwrap_or_else(|e| panic!("the embedded {} is valid: {e}", b.path))
}

/// A base scenario by id.
pub fn find(id: &str) -> Option<&'static BaseScenario> {
    SCENARIOS.iter().find(|b| b.id == id)
}

/// A complaint about one key of a set-up.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct FieldError {
    /// The dotted key (empty: the set-up as a whole).
    pub key: String,
    /// Why.
    pub reason: String,
}

impl FieldError {
    fn new(key: impl Into<String>, reason: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            reason: reason.into(),
        }
    }
}

impl From<ScenarioError> for FieldError {
    fn from(e: ScenarioError) -> Self {
        Self::new(e.key, e.reason.to_string())
    }
}

impl From<KeyError> for FieldError {
    fn from(e: KeyError) -> Self {
        Self::new(e.key, e.reason.to_string())
    }
}

/// The declared range of `key` under controller kind `kind`, if any.
fn range_of(kind: &str, key: &str) -> Option<Param> {
    let declared = kinds()
        .into_iter()
        .find(|k| k.kind == kind)
        .map(|k| k.params)
        .unwrap_or_default();
    declared
        .into_iter()
        .chain(UNCERTAINTY.iter().map(|t| Param::of("uncertainty", t)))
        .find(|p| p.key == key)
}

/// The scenario `id` with `overrides` (key, text as typed) applied and
/// validated, with its built set-up; or every complaint, each naming its
/// key: an empty field, text that is not a number, a value outside the
/// key's declared range, and whatever the scenario's own validator says of
/// the key on its own — then, if each key is fine alone, what it says of
/// them together.
pub fn resolve(id: &str, overrides: &[(String, String)]) -> Result<Loop, Vec<FieldError>> {
    let b = find(id).ok_or_else(|| {
        vec![FieldError::new(
            "scenario",
            format!(
                "unknown scenario `{id}` (known: {})",
                SCENARIOS
                    .iter()
                    .map(|b| b.id)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )]
    })?;
    let base = base(b);
    // The kind first: every other key is read under it.
    let kind = overrides
        .iter()
        .rev()
        .find(|(k, _)| k.trim() == "controller.kind")
        .map(|(_, v)| v.trim().to_string())
        .unwrap_or_else(|| base.controller().kind().to_string());
    let kind_value = (
        "controller.kind".to_string(),
        toml::Value::String(kind.clone()),
    );
    let under_kind = base
        .with_values(std::slice::from_ref(&kind_value))
        .map_err(|e| vec![e.into()])?
        .scenario()
        .resolved_table();
    let mut errors = Vec::new();
    let mut values = vec![kind_value.clone()];
    for (key, raw) in overrides {
        let key = key.trim();
        if key == "controller.kind" {
            continue;
        }
        let raw = raw.trim();
        if raw.is_empty() {
            errors.push(FieldError::new(key, "is empty: enter a number"));
            continue;
        }
        let value = parse_value(raw);
        let number = match value {
            toml::Value::Float(v) => Some(v),
            toml::Value::Integer(v) => Some(v as f64),
            _ => None,
        };
        if let Some(p) = range_of(&kind, key).map(|p| p.including(value_at(&under_kind, key))) {
            match number {
                None => {
                    errors.push(FieldError::new(key, format!("`{raw}` is not a number")));
                    continue;
                }
                Some(v) if !(p.low..=p.high).contains(&v) => {
                    errors.push(FieldError::new(
                        key,
                        format!(
                            "{v} is outside the range declared for `{}`: [{}, {}]",
                            p.name, p.low, p.high
                        ),
                    ));
                    continue;
                }
                Some(_) => {}
            }
        }
        let one = [kind_value.clone(), (key.to_string(), value.clone())];
        if let Err(e) = base.with_values(&one) {
            errors.push(e.into());
            continue;
        }
        values.push((key.to_string(), value));
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    base.with_values(&values).map_err(|e| vec![e.into()])
}

/// One plotted series of a controller signal.
#[derive(Debug, Clone, Serialize)]
pub struct SignalTrace {
    /// Its description.
    #[serde(flatten)]
    pub info: SignalInfo,
    /// Its values at the kept samples.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub values: Vec<f64>,
}

/// The kept samples of a run, in plotting units.
#[derive(Debug, Clone, Serialize, Default)]
pub struct Trace {
    /// t (s).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub t: Vec<f64>,
    /// θd (deg), or yd (mm) on a linear axis.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub theta_d: Vec<f64>,
    /// θ (deg), or y (mm).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub theta: Vec<f64>,
    /// e = θd − θ (deg or mm).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub e: Vec<f64>,
    /// u (V).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub u: Vec<f64>,
    /// The controller's signals.
    pub signals: Vec<SignalTrace>,
}

/// A finished run.
#[derive(Debug, Clone, Serialize)]
pub struct RunOut {
    /// The scenario's name.
    pub name: String,
    /// The controller kind run.
    pub kind: &'static str,
    /// Steps in the horizon.
    pub steps: u64,
    /// Every n-th sample is in the trace.
    pub every: u64,
    /// The display unit of the plant's axis: `"deg"` or `"mm"` (the
    /// trace's positions and the metrics' errors are in it).
    pub unit: &'static str,
    /// SPEC §9 metrics, as in `summary.json`.
    pub metrics: Metrics,
    /// Why and when the run ended early, if it did.
    pub divergence: Option<String>,
    /// The trace.
    pub trace: Trace,
}

/// Runs the set-up.
pub fn simulate(id: &str, overrides: &[(String, String)]) -> Result<RunOut, Vec<FieldError>> {
    let lp = resolve(id, overrides)?;
    let scenario = lp.scenario();
    let steps = lp.sim().steps;
    let axis = lp.axis();
    let every = steps.div_ceil(MAX_POINTS).max(1);
    let mut trace = Trace::default();
    let mut keys: Vec<usize> = Vec::new();
    let mut dec = Decimate::every(every);
    let mut push = |trace: &mut Trace, smp: &Sample| {
        if trace.t.is_empty() {
            keys = (0..smp.signals.len())
                .filter(|&i| !smp.signals[i].column.is_empty())
                .collect();
            trace.signals = keys
                .iter()
                .map(|&i| SignalTrace {
                    info: SignalInfo {
                        key: smp.signals[i].key,
                        unit: smp.signals[i].unit,
                        doc: smp.signals[i].doc,
                    },
                    values: Vec::new(),
                })
                .collect();
        }
        trace.t.push(smp.t);
        trace.theta_d.push(axis.display(smp.z[0]));
        trace.theta.push(axis.display(smp.x[0]));
        trace.e.push(axis.display(smp.e));
        trace.u.push(smp.u);
        for (s, &i) in trace.signals.iter_mut().zip(&keys) {
            s.values.push(smp.values[i]);
        }
    };
    let (outcome, metrics) = run_metrics(&lp, &mut |smp: &Sample| {
        if let Some(smp) = dec.offer(smp) {
            push(&mut trace, smp);
        }
    });
    if let Some(l) = dec.finish() {
        push(&mut trace, &l);
    }
    Ok(RunOut {
        name: scenario.name.clone(),
        kind: scenario.controller.kind(),
        steps,
        every,
        unit: axis.unit(),
        metrics,
        divergence: outcome
            .diverged
            .map(|d| format!("unbounded at t = {:.4} s: {}", d.t, d.reason.describe())),
        trace,
    })
}

/// The set-up as a scenario file that `ehservo run` accepts and runs to
/// the same result: the base file's keys with the overrides set in them
/// (by the same `set_path` as `--set`), a header saying where it came
/// from. Checked: the file read back is the scenario the page ran; if the
/// short form were ever not (it always should be), the file is the
/// scenario with every key written out instead.
pub fn scenario_toml(id: &str, overrides: &[(String, String)]) -> Result<String, Vec<FieldError>> {
    let lp = resolve(id, overrides)?;
    let scenario = lp.scenario();
    let b = find(id).expect("resolve found it");
    let mut table: toml::Table = toml::from_str(b.text).expect("the embedded file parses");
    if !table.contains_key("name") {
        table.insert("name".into(), toml::Value::String(scenario.name.clone()));
    }
    let base_kind = base(b).controller().kind();
    let mut flags = Vec::new();
    let keys = |kind: &str| -> Vec<String> {
        ControllerCfg::default_of(kind)
            .map(|c| c.to_table().keys().cloned().collect())
            .unwrap_or_default()
    };
    if scenario.controller.kind() != base_kind {
        flags.push(format!("controller.kind={}", scenario.controller.kind()));
    }
    if scenario.controller.kind() != base_kind
        && keys(base_kind) == keys(scenario.controller.kind())
    {
        // nnvsc, vsc and vsc-sat share one table: the base's values carry over.
        set_path(
            &mut table,
            "controller.kind",
            toml::Value::String(scenario.controller.kind().into()),
        )
        .map_err(|e| vec![e.into()])?;
    } else if scenario.controller.kind() != base_kind {
        // Another kind starts from its own defaults, as in a study.
        let mut c = toml::Table::new();
        c.insert(
            "kind".into(),
            toml::Value::String(scenario.controller.kind().into()),
        );
        table.insert("controller".into(), toml::Value::Table(c));
    }
    for (k, raw) in overrides {
        let k = k.trim();
        if k == "controller.kind" {
            continue;
        }
        set_path(&mut table, k, parse_value(raw)).map_err(|e| vec![e.into()])?;
        flags.push(format!("{k}={}", raw.trim()));
    }
    let body = toml::to_string_pretty(&table).unwrap_or_default();
    let same = Loop::parse_with(&body, b.path, &[]).is_ok_and(|s| s.scenario() == scenario);
    let body = if same { body } else { scenario.to_toml() };
    let mut head = format!(
        "# {} from the ehservo playground: {}",
        scenario.name, b.path
    );
    if flags.is_empty() {
        head.push_str(" as it is\n");
    } else {
        head.push_str(" with\n");
        for f in &flags {
            head.push_str(&format!("#   --set {f}\n"));
        }
    }
    head.push_str("# Run it with: ehservo run <this file>\n\n");
    Ok(head + &body)
}

/// The values the base scenario `id` gives the page's parameters under
/// controller kind `kind` (its own or another's defaults): key → value,
/// `None` when the key is unset (a PID gain left to its pole-placement
/// design).
pub fn base_values(
    id: &str,
    kind: &str,
) -> Result<std::collections::BTreeMap<String, Option<f64>>, Vec<FieldError>> {
    let lp = resolve(id, &[("controller.kind".into(), kind.into())])?;
    let table = lp.scenario().resolved_table();
    let info = kinds()
        .into_iter()
        .find(|k| k.kind == kind)
        .map(|k| k.params)
        .unwrap_or_default();
    let params = info
        .into_iter()
        .chain(UNCERTAINTY.iter().map(|t| Param::of("uncertainty", t)));
    Ok(params
        .map(|p| {
            let value = value_at(&table, &p.key);
            (p.key, value)
        })
        .collect())
}

/// The number at the dotted `key` of a resolved scenario table, if it is
/// set to one.
fn value_at(table: &toml::Table, key: &str) -> Option<f64> {
    let mut cur = Some(table);
    let parts: Vec<&str> = key.split('.').collect();
    for (i, part) in parts.iter().enumerate() {
        let v = cur.and_then(|t| t.get(*part));
        if i + 1 == parts.len() {
            return match v {
                Some(toml::Value::Float(f)) => Some(*f),
                Some(toml::Value::Integer(n)) => Some(*n as f64),
                _ => None,
            };
        }
        cur = v.and_then(toml::Value::as_table);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn set(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    fn repo(path: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(path)
    }

    /// The CLI's own path: the file loaded with `--set` flags, run by
    /// `ehservo_scenario::run::run` (what `ehservo run` writes to summary.json).
    fn cli_metrics(path: &str, flags: &[&str]) -> Metrics {
        let flags: Vec<String> = flags.iter().map(|s| s.to_string()).collect();
        let s = Loop::load(&repo(path), &flags).unwrap();
        ehservo_scenario::run::run(&s, ehservo_scenario::run::Keep::Nothing).metrics
    }

    #[test]
    fn every_scenario_file_is_offered_but_the_manifest() {
        let mut on_disk = Vec::new();
        for group in ["paper", "realistic", "cylinders", "hopsan"] {
            for e in std::fs::read_dir(repo(&format!("scenarios/{group}"))).unwrap() {
                let p = e.unwrap().path();
                let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
                // Study files sit beside the scenarios: they do not load as one.
                if p.extension().is_some_and(|x| x == "toml")
                    && stem != "manifest"
                    && Loop::load(&p, &[]).is_ok()
                {
                    on_disk.push(format!("{group}/{stem}"));
                }
            }
        }
        on_disk.sort();
        let mut offered: Vec<String> = catalog().scenarios.iter().map(|s| s.id.into()).collect();
        offered.sort();
        assert_eq!(offered, on_disk);
        assert!(offered.contains(&"paper/fig2".to_string()));
        assert!(offered.contains(&"cylinders/chrono-single-rod".to_string()));
        assert!(offered.contains(&"hopsan/position-servo".to_string()));
    }

    /// A linear axis in the page reads in mm, as `ehservo run` writes it:
    /// the same metrics (e_max and its unit "mm", no key in degrees), the
    /// trace's position in mm (the rod starts at the scenario's 142 mm).
    #[test]
    fn a_cylinder_runs_in_mm_as_the_cli_does() {
        let flags = ["simulation.horizon=1.0", "simulation.settle=0.5"];
        let run = simulate(
            "cylinders/chrono-single-rod",
            &set(&[("simulation.horizon", "1.0"), ("simulation.settle", "0.5")]),
        )
        .unwrap();
        assert_eq!(run.unit, "mm");
        let cli = cli_metrics("scenarios/cylinders/chrono-single-rod.toml", &flags);
        assert_eq!(run.metrics, cli);
        let json = serde_json::to_value(run.metrics).unwrap();
        assert_eq!(json["unit"], "mm");
        assert!(json.get("e_max").is_some_and(|v| v.is_f64()), "{json}");
        let keys: Vec<&String> = json.as_object().unwrap().keys().collect();
        assert!(!keys.iter().any(|k| k.contains("deg")), "{keys:?}");
        assert!(
            (run.trace.theta[0] - 142.0).abs() < 1e-9,
            "{}",
            run.trace.theta[0]
        );
        // Its P gain (11 162 V/m) is beyond the declared slider range of
        // kp (10⁴): the range holds the scenario's own value, so the page
        // may set it, and refuses what lies beyond both.
        let kp = |v: &str| {
            simulate(
                "cylinders/chrono-single-rod",
                &set(&[("simulation.horizon", "1.0"), ("controller.kp", v)]),
            )
        };
        assert!(kp("11162").is_ok());
        assert!(kp("11000").is_ok());
        let e = kp("20000").unwrap_err();
        assert!(e[0].reason.contains("[0.1, 11162]"), "{e:?}");
        let hopsan = simulate("hopsan/position-servo", &[]).unwrap();
        assert_eq!(hopsan.unit, "mm");
        assert_eq!(
            hopsan.metrics,
            cli_metrics("scenarios/hopsan/position-servo.toml", &[])
        );
    }

    #[test]
    fn kinds_come_with_their_declared_tunables_and_signals() {
        let ks = kinds();
        assert_eq!(ks.len(), ControllerCfg::KINDS.len());
        let pid = ks.iter().find(|k| k.kind == "pid").unwrap();
        let keys: Vec<&str> = pid.params.iter().map(|p| p.key.as_str()).collect();
        assert_eq!(keys, ["controller.kp", "controller.ki", "controller.kd"]);
        assert!(pid.params.iter().all(|p| p.log));
        let nn = ks.iter().find(|k| k.kind == "nnvsc").unwrap();
        assert_eq!(nn.params[0].key, "controller.gamma1");
        assert_eq!((nn.params[0].low, nn.params[0].high), (1.0, 1e4));
        let sig: Vec<&str> = nn.signals.iter().map(|s| s.key).collect();
        assert!(sig.contains(&"sigma") && sig.contains(&"w_norm"), "{sig:?}");
        // In-memory parts (no trace column) are not offered.
        assert!(!sig.contains(&"xi") && !sig.contains(&"e"), "{sig:?}");
    }

    #[test]
    fn a_run_is_the_clis_run() {
        let run = simulate("paper/fig2", &[]).unwrap();
        assert_eq!(run.metrics, cli_metrics("scenarios/paper/fig2.toml", &[]));
        assert_eq!(run.every, 1);
        assert_eq!(run.trace.t.len() as u64, run.metrics.samples);
        // θ in degrees, e = θd − θ.
        let i = 500;
        assert!((run.trace.e[i] - (run.trace.theta_d[i] - run.trace.theta[i])).abs() < 1e-9);
        let e_max = run.metrics.e_max.unwrap();
        let moved = simulate("paper/fig2", &set(&[("controller.gamma1", "200")])).unwrap();
        assert_eq!(
            moved.metrics,
            cli_metrics("scenarios/paper/fig2.toml", &["controller.gamma1=200"])
        );
        assert_ne!(moved.metrics.e_max, Some(e_max));
        let pid = simulate(
            "realistic/base",
            &set(&[("controller.kind", "pid"), ("uncertainty.a_bias", "0.5")]),
        )
        .unwrap();
        assert_eq!(
            pid.metrics,
            cli_metrics(
                "scenarios/realistic/base.toml",
                &["controller.kind=pid", "uncertainty.a_bias=0.5"]
            )
        );
        assert!(pid.trace.t.len() as u64 <= MAX_POINTS + 1);
    }

    #[test]
    fn bad_fields_are_named_with_the_reason() {
        let errs = |pairs: &[(&str, &str)]| simulate("paper/fig2", &set(pairs)).unwrap_err();
        let e = errs(&[("controller.gamma1", "abc"), ("controller.eta", "")]);
        assert_eq!(e.len(), 2);
        assert_eq!(e[0].key, "controller.gamma1");
        assert!(e[0].reason.contains("not a number"), "{e:?}");
        assert_eq!(e[1].key, "controller.eta");
        assert!(e[1].reason.contains("empty"), "{e:?}");
        let e = errs(&[("controller.gamma1", "1e9")]);
        assert!(
            e[0].reason.contains("outside") && e[0].reason.contains("10000"),
            "{e:?}"
        );
        // Fine alone, not together: the scenario's validator (Assumption A1).
        let e = errs(&[("uncertainty.b_bias", "-1"), ("uncertainty.b_random", "1")]);
        assert_eq!(e[0].key, "uncertainty.b_bias");
        assert!(e[0].reason.contains("must stay > 0"), "{e:?}");
        let e = simulate("paper/nope", &[]).unwrap_err();
        assert_eq!(e[0].key, "scenario");
    }

    #[test]
    fn the_downloaded_file_runs_to_the_same_result() {
        for (id, pairs) in [
            ("paper/fig2", vec![]),
            (
                "paper/fig2",
                vec![("controller.gamma1", "200"), ("uncertainty.a_bias", "0.4")],
            ),
            (
                "paper/gamma1-200",
                vec![("controller.kind", "vsc-sat"), ("controller.mu", "2")],
            ),
            (
                "realistic/base",
                vec![("controller.kind", "pid"), ("controller.kp", "30")],
            ),
        ] {
            let o = set(&pairs);
            let text = scenario_toml(id, &o).unwrap();
            let s = Loop::parse(&text).unwrap();
            let resolved = resolve(id, &o).unwrap().scenario().clone();
            assert_eq!(*s.scenario(), resolved, "{id} {pairs:?}:\n{text}");
            let cli = ehservo_scenario::run::run(&s, ehservo_scenario::run::Keep::Nothing);
            assert_eq!(cli.metrics, simulate(id, &o).unwrap().metrics);
            for (k, v) in &pairs {
                assert!(text.contains(&format!("--set {k}={v}")), "{text}");
            }
        }
        // vsc-sat shares nnvsc's table: gamma1-200's γ1 carries over.
        let text =
            scenario_toml("paper/gamma1-200", &set(&[("controller.kind", "vsc-sat")])).unwrap();
        assert!(text.contains("gamma1 = 200"), "{text}");
        assert!(scenario_toml("paper/fig2", &set(&[("controller.gamma1", "x")])).is_err());
    }

    #[test]
    fn base_values_are_the_scenarios_or_the_kinds_defaults() {
        let v = base_values("paper/gamma1-200", "nnvsc").unwrap();
        assert_eq!(v["controller.gamma1"], Some(200.0));
        assert_eq!(v["uncertainty.a_bias"], Some(1.0));
        let v = base_values("paper/fig2", "pid").unwrap();
        assert_eq!(v["controller.kp"], None, "designed by pole placement");
        assert_eq!(v.len(), 3 + UNCERTAINTY.len());
    }
}
