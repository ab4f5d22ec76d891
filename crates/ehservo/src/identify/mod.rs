//! `ehservo identify`: from logged (t, u, y) data to a scenario.
//!
//! One file or several (estimation), and optionally others for validation
//! (`--validate`), each read and checked by [`data`]. Then:
//!
//! 1. the nonparametric frequency response of each estimation file
//!    ([`frf`]: Welch's H1 with its coherence; the indirect estimate from
//!    the reference when the file has one);
//! 2. the linear third-order model (8) by output error ([`oe`]);
//! 3. the grey-box fit of the physical model (1)–(6) ([`greybox`]; rotary
//!    data only: the cylinder plant exists, a grey-box of it does not yet);
//! 4. for each fit: every estimate's standard error and 95 % interval, the
//!    parameters the data cannot identify ([`fit`]), NRMSE on the
//!    estimation and validation data, residual whiteness and
//!    residual–input cross-correlation ([`stats`]);
//! 5. the spread of the estimates over experiments (each fitted alone) or
//!    over bootstrap resamples, as the bounds `bound_a`, `bound_b` of the
//!    paper's assumption A1 ([`Bounds`]);
//! 6. the identified scenario, the JSON report, CSV tables and plots
//!    ([`report`]).
//!
//! The method, the CSV layout and the commands: docs/identification.md.
//!
//! Here: the request ([`Options`]), the results' types and the run
//! ([`identify`]); the shared fit passes in `passes`, the derived
//! quantities in `derived`, the spread and bounds in `bounds`, the
//! grey-box's start and the identified scenario in `scenario`.

pub mod data;
pub mod excite;
pub mod fit;
pub mod frf;
pub mod greybox;
pub mod greybox_axis;
pub mod model;
pub mod oe;
pub mod report;
pub mod stats;

mod bounds;
mod derived;
mod passes;
mod scenario;

pub use bounds::Bounds;

use crate::error::InputError;
use crate::scenario::{Loop, Scenario};
use anyhow::Context;
use bounds::{spread, Fitted};
use data::{Axis, ColumnMap, Experiment, ReadOptions};
use derived::{greybox_derived, linear_derived};
use ehservo_core::servo::{Load, ServoParams};
use fit::{FitOptions, FitReport, Param, Problem, Status};
use frf::Frf;
use model::{OutputError, SimOut, Weights};
use passes::{apply_fix, experiment_fit, fit_weighted, nuisance, validate};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use scenario::{effective_linear, identified_scenario, match_coefficients};
use serde::Serialize;
use std::path::PathBuf;

/// Most samples over all files: 10⁷ (three hours at 1 kHz).
pub const MAX_SAMPLES: usize = 10_000_000;
/// Most RK4 steps of one simulation of every estimation file: 5·10⁷.
pub const MAX_STEPS_PER_EVALUATION: usize = 50_000_000;
/// Most bootstrap resamples.
pub const MAX_BOOTSTRAP: usize = 1000;

/// What `identify` is asked to do.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// The estimation files.
    pub files: Vec<PathBuf>,
    /// The validation files.
    pub validate: Vec<PathBuf>,
    /// The column mapping.
    pub map: ColumnMap,
    /// Reading checks.
    pub read: ReadOptions,
    /// The prior scenario (the paper's Fig. 2 case when absent).
    pub prior: Option<PathBuf>,
    /// `--set` overrides of the prior.
    pub set: Vec<String>,
    /// `--fix KEY=VALUE`.
    pub fix: Vec<(String, f64)>,
    /// `--free KEY,…` of the grey-box (default [`greybox::DEFAULT_FREE`]).
    pub free: Option<Vec<String>>,
    /// d1, d2 in the linear model.
    pub load_terms: bool,
    /// Welch segment length (default [`frf::default_segment`]).
    pub segment: Option<usize>,
    /// The fitting engine's settings.
    pub fit: FitOptions,
    /// Bootstrap resamples (0: none).
    pub bootstrap: usize,
    /// Seed of the bootstrap.
    pub seed: u64,
    /// Skip the grey-box fit.
    pub no_greybox: bool,
    /// Lags of the residual tests.
    pub lags: usize,
}

