//! Force (or load-pressure) PI with velocity feed-forward: the load
//! simulator's classic law (issue #49 item 3, docs/force-control.md).
//!
//! On a force or pressure loop (`[reference] quantity = "force"` or
//! `"load-pressure"`) the controller measures x = (q, ẏ, ÿ): the
//! controlled quantity (N or Pa) and the rod's velocity and acceleration.
//!
//! ```text
//! e  = q_d − q                      force (N) or load-pressure (Pa) error
//! p  = kp·e
//! ff = kv·ẏ                         the flow the rod's motion takes, fed forward
//! v  = p + I + ff,   u = clamp(v, ±u_limit)
//! İ  = ki·e,  held while u is clamped and e pushes further (conditional integration)
//! ```
//!
//! **The feed-forward, from the pressure dynamics.** Merritt's load-flow
//! continuity of a valve-controlled actuator (H. E. Merritt, *Hydraulic
//! Control Systems*, Wiley 1967, §6.2; the paper's (3) in the nominal
//! model's terms) reads
//!
//! ```text
//! (Vt/4βe)·ṗ_L = K_q(p_L)·u − Ā·ẏ − Kce·p_L,   K_q(p_L) = Kv·Cd·Ag·√((Ps − p_L)/ρ)
//! ```
//!
//! The rod's motion ẏ takes the flow Ā·ẏ, which the valve must supply for
//! p_L (hence the force Ā·p_L) to stay where it is: the "extra force" of a
//! load simulator. The command `u_ff = Ā·ẏ/K_q(p_L0)` supplies it at the
//! operating point p_L0, so that the pressure sees the motion only through
//! the linearisation's error:
//!
//! ```text
//! kv = Ā / K_q(p_L0) = Dm / (Kv·Cd·Ag·√((Ps − p_L0)/ρ))        (V·s/m)
//! ```
//!
//! with Dm = Ā, Kv, Cd, Ag, Ps and ρ the nominal model's (for a cylinder,
//! `CylinderPlant::nominal_model`), p_L0 the key `operating_pressure`
//! (Pa, default 0: the valve at null load). This is the velocity
//! synchronising compensation of the load-simulator literature: Karpenko &
//! Sepehri, *Control Engineering Practice* 20 (2012) 598–609, §2 (the load
//! emulator's flow continuity, whose velocity term is the disturbance);
//! Li, Shang, Jiao, Wu, "Surplus torque elimination control of
//! electro-hydraulic load simulator based on actuator velocity input
//! feedforward compensating method", *J. Dyn. Sys., Meas., Control* 140
//! (2018), doi 10.1115/1.4039663. `kv` may be given instead (0: no
//! feed-forward).
//!
//! **The gains.** kp and ki are given (V/N and V/(N·s) on a force loop,
//! V/Pa and V/(Pa·s) on a pressure loop): the loop's bandwidth depends on
//! the environment's stiffness, which the nominal model does not know.
//! docs/force-control.md derives them for a stiff specimen from the same
//! continuity equation.

use super::{flags, Config, Controller, Design, Measurement, Output, Signal, Signals, Tunable};
use crate::error::ParamError;
use crate::math::{sqrt, Real};

