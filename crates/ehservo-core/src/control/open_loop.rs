//! Open loop: the command is the reference, scaled. Not a controller but
//! the way an identification experiment drives a plant without feedback
//! (`ehservo excite --loop open` writes such scenarios):
//!
//! ```text
//! u = volts_per_deg · θd(t)/(π/180)
//! ```
//!
//! θd is the scenario's `[reference]` in degrees, so with the default
//! `volts_per_deg = 1` a reference of 0.3° is a command of 0.3 V. The
//! measurement is not used: a plant with an integrator (the servo's open
//! loop) drifts under any command whose integral does not vanish.

use super::{Config, Controller, Design, Measurement, Output, Signal, Signals};
use crate::error::ParamError;
use crate::math::{Real, DR};

/// `kind = "open-loop"`: the `[controller]` keys.
///
/// ```
/// use ehservo_core::control::open_loop::OpenLoopConfig;
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// let ol = OpenLoopConfig { volts_per_deg: 2.0 }.build(&design)?;
/// // 0.25° of reference at 2 V/° is 0.5 V, whatever the plant does.
/// let m = Measurement { t: 0.3, x: [0.7, -3.0, 9.0], z: [0.25_f64.to_radians(), 1.0, 2.0, 3.0] };
/// let out = ol.law(&m, &[0.0], &mut [0.0]);
/// assert!((out.u - 0.5).abs() < 1e-12);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct OpenLoopConfig {
    /// Volts of command per degree of reference (V/°). Default 1.
    pub volts_per_deg: f64,
}

impl Default for OpenLoopConfig {
    fn default() -> Self {
        Self { volts_per_deg: 1.0 }
    }
}

/// The open loop's one part.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OpenLoopParts<T = f64> {
    /// The command, `volts_per_deg·θd` (V).
    pub command: T,
}

impl<T: Real> Signals for OpenLoopParts<T> {
    const SIGNALS: &'static [Signal] = &[Signal::new(
        "command",
        "",
        "V",
        "the command volts_per_deg·θd (the trace's u_V)",
    )];
    fn write(&self, out: &mut [f64]) {
        out[0] = self.command.to_f64();
    }
}

/// The open loop, built: u = gain·θd with the gain in V/rad.
/// Built by [`OpenLoopConfig`] (`kind = "open-loop"`), whose example evaluates one
/// step of the law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenLoop<T: Real = f64> {
    gain: T,
}

impl<T: Real> OpenLoop<T> {
    /// The gain (V/rad).
    pub fn gain(&self) -> T {
        self.gain
    }

    /// The same law in another float type.
    pub fn cast<U: Real>(&self) -> OpenLoop<U> {
        OpenLoop {
            gain: U::of(self.gain.to_f64()),
        }
    }
}

impl Config for OpenLoopConfig {
    const KIND: &'static str = "open-loop";
    const USES_SURFACE: bool = false;
    type Controller = OpenLoop;
    type Law<F: Real> = OpenLoop<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<OpenLoop<F>, ParamError> {
        Ok(self.build(d)?.cast())
    }

    fn build(&self, _d: &Design) -> Result<OpenLoop, ParamError> {
        if !self.volts_per_deg.is_finite() {
            return Err(ParamError::new(
                "volts_per_deg",
                "must be finite",
                self.volts_per_deg,
            ));
        }
        Ok(OpenLoop {
            gain: self.volts_per_deg / DR,
        })
    }
}

impl<T: Real> Controller<T> for OpenLoop<T> {
    /// No state (one unused entry: a state type needs one).
    type State = [T; 1];
    type Parts = OpenLoopParts<T>;

    fn initial_state(&self) -> [T; 1] {
        [T::ZERO]
    }

    #[inline]
    fn law(&self, m: &Measurement<T>, _s: &[T; 1], ds: &mut [T; 1]) -> Output<OpenLoopParts<T>, T> {
        ds[0] = T::ZERO;
        let u = self.gain * m.z[0];
        Output {
            u,
            flags: 0,
            parts: OpenLoopParts { command: u },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::servo::{Load, NominalModel, ServoParams};
    use crate::surface::SwitchingSurface;

    /// 0.25° of reference at 2 V/° is 0.5 V, whatever the measurement.
    #[test]
    fn the_command_is_the_scaled_reference() {
        let d = Design {
            model: NominalModel::new(ServoParams::paper(), Load::paper()),
            surface: SwitchingSurface::paper(),
            dt: 1e-3,
        };
        let c = OpenLoopConfig { volts_per_deg: 2.0 }.build(&d).unwrap();
        let m = Measurement {
            t: 0.3,
            x: [0.7, -3.0, 9.0],
            z: [0.25 * DR, 1.0, 2.0, 3.0],
        };
        let mut ds = [1.0];
        let out = c.law(&m, &[0.0], &mut ds);
        assert!((out.u - 0.5).abs() < 1e-12, "{}", out.u);
        assert!(ds[0].abs() < 1e-300);
        assert!(OpenLoopConfig {
            volts_per_deg: f64::NAN
        }
        .build(&d)
        .is_err());
    }
}
