//! PID with feedforward through the nominal model: the industry's default
//! servo controller, as a baseline beside the paper's laws.
//!
//! ```text
//! e    = θd − θ
//! θ̇f   = (θ − θf)/Tf                     first-order filter of the measured θ
//! y_d  = (θ − θf)/Tf                     filtered derivative of the measurement
//! ff   = (θ⃛d + ā1·θd + ā2·θ̇d + ā3·θ̈d)/b̄0   feedforward through the nominal model (8)
//! p    = kp·e
//! d    = kd·(θ̇d − y_d)                    derivative on the measurement (θ̇d is known)
//! v    = ff + p + I + d,   u = clamp(v, ±u_limit)
//! İ    = ki·e + (u − v)/Tt                integral with back-calculation anti-windup
//! ```
//!
//! b̄0 = b(x = 0) is the nominal gain at rest: the controller is linear. The
//! derivative uses θ only (no θ̇ or θ̈ sensor), through a filter of time
//! constant Tf; with Tf equal to the sample period the sampled loop's
//! forward-Euler update makes θf the previous sample, so `y_d` is the
//! textbook backward difference (θ_k − θ_{k−1})/dt. θf starts at 0 (x(0) = 0).
//!
//! **Default gains, by pole placement on the nominal model.** With the
//! feedforward and derivative on the measurement, the nominal error obeys
//! `e⃛ + ā3ë + ā2ė + ā1e = −b̄0(kp·e + ki·∫e + kd·ė)` (filter neglected), so
//! the closed loop's characteristic polynomial is
//! `s⁴ + ā3·s³ + (ā2 + b̄0·kd)·s² + (ā1 + b̄0·kp)·s + b̄0·ki`. Its s³
//! coefficient is the plant's own: three gains place four poles with their
//! sum fixed at −ā3. The design takes a double real pole at −λ
//! (`design_pole`, default 30 s⁻¹) and a pair of damping ζ
//! (`design_damping`, default 0.7) whose natural frequency uses the rest of
//! the sum: `ω = (ā3 − 2λ)/(2ζ)`. Matching
//! `(s + λ)²(s² + 2ζω·s + ω²)` term by term:
//!
//! ```text
//! kd = (λ² + 4λζω + ω² − ā2)/b̄0
//! kp = (2λω² + 2ζωλ² − ā1)/b̄0
//! ki = λ²ω²/b̄0
//! ```
//!
//! For the paper's servo (ā1 = 0.39982, ā2 = 13000.2711, ā3 = 169.98043,
//! b̄0 = 17911.75): ω = 78.557, kd = 0.0375, kp = 26.2, ki = 310. The design
//! needs ā3 > 2λ and kd ≥ 0; otherwise the controller is refused with the
//! reason (give the gains instead). The tracking time defaults to
//! `Tt = √(Ti·Td)` (Ti = kp/ki, Td = kd/kp; Åström & Hägglund's rule), or Ti
//! when kd = 0; the filter to `Tf = max(Td/10, dt)`.
//!
//! References: K. J. Åström, T. Hägglund, *Advanced PID Control*, ISA 2006
//! (derivative filter, set-point weighting, back-calculation anti-windup);
//! H. E. Merritt, *Hydraulic Control Systems*, Wiley 1967 (feedforward of
//! the valve-controlled motor's nominal model).

use super::{
    flags, Config, Controller, Design, LinearForm, Measurement, Output, Signal, Signals, Tunable,
};
use crate::error::{positive, ParamError};
use crate::math::{sqrt, Real};