/// A derived quantity with its standard error (delta method).
#[derive(Debug, Clone, Serialize)]
pub struct Derived {
    /// Key.
    pub key: String,
    /// Unit.
    pub unit: String,
    /// Value.
    pub value: f64,
    /// Standard error, from the free parameters' covariance.
    pub se: Option<f64>,
    /// value ± 1.96·se.
    pub ci95: Option<[f64; 2]>,
}

/// One experiment under one fitted model.
#[derive(Debug, Clone, Serialize)]
pub struct ExperimentFit {
    /// The file.
    pub file: String,
    /// 100·‖y − ŷ‖/‖y − ȳ‖ (%).
    pub nrmse_pct: f64,
    /// 100 − NRMSE (%).
    pub fit_pct: f64,
    /// Position residual RMS (rad or m).
    pub residual_rms: f64,
    /// Residual tests.
    pub residual_tests: stats::ResidualTests,
    /// The initial position used (fitted).
    pub theta0: f64,
    /// The simulated outputs.
    #[serde(skip)]
    pub sim: SimOut,
}

/// One fitted model.
#[derive(Debug, Clone, Serialize)]
pub struct ModelResult {
    /// `"linear"` or `"greybox"`.
    pub model: &'static str,
    /// The fit.
    pub fit: FitReport,
    /// Quantities derived from the estimates.
    pub derived: Vec<Derived>,
    /// The estimation files.
    pub estimation: Vec<ExperimentFit>,
    /// The validation files.
    pub validation: Vec<ExperimentFit>,
    /// The channels' weights (1/σ).
    pub weights: Weights,
    /// How the fit started.
    pub start: String,
}

impl ModelResult {
    /// A derived quantity.
    pub fn derived(&self, key: &str) -> Option<&Derived> {
        self.derived.iter().find(|d| d.key == key)
    }
}

/// Everything `identify` found.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The estimation experiments.
    pub experiments: Vec<Experiment>,
    /// The validation experiments.
    pub validation: Vec<Experiment>,
    /// Per estimation file: H1, and the indirect estimate when it has a reference.
    pub frf: Vec<(Frf, Option<Frf>)>,
    /// The linear model.
    pub linear: ModelResult,
    /// The grey-box model.
    pub greybox: Option<ModelResult>,
    /// The bounds of A1.
    pub bounds: Option<Bounds>,
    /// The identified scenario (rotary data).
    pub scenario: Option<Scenario>,
    /// The prior scenario, built.
    pub prior: Loop,
    /// Things the reader should know.
    pub notes: Vec<String>,
    /// The linear model's settings (for the response over the FRF).
    pub linear_model: oe::Linear,
}

fn bad(msg: String) -> anyhow::Error {
    anyhow::Error::from(InputError::Request(msg))
}

/// The keys of the linear model.
pub fn linear_keys(load_terms: bool) -> Vec<&'static str> {
    let mut k = vec!["a1", "a2", "a3", "b"];
    if load_terms {
        k.extend(["d1", "d2"]);
    }
    k
}

/// Reads every file and checks the work before any of it.
fn read_all(opts: &Options) -> anyhow::Result<(Vec<Experiment>, Vec<Experiment>)> {
    if opts.files.is_empty() {
        return Err(bad("identify: no data file given".into()));
    }
    let read = |p: &PathBuf| data::read(p, &opts.map, opts.read);
    let exps = opts
        .files
        .iter()
        .map(read)
        .collect::<anyhow::Result<Vec<_>>>()?;
    let vals = opts
        .validate
        .iter()
        .map(read)
        .collect::<anyhow::Result<Vec<_>>>()?;
    let axis = exps[0].axis;
    if let Some(e) = exps.iter().chain(&vals).find(|e| e.axis != axis) {
        return Err(bad(format!(
            "{}: column `{}`: a {} position, where {} has a {} one: every file must measure the same axis",
            e.file,
            e.y.column,
            e.axis.unit(),
            exps[0].file,
            axis.unit()
        )));
    }
    let total: usize = exps.iter().chain(&vals).map(Experiment::len).sum();
    if total > MAX_SAMPLES {
        return Err(bad(format!(
            "identify: {total} samples over all files, more than the limit of {MAX_SAMPLES}"
        )));
    }
    if opts.bootstrap > MAX_BOOTSTRAP {
        return Err(bad(format!(
            "--bootstrap {}: at most {MAX_BOOTSTRAP}",
            opts.bootstrap
        )));
    }
    Ok((exps, vals))
}

