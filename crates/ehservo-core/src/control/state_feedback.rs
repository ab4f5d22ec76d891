//! Full state feedback of position, velocity and acceleration (the load
//! pressure's image), with integral action, reference feed-forward and the
//! valve's flow linearisation: the industrial answer to a lightly damped
//! hydraulic axis, where a PID alone cannot place the resonance.
//!
//! **Why not a PID.** A valve-controlled actuator is, about rest, the
//! third-order model (8), `x⃛ = −ā1x1 − ā2x2 − ā3x3 + b̄·u`: an integrator
//! (x1 from x2) and the hydraulic resonance `s² + ā3·s + ā2`, whose natural
//! frequency is `ω_h = √ā2` and whose damping is `ζ_h = ā3/(2√ā2)` — for a
//! cylinder moving a mass, often 0.01–0.1. A PID on position places four
//! closed-loop poles with three gains and leaves their sum at the plant's
//! own `−ā3` (`control/pid.rs`): with ā3 small the poles cannot all be
//! damped. Feeding back the acceleration — through the torque or force
//! balance (4), the load pressure `P_L = (Jt·x3 + Bm·x2 + G·x1 + Tl)/Dm` up
//! to the friction and load it leaves out: ΔP feedback — gives the missing
//! degree of freedom: every pole can be placed (Jelali & Kroll 2003; Merritt
//! 1967 §7 for the damping pressure feedback adds; the industrial practice
//! of position, velocity and acceleration or ΔP gains is summarised in
//! Tech Briefs, "Controlling hydraulic servo systems", 2013).
//!
//! **The law.** In the error coordinates `e = θd − θ` (and ė, ë from the
//! measured velocity and acceleration), with the integral `I = ki·∫e`:
//!
//! ```text
//! v   = θ⃛d + ā3·θ̈d + ā2·θ̇d + ā1·θd            reference feed-forward (inverse nominal model)
//!     + k3·ë + k2·ė + k1·e + I                   state feedback and integral
//! b̂   = b(x, sgn v)  (compensate)  or  b̄0        the valve's gain at the measured state
//! u   = clamp(v/b̂, ±u_limit)
//! İ   = ki·e + (b̂·u − v)/Tt                      back-calculation anti-windup, Tt = 1/λ
//! ```
//!
//! `b(x, s)` is the nominal model's gain of (9) at the load pressure of x in
//! the valve direction s (`NominalModel::gain_for`, floored at 10⁻³·b̄0 as
//! the sliding laws' is): dividing by it linearises the valve's flow, whose
//! gain falls as `√(Ps − s·P_L)` with the load pressure, and carries the
//! single rod's two directions (a cylinder's nominal model has its
//! direction offset, `NominalModel::with_offset`). With `compensate =
//! false` the law divides by the gain at rest b̄0 and is linear.
//!
//! **Gains by pole placement on the nominal model.** With the feed-forward
//! the nominal error obeys `e⃛ + ā3ë + ā2ė + ā1e = −(k3ë + k2ė + k1e + I)`,
//! so the closed loop's characteristic polynomial (differentiated once for
//! the integral) is
//! `s⁴ + (ā3 + k3)s³ + (ā2 + k2)s² + (ā1 + k1)s + ki`. The default places
//! it at `(s + λ)²·(s² + 2ζω·s + ω²)`: the resonance pair kept at the oil's
//! natural frequency `ω = ω_h` (the law does not fight the oil's
//! stiffness) with its damping raised to `ζ = damping` (0.7), and a double
//! real pole (position and integral) at `λ = min(ω_h/3, 0.2/dt)` — a third
//! of the resonance, and slow enough for the sample period. Term by term:
//!
//! ```text
//! k3 = 2λ + 2ζω − ā3
//! k2 = λ² + 4ζωλ + ω² − ā2
//! k1 = 2λω² + 2ζωλ² − ā1
//! ki = λ²ω²
//! ```
//!
//! `poles` (four, negative, rad/s) places the polynomial at any other real
//! poles instead (k3 = Σp − ā3 and so on, from the expanded product);
//! `integral = false` drops I and one λ (`(s + λ)(s² + 2ζωs + ω²)`, three
//! poles). The design is refused, naming the numbers, when the model has no
//! resonance to speak of (ā2 ≤ 0) or when the sample period cannot act on
//! it (ω_h·dt > 1: the sampled loop would feed back a resonance it sees
//! less than six times a period).
//!
//! The feedback reads x = (θ, θ̇, θ̈) as measured: give the sensors
//! (`[sensor]`) and an estimator for the channels that are not measured.
//!
//! References: M. Jelali, A. Kroll, *Hydraulic Servo-systems: Modelling,
//! Identification and Control*, Springer 2003 (linear state feedback of
//! valve-controlled cylinders by pole placement, with the pressure or
//! acceleration as the third state); H. E. Merritt, *Hydraulic Control
//! Systems*, Wiley 1967, §7 (pressure feedback and the damping of the load
//! resonance); "Controlling hydraulic servo systems: when PID is not
//! enough", Tech Briefs, 2013
//! (<https://www.techbriefs.com/component/content/article/tb/features/articles/18803>:
//! PID alone cannot place the four closed-loop poles of an underdamped
//! axis; a second-derivative gain adds the damping).

