//! Studies: parameter sweeps and Monte Carlo over scenarios, on every core
//! and across machines.
//!
//! A study file names a base scenario and how to vary it:
//!
//! ```toml
//! name = "bias-map"
//! base = "../paper/fig3.toml"   # relative to the study file
//! seed = 1                      # the study seed
//! set = ["simulation.horizon=10"]   # optional overrides for every run
//!
//! [[axis]]                      # a grid axis (the grid is their product)
//! keys = ["uncertainty.a_bias", "uncertainty.b_bias"]   # one value, several keys
//! name = "bias"                 # its column in results.csv (default: the first key)
//! values = { from = 0.0, to = 3.0, step = 0.05 }        # or [..], or { from, to, n, scale = "log" }
//!
//! [[axis]]
//! key = "controller.kind"
//! values = ["vsc", "nnvsc"]
//!
//! [monte_carlo]                 # optional: replicates of every grid point
//! runs = 100
//! [[monte_carlo.draw]]
//! key = "controller.gamma1"
//! dist = "uniform"              # uniform | loguniform | normal | choice
//! low = 50.0
//! high = 200.0
//! ```
//!
//! Runs are numbered i = g·R + r (grid point g in row-major order of the
//! axes, replicate r of R). Run i has the seed `derive(study seed, i)`
//! (SplitMix64): it drives the run's draws and, in Monte Carlo studies, its
//! `uncertainty.seed`. Every run is a pure function of (study, i), so the
//! results are identical bit for bit whatever the thread count or the shard
//! split (`--shard K/N` runs the K-th of N contiguous slices, K from 0).

pub mod plots;

use crate::metrics::Metrics;
use crate::output::{write_atomic, Staging, SOFTWARE};
use crate::run::{run, Keep};
use crate::scenario::{parse_value, Scenario, ScenarioError};
use anyhow::{anyhow, bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The values of an axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(
    untagged,
    expecting = "expected a list of values, { from, to, step } or { from, to, n, scale = \"linear\" | \"log\" }"
)]
pub enum AxisValues {
    /// An explicit list (numbers, strings or booleans).
    List(Vec<toml::Value>),
    /// `{ from, to, step }`: from, from + step, … up to `to` (inclusive within 1e-9).
    Step {
        /// First value.
        from: f64,
        /// Last value.
        to: f64,
        /// Increment (> 0).
        step: f64,
    },
    /// `{ from, to, n, scale }`: n values, linearly or logarithmically spaced.
    Count {
        /// First value.
        from: f64,
        /// Last value.
        to: f64,
        /// How many (≥ 2).
        n: u32,
        /// `"linear"` (default) or `"log"`.
        #[serde(default)]
        scale: Scale,
    },
}

/// Spacing of a counted axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Scale {
    /// Equal differences.
    #[default]
    Linear,
    /// Equal ratios.
    Log,
}

/// One grid axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Axis {
    /// One key (shorthand for `keys = [key]`).
    #[serde(default)]
    pub key: Option<String>,
    /// Several keys set to the same value.
    #[serde(default)]
    pub keys: Vec<String>,
    /// Column name (default: the first key).
    #[serde(default)]
    pub name: Option<String>,
    /// The values.
    pub values: AxisValues,
}

/// A distribution to draw a key from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Draw {
    /// The key.
    pub key: String,
    /// `uniform`, `loguniform`, `normal` or `choice`.
    pub dist: Dist,
    /// Lower bound (uniform, loguniform).
    #[serde(default)]
    pub low: Option<f64>,
    /// Upper bound (uniform, loguniform).
    #[serde(default)]
    pub high: Option<f64>,
    /// Mean (normal).
    #[serde(default)]
    pub mean: Option<f64>,
    /// Standard deviation (normal).
    #[serde(default)]
    pub sd: Option<f64>,
    /// Values (choice).
    #[serde(default)]
    pub values: Vec<toml::Value>,
}

/// Distribution names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Dist {
    /// Uniform on [low, high).
    Uniform,
    /// log-uniform on [low, high).
    Loguniform,
    /// Normal(mean, sd).
    Normal,
    /// One of `values`, equally likely.
    Choice,
}

/// `[monte_carlo]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MonteCarlo {
    /// Replicates per grid point.
    pub runs: u32,
    /// Keys drawn per run (in this order).
    #[serde(default)]
    pub draw: Vec<Draw>,
}

