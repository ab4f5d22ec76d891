//! What a sweep writes: the columns and rows of `results.csv`, and
//! `study.json`.

use super::{Plan, RunRow, Study};
use crate::metrics::Metrics;
use anyhow::{anyhow, Result};
use serde::{Deserialize, Serialize};

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

/// The value of a column as a number, if it is one.
pub fn as_f64(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}