/// `kind = "pid"`: the `[controller]` keys. Gains left out are designed
/// from the nominal model (module doc).
///
/// ```
/// use ehservo_core::control::pid::PidConfig;
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// let pid = PidConfig::default().build(&design)?;
/// let (kp, ki, kd) = pid.gains();
/// // The pole placement worked by hand in the module doc: ω = 78.557,
/// // kp = 26.2, ki = 310, kd = 0.0375.
/// assert!((kp - 26.2).abs() < 0.05 && (ki - 310.0).abs() < 1.0 && (kd - 0.0375).abs() < 5e-4);
/// // At rest with θd = 0.01 rad and θ̇d = θ̈d = θ⃛d = 0, state 0: e = 0.01, the
/// // filter and the integral still at 0, so p = kp·e and the feedforward
/// // is ā1·θd/b̄0 (the nominal model's static term).
/// let m = Measurement { t: 0.0, x: [0.0; 3], z: [0.01, 0.0, 0.0, 0.0] };
/// let out = pid.law(&m, &[0.0; 2], &mut [0.0; 2]);
/// assert!((out.p - kp * 0.01).abs() < 1e-15);
/// let ff = design.model.coeffs.a1 * 0.01 / design.model.b_at_rest();
/// assert!((out.u - (kp * 0.01 + ff)).abs() < 1e-15);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct PidConfig {
    /// Proportional gain (V/rad); designed when absent.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub kp: Option<f64>,
    /// Integral gain (V/(rad·s)); designed when absent.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub ki: Option<f64>,
    /// Derivative gain (V·s/rad); designed when absent.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub kd: Option<f64>,
    /// λ, the double real closed-loop pole of the design (s⁻¹). Default 30.
    pub design_pole: f64,
    /// ζ, the damping of the design's complex pair. Default 0.7.
    pub design_damping: f64,
    /// Tf, the derivative filter's time constant (s); default max(Td/10, dt).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub filter_time: Option<f64>,
    /// Tt, the anti-windup tracking time (s); default √(Ti·Td) (Ti if kd = 0).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub tracking_time: Option<f64>,
    /// Output limit ±u_limit (V); none by default.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub u_limit: Option<f64>,
    /// Feedforward of the reference through the nominal model. Default true.
    pub feedforward: bool,
}

impl Default for PidConfig {
    fn default() -> Self {
        Self {
            kp: None,
            ki: None,
            kd: None,
            design_pole: 30.0,
            design_damping: 0.7,
            filter_time: None,
            tracking_time: None,
            u_limit: None,
            feedforward: true,
        }
    }
}

/// Gains designed by pole placement (module doc): `(kp, ki, kd)`.
///
/// ```
/// use ehservo_core::control::pid::design_gains;
/// use ehservo_core::servo::{Load, NominalModel, ServoParams};
///
/// let m = NominalModel::new(ServoParams::paper(), Load::paper());
/// let (a, b0) = (m.coeffs.as_array(), m.b_at_rest());
/// let (kp, ki, kd) = design_gains(a, b0, 30.0, 0.7)?;
/// // The closed loop's s⁴ + ā3s³ + (ā2 + b̄0kd)s² + (ā1 + b̄0kp)s + b̄0ki
/// // has the double pole λ = 30 asked for: it and its derivative vanish at −30.
/// let c = [1.0, a[2], a[1] + b0 * kd, a[0] + b0 * kp, b0 * ki];
/// let p = |s: f64| c.iter().fold(0.0, |acc, ci| acc * s + ci);
/// let dp = |s: f64| 4.0 * s.powi(3) + 3.0 * c[1] * s * s + 2.0 * c[2] * s + c[3];
/// assert!(p(-30.0).abs() < 1e-9 * c[4] && dp(-30.0).abs() < 1e-9 * c[4]);
/// // The poles' sum is the plant's −ā3: λ = 90 leaves nothing for the pair.
/// assert_eq!(design_gains(a, b0, 90.0, 0.7).unwrap_err().name, "design_pole");
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
pub fn design_gains(
    a: [f64; 3],
    b0: f64,
    lambda: f64,
    zeta: f64,
) -> Result<(f64, f64, f64), ParamError> {
    positive("design_pole", lambda)?;
    positive("design_damping", zeta)?;
    if a[2] <= 2.0 * lambda {
        return Err(ParamError::new(
            "design_pole",
            "must be < ā3/2: the poles' sum is fixed at −ā3 (use kind = \"state-feedback\", or give kp, ki, kd)",
            lambda,
        ));
    }
    let w = (a[2] - 2.0 * lambda) / (2.0 * zeta);
    let kd = (lambda * lambda + 4.0 * lambda * zeta * w + w * w - a[1]) / b0;
    let kp = (2.0 * lambda * w * w + 2.0 * zeta * w * lambda * lambda - a[0]) / b0;
    let ki = lambda * lambda * w * w / b0;
    if kd < 0.0 {
        return Err(ParamError::new(
            "design_pole",
            "gives kd < 0 for this plant (the pair's ω² is below ā2): give kp, ki, kd, or use kind = \"state-feedback\" on a lightly damped axis",
            lambda,
        ));
    }
    Ok((kp, ki, kd))
}

