//! The study file format: its types, how a file is read, and the checks
//! that turn it into a [`Plan`].

use super::Plan;
use crate::error::InputError;
use crate::scenario::{parse_value, Loop, Reason, ScenarioError};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// `Plan::load` and `Plan::build`: the checks that turn a study file into
/// a plan (size, columns, axes, draws).
mod plan;

/// The values of an axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(
    untagged,
    expecting = "expected a list of values, { from, to, step } or { from, to, n, scale = \"linear\" | \"log\" }"
)]
pub enum AxisValues {
    /// An explicit list (numbers, strings or booleans).
    List(#[schemars(with = "Vec<crate::schema::TomlValue>")] Vec<toml::Value>),
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
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Scale {
    /// Equal differences.
    #[default]
    Linear,
    /// Equal ratios.
    Log,
}

/// One grid axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
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
    #[schemars(with = "Vec<crate::schema::TomlValue>")]
    pub values: Vec<toml::Value>,
}

/// Distribution names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MonteCarlo {
    /// Replicates per grid point.
    pub runs: u32,
    /// Keys drawn per run (in this order).
    #[serde(default)]
    pub draw: Vec<Draw>,
}

/// A study file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
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

/// The largest |z| a normal draw can reach: Box–Muller from u1 ≥ 2⁻⁵³
/// gives |z| ≤ √(−2 ln 2⁻⁵³) ≈ 8.57, rounded up.
const NORMAL_Z_MAX: f64 = 9.0;

/// A value for a message: floats in the shortest form that reads back
/// (`1e308`, not 309 digits).
fn show(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(f) => format!("{f:?}"),
        toml::Value::Array(a) => format!("[{}]", a.iter().map(show).collect::<Vec<_>>().join(", ")),
        other => other.to_string(),
    }
}

/// Whether every number in a value (and in its arrays and tables) is finite.
fn all_finite(v: &toml::Value) -> bool {
    match v {
        toml::Value::Float(f) => f.is_finite(),
        toml::Value::Array(a) => a.iter().all(all_finite),
        toml::Value::Table(t) => t.values().all(all_finite),
        _ => true,
    }
}