/// The prior scenario, built, and checked against the data before any
/// fit: a `--prior`'s axis must be the data's, and on rotary data the scenario
/// `identify` will write from it must be valid at the prior's own
/// parameters (a refusal names `--prior` and its file).
fn prior(opts: &Options, axis: Axis) -> anyhow::Result<Loop> {
    let flag = || match &opts.prior {
        Some(p) => format!("--prior {}", p.display()),
        None => "the default prior (the paper's Fig. 2 case)".into(),
    };
    let prior = match &opts.prior {
        Some(p) => crate::formats::load(p, &opts.set).with_context(flag)?,
        None => Loop::parse_with("name = \"prior\"", "<the paper's Fig. 2 case>", &opts.set)?,
    };
    let (pa, model) = (prior.axis(), prior.scenario().plant.model());
    // The default prior is only the linear fit's start on linear data.
    if opts.prior.is_some() && (pa == ehservo_sim::axis::Axis::Linear) != (axis == Axis::Linear) {
        return Err(bad(format!(
            "{}: a {} plant (plant.model = \"{model}\"), where the data measure a {} axis ({}): give a prior of the data's axis",
            flag(),
            pa.name(),
            match axis {
                Axis::Rotary => "rotary",
                Axis::Linear => "linear",
            },
            axis.unit()
        )));
    }
    if axis == Axis::Rotary && !opts.no_greybox {
        let at_prior = greybox::to_vec(&prior.model().params, &prior.model().load);
        identified_scenario(&prior, &at_prior, None, &opts.files).map_err(|e| {
            bad(format!(
                "{}: the identified scenario written from it would be refused: {e:#}",
                flag()
            ))
        })?;
    }
    Ok(prior)
}

/// Runs the identification (no file written).
pub fn identify(opts: &Options) -> anyhow::Result<Outcome> {
    let (exps, vals) = read_all(opts)?;
    let axis = exps[0].axis;
    let prior = prior(opts, axis)?;
    let mut notes = Vec::new();
    let seg = welch_segment(opts, &exps)?;
    // 1. Nonparametric estimates.
    let frfs = nonparametric(&exps, seg);
    // 2. The linear model.
    let k = prior.model().load.wavenumber;
    if opts.load_terms && !(k.is_finite() && k > 0.0) {
        return Err(bad(format!(
            "--load-terms: the prior's load.wavenumber is {k}: the load terms need k > 0 (set it with --set load.wavenumber=K)"
        )));
    }
    let job = Job {
        opts,
        exps: &exps,
        vals: &vals,
        unit: axis.unit(),
        pp: prior.model().params,
        pl: prior.model().load,
    };
    let (linear, linear_result) = job.fit_linear(&frfs, &mut notes)?;
    // 3. The grey-box model.
    let mut greybox_result = None;
    let mut gb_model = None;
    let mut axis_model = None;
    if axis == Axis::Linear && !opts.no_greybox {
        if !matches!(exps[0].u.unit, "" | "V") {
            notes.push(format!("the input is in {}, not the command in V that the prior's actuator and valve take: no grey-box and no identified scenario; the linear model is fitted", exps[0].u.unit));
        } else if opts.prior.is_some() {
            let (model, result) = job.fit_axis_greybox(&prior, &linear_result, &mut notes)?;
            greybox_result = Some(result);
            axis_model = Some(model);
        } else {
            notes.push("linear-axis data without --prior: no grey-box and no identified scenario (give the axis's scenario, e.g. --prior scenarios/cylinders/slide.toml); the linear model is fitted".into());
        }
    } else if !opts.no_greybox {
        let (model, result) = job.fit_greybox(&linear, &linear_result, &mut notes)?;
        greybox_result = Some(result);
        gb_model = Some(model);
    }
    // 4. The spread and the bounds.
    let fitted = Fitted {
        linear: &linear,
        lin: &linear_result,
        gb: gb_model.as_ref(),
        // The spread of a linear axis is the linear model's.
        gbr: greybox_result.as_ref().filter(|_| gb_model.is_some()),
    };
    let bounds = spread(opts, &exps, &fitted, &job.pl, opts.load_terms, k)?;
    // 5. The scenario.
    let scenario = match (&greybox_result, &axis_model) {
        (Some(g), Some(m)) if g.fit.converged => Some(greybox_axis::identified_scenario(
            m,
            &g.fit,
            bounds.as_ref(),
            &opts.files,
        )?),
        (Some(g), None) if g.fit.converged => Some(identified_scenario(
            &prior,
            &g.fit.values(),
            bounds.as_ref(),
            &opts.files,
        )?),
        _ => None,
    };
    Ok(Outcome {
        experiments: exps,
        validation: vals,
        frf: frfs,
        linear: linear_result,
        greybox: greybox_result,
        bounds,
        scenario,
        prior,
        notes,
        linear_model: linear,
    })
}