/// The PID's parts.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PidParts<T = f64> {
    /// Proportional term kp·e (V).
    pub p: T,
    /// Integral term I (V).
    pub i: T,
    /// Derivative term kd·(θ̇d − y_d) (V).
    pub d: T,
    /// Feedforward (V).
    pub ff: T,
    /// The command before the output limit (V).
    pub u_unsat: T,
}

impl<T: Real> Signals for PidParts<T> {
    const SIGNALS: &'static [Signal] = &[
        Signal::new("p", "p_V", "V", "proportional term kp·e"),
        Signal::new("i", "i_V", "V", "integral term"),
        Signal::new(
            "d",
            "d_V",
            "V",
            "derivative term on the filtered measurement",
        ),
        Signal::new("ff", "ff_V", "V", "feedforward through the nominal model"),
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
            .zip([self.p, self.i, self.d, self.ff, self.u_unsat])
        {
            *o = v.to_f64();
        }
    }
}

/// The PID controller, built.
///
/// ```
/// use ehservo_core::control::pid::PidConfig;
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// // Gains given, no feedforward: kp = 2, ki = 3, kd = 0.5, Tf = 0.1 s.
/// let pid = PidConfig {
///     kp: Some(2.0),
///     ki: Some(3.0),
///     kd: Some(0.5),
///     filter_time: Some(0.1),
///     feedforward: false,
///     ..PidConfig::default()
/// }
/// .build(&design)?;
/// // State (I, θf) = (0.25, 0.01), θ = 0.03, θd = 0.05, θ̇d = 0.2:
/// // e = 0.02, y_d = (0.03 − 0.01)/0.1 = 0.2, p = 2·0.02 = 0.04,
/// // d = 0.5·(0.2 − 0.2) = 0, u = 0.04 + 0.25 + 0 = 0.29; İ = 3·0.02 = 0.06.
/// let m = Measurement { t: 0.0, x: [0.03, 0.0, 0.0], z: [0.05, 0.2, 0.0, 0.0] };
/// let mut ds = [0.0; 2];
/// let out = pid.law(&m, &[0.25, 0.01], &mut ds);
/// assert!((out.u - 0.29).abs() < 1e-12 && (out.p - 0.04).abs() < 1e-12);
/// assert!((ds[0] - 0.06).abs() < 1e-12 && (ds[1] - 0.2).abs() < 1e-12);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pid<T: Real = f64> {
    kp: T,
    ki: T,
    kd: T,
    tf: T,
    tt: T,
    u_limit: T,
    a: [T; 3],
    b0: T,
    feedforward: bool,
}

impl<T: Real> Pid<T> {
    /// The gains `(kp, ki, kd)` in use.
    pub fn gains(&self) -> (T, T, T) {
        (self.kp, self.ki, self.kd)
    }

    /// The filter and tracking times `(Tf, Tt)` (s).
    pub fn times(&self) -> (T, T) {
        (self.tf, self.tt)
    }

