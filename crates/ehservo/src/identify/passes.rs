//! The fit passes both models share: the nuisance parameters (the
//! command's offset, each file's initial position), `--fix`, the two-pass
//! weighted fit, the validation on other files and each experiment's
//! NRMSE and residual tests.

use super::data::Experiment;
use super::fit::{self, FitOptions, FitReport, Param, Status};
use super::model::{Model, OutputError, SimOut, Weights};
use super::{bad, stats, ExperimentFit};

/// The nuisance parameters appended to a model's: u_offset, then θ0 of
/// each experiment (`theta0` for one, `theta0_1`, … for several).
pub(super) fn nuisance(experiments: &[Experiment], unit: &str) -> Vec<Param> {
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
pub(super) fn apply_fix(
    params: &mut [Param],
    fix: &[(String, f64)],
    other: &[&str],
) -> anyhow::Result<()> {
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
pub(super) fn fit_weighted<M: Model>(
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
pub(super) fn validate<M: Model>(
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
pub(super) fn experiment_fit<M: Model>(
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
