//! The suite file: its format (`[[controller]]`, `[[scenario]]`,
//! `[tuning]`, `[margin]`), and [`League`], the file checked, its
//! scenarios loaded and its tunes built, with the work it asks for.

use super::param_box::{checked_points, BoxCfg, Point};
use super::{build_with, Margin};
use crate::error::InputError;
use crate::scenario::{ControllerCfg, Loop};
use crate::tune::{Objective, Penalty, Reject, Tune, TuneFile, Verify};
use anyhow::Result;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

#[path = "suite_margin.rs"]
mod margin;

/// One `[[controller]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ControllerEntry {
    /// The controller kind.
    #[schemars(schema_with = "crate::schema::controller_kind")]
    pub kind: String,
    /// Its label in the report (default: the kind).
    #[serde(default)]
    pub name: Option<String>,
    /// Tuned by `[tuning]` (default), or run with the kind's defaults and
    /// `params`.
    #[serde(default = "yes")]
    pub tune: bool,
    /// Given parameters (with `tune = false`), on top of the kind's defaults.
    #[serde(default)]
    #[schemars(with = "crate::schema::TomlTable")]
    pub params: toml::Table,
}

fn yes() -> bool {
    true
}

/// One `[[scenario]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ScenarioEntry {
    /// The scenario file, relative to the suite file.
    pub file: PathBuf,
    /// Its label (default: the file's stem).
    #[serde(default)]
    pub name: Option<String>,
    /// Overrides, `key.path=value` as `ehservo run --set`.
    #[serde(default)]
    pub set: Vec<String>,
    /// Uncertainty draws (default 1).
    #[serde(default = "one")]
    pub draws: u64,
    /// The first draw's `uncertainty.seed` (default: the scenario's own
    /// with one draw, 0 with several).
    #[serde(default)]
    pub first_seed: Option<u64>,
    /// A box of keys whose corners and inner points are each run, under
    /// every draw (`[scenario.box]`, [`super::param_box`]).
    #[serde(default, rename = "box", skip_serializing_if = "Option::is_none")]
    pub param_box: Option<BoxCfg>,
}

fn one() -> u64 {
    1
}

/// `[tuning]`: the budget every tuned controller gets.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TuningCfg {
    /// The scenarios of the objective (relative to the suite file).
    pub scenarios: Vec<PathBuf>,
    /// Evaluations of the objective per controller.
    #[serde(default = "crate::tune::default_budget")]
    pub budget: u64,
    /// Particles of the swarm.
    #[serde(default = "crate::tune::default_particles")]
    pub particles: u64,
    /// Seed of the swarm.
    #[serde(default = "crate::tune::default_seed")]
    pub seed: u64,
    /// `"mean"` or `"worst"`.
    #[serde(default)]
    pub objective: Objective,
    /// Uncertainty seeds per scenario.
    #[serde(default = "crate::tune::default_draws")]
    pub draws: u64,
    /// Penalties.
    #[serde(default)]
    pub penalty: Penalty,
    /// What makes a candidate unacceptable (+∞): as a tune file's.
    #[serde(default)]
    pub reject: Reject,
    /// The verification of each tuned controller: as a tune file's.
    #[serde(default)]
    pub verify: Verify,
}

/// `[margin]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MarginCfg {
    /// The scenario varied (relative to the suite file).
    pub scenario: PathBuf,
    /// Its overrides.
    #[serde(default)]
    pub set: Vec<String>,
    /// The keys all set to `scale`·x, x the bisected value.
    pub keys: Vec<String>,
    /// The factor on x (default 1; −1 bisects a negative bias).
    #[serde(default = "unit")]
    pub scale: f64,
    /// The lowest x (default 0).
    #[serde(default)]
    pub low: f64,
    /// The highest x.
    pub high: f64,
    /// Bisection stops when the bracket is narrower (default 0.01).
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// e_max above this (°, a rotary axis) counts as unbounded.
    #[serde(default)]
    pub e_limit_deg: Option<f64>,
    /// e_max above this (mm, a linear axis) counts as unbounded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub e_limit_mm: Option<f64>,
}