/// A study file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Study {
    /// Name.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The base scenario, relative to the study file.
    pub base: String,
    /// The study seed.
    #[serde(default)]
    pub seed: u64,
    /// Overrides applied to every run (`key.path=value`).
    #[serde(default)]
    pub set: Vec<String>,
    /// Grid axes.
    #[serde(default)]
    pub axis: Vec<Axis>,
    /// Monte Carlo replicates.
    #[serde(default)]
    pub monte_carlo: Option<MonteCarlo>,
}

/// Largest number of runs a study may ask for.
pub const MAX_RUNS: u64 = 2_000_000;

/// SplitMix64: the seed of run `i` of a study with seed `seed`.
pub fn derive_seed(seed: u64, i: u64) -> u64 {
    let mut z = seed
        ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A small deterministic stream of uniforms on [0, 1) from a run seed.
struct Stream(u64);

impl Stream {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let z = derive_seed(self.0, 0);
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

impl Axis {
    /// The keys this axis sets.
    pub fn keys(&self) -> Vec<String> {
        let mut k: Vec<String> = self.key.iter().cloned().collect();
        k.extend(self.keys.iter().cloned());
        k
    }

    /// The column name.
    pub fn column(&self) -> String {
        self.name
            .clone()
            .unwrap_or_else(|| self.keys().first().cloned().unwrap_or_default())
    }

    /// The values, expanded.
    pub fn expand(&self) -> Result<Vec<toml::Value>, String> {
        match &self.values {
            AxisValues::List(v) => {
                if v.is_empty() {
                    return Err("`values` is empty".into());
                }
                Ok(v.clone())
            }
            AxisValues::Step { from, to, step } => {
                if !(from.is_finite()
                    && to.is_finite()
                    && step.is_finite()
                    && *step > 0.0
                    && to >= from)
                {
                    return Err(format!(
                        "needs finite from ≤ to and step > 0 (got {from}, {to}, {step})"
                    ));
                }
                let n = ((to - from) / step + 1e-9).floor() as u64 + 1;
                if n > MAX_RUNS {
                    return Err(format!("{n} values is too many"));
                }
                // from + k·step, never accumulated.
                Ok((0..n)
                    .map(|k| toml::Value::Float(from + k as f64 * step))
                    .collect())
            }
            AxisValues::Count { from, to, n, scale } => {
                if *n < 2 || !from.is_finite() || !to.is_finite() {
                    return Err(format!("needs finite from, to and n ≥ 2 (got n = {n})"));
                }
                if *scale == Scale::Log && (*from <= 0.0 || *to <= 0.0) {
                    return Err("a log scale needs from, to > 0".into());
                }
                Ok((0..*n)
                    .map(|k| {
                        let f = k as f64 / (*n - 1) as f64;
                        toml::Value::Float(match scale {
                            Scale::Linear => from + f * (to - from),
                            Scale::Log => (from.ln() + f * (to.ln() - from.ln())).exp(),
                        })
                    })
                    .collect())
            }
        }
    }
}

impl Draw {
    fn check(&self) -> Result<(), String> {
        let ok = |v: Option<f64>| v.is_some_and(f64::is_finite);
        match self.dist {
            Dist::Uniform | Dist::Loguniform => {
                if !(ok(self.low) && ok(self.high) && self.low < self.high) {
                    return Err("needs finite low < high".into());
                }
                if self.dist == Dist::Loguniform && self.low.unwrap_or(0.0) <= 0.0 {
                    return Err("loguniform needs low > 0".into());
                }
            }
            Dist::Normal => {
                if !(ok(self.mean) && ok(self.sd) && self.sd.unwrap_or(-1.0) >= 0.0) {
                    return Err("needs finite mean and sd ≥ 0".into());
                }
            }
            Dist::Choice => {
                if self.values.is_empty() {
                    return Err("needs a non-empty `values`".into());
                }
            }
        }
        Ok(())
    }

    fn sample(&self, s: &mut Stream) -> toml::Value {
        let (lo, hi) = (self.low.unwrap_or(0.0), self.high.unwrap_or(1.0));
        match self.dist {
            Dist::Uniform => toml::Value::Float(lo + (hi - lo) * s.next()),
            Dist::Loguniform => {
                toml::Value::Float((lo.ln() + (hi.ln() - lo.ln()) * s.next()).exp())
            }
            Dist::Normal => {
                // Box–Muller from two uniforms (1 − u keeps the log finite).
                let (u1, u2) = (1.0 - s.next(), s.next());
                let z = (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos();
                toml::Value::Float(self.mean.unwrap_or(0.0) + self.sd.unwrap_or(0.0) * z)
            }
            Dist::Choice => {
                let i = ((s.next() * self.values.len() as f64) as usize).min(self.values.len() - 1);
                self.values[i].clone()
            }
        }
    }
}

/// A study, checked, with its base scenario and expanded axes.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The study as written.
    pub study: Study,
    /// The base scenario with `set` applied.
    pub base: Scenario,
    /// Expanded values of every axis.
    pub axes: Vec<(Axis, Vec<toml::Value>)>,
    /// Replicates per grid point (1 without Monte Carlo).
    pub replicates: u64,
    /// Total runs.
    pub runs: u64,
}

/// A study file could not be used: file, key, reason (exit code 2).
#[derive(Debug, Clone)]
pub struct StudyError(pub String);

impl std::fmt::Display for StudyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for StudyError {}

impl Plan {
    /// Reads and checks a study file (and its base scenario).
    pub fn load(path: &Path) -> Result<Plan, StudyError> {
        let file = path.display().to_string();
        let bad = |key: &str, lc: Option<(usize, usize)>, reason: String| {
            let at = lc.map(|(l, c)| format!(":{l}:{c}")).unwrap_or_default();
            StudyError(if key.is_empty() {
                format!("{file}{at}: {reason}")
            } else {
                format!("{file}{at}: `{key}`: {reason}")
            })
        };
        let text = std::fs::read_to_string(path)
            .map_err(|e| bad("", None, format!("cannot read the study file: {e}")))?;
        let de = toml::Deserializer::parse(&text).map_err(|e| {
            let lc = e
                .span()
                .map(|sp| crate::scenario::line_col(&text, sp.start));
            bad(
                "",
                lc,
                format!(
                    "TOML syntax error: {}",
                    e.message().lines().next().unwrap_or("")
                ),
            )
        })?;
        let study: Study = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = e.path().to_string();
            let inner = e.into_inner();
            let lc = inner
                .span()
                .map(|sp| crate::scenario::line_col(&text, sp.start));
            bad(
                if key == "." { "" } else { &key },
                lc,
                inner.message().lines().next().unwrap_or("").to_string(),
            )
        })?;
        let base_path = path.parent().unwrap_or(Path::new(".")).join(&study.base);
        let base = Scenario::load(&base_path, &study.set)
            .map_err(|e: ScenarioError| StudyError(format!("{file}: base: {e}")))?;
        Self::build(study, base, &file)
    }

    fn build(study: Study, base: Scenario, file: &str) -> Result<Plan, StudyError> {
        let bad = |key: String, reason: String| StudyError(format!("{file}: `{key}`: {reason}"));
        let mut axes = Vec::new();
        let mut grid: u64 = 1;
        let mut columns: Vec<String> = Vec::new();
        for (i, a) in study.axis.iter().enumerate() {
            if a.keys().is_empty() {
                return Err(bad(format!("axis[{i}]"), "needs `key` or `keys`".into()));
            }
            let vals = a
                .expand()
                .map_err(|r| bad(format!("axis[{i}].values"), r))?;
            grid = grid.saturating_mul(vals.len() as u64);
            if columns.contains(&a.column()) {
                return Err(bad(
                    format!("axis[{i}]"),
                    format!("column `{}` appears twice", a.column()),
                ));
            }
            columns.push(a.column());
            // Every value must give a valid scenario (first and last suffice
            // for ranges; lists are checked whole).
            let probe: Vec<&toml::Value> = match a.values {
                AxisValues::List(_) => vals.iter().collect(),
                _ => vec![&vals[0], &vals[vals.len() - 1]],
            };
            for v in probe {
                let set: Vec<(String, toml::Value)> =
                    a.keys().into_iter().map(|k| (k, v.clone())).collect();
                base.with_values(&set)
                    .map_err(|e| bad(format!("axis[{i}]"), format!("value {v}: {e}")))?;
            }
        }
        let replicates = match &study.monte_carlo {
            Some(mc) => {
                if mc.runs == 0 {
                    return Err(bad("monte_carlo.runs".into(), "must be ≥ 1".into()));
                }
                for (j, d) in mc.draw.iter().enumerate() {
                    d.check()
                        .map_err(|r| bad(format!("monte_carlo.draw[{j}]"), r))?;
                    if columns.contains(&d.key) {
                        return Err(bad(
                            format!("monte_carlo.draw[{j}]"),
                            format!("`{}` is also an axis", d.key),
                        ));
                    }
                    columns.push(d.key.clone());
                }
                mc.runs as u64
            }
            None => 1,
        };
        let runs = grid.saturating_mul(replicates);
        if runs > MAX_RUNS {
            return Err(bad(
                "axis".into(),
                format!("{runs} runs exceed the limit of {MAX_RUNS}"),
            ));
        }
        for (i, a) in study.axis.iter().enumerate() {
            let vals = a
                .expand()
                .map_err(|r| bad(format!("axis[{i}].values"), r))?;
            axes.push((a.clone(), vals));
        }
        Ok(Plan {
            study,
            base,
            axes,
            replicates,
            runs,
        })
    }

    /// The varied columns of results.csv, in order: axes, then drawn keys.
    pub fn columns(&self) -> Vec<String> {
        let mut c: Vec<String> = self.axes.iter().map(|(a, _)| a.column()).collect();
        if let Some(mc) = &self.study.monte_carlo {
            c.extend(mc.draw.iter().map(|d| d.key.clone()));
        }
        c
    }

    /// The values of run `i`: (column values, scenario overrides, seed).
    pub fn run_values(&self, i: u64) -> (Vec<toml::Value>, Vec<(String, toml::Value)>, u64) {
        let seed = derive_seed(self.study.seed, i);
        let mut g = i / self.replicates;
        let mut idx = vec![0usize; self.axes.len()];
        for (k, (_, vals)) in self.axes.iter().enumerate().rev() {
            let n = vals.len() as u64;
            idx[k] = (g % n) as usize;
            g /= n;
        }
        let mut cols = Vec::new();
        let mut sets = Vec::new();
        for (k, (a, vals)) in self.axes.iter().enumerate() {
            let v = vals[idx[k]].clone();
            for key in a.keys() {
                sets.push((key, v.clone()));
            }
            cols.push(v);
        }
        if let Some(mc) = &self.study.monte_carlo {
            sets.push((
                "uncertainty.seed".into(),
                toml::Value::Integer((seed >> 1) as i64),
            ));
            let mut s = Stream(seed);
            for d in &mc.draw {
                let v = d.sample(&mut s);
                sets.push((d.key.clone(), v.clone()));
                cols.push(v);
            }
        }
        (cols, sets, seed)
    }

    /// The run indices of shard `k` of `n` (contiguous).
    pub fn shard_range(&self, k: u64, n: u64) -> std::ops::Range<u64> {
        let lo = (self.runs as u128 * k as u128 / n as u128) as u64;
        let hi = (self.runs as u128 * (k + 1) as u128 / n as u128) as u64;
        lo..hi
    }
}

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
    let work = || -> Vec<RunRow> {
        range
            .clone()
            .into_par_iter()
            .map(|i| {
                let (values, sets, seed) = plan.run_values(i);
                let row = match plan.base.with_values(&sets) {
                    Ok(s) => match run(&s, Keep::Nothing) {
                        Ok(r) => RunRow {
                            index: i,
                            values,
                            seed,
                            metrics: Some(r.metrics),
                            error: None,
                        },
                        Err(e) => RunRow {
                            index: i,
                            values,
                            seed,
                            metrics: None,
                            error: Some(e.to_string()),
                        },
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
    match threads {
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n.max(1))
                .build()
                .context("building the thread pool")?;
            Ok(pool.install(work))
        }
        None => Ok(work()),
    }
}

/// The metric columns of results.csv, in order.
pub const METRIC_COLUMNS: [&str; 13] = Metrics::NAMES;

fn cell(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        toml::Value::Float(f) => format!("{f}"),
        other => other.to_string(),
    }
}

/// results.csv (header + rows in run order).
pub fn results_csv(plan: &Plan, rows: &[RunRow]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut head: Vec<String> = vec!["run".into()];
    head.extend(plan.columns());
    head.push("seed".into());
    head.extend(METRIC_COLUMNS.iter().map(|s| s.to_string()));
    head.push("error".into());
    w.write_record(&head)?;
    for r in rows {
        let mut rec: Vec<String> = vec![r.index.to_string()];
        rec.extend(r.values.iter().map(cell));
        rec.push(r.seed.to_string());
        match &r.metrics {
            Some(m) => rec.extend(METRIC_COLUMNS.iter().map(|k| m.cell(k))),
            None => rec.extend(std::iter::repeat_n(String::new(), METRIC_COLUMNS.len())),
        }
        rec.push(r.error.clone().unwrap_or_default());
        w.write_record(&rec)?;
    }
    w.into_inner().map_err(|e| anyhow!("{e}"))
}

/// study.json: the study as run.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct StudyRecord {
    /// Software name.
    pub software: String,
    /// Software version.
    pub version: String,
    /// The study file as parsed.
    pub study: Study,
    /// The base scenario with the study's `set` applied.
    pub base: serde_json::Value,
    /// Total runs of the study.
    pub runs: u64,
    /// This output's shard `[k, n]` (None: the whole study).
    pub shard: Option<[u64; 2]>,
    /// Run indices in this output.
    pub range: [u64; 2],
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
    let record = StudyRecord {
        software: SOFTWARE.name.into(),
        version: SOFTWARE.version.into(),
        study: plan.study.clone(),
        base: serde_json::to_value(&plan.base)?,
        runs: plan.runs,
        shard: opts.shard.map(|(k, n)| [k, n]),
        range: [range.start, range.end],
    };
    write_atomic(
        &stage.path().join("study.json"),
        serde_json::to_string_pretty(&record)?.as_bytes(),
    )?;
    if opts.plots && opts.shard.is_none() {
        plots::study_plots(plan, &rows, stage.path())?;
    }
    stage.commit()?;
    Ok(rows)
}

