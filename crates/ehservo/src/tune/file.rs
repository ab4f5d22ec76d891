//! The tune file: its format (ranges, penalties, objective), its defaults,
//! and [`Tune`], the file checked against its scenarios and the kind's
//! tunables.

use crate::error::InputError;
use crate::scenario::{ControllerCfg, Loop, Reason};
use anyhow::Result;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// How the scores of the scenarios × draws make one objective.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Objective {
    /// Their mean.
    #[default]
    Mean,
    /// Their largest.
    Worst,
}

/// Spacing of a parameter's search.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Scale {
    /// Searched as given.
    #[default]
    Linear,
    /// Searched as its log10.
    Log,
}

/// One searched parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ParamRange {
    /// Key in `[controller]`.
    pub key: String,
    /// Lowest value.
    pub low: f64,
    /// Highest value.
    pub high: f64,
    /// `"linear"` (default) or `"log"`.
    #[serde(default)]
    pub scale: Scale,
}

/// `[penalty]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Penalty {
    /// Weight on the chattering index (L2[Δu]/L2[u] after the transient).
    pub chattering: f64,
    /// The valve's range (V): u_max beyond it is penalised.
    pub u_limit: Option<f64>,
    /// Weight on u_max beyond `u_limit`, in the axis's unit per volt
    /// (°/V on a rotary axis, mm/V on a linear one).
    pub u_excess: f64,
}

impl Default for Penalty {
    fn default() -> Self {
        Self {
            chattering: 0.0,
            u_limit: None,
            u_excess: 1.0,
        }
    }
}

/// `[reject]`: a candidate whose run does any of these scores +∞ (on any
/// scenario × draw), whatever its error.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Reject {
    /// The largest share of samples at the command's limit a run may have
    /// (0 to 1; default 0.2): a law that spends more of the run saturated
    /// is a bang-bang law, whatever its error. A run also scores +∞ when it
    /// hits an end stop or its error oscillates after the transient
    /// without decaying (`ehservo run`'s verdict).
    pub saturation_share: f64,
    /// The least gain margin (dB) a linear law's loop may have (default
    /// 6, the textbook minimum: Åström & Murray, *Feedback Systems*, 2nd
    /// ed. 2021, §10.3 — gain margins of 2 to 5 and phase margins of 30°
    /// to 60° are typical requirements; 6 dB and 45° the usual picks).
    /// Computed, as `ehservo freq` does, at the trim at the reference's
    /// start ([`crate::freq::stability`]); a computed unstable closed
    /// loop is rejected too. 0 turns it off. A nonlinear law (no linear
    /// model) is judged by its runs alone.
    #[serde(rename = "gain_margin_dB")]
    pub gain_margin_db: f64,
    /// The least phase margin (°) of a linear law's loop (default 45; 0
    /// turns it off).
    pub phase_margin_deg: f64,
}

impl Default for Reject {
    fn default() -> Self {
        Self {
            saturation_share: crate::behaviour::SATURATION_SHARE_LIMIT,
            gain_margin_db: 6.0,
            phase_margin_deg: 45.0,
        }
    }
}

impl Reject {
    /// Whether any margin is asked of a linear law.
    pub fn asks_margins(&self) -> bool {
        self.gain_margin_db > 0.0 || self.phase_margin_deg > 0.0
    }
}

/// `[verify]`: the chosen parameters run again, longer and over more
/// draws, before the tune reports them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Verify {
    /// Each scenario's horizon is multiplied by this (1 to 100; default
    /// 2): an oscillation that grows slowly, or a drift into an end stop,
    /// shows after the tune's horizon.
    pub horizon_factor: f64,
    /// Uncertainty draws per scenario (`uncertainty.seed` = 0, 1, …; 1:
    /// the scenario's own seed, as the tune's `draws`); default: the
    /// tune's `draws`, at least 3.
    pub draws: Option<u64>,
}

impl Default for Verify {
    fn default() -> Self {
        Self {
            horizon_factor: 2.0,
            draws: None,
        }
    }
}

