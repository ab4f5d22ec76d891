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

pub mod data;
pub mod excite;
pub mod fit;
pub mod frf;
pub mod greybox;
pub mod model;
pub mod oe;
pub mod report;
pub mod stats;

use crate::error::InputError;
use crate::scenario::Scenario;
use data::{Axis, ColumnMap, Experiment, ReadOptions};
use ehservo_core::servo::{Load, ServoParams};
use fit::{FitOptions, FitReport, Param, Problem, Status};
use frf::Frf;
use model::{Model, OutputError, SimOut, Weights};
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
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

/// The spread of the third-order coefficients over experiments or
/// resamples, and the bounds of A1 it gives.
#[derive(Debug, Clone, Serialize)]
pub struct Bounds {
    /// `"experiments"` or `"bootstrap"`.
    pub method: String,
    /// Which model's coefficients.
    pub model: &'static str,
    /// The nominal ā1, ā2, ā3, b̄ (the pooled fit).
    pub nominal: [f64; 4],
    /// Each experiment's or resample's (a1, a2, a3, b).
    pub samples: Vec<[f64; 4]>,
    /// max_k |a_i^k − ā_i|/|ā_i| and its b counterpart, at least the
    /// pooled fit's 95 % half-width: (α1, α2, α3, β) as fractions.
    pub fractions: [f64; 4],
    /// Whether each coefficient's spread counts for `bound_a` (its pooled
    /// relative standard error is below the identifiability threshold).
    pub counted: [bool; 3],
    /// max of the counted α_i fractions.
    pub bound_a: f64,
    /// The β fraction.
    pub bound_b: f64,
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
    /// The prior scenario.
    pub prior: Scenario,
    /// Things the reader should know.
    pub notes: Vec<String>,
    /// The linear model's settings (for the response over the FRF).
    pub linear_model: oe::Linear,
}

fn bad(msg: String) -> anyhow::Error {
    anyhow::Error::from(InputError(msg))
}

/// The keys of the linear model.
pub fn linear_keys(load_terms: bool) -> Vec<&'static str> {
    let mut k = vec!["a1", "a2", "a3", "b"];
    if load_terms {
        k.extend(["d1", "d2"]);
    }
    k
}

/// The nuisance parameters appended to a model's: u_offset, then θ0 of
/// each experiment (`theta0` for one, `theta0_1`, … for several).
fn nuisance(experiments: &[Experiment], unit: &str) -> Vec<Param> {
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
    let u_rms = experiments
        .iter()
        .map(|e| rms(&e.u.values))
        .fold(0.0f64, f64::max);
    let u_unit = match experiments.first().map_or("", |e| e.u.unit) {
        "" => "V",
        u => u,
    };
    let mut v = vec![Param {
        nuisance: true,
        ..Param::signed("u_offset", u_unit, 0.0, u_rms.max(1e-9))
    }];
    for (i, e) in experiments.iter().enumerate() {
        let y = &e.y.values;
        let (lo, hi) = y
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let key = if experiments.len() == 1 {
            "theta0".to_string()
        } else {
            format!("theta0_{}", i + 1)
        };
        v.push(Param {
            nuisance: true,
            ..Param::signed(&key, unit, y[0], (hi - lo).max(1e-9))
        });
    }
    v
}

/// Applies `--fix` to `params`; an unknown key is an error naming the valid ones.
fn apply_fix(params: &mut [Param], fix: &[(String, f64)], other: &[&str]) -> anyhow::Result<()> {
    for (k, v) in fix {
        if let Some(p) = params.iter_mut().find(|p| &p.key == k) {
            if !v.is_finite() || (matches!(p.scale, fit::Scale::Log) && *v <= 0.0) {
                return Err(bad(format!(
                    "--fix {k}={v}: must be finite{}",
                    if matches!(p.scale, fit::Scale::Log) {
                        " and > 0"
                    } else {
                        ""
                    }
                )));
            }
            p.value = *v;
            p.prior = *v;
            p.status = Status::Fixed;
        } else if !other.contains(&k.as_str()) {
            let mut known: Vec<String> = params.iter().map(|p| p.key.clone()).collect();
            known.extend(other.iter().map(|s| s.to_string()));
            return Err(bad(format!(
                "--fix {k}: no such parameter (known: {})",
                known.join(", ")
            )));
        }
    }
    Ok(())
}

