//! Running a study: its runs in parallel with a progress bar, and the
//! sweep that writes their outputs.

use super::{plots, results_csv, Plan, StudyRecord};
use crate::metrics::Metrics;
use crate::output::{write_atomic, Staging, SOFTWARE};
use anyhow::{Context, Result};
use std::path::PathBuf;

/// One finished run.
#[derive(Debug, Clone)]
pub struct RunRow {
    /// Run index.
    pub index: u64,
    /// Values of the varied columns.
    pub values: Vec<toml::Value>,
    /// Seed.
    pub seed: u64,
    /// Metrics (None if the drawn scenario was invalid).
    pub metrics: Option<Metrics>,
    /// Why the run could not be made (invalid drawn values).
    pub error: Option<String>,
}

/// Runs `range` of the plan in parallel (optionally on `threads` threads).
pub fn execute(
    plan: &Plan,
    range: std::ops::Range<u64>,
    threads: Option<usize>,
    progress: &indicatif::ProgressBar,
) -> Result<Vec<RunRow>> {
    use rayon::prelude::*;
    // The work of these runs, bounded before any of them.
    super::check_study(plan, range.clone())?;
    let work = || -> Vec<RunRow> {
        range
            .clone()
            .into_par_iter()
            .map(|i| {
                let (values, sets, seed) = plan.run_values(i);
                if crate::cancel::requested() {
                    // Interrupted (crate::cancel): no run is started, and
                    // these rows are never returned.
                    return RunRow {
                        index: i,
                        values,
                        seed,
                        metrics: None,
                        error: None,
                    };
                }
                let row = match plan.build_run(&sets) {
                    // Validation built the Setup: run it, not the scenario again.
                    // One study, one unit: a run whose plant is on another
                    // axis (a swept plant.model) is refused, not mixed in.
                    Ok(lp) if lp.axis() != plan.axis() => RunRow {
                        index: i,
                        values,
                        seed,
                        metrics: None,
                        error: Some(format!(
                            "`plant.model`: its axis is {} but the base scenario's is {}: a study's errors share one unit",
                            lp.axis().name(),
                            plan.axis().name()
                        )),
                    },
                    Ok(lp) => RunRow {
                        index: i,
                        values,
                        seed,
                        metrics: Some(crate::run::run_metrics(&lp, &mut |_| {}).1),
                        error: None,
                    },
                    Err(e) => RunRow {
                        index: i,
                        values,
                        seed,
                        metrics: None,
                        error: Some(format!("`{}`: {}", e.key, e.reason)),
                    },
                };
                progress.inc(1);
                row
            })
            .collect()
    };
    let rows = match threads {
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n.max(1))
                .build()
                .context("building the thread pool")?;
            pool.install(work)
        }
        None => work(),
    };
    if crate::cancel::requested() {
        return Err(crate::cancel::Cancelled.into());
    }
    Ok(rows)
}

/// Options of a sweep.
#[derive(Debug, Clone)]
pub struct SweepOptions {
    /// Output directory.
    pub out: PathBuf,
    /// `(k, n)`: run only the k-th of n slices.
    pub shard: Option<(u64, u64)>,
    /// Thread count (default: all cores).
    pub threads: Option<usize>,
    /// Show a progress bar.
    pub progress: bool,
    /// Draw plots.
    pub plots: bool,
}

/// The study.json a sweep of `plan` (or of its `shard`) writes.
fn study_json(plan: &Plan, shard: Option<(u64, u64)>) -> Result<String> {
    let range = match shard {
        Some((k, n)) => plan.shard_range(k, n),
        None => 0..plan.runs,
    };
    let record = StudyRecord {
        software: SOFTWARE.name.into(),
        version: SOFTWARE.version.into(),
        study: plan.study.clone(),
        base: serde_json::to_value(plan.base.scenario())?,
        runs: plan.runs,
        shard: shard.map(|(k, n)| [k, n]),
        range: [range.start, range.end],
        axis: plan.axis(),
    };
    Ok(serde_json::to_string_pretty(&record)?)
}

/// What `sweep --resume` finds in the output folder.
#[derive(Debug, Clone, PartialEq)]
pub enum Resume {
    /// Nothing there (or no study.json): run.
    Absent,
    /// An output is there but is not this sweep's, whole: run again,
    /// replacing it (the reason says why).
    Redo(String),
    /// This sweep's output is there, whole: its study.json is the one this
    /// sweep would write, byte for byte (same study, base scenario, shard
    /// and version), and its results.csv holds every row it promises, as
    /// `merge` checks them.
    Complete,
}

/// Whether `opts.out` already holds this sweep's output, whole (for
/// `sweep --resume`: a resubmitted job array reruns only what is missing).
pub fn resume_state(plan: &Plan, opts: &SweepOptions) -> Result<Resume> {
    if !opts.out.join("study.json").exists() {
        return Ok(Resume::Absent);
    }
    let text = match super::check_shard(&opts.out) {
        Ok(t) => t,
        Err(e) if crate::error::is_bad_input(&e) => return Ok(Resume::Redo(format!("{e:#}"))),
        Err(e) => return Err(e),
    };
    if text != study_json(plan, opts.shard)? {
        return Ok(Resume::Redo(format!(
            "{}: is not this sweep's study.json (another study, shard, base scenario or version)",
            opts.out.join("study.json").display()
        )));
    }
    Ok(Resume::Complete)
}

/// Runs a study and writes results.csv, study.json and plots.
pub fn sweep(plan: &Plan, opts: &SweepOptions) -> Result<Vec<RunRow>> {
    let range = match opts.shard {
        Some((k, n)) => plan.shard_range(k, n),
        None => 0..plan.runs,
    };
    let pb = indicatif::ProgressBar::with_draw_target(
        Some(range.end - range.start),
        if opts.progress {
            indicatif::ProgressDrawTarget::stderr()
        } else {
            indicatif::ProgressDrawTarget::hidden()
        },
    );
    pb.set_style(
        indicatif::ProgressStyle::with_template(
            "{msg} [{bar:40}] {pos}/{len} runs, {per_sec}, ETA {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    pb.set_message(plan.study.name.clone());
    let rows = execute(plan, range.clone(), opts.threads, &pb)?;
    pb.finish_and_clear();

    let stage = Staging::new(&opts.out)?;
    write_atomic(
        &stage.path().join("results.csv"),
        &results_csv(plan, &rows)?,
    )?;
    write_atomic(
        &stage.path().join("study.json"),
        study_json(plan, opts.shard)?.as_bytes(),
    )?;
    if opts.plots && opts.shard.is_none() {
        plots::study_plots(plan, &rows, stage.path())?;
    }
    stage.commit()?;
    Ok(rows)
}
