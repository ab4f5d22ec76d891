//! The actuator stage between the controller and the plant: the servo valve
//! that saturates, lags, has a dead band and a null bias.
//!
//! ```text
//! u_c = clamp(u, −limit, limit)                         saturation (V)
//! first order  (τ):      v̇ = clamp((u_c − v)/τ, ±rate_limit)
//! second order (ωn, ζ):  v̇ = clamp(w, ±rate_limit),
//!                        ẇ = ωn²·(u_c − v) − 2ζωn·w     (ẇ = 0 while |w| ≥ rate_limit pushes out)
//! no dynamics:           v = u_c
//! plant input = db(v + null_bias),  db(s) = sgn(s)·max(|s| − dead_band, 0)
//! ```
//!
//! `v` is the spool position in volts of command (the valve's own spool
//! travel is `Kv·v`). The dynamics are given by `time_constant` τ (first
//! order), or by the −3 dB `bandwidth_hz` f_b and `order`: a first-order
//! valve has τ = 1/(2π f_b); a second-order one with damping ζ (default 0.7)
//! has ωn = 2π f_b / √(1 − 2ζ² + √(4ζ⁴ − 4ζ² + 2)), the natural frequency
//! whose |G(j2πf_b)| = 1/√2 (servo valves of the Moog G761 class: roughly
//! 100–200 Hz at ±10 V). The dead band is the spool's overlap: no flow while
//! |v + null_bias| ≤ dead_band, and the opening beyond it; the null bias is
//! the spool's offset at zero command (flow at u = 0).
//!
//! The spool state (v, w) is integrated with the plant in both simulation
//! modes: inside the RK4 steps of the held command in sampled mode, and in
//! every RK4 stage together with the plant and the controller state in
//! continuous mode. A rate limit bounds the spool's slew and so needs
//! dynamics (a pure rate limiter is discontinuous in its input; model a fast
//! valve with a high bandwidth). With no key set the stage is the identity
//! and the plant sees the command exactly (the same bits).

use ehservo_core::error::ParamError;
use serde::{Deserialize, Serialize};

/// `[actuator]`: every key optional; none means no such effect.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ActuatorConfig {
    /// Saturation of the command, ±limit (V).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub limit: Option<f64>,
    /// Largest slew of the spool, |v̇| ≤ rate_limit (V/s); needs dynamics.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_limit: Option<f64>,
    /// First-order lag τ (s) between command and spool (or give `bandwidth_hz`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_constant: Option<f64>,
    /// −3 dB bandwidth of the spool dynamics (Hz).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bandwidth_hz: Option<f64>,
    /// Order of the spool dynamics with `bandwidth_hz`: 1 or 2 (default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<u8>,
    /// Natural frequency ωn of a second-order spool (rad/s), instead of
    /// `bandwidth_hz` (a datasheet's or a model's ω, as Hopsan's
    /// `omega_h`); with `damping`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub natural_frequency: Option<f64>,
    /// Damping ratio ζ of a second-order spool (default 0.7).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// Half-width of the dead band (overlap) of the spool (V).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dead_band: Option<f64>,
    /// Spool offset at zero command (V).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub null_bias: Option<f64>,
}

impl ActuatorConfig {
    /// No effect at all.
    pub fn is_identity(&self) -> bool {
        *self == Self::default()
    }
}

/// The spool's dynamics, as [`Actuator::try_new`] derives them from
/// `[actuator]` (what the frequency domain linearises: `ehservo::freq`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Dynamics {
    /// The spool is where the (saturated) command puts it.
    None,
    /// v̇ = (u_c − v)/τ.
    First {
        /// τ (s).
        tau: f64,
    },
    /// v̈ = ωn²(u_c − v) − 2ζωn v̇.
    Second {
        /// ωn² (1/s²).
        wn2: f64,
        /// 2ζωn (1/s).
        two_zeta_wn: f64,
    },
}