impl MarginCfg {
    /// The error limit in the axis's unit, whichever key gives it.
    pub fn e_limit(&self) -> Option<f64> {
        self.e_limit_deg.or(self.e_limit_mm)
    }
}

fn default_tolerance() -> f64 {
    0.01
}

fn unit() -> f64 {
    1.0
}

/// A suite file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SuiteFile {
    /// Name (default: the file's stem).
    #[serde(default)]
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The controllers.
    #[serde(default)]
    pub controller: Vec<ControllerEntry>,
    /// The scenarios.
    #[serde(default)]
    pub scenario: Vec<ScenarioEntry>,
    /// The tuning budget.
    #[serde(default)]
    pub tuning: Option<TuningCfg>,
    /// The robustness margin.
    #[serde(default)]
    pub margin: Option<MarginCfg>,
}

/// How a controller of the league gets its parameters.
#[derive(Debug, Clone)]
pub enum Source {
    /// Tuned by the suite's `[tuning]`.
    Tuned(Box<Tune>),
    /// The kind's defaults with the given parameters.
    Given,
}

/// A checked `[[controller]]`.
#[derive(Debug, Clone)]
pub struct Contestant {
    /// Its label.
    pub name: String,
    /// Its kind.
    pub kind: &'static str,
    /// Its `[controller]` table before tuning.
    pub table: toml::Table,
    /// Tuned or given.
    pub source: Source,
}

/// A checked `[[scenario]]`.
#[derive(Debug, Clone)]
pub struct Case {
    /// Its label.
    pub name: String,
    /// The scenario (overrides applied).
    pub scenario: Loop,
    pub(super) table: toml::Table,
    /// The seed of each draw (None: the scenario's own).
    pub seeds: Vec<Option<u64>>,
    /// The box's points, each run under every seed (one empty point
    /// without a box: the scenario as written).
    pub points: Vec<Point>,
}

/// A suite, checked.
#[derive(Debug, Clone)]
pub struct League {
    /// As written.
    pub file: SuiteFile,
    /// The controllers.
    pub contestants: Vec<Contestant>,
    /// The scenarios.
    pub cases: Vec<Case>,
    /// The margin.
    pub margin: Option<Margin>,
    /// The scenarios' axis: the unit of every error (deg or mm).
    pub axis: crate::axis::Axis,
}

/// The most draws of one scenario.
pub const MAX_DRAWS: u64 = 10_000;