/// `kind = "force-pi"`: the `[controller]` keys.
///
/// ```
/// use ehservo_core::control::force_pi::ForcePiConfig;
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// // kp = 1e-4 V/N, ki = 1e-3 V/(N·s), kv = 2 V·s/m given.
/// let c = ForcePiConfig { kp: 1e-4, ki: 1e-3, kv: Some(2.0), ..Default::default() };
/// let law = c.build(&design)?;
/// // 10 kN asked, 8 kN measured, the rod at 0.05 m/s, I = 0.5 V:
/// // p = 1e-4·2000 = 0.2 V, ff = 2·0.05 = 0.1 V, u = 0.2 + 0.5 + 0.1 = 0.8 V;
/// // İ = 1e-3·2000 = 2 V/s.
/// let m = Measurement { t: 0.0, x: [8e3, 0.05, 0.0], z: [1e4, 0.0, 0.0, 0.0] };
/// let mut ds = [0.0];
/// let out = law.law(&m, &[0.5], &mut ds);
/// assert!((out.u - 0.8).abs() < 1e-12 && (ds[0] - 2.0).abs() < 1e-12);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct ForcePiConfig {
    /// Proportional gain (V/N on a force loop, V/Pa on a pressure loop), ≥ 0.
    pub kp: f64,
    /// Integral gain (V/(N·s) or V/(Pa·s)), ≥ 0.
    pub ki: f64,
    /// Velocity feed-forward gain (V·s/m), ≥ 0; designed from the nominal
    /// model at `operating_pressure` when absent (module doc).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub kv: Option<f64>,
    /// p_L0, the load pressure (Pa) at which `kv` is designed: in [0, Ps).
    /// Default 0.
    pub operating_pressure: f64,
    /// Output limit ±u_limit (V), past which the integral is held; none
    /// by default.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub u_limit: Option<f64>,
}

impl Default for ForcePiConfig {
    fn default() -> Self {
        Self {
            kp: 0.0,
            ki: 0.0,
            kv: None,
            operating_pressure: 0.0,
            u_limit: None,
        }
    }
}

/// kv = Dm/(Kv·Cd·Ag·√((Ps − p_L0)/ρ)) (V·s/m) of the nominal model at the
/// load pressure `pl0` (Pa): the command that supplies the flow Dm·ẏ the
/// motion takes (module doc).
///
/// ```
/// use ehservo_core::control::force_pi::feedforward_gain;
/// use ehservo_core::servo::ServoParams;
///
/// let p = ServoParams::paper();
/// // At p_L0 = 0: Dm/(Kv·Cd·Ag·√(Ps/ρ)), the inverse of (2)'s gain at rest per Dm.
/// let kg = p.kv * p.cd * p.ag * (p.ps / p.rho).sqrt();
/// assert!((feedforward_gain(&p, 0.0)? - p.dm / kg).abs() < 1e-12 * p.dm / kg);
/// // At p_L0 = 3/4·Ps the root halves: kv doubles.
/// let k34 = feedforward_gain(&p, 0.75 * p.ps)?;
/// assert!((k34 - 2.0 * p.dm / kg).abs() < 1e-9 * k34);
/// assert_eq!(feedforward_gain(&p, p.ps).unwrap_err().name, "operating_pressure");
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
pub fn feedforward_gain(p: &crate::servo::ServoParams, pl0: f64) -> Result<f64, ParamError> {
    if !(pl0.is_finite() && pl0 >= 0.0 && pl0 < p.ps) {
        return Err(ParamError::new(
            "operating_pressure",
            "must be finite, >= 0 and below the nominal supply pressure Ps",
            pl0,
        ));
    }
    let kq = p.kv * p.cd * p.ag * sqrt((p.ps - pl0) / p.rho);
    let kv = p.dm / kq;
    if kv.is_finite() && kv > 0.0 {
        Ok(kv)
    } else {
        Err(ParamError::new(
            "kv",
            "the nominal model's flow gain gives no finite feed-forward: give kv",
            kv,
        ))
    }
}

/// The force PI's parts.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ForcePiParts<T = f64> {
    /// Proportional term kp·e (V).
    pub p: T,
    /// Integral term I (V).
    pub i: T,
    /// Velocity feed-forward kv·ẏ (V).
    pub ff: T,
    /// The command before the output limit (V).
    pub u_unsat: T,
}

impl<T: Real> Signals for ForcePiParts<T> {
    const SIGNALS: &'static [Signal] = &[
        Signal::new("p", "p_V", "V", "proportional term kp·e"),
        Signal::new("i", "i_V", "V", "integral term"),
        Signal::new("ff", "ff_V", "V", "velocity feed-forward kv·ẏ"),
        Signal::new(
            "u_unsat",
            "u_unsat_V",
            "V",
            "command before the output limit",
        ),
    ];
    fn write(&self, out: &mut [f64]) {
        for (o, v) in out.iter_mut().zip([self.p, self.i, self.ff, self.u_unsat]) {
            *o = v.to_f64();
        }
    }
}