/// A tune file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TuneFile {
    /// Name (default: the file's stem).
    #[serde(default)]
    pub name: String,
    /// The scenarios the objective runs (relative to the tune file).
    pub scenarios: Vec<PathBuf>,
    /// The controller kind tuned (default: the first scenario's).
    #[serde(default)]
    #[schemars(schema_with = "crate::schema::controller_kind")]
    pub controller: Option<String>,
    /// Evaluations of the objective (default 2000).
    #[serde(default = "default_budget")]
    pub budget: u64,
    /// Particles of the swarm (default 40).
    #[serde(default = "default_particles")]
    pub particles: u64,
    /// Seed of the swarm (default 1).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// `"mean"` (default) or `"worst"`.
    #[serde(default)]
    pub objective: Objective,
    /// Uncertainty seeds per scenario (default 1: the scenario's own).
    #[serde(default = "default_draws")]
    pub draws: u64,
    /// Penalties.
    #[serde(default)]
    pub penalty: Penalty,
    /// What makes a candidate unacceptable (+∞).
    #[serde(default)]
    pub reject: Reject,
    /// The verification of the chosen parameters.
    #[serde(default)]
    pub verify: Verify,
    /// The parameters searched (default: the kind's declared tunables).
    #[serde(default)]
    pub param: Vec<ParamRange>,
}

pub(crate) fn default_budget() -> u64 {
    2000
}
pub(crate) fn default_particles() -> u64 {
    40
}
pub(crate) fn default_seed() -> u64 {
    1
}
pub(crate) fn default_draws() -> u64 {
    1
}

/// Most evaluations one tune may ask for.
pub const MAX_BUDGET: u64 = 1_000_000;

/// A tune file, checked: its scenarios as TOML tables to start each
/// evaluation from, the kind and the searched ranges.
#[derive(Debug, Clone)]
pub struct Tune {
    /// The file as written (defaults filled).
    pub file: TuneFile,
    /// The scenarios.
    pub scenarios: Vec<Loop>,
    pub(super) tables: Vec<toml::Table>,
    /// The kind tuned.
    pub kind: &'static str,
    /// The searched parameters.
    pub params: Vec<ParamRange>,
    /// The scenarios' axis: the unit of every score (deg or mm).
    pub axis: crate::axis::Axis,
}

/// The one axis of a tune's or a league's scenarios (their scores add up
/// in one unit): the first's, or the index of the first that differs.
pub fn common_axis(scenarios: &[Loop]) -> Result<crate::axis::Axis, usize> {
    let axis = scenarios.first().map(Loop::axis).unwrap_or_default();
    match scenarios.iter().position(|s| s.axis() != axis) {
        Some(i) => Err(i),
        None => Ok(axis),
    }
}

/// The declared tunables of a kind ([`declared`]).
struct Tunables;

/// The tunables `kind` declares (`Config::TUNABLE`): what a tune searches
/// when its file gives no `[[param]]`; `None` for an unknown kind.
pub fn declared(kind: &str) -> Option<&'static [ehservo_core::control::Tunable]> {
    crate::scenario::ControllerCfg::default_of(kind).map(|c| c.visit(Tunables))
}

impl crate::scenario::Visit for Tunables {
    type Out = &'static [ehservo_core::control::Tunable];
    fn visit<K: crate::scenario::ControllerConfig>(self, _: &K) -> Self::Out {
        <K as ehservo_core::control::Config>::TUNABLE
    }
}

