//! The grey-box of a linear axis: the prior scenario's own plant (the
//! cylinder with its valve, supply, load and `[actuator]`), stepped by
//! [`PlantStepper`] with the logged command held over each sample period
//! exactly as `ehservo run` integrates it, some of its scenario keys fitted
//! by output error.
//!
//! **What the data can identify.** Linearised about a trim with the rod
//! moving slowly, the cylinder from the command u to the position y is
//! (docs/cylinder.md, "The nominal model"; Merritt, *Hydraulic Control
//! Systems*, 1967, §6.4)
//!
//! ```text
//! y/u = Kq·A·βe/(V·M) / (s·(s² + (B/M + βe·Kce/V)·s + ω_h² + B·βe·Kce/(V·M)))
//! ```
//!
//! with ω_h² = βe·(A_A²/V_A + A_B²/V_B)/M, Kq the valve's flow gain
//! (`rated_flow`), Kce = Kc + the cross-piston leakage and B the viscous
//! friction. From (y, u) alone the data fix three coefficients; with the
//! mass given (a slide's mass is on its drawing), βe, B and Kq are the
//! three they fix, which is the default free set. The leakage's share of
//! the damping trades with B (both add to the s² coefficient), so freeing
//! `leakage` as well is refused by the identifiability test unless the
//! data hold more (a velocity channel, several operating points), and the
//! mass is identifiable only with a known force (a spring, the weight on an
//! inclined axis). `--free` and `--fix` change the set; a key the prior's
//! `[plant]` does not set cannot be freed (a start of 0 cannot be
//! log-scaled: give one with `--set`).

use super::data::Experiment;
use super::fit::{Param, Status};
use super::model::{Model, SimOut};
use crate::scenario::Loop;
use crate::stepper::PlantStepper;

/// A grey-box key: its name (as `--free`/`--fix` take it), its scenario
/// path, its unit, and the `[uncertainty.physical]` factor it varies by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Key {
    /// The name.
    pub name: &'static str,
    /// The dotted scenario key.
    pub path: &'static str,
    /// The unit.
    pub unit: &'static str,
    /// The `[uncertainty.physical]` table that scales it, if one does.
    pub physical: Option<&'static str>,
}

/// Every key the cylinder's grey-box can fit.
pub const KEYS: &[Key] = &[
    Key {
        name: "bulk_modulus",
        path: "plant.fluid.bulk_modulus",
        unit: "Pa",
        physical: Some("bulk_modulus"),
    },
    Key {
        name: "leakage",
        path: "plant.cylinder.leakage",
        unit: "m^3/(s*Pa)",
        physical: Some("leakage"),
    },
    Key {
        name: "viscous",
        path: "plant.cylinder.viscous",
        unit: "N*s/m",
        physical: Some("friction"),
    },
    Key {
        name: "rated_flow",
        path: "plant.valve.rated_flow",
        unit: "m^3/s",
        physical: None,
    },
    Key {
        name: "mass",
        path: "plant.load.mass",
        unit: "kg",
        physical: Some("mass"),
    },
    Key {
        name: "coulomb",
        path: "plant.load.friction.coulomb",
        unit: "N",
        physical: Some("friction"),
    },
];

/// The default free set (the mass given).
pub const DEFAULT_FREE: &[&str] = &["bulk_modulus", "viscous", "rated_flow"];

/// The value at a dotted path of a TOML table, if it is a number.
fn number_at(t: &toml::Table, path: &str) -> Option<f64> {
    let mut parts = path.split('.').peekable();
    let mut cur = t;
    while let Some(p) = parts.next() {
        let v = cur.get(p)?;
        if parts.peek().is_none() {
            return v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
        }
        cur = v.as_table()?;
    }
    None
}

/// The grey-box model of a linear axis on a set of experiments.
#[derive(Debug, Clone)]
pub struct AxisModel {
    /// The prior, built.
    prior: Loop,
    /// The prior's table without parameter variation (the experiment is
    /// the plant as it is) and without a settling time.
    table: toml::Table,
    /// The keys the prior sets (a subset of [`KEYS`], in its order).
    pub keys: Vec<Key>,
    /// The prior's RK4 sub-step (s): no experiment is integrated coarser.
    hs: f64,
    /// |y| (m) beyond which a run has diverged.
    limit: f64,
}

