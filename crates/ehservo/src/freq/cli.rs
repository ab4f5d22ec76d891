//! The two subcommands' glue, so that `main.rs` stays a thin dispatcher.

use super::linearize::Side;
use super::oppoint::At;
use super::report::{freq_to_dir, FreqOptions, FreqSummary, Method};
use super::response::Discretisation;
use super::{all_finite, linearisation_json, linearise};
use crate::output::Staging;
use crate::scenario::Loop;
use anyhow::{Context, Result};
use ehservo_core::math::DR;
use std::path::Path;

/// The operating point of `--at T` or `--trim [DEG]` (None: the default,
/// a trim at θd(0)).
pub fn operating_point(at: Option<f64>, trim: Option<Option<f64>>) -> Option<At> {
    match (at, trim) {
        (Some(t), _) => Some(At::Time(t)),
        (None, Some(Some(deg))) => Some(At::Trim(deg * DR)),
        _ => None,
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

/// `ehservo linearize`: the JSON text, written to `out/linearization.json`
/// too when given.
pub fn linearize_cmd(
    scenario: &Path,
    set: &[String],
    at: Option<At>,
    side: Option<Side>,
    d: Discretisation,
    out: Option<&Path>,
) -> Result<String> {
    let lp = crate::formats::load(scenario, set)?;
    let file = scenario.display().to_string();
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
