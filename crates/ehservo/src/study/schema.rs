//! The study file format: its types, how a file is read, and the checks
//! that turn it into a [`Plan`].

use super::Plan;
use crate::scenario::{parse_value, Scenario, ScenarioError};
use serde::{Deserialize, Serialize};
use std::path::Path;

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

    pub(super) fn build(study: Study, base: Scenario, file: &str) -> Result<Plan, StudyError> {
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
}

/// Parses an override's value (re-exported for the CLI).
pub fn value(raw: &str) -> toml::Value {
    parse_value(raw)
}

#[cfg(test)]
mod tests {
    use super::*;

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