impl Tune {
    /// Reads and checks a tune file and its scenarios.
    pub fn load(path: &Path) -> Result<Tune, InputError> {
        let file = path.display().to_string();
        let mut tf: TuneFile = crate::study::load_toml(path, "tune")?;
        if tf.name.is_empty() {
            tf.name = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "tune".into());
        }
        let dir = path.parent().unwrap_or(Path::new("."));
        let scenarios = tf
            .scenarios
            .iter()
            .map(|p| {
                crate::formats::load(&dir.join(p), &[])
                    .map_err(|e| InputError::key(&file, "scenarios", e.to_string()))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Self::build(tf, scenarios, &file)
    }

    /// Checks a parsed tune file against its loaded scenarios.
    pub fn build(tf: TuneFile, scenarios: Vec<Loop>, file: &str) -> Result<Tune, InputError> {
        Self::build_under(tf, scenarios, file, "")
    }

    /// As [`Tune::build`] for a tune file's keys that sit under `section`
    /// in `file` (a league suite's `[tuning]`: `section = "tuning"`), so an
    /// error names the key as it is written there (`tuning.budget`).
    pub fn build_under(
        tf: TuneFile,
        scenarios: Vec<Loop>,
        file: &str,
        section: &str,
    ) -> Result<Tune, InputError> {
        let at = Keys { file, section };
        if scenarios.is_empty() {
            return Err(at.bad(
                "scenarios",
                "is empty: list at least one scenario file".into(),
            ));
        }
        let axis = common_axis(&scenarios).map_err(|i| {
            at.bad(
                &format!("scenarios[{i}]"),
                format!(
                    "`{}` is on a {} axis, `{}` on a {} one: the scores of one tune share one unit",
                    scenarios[i].name(),
                    scenarios[i].axis().name(),
                    scenarios[0].name(),
                    scenarios[0].axis().name()
                ),
            )
        })?;
        at.check_search(&tf)?;
        let kind = at.kind(&tf, &scenarios)?;
        let params = at.params(&tf, kind)?;
        at.check_work(&tf, &scenarios)?;
        let tables = scenarios
            .iter()
            .map(|s| s.table().map_err(|e| InputError::file(file, e.to_string())))
            .collect::<Result<Vec<_>, _>>()?;
        let t = Tune {
            file: tf,
            scenarios,
            tables,
            kind,
            params,
            axis,
        };
        // Every scenario must take the kind and every parameter: check the
        // two ends and the middle of the ranges now, not in the search.
        for x in [0.0, 0.5, 1.0] {
            let values: Vec<f64> = t.params.iter().map(|r| r.at(x)).collect();
            for (i, sets) in t.sets(&values).iter().enumerate() {
                if let Err(e) = t.build_run(i, sets) {
                    // A refused parameter value inside its range is a
                    // result (+∞), an unknown key is not.
                    if not_a_result(&e.reason) {
                        return Err(at.bad(&e.key, e.reason.to_string()));
                    }
                }
            }
        }
        Ok(t)
    }
}

/// Where a tune file's keys are written: the file, and the section they
/// sit under (empty in a tune file of its own).
struct Keys<'a> {
    file: &'a str,
    section: &'a str,
}

