//! Open loop: the command is the reference, scaled. Not a controller but
//! the way an identification experiment drives a plant without feedback
//! (`ehservo excite --loop open` writes such scenarios):
//!
//! ```text
//! u = volts_per_deg · θd(t)/(π/180)     (a rotary axis, θd in rad)
//! u = volts_per_mm · 1000·yd(t)         (a linear axis, yd in m)
//! ```
//!
//! θd is the scenario's `[reference]`, so with the default
//! `volts_per_deg = 1` a reference of 0.3° is a command of 0.3 V, and with
//! `volts_per_mm = 0.5` a reference of 2 mm is 1 V. A linear axis must give
//! `volts_per_mm` (the scenario refuses `volts_per_deg` there). The
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
/// let ol = OpenLoopConfig { volts_per_deg: Some(2.0), ..Default::default() }.build(&design)?;
/// // 0.25° of reference at 2 V/° is 0.5 V, whatever the plant does.
/// let m = Measurement { t: 0.3, x: [0.7, -3.0, 9.0], z: [0.25_f64.to_radians(), 1.0, 2.0, 3.0] };
/// let out = ol.law(&m, &[0.0], &mut [0.0]);
/// assert!((out.u - 0.5).abs() < 1e-12);
/// // On a linear axis: 3 mm of reference at 0.5 V/mm is 1.5 V.
/// let lin = OpenLoopConfig { volts_per_mm: Some(0.5), ..Default::default() }.build(&design)?;
/// let m = Measurement { t: 0.0, x: [0.0; 3], z: [0.003, 0.0, 0.0, 0.0] };
/// assert!((lin.law(&m, &[0.0], &mut [0.0]).u - 1.5).abs() < 1e-12);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct OpenLoopConfig {
    /// Volts of command per degree of reference (V/°), on a rotary axis.
    /// Default 1 when `volts_per_mm` is not given.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub volts_per_deg: Option<f64>,
    /// Volts of command per millimetre of reference (V/mm), on a linear
    /// axis, where it is required.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub volts_per_mm: Option<f64>,
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
        let finite = |name, v: f64| {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(ParamError::new(name, "must be finite", v))
            }
        };
        let gain =
            match (self.volts_per_deg, self.volts_per_mm) {
                (Some(_), Some(v)) => return Err(ParamError::new(
                    "volts_per_mm",
                    "give volts_per_deg (a rotary axis) or volts_per_mm (a linear one), not both",
                    v,
                )),
                (Some(v), None) => finite("volts_per_deg", v)? / DR,
                // V/mm to V/m.
                (None, Some(v)) => finite("volts_per_mm", v)? * 1e3,
                (None, None) => 1.0 / DR,
            };
        Ok(OpenLoop { gain })
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
        let c = OpenLoopConfig {
            volts_per_deg: Some(2.0),
            ..Default::default()
        }
        .build(&d)
        .unwrap();
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
            volts_per_deg: Some(f64::NAN),
            ..Default::default()
        }
        .build(&d)
        .is_err());
        // The default is the rotary 1 V/°: 1 V per π/180 rad.
        let def = OpenLoopConfig::default().build(&d).unwrap();
        assert!((def.gain() - 180.0 / core::f64::consts::PI).abs() < 1e-12);
        // 0.5 V/mm is 500 V/m; both keys at once are refused.
        let lin = OpenLoopConfig {
            volts_per_mm: Some(0.5),
            ..Default::default()
        };
        assert!((lin.build(&d).unwrap().gain() - 500.0).abs() < 1e-12);
        let both = OpenLoopConfig {
            volts_per_deg: Some(1.0),
            ..lin
        };
        assert_eq!(both.build(&d).unwrap_err().name, "volts_per_mm");
    }
}