/// The Welch segment length (`--segment`, or the default for the shortest
/// file), which every estimation file must hold at least once.
fn welch_segment(opts: &Options, exps: &[Experiment]) -> anyhow::Result<usize> {
    let min_n = exps.iter().map(Experiment::len).min().unwrap_or(0);
    let seg = opts.segment.unwrap_or_else(|| frf::default_segment(min_n));
    if !(16..=1 << 20).contains(&seg) {
        return Err(bad(format!(
            "--segment {seg}: must be between 16 and 1048576 samples"
        )));
    }
    if let Some(e) = exps.iter().find(|e| e.len() < seg) {
        return Err(bad(format!(
            "{}: {} rows, fewer than one Welch segment of {seg} samples (--segment)",
            e.file,
            e.len()
        )));
    }
    Ok(seg)
}

/// The nonparametric estimates of each estimation file: H1, and the
/// indirect estimate when the file has a reference that moves.
fn nonparametric(exps: &[Experiment], seg: usize) -> Vec<(Frf, Option<Frf>)> {
    exps.iter()
        .map(|e| {
            let h1 = frf::h1(&e.u.values, &e.y.values, e.h, seg);
            let ind = e
                .reference
                .as_ref()
                .filter(|r| moves(&r.values))
                .map(|r| frf::indirect(&r.values, &e.u.values, &e.y.values, e.h, seg));
            (h1, ind)
        })
        .collect()
}

/// One identification's request, its data and the prior's physical
/// parameters: what both models' fits read.
struct Job<'a> {
    opts: &'a Options,
    exps: &'a [Experiment],
    vals: &'a [Experiment],
    /// The position's unit (rad or m).
    unit: &'static str,
    /// The prior's servo parameters.
    pp: ServoParams,
    /// The prior's load.
    pl: Load,
}

/// A start of the linear fit: its name, its (a1, a2, a3, b) and, when it
/// has them, u_offset and the θ0s.
type Start = (&'static str, [f64; 4], Option<(f64, Vec<f64>)>);

/// What the linear model's starts share: the data, the load terms and the
/// prior's, and the substeps of the prior's dynamics.
struct LinearStarts<'a> {
    exps: &'a [Experiment],
    load_terms: bool,
    /// The load's wavenumber.
    k: f64,
    /// The prior's load terms (d1, d2).
    prior_d: [f64; 2],
    /// The position's unit and the command's.
    unit: &'static str,
    u_unit: &'static str,
    /// The model at the prior's coefficients.
    prior_model: oe::Linear,
}