/// Fits with the two-pass weights: once with the first weights, again
/// (from there) with 1/RMS of each channel's residual when more than the
/// position is fitted.
fn fit_weighted<M: Model>(
    model: &M,
    experiments: &[Experiment],
    params: Vec<Param>,
    opts: &FitOptions,
) -> (FitReport, Weights, Vec<Param>) {
    let w0 = OutputError::initial_weights(model, experiments);
    let prob = OutputError {
        model,
        experiments,
        weights: w0,
    };
    let rep = fit::fit(&prob, params.clone(), opts);
    let multi = w0.v > 0.0 || w0.p > 0.0;
    let after = |rep: &FitReport| -> Vec<Param> {
        params
            .iter()
            .zip(&rep.estimates)
            .map(|(p, e)| Param {
                value: e.value,
                status: e.status,
                ..p.clone()
            })
            .collect()
    };
    if !multi || rep.diverged {
        let p = after(&rep);
        return (rep, w0, p);
    }
    let w1 = prob.reweighted(&rep.values());
    // The second pass starts where the first ended, with every parameter
    // the first found unidentifiable free again: the balance of channels
    // may change what is identifiable.
    let start: Vec<Param> = params
        .iter()
        .zip(&rep.estimates)
        .map(|(p, e)| Param {
            value: if e.status == Status::Free {
                e.value
            } else {
                p.value
            },
            ..p.clone()
        })
        .collect();
    let prob1 = OutputError {
        model,
        experiments,
        weights: w1,
    };
    let rep1 = fit::fit(&prob1, start, opts);
    let p = after(&rep1);
    (rep1, w1, p)
}

/// Simulates `model` on `exps` with every parameter at `values` but the
/// initial positions, which are fitted (one parameter each, the rest
/// held): the validation of a fitted model.
#[allow(clippy::too_many_arguments)]
fn validate<M: Model>(
    model: &M,
    values: &[f64],
    n_model: usize,
    exps: &[Experiment],
    weights: Weights,
    opts: &FitOptions,
    lags: usize,
    unit: &str,
) -> Vec<ExperimentFit> {
    exps.iter()
        .map(|e| {
            // The model's parameters fixed, u_offset fixed, θ0 free.
            let mut ps: Vec<Param> = values[..=n_model]
                .iter()
                .enumerate()
                .map(|(i, &v)| Param {
                    status: Status::Fixed,
                    ..Param::signed(&format!("p{i}"), "", v, 1.0)
                })
                .collect();
            ps.extend(nuisance(std::slice::from_ref(e), unit).into_iter().skip(1));
            let one = std::slice::from_ref(e);
            let prob = OutputError {
                model,
                experiments: one,
                weights: Weights {
                    v: 0.0,
                    p: 0.0,
                    ..weights
                },
            };
            let rep = fit::fit(&prob, ps, opts);
            let v = rep.values();
            experiment_fit(model, &v, 0, e, lags)
        })
        .collect()
}

/// The fit of experiment `i` at the parameter values `v`.
fn experiment_fit<M: Model>(
    model: &M,
    v: &[f64],
    i: usize,
    e: &Experiment,
    lags: usize,
) -> ExperimentFit {
    let mut sim = SimOut::default();
    let ok = model.simulate(v, i, e, &mut sim);
    if !ok || sim.y.len() != e.len() {
        sim.y = vec![f64::NAN; e.len()];
    }
    let y = &e.y.values;
    let res: Vec<f64> = y.iter().zip(&sim.y).map(|(a, b)| a - b).collect();
    let nrmse = if ok {
        stats::nrmse_pct(y, &sim.y)
    } else {
        f64::INFINITY
    };
    let rms = (res.iter().map(|r| r * r).sum::<f64>() / res.len().max(1) as f64).sqrt();
    let tests = stats::residual_tests(if ok { &res } else { &[] }, &e.u.values, lags);
    ExperimentFit {
        file: e.file.clone(),
        nrmse_pct: nrmse,
        fit_pct: 100.0 - nrmse,
        residual_rms: if ok { rms } else { f64::INFINITY },
        residual_tests: tests,
        theta0: sim.y.first().copied().unwrap_or(f64::NAN),
        sim,
    }
}