impl AxisModel {
    /// The model for `experiments` from the prior (a linear axis's
    /// scenario).
    pub fn new(prior: &Loop, experiments: &[Experiment]) -> anyhow::Result<Self> {
        let mut table = prior.table()?;
        let keys: Vec<Key> = KEYS
            .iter()
            .copied()
            .filter(|k| number_at(&table, k.path).is_some())
            .collect();
        table.remove("uncertainty");
        if let Some(s) = table.get_mut("simulation").and_then(|s| s.as_table_mut()) {
            s.remove("settle");
        }
        let sim = prior.sim();
        Ok(Self {
            prior: prior.clone(),
            table,
            keys,
            hs: sim.step / f64::from(sim.substeps.max(1)),
            limit: super::model::divergence_limit(experiments),
        })
    }

    /// RK4 sub-steps per sample of a period `h`: the prior's sub-step or
    /// finer (at most 4096).
    pub fn substeps(&self, h: f64) -> u32 {
        (h / self.hs * (1.0 - 1e-9)).ceil().clamp(1.0, 4096.0) as u32
    }

    /// The prior's values of [`AxisModel::keys`].
    pub fn prior_values(&self) -> Vec<f64> {
        self.keys
            .iter()
            .map(|k| number_at(&self.table, k.path).unwrap_or(0.0))
            .collect()
    }

    /// The keys' values as scenario overrides.
    pub fn values(&self, v: &[f64]) -> Vec<(String, toml::Value)> {
        self.keys
            .iter()
            .zip(v)
            .map(|(k, &x)| (k.path.to_string(), toml::Value::Float(x)))
            .collect()
    }

    /// The loop of experiment `e` with the keys at `v` and the rod at rest
    /// at `y0` (m), or `None` where the scenario refuses them.
    fn loop_for(&self, v: &[f64], e: &Experiment, y0: f64) -> Option<Loop> {
        let f = toml::Value::Float;
        let mut values = self.values(v);
        values.extend([
            ("simulation.step".to_string(), f(e.h)),
            (
                "simulation.substeps".to_string(),
                toml::Value::Integer(i64::from(self.substeps(e.h))),
            ),
            (
                "simulation.horizon".to_string(),
                f(e.h * (e.len().max(2) - 1) as f64),
            ),
            (
                "simulation.x0".to_string(),
                toml::Value::Array(vec![f(y0), f(0.0), f(0.0)]),
            ),
        ]);
        self.prior.with_values_on(self.table.clone(), &values).ok()
    }

    /// The parameters: every key at its prior, those in `free` free
    /// (log-scaled), the rest fixed.
    pub fn params(&self, free: &[String]) -> Vec<Param> {
        self.keys
            .iter()
            .zip(self.prior_values())
            .map(|(k, v)| {
                let mut p = Param::new(k.name, k.unit, v, v.abs().max(1.0));
                if !free.iter().any(|f| f == k.name) {
                    p.status = Status::Fixed;
                }
                p
            })
            .collect()
    }
}

impl Model for AxisModel {
    fn simulate(&self, v: &[f64], i: usize, e: &Experiment, out: &mut SimOut) -> bool {
        let nk = self.keys.len();
        let u_off = v[nk];
        let y0 = v[nk + 1 + i];
        out.y.clear();
        out.v.clear();
        out.p.clear();
        let Some(lp) = self.loop_for(&v[..nk], e, y0) else {
            return false;
        };
        let mut plant = PlantStepper::new(&lp);
        let n = e.len();
        for k in 0..n {
            let u = e.u.values[k] + u_off;
            let x = plant.output(u).x;
            out.y.push(x[0]);
            out.v.push(x[1]);
            if k + 1 == n {
                break;
            }
            if plant.hold(u).is_err() {
                return false;
            }
            let y = out.y[k];
            if !(y.is_finite() && y.abs() <= self.limit) {
                return false;
            }
        }
        true
    }

