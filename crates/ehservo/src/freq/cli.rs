//! The two subcommands' glue, so that `main.rs` stays a thin dispatcher.

use super::linearize::Side;
use super::oppoint::At;
use super::report::{freq_to_dir, FreqOptions, FreqSummary, Method};
use super::response::Discretisation;
use super::{all_finite, linearisation_json, linearise};
use crate::axis::Axis;
use crate::output::Staging;
use crate::scenario::Loop;
use anyhow::{Context, Result};
use std::path::Path;

/// The operating point of `--at T` or `--trim [DEG]` on a rotary axis
/// (None: the default, a trim at θd(0)).
pub fn operating_point(at: Option<f64>, trim: Option<Option<f64>>) -> Option<At> {
    operating_point_on(Axis::Rotary, at, trim, None, None)
}

/// The operating point of `--at T`, `--trim [X]` (X in the axis's display
/// unit: degrees on a rotary axis, mm on a linear one) and `--velocity V`
/// (its unit per second; a trim in steady motion), with `default` the
/// position of a trim without a value (the reference's θd(0); None: the
/// loop's default point).
pub fn operating_point_on(
    axis: Axis,
    at: Option<f64>,
    trim: Option<Option<f64>>,
    velocity: Option<f64>,
    default: Option<f64>,
) -> Option<At> {
    let v = velocity.map(|v| axis.to_si(v)).filter(|v| *v != 0.0);
    match (at, trim, v) {
        (Some(t), _, _) => Some(At::Time(t)),
        (None, Some(Some(x)), None) => Some(At::Trim(axis.to_si(x))),
        (None, Some(Some(x)), Some(v)) => Some(At::Moving(axis.to_si(x), v)),
        (None, _, Some(v)) => default.map(|x| At::Moving(x, v)),
        _ => None,
    }
}

/// The tracking amplitude in SI and the flag it came from: `--amplitude A`
/// in the axis's display unit (default 0.5), or `--amplitude-deg` on a
/// rotary axis (refused on a linear one, naming the flag).
pub fn amplitude(
    axis: Axis,
    amplitude: Option<f64>,
    amplitude_deg: Option<f64>,
    file: &str,
) -> Result<(f64, &'static str), crate::scenario::ScenarioError> {
    let flag = if amplitude_deg.is_some() {
        "--amplitude-deg"
    } else {
        "--amplitude"
    };
    if let Some(a) = amplitude_deg.or(amplitude) {
        if !(a.is_finite() && a > 0.0) {
            return Err(super::bad(file, flag, format!("{a}: must be > 0")));
        }
    }
    match (amplitude, amplitude_deg) {
        (_, Some(d)) if axis == Axis::Linear => Err(super::bad(
            file,
            "--amplitude-deg",
            format!(
                "{d}: the axis is linear (a length, in mm), not an angle: give the amplitude as --amplitude in mm"
            ),
        )),
        (_, Some(d)) => Ok((axis.to_si(d), "--amplitude-deg")),
        (Some(a), None) => Ok((axis.to_si(a), "--amplitude")),
        (None, None) => Ok((axis.to_si(0.5), "--amplitude")),
    }
}

/// `--side minus|plus`.
pub fn side(s: Option<&str>) -> Option<Side> {
    match s {
        Some("minus") => Some(Side::Minus),
        Some("plus") => Some(Side::Plus),
        _ => None,
    }
}

/// `--discretise zoh|rk4`.
pub fn discretisation(s: &str) -> Discretisation {
    if s == "rk4" {
        Discretisation::Rk4
    } else {
        Discretisation::Zoh
    }
}

/// The operating-point flags as given: `--at T`, `--trim [X]` and
/// `--velocity V` in the axis's display unit (resolved once the scenario,
/// and so its axis, is known).
#[derive(Debug, Clone, Copy, Default)]
pub struct PointFlags {
    /// `--at T` (s).
    pub at: Option<f64>,
    /// `--trim [X]`.
    pub trim: Option<Option<f64>>,
    /// `--velocity V`.
    pub velocity: Option<f64>,
}

impl PointFlags {
    /// The operating point on the scenario's axis.
    pub fn resolve(&self, lp: &Loop) -> Option<At> {
        let default = match super::default_at(lp) {
            At::Trim(x) => Some(x),
            _ => None,
        };
        operating_point_on(lp.axis(), self.at, self.trim, self.velocity, default)
    }
}

/// `ehservo linearize`: the JSON text, written to `out/linearization.json`
/// too when given.
pub fn linearize_cmd(
    scenario: &Path,
    set: &[String],
    point: PointFlags,
    side: Option<Side>,
    d: Discretisation,
    out: Option<&Path>,
) -> Result<String> {
    let lp = crate::formats::load(scenario, set)?;
    let file = scenario.display().to_string();
    let at = point.resolve(&lp);
    let l = linearise(&lp, &file, at, side, d)?;
    if !all_finite(&l) {
        anyhow::bail!("{file}: the linearised models are not finite");
    }
    let text = serde_json::to_string_pretty(&linearisation_json(&l))? + "\n";
    if let Some(dir) = out {
        let stage = Staging::new(dir)?;
        let p = stage.path().join("linearization.json");
        std::fs::write(&p, &text).with_context(|| format!("writing {}", p.display()))?;
        stage.commit()?;
    }
    Ok(text)
}

/// `ehservo freq` into `dir`, on `threads` worker threads (None: every
/// core).
pub fn freq_cmd(
    s: &Loop,
    scenario: &Path,
    o: &FreqOptions,
    dir: &Path,
    threads: Option<usize>,
) -> Result<FreqSummary> {
    let file = scenario.display().to_string();
    match threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
            .context("building the thread pool")?
            .install(|| freq_to_dir(s, &file, o, dir)),
        None => freq_to_dir(s, &file, o, dir),
    }
}

/// `--measure sine,multisine,chirp|none` (repeatable); an unknown name is
/// bad input about the scenario `file`'s request.
pub fn methods(v: &[String], file: &str) -> Result<Vec<Method>, crate::scenario::ScenarioError> {
    let mut out = Vec::new();
    for item in v.iter().flat_map(|s| s.split(',')) {
        let item = item.trim();
        if item == "none" {
            continue;
        }
        match Method::parse(item) {
            Some(m) if !out.contains(&m) => out.push(m),
            Some(_) => {}
            None => {
                return Err(super::bad(
                    file,
                    "--measure",
                    format!("{item}: unknown method (expected sine, multisine, chirp or none)"),
                ))
            }
        }
    }
    Ok(out)
}