    /// The same controller in another float type.
    pub fn cast<U: Real>(&self) -> Pid<U> {
        let c = |v: T| U::of(v.to_f64());
        Pid {
            kp: c(self.kp),
            ki: c(self.ki),
            kd: c(self.kd),
            tf: c(self.tf),
            tt: c(self.tt),
            u_limit: c(self.u_limit),
            a: self.a.map(c),
            b0: c(self.b0),
            feedforward: self.feedforward,
        }
    }
}

impl Config for PidConfig {
    const KIND: &'static str = "pid";
    const USES_SURFACE: bool = false;
    /// The three gains over decades around the pole-placement design of
    /// the Fig. 2 case (kp ≈ 26 V/rad, ki ≈ 310 V/(rad·s), kd ≈ 0.038 V·s/rad).
    const TUNABLE: &'static [Tunable] = &[
        Tunable::log("kp", 0.1, 1e4),
        Tunable::log("ki", 0.1, 1e5),
        Tunable::log("kd", 1e-4, 10.0),
    ];
    type Controller = Pid;
    type Law<F: Real> = Pid<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<Pid<F>, ParamError> {
        Ok(self.build(d)?.cast())
    }

    /// The PID with its reference feed-forward
    /// `(θ⃛d + ā1·θd + ā2·θ̇d + ā3·θ̈d)/b̄0` when `feedforward` is on.
    fn linear(&self, d: &Design) -> Option<Result<LinearForm, ParamError>> {
        Some(self.build(d).map(|pid| {
            let (kp, ki, kd) = pid.gains();
            let (tf, _) = pid.times();
            let a = d.model.coeffs.as_array();
            let b0 = d.model.b_at_rest();
            let feedforward = if self.feedforward {
                [a[0] / b0, a[1] / b0, a[2] / b0, 1.0 / b0]
            } else {
                [0.0; 4]
            };
            LinearForm::Pid {
                kp,
                ki,
                kd,
                tf,
                feedforward,
                u_limit: self.u_limit.unwrap_or(f64::INFINITY),
            }
        }))
    }

    /// The gains and the filter and tracking times, designed or given.
    fn designed(&self, d: &Design) -> Option<Result<Self, ParamError>> {
        Some(self.build(d).map(|pid| {
            let (kp, ki, kd) = pid.gains();
            let (tf, tt) = pid.times();
            Self {
                kp: Some(kp),
                ki: Some(ki),
                kd: Some(kd),
                filter_time: Some(tf),
                tracking_time: Some(tt),
                ..*self
            }
        }))
    }

    fn build(&self, d: &Design) -> Result<Pid, ParamError> {
        let a = d.model.coeffs.as_array();
        let b0 = d.model.b_at_rest();
        let designed = design_gains(a, b0, self.design_pole, self.design_damping);
        let gain = |name, v: Option<f64>, pick: fn((f64, f64, f64)) -> f64| match v {
            Some(g) if g.is_finite() && g >= 0.0 => Ok(g),
            Some(g) => Err(ParamError::new(name, "must be finite and >= 0", g)),
            None => designed.map(pick),
        };
        let kp = gain("kp", self.kp, |g| g.0)?;
        let ki = gain("ki", self.ki, |g| g.1)?;
        let kd = gain("kd", self.kd, |g| g.2)?;
        let tf = match self.filter_time {
            Some(t) => positive("filter_time", t)?,
            None if kp > 0.0 => (kd / kp / 10.0).max(d.dt),
            None => d.dt,
        };
        let tt = match self.tracking_time {
            Some(t) => positive("tracking_time", t)?,
            None if ki > 0.0 && kd > 0.0 && kp > 0.0 => sqrt(kp / ki * kd / kp),
            None if ki > 0.0 && kp > 0.0 => kp / ki,
            None => 1.0,
        };
        let u_limit = match self.u_limit {
            Some(l) => positive("u_limit", l)?,
            None => f64::INFINITY,
        };
        Ok(Pid {
            kp,
            ki,
            kd,
            tf,
            tt,
            u_limit,
            a,
            b0,
            feedforward: self.feedforward,
        })
    }
}