    fn has_pressure(&self) -> bool {
        false
    }
}

impl super::Job<'_> {
    /// The grey-box of a linear axis (the prior's cylinder): its free keys
    /// checked, started at the prior, fitted, with its derived quantities
    /// and its fit on every file.
    pub(super) fn fit_axis_greybox(
        &self,
        prior: &Loop,
        linear: &super::ModelResult,
        notes: &mut Vec<String>,
    ) -> anyhow::Result<(AxisModel, super::ModelResult)> {
        let (opts, exps) = (self.opts, self.exps);
        let model = AxisModel::new(prior, exps)?;
        let free = self.axis_free(&model)?;
        let mut gp = model.params(&free);
        gp.extend(super::nuisance(exps, self.unit));
        super::apply_fix(&mut gp, &opts.fix, &super::linear_keys(opts.load_terms))?;
        // The nuisance parameters start at the linear fit's.
        let (nk, lv) = (model.keys.len(), linear.fit.values());
        let nl = lv.len() - (exps.len() + 1);
        for j in 0..=exps.len() {
            gp[nk + j].value = lv[nl + j];
        }
        let steps = exps.iter().try_fold(0usize, |acc, e| {
            e.len()
                .checked_mul(model.substeps(e.h) as usize)
                .and_then(|s| acc.checked_add(s))
        });
        if steps.is_none_or(|s| s > super::MAX_STEPS_PER_EVALUATION) {
            return Err(super::bad(format!(
                "identify: more than {} RK4 steps per evaluation of the grey-box (the prior's sub-step is {:.3e} s)",
                super::MAX_STEPS_PER_EVALUATION,
                model.hs
            )));
        }
        let (rep, w, _) = super::fit_weighted(&model, exps, gp, &opts.fit);
        if rep.diverged {
            notes.push("the grey-box model diverged at its start (the prior)".into());
        }
        let gv = rep.values();
        let result = super::ModelResult {
            model: "greybox",
            derived: derived(&model, &rep, exps),
            estimation: exps
                .iter()
                .enumerate()
                .map(|(i, e)| super::experiment_fit(&model, &gv, i, e, opts.lags))
                .collect(),
            validation: super::validate(
                &model, &gv, nk, self.vals, w, &opts.fit, opts.lags, self.unit,
            ),
            weights: w,
            start: "the prior scenario".into(),
            fit: rep,
        };
        Ok((model, result))
    }

    /// The free keys (`--free`, or [`DEFAULT_FREE`]), each one the prior sets.
    fn axis_free(&self, model: &AxisModel) -> anyhow::Result<Vec<String>> {
        let free: Vec<String> = self
            .opts
            .free
            .clone()
            .unwrap_or_else(|| DEFAULT_FREE.iter().map(|s| s.to_string()).collect());
        let known = || KEYS.iter().map(|k| k.name).collect::<Vec<_>>().join(", ");
        for f in &free {
            let Some(k) = KEYS.iter().find(|k| k.name == f) else {
                return Err(super::bad(format!(
                    "--free {f}: no such grey-box parameter of a linear axis (known: {})",
                    known()
                )));
            };
            let at = model
                .keys
                .iter()
                .position(|m| m.name == k.name)
                .map(|i| model.prior_values()[i]);
            if !at.is_some_and(|v| v > 0.0) {
                let flag = match &self.opts.free {
                    Some(_) => format!("--free {f}"),
                    None => format!("the grey-box's default free key {f} (--free chooses others, --no-greybox skips it)"),
                };
                return Err(super::bad(format!(
                    "{flag}: the prior sets no positive {} to start from; give one with --set {}=VALUE",
                    k.path, k.path
                )));
            }
        }
        Ok(free)
    }
}

