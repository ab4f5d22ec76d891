//! `ehservo excite`'s second half: the designed signal written as the
//! rig's CSV and as the scenario that simulates the same experiment on the
//! prior's plant (the module doc of [`super`] says what each holds).

use super::*;
use crate::output::Staging;
use anyhow::Context;
use std::path::{Path, PathBuf};

/// What `excite` wrote.
#[derive(Debug, Clone, Serialize)]
pub struct Written {
    /// The design.
    pub design: Design,
    /// Predicted peak |θ| (rad, or m on a linear axis: see `unit`).
    pub predicted_peak_rad: f64,
    /// The position's SI unit (`rad` or `m`).
    pub unit: &'static str,
    /// The gain of a closed-loop experiment (V/rad).
    pub kp: Option<f64>,
    /// The files.
    pub files: Vec<PathBuf>,
}

/// Designs the experiment and writes it into `out` (staged).
pub fn excite_to_dir(
    spec: &Spec,
    prior_path: Option<&Path>,
    set: &[String],
    out: &Path,
) -> Result<Written> {
    let prior = match prior_path {
        Some(p) => crate::formats::load(p, set)?,
        None => {
            crate::scenario::Loop::parse_with("name = \"prior\"", "<the paper's Fig. 2 case>", set)?
        }
    };
    crate::freq::position_loop(
        &prior,
        &prior_path.map_or("<prior>".into(), |p| p.display().to_string()),
    )?;
    let d = design(spec)?;
    let plan = Plan::on(&prior, spec, &d)?;
    let (h, kp, pk) = (plan.h, plan.kp, plan.pk);
    let stage = Staging::new(out)?;
    let dir = stage.path().to_path_buf();
    let mut files = Vec::new();
    // The rig's signal.
    let mut csv = String::new();
    let axis = prior.axis();
    let col = match (spec.loop_kind, axis) {
        (Loop::Open, _) => "u_V",
        (Loop::Closed, Axis::Rotary) => "reference_rad",
        (Loop::Closed, Axis::Linear) => "reference_m",
        (Loop::Closed, Axis::Force) => "reference_N",
        (Loop::Closed, Axis::Pressure) => "reference_Pa",
    };
    let _ = writeln!(csv, "t_s,{col}");
    for (k, v) in d.values.iter().enumerate() {
        let _ = writeln!(csv, "{},{}", k as f64 * h, v);
    }
    std::fs::write(dir.join("excitation.csv"), &csv).context("writing excitation.csv")?;
    files.push(out.join("excitation.csv"));
    let reference = if spec.signal == Signal::Chirp {
        chirp_reference(spec, axis)
    } else {
        let t = reference_csv(spec, axis, &d.values, h)?;
        std::fs::write(dir.join("reference.csv"), &t).context("writing reference.csv")?;
        files.push(out.join("reference.csv"));
        let mut reference = toml::Table::new();
        reference.insert("kind".into(), "csv".into());
        reference.insert("file".into(), "reference.csv".into());
        // Four lags of 10⁻⁶ of a period: the hold, delayed by 4·10⁻⁶ h.
        reference.insert("prefilter_tau".into(), (1e-6 * h).into());
        reference
    };
    let table = scenario_table(&prior, spec, set, &plan, d.values.len(), reference)?;
    let text = toml::to_string_pretty(&table).context("the scenario as TOML")?;
    // Checked as `run` will read it, its reference table from the stage;
    // a refusal names the file it would have been and the prior it came from.
    crate::scenario::Loop::parse_in(&text, "scenario.toml", &[], Some(dir.clone())).with_context(
        || {
            format!(
                "the scenario excite would write to {} from {} (nothing written)",
                out.join("scenario.toml").display(),
                prior_path.map_or("the paper's Fig. 2 case".into(), |p| format!(
                    "--prior {}",
                    p.display()
                ))
            )
        },
    )?;
    std::fs::write(dir.join("scenario.toml"), &text).context("writing scenario.toml")?;
    files.push(out.join("scenario.toml"));
    let w = Written {
        design: d,
        predicted_peak_rad: pk,
        unit: axis.si_unit(),
        kp,
        files: files.clone(),
    };
    let json = serde_json::json!({
        "software": crate::output::SOFTWARE,
        "spec": spec,
        "design": w.design,
        "predicted_peak_rad": pk,
        "position_unit": axis.si_unit(),
        "kp_V_per_rad": kp,
        "prior": prior_path.map(|p| p.display().to_string()),
        "set": set,
        "files": ["excitation.csv", "scenario.toml"],
    });
    std::fs::write(
        dir.join("excite.json"),
        serde_json::to_string_pretty(&json)? + "\n",
    )
    .context("writing excite.json")?;
    let mut w = w;
    w.files.push(out.join("excite.json"));
    stage.commit()?;
    Ok(w)
}

