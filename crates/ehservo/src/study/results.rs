//! What a sweep writes: the columns and rows of `results.csv`, and
//! `study.json`.

use super::{Plan, RunRow, Study};
use crate::axis::Axis;
use crate::metrics::Metrics;
use anyhow::{anyhow, Result};
use serde::{Deserialize, Serialize};

/// The metric columns of a rotary axis's results.csv, in order (a linear
/// axis's are [`Metrics::CSV_LINEAR`]: `e_max_mm` for `e_max_deg`).
pub const METRIC_COLUMNS: [&str; 13] = Metrics::NAMES;

/// A number as a cell: the shortest decimal that reads back to the same
/// f64, with an exponent for very large or small magnitudes (`1e308`, not
/// 309 digits); empty if it is not finite (the plan and the metrics never
/// give one, and results.csv never holds NaN or ∞).
pub(crate) fn number_cell(f: f64) -> String {
    if f.is_finite() {
        format!("{f:?}")
    } else {
        String::new()
    }
}

fn cell(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        toml::Value::Float(f) => number_cell(*f),
        other => other.to_string(),
    }
}

/// A metric's cell: `true`/`false` for `diverged`, an integer for
/// `samples`, a number otherwise, empty when undefined.
fn metric_cell(m: &Metrics, name: &str) -> String {
    match name {
        "diverged" => m.diverged.to_string(),
        "samples" => m.samples.to_string(),
        _ => m.get(name).map(number_cell).unwrap_or_default(),
    }
}

/// The header of results.csv for a study's varied columns on `axis`.
pub(crate) fn header(columns: Vec<String>, axis: Axis) -> Vec<String> {
    let mut head: Vec<String> = vec!["run".into()];
    head.extend(columns);
    head.push("seed".into());
    head.extend(Metrics::csv_names(axis).iter().map(|s| s.to_string()));
    head.extend(
        crate::behaviour::columns(axis)
            .iter()
            .map(|s| s.to_string()),
    );
    head.push("error".into());
    head
}

/// results.csv (header + rows in run order).
pub fn results_csv(plan: &Plan, rows: &[RunRow]) -> Result<Vec<u8>> {
    let axis = plan.axis();
    let names = Metrics::csv_names(axis);
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header(plan.columns(), axis))?;
    for r in rows {
        let mut rec: Vec<String> = vec![r.index.to_string()];
        rec.extend(r.values.iter().map(cell));
        rec.push(r.seed.to_string());
        match &r.metrics {
            Some(m) => {
                rec.extend(names.iter().map(|k| metric_cell(m, k)));
                rec.extend(m.behaviour.cells(m.diverged));
            }
            None => rec.extend(std::iter::repeat_n(
                String::new(),
                names.len() + crate::behaviour::columns(axis).len(),
            )),
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
    /// The base scenario's axis (the unit of the error columns); absent
    /// for a rotary one.
    #[serde(default, skip_serializing_if = "is_rotary")]
    pub axis: Axis,
}

fn is_rotary(a: &Axis) -> bool {
    *a == Axis::Rotary
}

/// The value of a column as a number, if it is one.
pub fn as_f64(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short_and_finite() {
        assert_eq!(number_cell(1e308), "1e308");
        assert_eq!(number_cell(-1.5e-300), "-1.5e-300");
        assert_eq!(number_cell(0.25), "0.25");
        assert_eq!(number_cell(100.0), "100.0");
        assert_eq!(number_cell(0.1 + 0.2), "0.30000000000000004");
        assert_eq!(number_cell(f64::MAX).parse::<f64>(), Ok(f64::MAX));
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(number_cell(x), "");
        }
        assert_eq!(cell(&toml::Value::Float(1e300)), "1e300");
        assert_eq!(cell(&toml::Value::Integer(3)), "3");
        assert_eq!(cell(&toml::Value::String("vsc".into())), "vsc");
    }
}