/// The delta-method standard errors of `f(values)` from the fit's covariance.
fn delta(rep: &FitReport, keys: &[(&str, &str)], f: &dyn Fn(&[f64]) -> Vec<f64>) -> Vec<Derived> {
    let v = rep.values();
    let base = f(&v);
    let free: Vec<usize> = rep
        .free_keys
        .iter()
        .filter_map(|k| rep.estimates.iter().position(|e| &e.key == k))
        .collect();
    let grads: Vec<Vec<f64>> = free
        .iter()
        .map(|&j| {
            let h = 1e-6 * v[j].abs().max(1e-300);
            let (mut a, mut b) = (v.clone(), v.clone());
            a[j] += h;
            b[j] -= h;
            f(&a)
                .iter()
                .zip(f(&b))
                .map(|(x, y)| (x - y) / (2.0 * h))
                .collect()
        })
        .collect();
    let ok = !rep.covariance.is_empty() && rep.covariance.iter().flatten().all(|c| c.is_finite());
    keys.iter()
        .enumerate()
        .map(|(q, &(key, unit))| {
            let se = ok.then(|| {
                let mut s = 0.0;
                for a in 0..free.len() {
                    for b in 0..free.len() {
                        s += grads[a][q] * rep.covariance[a][b] * grads[b][q];
                    }
                }
                s.max(0.0).sqrt()
            });
            let value = base[q];
            Derived {
                key: key.into(),
                unit: unit.into(),
                value,
                se: se.filter(|s| s.is_finite()),
                ci95: se
                    .filter(|s| s.is_finite())
                    .map(|s| [value - stats::Z95 * s, value + stats::Z95 * s]),
            }
        })
        .collect()
}

/// ω_n, ζ of the complex pair of s³ + a3·s² + a2·s + a1 (NaN without one).
fn pair_of(a: [f64; 3]) -> [f64; 2] {
    oe::pair(a).map_or([f64::NAN; 2], |(w, z, _)| [w, z])
}

/// The linear model's derived quantities.
fn linear_derived(rep: &FitReport, load_terms: bool, k: f64) -> Vec<Derived> {
    delta(
        rep,
        &[("omega_n_rad_s", "rad/s"), ("zeta", ""), ("f_n_Hz", "Hz")],
        &|v| {
            let mut a = [v[0], v[1], v[2]];
            if load_terms {
                a[0] += v[4] * k;
                a[1] += v[5];
            }
            let [w, z] = pair_of(a);
            vec![w, z, w / (2.0 * std::f64::consts::PI)]
        },
    )
}