impl Keys<'_> {
    /// The error at `key`, named as it is written in the file.
    fn bad(&self, key: &str, reason: String) -> InputError {
        let (file, section) = (self.file, self.section);
        let dot = if section.is_empty() { "" } else { "." };
        InputError::key(file, format!("{section}{dot}{key}"), reason)
    }

    /// The search's settings: budget, particles, draws and penalties.
    fn check_search(&self, tf: &TuneFile) -> Result<(), InputError> {
        if !(1..=MAX_BUDGET).contains(&tf.budget) {
            return Err(self.bad(
                "budget",
                format!("must be in 1..={MAX_BUDGET} (got {})", tf.budget),
            ));
        }
        if !(2..=10_000).contains(&tf.particles) {
            return Err(self.bad(
                "particles",
                format!("must be in 2..=10000 (got {})", tf.particles),
            ));
        }
        if tf.budget < 2 * tf.particles {
            return Err(self.bad(
                "budget",
                format!(
                    "{} evaluations are fewer than two generations of {} particles",
                    tf.budget, tf.particles
                ),
            ));
        }
        if !(1..=10_000).contains(&tf.draws) {
            return Err(self.bad("draws", format!("must be in 1..=10000 (got {})", tf.draws)));
        }
        let r = tf.reject.saturation_share;
        if !(0.0..=1.0).contains(&r) {
            return Err(self.bad(
                "reject.saturation_share",
                format!("must be a share from 0 to 1 (got {r:?})"),
            ));
        }
        let g = tf.reject.gain_margin_db;
        if !(0.0..=60.0).contains(&g) {
            return Err(self.bad(
                "reject.gain_margin_dB",
                format!("must be from 0 to 60 dB (got {g:?})"),
            ));
        }
        let p = tf.reject.phase_margin_deg;
        if !(0.0..=90.0).contains(&p) {
            return Err(self.bad(
                "reject.phase_margin_deg",
                format!("must be from 0 to 90° (got {p:?})"),
            ));
        }
        let f = tf.verify.horizon_factor;
        if !(1.0..=100.0).contains(&f) {
            return Err(self.bad(
                "verify.horizon_factor",
                format!("must be from 1 to 100 (got {f:?})"),
            ));
        }
        if let Some(d) = tf.verify.draws {
            if !(1..=10_000).contains(&d) {
                return Err(self.bad("verify.draws", format!("must be in 1..=10000 (got {d})")));
            }
        }
        let p = &tf.penalty;
        if !(p.chattering.is_finite() && p.chattering >= 0.0) {
            return Err(self.bad(
                "penalty.chattering",
                format!("must be finite and >= 0 (got {:?})", p.chattering),
            ));
        }
        if !(p.u_excess.is_finite() && p.u_excess >= 0.0) {
            return Err(self.bad(
                "penalty.u_excess",
                format!("must be finite and >= 0 (got {:?})", p.u_excess),
            ));
        }
        if let Some(l) = p.u_limit {
            if !(l.is_finite() && l > 0.0) {
                return Err(self.bad(
                    "penalty.u_limit",
                    format!("must be finite and > 0 (got {l:?})"),
                ));
            }
        }
        Ok(())
    }

    /// The controller kind tuned: `controller`, or the first scenario's.
    fn kind(&self, tf: &TuneFile, scenarios: &[Loop]) -> Result<&'static str, InputError> {
        let kind_name = tf
            .controller
            .clone()
            .unwrap_or_else(|| scenarios[0].controller().kind().to_string());
        let Some(&kind) = ControllerCfg::KINDS.iter().find(|k| **k == kind_name) else {
            return Err(self.bad(
                "controller",
                format!(
                    "unknown controller kind `{kind_name}`: expected one of {}",
                    ControllerCfg::KINDS.join(", ")
                ),
            ));
        };
        Ok(kind)
    }

    /// The parameters tuned: the `[[param]]` ranges, or the kind's declared
    /// tunables; each checked.
    fn params(&self, tf: &TuneFile, kind: &'static str) -> Result<Vec<ParamRange>, InputError> {
        let declared = declared(kind).unwrap_or(&[]);
        let params: Vec<ParamRange> = if tf.param.is_empty() {
            declared
                .iter()
                .map(|t| ParamRange {
                    key: t.key.to_string(),
                    low: t.low,
                    high: t.high,
                    scale: if t.log { Scale::Log } else { Scale::Linear },
                })
                .collect()
        } else {
            tf.param.clone()
        };
        if params.is_empty() {
            return Err(self.bad(
                "param",
                format!("controller kind `{kind}` declares no tunable parameters: list them as [[param]]"),
            ));
        }
        let defaults = ControllerCfg::default_of(kind)
            .map(|c| c.to_table())
            .unwrap_or_default();
        for (i, r) in params.iter().enumerate() {
            let key = format!("param[{i}]");
            if params[..i].iter().any(|q| q.key == r.key) {
                return Err(self.bad(&key, format!("`{}` is listed twice", r.key)));
            }
            if let Some(v) = defaults.get(&r.key) {
                numeric(v).map_err(|what| {
                    self.bad(
                        &key,
                        format!(
                            "`{}` of `{kind}` is {what}, not a real number: only numeric parameters can be tuned",
                            r.key
                        ),
                    )
                })?;
            }
            self.check_range(&key, r)?;
        }
        Ok(params)
    }

    /// A parameter's range: finite, low below high, above 0 on a log
    /// scale, and within what the swarm can compute beyond it.
    fn check_range(&self, key: &str, r: &ParamRange) -> Result<(), InputError> {
        if !(r.low.is_finite() && r.high.is_finite()) {
            return Err(self.bad(key, format!("`{}`: low and high must be finite", r.key)));
        }
        if r.low >= r.high {
            return Err(self.bad(
                key,
                format!("`{}`: low = {} must be < high = {}", r.key, r.low, r.high),
            ));
        }
        if r.scale == Scale::Log && r.low <= 0.0 {
            return Err(self.bad(
                key,
                format!(
                    "`{}`: a log range must lie above 0 (low = {})",
                    r.key, r.low
                ),
            ));
        }
        // The swarm draws velocities up to ±(high − low) and moves a
        // particle by at most (c1 + c2)/(1 − w) ≈ 8.6 times that
        // (argmin's SPSO 2011 weights): with a margin, all it computes
        // must stay finite.
        let (lo, hi) = r.bounds();
        let reach = lo.abs().max(hi.abs()) + SWARM_REACH * (hi - lo);
        if !reach.is_finite() {
            return Err(self.bad(
                key,
                format!(
                    "`{}`: the swarm computes up to {SWARM_REACH}·(high − low) beyond the range, which overflows for [{:e}, {:e}]: narrow it (or use scale = \"log\")",
                    r.key, r.low, r.high
                ),
            ));
        }
        Ok(())
    }

    /// The work asked for, bounded before any of it: every evaluation of
    /// the objective runs every scenario × draw (and the defaults once).
    fn check_work(&self, tf: &TuneFile, scenarios: &[Loop]) -> Result<(), InputError> {
        let mut work = crate::limits::Batch::default();
        let per: f64 = scenarios
            .iter()
            .map(|s| crate::limits::run_evaluations(s.scenario()) + crate::limits::RUN_OVERHEAD)
            .sum::<f64>()
            * tf.draws as f64;
        let runs = (scenarios.len() as u64 * tf.draws) as f64;
        work.add(
            "budget",
            (tf.budget + 1) as f64,
            per - crate::limits::RUN_OVERHEAD,
            format!(
                "{} evaluations of the objective × {runs} runs each ({} scenario(s) × {} draw(s))",
                tf.budget,
                scenarios.len(),
                tf.draws
            ),
        );
        work.check("tune")
            .map_err(|e| self.bad(&e.key, e.reason.to_string()))
    }
}