/// The grey-box's derived quantities: ω_h = √(βe·(A_A²/V_A + A_B²/V_B)/M)
/// at the mean position of the estimation data, and f_h, of the cylinder
/// built with the values (its hoses' equivalent volumes follow βe).
fn derived(model: &AxisModel, rep: &super::FitReport, exps: &[Experiment]) -> Vec<super::Derived> {
    let (sum, n) = exps.iter().fold((0.0, 0usize), |(s, n), e| {
        (s + e.y.values.iter().sum::<f64>(), n + e.len())
    });
    let y = sum / n.max(1) as f64;
    let nk = model.keys.len();
    let wh = |v: &[f64]| -> Option<f64> {
        let lp = model
            .prior
            .with_values_on(model.table.clone(), &model.values(&v[..nk]))
            .ok()?;
        let c = lp
            .plant()
            .get::<ehservo_sim::cylinder::CylinderPlant>()?
            .cylinder()
            .clone();
        let [va, vb] = c.volumes(y);
        Some((c.beta * (c.area[0].powi(2) / va + c.area[1].powi(2) / vb) / c.mass).sqrt())
    };
    if wh(&rep.values()).is_none() {
        return Vec::new();
    }
    super::derived::delta(rep, &[("omega_h_rad_s", "rad/s"), ("f_h_Hz", "Hz")], &|v| {
        let w = wh(v).unwrap_or(f64::NAN);
        vec![w, w / (2.0 * std::f64::consts::PI)]
    })
}

/// The prior scenario with the grey-box's values, its parameters varied by
/// their 95 % intervals (`[uncertainty.physical]`, `random`), and the
/// controller told the bounds of A1 from the spread when it takes them.
pub(super) fn identified_scenario(
    model: &AxisModel,
    rep: &super::FitReport,
    bounds: Option<&super::Bounds>,
    files: &[std::path::PathBuf],
) -> anyhow::Result<crate::scenario::Scenario> {
    let v = rep.values();
    let mut values = model.values(&v[..model.keys.len()]);
    values.extend(uncertainty(model, rep));
    values.push(("name".into(), toml::Value::String("identified".into())));
    values.push((
        "description".into(),
        toml::Value::String(format!(
            "Identified by `ehservo identify` from {}: the grey-box fit's values of the prior's cylinder; [uncertainty.physical] from their 95 % intervals",
            files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>().join(", ")
        )),
    ));
    if let Some(b) = bounds {
        let t = model.prior.controller().to_table();
        if t.contains_key("bound_a") && t.contains_key("bound_b") {
            values.push(("controller.bound_a".into(), toml::Value::Float(b.bound_a)));
            // The sliding laws need bound_b < 1 (their 1/(1 − bound_b)).
            values.push((
                "controller.bound_b".into(),
                toml::Value::Float(b.bound_b.min(0.99)),
            ));
        }
    }
    let mut table = model.prior.table()?;
    table.remove("uncertainty");
    let lp = model.prior.with_values_on(table, &values)?;
    Ok(lp.scenario().clone())
}

/// `uncertainty.physical.F.random` for each factor F that scales a free
/// key: the largest relative half-width of their 95 % intervals (a key
/// fixed or held unidentifiable adds nothing), at most 0.9.
fn uncertainty(model: &AxisModel, rep: &super::FitReport) -> Vec<(String, toml::Value)> {
    let mut out: Vec<(&str, f64)> = Vec::new();
    for k in &model.keys {
        let (Some(f), Some(e)) = (k.physical, rep.get(k.name)) else {
            continue;
        };
        let Some([_, hi]) = e.ci95.filter(|_| e.status == Status::Free) else {
            continue;
        };
        let frac = (hi / e.value - 1.0).clamp(0.0, 0.9);
        if !frac.is_finite() {
            continue;
        }
        match out.iter_mut().find(|(g, _)| *g == f) {
            Some(slot) => slot.1 = slot.1.max(frac),
            None => out.push((f, frac)),
        }
    }
    out.into_iter()
        .map(|(f, frac)| {
            (
                format!("uncertainty.physical.{f}.random"),
                toml::Value::Float(frac),
            )
        })
        .collect()
}