impl Study {
    /// The varied columns of results.csv, in order: axes, then drawn keys.
    pub fn columns(&self) -> Vec<String> {
        let mut c: Vec<String> = self.axis.iter().map(Axis::column).collect();
        if let Some(mc) = &self.monte_carlo {
            c.extend(mc.draw.iter().map(|d| d.key.clone()));
        }
        c
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

    /// How many values the axis has, computed without expanding it: a
    /// range that is not finite, whose width `to − from` overflows, or
    /// whose count exceeds [`MAX_RUNS`] is an error, so nothing is ever
    /// allocated or indexed from an overflowed count.
    pub fn count(&self) -> Result<u64, String> {
        match &self.values {
            AxisValues::List(v) => {
                if v.is_empty() {
                    return Err("`values` is empty".into());
                }
                Ok(v.len() as u64)
            }
            AxisValues::Step { from, to, step } => {
                if !(from.is_finite()
                    && to.is_finite()
                    && step.is_finite()
                    && *step > 0.0
                    && to >= from)
                {
                    return Err(format!(
                        "needs finite from ≤ to and step > 0 (got {from:?}, {to:?}, {step:?})"
                    ));
                }
                let width = to - from;
                if !width.is_finite() {
                    return Err(format!(
                        "the width to − from = {to:?} − {from:?} overflows a float"
                    ));
                }
                // The count as a float first: a huge quotient must not
                // saturate (or wrap) an integer. (Never NaN: width ≥ 0 and
                // step > 0 are finite; ∞ is caught here.)
                let q = (width / step + 1e-9).floor();
                if q >= MAX_RUNS as f64 {
                    return Err(format!(
                        "from {from:?} to {to:?} by {step:?} is more than {MAX_RUNS} values (the run limit)"
                    ));
                }
                Ok(q as u64 + 1)
            }
            AxisValues::Count { from, to, n, scale } => {
                if *n < 2 || !from.is_finite() || !to.is_finite() {
                    return Err(format!("needs finite from, to and n ≥ 2 (got n = {n})"));
                }
                if u64::from(*n) > MAX_RUNS {
                    return Err(format!(
                        "n = {n} values is more than {MAX_RUNS} (the run limit)"
                    ));
                }
                match scale {
                    Scale::Log if *from <= 0.0 || *to <= 0.0 => {
                        return Err(format!(
                            "a log scale needs from, to > 0 (got {from:?}, {to:?})"
                        ))
                    }
                    Scale::Linear if !(to - from).is_finite() => {
                        return Err(format!(
                            "the width to − from = {to:?} − {from:?} overflows a float"
                        ))
                    }
                    _ => {}
                }
                Ok(u64::from(*n))
            }
        }
    }

    /// The values, expanded (after [`Axis::count`] has bounded their
    /// number); every number among them is finite.
    pub fn expand(&self) -> Result<Vec<toml::Value>, String> {
        let n = self.count()?;
        let vals: Vec<toml::Value> = match &self.values {
            AxisValues::List(v) => v.clone(),
            // from + k·step, never accumulated.
            AxisValues::Step { from, step, .. } => (0..n)
                .map(|k| toml::Value::Float(from + k as f64 * step))
                .collect(),
            // The ends exactly as written, the values between them kept
            // inside [from, to] (exp∘ln of a `to` near the largest float
            // could round to ∞).
            AxisValues::Count {
                from, to, scale, ..
            } => (0..n)
                .map(|k| {
                    let f = k as f64 / (n - 1) as f64;
                    toml::Value::Float(match k {
                        0 => *from,
                        _ if k == n - 1 => *to,
                        _ => match scale {
                            Scale::Linear => from + f * (to - from),
                            Scale::Log => (from.ln() + f * (to.ln() - from.ln())).exp(),
                        }
                        .clamp(from.min(*to), from.max(*to)),
                    })
                })
                .collect(),
        };
        if let Some((k, v)) = vals.iter().enumerate().find(|(_, v)| !all_finite(v)) {
            return Err(format!("value {k} ({}) is not a finite number", show(v)));
        }
        Ok(vals)
    }
}

impl Draw {
    /// Checks the parameters: finite, in their domain, only those of the
    /// distribution, and such that no draw can overflow to ±∞ or NaN.
    fn check(&self) -> Result<(), String> {
        let ok = |v: Option<f64>| v.is_some_and(f64::is_finite);
        let name = match self.dist {
            Dist::Uniform => "uniform",
            Dist::Loguniform => "loguniform",
            Dist::Normal => "normal",
            Dist::Choice => "choice",
        };
        let given = [
            ("low", self.low.is_some()),
            ("high", self.high.is_some()),
            ("mean", self.mean.is_some()),
            ("sd", self.sd.is_some()),
            ("values", !self.values.is_empty()),
        ];
        let wanted: &[&str] = match self.dist {
            Dist::Uniform | Dist::Loguniform => &["low", "high"],
            Dist::Normal => &["mean", "sd"],
            Dist::Choice => &["values"],
        };
        if let Some((k, _)) = given.iter().find(|(k, g)| *g && !wanted.contains(k)) {
            return Err(format!(
                "`{k}` does not apply to a {name} draw (it takes {})",
                wanted.join(", ")
            ));
        }
        match self.dist {
            Dist::Uniform | Dist::Loguniform => {
                if !(ok(self.low) && ok(self.high) && self.low < self.high) {
                    return Err("needs finite low < high".into());
                }
                let (lo, hi) = (self.low.unwrap_or(0.0), self.high.unwrap_or(1.0));
                if self.dist == Dist::Loguniform && lo <= 0.0 {
                    return Err("loguniform needs low > 0".into());
                }
                if !(hi - lo).is_finite() {
                    return Err(format!(
                        "the width high − low = {hi:?} − {lo:?} overflows a float"
                    ));
                }
            }
            Dist::Normal => {
                if !(ok(self.mean) && ok(self.sd) && self.sd.unwrap_or(-1.0) >= 0.0) {
                    return Err("needs finite mean and sd ≥ 0".into());
                }
                let (m, sd) = (self.mean.unwrap_or(0.0), self.sd.unwrap_or(0.0));
                if !(m.abs() + NORMAL_Z_MAX * sd).is_finite() {
                    return Err(format!(
                        "draws of mean ± {NORMAL_Z_MAX:?}·sd (mean {m:?}, sd {sd:?}) overflow a float"
                    ));
                }
            }
            Dist::Choice => {
                if self.values.is_empty() {
                    return Err("needs a non-empty `values`".into());
                }
                if let Some(v) = self.values.iter().find(|v| !all_finite(v)) {
                    return Err(format!("value {} is not a finite number", show(v)));
                }
            }
        }
        Ok(())
    }