use super::{
    flags, Config, Controller, Design, LinearForm, Measurement, Output, Signal, Signals, Tunable,
};
use crate::error::{positive, ParamError};
use crate::math::{sgn, sqrt, Real};
use crate::servo::NominalModel;

/// `kind = "state-feedback"`: the `[controller]` keys. Gains left out are
/// designed from the nominal model (module doc).
///
/// ```
/// use ehservo_core::control::state_feedback::StateFeedbackConfig;
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.001,
/// # };
/// let c = StateFeedbackConfig::default().build(&design)?;
/// // The paper's servo: ω_h = √ā2 = √13000.2711 = 114.02 rad/s, so
/// // λ = min(ω_h/3, 0.2/dt) = 38.007 at dt = 1 ms, and ki = λ²·ω_h².
/// let (wh, lambda) = (13000.2711f64.sqrt(), 13000.2711f64.sqrt() / 3.0);
/// let [_, _, _, ki] = c.gains();
/// assert!((ki - lambda * lambda * wh * wh).abs() < 1e-6 * ki);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct StateFeedbackConfig {
    /// The closed-loop poles (rad/s, four negative reals; three without
    /// `integral`): place the polynomial there instead of the default
    /// pattern.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub poles: Option<[f64; 4]>,
    /// The double real pole λ of the default pattern (1/s); default
    /// min(ω_h/3, 0.2/dt).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub pole: Option<f64>,
    /// The natural frequency of the resonance pair (rad/s); default
    /// ω_h = √ā2, the oil's.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub frequency: Option<f64>,
    /// The damping ratio the pair is given. Default 0.7.
    pub damping: f64,
    /// Integral action on the position error. Default true.
    pub integral: bool,
    /// Reference feed-forward through the nominal model. Default true.
    pub feedforward: bool,
    /// Divide by the valve's gain at the measured state and direction
    /// (flow linearisation, the single rod's two gains) instead of the gain
    /// at rest. Default true.
    pub compensate: bool,
    /// The command's limit (V); none by default.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub u_limit: Option<f64>,
}

impl Default for StateFeedbackConfig {
    fn default() -> Self {
        Self {
            poles: None,
            pole: None,
            frequency: None,
            damping: 0.7,
            integral: true,
            feedforward: true,
            compensate: true,
            u_limit: None,
        }
    }
}

/// The coefficients `[c3, c2, c1, c0]` of `Π (s − p_i)` over four poles
/// (the monic quartic `s⁴ + c3·s³ + c2·s² + c1·s + c0`).
fn quartic(p: [f64; 4]) -> [f64; 4] {
    // Multiply the monic factors in turn: coefficients from the highest.
    let mut c = [1.0, 0.0, 0.0, 0.0, 0.0];
    for (n, root) in p.iter().enumerate() {
        for i in (1..=n + 1).rev() {
            c[i] -= root * c[i - 1];
        }
    }
    [c[1], c[2], c[3], c[4]]
}

/// The designed gains `[k3, k2, k1, ki]` (module doc) on the nominal
/// model `a = [ā1, ā2, ā3]` for sample period `dt`.
pub fn design_gains(
    cfg: &StateFeedbackConfig,
    a: [f64; 3],
    dt: f64,
) -> Result<[f64; 4], ParamError> {
    design(cfg, a, dt).map(|(k, _)| k)
}

