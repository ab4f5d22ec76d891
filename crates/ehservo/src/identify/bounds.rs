//! The spread of the third-order coefficients over experiments (each fitted
//! alone) or over a block bootstrap of the residuals, and the bounds
//! `bound_a`, `bound_b` of the paper's assumption A1 it gives.

use super::data::Experiment;
use super::fit::{FitReport, Param, Status};
use super::model::{OutputError, SimOut};
use super::passes::fit_weighted;
use super::{greybox, oe, stats, ModelResult, Options};
use ehservo_core::servo::Load;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

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

/// The fitted models the spread is taken over: the linear one and, when
/// fitted, the grey-box, each with its result.
pub(super) struct Fitted<'a> {
    pub(super) linear: &'a oe::Linear,
    pub(super) lin: &'a ModelResult,
    pub(super) gb: Option<&'a greybox::Physical>,
    pub(super) gbr: Option<&'a ModelResult>,
}

/// The pooled fit the spread is taken around: which model (`"greybox"` or
/// `"linear"`), its report, and what its coefficients are read with.
struct Pooled<'a> {
    name: &'static str,
    rep: &'a FitReport,
    /// The grey-box's result, whose derived quantities carry its
    /// coefficients' standard errors.
    gbr: Option<&'a ModelResult>,
    load: &'a Load,
    load_terms: bool,
    /// The load's wavenumber.
    k: f64,
}