/// The validated stage.
///
/// ```
/// use ehservo_sim::actuator::{Actuator, ActuatorConfig};
///
/// // A ±10 V valve with a 10-ms spool lag and a 0.5-V overlap, as `[actuator]`.
/// let cfg: ActuatorConfig = toml::from_str("limit = 10.0\ntime_constant = 0.01\ndead_band = 0.5")
///     .unwrap();
/// let act = Actuator::try_new(&cfg)?;
/// assert_eq!(act.saturate(12.0), 10.0);
/// // From rest under 12 V: v̇ = (u_c − v)/τ = (10 − 0)/0.01 = 1000 V/s.
/// let mut ds = [0.0; 2];
/// act.deriv(&act.initial_state(), 12.0, &mut ds);
/// assert!((ds[0] - 1000.0).abs() < 1e-9);
/// // The plant sees the spool beyond the overlap: 2 V → 1.5 V, 0.3 V → 0.
/// assert_eq!(act.output(&[2.0, 0.0], 0.0), 1.5);
/// assert_eq!(act.output(&[0.3, 0.0], 0.0), 0.0);
/// // A rate limit needs spool dynamics to limit.
/// let bad = ActuatorConfig { rate_limit: Some(100.0), ..ActuatorConfig::default() };
/// assert_eq!(Actuator::try_new(&bad).unwrap_err().name, "rate_limit");
/// # Ok::<(), ehservo_sim::core::error::ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Actuator {
    limit: f64,
    rate: f64,
    dynamics: Dynamics,
    dead_band: f64,
    null_bias: f64,
    /// Neither dead band nor null bias: the output is the spool itself.
    plain: bool,
}

/// The −3 dB bandwidth of a second-order lag as a multiple of ωn.
///
/// ```
/// use ehservo_sim::actuator::second_order_bandwidth_ratio;
///
/// // ζ = 1/√2 (Butterworth): |G(jω)|² = 1/(1 + (ω/ωn)⁴), so −3 dB at ω = ωn.
/// assert!((second_order_bandwidth_ratio(std::f64::consts::FRAC_1_SQRT_2) - 1.0).abs() < 1e-12);
/// // ζ = 1: |G(jω)| = 1/(1 + (ω/ωn)²), so −3 dB at ω = ωn·√(√2 − 1).
/// let want = (2f64.sqrt() - 1.0).sqrt();
/// assert!((second_order_bandwidth_ratio(1.0) - want).abs() < 1e-12);
/// ```
pub fn second_order_bandwidth_ratio(zeta: f64) -> f64 {
    let z2 = zeta * zeta;
    (1.0 - 2.0 * z2 + (4.0 * z2 * z2 - 4.0 * z2 + 2.0).sqrt()).sqrt()
}

impl Actuator {
    /// The identity: the plant sees the command.
    pub const IDENTITY: Actuator = Actuator {
        limit: f64::INFINITY,
        rate: f64::INFINITY,
        dynamics: Dynamics::None,
        dead_band: 0.0,
        null_bias: 0.0,
        plain: true,
    };

    /// Validates the keys; the error names the key.
    pub fn try_new(c: &ActuatorConfig) -> Result<Self, ParamError> {
        let pos = |name, v: Option<f64>, default: f64| match v {
            None => Ok(default),
            Some(x) if x.is_finite() && x > 0.0 => Ok(x),
            Some(x) => Err(ParamError::new(name, "must be finite and > 0", x)),
        };
        let dead_band = match c.dead_band {
            Some(x) if !(x.is_finite() && x >= 0.0) => {
                return Err(ParamError::new("dead_band", "must be finite and >= 0", x))
            }
            v => v.unwrap_or(0.0),
        };
        let null_bias = match c.null_bias {
            Some(x) if !x.is_finite() => {
                return Err(ParamError::new("null_bias", "must be finite", x))
            }
            v => v.unwrap_or(0.0),
        };
        let order = match c.order {
            None | Some(1) => 1,
            Some(2) => 2,
            Some(o) => {
                return Err(ParamError::new("order", "must be 1 or 2", f64::from(o)));
            }
        };
        if c.order.is_some() && c.bandwidth_hz.is_none() {
            return Err(ParamError::new(
                "order",
                "needs actuator.bandwidth_hz (the order of the spool dynamics it sets)",
                f64::NAN,
            ));
        }
        if c.natural_frequency.is_some() && (c.order == Some(1)) {
            return Err(ParamError::new(
                "order",
                "a natural_frequency sets a second-order spool: remove order = 1",
                f64::NAN,
            ));
        }
        let order = if c.natural_frequency.is_some() {
            2
        } else {
            order
        };
        if c.damping.is_some() && order != 2 {
            return Err(ParamError::new(
                "damping",
                "applies to a second-order spool only: set actuator.order = 2",
                f64::NAN,
            ));
        }
        if c.natural_frequency.is_some() && (c.time_constant.is_some() || c.bandwidth_hz.is_some())
        {
            return Err(ParamError::new(
                "natural_frequency",
                "give one of actuator.time_constant, actuator.bandwidth_hz and actuator.natural_frequency",
                f64::NAN,
            ));
        }
        let dynamics = match (c.time_constant, c.bandwidth_hz) {
            (None, None) if c.natural_frequency.is_some() => {
                let wn = pos("natural_frequency", c.natural_frequency, 0.0)?;
                let zeta = pos("damping", c.damping, 0.7)?;
                Dynamics::Second {
                    wn2: wn * wn,
                    two_zeta_wn: 2.0 * zeta * wn,
                }
            }
            (Some(_), Some(_)) => {
                return Err(ParamError::new(
                    "bandwidth_hz",
                    "give either actuator.time_constant or actuator.bandwidth_hz, not both",
                    f64::NAN,
                ))
            }
            (Some(t), None) => Dynamics::First {
                tau: pos("time_constant", Some(t), 0.0)?,
            },
            (None, Some(f)) => {
                let wb = 2.0 * core::f64::consts::PI * pos("bandwidth_hz", Some(f), 0.0)?;
                if order == 1 {
                    Dynamics::First { tau: 1.0 / wb }
                } else {
                    let zeta = pos("damping", c.damping, 0.7)?;
                    let wn = wb / second_order_bandwidth_ratio(zeta);
                    Dynamics::Second {
                        wn2: wn * wn,
                        two_zeta_wn: 2.0 * zeta * wn,
                    }
                }
            }
            (None, None) => Dynamics::None,
        };
        if c.rate_limit.is_some() && dynamics == Dynamics::None {
            return Err(ParamError::new(
                "rate_limit",
                "needs spool dynamics: actuator.time_constant, bandwidth_hz or natural_frequency (the rate limit bounds the spool's slew)",
                f64::NAN,
            ));
        }
        Ok(Actuator {
            limit: pos("limit", c.limit, f64::INFINITY)?,
            rate: pos("rate_limit", c.rate_limit, f64::INFINITY)?,
            dynamics,
            dead_band,
            null_bias,
            plain: dead_band == 0.0 && null_bias == 0.0,
        })
    }