/// Joins shard outputs into one results.csv (rows in run order), refusing
/// shards of different studies, overlaps and gaps.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<u64> {
    if dirs.is_empty() {
        bail!("nothing to merge");
    }
    let mut records: Vec<(PathBuf, StudyRecord)> = Vec::new();
    for d in dirs {
        let p = d.join("study.json");
        let text =
            std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        let r: StudyRecord =
            serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))?;
        records.push((d.clone(), r));
    }
    let (first_dir, first) = records[0].clone();
    for (d, r) in &records[1..] {
        if r.study != first.study || r.base != first.base || r.runs != first.runs {
            bail!(
                "{} and {} are outputs of different studies: refusing to merge",
                first_dir.display(),
                d.display()
            );
        }
        if r.version != first.version {
            bail!(
                "{} was written by {} {} and {} by {}: refusing to merge",
                first_dir.display(),
                first.software,
                first.version,
                d.display(),
                r.version
            );
        }
    }
    records.sort_by_key(|(_, r)| r.range[0]);
    let mut next = 0u64;
    for (d, r) in &records {
        if r.range[0] != next {
            bail!(
                "runs {}..{} are {} (at {}): shards overlap or one is missing",
                next,
                r.range[0],
                if r.range[0] > next {
                    "missing"
                } else {
                    "duplicated"
                },
                d.display()
            );
        }
        next = r.range[1];
    }
    if next != first.runs {
        bail!("runs {next}..{} are missing: a shard is absent", first.runs);
    }
    let mut out_bytes: Vec<u8> = Vec::new();
    let mut header: Option<String> = None;
    for (d, _) in &records {
        let p = d.join("results.csv");
        let text =
            std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        let mut lines = text.split_inclusive('\n');
        let h = lines.next().unwrap_or_default().to_string();
        match &header {
            None => {
                out_bytes.extend_from_slice(h.as_bytes());
                header = Some(h);
            }
            Some(h0) if *h0 != h => bail!("{}: a different header", p.display()),
            _ => {}
        }
        for l in lines {
            out_bytes.extend_from_slice(l.as_bytes());
        }
    }
    let stage = Staging::new(out)?;
    write_atomic(&stage.path().join("results.csv"), &out_bytes)?;
    let merged = StudyRecord {
        shard: None,
        range: [0, first.runs],
        ..first.clone()
    };
    write_atomic(
        &stage.path().join("study.json"),
        serde_json::to_string_pretty(&merged)?.as_bytes(),
    )?;
    stage.commit()?;
    Ok(first.runs)
}