/// The experiment on the prior: its sample period, the gain of a closed
/// loop, and the peak |θ| (rad) the prior's linear model predicts.
struct Plan {
    h: f64,
    kp: Option<f64>,
    pk: f64,
}

impl Plan {
    /// The plan of design `d` on the prior's effective linear model, which
    /// must not diverge under it.
    fn on(prior: &crate::scenario::Loop, spec: &Spec, d: &Design) -> Result<Plan> {
        let h = 1.0 / spec.rate;
        let pm = prior.model();
        let a = super::super::greybox::effective(&pm.params, &pm.load);
        let b = pm.b_at_rest();
        let kp = match spec.loop_kind {
            Loop::Open => None,
            Loop::Closed => Some(spec.kp.unwrap_or_else(|| default_kp(a, b))),
        };
        let pk = predicted_peak(a, b, &d.values, h, kp);
        if !pk.is_finite() {
            return Err(bad(format!(
                "the experiment diverges on the prior's linear model{}: lower --kp",
                kp.map_or(String::new(), |k| format!(" under kp = {k} V/rad"))
            )));
        }
        Ok(Plan { h, kp, pk })
    }
}

/// The scenario's reference value of a designed value, in the axis's
/// display unit (degrees or mm): the command at 1 V a unit in open loop
/// (1 V per ° or mm: `volts_per_deg` or `volts_per_mm` = 1), the reference itself in closed loop.
fn to_display(spec: &Spec, axis: Axis, v: f64) -> f64 {
    match spec.loop_kind {
        Loop::Open => v,
        Loop::Closed => axis.display(v),
    }
}

/// The scenario's `[reference]` of a chirp: the chirp itself.
fn chirp_reference(spec: &Spec, axis: Axis) -> toml::Table {
    let mut reference = toml::Table::new();
    reference.insert("kind".into(), "chirp".into());
    let key = match axis {
        Axis::Rotary => "amplitude_deg",
        Axis::Linear => "amplitude_mm",
        Axis::Force => "amplitude_kN",
        Axis::Pressure => "amplitude_bar",
    };
    reference.insert(key.into(), to_display(spec, axis, spec.amplitude).into());
    reference.insert("f0_hz".into(), spec.f0.into());
    reference.insert("f1_hz".into(), spec.f1.into());
    reference.insert("duration".into(), spec.duration.into());
    reference
}

/// The scenario's reference table (reference.csv) of a sampled signal:
/// knots at every sample (multisine), or at each level's first and last
/// sample (piecewise constant), so that the table's linear interpolation is
/// the zero-order hold at every sample instant. It must fit an input file.
fn reference_csv(spec: &Spec, axis: Axis, values: &[f64], h: f64) -> Result<String> {
    let mut t = format!("t,{}\n", axis.column("", ""));
    let piecewise = spec.signal != Signal::Multisine;
    let n = values.len();
    for k in 0..n {
        let first = k == 0 || values[k].to_bits() != values[k - 1].to_bits();
        let last = k + 1 == n || values[k + 1].to_bits() != values[k].to_bits();
        if !piecewise || first || last {
            let tk = k as f64 * h;
            let tk = if piecewise && last && !first && k + 1 < n {
                tk + 0.999 * h
            } else {
                tk
            };
            let _ = writeln!(t, "{},{}", tk, to_display(spec, axis, values[k]));
        }
    }
    if t.len() as u64 > crate::input::MAX_INPUT_BYTES {
        return Err(bad(format!(
            "the scenario's reference table would be {} bytes, more than an input file's {} bytes: shorten --duration or lower --rate",
            t.len(),
            crate::input::MAX_INPUT_BYTES
        )));
    }
    Ok(t)
}