/// The default pattern's pair frequency ω and double pole λ (module doc):
/// `frequency` or ω_h = √ā2, and `pole` or min(ω/3, 0.2/dt).
fn pattern(cfg: &StateFeedbackConfig, a: [f64; 3], dt: f64) -> Result<(f64, f64), ParamError> {
    if !(a[1].is_finite() && a[1] > 0.0) {
        return Err(ParamError::new(
            "frequency",
            "cannot default to ω_h = √ā2: the nominal model has ā2 ≤ 0 (no hydraulic resonance); give frequency or poles",
            a[1],
        ));
    }
    let wh = sqrt(a[1]);
    let w = match cfg.frequency {
        Some(f) => positive("frequency", f)?,
        None => wh,
    };
    if w * dt > 1.0 {
        return Err(ParamError::new(
            "frequency",
            "times the sample period dt exceeds 1: the sampled loop cannot act on a resonance it sees less than six times a period (shorten simulation.step, or give a lower frequency)",
            w,
        ));
    }
    let l = match cfg.pole {
        Some(p) => positive("pole", p)?,
        None => (w / 3.0).min(0.2 / dt),
    };
    Ok((w, l))
}

/// [`design_gains`] with the slowest designed pole's speed (1/s): λ of
/// the default pattern, or the least |p| of the poles in use.
fn design(cfg: &StateFeedbackConfig, a: [f64; 3], dt: f64) -> Result<([f64; 4], f64), ParamError> {
    // The polynomial's coefficients [c3, c2, c1, c0] (c0 = 0 without I),
    // and the slowest pole.
    let (c, slow) = match cfg.poles {
        Some(p) => {
            let used = &p[..if cfg.integral { 4 } else { 3 }];
            for &v in used {
                if !(v.is_finite() && v < 0.0) {
                    return Err(ParamError::new("poles", "must be finite and < 0", v));
                }
            }
            let slow = used.iter().fold(f64::INFINITY, |m, v| m.min(v.abs()));
            let c = if cfg.integral {
                quartic(p)
            } else {
                // The cubic of the first three, as the quartic's with a
                // root at 0: its last coefficient vanishes.
                quartic([p[0], p[1], p[2], 0.0])
            };
            (c, slow)
        }
        None => {
            let (w, l) = pattern(cfg, a, dt)?;
            let z = positive("damping", cfg.damping)?;
            let c = if cfg.integral {
                // (s + λ)²(s² + 2ζωs + ω²), expanded (module doc).
                [
                    2.0 * l + 2.0 * z * w,
                    l * l + 4.0 * z * w * l + w * w,
                    2.0 * l * w * w + 2.0 * z * w * l * l,
                    l * l * w * w,
                ]
            } else {
                // (s + λ)(s² + 2ζωs + ω²)·s: the cubic's coefficients.
                [l + 2.0 * z * w, 2.0 * z * w * l + w * w, l * w * w, 0.0]
            };
            (c, l)
        }
    };
    Ok(([c[0] - a[2], c[1] - a[1], c[2] - a[0], c[3]], slow))
}

/// The parts of the state feedback at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StateFeedbackParts<T = f64> {
    /// The reference feed-forward `θ⃛d + ā·z` (position unit/s³).
    pub ff: T,
    /// The state feedback `k3·ë + k2·ė + k1·e` (position unit/s³).
    pub fb: T,
    /// The integral term I (position unit/s³).
    pub i: T,
    /// The valve gain the law divided by.
    pub b_hat: T,
    /// The command before the limit (V).
    pub u_unsat: T,
}

impl<T: Real> Signals for StateFeedbackParts<T> {
    const SIGNALS: &'static [Signal] = &[
        Signal::new(
            "ff",
            "ff_per_s3",
            "1/s³",
            "reference feed-forward through the nominal model (in b̂·u units)",
        ),
        Signal::new(
            "fb",
            "fb_per_s3",
            "1/s³",
            "state feedback k3·ë + k2·ė + k1·e (in b̂·u units)",
        ),
        Signal::new("i", "i_per_s3", "1/s³", "integral term (in b̂·u units)"),
        Signal::new(
            "b_hat",
            "b_hat",
            "1/(s³·V)",
            "the valve gain divided by: b(x, sgn v), or b̄0",
        ),
        Signal::new(
            "u_unsat",
            "u_unsat_V",
            "V",
            "command before the output limit",
        ),
    ];
    fn write(&self, out: &mut [f64]) {
        for (o, v) in out
            .iter_mut()
            .zip([self.ff, self.fb, self.i, self.b_hat, self.u_unsat])
        {
            *o = v.to_f64();
        }
    }
}

