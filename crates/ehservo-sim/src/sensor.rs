//! The sensor stage between the plant and the controller: what the
//! controller measures of x = (θ, θ̇, θ̈).
//!
//! ```text
//! x_m[i] = q_i(x[i] + bias[i]),   q_i(v) = resolution[i]·round(v/resolution[i])  (resolution > 0)
//!                                 q_i(v) = v                                    (resolution = 0)
//! ```
//!
//! The identity by default (the paper's Assumption A4: x measured exactly).
//! The metrics and the trace's θ and e are always of the true plant; only
//! the controller sees the measured values.

use ehservo_core::error::ParamError;
use serde::{Deserialize, Serialize};

/// `[sensor]`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorConfig {
    /// Constant offset added to (θ, θ̇, θ̈) (rad, rad/s, rad/s²). Default 0.
    pub bias: [f64; 3],
    /// Quantisation step of each channel (0: exact). An encoder of N counts
    /// per revolution has a θ step of 2π/N rad. Default 0.
    pub resolution: [f64; 3],
}

impl SensorConfig {
    /// No effect at all.
    pub fn is_identity(&self) -> bool {
        *self == Self::default()
    }
}

/// The validated stage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensor {
    cfg: SensorConfig,
    identity: bool,
}

impl Sensor {
    /// Exact measurement.
    pub const IDENTITY: Sensor = Sensor {
        cfg: SensorConfig {
            bias: [0.0; 3],
            resolution: [0.0; 3],
        },
        identity: true,
    };

    /// Validates the keys (`bias` finite, `resolution` finite and ≥ 0).
    pub fn try_new(c: &SensorConfig) -> Result<Self, ParamError> {
        for &b in &c.bias {
            if !b.is_finite() {
                return Err(ParamError::new("bias", "must be finite", b));
            }
        }
        for &r in &c.resolution {
            if !(r.is_finite() && r >= 0.0) {
                return Err(ParamError::new("resolution", "must be finite and >= 0", r));
            }
        }
        Ok(Self {
            cfg: *c,
            identity: c.is_identity(),
        })
    }

    /// What the controller measures when the plant is at `x`.
    #[inline]
    pub fn measure(&self, x: [f64; 3]) -> [f64; 3] {
        if self.identity {
            return x;
        }
        core::array::from_fn(|i| {
            let v = x[i] + self.cfg.bias[i];
            let r = self.cfg.resolution[i];
            if r > 0.0 {
                r * (v / r).round()
            } else {
                v
            }
        })
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    #[test]
    fn identity_and_quantisation() {
        let x = [0.123456, -2.5, 7.0];
        assert_eq!(Sensor::IDENTITY.measure(x), x);
        // A 4096-count encoder: step 2π/4096 = 1.5339808e-3 rad;
        // 0.123456/1.5339808e-3 = 80.48 → 80 counts = 0.1227185 rad.
        let s = Sensor::try_new(&SensorConfig {
            bias: [0.0, 0.5, 0.0],
            resolution: [2.0 * std::f64::consts::PI / 4096.0, 0.0, 0.0],
        })
        .unwrap();
        let m = s.measure(x);
        assert!((m[0] - 0.1227185).abs() < 1e-7, "{}", m[0]);
        assert_eq!(m[1], -2.0);
        assert_eq!(m[2], 7.0);
        assert_eq!(
            Sensor::try_new(&SensorConfig {
                resolution: [-1.0, 0.0, 0.0],
                ..Default::default()
            })
            .unwrap_err()
            .name,
            "resolution"
        );
    }
}