impl League {
    /// Reads and checks a suite file and the scenarios it names.
    pub fn load(path: &Path) -> Result<League, InputError> {
        let at = Loader {
            file: path.display().to_string(),
            dir: path.parent().unwrap_or(Path::new(".")),
        };
        let mut sf: SuiteFile = crate::study::load_toml(path, "suite")?;
        if sf.name.is_empty() {
            sf.name = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "league".into());
        }
        if sf.controller.is_empty() {
            return Err(at.bad(
                "controller",
                "the suite has no [[controller]]: list at least one".into(),
            ));
        }
        if sf.scenario.is_empty() {
            return Err(at.bad(
                "scenario",
                "the suite has no [[scenario]]: list at least one".into(),
            ));
        }
        let cases = at.cases(&sf.scenario)?;
        let contestants = at.contestants(&sf, &cases)?;
        let margin = match &sf.margin {
            None => None,
            Some(m) => Some(at.margin(m, &contestants)?),
        };
        let axis = at.one_axis(&cases, margin.as_ref())?;
        let league = League {
            file: sf,
            contestants,
            cases,
            margin,
            axis,
        };
        league
            .work_asked()
            .check("league")
            .map_err(|e| at.bad(&e.key, e.reason.to_string()))?;
        Ok(league)
    }

    /// The evaluations the league asks for, by the key that asks: the
    /// tunes, every run of every scenario, the margins' bisections.
    fn work_asked(&self) -> crate::limits::Batch {
        use crate::limits::{run_evaluations, RUN_OVERHEAD};
        let mut b = crate::limits::Batch::default();
        let n = self.contestants.len() as f64;
        let tuned: Vec<&Tune> = self
            .contestants
            .iter()
            .filter_map(|c| match &c.source {
                Source::Tuned(t) => Some(&**t),
                Source::Given => None,
            })
            .collect();
        if let Some(t) = tuned.first() {
            let per: f64 = t
                .scenarios
                .iter()
                .map(|s| run_evaluations(s.scenario()) + RUN_OVERHEAD)
                .sum::<f64>()
                * t.file.draws as f64;
            b.add(
                "tuning.budget",
                tuned.len() as f64 * (t.file.budget + 1) as f64,
                per - RUN_OVERHEAD,
                format!(
                    "tuning {} controllers × {} evaluations × {} runs each",
                    tuned.len(),
                    t.file.budget,
                    t.scenarios.len() as u64 * t.file.draws
                ),
            );
        }
        for (i, c) in self.cases.iter().enumerate() {
            b.add(
                &format!("scenario[{i}].draws"),
                n * c.runs() as f64,
                run_evaluations(c.scenario.scenario()),
                format!(
                    "scenario `{}`: {} controllers × {} runs",
                    c.name,
                    self.contestants.len(),
                    c.runs()
                ),
            );
        }
        if let Some(m) = &self.margin {
            b.add(
                "margin.tolerance",
                n * m.steps() as f64,
                run_evaluations(m.scenario.scenario()),
                format!(
                    "the margin: {} controllers × {} bisection runs",
                    self.contestants.len(),
                    m.steps()
                ),
            );
        }
        b
    }

    /// The runs of the league, in report order: (controller, scenario,
    /// draw).
    pub fn cells(&self) -> Vec<(usize, usize, usize)> {
        let mut out = Vec::new();
        for ci in 0..self.contestants.len() {
            for (si, c) in self.cases.iter().enumerate() {
                for d in 0..c.runs() {
                    out.push((ci, si, d));
                }
            }
        }
        out
    }

    /// Evaluations the league makes (tuning, runs, and a bound on the
    /// margin's), for a progress bar.
    pub fn work(&self) -> u64 {
        let tunes: u64 = self
            .contestants
            .iter()
            .map(|c| match &c.source {
                Source::Tuned(t) => t.file.budget,
                Source::Given => 0,
            })
            .sum();
        let margin = self
            .margin
            .as_ref()
            .map(|m| m.steps() as u64 * self.contestants.len() as u64)
            .unwrap_or(0);
        tunes + self.cells().len() as u64 + margin
    }
}

/// The suite file being loaded: its name, which its errors carry, and its
/// folder, which the files it names are relative to.
struct Loader<'a> {
    file: String,
    dir: &'a Path,
}

