//! Between the fits and the physical parameters: the grey-box's start, the
//! prior moved to the linear fit's coefficients; and the identified
//! scenario, the prior with the grey-box's estimates and the bounds.

use super::fit::{self, FitOptions, Param, Problem, Status};
use super::{greybox, Bounds, ModelResult};

use crate::scenario::{Loop, Scenario};
use ehservo_core::servo::{Load, ServoParams};
use std::path::PathBuf;

/// The linear fit's effective (a1, a2, a3, b) (load terms linearised in).
pub(super) fn effective_linear(r: &ModelResult, load_terms: bool, k: f64) -> [f64; 4] {
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
pub(super) fn match_coefficients(
    gp: &[Param],
    load: &Load,
    target: [f64; 4],
    opts: &FitOptions,
) -> Vec<f64> {
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

/// The prior scenario with the grey-box's parameters, no variation, and
/// the controller told the bounds.
pub(super) fn identified_scenario(
    prior: &Loop,
    values: &[f64],
    bounds: Option<&Bounds>,
    files: &[PathBuf],
) -> anyhow::Result<Scenario> {
    let nk = greybox::KEYS.len();
    let (p, l): (ServoParams, Load) = greybox::from_vec(&values[..nk], &prior.model().load);
    let mut s = prior.scenario().clone();
    s.name = "identified".into();
    s.description = format!(
        "Identified by `ehservo identify` from {}: the grey-box fit's physical parameters (the paper's model (1)-(6)); no parameter variation; the controller's bound_a and bound_b from the estimates' spread when there was one.",
        files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>().join(", ")
    );
    // The prior's own model when it is of the paper's family (physical or
    // third-order), else the third-order model the grey-box is.
    s.plant = s.plant.with_paper_params(p).unwrap_or({
        crate::scenario::PlantCfg::ThirdOrder(ehservo_sim::third_order::ThirdOrderCfg { params: p })
    });
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
    let s = Loop::new(s)
        .and_then(|lp| lp.with_values(&values))
        .map_err(anyhow::Error::from)?;
    Ok(s.scenario().clone())
}

fn round6(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let e = 10f64.powi(5 - v.abs().log10().floor() as i32);
    (v * e).ceil() / e
}