/// The force PI, built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForcePi<T: Real = f64> {
    kp: T,
    ki: T,
    kv: T,
    u_limit: T,
}

impl<T: Real> ForcePi<T> {
    /// The gains `(kp, ki, kv)` in use.
    pub fn gains(&self) -> (T, T, T) {
        (self.kp, self.ki, self.kv)
    }

    /// The same controller in another float type.
    pub fn cast<U: Real>(&self) -> ForcePi<U> {
        let c = |v: T| U::of(v.to_f64());
        ForcePi {
            kp: c(self.kp),
            ki: c(self.ki),
            kv: c(self.kv),
            u_limit: c(self.u_limit),
        }
    }
}

fn gain(name: &'static str, v: f64) -> Result<f64, ParamError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(ParamError::new(name, "must be finite and >= 0", v))
    }
}

impl Config for ForcePiConfig {
    const KIND: &'static str = "force-pi";
    const USES_SURFACE: bool = false;
    const CLOSES_ON_FORCE: bool = true;
    /// kp and ki over decades around the slide's force loop
    /// (scenarios/force/force-pi.toml: kp = 2e-4 V/N, ki = 4e-3 V/(N·s)).
    const TUNABLE: &'static [Tunable] = &[
        Tunable::log("kp", 1e-7, 1e-2),
        Tunable::log("ki", 1e-6, 1.0),
    ];
    type Controller = ForcePi;
    type Law<F: Real> = ForcePi<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<ForcePi<F>, ParamError> {
        Ok(self.build(d)?.cast())
    }

    /// kv designed from the nominal model when absent.
    fn designed(&self, d: &Design) -> Option<Result<Self, ParamError>> {
        Some(self.build(d).map(|c| Self {
            kv: Some(c.kv),
            ..*self
        }))
    }

    fn build(&self, d: &Design) -> Result<ForcePi, ParamError> {
        let kp = gain("kp", self.kp)?;
        let ki = gain("ki", self.ki)?;
        let designed = feedforward_gain(&d.model.params, self.operating_pressure);
        let kv = match self.kv {
            Some(k) => {
                designed?;
                gain("kv", k)?
            }
            None => designed?,
        };
        let u_limit = match self.u_limit {
            Some(l) if l.is_finite() && l > 0.0 => l,
            Some(l) => return Err(ParamError::new("u_limit", "must be finite and > 0", l)),
            None => f64::INFINITY,
        };
        Ok(ForcePi {
            kp,
            ki,
            kv,
            u_limit,
        })
    }
}

impl<T: Real> Controller<T> for ForcePi<T> {
    /// I, the integral term (V).
    type State = [T; 1];
    type Parts = ForcePiParts<T>;

    fn initial_state(&self) -> [T; 1] {
        [T::ZERO]
    }