impl Loader<'_> {
    /// The error at `key` of the suite file.
    fn bad(&self, key: &str, reason: String) -> InputError {
        InputError::key(&self.file, key, reason)
    }

    /// A scenario the suite names. One that fails to load is named by its
    /// file, or by its `set` when an override is what fails.
    fn load(&self, key: &str, p: &Path, set: &[String]) -> Result<Loop, InputError> {
        crate::formats::load(&self.dir.join(p), set).map_err(|e| {
            let msg = e.to_string();
            let at = if msg.starts_with("--set") {
                "set"
            } else {
                "file"
            };
            let key = match key.strip_suffix(".file") {
                Some(k) => format!("{k}.{at}"),
                None => key.to_string(),
            };
            self.bad(&key, msg)
        })
    }

    /// A loaded scenario as a table, the base its runs are built on.
    fn table_of(&self, key: &str, s: &Loop) -> Result<toml::Table, InputError> {
        s.table().map_err(|e| self.bad(key, e.to_string()))
    }

    /// The `[[scenario]]`s, each loaded, labelled and given its draws' seeds.
    fn cases(&self, entries: &[ScenarioEntry]) -> Result<Vec<Case>, InputError> {
        let mut cases = Vec::new();
        for (i, e) in entries.iter().enumerate() {
            let key = format!("scenario[{i}]");
            if !(1..=MAX_DRAWS).contains(&e.draws) {
                return Err(self.bad(
                    &format!("{key}.draws"),
                    format!("must be in 1..={MAX_DRAWS} (got {})", e.draws),
                ));
            }
            let scenario = self.load(&format!("{key}.file"), &e.file, &e.set)?;
            let name = e.name.clone().unwrap_or_else(|| {
                e.file
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| format!("scenario-{i}"))
            });
            check_label(&name).map_err(|r| self.bad(&format!("{key}.name"), r))?;
            if cases.iter().any(|c: &Case| c.name == name) {
                return Err(self.bad(
                    &format!("{key}.name"),
                    format!("`{name}` names two scenarios: give each a distinct `name`"),
                ));
            }
            let seeds = self.seeds(&key, e)?;
            let table = self.table_of(&key, &scenario)?;
            let mut case = Case {
                name,
                scenario,
                table,
                seeds,
                points: vec![Vec::new()],
            };
            if let Some(b) = &e.param_box {
                case.points = checked_points(b, &case).map_err(|(k, r)| {
                    self.bad(format!("{key}.box.{k}").trim_end_matches('.'), r)
                })?;
            }
            cases.push(case);
        }
        Ok(cases)
    }

    /// The seed of each draw of a `[[scenario]]` (None: the scenario's own).
    fn seeds(&self, key: &str, e: &ScenarioEntry) -> Result<Vec<Option<u64>>, InputError> {
        if e.draws == 1 && e.first_seed.is_none() {
            return Ok(vec![None]);
        }
        let first = e.first_seed.unwrap_or(0);
        // `uncertainty.seed` is a TOML integer: at most 2⁶³ − 1.
        let last = first
            .checked_add(e.draws - 1)
            .filter(|&l| l <= i64::MAX as u64);
        if last.is_none() {
            return Err(self.bad(
                &format!("{key}.first_seed"),
                format!(
                    "{first} + {} draws runs past the largest seed, 2^63 − 1 = {}: lower first_seed",
                    e.draws,
                    i64::MAX
                ),
            ));
        }
        Ok((0..e.draws).map(|d| Some(first + d)).collect())
    }

    /// The `[[controller]]`s, each checked, its table built on every
    /// scenario and its tune made; `[tuning]` must tune at least one.
    fn contestants(&self, sf: &SuiteFile, cases: &[Case]) -> Result<Vec<Contestant>, InputError> {
        let mut contestants: Vec<Contestant> = Vec::new();
        for (i, e) in sf.controller.iter().enumerate() {
            let key = format!("controller[{i}]");
            let Some(&kind) = ControllerCfg::KINDS.iter().find(|k| **k == e.kind) else {
                return Err(self.bad(
                    &format!("{key}.kind"),
                    format!(
                        "unknown controller kind `{}`: expected one of {}",
                        e.kind,
                        ControllerCfg::KINDS.join(", ")
                    ),
                ));
            };
            let name = e.name.clone().unwrap_or_else(|| kind.to_string());
            check_label(&name).map_err(|r| self.bad(&format!("{key}.name"), r))?;
            if contestants.iter().any(|c| c.name == name) {
                return Err(self.bad(
                    &format!("{key}.name"),
                    format!("`{name}` names two controllers: give each a distinct `name`"),
                ));
            }
            let table = self.controller_table(&key, e, kind, cases)?;
            let source = if e.tune {
                let Some(t) = &sf.tuning else {
                    return Err(self.bad(
                        "tuning",
                        format!(
                            "controller `{name}` is to be tuned (`tune` defaults to true) but the suite has no [tuning] section: add one, or set `tune = false`"
                        ),
                    ));
                };
                Source::Tuned(Box::new(tune_for(t, kind, &table, self.dir, &self.file)?))
            } else {
                Source::Given
            };
            contestants.push(Contestant {
                name,
                kind,
                table,
                source,
            });
        }
        if sf.tuning.is_some()
            && !contestants
                .iter()
                .any(|c| matches!(c.source, Source::Tuned(_)))
        {
            return Err(self.bad(
                "tuning",
                "no controller is tuned (every one has `tune = false`): drop [tuning]".into(),
            ));
        }
        Ok(contestants)
    }

    /// A controller's full `[controller]` table: the kind's defaults and its
    /// given `params`, which must build on every scenario of the suite.
    fn controller_table(
        &self,
        key: &str,
        e: &ControllerEntry,
        kind: &'static str,
        cases: &[Case],
    ) -> Result<toml::Table, InputError> {
        let mut table = ControllerCfg::default_of(kind)
            .expect("a listed kind has defaults")
            .to_table();
        if e.tune && !e.params.is_empty() {
            return Err(self.bad(
                &format!("{key}.params"),
                "given parameters with `tune = true`: set `tune = false` to run them as given, or drop `params` to tune".into(),
            ));
        }
        if e.params.contains_key("kind") {
            return Err(self.bad(
                &format!("{key}.params.kind"),
                "the kind is `kind`, not a parameter".into(),
            ));
        }
        table.extend(e.params.clone());
        for c in cases {
            build_with(c, &table, 0).map_err(|r| {
                self.bad(
                    &format!("{key}.params"),
                    format!("on scenario `{}`: {r}", c.name),
                )
            })?;
        }
        Ok(table)
    }
}

