//! `ehservo tune`: a controller's parameters searched to minimise an
//! objective over a set of scenarios, by argmin's particle swarm.
//!
//! ```toml
//! name = "pid-fig2"
//! scenarios = ["../paper/fig2.toml"]   # relative to this file
//! controller = "pid"                    # the kind tuned (default: the first scenario's)
//! budget = 2000                         # evaluations of the objective
//! particles = 40
//! seed = 1
//! objective = "mean"                    # or "worst", over scenarios × draws
//! draws = 1                             # uncertainty seeds per scenario (uncertainty.seed = 0, 1, …)
//! [penalty]
//! chattering = 0.0                      # + weight·chattering index
//! u_limit = 10.0                        # V; + u_excess·max(0, u_max − u_limit)
//! u_excess = 1.0
//! [[param]]                             # default: the kind's declared tunables
//! key = "kp"
//! low = 1.0
//! high = 1000.0
//! scale = "log"
//! ```
//!
//! One evaluation runs every scenario (× draws) with the candidate
//! parameters and scores it: e_max after the transient (°), plus the
//! penalties; a run that diverges, or parameters the controller refuses,
//! score +∞. The swarm (Zambrano-Bigiarini et al., SPSO 2011, as argmin
//! implements it) searches a log-scaled parameter as its log10. Its random
//! numbers come from a seeded generator, and the particles of an
//! iteration are evaluated in parallel by rayon and collected in order,
//! so a seed gives the same result bit for bit whatever the thread count.

use crate::metrics::Metrics;
use crate::output::{write_atomic, Staging, SOFTWARE};
use crate::plot::{Figure, Panel, Series};
use crate::scenario::{ControllerCfg, Scenario, Setup};
use crate::study::StudyError;
use anyhow::{Context, Result};
use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{CostFunction, Executor, State, KV};
use argmin::solver::particleswarm::ParticleSwarm;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

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
    pub scenarios: Vec<Scenario>,
    tables: Vec<toml::Table>,
    /// The kind tuned.
    pub kind: &'static str,
    /// The searched parameters.
    pub params: Vec<ParamRange>,
    /// The scenarios' axis: the unit of every score (deg or mm).
    pub axis: crate::axis::Axis,
}

/// The one axis of a tune's or a league's scenarios (their scores add up
/// in one unit): the first's, or the index of the first that differs.
pub fn common_axis(scenarios: &[Scenario]) -> Result<crate::axis::Axis, usize> {
    let axis = scenarios
        .first()
        .map(|s| s.plant.axis())
        .unwrap_or_default();
    match scenarios.iter().position(|s| s.plant.axis() != axis) {
        Some(i) => Err(i),
        None => Ok(axis),
    }
}

/// The declared tunables of a kind.
struct Tunables;

impl crate::scenario::Visit for Tunables {
    type Out = &'static [ehservo_core::control::Tunable];
    fn visit<K: crate::scenario::ControllerConfig>(self, _: &K) -> Self::Out {
        <K as ehservo_core::control::Config>::TUNABLE
    }
}