/// The state-feedback controller, designed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StateFeedback<T: Real = f64> {
    /// `[k3, k2, k1, ki]`.
    k: [T; 4],
    a: [T; 3],
    b0: T,
    b_floor: T,
    /// 1/Tt.
    inv_tt: T,
    u_limit: T,
    model: NominalModel<T>,
    feedforward: bool,
    compensate: bool,
}

impl<T: Real> StateFeedback<T> {
    /// `[k3, k2, k1, ki]` (1/s, 1/s², 1/s³, 1/s⁴).
    pub fn gains(&self) -> [T; 4] {
        self.k
    }

    /// The same controller in another float type.
    pub fn cast<U: Real>(&self) -> StateFeedback<U> {
        let c = |v: T| U::of(v.to_f64());
        StateFeedback {
            k: self.k.map(c),
            a: self.a.map(c),
            b0: c(self.b0),
            b_floor: c(self.b_floor),
            inv_tt: c(self.inv_tt),
            u_limit: c(self.u_limit),
            model: self.model.cast(),
            feedforward: self.feedforward,
            compensate: self.compensate,
        }
    }
}

impl Config for StateFeedbackConfig {
    const KIND: &'static str = "state-feedback";
    const USES_SURFACE: bool = false;
    /// The pattern's three numbers (the pair's frequency and damping, the
    /// double pole), over decades around a hydraulic axis's.
    const TUNABLE: &'static [Tunable] = &[
        Tunable::log("frequency", 1.0, 3000.0),
        Tunable::linear("damping", 0.2, 1.5),
        Tunable::log("pole", 0.3, 1000.0),
    ];
    type Controller = StateFeedback;
    type Law<F: Real> = StateFeedback<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<StateFeedback<F>, ParamError> {
        Ok(self.build(d)?.cast())
    }

    /// The default pattern's `frequency` and `pole`, as designed (none
    /// filled when `poles` are given: they are the design).
    fn designed(&self, d: &Design) -> Option<Result<Self, ParamError>> {
        Some(self.build(d).and_then(|_| {
            if self.poles.is_some() {
                return Ok(*self);
            }
            let (w, l) = pattern(self, d.model.coeffs.as_array(), d.dt)?;
            Ok(Self {
                frequency: Some(w),
                pole: Some(l),
                ..*self
            })
        }))
    }

    /// The law while its limit does not act, dividing by b̄0 (exactly the
    /// law with `compensate = false`; with it, the law's gain at rest).
    fn linear(&self, d: &Design) -> Option<Result<LinearForm, ParamError>> {
        Some(self.build(d).map(|c| LinearForm::StateFeedback {
            k: c.k,
            feedforward: if self.feedforward {
                [c.a[0], c.a[1], c.a[2], 1.0]
            } else {
                [0.0; 4]
            },
            b0: c.b0,
            compensate: self.compensate,
            u_limit: c.u_limit,
        }))
    }

    fn build(&self, d: &Design) -> Result<StateFeedback, ParamError> {
        let a = d.model.coeffs.as_array();
        // Tt = 1/λ: the slowest designed pole, the integral's own speed.
        let (k, slow) = design(self, a, d.dt)?;
        let u_limit = match self.u_limit {
            Some(l) => positive("u_limit", l)?,
            None => f64::INFINITY,
        };
        let b0 = d.model.b_at_rest();
        Ok(StateFeedback {
            k: if self.integral {
                k
            } else {
                [k[0], k[1], k[2], 0.0]
            },
            a,
            b0,
            b_floor: 1e-3 * b0,
            inv_tt: slow,
            u_limit,
            model: d.model,
            feedforward: self.feedforward,
            compensate: self.compensate,
        })
    }
}

impl<T: Real> Controller<T> for StateFeedback<T> {
    /// I, the integral term (position unit/s³).
    type State = [T; 1];
    type Parts = StateFeedbackParts<T>;

    fn initial_state(&self) -> [T; 1] {
        [T::ZERO]
    }