impl<T: Real> Controller<T> for Pid<T> {
    /// (I, θf): the integral term (V) and the filtered θ (rad).
    type State = [T; 2];
    type Parts = PidParts<T>;

    fn initial_state(&self) -> [T; 2] {
        [T::ZERO; 2]
    }

    #[inline]
    fn law(&self, m: &Measurement<T>, s: &[T; 2], ds: &mut [T; 2]) -> Output<PidParts<T>, T> {
        let (x, z) = (&m.x, &m.z);
        let e = z[0] - x[0];
        let y_d = (x[0] - s[1]) / self.tf;
        let ff = if self.feedforward {
            (z[3] + self.a[0] * z[0] + self.a[1] * z[1] + self.a[2] * z[2]) / self.b0
        } else {
            T::ZERO
        };
        let p = self.kp * e;
        let d = self.kd * (z[1] - y_d);
        let v = ff + p + s[0] + d;
        let (u, fl) = if v.abs() > self.u_limit {
            (v.clamp(-self.u_limit, self.u_limit), flags::SATURATED)
        } else {
            (v, 0)
        };
        ds[0] = self.ki * e + (u - v) / self.tt;
        ds[1] = y_d;
        Output {
            u,
            flags: fl,
            parts: PidParts {
                p,
                i: s[0],
                d,
                ff,
                u_unsat: v,
            },
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use crate::servo::{Load, NominalModel, ServoParams};
    use crate::surface::SwitchingSurface;

    fn design(dt: f64) -> Design {
        Design {
            model: NominalModel::new(ServoParams::paper(), Load::paper()),
            surface: SwitchingSurface::paper(),
            dt,
        }
    }

    /// The designed polynomial has the chosen roots: with the paper's
    /// ā and b̄0, s⁴ + ā3s³ + (ā2 + b̄0kd)s² + (ā1 + b̄0kp)s + b̄0ki must
    /// vanish at s = −λ (double: the derivative vanishes too) and at the
    /// pair −ζω ± jω√(1 − ζ²), ω = (ā3 − 2λ)/(2ζ) = 78.557.
    #[test]
    fn designed_gains_place_the_poles() {
        let d = design(0.01);
        let a = d.model.coeffs.as_array();
        let b0 = d.model.b_at_rest();
        let (kp, ki, kd) = design_gains(a, b0, 30.0, 0.7).unwrap();
        let c = [1.0, a[2], a[1] + b0 * kd, a[0] + b0 * kp, b0 * ki];
        let poly = |s: f64| c.iter().fold(0.0, |acc, ci| acc * s + ci);
        let dpoly = |s: f64| 4.0 * s * s * s + 3.0 * c[1] * s * s + 2.0 * c[2] * s + c[3];
        let scale = c[4];
        assert!(poly(-30.0).abs() < 1e-9 * scale, "{}", poly(-30.0));
        assert!(dpoly(-30.0).abs() < 1e-9 * scale);
        // Complex root: evaluate with (re, im) arithmetic.
        let w = (a[2] - 60.0) / 1.4;
        let (re, im) = (-0.7 * w, w * (1.0f64 - 0.49).sqrt());
        let mut acc = (0.0, 0.0);
        for ci in c {
            acc = (acc.0 * re - acc.1 * im + ci, acc.0 * im + acc.1 * re);
        }
        assert!(
            acc.0.abs() < 1e-6 * scale && acc.1.abs() < 1e-6 * scale,
            "{acc:?}"
        );
        // Hand values (module doc): ω = 110.0/1.4 = 78.557, kd = 0.0375, kp = 26.2, ki = 310.
        assert!((w - 78.557).abs() < 1e-3);
        assert!((kd - 0.0375).abs() < 5e-4, "{kd}");
        assert!((kp - 26.2).abs() < 0.05, "{kp}");
        assert!((ki - 310.0).abs() < 1.0, "{ki}");
    }

    /// One evaluation by hand, gains given: kp = 2, ki = 3, kd = 0.5,
    /// Tf = 0.1, no feedforward, state (I, θf) = (0.25, 0.01), θ = 0.03,
    /// θd = 0.05, θ̇d = 0.2: e = 0.02, y_d = (0.03 − 0.01)/0.1 = 0.2,
    /// p = 0.04, d = 0.5·(0.2 − 0.2) = 0, v = 0.04 + 0.25 + 0 = 0.29;
    /// İ = 3·0.02 = 0.06 (no saturation), θ̇f = 0.2.
    /// With u_limit = 0.1: u = 0.1, İ = 0.06 + (0.1 − 0.29)/Tt.
    #[test]
    fn law_by_hand_and_anti_windup() {
        let cfg = PidConfig {
            kp: Some(2.0),
            ki: Some(3.0),
            kd: Some(0.5),
            filter_time: Some(0.1),
            tracking_time: Some(0.5),
            feedforward: false,
            ..PidConfig::default()
        };
        let c = cfg.build(&design(0.01)).unwrap();
        let m = Measurement {
            t: 0.0,
            x: [0.03, 9.0, 9.0],
            z: [0.05, 0.2, 0.0, 0.0],
        };
        let mut ds = [0.0; 2];
        let o = c.law(&m, &[0.25, 0.01], &mut ds);
        let close = |a: f64, b: f64| assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        close(o.p, 0.04);
        close(o.d, 0.0);
        close(o.u, 0.29);
        close(ds[0], 0.06);
        close(ds[1], 0.2);
        assert_eq!(o.flags, 0);
        let lim = PidConfig {
            u_limit: Some(0.1),
            ..cfg
        }
        .build(&design(0.01))
        .unwrap();
        let o = lim.law(&m, &[0.25, 0.01], &mut ds);
        close(o.u, 0.1);
        close(o.u_unsat, 0.29);
        close(ds[0], 0.06 + (0.1 - 0.29) / 0.5);
        assert_ne!(o.flags & flags::SATURATED, 0);
    }

    /// The feedforward inverts the nominal model: at rest with
    /// z = (0, 0, 0, θ⃛d), ff = θ⃛d/b̄0.
    #[test]
    fn feedforward_inverts_the_nominal_model() {
        let d = design(0.01);
        let c = PidConfig::default().build(&d).unwrap();
        let m = Measurement {
            t: 0.0,
            x: [0.0; 3],
            z: [0.0, 0.0, 0.0, -21.6464647],
        };
        let o = c.law(&m, &[0.0; 2], &mut [0.0; 2]);
        assert!((o.ff - (-21.6464647 / d.model.b_at_rest())).abs() < 1e-15);
        assert!((o.u - o.ff).abs() < 1e-15);
    }

    #[test]
    fn bad_parameters_are_named() {
        let d = design(0.01);
        let bad = |c: PidConfig| c.build(&d).unwrap_err().name;
        assert_eq!(
            bad(PidConfig {
                kp: Some(-1.0),
                ..PidConfig::default()
            }),
            "kp"
        );
        assert_eq!(
            bad(PidConfig {
                design_pole: 100.0,
                ..PidConfig::default()
            }),
            "design_pole"
        );
        assert_eq!(
            bad(PidConfig {
                u_limit: Some(0.0),
                ..PidConfig::default()
            }),
            "u_limit"
        );
        // Tf defaults to the sample period when Td/10 is shorter.
        let c = PidConfig::default().build(&d).unwrap();
        assert_eq!(c.times().0, 0.01);
    }
}