impl Tune {
    /// Reads and checks a tune file and its scenarios.
    pub fn load(path: &Path) -> Result<Tune, StudyError> {
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
                Scenario::load(&dir.join(p), &[])
                    .map_err(|e| StudyError(format!("{file}: `scenarios`: {e}")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Self::build(tf, scenarios, &file)
    }

    /// Checks a parsed tune file against its loaded scenarios.
    pub fn build(tf: TuneFile, scenarios: Vec<Scenario>, file: &str) -> Result<Tune, StudyError> {
        Self::build_under(tf, scenarios, file, "")
    }

    /// As [`Tune::build`] for a tune file's keys that sit under `section`
    /// in `file` (a league suite's `[tuning]`: `section = "tuning"`), so an
    /// error names the key as it is written there (`tuning.budget`).
    pub fn build_under(
        tf: TuneFile,
        scenarios: Vec<Scenario>,
        file: &str,
        section: &str,
    ) -> Result<Tune, StudyError> {
        let dot = if section.is_empty() { "" } else { "." };
        let bad = |key: &str, reason: String| {
            StudyError(format!("{file}: `{section}{dot}{key}`: {reason}"))
        };
        if scenarios.is_empty() {
            return Err(bad(
                "scenarios",
                "is empty: list at least one scenario file".into(),
            ));
        }
        let axis = common_axis(&scenarios).map_err(|i| {
            bad(
                &format!("scenarios[{i}]"),
                format!(
                    "`{}` is on a {} axis, `{}` on a {} one: the scores of one tune share one unit",
                    scenarios[i].name,
                    scenarios[i].plant.axis().name(),
                    scenarios[0].name,
                    scenarios[0].plant.axis().name()
                ),
            )
        })?;
        if !(1..=MAX_BUDGET).contains(&tf.budget) {
            return Err(bad(
                "budget",
                format!("must be in 1..={MAX_BUDGET} (got {})", tf.budget),
            ));
        }
        if !(2..=10_000).contains(&tf.particles) {
            return Err(bad(
                "particles",
                format!("must be in 2..=10000 (got {})", tf.particles),
            ));
        }
        if tf.budget < 2 * tf.particles {
            return Err(bad(
                "budget",
                format!(
                    "{} evaluations are fewer than two generations of {} particles",
                    tf.budget, tf.particles
                ),
            ));
        }
        if !(1..=10_000).contains(&tf.draws) {
            return Err(bad(
                "draws",
                format!("must be in 1..=10000 (got {})", tf.draws),
            ));
        }
        let p = &tf.penalty;
        if !(p.chattering.is_finite() && p.chattering >= 0.0) {
            return Err(bad(
                "penalty.chattering",
                format!("must be finite and >= 0 (got {:?})", p.chattering),
            ));
        }
        if !(p.u_excess.is_finite() && p.u_excess >= 0.0) {
            return Err(bad(
                "penalty.u_excess",
                format!("must be finite and >= 0 (got {:?})", p.u_excess),
            ));
        }
        if let Some(l) = p.u_limit {
            if !(l.is_finite() && l > 0.0) {
                return Err(bad(
                    "penalty.u_limit",
                    format!("must be finite and > 0 (got {l:?})"),
                ));
            }
        }
        let kind_name = tf
            .controller
            .clone()
            .unwrap_or_else(|| scenarios[0].controller.kind().to_string());
        let Some(&kind) = ControllerCfg::KINDS.iter().find(|k| **k == kind_name) else {
            return Err(bad(
                "controller",
                format!(
                    "unknown controller kind `{kind_name}`: expected one of {}",
                    ControllerCfg::KINDS.join(", ")
                ),
            ));
        };
        let declared = ControllerCfg::default_of(kind)
            .map(|c| c.visit(Tunables))
            .unwrap_or(&[]);
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
            return Err(bad(
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
                return Err(bad(&key, format!("`{}` is listed twice", r.key)));
            }
            if let Some(v) = defaults.get(&r.key) {
                numeric(v).map_err(|what| {
                    bad(
                        &key,
                        format!(
                            "`{}` of `{kind}` is {what}, not a real number: only numeric parameters can be tuned",
                            r.key
                        ),
                    )
                })?;
            }
            if !(r.low.is_finite() && r.high.is_finite()) {
                return Err(bad(
                    &key,
                    format!("`{}`: low and high must be finite", r.key),
                ));
            }
            if r.low >= r.high {
                return Err(bad(
                    &key,
                    format!("`{}`: low = {} must be < high = {}", r.key, r.low, r.high),
                ));
            }
            if r.scale == Scale::Log && r.low <= 0.0 {
                return Err(bad(
                    &key,
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
                return Err(bad(
                    &key,
                    format!(
                        "`{}`: the swarm computes up to {SWARM_REACH}·(high − low) beyond the range, which overflows for [{:e}, {:e}]: narrow it (or use scale = \"log\")",
                        r.key, r.low, r.high
                    ),
                ));
            }
        }
        // The work asked for, bounded before any of it: every evaluation of
        // the objective runs every scenario × draw (and the defaults once).
        let mut work = crate::limits::Batch::default();
        let per: f64 = scenarios
            .iter()
            .map(|s| crate::limits::run_evaluations(s) + crate::limits::RUN_OVERHEAD)
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
        work.check("tune").map_err(|(k, r)| bad(&k, r))?;
        let tables = scenarios
            .iter()
            .map(|s| s.table().map_err(|e| StudyError(format!("{file}: {e}"))))
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
                        return Err(bad(&e.key, e.reason));
                    }
                }
            }
        }
        Ok(t)
    }

