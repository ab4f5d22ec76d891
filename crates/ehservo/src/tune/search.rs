//! The search: argmin's particle swarm over the tune's ranges, and its
//! outputs (tuned.toml, convergence.csv/png, tune.json).

use super::{Objective, Tune};
use crate::output::{write_atomic, Staging, SOFTWARE};
use crate::plot::{Figure, Panel, Series};
use anyhow::{Context, Result};
use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{CostFunction, Executor, State, KV};
use argmin::solver::particleswarm::ParticleSwarm;
use serde::Serialize;
use std::path::Path;
use std::sync::{Arc, Mutex};

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
    /// tuned.toml then carries the default parameters, and `params` are
    /// the defaults' values on the first scenario (given in its
    /// `[controller]` or designed there, [`crate::scenario::Loop::designed`]).
    pub kept_defaults: bool,
    /// When the defaults are kept: the swarm's best candidate, which was
    /// no better (or was rejected: objective +∞), with its objective. It
    /// is not a result; it says what the search reached.
    pub swarm_best: Option<SwarmBest>,
    /// Evaluations made.
    pub evaluations: u64,
    /// Best objective after each iteration of the swarm (the first after
    /// its second generation: the initial swarm is one).
    pub history: Vec<f64>,
    /// The chosen parameters run again, longer and over more draws
    /// (None: no candidate passed, nothing was chosen).
    pub verification: Option<super::Verification>,
}

/// The swarm's best candidate when it is not the result.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SwarmBest {
    /// Its parameters, by key.
    pub params: Vec<(String, f64)>,
    /// Its objective (+∞: rejected).
    pub objective: f64,
}

impl TuneResult {
    /// A candidate passed (a finite objective) and the choice passed its
    /// verification.
    pub fn accepted(&self) -> bool {
        self.objective.is_finite() && self.verification.as_ref().is_some_and(|v| v.passed)
    }

    /// Why the result is not accepted, in one sentence naming the numbers;
    /// None when it is.
    pub fn failure(&self, t: &Tune) -> Option<String> {
        if !self.objective.is_finite() {
            let r = &t.file.reject;
            let margins = if r.asks_margins() && t.is_linear() {
                format!(
                    ", or its loop was unstable or had less than {} dB or {}° of margin (`[reject]`)",
                    r.gain_margin_db, r.phase_margin_deg
                )
            } else {
                String::new()
            };
            return Some(format!(
                "no candidate passed: every one of {} evaluations (and the kind's defaults) diverged, was refused, hit an end stop, oscillated after the transient or saturated in more than {} % of the samples on some scenario × draw{margins}",
                self.evaluations,
                100.0 * r.saturation_share
            ));
        }
        match &self.verification {
            Some(v) if !v.passed => Some(format!(
                "the chosen {} parameters failed: {}",
                t.kind,
                v.summary(t.axis.suffix())
            )),
            _ => None,
        }
    }
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
            swarm_best: None,
            evaluations,
            history: history.0.lock().expect("unpoisoned").clone(),
            verification: None,
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
    // No finite objective anywhere (every candidate rejected): the
    // defaults are kept, and the result is not accepted.
    if r.objective > r.defaults || !r.objective.is_finite() {
        r.kept_defaults = true;
        r.swarm_best = Some(SwarmBest {
            params: std::mem::replace(&mut r.params, t.default_values()),
            objective: r.objective,
        });
        r.objective = r.defaults;
    }
    if r.objective.is_finite() {
        let values: Vec<f64> = r.params.iter().map(|p| p.1).collect();
        r.verification = Some(t.verify((!r.kept_defaults).then_some(&values[..])));
    }
    if crate::cancel::requested() {
        return Err(crate::cancel::Cancelled.into());
    }
    Ok(r)
}

/// Runs a tune and writes its outputs into `out`: `tuned.toml` (the first
/// scenario with the tuned controller, which `ehservo run` accepts; only
/// when the result is accepted, [`TuneResult::accepted`]),
/// `convergence.csv` and `convergence.png`, `tune.json` (with the
/// verification and, when not accepted, why).
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
    let mut tuned = t
        .build_run(0, &sets)
        .map_err(anyhow::Error::from)?
        .scenario()
        .clone();
    tuned.description = format!(
        "{} with {} tuned by `ehservo tune` ({})",
        tuned.name, t.kind, t.file.name
    );
    tuned.name = format!("{}-tuned", t.file.name);
    let failure = r.failure(t);
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
    if let Some(v) = &r.verification {
        text.push_str(&format!("# {}\n", v.summary(t.axis.suffix())));
    }
    text.push_str(&toml::to_string(&tuned).context("writing tuned.toml")?);
    if failure.is_none() {
        write_atomic(&stage.path().join("tuned.toml"), text.as_bytes())?;
    }
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
        "accepted": failure.is_none(),
        "failure": failure,
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