    /// Whether the stage has a state (spool dynamics).
    pub fn has_lag(&self) -> bool {
        self.dynamics != Dynamics::None
    }

    /// The magnitude of the spool dynamics' fastest eigenvalue (1/s): 1/τ,
    /// or ωn; 0 without dynamics.
    pub fn fastest_rate(&self) -> f64 {
        match self.dynamics {
            Dynamics::None => 0.0,
            Dynamics::First { tau } => 1.0 / tau,
            Dynamics::Second { wn2, .. } => wn2.sqrt(),
        }
    }

    /// Whether the stage changes nothing.
    pub fn is_identity(&self) -> bool {
        *self == Self::IDENTITY
    }

    /// The saturation limit (V); infinite when there is none.
    pub fn limit(&self) -> f64 {
        self.limit
    }

    /// The spool's dynamics.
    pub fn dynamics(&self) -> Dynamics {
        self.dynamics
    }

    /// The spool's rate limit (V/s); infinite when there is none.
    pub fn rate_limit(&self) -> f64 {
        self.rate
    }

    /// The dead band's half-width (V).
    pub fn dead_band(&self) -> f64 {
        self.dead_band
    }

    /// The spool's offset at zero command (V).
    pub fn null_bias(&self) -> f64 {
        self.null_bias
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

    /// The valve's state (v, v̇) at rest.
    pub fn initial_state(&self) -> [f64; 2] {
        [0.0; 2]
    }

    /// The spool position (V): the dynamics' state, or the saturated command.
    #[inline]
    pub fn spool(&self, s: &[f64; 2], u: f64) -> f64 {
        match self.dynamics {
            Dynamics::None => self.saturate(u),
            _ => s[0],
        }
    }

    /// What the plant sees: the spool through the dead band, with the null bias.
    #[inline]
    pub fn output(&self, s: &[f64; 2], u: f64) -> f64 {
        let v = self.spool(s, u);
        if self.plain {
            return v;
        }
        let p = v + self.null_bias;
        let over = p.abs() - self.dead_band;
        if over > 0.0 {
            over.copysign(p)
        } else {
            0.0
        }
    }

    /// What the plant sees under command `u` when it does not depend on
    /// the stage's state (no spool dynamics): the same over a whole step,
    /// so the sampled loop computes it once. None with spool dynamics.
    #[inline]
    pub fn held_output(&self, u: f64) -> Option<f64> {
        match self.dynamics {
            Dynamics::None => Some(self.output(&[0.0; 2], u)),
            _ => None,
        }
    }

    /// The state derivative under command `u`.
    #[inline]
    pub fn deriv(&self, s: &[f64; 2], u: f64, ds: &mut [f64; 2]) {
        match self.dynamics {
            Dynamics::None => *ds = [0.0; 2],
            Dynamics::First { tau } => {
                let r = (self.saturate(u) - s[0]) / tau;
                ds[0] = if r.abs() > self.rate {
                    r.clamp(-self.rate, self.rate)
                } else {
                    r
                };
                ds[1] = 0.0;
            }
            Dynamics::Second { wn2, two_zeta_wn } => {
                let w = s[1];
                let a = wn2 * (self.saturate(u) - s[0]) - two_zeta_wn * w;
                if w.abs() >= self.rate {
                    ds[0] = w.clamp(-self.rate, self.rate);
                    // Held at the rate limit: no acceleration outward.
                    ds[1] = if a * w > 0.0 { 0.0 } else { a };
                } else {
                    ds[0] = w;
                    ds[1] = a;
                }
            }
        }
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
            ..Default::default()
        })
        .unwrap()
    }

    #[test]
    fn identity_passes_the_command_exactly() {
        let a = Actuator::IDENTITY;
        for u in [0.0, -0.0, 1e-300, -3.7, 1e300] {
            assert_eq!(a.output(&[5.0, 1.0], u).to_bits(), u.to_bits());
        }
        let mut d = [1.0; 2];
        a.deriv(&[5.0, 1.0], 2.0, &mut d);
        assert_eq!(d, [0.0; 2]);
    }

    /// A unit step through τ = 0.05 s: v(t) = 1 − e^(−t/τ); at t = τ,
    /// 1 − e^−1 = 0.6321206 (RK4 with h = τ/50 is exact to ~1e-10).
    #[test]
    fn lag_step_response_reaches_63_percent_at_tau() {
        let a = act(None, None, Some(0.05));
        let mut s = [0.0; 2];
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
        let mut s = [0.0; 2];
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
        assert_eq!(b.output(&[0.0; 2], -3.0), -0.5);
        assert_eq!(b.output(&[0.0; 2], 0.25), 0.25);
    }

    fn valve(order: u8, f: f64, zeta: Option<f64>) -> Actuator {
        Actuator::try_new(&ActuatorConfig {
            bandwidth_hz: Some(f),
            order: Some(order),
            damping: zeta,
            ..Default::default()
        })
        .unwrap()
    }

    /// Steady amplitude of the spool under a unit sine at `f` (Hz): RK4
    /// with 2000 steps per period, over 30 periods, the last 10 measured.
    fn gain_at(a: &Actuator, f: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI * f;
        let n = 2000;
        let h = 1.0 / (f * n as f64);
        let mut s = [0.0; 2];
        let mut peak: f64 = 0.0;
        for k in 0..30 * n {
            let t = k as f64 * h;
            rk4_step(|tt, s, ds| a.deriv(s, (w * tt).sin(), ds), t, &mut s, h);
            if k >= 20 * n {
                peak = peak.max(s[0].abs());
            }
        }
        peak
    }

    /// The −3 dB bandwidth means |G(j2πf_b)| = 1/√2, for both orders
    /// (150 Hz, a G761-class valve; ζ = 0.7 and 0.4).
    #[test]
    fn bandwidth_is_the_minus_3_db_frequency() {
        for a in [
            valve(1, 150.0, None),
            valve(2, 150.0, None),
            valve(2, 150.0, Some(0.4)),
        ] {
            let g = gain_at(&a, 150.0);
            assert!(
                (g - std::f64::consts::FRAC_1_SQRT_2).abs() < 2e-4,
                "{a:?}: {g}"
            );
        }
        // First order: τ = 1/(2π·150) = 1.0610e-3 s, as time_constant gives.
        let a = valve(1, 150.0, None);
        let b = act(None, None, Some(1.0 / (2.0 * std::f64::consts::PI * 150.0)));
        assert_eq!(a, b);
    }

    /// A unit step through the second-order spool against the closed form
    /// 1 − e^(−ζωn t)(cos ωd t + ζ/√(1−ζ²)·sin ωd t), ωd = ωn√(1−ζ²), with
    /// ωn from the bandwidth: for ζ = 0.7 the ratio f_b/f_n is
    /// √(1 − 0.98 + √(0.9604 − 1.96 + 2)) = √1.02020 = 1.010050.
    #[test]
    fn second_order_step_response_closed_form() {
        assert!((second_order_bandwidth_ratio(0.7) - 1.010050).abs() < 1e-6);
        // ζ = 1/√2: the Butterworth case, bandwidth = ωn exactly.
        assert!(
            (second_order_bandwidth_ratio(std::f64::consts::FRAC_1_SQRT_2) - 1.0).abs() < 1e-12
        );
        let a = valve(2, 100.0, None);
        let wn = 2.0 * std::f64::consts::PI * 100.0 / 1.010050;
        let z: f64 = 0.7;
        let wd = wn * (1.0 - z * z).sqrt();
        let h = 1e-6;
        let mut s = [0.0; 2];
        for k in 0..20_000 {
            rk4_step(|_, s, ds| a.deriv(s, 1.0, ds), k as f64 * h, &mut s, h);
            let t = (k + 1) as f64 * h;
            let y = 1.0
                - (-z * wn * t).exp()
                    * ((wd * t).cos() + z / (1.0 - z * z).sqrt() * (wd * t).sin());
            assert!((s[0] - y).abs() < 2e-6, "t = {t}: {} vs {y}", s[0]);
        }
        // ζ = 0.7: overshoot e^(−πζ/√(1−ζ²)) = 4.60 %.
        let mut s = [0.0; 2];
        let mut peak: f64 = 0.0;
        for k in 0..20_000 {
            rk4_step(|_, s, ds| a.deriv(s, 1.0, ds), k as f64 * h, &mut s, h);
            peak = peak.max(s[0]);
        }
        assert!((peak - 1.0459_9).abs() < 1e-4, "{peak}");
    }

    /// Dead band 0.1 V and null bias 0.02 V, no dynamics: db(u + 0.02).
    #[test]
    fn dead_band_and_null_bias() {
        let a = Actuator::try_new(&ActuatorConfig {
            dead_band: Some(0.1),
            null_bias: Some(0.02),
            limit: Some(1.0),
            ..Default::default()
        })
        .unwrap();
        let s = [0.0; 2];
        assert_eq!(a.output(&s, 0.0), 0.0); // 0.02 inside the band
        assert_eq!(a.output(&s, 0.08), 0.0); // 0.10 on its edge
        assert!((a.output(&s, 0.5) - 0.42).abs() < 1e-15); // 0.52 − 0.1
        assert!((a.output(&s, -0.5) + 0.38).abs() < 1e-15); // −0.48 + 0.1
        assert!((a.output(&s, 7.0) - 0.92).abs() < 1e-15); // saturated at 1, + 0.02 − 0.1
        assert!(!a.is_identity() && Actuator::IDENTITY.is_identity());
    }

    /// A second-order spool slews at the rate limit: from rest, a 1 V step
    /// through a 1 kHz valve with 20 V/s never moves faster than 20 V/s.
    #[test]
    fn second_order_rate_limit() {
        let a = Actuator::try_new(&ActuatorConfig {
            bandwidth_hz: Some(1000.0),
            order: Some(2),
            rate_limit: Some(20.0),
            ..Default::default()
        })
        .unwrap();
        let h = 1e-5;
        let mut s = [0.0; 2];
        let mut prev = 0.0;
        for k in 0..5000 {
            rk4_step(|_, s, ds| a.deriv(s, 1.0, ds), k as f64 * h, &mut s, h);
            assert!((s[0] - prev) / h <= 20.0 + 1e-9);
            prev = s[0];
        }
        // 0.05 s at 20 V/s: 1 V reached at ~0.05 s (plus the rise into the limit).
        assert!(s[0] > 0.9 && s[0] < 1.0 + 1e-9, "{}", s[0]);
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
        for (c, key) in [
            (
                ActuatorConfig {
                    bandwidth_hz: Some(-100.0),
                    ..c
                },
                "bandwidth_hz",
            ),
            (
                ActuatorConfig {
                    bandwidth_hz: Some(100.0),
                    order: Some(3),
                    ..c
                },
                "order",
            ),
            (
                ActuatorConfig {
                    order: Some(2),
                    ..c
                },
                "order",
            ),
            (
                ActuatorConfig {
                    bandwidth_hz: Some(100.0),
                    damping: Some(0.5),
                    ..c
                },
                "damping",
            ),
            (
                ActuatorConfig {
                    bandwidth_hz: Some(100.0),
                    order: Some(2),
                    damping: Some(0.0),
                    ..c
                },
                "damping",
            ),
            (
                ActuatorConfig {
                    bandwidth_hz: Some(100.0),
                    time_constant: Some(0.01),
                    ..c
                },
                "bandwidth_hz",
            ),
            (
                ActuatorConfig {
                    dead_band: Some(-0.1),
                    ..c
                },
                "dead_band",
            ),
            (
                ActuatorConfig {
                    null_bias: Some(f64::INFINITY),
                    ..c
                },
                "null_bias",
            ),
        ] {
            assert_eq!(e(c), key);
        }
    }
}