/// The experiment's scenario: the prior's, with the designed reference,
/// the open loop (1 V/°) or the proportional loop, the sampled simulation
/// of the `n` samples, and the plant as it is unless `--set` varies it.
fn scenario_table(
    prior: &crate::scenario::Loop,
    spec: &Spec,
    set: &[String],
    plan: &Plan,
    n: usize,
    reference: toml::Table,
) -> Result<toml::Table> {
    let (h, pk) = (plan.h, plan.pk);
    let mut table = prior.table()?;
    table.insert("name".into(), "excite".into());
    table.insert(
        "description".into(),
        format!(
            "An identification experiment designed by `ehservo excite`: {:?} signal, {} loop, peak {} {}.",
            spec.signal,
            match spec.loop_kind {
                Loop::Open => "open",
                Loop::Closed => "closed",
            },
            spec.amplitude,
            if spec.loop_kind == Loop::Open {
                "V"
            } else {
                prior.axis().si_unit()
            }
        )
        .into(),
    );
    let mut reference = reference;
    if plan.kp.is_some() && prior.axis() == Axis::Linear {
        // A cylinder's reference is a position in its stroke: the
        // experiment about the rod's start.
        let y0 = prior.scenario().simulation.x0[0];
        reference.insert("offset_mm".into(), prior.axis().display(y0).into());
    }
    table.insert("reference".into(), toml::Value::Table(reference));
    let mut ctrl = toml::Table::new();
    match plan.kp {
        None => {
            ctrl.insert("kind".into(), "open-loop".into());
            // 1 V per unit of the reference table (° or mm).
            // A force or pressure prior is refused first (`excite_to_dir`).
            let key = match prior.axis() {
                Axis::Rotary => "volts_per_deg",
                _ => "volts_per_mm",
            };
            ctrl.insert(key.into(), 1.0.into());
        }
        Some(k) => {
            ctrl.insert("kind".into(), "pid".into());
            ctrl.insert("kp".into(), k.into());
            ctrl.insert("ki".into(), 0.0.into());
            ctrl.insert("kd".into(), 0.0.into());
            ctrl.insert("feedforward".into(), false.into());
        }
    }
    table.insert("controller".into(), toml::Value::Table(ctrl));
    let sim = table
        .entry("simulation")
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    if let toml::Value::Table(sim) = sim {
        sim.insert("step".into(), h.into());
        sim.insert("horizon".into(), ((n - 1) as f64 * h).into());
        sim.insert("mode".into(), "sampled".into());
        sim.insert("settle".into(), 0.0.into());
        let lim = sim
            .get("theta_limit")
            .and_then(|v| v.as_float())
            .unwrap_or(1.0);
        sim.insert("theta_limit".into(), lim.max(3.0 * pk).into());
    }
    // The plant as it is (no parameter variation) unless the prior's --set
    // says otherwise: the paper's Δa_i/Δb form at zero on its family, an
    // empty table (no [uncertainty.physical] variation) on the others (a
    // cylinder refuses the paper's keys).
    if !set
        .iter()
        .any(|s| s.trim_start().starts_with("uncertainty"))
    {
        let none = if prior.scenario().plant.paper_uncertainty() {
            toml::Value::try_from(ehservo_sim::plant::UncertaintySpec::NONE)
                .context("uncertainty table")?
        } else {
            toml::Value::Table(toml::Table::new())
        };
        table.insert("uncertainty".into(), none);
    }
    Ok(table)
}