    #[inline]
    fn law(&self, m: &Measurement<T>, s: &[T; 1], ds: &mut [T; 1]) -> Output<ForcePiParts<T>, T> {
        let e = m.z[0] - m.x[0];
        let p = self.kp * e;
        let ff = self.kv * m.x[1];
        let v = p + s[0] + ff;
        let (u, fl) = if v.abs() > self.u_limit {
            (v.clamp(-self.u_limit, self.u_limit), flags::SATURATED)
        } else {
            (v, 0)
        };
        // Conditional integration: the integral stops growing while the
        // limit holds the command and the error pushes further into it.
        let winding = fl != 0 && (e > T::ZERO) == (v > T::ZERO);
        ds[0] = if winding { T::ZERO } else { self.ki * e };
        Output {
            u,
            flags: fl,
            parts: ForcePiParts {
                p,
                i: s[0],
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

    fn design() -> Design {
        Design {
            model: NominalModel::new(ServoParams::paper(), Load::paper()),
            surface: SwitchingSurface::paper(),
            dt: 1e-3,
        }
    }

    /// With kv absent the feed-forward is the nominal model's Dm/K_q at
    /// p_L0: the paper's Ps = 7 MPa (SI in `ServoParams::paper`), so at
    /// p_L0 = Ps·(1 − 1/4) the root √((Ps − p_L0)/ρ) is half its value at
    /// rest, and kv doubles.
    #[test]
    fn designed_feedforward_is_the_flow_of_the_motion() {
        let d = design();
        let p = d.model.params;
        let at_rest = ForcePiConfig::default().build(&d).unwrap().gains().2;
        let hand = p.dm / (p.kv * p.cd * p.ag * (p.ps / p.rho).sqrt());
        assert!((at_rest - hand).abs() <= 1e-12 * hand);
        let c = ForcePiConfig {
            operating_pressure: 0.75 * p.ps,
            ..Default::default()
        };
        let loaded = c.build(&d).unwrap().gains().2;
        assert!((loaded - 2.0 * hand).abs() <= 1e-9 * hand);
    }

    /// The feed-forward's sign: a rod extending (ẏ > 0) must be fed flow
    /// into chamber A, a positive command, with the error zero.
    #[test]
    fn motion_is_fed_forward_with_its_sign_and_the_limit_holds_the_integral() {
        let c = ForcePiConfig {
            kp: 1e-4,
            ki: 1e-2,
            kv: Some(3.0),
            u_limit: Some(1.0),
            ..Default::default()
        };
        let law = c.build(&design()).unwrap();
        let m = Measurement {
            t: 0.0,
            x: [5e3, 0.1, 0.0],
            z: [5e3, 0.0, 0.0, 0.0],
        };
        let mut ds = [9.0];
        let out = law.law(&m, &[0.0], &mut ds);
        // e = 0: p = 0, ff = 3·0.1 = 0.3 V, İ = 0.
        assert_eq!((out.p, out.u, ds[0]), (0.0, 3.0 * 0.1, 0.0));
        // 20 kN short: v = 1e-4·2e4 + 0.5 + 0 = 2.5 V, clamped to 1 V, and
        // the positive error would wind I up further: İ = 0.
        let m = Measurement {
            t: 0.0,
            x: [0.0, 0.0, 0.0],
            z: [2e4, 0.0, 0.0, 0.0],
        };
        let out = law.law(&m, &[0.5], &mut ds);
        assert_eq!((out.u, out.u_unsat, ds[0]), (1.0, 2.5, 0.0));
        assert_eq!(out.flags, flags::SATURATED);
        // A wound-up I = 3.5 V with the force now 20 kN over: v = 1e-4·(−2e4)
        // + 3.5 = 1.5 V, still clamped to +1 V, but the negative error
        // unwinds it: İ = 1e-2·(−2e4) = −200 V/s.
        let m = Measurement {
            t: 0.0,
            x: [2e4, 0.0, 0.0],
            z: [0.0, 0.0, 0.0, 0.0],
        };
        let out = law.law(&m, &[3.5], &mut ds);
        assert_eq!((out.u, out.u_unsat, ds[0]), (1.0, 1.5, -200.0));
    }

    #[test]
    fn bad_gains_are_refused_by_name() {
        let d = design();
        let bad = |c: ForcePiConfig| c.build(&d).unwrap_err().name;
        let base = ForcePiConfig::default();
        assert_eq!(bad(ForcePiConfig { kp: -1.0, ..base }), "kp");
        assert_eq!(
            bad(ForcePiConfig {
                ki: f64::NAN,
                ..base
            }),
            "ki"
        );
        assert_eq!(
            bad(ForcePiConfig {
                kv: Some(-2.0),
                ..base
            }),
            "kv"
        );
        let ps = d.model.params.ps;
        assert_eq!(
            bad(ForcePiConfig {
                operating_pressure: ps,
                ..base
            }),
            "operating_pressure"
        );
        assert_eq!(
            bad(ForcePiConfig {
                u_limit: Some(0.0),
                ..base
            }),
            "u_limit"
        );
    }
}