/// How far beyond its range the swarm computes, in widths of the range
/// (with a margin over argmin's bound of about 8.6).
const SWARM_REACH: f64 = 16.0;

/// Whether a value of a parameter's default table is a number the tune
/// can set; otherwise what it is.
pub(crate) fn numeric(v: &toml::Value) -> Result<(), &'static str> {
    match v {
        toml::Value::Float(_) => Ok(()),
        toml::Value::Integer(_) => Err("an integer"),
        toml::Value::Boolean(_) => Err("a boolean"),
        toml::Value::String(_) => Err("a string (a choice of names)"),
        toml::Value::Array(_) => Err("an array"),
        toml::Value::Table(_) => Err("a table"),
        toml::Value::Datetime(_) => Err("a date"),
    }
}

/// Whether a refusal of a trial value is the key's fault (unknown, unused,
/// or not a number at all) rather than a result (a value the controller
/// refuses inside its range, scored +∞).
pub(crate) fn not_a_result(reason: &Reason) -> bool {
    match reason {
        Reason::Serde(r) => r.contains("unknown field") || r.contains("invalid type"),
        r => r.contains("not used by"),
    }
}

impl ParamRange {
    /// The value at fraction `x` of the range (on its scale).
    fn at(&self, x: f64) -> f64 {
        match self.scale {
            Scale::Log => 10f64.powf(self.low.log10() + x * (self.high.log10() - self.low.log10())),
            Scale::Linear => self.low + x * (self.high - self.low),
        }
        .clamp(self.low, self.high)
    }

    /// The search-space bounds.
    pub(super) fn bounds(&self) -> (f64, f64) {
        match self.scale {
            Scale::Log => (self.low.log10(), self.high.log10()),
            Scale::Linear => (self.low, self.high),
        }
    }
}
