//! The one error of the core: a parameter rejected at construction.

use core::fmt;

use crate::math::Real;

/// A parameter rejected at construction. `Copy`, allocation-free, and it
/// names the parameter and the reason, so that a board can report it and a
/// scenario loader can map it back to its key.
///
/// ```
/// use ehservo_core::control::Config;
/// use ehservo_core::control::pid::PidConfig;
/// use ehservo_core::prelude::*;
///
/// let design = Design {
///     model: NominalModel::new(ServoParams::paper(), Load::paper()),
///     surface: SwitchingSurface::paper(),
///     dt: 0.01,
/// };
/// // `kind = "pid"` with `kp = -1`: refused at construction, by name.
/// let err = PidConfig { kp: Some(-1.0), ..PidConfig::default() }
///     .build(&design)
///     .unwrap_err();
/// assert_eq!(err.name, "kp");
/// assert_eq!(err.value, -1.0);
/// assert_eq!(err.to_string(), "kp: must be finite and >= 0 (got -1.0)");
/// // It converts with `?` to a boxed error, on a board's `core` as on a host.
/// let boxed: Box<dyn core::error::Error> = err.into();
/// assert!(boxed.to_string().starts_with("kp"));
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamError {
    /// The parameter's name (as in the paper, e.g. `"gamma1"`).
    pub name: &'static str,
    /// Why it was rejected.
    pub reason: &'static str,
    /// The offending value (NaN when the value is a combination).
    pub value: f64,
}

impl ParamError {
    /// A new error.
    pub const fn new(name: &'static str, reason: &'static str, value: f64) -> Self {
        Self {
            name,
            reason,
            value,
        }
    }
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.value.is_nan() {
            write!(f, "{}: {}", self.name, self.reason)
        } else {
            write!(f, "{}: {} (got {:?})", self.name, self.reason, self.value)
        }
    }
}

/// `core::error::Error`, so `?` converts it to `Box<dyn Error>` with or
/// without `std`.
impl core::error::Error for ParamError {}

/// `Ok(v)` when `v` is finite and `> 0`, else an error naming `name`.
pub(crate) fn positive<T: Real>(name: &'static str, v: T) -> Result<T, ParamError> {
    if v.is_finite() && v > T::ZERO {
        Ok(v)
    } else {
        Err(ParamError::new(name, "must be finite and > 0", v.to_f64()))
    }
}

/// `Ok(v)` when `v` is finite and `>= 0`, else an error naming `name`.
pub(crate) fn non_negative<T: Real>(name: &'static str, v: T) -> Result<T, ParamError> {
    if v.is_finite() && v >= T::ZERO {
        Ok(v)
    } else {
        Err(ParamError::new(name, "must be finite and >= 0", v.to_f64()))
    }
}

/// `Ok(v)` when `v` is finite.
pub(crate) fn finite<T: Real>(name: &'static str, v: T) -> Result<T, ParamError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ParamError::new(name, "must be finite", v.to_f64()))
    }
}
