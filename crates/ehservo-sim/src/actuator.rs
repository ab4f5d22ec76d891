//! The actuator stage between the controller and the plant: the valve that
//! saturates and lags.
//!
//! ```text
//! u_c = clamp(u, −limit, limit)                      saturation (V)
//! v̇   = clamp((u_c − v)/τ, −rate_limit, rate_limit)  first-order lag, slew-limited
//! plant input = v          (τ > 0)
//!             = u_c        (no time constant: a static saturation)
//! ```
//!
//! The lag's state `v` (V) is integrated with the plant in both simulation
//! modes: inside the RK4 steps of the held command in sampled mode, and in
//! every RK4 stage together with the plant and the controller state in
//! continuous mode. A rate limit bounds the lag's slew and so needs a time
//! constant (a pure rate limiter is discontinuous in its input; model a
//! fast valve with a small τ). With no key set the stage is the identity
//! and the plant sees the command exactly.

use ehservo_core::error::ParamError;
use serde::{Deserialize, Serialize};

/// `[actuator]`: every key optional; none means no such effect.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ActuatorConfig {
    /// Saturation of the command, ±limit (V).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub limit: Option<f64>,
    /// Largest slew of the valve, |v̇| ≤ rate_limit (V/s); needs `time_constant`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_limit: Option<f64>,
    /// First-order lag τ (s) between command and valve.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_constant: Option<f64>,
}

impl ActuatorConfig {
    /// No effect at all.
    pub fn is_identity(&self) -> bool {
        self.limit.is_none() && self.rate_limit.is_none() && self.time_constant.is_none()
    }
}

/// The validated stage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Actuator {
    limit: f64,
    rate: f64,
    tau: f64,
}

impl Actuator {
    /// The identity: the plant sees the command.
    pub const IDENTITY: Actuator = Actuator {
        limit: f64::INFINITY,
        rate: f64::INFINITY,
        tau: 0.0,
    };

    /// Validates the keys; the error names the key (`limit`, `rate_limit`,
    /// `time_constant`).
    pub fn try_new(c: &ActuatorConfig) -> Result<Self, ParamError> {
        let pos = |name, v: Option<f64>, default: f64| match v {
            None => Ok(default),
            Some(x) if x.is_finite() && x > 0.0 => Ok(x),
            Some(x) => Err(ParamError::new(name, "must be finite and > 0", x)),
        };
        let a = Actuator {
            limit: pos("limit", c.limit, f64::INFINITY)?,
            rate: pos("rate_limit", c.rate_limit, f64::INFINITY)?,
            tau: pos("time_constant", c.time_constant, 0.0)?,
        };
        if c.rate_limit.is_some() && c.time_constant.is_none() {
            return Err(ParamError::new(
                "rate_limit",
                "needs actuator.time_constant > 0 (the rate limit bounds the lag's slew)",
                f64::NAN,
            ));
        }
        Ok(a)
    }

    /// Whether the stage has a state (a lag).
    pub fn has_lag(&self) -> bool {
        self.tau > 0.0
    }

    /// The saturation limit (V); infinite when there is none.
    pub fn limit(&self) -> f64 {
        self.limit
    }

    /// The saturated command.
    #[inline]
    pub fn saturate(&self, u: f64) -> f64 {
        if u.abs() > self.limit {
            u.clamp(-self.limit, self.limit)
        } else {
            u
        }
    }

    /// The valve's state at rest.
    pub fn initial_state(&self) -> [f64; 1] {
        [0.0]
    }

    /// What the plant sees: the lag's state, or the saturated command.
    #[inline]
    pub fn output(&self, s: &[f64; 1], u: f64) -> f64 {
        if self.tau > 0.0 {
            s[0]
        } else {
            self.saturate(u)
        }
    }

    /// The state derivative under command `u`.
    #[inline]
    pub fn deriv(&self, s: &[f64; 1], u: f64, ds: &mut [f64; 1]) {
        ds[0] = if self.tau > 0.0 {
            let r = (self.saturate(u) - s[0]) / self.tau;
            if r.abs() > self.rate {
                r.clamp(-self.rate, self.rate)
            } else {
                r
            }
        } else {
            0.0
        };
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use ehservo_core::rk4::rk4_step;

    fn act(limit: Option<f64>, rate: Option<f64>, tau: Option<f64>) -> Actuator {
        Actuator::try_new(&ActuatorConfig {
            limit,
            rate_limit: rate,
            time_constant: tau,
        })
        .unwrap()
    }

    #[test]
    fn identity_passes_the_command_exactly() {
        let a = Actuator::IDENTITY;
        for u in [0.0, -0.0, 1e-300, -3.7, 1e300] {
            assert_eq!(a.output(&[5.0], u).to_bits(), u.to_bits());
        }
        let mut d = [1.0];
        a.deriv(&[5.0], 2.0, &mut d);
        assert_eq!(d[0], 0.0);
    }

    /// A unit step through τ = 0.05 s: v(t) = 1 − e^(−t/τ); at t = τ,
    /// 1 − e^−1 = 0.6321206 (RK4 with h = τ/50 is exact to ~1e-10).
    #[test]
    fn lag_step_response_reaches_63_percent_at_tau() {
        let a = act(None, None, Some(0.05));
        let mut s = [0.0];
        let h = 0.001;
        for k in 0..50 {
            rk4_step(|_, s, ds| a.deriv(s, 1.0, ds), k as f64 * h, &mut s, h);
        }
        assert!((s[0] - (1.0 - (-1.0f64).exp())).abs() < 1e-9, "{}", s[0]);
    }

    /// Saturation at 0.5 V and a slew limit of 2 V/s: from rest, a 10 V
    /// step through τ = 0.01 s asks (0.5 − 0)/0.01 = 50 V/s, so the valve
    /// ramps at 2 V/s: v(0.1 s) = 0.2 V exactly (a linear ramp, which RK4
    /// integrates exactly); it never exceeds the 0.5 V limit.
    #[test]
    fn saturation_and_rate_limit() {
        let a = act(Some(0.5), Some(2.0), Some(0.01));
        let mut s = [0.0];
        let h = 0.001;
        for k in 0..100 {
            rk4_step(|_, s, ds| a.deriv(s, 10.0, ds), k as f64 * h, &mut s, h);
        }
        assert!((s[0] - 0.2).abs() < 1e-12, "{}", s[0]);
        for k in 100..2000 {
            rk4_step(|_, s, ds| a.deriv(s, 10.0, ds), k as f64 * h, &mut s, h);
        }
        assert!(s[0] <= 0.5 + 1e-12 && s[0] > 0.49, "{}", s[0]);
        // Static saturation without a lag.
        let b = act(Some(0.5), None, None);
        assert_eq!(b.output(&[0.0], -3.0), -0.5);
        assert_eq!(b.output(&[0.0], 0.25), 0.25);
    }

    #[test]
    fn bad_keys_are_named() {
        let e = |c: ActuatorConfig| Actuator::try_new(&c).unwrap_err().name;
        let c = ActuatorConfig::default();
        assert_eq!(
            e(ActuatorConfig {
                limit: Some(0.0),
                ..c
            }),
            "limit"
        );
        assert_eq!(
            e(ActuatorConfig {
                time_constant: Some(f64::NAN),
                ..c
            }),
            "time_constant"
        );
        assert_eq!(
            e(ActuatorConfig {
                rate_limit: Some(1.0),
                ..c
            }),
            "rate_limit"
        );
    }
}