    /// The overrides of one evaluation of `values`: one list per
    /// scenario × draw.
    fn sets(&self, values: &[f64]) -> Vec<Vec<(String, toml::Value)>> {
        self.sets_of(Some(values))
    }

    /// [`Tune::sets`] of `values`, or of the kind's default parameters.
    fn sets_of(&self, values: Option<&[f64]>) -> Vec<Vec<(String, toml::Value)>> {
        let mut out = Vec::new();
        for _ in &self.scenarios {
            for d in 0..self.file.draws {
                let mut sets = vec![(
                    "controller.kind".to_string(),
                    toml::Value::String(self.kind.into()),
                )];
                for (r, &v) in self.params.iter().zip(values.unwrap_or(&[])) {
                    sets.push((format!("controller.{}", r.key), toml::Value::Float(v)));
                }
                if self.file.draws > 1 {
                    sets.push(("uncertainty.seed".into(), toml::Value::Integer(d as i64)));
                }
                out.push(sets);
            }
        }
        out
    }

    fn build_run(
        &self,
        run: usize,
        sets: &[(String, toml::Value)],
    ) -> Result<(Scenario, Setup), crate::scenario::ScenarioError> {
        let i = run / self.file.draws as usize;
        self.scenarios[i].with_values_built_on(self.tables[i].clone(), sets)
    }

    /// The parameter values of a point of the search space.
    pub fn values(&self, p: &[f64]) -> Vec<f64> {
        self.params
            .iter()
            .zip(p)
            .map(|(r, &x)| match r.scale {
                Scale::Log => 10f64.powf(x).clamp(r.low, r.high),
                Scale::Linear => x.clamp(r.low, r.high),
            })
            .collect()
    }

    /// The metrics of every scenario × draw at `values` (None where the
    /// controller refused them).
    pub fn evaluate(&self, values: &[f64]) -> Vec<Option<Metrics>> {
        self.evaluate_sets(&self.sets(values))
    }

    fn evaluate_sets(&self, sets: &[Vec<(String, toml::Value)>]) -> Vec<Option<Metrics>> {
        sets.iter()
            .enumerate()
            .map(|(i, sets)| {
                self.build_run(i, sets)
                    .ok()
                    .map(|(_, setup)| crate::run::run_setup(&setup, &mut |_| {}).1)
            })
            .collect()
    }

    /// One run's score: e_max (in the axis's unit, ° or mm) plus the penalties; +∞ when unbounded,
    /// refused or undefined.
    pub fn score(&self, m: Option<&Metrics>) -> f64 {
        let Some(m) = m else {
            return f64::INFINITY;
        };
        let (Some(e), false) = (m.e_max, m.diverged) else {
            return f64::INFINITY;
        };
        let p = &self.file.penalty;
        let mut s = e;
        if p.chattering > 0.0 {
            s += p.chattering * m.chattering.unwrap_or(f64::INFINITY);
        }
        if let Some(l) = p.u_limit {
            s += p.u_excess * (m.u_max.unwrap_or(f64::INFINITY) - l).max(0.0);
        }
        if s.is_nan() {
            f64::INFINITY
        } else {
            s
        }
    }

    /// The objective at parameter `values`.
    pub fn objective(&self, values: &[f64]) -> f64 {
        self.objective_of(Some(values))
    }