    #[inline]
    fn law(
        &self,
        m: &Measurement<T>,
        s: &[T; 1],
        ds: &mut [T; 1],
    ) -> Output<StateFeedbackParts<T>, T> {
        let (x, z) = (&m.x, &m.z);
        let e = [z[0] - x[0], z[1] - x[1], z[2] - x[2]];
        let ff = if self.feedforward {
            z[3] + self.a[2] * z[2] + self.a[1] * z[1] + self.a[0] * z[0]
        } else {
            T::ZERO
        };
        let fb = self.k[0] * e[2] + self.k[1] * e[1] + self.k[2] * e[0];
        let v = ff + fb + s[0];
        let (b_hat, mut fl) = if self.compensate {
            let (b, floored) = self.model.gain_for(x, v, self.b_floor);
            (
                b,
                if floored {
                    flags::VALVE_ROOT_CLAMPED
                } else {
                    0
                },
            )
        } else {
            (self.b0, 0)
        };
        let u_unsat = v / b_hat;
        let u = if u_unsat.abs() > self.u_limit {
            fl |= flags::SATURATED;
            u_unsat.clamp(-self.u_limit, self.u_limit)
        } else {
            u_unsat
        };
        // Back-calculation: what the limit took away, in b̂·u units.
        ds[0] = self.k[3] * e[0] + (b_hat * u - v) * self.inv_tt;
        Output {
            u,
            flags: fl,
            parts: StateFeedbackParts {
                ff,
                fb,
                i: s[0],
                b_hat,
                u_unsat,
            },
        }
    }
}

