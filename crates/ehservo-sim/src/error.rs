//! The error of a configuration checked here: a scenario key rejected,
//! with its path from the scenario's root and the reason as data.
//!
//! The core's [`ParamError`] names a law's or a model's parameter; this
//! layer knows which key of a scenario set it, so it carries the key path
//! (`plant.cylinder.bore`, `uncertainty.hold`). The scenario's loader adds
//! the file, and the line and column (`ehservo_scenario::scenario::ScenarioError`).
//!
//! ```
//! use ehservo_sim::error::{positive, KeyError, Reason};
//! let e = positive("plant.cylinder.bore", 0.0).unwrap_err();
//! assert_eq!(e.key, "plant.cylinder.bore");
//! assert_eq!(e.reason, Reason::NotPositive(0.0));
//! assert_eq!(e.to_string(), "`plant.cylinder.bore`: must be finite and > 0 (got 0.0)");
//! assert_eq!(positive("x", 2.5), Ok(2.5));
//! # let _: KeyError = e;
//! ```

use ehservo_core::error::ParamError;
use std::fmt;

/// How many characters of a file's content an error quotes.
pub const QUOTE_CHARS: usize = 60;

/// The start of `s` for a one-line message: its first [`QUOTE_CHARS`]
/// characters, escaped (`\u{0}`, `\t`), in backticks, and when there are more,
/// how many in all. The line stays short whatever `s` holds.
///
/// ```
/// use ehservo_sim::error::quote_start;
/// assert_eq!(quote_start("t,theta"), "`t,theta`");
/// let long = "x".repeat(1000);
/// assert_eq!(
///     quote_start(&long),
///     format!("`{}…` (1000 characters)", "x".repeat(60))
/// );
/// assert_eq!(quote_start("a\tb"), "`a\\tb`");
/// ```
pub fn quote_start(s: &str) -> String {
    let mut chars = s.chars();
    let head: String = chars
        .by_ref()
        .take(QUOTE_CHARS)
        .flat_map(char::escape_debug)
        .collect();
    if chars.next().is_none() {
        format!("`{head}`")
    } else {
        format!("`{head}…` ({} characters)", s.chars().count())
    }
}

/// Why a value was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Reason {
    /// Not finite, or ≤ 0, where a positive number is needed.
    #[error("must be finite and > 0 (got {0:?})")]
    NotPositive(f64),
    /// Not finite, or < 0, where a non-negative number is needed.
    #[error("must be finite and >= 0 (got {0:?})")]
    Negative(f64),
    /// NaN or infinite.
    #[error("must be finite (got {0})")]
    NotFinite(f64),
    /// The core's own check of a parameter, by its name there.
    #[error("{}", param_reason(.0))]
    Param(ParamError),
    /// A name that is none of the known ones (a kind, a model, a key).
    #[error("{0}")]
    Unknown(Box<Unknown>),
    /// A file's text is not TOML.
    #[error("TOML syntax error: {0}")]
    Syntax(String),
    /// A value of the wrong type or shape, or an unknown field (serde's
    /// message).
    #[error("{0}")]
    Serde(String),
    /// Any other reason, as a sentence.
    #[error("{0}")]
    Other(String),
    /// A value outside a published box (a benchmark's parameter range).
    #[error("must lie in the published box [{low}, {high}] (got {value:?}); set widen_box = true to leave it")]
    OutsideBox {
        /// The value given.
        value: f64,
        /// The box's lower end.
        low: f64,
        /// The box's upper end.
        high: f64,
    },
}

/// A name that is none of the known ones.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("unknown {what} `{name}` (known: {})", known.join(", "))]
pub struct Unknown {
    /// What was named (`controller kind`, `plant model`).
    pub what: &'static str,
    /// The name given.
    pub name: String,
    /// The known names.
    pub known: &'static [&'static str],
}

/// The reason of a core [`ParamError`] as a key's reason: the core's
/// sentence with the value (when it is one number).
fn param_reason(e: &ParamError) -> String {
    if e.value.is_nan() {
        e.reason.to_string()
    } else {
        format!("{} (got {:?})", e.reason, e.value)
    }
}

impl Reason {
    /// Whether the reason's sentence contains `text`.
    pub fn contains(&self, text: &str) -> bool {
        self.to_string().contains(text)
    }
}

impl From<String> for Reason {
    fn from(s: String) -> Self {
        Reason::Other(s)
    }
}

impl From<&str> for Reason {
    fn from(s: &str) -> Self {
        Reason::Other(s.to_string())
    }
}

/// A key rejected, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyError {
    /// The key's path from the scenario's root (`simulation.step`); empty
    /// when the whole section or file is at fault.
    pub key: String,
    /// Why.
    pub reason: Reason,
}

impl fmt::Display for KeyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}", self.reason)
        } else {
            write!(f, "`{}`: {}", self.key, self.reason)
        }
    }
}

impl std::error::Error for KeyError {}

impl KeyError {
    /// Key `key` refused for `reason`.
    pub fn new(key: impl Into<String>, reason: impl Into<Reason>) -> Self {
        Self {
            key: key.into(),
            reason: reason.into(),
        }
    }

    /// A core parameter error as the key `prefix.name`.
    pub fn param(prefix: &str, e: ParamError) -> Self {
        Self {
            key: format!("{prefix}.{}", e.name),
            reason: Reason::Param(e),
        }
    }

    /// The same reason under `prefix.` + this key (a section's error seen
    /// from the scenario's root).
    pub fn under(mut self, prefix: &str) -> Self {
        self.key = if self.key.is_empty() {
            prefix.to_string()
        } else {
            format!("{prefix}.{}", self.key)
        };
        self
    }

    /// The same reason under another key.
    pub fn at(mut self, key: impl Into<String>) -> Self {
        self.key = key.into();
        self
    }
}

/// `Ok(v)` when `v` is finite and > 0.
pub fn positive(key: &str, v: f64) -> Result<f64, KeyError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(KeyError::new(key, Reason::NotPositive(v)))
    }
}

/// `Ok(v)` when `v` is finite and ≥ 0.
pub fn non_negative(key: &str, v: f64) -> Result<f64, KeyError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(KeyError::new(key, Reason::Negative(v)))
    }
}

/// `Ok(v)` when `v` is finite.
pub fn finite(key: &str, v: f64) -> Result<f64, KeyError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(KeyError::new(key, Reason::NotFinite(v)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The messages users see, written out by hand.
    #[test]
    fn reasons_read_as_sentences() {
        assert_eq!(
            Reason::NotPositive(f64::NAN).to_string(),
            "must be finite and > 0 (got NaN)"
        );
        assert_eq!(
            Reason::Negative(-1.0).to_string(),
            "must be finite and >= 0 (got -1.0)"
        );
        assert_eq!(
            Reason::NotFinite(f64::INFINITY).to_string(),
            "must be finite (got inf)"
        );
        let p = ParamError::new("gamma1", "must be finite and > 0", -2.0);
        assert_eq!(
            KeyError::param("controller", p).to_string(),
            "`controller.gamma1`: must be finite and > 0 (got -2.0)"
        );
        let p = ParamError::new("p", "not Hurwitz", f64::NAN);
        assert_eq!(Reason::Param(p).to_string(), "not Hurwitz");
        assert_eq!(
            KeyError::new("bore", "too small").under("plant").key,
            "plant.bore"
        );
        assert_eq!(KeyError::new("", "x").under("plant").key, "plant");
    }
}