    /// Values to try on the base scenario, as an axis's values are tried:
    /// the middle of a range (its ends may be open, or outside a key's
    /// domain only at the edge), the mean, or every choice.
    fn probes(&self) -> Vec<toml::Value> {
        let (lo, hi) = (self.low.unwrap_or(0.0), self.high.unwrap_or(1.0));
        match self.dist {
            Dist::Uniform => vec![toml::Value::Float(lo + (hi - lo) / 2.0)],
            Dist::Loguniform => vec![toml::Value::Float(
                ((lo.ln() + hi.ln()) / 2.0).exp().clamp(lo, hi),
            )],
            Dist::Normal => vec![toml::Value::Float(self.mean.unwrap_or(0.0))],
            Dist::Choice => self.values.clone(),
        }
    }
}

/// Reads a TOML input file (a study, a tune file) into `T`; a failure is
/// one line: the file, the line and column when TOML knows them, the key
/// and the reason.
pub(crate) fn load_toml<T: serde::de::DeserializeOwned>(
    path: &Path,
    what: &str,
) -> Result<T, InputError> {
    let file = path.display().to_string();
    let bad = |key: &str, line_col: Option<(usize, usize)>, reason: String| {
        if key.is_empty() {
            InputError::File {
                file: file.clone(),
                line_col,
                reason: reason.into(),
            }
        } else {
            InputError::Key {
                file: file.clone(),
                line_col,
                key: key.to_string(),
                reason: reason.into(),
            }
        }
    };
    let text =
        crate::input::read_text(path).map_err(|r| bad("", None, format!("the {what} file {r}")))?;
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
    serde_path_to_error::deserialize(de).map_err(|e| {
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
    })
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
        let e = Plan::build(study, Loop::parse("").unwrap(), "t.toml").unwrap_err();
        assert!(
            e.to_string().contains("axis[0]") && e.to_string().contains("gamma1"),
            "{e}"
        );
    }

    fn build(text: &str) -> Result<Plan, InputError> {
        let study: Study = toml::from_str(text).unwrap();
        Plan::build(study, Loop::parse("").unwrap(), "t.toml")
    }