    /// The objective at `values`, or at the kind's default parameters.
    pub fn objective_of(&self, values: Option<&[f64]>) -> f64 {
        let scores: Vec<f64> = self
            .evaluate_sets(&self.sets_of(values))
            .iter()
            .map(|m| self.score(m.as_ref()))
            .collect();
        match self.file.objective {
            Objective::Mean => scores.iter().sum::<f64>() / scores.len() as f64,
            Objective::Worst => scores.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
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
pub(crate) fn not_a_result(reason: &str) -> bool {
    reason.contains("unknown field")
        || reason.contains("not used by")
        || reason.contains("invalid type")
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
    fn bounds(&self) -> (f64, f64) {
        match self.scale {
            Scale::Log => (self.low.log10(), self.high.log10()),
            Scale::Linear => (self.low, self.high),
        }
    }
}

/// The swarm's cost function: the objective at a point of the search
/// space, counted for the progress bar.
struct Problem<'a> {
    tune: &'a Tune,
    progress: &'a indicatif::ProgressBar,
    count: &'a std::sync::atomic::AtomicU64,
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        // Interrupted (crate::cancel): the swarm stops here.
        if crate::cancel::requested() {
            return Err(crate::cancel::Cancelled.into());
        }
        let v = self.tune.objective(&self.tune.values(p));
        self.progress.inc(1);
        self.count
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Ok(v)
    }
}

/// Records the best objective after every generation.
#[derive(Clone, Default)]
struct History(Arc<Mutex<Vec<f64>>>);

impl<I: State<Float = f64>> Observe<I> for History {
    fn observe_iter(&mut self, state: &I, _kv: &KV) -> Result<(), argmin::core::Error> {
        self.0
            .lock()
            .expect("the history lock is never poisoned")
            .push(state.get_best_cost());
        Ok(())
    }
}

/// What a tune found.
#[derive(Debug, Clone, Serialize)]
pub struct TuneResult {
    /// The tuned parameters, by key.
    pub params: Vec<(String, f64)>,
    /// The objective there.
    pub objective: f64,
    /// The objective at the kind's default parameters (its design rules;
    /// for a scenario of the kind tuned, its own `[controller]` table).
    pub defaults: f64,
    /// The swarm found nothing better than the defaults, which are kept:
    /// tuned.toml then carries the default parameters.
    pub kept_defaults: bool,
    /// Evaluations made.
    pub evaluations: u64,
    /// Best objective after each iteration of the swarm (the first after
    /// its second generation: the initial swarm is one).
    pub history: Vec<f64>,
}

/// Runs the swarm (on `threads` threads, default all cores).
pub fn search(
    t: &Tune,
    threads: Option<usize>,
    progress: &indicatif::ProgressBar,
) -> Result<TuneResult> {
    use rand09::SeedableRng;
    let (lo, hi): (Vec<f64>, Vec<f64>) = t.params.iter().map(|r| r.bounds()).unzip();
    let n = t.file.particles;
    // The initial swarm is one generation of evaluations; each iteration
    // another.
    let iters = t.file.budget / n - 1;
    let history = History::default();
    let count = std::sync::atomic::AtomicU64::new(0);
    let work = || -> Result<TuneResult> {
        let solver = ParticleSwarm::new((lo.clone(), hi.clone()), n as usize)
            .with_rng_generator(rand09::rngs::StdRng::seed_from_u64(t.file.seed));
        let problem = Problem {
            tune: t,
            progress,
            count: &count,
        };
        let res = Executor::new(problem, solver)
            .configure(|s| s.max_iters(iters))
            .add_observer(history.clone(), ObserverMode::Always)
            .run()
            .map_err(|e| {
                if crate::cancel::requested() {
                    anyhow::Error::from(crate::cancel::Cancelled)
                } else {
                    anyhow::anyhow!("the particle swarm failed: {e}")
                }
            })?;
        let state = res.state();
        let best = state
            .get_best_param()
            .map(|p| p.position.clone())
            .context("the swarm returned no best particle")?;
        let values = t.values(&best);
        let evaluations = count.load(std::sync::atomic::Ordering::Relaxed);
        Ok(TuneResult {
            params: t.params.iter().map(|r| r.key.clone()).zip(values).collect(),
            objective: state.get_best_cost(),
            defaults: f64::INFINITY,
            kept_defaults: false,
            evaluations,
            history: history.0.lock().expect("unpoisoned").clone(),
        })
    };
    let mut r = match threads {
        Some(k) => rayon::ThreadPoolBuilder::new()
            .num_threads(k.max(1))
            .build()
            .context("building the thread pool")?
            .install(work)?,
        None => work()?,
    };
    // A tune never returns worse than where it starts: the defaults.
    r.defaults = t.objective_of(None);
    if crate::cancel::requested() {
        return Err(crate::cancel::Cancelled.into());
    }
    if r.objective > r.defaults || r.objective.is_nan() {
        r.kept_defaults = true;
        r.objective = r.defaults;
    }
    Ok(r)
}

/// Runs a tune and writes its outputs into `out`: `tuned.toml` (the first
/// scenario with the tuned controller, which `ehservo run` accepts),
/// `convergence.csv` and `convergence.png`, `tune.json`.
pub fn tune_to_dir(
    t: &Tune,
    out: &Path,
    threads: Option<usize>,
    progress: &indicatif::ProgressBar,
    plot: bool,
) -> Result<TuneResult> {
    let r = search(t, threads, progress)?;
    let stage = Staging::new(out)?;
    // The tuned scenario: the first scenario, its controller replaced.
    let values: Vec<f64> = r.params.iter().map(|p| p.1).collect();
    let sets: Vec<(String, toml::Value)> = t.sets_of((!r.kept_defaults).then_some(&values[..]))[0]
        .iter()
        .filter(|(k, _)| k != "uncertainty.seed")
        .cloned()
        .collect();
    let (mut tuned, _) = t.build_run(0, &sets).map_err(anyhow::Error::from)?;
    tuned.description = format!(
        "{} with {} tuned by `ehservo tune` ({})",
        tuned.name, t.kind, t.file.name
    );
    tuned.name = format!("{}-tuned", t.file.name);
    let mut text = format!(
        "# Tuned by `ehservo tune` ({} {}): {} = {:.6} {} over {} evaluations (seed {}).\n",
        SOFTWARE.name,
        SOFTWARE.version,
        match t.file.objective {
            Objective::Mean => "mean score",
            Objective::Worst => "worst score",
        },
        r.objective,
        t.axis.unit(),
        r.evaluations,
        t.file.seed
    );
    text.push_str(&toml::to_string(&tuned).context("writing tuned.toml")?);
    write_atomic(&stage.path().join("tuned.toml"), text.as_bytes())?;
    let mut csv = String::from("iteration,evaluations,best_objective\n");
    for (g, b) in r.history.iter().enumerate() {
        csv.push_str(&format!("{},{},{b}\n", g + 1, evaluations_after(t, g)));
    }
    write_atomic(&stage.path().join("convergence.csv"), csv.as_bytes())?;
    let json = serde_json::json!({
        "software": SOFTWARE,
        "tune": t.file,
        "kind": t.kind,
        "result": r,
        "unit": t.axis.unit(),
    });
    write_atomic(
        &stage.path().join("tune.json"),
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    if plot {
        convergence_figure(t, &r).png(&stage.path().join("convergence.png"))?;
    }
    stage.commit()?;
    Ok(r)
}

/// Evaluations spent when the `g`-th history entry (0-based) was taken:
/// the initial swarm and `g + 1` iterations.
fn evaluations_after(t: &Tune, g: usize) -> u64 {
    (g as u64 + 2) * t.file.particles
}

/// The best objective against the evaluations spent.
fn convergence_figure(t: &Tune, r: &TuneResult) -> Figure {
    let (x, y): (Vec<f64>, Vec<f64>) = r
        .history
        .iter()
        .enumerate()
        .filter(|(_, b)| b.is_finite())
        .map(|(g, &b)| (evaluations_after(t, g) as f64, b))
        .unzip();
    Figure {
        title: format!(
            "{} — {} tuned by particle swarm ({} particles, seed {})",
            t.file.name, t.kind, t.file.particles, t.file.seed
        ),
        panels: vec![Panel {
            title: format!(
                "best objective: {:.5}{}{}",
                r.objective,
                t.axis.suffix(),
                if r.kept_defaults {
                    " — the defaults, kept: the swarm found nothing better".to_string()
                } else {
                    format!(" (the kind's defaults: {:.5})", r.defaults)
                }
            ),
            x_label: "evaluations".into(),
            y_label: format!("objective ({} + penalties)", t.axis.unit()),
            series: vec![Series::new("best so far", x, y, 0)],
            log_y: false,
            ..Default::default()
        }],
        ..Default::default()
    }
}