impl Job<'_> {
    /// The linear model (8): the best of its starts, fitted, with its
    /// derived quantities and its fit on every file.
    fn fit_linear(
        &self,
        frfs: &[(Frf, Option<Frf>)],
        notes: &mut Vec<String>,
    ) -> anyhow::Result<(oe::Linear, ModelResult)> {
        let (opts, exps) = (self.opts, self.exps);
        let (load_terms, k) = (opts.load_terms, self.pl.wavenumber);
        let (prior_lin, prior_d) = self.prior_linear();
        let candidates = self.linear_candidates(frfs, prior_lin, prior_d);
        // The work, checked before any fit: one evaluation's RK4 steps at the
        // prior's dynamics.
        let prior_model = oe::Linear::new(
            exps,
            load_terms,
            k,
            [prior_lin[0], prior_lin[1], prior_lin[2]],
        );
        check_linear_work(exps, &prior_model)?;
        let starts = LinearStarts {
            exps,
            load_terms,
            k,
            prior_d,
            unit: self.unit,
            // The command's unit (V, A, or m for a spool position; V without a suffix).
            u_unit: match exps[0].u.unit {
                "" => "V",
                u => u,
            },
            prior_model,
        };
        let w0 = OutputError::initial_weights(&starts.prior_model, exps);
        let best = candidates
            .iter()
            .min_by(|a, b| starts.cost(a, w0).total_cmp(&starts.cost(b, w0)))
            .expect("at least the prior");
        let (start_name, mut lp) = (best.0, starts.start_params(best));
        let linear = starts.model_for(best.1);
        let other_keys: Vec<&str> = greybox::KEYS
            .iter()
            .map(|k| k.0)
            .chain(greybox_axis::KEYS.iter().map(|k| k.name))
            .collect();
        apply_fix(&mut lp, &opts.fix, &other_keys)?;
        let nl = linear.n_model();
        let (lrep, lw, _) = fit_weighted(&linear, exps, lp, &opts.fit);
        if lrep.diverged {
            notes.push("the linear model diverged on the data from every start".into());
        }
        let lv = lrep.values();
        let linear_result = ModelResult {
            model: "linear",
            derived: linear_derived(&lrep, load_terms, k),
            estimation: exps
                .iter()
                .enumerate()
                .map(|(i, e)| experiment_fit(&linear, &lv, i, e, opts.lags))
                .collect(),
            validation: validate(
                &linear, &lv, nl, self.vals, lw, &opts.fit, opts.lags, self.unit,
            ),
            weights: lw,
            start: start_name.into(),
            fit: lrep,
        };
        Ok((linear, linear_result))
    }

    /// The prior's coefficients of the linear model, (a1, a2, a3, b) (the
    /// load's share in them unless `--load-terms` fits it apart), and its
    /// load terms (d1, d2).
    fn prior_linear(&self) -> ([f64; 4], [f64; 2]) {
        let (pp, pl) = (self.pp, self.pl);
        let pm = ehservo_core::servo::NominalModel::new(pp, pl);
        let prior_eff = greybox::effective(&pp, &pl);
        let prior_d = [
            pp.d_per_torque() * pl.amplitude,
            pl.amplitude * pl.wavenumber / pp.jt,
        ];
        let prior_lin: [f64; 4] = if self.opts.load_terms {
            let c = pp.coefficients();
            [c.a1, c.a2, c.a3, pm.b_at_rest()]
        } else {
            [prior_eff[0], prior_eff[1], prior_eff[2], pm.b_at_rest()]
        };
        (prior_lin, prior_d)
    }

    /// The linear fit's starts: the frequency-domain fit of the first
    /// file's response (when it has one), the prior's coefficients, and the
    /// grid of denominators (without load terms).
    fn linear_candidates(
        &self,
        frfs: &[(Frf, Option<Frf>)],
        prior_lin: [f64; 4],
        prior_d: [f64; 2],
    ) -> Vec<Start> {
        let (load_terms, k) = (self.opts.load_terms, self.pl.wavenumber);
        let primary = |i: usize| frfs[i].1.as_ref().unwrap_or(&frfs[i].0);
        let levy = oe::frequency_fit(primary(0), self.exps[0].h).map(|mut p| {
            if load_terms {
                p[0] -= prior_d[0] * k;
                p[1] -= prior_d[1];
            }
            p
        });
        let mut candidates: Vec<Start> =
            vec![("the prior scenario's coefficients", prior_lin, None)];
        if let Some(l) = levy {
            candidates.insert(
                0,
                (
                    "the frequency-domain fit (Levy/Sanathanan-Koerner)",
                    l,
                    None,
                ),
            );
        }
        if !load_terms {
            if let Some((c, uo, th)) = oe::grid_start(self.exps) {
                candidates.push((
                    "the grid of denominators (s + p)(s^2 + 2 zeta omega s + omega^2), b by least squares",
                    c,
                    Some((uo, th)),
                ));
            }
        }
        candidates
    }

    /// The grey-box model (1)–(6): its free parameters checked, started at
    /// the prior moved to the linear fit's coefficients, fitted, with its
    /// derived quantities and its fit on every file.
    fn fit_greybox(
        &self,
        linear: &oe::Linear,
        linear_result: &ModelResult,
        notes: &mut Vec<String>,
    ) -> anyhow::Result<(greybox::Physical, ModelResult)> {
        let (opts, exps, pl) = (self.opts, self.exps, self.pl);
        let free = self.greybox_free()?;
        let gp = self.greybox_start(&free, linear, linear_result)?;
        let nk = greybox::KEYS.len();
        let model =
            greybox::Physical::new(exps, pl, &gp.iter().map(|p| p.value).collect::<Vec<_>>());
        let steps: usize = exps
            .iter()
            .zip(&model.substeps)
            .map(|(e, m)| e.len() * m)
            .sum();
        if steps > MAX_STEPS_PER_EVALUATION {
            return Err(bad(format!(
                "identify: {steps} RK4 steps per evaluation of the grey-box, more than the limit of {MAX_STEPS_PER_EVALUATION}"
            )));
        }
        let (grep, gw, _) = fit_weighted(&model, exps, gp, &opts.fit);
        if grep.diverged {
            notes.push("the grey-box model diverged at its start".into());
        }
        let gv = grep.values();
        let result = ModelResult {
            model: "greybox",
            derived: greybox_derived(&grep, &pl),
            estimation: exps
                .iter()
                .enumerate()
                .map(|(i, e)| experiment_fit(&model, &gv, i, e, opts.lags))
                .collect(),
            validation: validate(
                &model, &gv, nk, self.vals, gw, &opts.fit, opts.lags, self.unit,
            ),
            weights: gw,
            start: "the prior scenario, moved to the linear fit's coefficients".into(),
            fit: grep,
        };
        Ok((model, result))
    }

    /// The grey-box's free parameters (`--free`, or the default ones), each
    /// one the grey-box has and the prior can start.
    fn greybox_free(&self) -> anyhow::Result<Vec<String>> {
        let pl = &self.pl;
        let free: Vec<String> = self.opts.free.clone().unwrap_or_else(|| {
            greybox::DEFAULT_FREE
                .iter()
                .map(|s| s.to_string())
                .collect()
        });
        for f in &free {
            if !greybox::KEYS.iter().any(|k| k.0 == f) {
                return Err(bad(format!(
                    "--free {f}: no such grey-box parameter (known: {})",
                    greybox::KEYS
                        .iter()
                        .map(|k| k.0)
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
            if f.starts_with("friction.") && pl.friction.is_none() {
                return Err(bad(format!(
                    "--free {f}: the prior's load has no [load.friction] table"
                )));
            }
            if f == "load.amplitude" && pl.amplitude == 0.0 {
                return Err(bad("--free load.amplitude: the prior's load amplitude is 0; give a nonzero start with --set load.amplitude=A".into()));
            }
        }
        Ok(free)
    }

    /// The grey-box's parameters at their start: the prior's physical
    /// parameters moved to match the linear fit's effective coefficients
    /// where they can, `--fix` applied, the nuisance parameters at the
    /// linear fit's.
    fn greybox_start(
        &self,
        free: &[String],
        linear: &oe::Linear,
        linear_result: &ModelResult,
    ) -> anyhow::Result<Vec<Param>> {
        let (opts, exps) = (self.opts, self.exps);
        let load_terms = opts.load_terms;
        let prior_v = greybox::to_vec(&self.pp, &self.pl);
        let mut gp = greybox::params(&prior_v, free);
        gp.extend(nuisance(exps, self.unit));
        let lin_keys = linear_keys(load_terms);
        apply_fix(&mut gp, &opts.fix, &lin_keys)?;
        let target = effective_linear(linear_result, load_terms, self.pl.wavenumber);
        let start = match_coefficients(&gp, &self.pl, target, &opts.fit);
        for (p, v) in gp.iter_mut().zip(&start) {
            if p.status == Status::Free {
                p.value = *v;
            }
        }
        let (nk, nl) = (greybox::KEYS.len(), linear.n_model());
        let lv = linear_result.fit.values();
        for j in 0..=exps.len() {
            gp[nk + j].value = lv[nl + j];
        }
        Ok(gp)
    }
}

/// One evaluation of the linear model at the prior's dynamics must stay
/// within [`MAX_STEPS_PER_EVALUATION`] RK4 steps.
fn check_linear_work(exps: &[Experiment], prior_model: &oe::Linear) -> anyhow::Result<()> {
    let steps: usize = exps
        .iter()
        .zip(&prior_model.substeps)
        .map(|(e, m)| e.len() * m)
        .sum();
    if steps > MAX_STEPS_PER_EVALUATION {
        return Err(bad(format!(
            "identify: {steps} RK4 steps per evaluation ({} substeps a sample for the prior's dynamics), more than the limit of {MAX_STEPS_PER_EVALUATION}",
            prior_model.substeps.iter().max().unwrap_or(&1)
        )));
    }
    Ok(())
}

impl LinearStarts<'_> {
    /// The linear model's parameters from (a1, a2, a3, b): those, the load
    /// terms at the prior's, and the nuisance parameters.
    fn params(&self, start: [f64; 4]) -> Vec<Param> {
        let (unit, u_unit, prior_d) = (self.unit, self.u_unit, self.prior_d);
        let [a1, a2, a3, b] = start;
        // a1's scale: a2 times the slowest rate the records resolve,
        // 2π/T (a real pole there: a1 = p·ω² ≈ p·a2). At 10⁻⁹·a2, as it
        // was, a start at a1 = 0 made its Jacobian column vanish and a1
        // was "unidentifiable" at every threshold.
        let t = self
            .exps
            .iter()
            .map(|e| e.h * e.len() as f64)
            .fold(f64::INFINITY, f64::min);
        let a1_scale = a1
            .abs()
            .max(a2.abs().max(1.0) * 2.0 * std::f64::consts::PI / t);
        let mut v = vec![
            Param {
                prior: 0.0,
                ..Param::signed("a1", "1/s^3", a1, a1_scale)
            },
            Param::new("a2", "1/s^2", a2.max(1e-9), 1.0),
            Param::new("a3", "1/s", a3.max(1e-9), 1.0),
            Param::signed(
                "b",
                &format!("{unit}/({u_unit}*s^3)"),
                b,
                b.abs().max(1e-300),
            ),
        ];
        if self.load_terms {
            v.push(Param {
                prior: 0.0,
                ..Param::signed(
                    "d1",
                    &format!("{unit}/s^3"),
                    prior_d[0],
                    prior_d[0].abs().max(1e-6 * a2.abs()),
                )
            });
            v.push(Param {
                prior: 0.0,
                ..Param::signed(
                    "d2",
                    "1/s^2",
                    prior_d[1],
                    prior_d[1].abs().max(1e-3 * a2.abs()),
                )
            });
        }
        v.extend(nuisance(self.exps, unit));
        v
    }

    /// A start's parameters, its u_offset and θ0s set when it has them.
    fn start_params(&self, s: &Start) -> Vec<Param> {
        let mut ps = self.params(s.1);
        if let Some((uo, th)) = &s.2 {
            let n = ps.len() - self.exps.len() - 1;
            ps[n].value = *uo;
            for (j, t) in th.iter().enumerate() {
                ps[n + 1 + j].value = *t;
            }
        }
        ps
    }

    /// The model integrated with the substeps of the faster of the prior's
    /// and the start's dynamics.
    fn model_for(&self, a: [f64; 4]) -> oe::Linear {
        let mut m = oe::Linear::new(self.exps, self.load_terms, self.k, [a[0], a[1], a[2]]);
        for (s, p) in m.substeps.iter_mut().zip(&self.prior_model.substeps) {
            *s = (*s).max(*p);
        }
        m
    }

    /// A start's weighted cost (infinite where the model diverges).
    fn cost(&self, s: &Start, w0: Weights) -> f64 {
        let m = self.model_for(s.1);
        let prob = OutputError {
            model: &m,
            experiments: self.exps,
            weights: w0,
        };
        let mut r = Vec::new();
        let v: Vec<f64> = self.start_params(s).iter().map(|p| p.value).collect();
        if prob.residuals(&v, &mut r) {
            r.iter().map(|x| x * x).sum()
        } else {
            f64::INFINITY
        }
    }
}

fn moves(v: &[f64]) -> bool {
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    hi > lo
}

/// Gaussian draws for tests and examples: a seeded stream.
pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    // Box–Muller on two uniforms in (0, 1].
    let u1 = 1.0 - rng.random::<f64>();
    let u2 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}