    #[test]
    fn sizes_are_checked_before_anything_is_expanded() {
        let axis = |values: &str| -> Axis {
            toml::from_str(&format!("key = \"controller.eta\"\nvalues = {values}")).unwrap()
        };
        // Counts that overflow a float or an integer, or exceed the limit.
        for v in [
            "{ from = 0.0, to = 1e300, step = 1e-300 }",
            "{ from = -1e308, to = 1e308, step = 1.0 }",
            "{ from = 0.0, to = 1.0, step = 5e-324 }",
            "{ from = 0.0, to = 1.0, n = 4294967295 }",
            "{ from = -1e308, to = 1e308, n = 3 }",
        ] {
            assert!(axis(v).count().is_err(), "{v}");
            assert!(axis(v).expand().is_err(), "{v}");
        }
        // The count is the number of values expanded.
        for v in [
            "{ from = 0.0, to = 3.0, step = 0.025 }",
            "{ from = 0.0, to = 1.0, step = 0.3 }",
            "{ from = 2.0, to = 2.0, step = 1.0 }",
            "{ from = 1e-300, to = 1e300, n = 7, scale = \"log\" }",
            "{ from = 5e-324, to = 1.7976931348623157e308, n = 5, scale = \"log\" }",
            "{ from = -8.9e307, to = 8.9e307, n = 5 }",
            "{ from = 1.0, to = 0.0, n = 4 }",
            "[1.0, 2.0]",
        ] {
            let a = axis(v);
            let vals = a.expand().unwrap();
            assert_eq!(a.count().unwrap(), vals.len() as u64, "{v}");
            if let AxisValues::Count { from, to, .. } = a.values {
                // The ends as written, the rest between them.
                let x: Vec<f64> = vals.iter().filter_map(toml::Value::as_float).collect();
                assert_eq!((x[0], x[x.len() - 1]), (from, to), "{v}");
                assert!(
                    x.iter().all(|x| (from.min(to)..=from.max(to)).contains(x)),
                    "{v}"
                );
            }
        }
        // Each axis within the limit, their product not: refused from the
        // counts (2000³ values would be 8·10⁹ runs).
        let e = build(
            r#"name = "t"
base = "x"
[[axis]]
key = "controller.gamma1"
values = { from = 1.0, to = 2.0, n = 2000 }
[[axis]]
key = "controller.eta"
values = { from = 0.0, to = 1.0, n = 2000 }
[[axis]]
key = "uncertainty.a_bias"
values = { from = 0.0, to = 1.0, n = 2000 }
"#,
        )
        .unwrap_err();
        assert!(e.to_string().contains("2000 × 2000 × 2000 values"), "{e}");
        // Replicates that take a grid within the limit over it.
        let e = build(
            r#"name = "t"
base = "x"
[[axis]]
key = "controller.eta"
values = { from = 0.0, to = 1.0, n = 2000000 }
[monte_carlo]
runs = 4294967295
"#,
        )
        .unwrap_err();
        assert!(e.to_string().contains("`monte_carlo.runs`"), "{e}");
    }

    #[test]
    fn draws_are_checked_like_axes() {
        for (draw, needle) in [
            // A typo: every run would have been invalid.
            (
                "key = \"controller.gama1\"\ndist = \"uniform\"\nlow = 1.0\nhigh = 2.0",
                "gama1",
            ),
            (
                "key = \"controller.eta\"\ndist = \"uniform\"\nlow = -1e308\nhigh = 1e308",
                "overflows",
            ),
            (
                "key = \"controller.eta\"\ndist = \"normal\"\nmean = 1.0\nsd = 1e308",
                "overflow",
            ),
            (
                "key = \"controller.eta\"\ndist = \"normal\"\nmean = 1.0\nsd = 0.1\nlow = 0.0",
                "`low` does not apply",
            ),
            (
                "key = \"controller.eta\"\ndist = \"choice\"\nvalues = [0.1, nan]",
                "finite",
            ),
            (
                "key = \"controller.kind\"\ndist = \"choice\"\nvalues = [\"vsc\", \"vcs\"]",
                "vcs",
            ),
        ] {
            let e = build(&format!(
                "name = \"t\"\nbase = \"x\"\n[monte_carlo]\nruns = 2\n[[monte_carlo.draw]]\n{draw}\n"
            ))
            .unwrap_err();
            assert!(
                e.to_string().contains("monte_carlo.draw[0]") && e.to_string().contains(needle),
                "{needle}: {e}"
            );
        }
    }
}