/// Parses `K/N` (0 ≤ K < N).
pub fn parse_shard(s: &str) -> Result<(u64, u64), String> {
    let (k, n) = s.split_once('/').ok_or("expected K/N, e.g. 0/4")?;
    let k: u64 = k
        .trim()
        .parse()
        .map_err(|_| format!("K in {s} is not a whole number"))?;
    let n: u64 = n
        .trim()
        .parse()
        .map_err(|_| format!("N in {s} is not a whole number"))?;
    if n == 0 || k >= n {
        return Err(format!("need 0 ≤ K < N (got {k}/{n}); K counts from 0"));
    }
    Ok((k, n))
}

/// The value of a column as a number, if it is one.
pub fn as_f64(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// Parses an override's value (re-exported for the CLI).
pub fn value(raw: &str) -> toml::Value {
    parse_value(raw)
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    fn plan(text: &str) -> Plan {
        let study: Study = toml::from_str(text).unwrap();
        Plan::build(study, Scenario::parse("").unwrap(), "t.toml").unwrap()
    }

    #[test]
    fn grid_order_and_values() {
        let p = plan(
            r#"name = "t"
base = "x"
[[axis]]
key = "controller.gamma1"
values = { from = 50.0, to = 150.0, step = 50.0 }
[[axis]]
keys = ["uncertainty.a_bias", "uncertainty.b_bias"]
name = "bias"
values = [0.0, 0.5]
"#,
        );
        assert_eq!(p.runs, 6);
        assert_eq!(p.columns(), vec!["controller.gamma1", "bias"]);
        // Row-major: the last axis varies fastest.
        let (c, sets, _) = p.run_values(3);
        assert_eq!(c, vec![toml::Value::Float(100.0), toml::Value::Float(0.5)]);
        assert_eq!(sets.len(), 3);
        assert_eq!(sets[1].0, "uncertainty.a_bias");
        assert_eq!(sets[2].0, "uncertainty.b_bias");
    }

    #[test]
    fn log_axis_and_shards() {
        let p = plan(
            r#"name = "t"
base = "x"
[[axis]]
key = "controller.gamma1"
values = { from = 10.0, to = 1000.0, n = 3, scale = "log" }
"#,
        );
        let v: Vec<f64> = (0..3)
            .map(|i| as_f64(&p.run_values(i).0[0]).unwrap())
            .collect();
        assert!((v[1] - 100.0).abs() < 1e-9 && (v[2] - 1000.0).abs() < 1e-9);
        // 3 runs in 2 shards: 0..1 and 1..3.
        assert_eq!(p.shard_range(0, 2), 0..1);
        assert_eq!(p.shard_range(1, 2), 1..3);
        assert_eq!(parse_shard("1/2"), Ok((1, 2)));
        assert!(parse_shard("2/2").is_err());
    }

    #[test]
    fn draws_are_seeded_and_in_range() {
        let p = plan(
            r#"name = "t"
base = "x"
seed = 7
[monte_carlo]
runs = 200
[[monte_carlo.draw]]
key = "controller.gamma1"
dist = "uniform"
low = 50.0
high = 200.0
[[monte_carlo.draw]]
key = "controller.eta"
dist = "normal"
mean = 0.25
sd = 0.01
"#,
        );
        let draws: Vec<f64> = (0..200)
            .map(|i| as_f64(&p.run_values(i).0[0]).unwrap())
            .collect();
        assert!(draws.iter().all(|g| (50.0..200.0).contains(g)));
        let mean = draws.iter().sum::<f64>() / 200.0;
        assert!((mean - 125.0).abs() < 10.0, "{mean}");
        // The same run gives the same draw and seed, whoever asks.
        assert_eq!(p.run_values(17), p.run_values(17));
        assert_ne!(p.run_values(17).2, p.run_values(18).2);
        let eta: Vec<f64> = (0..200)
            .map(|i| as_f64(&p.run_values(i).0[1]).unwrap())
            .collect();
        let m = eta.iter().sum::<f64>() / 200.0;
        let sd = (eta.iter().map(|e| (e - m) * (e - m)).sum::<f64>() / 199.0).sqrt();
        assert!(
            (m - 0.25).abs() < 0.003 && (sd - 0.01).abs() < 0.002,
            "{m} {sd}"
        );
    }

    #[test]
    fn bad_studies_name_the_key() {
        let study: Study = toml::from_str(
            r#"name = "t"
base = "x"
[[axis]]
key = "controller.gamma1"
values = [-1.0]
"#,
        )
        .unwrap();
        let e = Plan::build(study, Scenario::parse("").unwrap(), "t.toml").unwrap_err();
        assert!(e.0.contains("axis[0]") && e.0.contains("gamma1"), "{e}");
    }
}