/// The sign the law's command takes for `v` (the valve direction b̂ is
/// chosen by): `sgn v`, exposed for the tests of the compensation.
pub fn direction<T: Real>(v: T) -> T {
    sgn(v)
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use crate::sampled::SampledController;
    use crate::servo::{Load, ServoParams};
    use crate::surface::SwitchingSurface;

    fn design(dt: f64) -> Design {
        Design {
            model: NominalModel::new(ServoParams::paper(), Load::paper()),
            surface: SwitchingSurface::paper(),
            dt,
        }
    }

    /// (s + 1)(s + 2)(s + 3)(s + 4) = s⁴ + 10s³ + 35s² + 50s + 24.
    #[test]
    fn quartic_expands_by_hand() {
        assert_eq!(quartic([-1.0, -2.0, -3.0, -4.0]), [10.0, 35.0, 50.0, 24.0]);
    }

    /// The designed polynomial s⁴ + (ā3 + k3)s³ + (ā2 + k2)s² + (ā1 +
    /// k1)s + ki vanishes at −λ (double: its derivative too) and at the pair
    /// −ζω ± jω√(1 − ζ²), with the paper's ā at dt = 1 ms: ω = ω_h =
    /// √13000.2711 = 114.018, λ = ω/3 = 38.006.
    #[test]
    fn default_gains_place_the_poles() {
        let d = design(0.001);
        let a = d.model.coeffs.as_array();
        let k = design_gains(&StateFeedbackConfig::default(), a, 0.001).unwrap();
        let c = [1.0, a[2] + k[0], a[1] + k[1], a[0] + k[2], k[3]];
        let poly = |s: f64| c.iter().fold(0.0, |acc, ci| acc * s + ci);
        let dpoly = |s: f64| 4.0 * s * s * s + 3.0 * c[1] * s * s + 2.0 * c[2] * s + c[3];
        let w = a[1].sqrt();
        let l = w / 3.0;
        assert!((w - 114.018).abs() < 1e-3, "{w}");
        assert!(poly(-l).abs() < 1e-9 * c[4], "{}", poly(-l));
        assert!(dpoly(-l).abs() < 1e-9 * c[4]);
        let (re, im) = (-0.7 * w, w * (1.0f64 - 0.49).sqrt());
        let mut acc = (0.0, 0.0);
        for ci in c {
            acc = (acc.0 * re - acc.1 * im + ci, acc.0 * im + acc.1 * re);
        }
        assert!(
            acc.0.abs() < 1e-6 * c[4] && acc.1.abs() < 1e-6 * c[4],
            "{acc:?}"
        );
    }

    /// Given poles are the polynomial's roots: at −10, −20, −30, −40 the
    /// coefficients are (100, 3500, 50000, 240000) (expanded by hand:
    /// (s² + 30s + 200)(s² + 70s + 1200)).
    #[test]
    fn given_poles_are_placed() {
        let a = [0.5, 1000.0, 20.0];
        let cfg = StateFeedbackConfig {
            poles: Some([-10.0, -20.0, -30.0, -40.0]),
            ..StateFeedbackConfig::default()
        };
        let k = design_gains(&cfg, a, 0.001).unwrap();
        assert_eq!(k, [100.0 - 20.0, 3500.0 - 1000.0, 50000.0 - 0.5, 240000.0]);
        let bad = StateFeedbackConfig {
            poles: Some([-10.0, 5.0, -30.0, -40.0]),
            ..cfg
        };
        assert_eq!(design_gains(&bad, a, 0.001).unwrap_err().name, "poles");
    }

    /// A resonance the sample period cannot act on is refused, naming it:
    /// ω_h·dt = 114.018·0.01 = 1.14 > 1 for the paper's servo at 10 ms.
    #[test]
    fn a_resonance_beyond_the_sample_rate_is_refused() {
        let e = StateFeedbackConfig::default()
            .build(&design(0.01))
            .unwrap_err();
        assert_eq!(e.name, "frequency");
        assert!((e.value - 13000.2711f64.sqrt()).abs() < 1e-3);
        // A slower pair is accepted there.
        let slow = StateFeedbackConfig {
            frequency: Some(50.0),
            ..StateFeedbackConfig::default()
        };
        assert!(slow.build(&design(0.01)).is_ok());
    }

    /// The compensation divides by the gain of the command's direction at
    /// the measured load pressure: with x3 = 100 rad/s² the paper's
    /// P_L = (Jt·x3 + Tl(0))/Dm > 0, so b(x, +1) < b̄0 < b(x, −1), and
    /// b̂·u is v in both directions.
    #[test]
    fn the_gain_follows_the_direction_and_the_load_pressure() {
        let d = design(0.001);
        let c = StateFeedbackConfig::default().build(&d).unwrap();
        let b0 = d.model.b_at_rest();
        for target in [0.01, -0.01] {
            let m = Measurement {
                t: 0.0,
                x: [0.0, 0.0, 100.0],
                z: [target, 0.0, 0.0, 0.0],
            };
            let o = c.law(&m, &[0.0], &mut [0.0]);
            let v = o.parts.ff + o.parts.fb + o.parts.i;
            assert!((o.u * o.parts.b_hat - v).abs() < 1e-9 * v.abs());
            let (b, _) = d.model.b(&m.x, direction(v));
            assert_eq!(o.parts.b_hat, b);
            if v > 0.0 {
                assert!(o.parts.b_hat < b0);
            } else {
                assert!(o.parts.b_hat > b0);
            }
        }
    }

    /// On the nominal linear plant x⃛ = −ā·x + b̄0·u (no load, the gain at
    /// rest), the sampled law at 0.1 ms holds a step of 0.01 rad: the
    /// error decays at the designed rate. The slowest designed pole is
    /// λ = 38 1/s (double): after 0.5 s (19 time constants) e < 1e-5 rad.
    #[test]
    fn a_step_on_the_nominal_plant_settles() {
        let dt = 1e-4;
        let d = Design {
            model: NominalModel::new(
                ServoParams::paper(),
                Load {
                    amplitude: 0.0,
                    wavenumber: 0.0,
                    friction: None,
                },
            ),
            ..design(dt)
        };
        let cfg = StateFeedbackConfig {
            compensate: false,
            ..StateFeedbackConfig::default()
        };
        let c = cfg.build(&d).unwrap();
        let a = d.model.coeffs.as_array();
        let b0 = d.model.b_at_rest();
        let mut sc = SampledController::new(c, dt).unwrap();
        let mut x = [0.0f64; 3];
        let z = [0.01, 0.0, 0.0, 0.0];
        for k in 0..5000 {
            let u = sc.step(k as f64 * dt, x, z).u;
            // Forward Euler of the plant at dt/10 under the held u.
            for _ in 0..10 {
                let j = -a[0] * x[0] - a[1] * x[1] - a[2] * x[2] + b0 * u;
                x = [
                    x[0] + dt / 10.0 * x[1],
                    x[1] + dt / 10.0 * x[2],
                    x[2] + dt / 10.0 * j,
                ];
            }
        }
        assert!((0.01 - x[0]).abs() < 1e-5, "{}", x[0]);
    }
}