/// The per-experiment (or bootstrap) spread of (a1, a2, a3, b).
pub(super) fn spread(
    opts: &Options,
    exps: &[Experiment],
    fitted: &Fitted,
    load: &Load,
    load_terms: bool,
    k: f64,
) -> anyhow::Result<Option<Bounds>> {
    if exps.len() < 2 && opts.bootstrap == 0 {
        return Ok(None);
    }
    // Which model: the grey-box when fitted (its coefficients are those of
    // the scenario), else the linear one.
    let (name, rep) = match fitted.gbr {
        Some(g) if !g.fit.diverged => ("greybox", &g.fit),
        _ => ("linear", &fitted.lin.fit),
    };
    let pooled = Pooled {
        name,
        rep,
        gbr: fitted.gbr,
        load,
        load_terms,
        k,
    };
    let nominal = pooled.coeffs(&rep.values());
    let base = pooled.base();
    let (method, samples): (String, Vec<[f64; 4]>) = if exps.len() >= 2 {
        let s = per_experiment(opts, exps, fitted, &pooled, &base);
        ("experiments".into(), s)
    } else {
        let Some(s) = bootstrap(opts, exps, fitted, &pooled, &base) else {
            return Ok(None);
        };
        (
            format!(
                "bootstrap ({} resamples, blocks of 50 samples, seed {})",
                opts.bootstrap, opts.seed
            ),
            s,
        )
    };
    let fractions = pooled.fractions(nominal, &samples);
    let counted = pooled.counted(nominal, opts.fit.ident_threshold);
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

impl Pooled<'_> {
    /// The third-order coefficients (a1, a2, a3, b) of the model's
    /// parameters `v`.
    fn coeffs(&self, v: &[f64]) -> [f64; 4] {
        let k = self.k;
        if self.name == "greybox" {
            let nk = greybox::KEYS.len();
            let (p, l) = greybox::from_vec(&v[..nk], self.load);
            let c = p.coefficients();
            [
                c.a1,
                c.a2,
                c.a3,
                ehservo_core::servo::NominalModel::new(p, l).b_at_rest(),
            ]
        } else if self.load_terms {
            [v[0] + v[4] * k, v[1] + v[5], v[2], v[3]]
        } else {
            [v[0], v[1], v[2], v[3]]
        }
    }

    /// The pooled fit's parameters, each refit starting there; what the
    /// pooled fit found unidentifiable stays held.
    fn base(&self) -> Vec<Param> {
        self.rep
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
            .collect()
    }

    /// Each coefficient's largest relative deviation over the samples, at
    /// least the pooled fit's own 95 % half-width (relative).
    fn fractions(&self, nominal: [f64; 4], samples: &[[f64; 4]]) -> [f64; 4] {
        let half = |key: &str, idx: usize| -> f64 {
            let d = if self.name == "greybox" {
                self.gbr.and_then(|g| g.derived(key)).and_then(|d| d.se)
            } else {
                self.rep.get(key).and_then(|e| e.se)
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
        fractions
    }

    /// Whether each of a1, a2, a3 counts for `bound_a`: its pooled
    /// relative standard error is at most the identifiability threshold.
    fn counted(&self, nominal: [f64; 4], threshold: f64) -> [bool; 3] {
        std::array::from_fn(|i| {
            let key = ["a1", "a2", "a3"][i];
            let rel = if self.name == "greybox" {
                self.gbr
                    .and_then(|g| g.derived(key))
                    .and_then(|d| d.se)
                    .map(|s| s / nominal[i].abs())
            } else {
                self.rep.get(key).and_then(|e| {
                    if e.status == Status::Free {
                        e.relative_se
                    } else {
                        None
                    }
                })
            };
            rel.is_some_and(|r| r <= threshold)
        })
    }
}

/// The coefficients of each experiment fitted alone (its own u_offset and
/// θ0), from the pooled fit's parameters.
fn per_experiment(
    opts: &Options,
    exps: &[Experiment],
    fitted: &Fitted,
    pooled: &Pooled,
    base: &[Param],
) -> Vec<[f64; 4]> {
    let nm = if pooled.name == "greybox" {
        greybox::KEYS.len()
    } else {
        fitted.linear.n_model()
    };
    (0..exps.len())
        .into_par_iter()
        .map(|i| {
            let one = std::slice::from_ref(&exps[i]);
            let mut ps: Vec<Param> = base[..=nm].to_vec();
            let mut th = base[nm + 1 + i].clone();
            th.key = "theta0".into();
            ps.push(th);
            let v = match pooled.name {
                "greybox" => {
                    let mut m = fitted.gb.expect("a grey-box result has its model").clone();
                    m.substeps = vec![m.substeps[i]];
                    let (r, ..) = fit_weighted(&m, one, ps, &opts.fit);
                    r.values()
                }
                _ => {
                    let mut m = fitted.linear.clone();
                    m.substeps = vec![m.substeps[i]];
                    let (r, ..) = fit_weighted(&m, one, ps, &opts.fit);
                    r.values()
                }
            };
            pooled.coeffs(&v)
        })
        .collect()
}

/// Parametric bootstrap: the coefficients refit on the fitted model's
/// output plus the residuals resampled in blocks of 50 samples (keeping
/// their colour); seeded ChaCha8, one stream per resample. None when the
/// model cannot be simulated on every file.
fn bootstrap(
    opts: &Options,
    exps: &[Experiment],
    fitted: &Fitted,
    pooled: &Pooled,
    base: &[Param],
) -> Option<Vec<[f64; 4]>> {
    let (name, gb, linear) = (pooled.name, fitted.gb, fitted.linear);
    let v = pooled.rep.values();
    let sims: Vec<SimOut> = match (name, gb) {
        ("greybox", Some(m)) => OutputError {
            model: m,
            experiments: exps,
            weights: fitted.gbr.map(|g| g.weights).unwrap_or(fitted.lin.weights),
        }
        .simulate_all(&v),
        _ => OutputError {
            model: linear,
            experiments: exps,
            weights: fitted.lin.weights,
        }
        .simulate_all(&v),
    }
    .unwrap_or_default();
    if sims.len() != exps.len() {
        return None;
    }
    let s = (0..opts.bootstrap)
        .into_par_iter()
        .map(|b| {
            let mut rng = ChaCha8Rng::seed_from_u64(opts.seed.wrapping_add(b as u64));
            let resampled: Vec<Experiment> = exps
                .iter()
                .zip(&sims)
                .map(|(e, s)| resample(e, s, &mut rng))
                .collect();
            let v = match (name, gb) {
                ("greybox", Some(m)) => fit_weighted(m, &resampled, base.to_vec(), &opts.fit)
                    .0
                    .values(),
                _ => fit_weighted(linear, &resampled, base.to_vec(), &opts.fit)
                    .0
                    .values(),
            };
            pooled.coeffs(&v)
        })
        .collect();
    Some(s)
}

/// One experiment resampled: the model's output `s` plus the residuals
/// drawn in blocks of 50 samples; the pressure (when logged and
/// simulated) its model's plus residuals drawn one by one.
fn resample(e: &Experiment, s: &SimOut, rng: &mut ChaCha8Rng) -> Experiment {
    let n = e.len();
    let res: Vec<f64> = e.y.values.iter().zip(&s.y).map(|(a, b)| a - b).collect();
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
            let r: Vec<f64> = p.values.iter().zip(&s.p).map(|(a, b)| a - b).collect();
            p.values = (0..n)
                .map(|j| s.p[j] + r[(j + (rng.next_u64() % n as u64) as usize) % n])
                .collect();
        }
    }
    e2
}