/// The value at a dotted key path of a table (`uncertainty.a_bias`).
fn lookup<'a>(t: &'a toml::Table, path: &str) -> Option<&'a toml::Value> {
    let mut parts = path.split('.');
    let mut v = t.get(parts.next()?.trim())?;
    for p in parts {
        v = v.as_table()?.get(p.trim())?;
    }
    Some(v)
}

/// A label used as a file name and a CSV cell.
fn check_label(s: &str) -> Result<(), String> {
    if s.is_empty()
        || !s
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
        || s.starts_with('.')
    {
        return Err(format!(
            "`{s}` must be letters, digits, `-`, `_` or `.` (it names files), not starting with `.`"
        ));
    }
    Ok(())
}

/// The tune of `kind` with the suite's budget, every tuning scenario
/// starting from the league's table for the kind.
fn tune_for(
    t: &TuningCfg,
    kind: &'static str,
    table: &toml::Table,
    dir: &Path,
    file: &str,
) -> Result<Tune, InputError> {
    let bad = |key: &str, reason: String| InputError::key(file, key, reason);
    let scenarios = t
        .scenarios
        .iter()
        .map(|p| {
            let s = crate::formats::load(&dir.join(p), &[])
                .map_err(|e| bad("tuning.scenarios", e.to_string()))?;
            let mut tab = s
                .table()
                .map_err(|e| bad("tuning.scenarios", e.to_string()))?;
            tab.insert("controller".into(), toml::Value::Table(table.clone()));
            s.with_values_on(tab, &[])
                .map_err(|e| bad("tuning.scenarios", e.to_string()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let tf = TuneFile {
        name: format!("league-{kind}"),
        scenarios: t.scenarios.clone(),
        controller: Some(kind.to_string()),
        budget: t.budget,
        particles: t.particles,
        seed: t.seed,
        objective: t.objective,
        draws: t.draws,
        penalty: t.penalty,
        reject: t.reject,
        verify: t.verify,
        param: Vec::new(),
    };
    // The tune's keys sit under `tuning` in a suite.
    Tune::build_under(tf, scenarios, file, "tuning")
}