/// The grey-box's derived quantities: (9)'s coefficients at P_l = 0, the
/// load terms, ω_h = √(4βe·Dm²/(Vt·Jt)) and the effective pair.
fn greybox_derived(rep: &FitReport, load: &Load) -> Vec<Derived> {
    let nk = greybox::KEYS.len();
    delta(
        rep,
        &[
            ("a1", "1/s^3"),
            ("a2", "1/s^2"),
            ("a3", "1/s"),
            ("b", "rad/(V*s^3)"),
            ("d1", "rad/s^3"),
            ("d2", "1/s^2"),
            ("omega_h_rad_s", "rad/s"),
            ("f_h_Hz", "Hz"),
            ("omega_n_rad_s", "rad/s"),
            ("zeta", ""),
        ],
        &|v| {
            let (p, l) = greybox::from_vec(&v[..nk], load);
            let c = p.coefficients();
            let b = ehservo_core::servo::NominalModel::new(p, l).b_at_rest();
            let wh = (4.0 * p.beta_e * p.dm * p.dm / (p.vt * p.jt)).sqrt();
            let [w, z] = pair_of(greybox::effective(&p, &l));
            vec![
                c.a1,
                c.a2,
                c.a3,
                b,
                p.d_per_torque() * l.amplitude,
                l.amplitude * l.wavenumber / p.jt,
                wh,
                wh / (2.0 * std::f64::consts::PI),
                w,
                z,
            ]
        },
    )
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

/// The prior scenario.
fn prior(opts: &Options) -> anyhow::Result<Scenario> {
    Ok(match &opts.prior {
        Some(p) => Scenario::load(p, &opts.set)?,
        None => Scenario::parse_with("name = \"prior\"", "<the paper's Fig. 2 case>", &opts.set)?,
    })
}

/// Runs the identification (no file written).
pub fn identify(opts: &Options) -> anyhow::Result<Outcome> {
    let (exps, vals) = read_all(opts)?;
    let prior = prior(opts)?;
    let axis = exps[0].axis;
    let unit = axis.unit();
    let mut notes = Vec::new();
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
    // 1. Nonparametric estimates.
    let frfs: Vec<(Frf, Option<Frf>)> = exps
        .iter()
        .map(|e| {
            let h1 = frf::h1(&e.u.values, &e.y.values, e.h, seg);
            let ind = e
                .reference
                .as_ref()
                .filter(|r| moves(&r.values))
                .map(|r| frf::indirect(&r.values, &e.u.values, &e.y.values, e.h, seg));
            (h1, ind)
        })
        .collect();
    // 2. The linear model.
    let load_terms = opts.load_terms;
    let k = prior.load_model().wavenumber;
    if load_terms && !(k.is_finite() && k > 0.0) {
        return Err(bad(format!(
            "--load-terms: the prior's load.wavenumber is {k}: the load terms need k > 0 (set it with --set load.wavenumber=K)"
        )));
    }
    let pp = prior.servo();
    let pl = prior.load_model();
    let pm = ehservo_core::servo::NominalModel::new(pp, pl);
    let prior_eff = greybox::effective(&pp, &pl);
    let prior_d = [
        pp.d_per_torque() * pl.amplitude,
        pl.amplitude * pl.wavenumber / pp.jt,
    ];
    let prior_lin: [f64; 4] = if load_terms {
        let c = pp.coefficients();
        [c.a1, c.a2, c.a3, pm.b_at_rest()]
    } else {
        [prior_eff[0], prior_eff[1], prior_eff[2], pm.b_at_rest()]
    };
    let primary = |i: usize| frfs[i].1.as_ref().unwrap_or(&frfs[i].0);
    let levy = oe::frequency_fit(primary(0), exps[0].h).map(|mut p| {
        if load_terms {
            p[0] -= prior_d[0] * k;
            p[1] -= prior_d[1];
        }
        p
    });
    // The command's unit (V, A, or m for a spool position; V without a suffix).
    let u_unit = match exps[0].u.unit {
        "" => "V",
        u => u,
    };
    let lin_params = |start: [f64; 4]| -> Vec<Param> {
        let [a1, a2, a3, b] = start;
        let mut v = vec![
            Param {
                prior: 0.0,
                ..Param::signed("a1", "1/s^3", a1, a1.abs().max(1e-9 * a2.abs().max(1.0)))
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
        if load_terms {
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
        v.extend(nuisance(&exps, unit));
        v
    };
    // Each start: its (a1, a2, a3, b) and, when it has them, u_offset and
    // the θ0s.
    type Start = (&'static str, [f64; 4], Option<(f64, Vec<f64>)>);
    let mut candidates: Vec<Start> = vec![("the prior scenario's coefficients", prior_lin, None)];
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
        if let Some((c, uo, th)) = oe::grid_start(&exps) {
            candidates.push((
                "the grid of denominators s(s^2 + 2 zeta omega s + omega^2), b by least squares",
                c,
                Some((uo, th)),
            ));
        }
    }
    let start_params = |s: &Start| -> Vec<Param> {
        let mut ps = lin_params(s.1);
        if let Some((uo, th)) = &s.2 {
            let n = ps.len() - exps.len() - 1;
            ps[n].value = *uo;
            for (j, t) in th.iter().enumerate() {
                ps[n + 1 + j].value = *t;
            }
        }
        ps
    };
    // The work, checked before any fit: one evaluation's RK4 steps at the
    // prior's dynamics.
    let prior_model = oe::Linear::new(
        &exps,
        load_terms,
        k,
        [prior_lin[0], prior_lin[1], prior_lin[2]],
    );
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
    // The model integrated with the substeps of the faster of the prior's
    // and the start's dynamics.
    let model_for = |a: [f64; 4]| -> oe::Linear {
        let mut m = oe::Linear::new(&exps, load_terms, k, [a[0], a[1], a[2]]);
        for (s, p) in m.substeps.iter_mut().zip(&prior_model.substeps) {
            *s = (*s).max(*p);
        }
        m
    };
    let w0 = OutputError::initial_weights(&prior_model, &exps);
    let cost = |s: &Start| -> f64 {
        let m = model_for(s.1);
        let prob = OutputError {
            model: &m,
            experiments: &exps,
            weights: w0,
        };
        let mut r = Vec::new();
        let v: Vec<f64> = start_params(s).iter().map(|p| p.value).collect();
        if prob.residuals(&v, &mut r) {
            r.iter().map(|x| x * x).sum()
        } else {
            f64::INFINITY
        }
    };
    let best = candidates
        .iter()
        .min_by(|a, b| cost(a).total_cmp(&cost(b)))
        .expect("at least the prior");
    let (start_name, mut lp) = (best.0, start_params(best));
    let linear = model_for(best.1);
    let other_keys: Vec<&str> = greybox::KEYS.iter().map(|k| k.0).collect();
    apply_fix(&mut lp, &opts.fix, &other_keys)?;
    let nl = linear.n_model();
    let (lrep, lw, _) = fit_weighted(&linear, &exps, lp, &opts.fit);
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
        validation: validate(&linear, &lv, nl, &vals, lw, &opts.fit, opts.lags, unit),
        weights: lw,
        start: start_name.into(),
        fit: lrep,
    };
    // 3. The grey-box model.
    let mut greybox_result = None;
    let mut gb_model = None;
    if axis == Axis::Linear {
        notes.push("linear-axis data: the grey-box fit is of the paper's rotary model (1)-(6) and is not made for a cylinder (the cylinder plant exists, a grey-box of it does not yet), so neither is the identified scenario; the linear model is fitted".into());
    } else if !opts.no_greybox {
        let free: Vec<String> = opts.free.clone().unwrap_or_else(|| {
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
        let prior_v = greybox::to_vec(&pp, &pl);
        let mut gp = greybox::params(&prior_v, &free);
        gp.extend(nuisance(&exps, unit));
        let lin_keys = linear_keys(load_terms);
        apply_fix(&mut gp, &opts.fix, &lin_keys)?;
        // The start: the prior's physical parameters moved to match the
        // linear fit's effective coefficients where they can.
        let target = effective_linear(&linear_result, load_terms, k);
        let start = match_coefficients(&gp, &pl, target, &opts.fit);
        for (p, v) in gp.iter_mut().zip(&start) {
            if p.status == Status::Free {
                p.value = *v;
            }
        }
        // The nuisance parameters start at the linear fit's.
        let nk = greybox::KEYS.len();
        for j in 0..=exps.len() {
            gp[nk + j].value = lv[nl + j];
        }
        let model =
            greybox::Physical::new(&exps, pl, &gp.iter().map(|p| p.value).collect::<Vec<_>>());
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
        let (grep, gw, _) = fit_weighted(&model, &exps, gp, &opts.fit);
        if grep.diverged {
            notes.push("the grey-box model diverged at its start".into());
        }
        let gv = grep.values();
        greybox_result = Some(ModelResult {
            model: "greybox",
            derived: greybox_derived(&grep, &pl),
            estimation: exps
                .iter()
                .enumerate()
                .map(|(i, e)| experiment_fit(&model, &gv, i, e, opts.lags))
                .collect(),
            validation: validate(&model, &gv, nk, &vals, gw, &opts.fit, opts.lags, unit),
            weights: gw,
            start: "the prior scenario, moved to the linear fit's coefficients".into(),
            fit: grep,
        });
        gb_model = Some(model);
    }
    // 4. The spread and the bounds.
    let bounds = spread(
        opts,
        &exps,
        &linear,
        &linear_result,
        gb_model.as_ref(),
        greybox_result.as_ref(),
        &pl,
        load_terms,
        k,
    )?;
    // 5. The scenario.
    let scenario = match &greybox_result {
        Some(g) if !g.fit.diverged => Some(identified_scenario(
            &prior,
            g,
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

fn moves(v: &[f64]) -> bool {
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    hi > lo
}

/// The linear fit's effective (a1, a2, a3, b) (load terms linearised in).
fn effective_linear(r: &ModelResult, load_terms: bool, k: f64) -> [f64; 4] {
    let v = r.fit.values();
    if load_terms {
        [v[0] + v[4] * k, v[1] + v[5], v[2], v[3]]
    } else {
        [v[0], v[1], v[2], v[3]]
    }
}

/// The physical parameters' start: the prior moved so that its effective
/// coefficients match `target` (log-differences of a2, a3, b; a1 relative
/// to a2's scale), by the same engine on those four residuals (what they
/// cannot fix stays at the prior). Falls back to the prior.
fn match_coefficients(gp: &[Param], load: &Load, target: [f64; 4], opts: &FitOptions) -> Vec<f64> {
    struct Coeffs<'a> {
        load: &'a Load,
        target: [f64; 4],
    }
    impl Problem for Coeffs<'_> {
        fn residuals(&self, v: &[f64], out: &mut Vec<f64>) -> bool {
            out.clear();
            let nk = greybox::KEYS.len();
            let (p, l) = greybox::from_vec(&v[..nk], self.load);
            if p.validate().is_err() {
                return false;
            }
            let a = greybox::effective(&p, &l);
            let b = ehservo_core::servo::NominalModel::new(p, l).b_at_rest();
            let t = self.target;
            if !(t[1] > 0.0 && t[2] > 0.0 && b * t[3] > 0.0) {
                return false;
            }
            out.push((a[0] - t[0]) / t[1].sqrt().max(1.0) / t[2].max(1.0));
            out.push((a[1] / t[1]).ln());
            out.push((a[2] / t[2]).ln());
            out.push((b / t[3]).ln());
            true
        }
    }
    let prob = Coeffs { load, target };
    let only_model: Vec<Param> = gp
        .iter()
        .map(|p| {
            if p.nuisance {
                Param {
                    status: Status::Fixed,
                    ..p.clone()
                }
            } else {
                p.clone()
            }
        })
        .collect();
    let mut r = Vec::new();
    let start: Vec<f64> = gp.iter().map(|p| p.value).collect();
    if !prob.residuals(&start, &mut r) {
        return start;
    }
    let o = FitOptions {
        ident_threshold: f64::INFINITY,
        ..*opts
    };
    let rep = fit::fit(&prob, only_model, &o);
    if rep.diverged {
        start
    } else {
        rep.values()
    }
}

/// The per-experiment (or bootstrap) spread of (a1, a2, a3, b).
#[allow(clippy::too_many_arguments)]
fn spread(
    opts: &Options,
    exps: &[Experiment],
    linear: &oe::Linear,
    lin: &ModelResult,
    gb: Option<&greybox::Physical>,
    gbr: Option<&ModelResult>,
    load: &Load,
    load_terms: bool,
    k: f64,
) -> anyhow::Result<Option<Bounds>> {
    if exps.len() < 2 && opts.bootstrap == 0 {
        return Ok(None);
    }
    // Which model: the grey-box when fitted (its coefficients are those of
    // the scenario), else the linear one.
    let (name, rep) = match gbr {
        Some(g) if !g.fit.diverged => ("greybox", &g.fit),
        _ => ("linear", &lin.fit),
    };
    let coeffs = |v: &[f64]| -> [f64; 4] {
        if name == "greybox" {
            let nk = greybox::KEYS.len();
            let (p, l) = greybox::from_vec(&v[..nk], load);
            let c = p.coefficients();
            [
                c.a1,
                c.a2,
                c.a3,
                ehservo_core::servo::NominalModel::new(p, l).b_at_rest(),
            ]
        } else if load_terms {
            [v[0] + v[4] * k, v[1] + v[5], v[2], v[3]]
        } else {
            [v[0], v[1], v[2], v[3]]
        }
    };
    let nominal = coeffs(&rep.values());
    // The pooled fit's parameters, each refit starting there; what the
    // pooled fit found unidentifiable stays held.
    let base: Vec<Param> = rep
        .estimates
        .iter()
        .map(|e| {
            let mut p = if e.nuisance || matches!(e.key.as_str(), "a1" | "b" | "d1" | "d2") {
                Param::signed(
                    &e.key,
                    &e.unit,
                    e.value,
                    e.se.unwrap_or(e.value.abs()).max(e.value.abs()).max(1e-12),
                )
            } else {
                Param::new(&e.key, &e.unit, e.value, e.value.abs().max(1.0))
            };
            p.nuisance = e.nuisance;
            p.prior = e.prior;
            p.status = if e.status == Status::Free {
                Status::Free
            } else {
                Status::Fixed
            };
            p
        })
        .collect();
    let nm = if name == "greybox" {
        greybox::KEYS.len()
    } else {
        linear.n_model()
    };
    let (method, samples): (String, Vec<[f64; 4]>) = if exps.len() >= 2 {
        // Each experiment alone: its own u_offset and θ0.
        let s = (0..exps.len())
            .into_par_iter()
            .map(|i| {
                let one = std::slice::from_ref(&exps[i]);
                let mut ps: Vec<Param> = base[..=nm].to_vec();
                let mut th = base[nm + 1 + i].clone();
                th.key = "theta0".into();
                ps.push(th);
                let v = match name {
                    "greybox" => {
                        let mut m = gb.expect("a grey-box result has its model").clone();
                        m.substeps = vec![m.substeps[i]];
                        let (r, ..) = fit_weighted(&m, one, ps, &opts.fit);
                        r.values()
                    }
                    _ => {
                        let mut m = linear.clone();
                        m.substeps = vec![m.substeps[i]];
                        let (r, ..) = fit_weighted(&m, one, ps, &opts.fit);
                        r.values()
                    }
                };
                coeffs(&v)
            })
            .collect();
        ("experiments".into(), s)
    } else {
        // Parametric bootstrap: the fitted model's output plus the
        // residuals resampled in blocks of 50 samples (keeping their
        // colour), refit; seeded ChaCha8, one stream per resample.
        let v = rep.values();
        let sims: Vec<SimOut> = match (name, gb) {
            ("greybox", Some(m)) => OutputError {
                model: m,
                experiments: exps,
                weights: gbr.map(|g| g.weights).unwrap_or(lin.weights),
            }
            .simulate_all(&v),
            _ => OutputError {
                model: linear,
                experiments: exps,
                weights: lin.weights,
            }
            .simulate_all(&v),
        }
        .unwrap_or_default();
        if sims.len() != exps.len() {
            return Ok(None);
        }
        let s = (0..opts.bootstrap)
            .into_par_iter()
            .map(|b| {
                let mut rng = ChaCha8Rng::seed_from_u64(opts.seed.wrapping_add(b as u64));
                let resampled: Vec<Experiment> = exps
                    .iter()
                    .zip(&sims)
                    .map(|(e, s)| {
                        let n = e.len();
                        let res: Vec<f64> =
                            e.y.values.iter().zip(&s.y).map(|(a, b)| a - b).collect();
                        let block = 50.min(n);
                        let mut y = Vec::with_capacity(n);
                        while y.len() < n {
                            let start = (rng.next_u64() % (n - block + 1) as u64) as usize;
                            for r in &res[start..start + block] {
                                if y.len() < n {
                                    y.push(s.y[y.len()] + r);
                                }
                            }
                        }
                        let mut e2 = e.clone();
                        e2.y.values = y;
                        // Other channels keep their measured values around the model's.
                        if let Some(p) = &mut e2.pressure {
                            if s.p.len() == n {
                                let r: Vec<f64> =
                                    p.values.iter().zip(&s.p).map(|(a, b)| a - b).collect();
                                p.values = (0..n)
                                    .map(|j| {
                                        s.p[j] + r[(j + (rng.next_u64() % n as u64) as usize) % n]
                                    })
                                    .collect();
                            }
                        }
                        e2
                    })
                    .collect();
                let v = match (name, gb) {
                    ("greybox", Some(m)) => fit_weighted(m, &resampled, base.clone(), &opts.fit)
                        .0
                        .values(),
                    _ => fit_weighted(linear, &resampled, base.clone(), &opts.fit)
                        .0
                        .values(),
                };
                coeffs(&v)
            })
            .collect();
        (
            format!(
                "bootstrap ({} resamples, blocks of 50 samples, seed {})",
                opts.bootstrap, opts.seed
            ),
            s,
        )
    };
    // The pooled fit's own 95 % half-widths, relative.
    let half = |key: &str, idx: usize| -> f64 {
        let d = if name == "greybox" {
            gbr.and_then(|g| g.derived(key)).and_then(|d| d.se)
        } else {
            rep.get(key).and_then(|e| e.se)
        };
        d.map_or(f64::INFINITY, |se| stats::Z95 * se / nominal[idx].abs())
    };
    let mut fractions = [0.0f64; 4];
    for i in 0..4 {
        let spread = samples
            .iter()
            .map(|s| (s[i] - nominal[i]).abs() / nominal[i].abs())
            .fold(0.0f64, f64::max);
        fractions[i] = spread.max(half(["a1", "a2", "a3", "b"][i], i));
    }
    let counted: [bool; 3] = std::array::from_fn(|i| {
        let key = ["a1", "a2", "a3"][i];
        let rel = if name == "greybox" {
            gbr.and_then(|g| g.derived(key))
                .and_then(|d| d.se)
                .map(|s| s / nominal[i].abs())
        } else {
            rep.get(key).and_then(|e| {
                if e.status == Status::Free {
                    e.relative_se
                } else {
                    None
                }
            })
        };
        rel.is_some_and(|r| r <= opts.fit.ident_threshold)
    });
    let bound_a = (0..3)
        .filter(|&i| counted[i])
        .map(|i| fractions[i])
        .fold(0.0f64, f64::max);
    Ok(Some(Bounds {
        method,
        model: name,
        nominal,
        samples,
        fractions,
        counted,
        bound_a,
        bound_b: fractions[3],
    }))
}

/// The prior scenario with the grey-box's parameters, no variation, and
/// the controller told the bounds.
fn identified_scenario(
    prior: &Scenario,
    g: &ModelResult,
    bounds: Option<&Bounds>,
    files: &[PathBuf],
) -> anyhow::Result<Scenario> {
    let nk = greybox::KEYS.len();
    let (p, l): (ServoParams, Load) = greybox::from_vec(&g.fit.values()[..nk], &prior.load_model());
    let mut s = prior.clone();
    s.name = "identified".into();
    s.description = format!(
        "Identified by `ehservo identify` from {}: the grey-box fit's physical parameters (the paper's model (1)-(6)); no parameter variation; the controller's bound_a and bound_b from the estimates' spread when there was one.",
        files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>().join(", ")
    );
    s.plant = if prior.plant.model() == "physical" {
        crate::scenario::PlantCfg::Physical(ehservo_sim::physical::PhysicalCfg { params: p })
    } else {
        crate::scenario::PlantCfg::ThirdOrder(ehservo_sim::third_order::ThirdOrderCfg { params: p })
    };
    s.load = Some(l);
    s.uncertainty = crate::scenario::UncertaintyCfg {
        a_bias: Some(0.0),
        a_random: Some(0.0),
        b_bias: Some(0.0),
        b_random: Some(0.0),
        ..Default::default()
    };
    let mut values: Vec<(String, toml::Value)> = Vec::new();
    if let Some(b) = bounds {
        let t = s.controller.to_table();
        if t.contains_key("bound_a") && t.contains_key("bound_b") {
            // The sliding laws need bound_b < 1 (their 1/(1 − bound_b)).
            values.push((
                "controller.bound_a".into(),
                toml::Value::Float(round6(b.bound_a)),
            ));
            values.push((
                "controller.bound_b".into(),
                toml::Value::Float(round6(b.bound_b.min(0.99))),
            ));
        }
    }
    let (s, _) = s.with_values_built(&values).map_err(anyhow::Error::from)?;
    Ok(s)
}

fn round6(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let e = 10f64.powi(5 - v.abs().log10().floor() as i32);
    (v * e).ceil() / e
}

/// Gaussian draws for tests and examples: a seeded stream.
pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    // Box–Muller on two uniforms in (0, 1].
    let u1 = 1.0 - rng.random::<f64>();
    let u2 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}
