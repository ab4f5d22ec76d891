//! Adaptive robust control (ARC) with discontinuous projection, after
//! B. Yao, F. Bu, J. Reedy, G. T.-C. Chiu, "Adaptive robust motion control
//! of single-rod hydraulic actuators: theory and experiments", IEEE/ASME
//! Transactions on Mechatronics 5(1), 79–91, 2000, and B. Yao,
//! M. Tomizuka, "Adaptive robust control of SISO nonlinear systems in a
//! semi-strict feedback form", Automatica 33(5), 893–900, 1997.
//!
//! **The model, linear in the unknown parameters.** With `v = b̄(x, sgn u)·u`
//! (the nominal gain of (9) times the command, see [`crate::control`]),
//! the plant is `θ⃛ = −a1·x1 − a2·x2 − a3·x3 + ϑb·v − d(x) + Δ`, with the
//! unknown `ϑ = (a1, a2, a3, ϑb)`, `ϑb = b/b̄`, in the known box
//! `Ω = {ā_i − bound_a·|ā_i| ≤ a_i ≤ ā_i + bound_a·|ā_i|,
//! 1 − bound_b ≤ ϑb ≤ 1 + bound_b}` — the same information the paper's VSC
//! gets (α_i = bound_a·|ā_i|, β = bound_b·b̄); bound_b < 1 keeps ϑb > 0.
//!
//! **The error.** The paper's surface (10), `σ = ë + p1·ė + p2·e + p3·∫e`,
//! `e = θd − x1`, is the ARC's switching-function-like error. It has
//! relative degree one:
//!
//! ```text
//! σ̇ = N + aᵀx − ϑb·v − Δ,    N = θ⃛d + p1·ë + p2·ė + p3·e + d(x)   (known)
//! ```
//!
//! **The law** (all in `v`, then `u = v/b̄(x, sgn v)`; `ϑ̂` clamped to Ω):
//!
//! ```text
//! v_a  = (N + âᵀx)/ϑ̂b                          model compensation
//! v_s1 = k_s·σ/ϑb_min                          linear stabilising feedback
//! v_s2 = h²/(4ε)·σ/ϑb_min                      smooth robust term
//! h    = Σ ϑM_i·|ψ_i| + δ,   ψ = (x1, x2, x3, −v_a),   ϑM = ϑ_max − ϑ_min
//! ϑ̂̇   = Proj_ϑ̂(Γ·ψ·σ)                         discontinuous projection
//! Proj_ϑ̂i(•) = 0 if ϑ̂i ≥ ϑi_max and • > 0, or ϑ̂i ≤ ϑi_min and • < 0; • otherwise
//! ```
//!
//! With `ϑ̃ = ϑ̂ − ϑ`, `σ̇ = −ϑ̃ᵀψ − ϑb·(v_s1 + v_s2) − Δ`; then
//! `V = σ²/2` has `V̇ ≤ −k_s·σ² + ε` whatever ϑ̂ ∈ Ω (the robust term meets
//! Yao's two conditions `σ·[−ϑb·v_s2 − ϑ̃ᵀψ − Δ] ≤ ε` and `σ·v_s2 ≥ 0`, since
//! `−h²σ²/(4ε) + h|σ| ≤ ε`), and with `Δ = 0` the ARC Lyapunov function
//! `V + ϑ̃ᵀΓ⁻¹ϑ̃/2` has `V̇ ≤ −k_s·σ²` (the projection only removes terms
//! `ϑ̃ᵀΓ⁻¹(Proj(Γτ) − Γτ) ≤ 0`), so σ → 0 and, the surface being Hurwitz,
//! e → 0. The robust term is Yao–Tomizuka's smooth example
//! `u_s2 = −h²/(4ε)·z` (Automatica 1997, Remark on the choice of u_s2; also
//! the form of Yao et al. 2000), with the sign flipped because this
//! project's error is `θd − θ` where Yao's is `θ − θd`.
//!
//! **Adaptations of Yao's single-rod design**, stated:
//! - Yao's cylinder has four states (position, velocity, two chamber
//!   pressures) and is designed by two backstepping steps. Here the model
//!   is third order with θ̈ measured (Assumption A4) and every uncertain
//!   parameter enters the last equation, so the backstepping steps before
//!   the last are exact and linear: they collapse into one error of
//!   relative degree one, which is taken to be the paper's σ (with its
//!   integral term p3·∫e, so the structure is comparable to the paper's
//!   laws); the state carries ∫e.
//! - Yao's input gain (βe·kq times a known valve function of the pressures
//!   and sgn of the spool) is `ϑb·b̄(x, sgn u)`: the unknown constant
//!   factor ϑb multiplies the paper's known valve function b̄ of (9). As
//!   Yao computes the spool from the desired flow, the law computes `v`
//!   (which does not depend on b̄) and then `u = v/b̄(x, sgn v)`. The
//!   projection keeps ϑ̂b ≥ 1 − bound_b > 0.
//! - The load term d(x) of (9) is known (nominal) and compensated in N;
//!   Yao's lumped constant disturbance d_n is not estimated (its bound is
//!   not part of the paper's information); any remaining |Δ| ≤ δ is
//!   dominated by the robust term (`delta`, default 0).
//! - The linear gain divides by ϑb_min so the σ-loop rate is at least k_s
//!   whatever ϑb ∈ Ω.
//!
//! **Default gains, by rule.** `k_s = p1/3` (the mean of the surface's
//! error poles: σ settles as fast as the error on the surface; 30 s⁻¹ for
//! the paper's surface). `ε = h_ref²/(4·k_s)`: the robust term's gain
//! h²/(4ε) equals k_s when the state is at the paper's reference scales
//! X = (6.25°, 12.5π °/s, 25π² °/s²) (the RBF's normalising scales) and
//! |v_a| at `X_v = āᵀX`, so `h_ref = Σ ϑM_i·X_i + ϑMb·X_v + δ`; this keeps
//! the robust gain within what the 0.01 s sampled loop can carry.
//! `Γ_i = ϑM_i/(T_a·X_i·Z)` with `Z = 0.1·(X3 + p1·X2 + p2·X1 + p3·X0)`,
//! `X0 = X1²/X2` (the scales are those of one sinusoid, X0 its integral):
//! Z is σ when every error is at 10 % of its reference scale (the tracking
//! threshold of this project's tests), and with |ψ_i| = X_i, |σ| = Z an
//! estimate crosses its whole range in `T_a` (`adapt_time`, default 1 s).
//! The backstepping controller ([`super::backstepping`]) uses the same
//! rule with its own error. For the paper's servo and bounds
//! (bound_a = 1, bound_b = 0.5): h_ref = 28 927 rad/s³,
//! ε = 6.97·10⁶ rad²/s⁵, Z = 76.63 rad/s², Γ = (0.0957, 495.1, 1.030,
//! 1.353·10⁻⁶).

use super::{flags, Config, Controller, Design, Measurement, Output, Signal, Signals, Tunable};
use crate::error::{non_negative, positive, ParamError};
use crate::math::Real;
use crate::rbf::Rbf;
use crate::servo::NominalModel;
use crate::surface::SwitchingSurface;

/// `kind = "arc"`: the `[controller]` keys. Values left out are designed
/// by the rules of the module doc.
///
/// ```
/// use ehservo_core::control::arc::ArcConfig;
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// let arc = ArcConfig::default().build(&design)?;
/// // The estimates start at the nominal model: (∫e, â1, â2, â3, ϑ̂b) = (0, ā, 1).
/// let s = arc.initial_state();
/// let [a1, a2, a3] = design.model.coeffs.as_array();
/// assert_eq!(s, [0.0, a1, a2, a3, 1.0]);
/// // At rest, z = (0, 0.5, 0, 0): σ = 90·0.5 = 45, the model part
/// // v_a = p2·θ̇d = 1300, k_s = p1/3 = 30 so v_s1 = k_s·σ/ϑb_min = 30·45/0.5 = 2700,
/// // and the robust bound h = (ϑb_max − ϑb_min)·|v_a| = (1.5 − 0.5)·1300.
/// let m = Measurement { t: 0.0, x: [0.0; 3], z: [0.0, 0.5, 0.0, 0.0] };
/// let out = arc.law(&m, &s, &mut [0.0; 5]);
/// assert!((out.u_a * out.b_bar - 1300.0).abs() < 1e-9);
/// assert!((out.u_s1 * out.b_bar - 2700.0).abs() < 1e-9);
/// assert!((out.h - 1300.0).abs() < 1e-9);
/// // v_s2 = h²/(4ε)·σ/ϑb_min.
/// let (_, eps, _) = arc.gains();
/// let v_s2 = 1300.0 * 1300.0 / (4.0 * eps) * 45.0 / 0.5;
/// assert!((out.u_s2 * out.b_bar - v_s2).abs() <= 1e-12 * v_s2);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct ArcConfig {
    /// Bound on Δa_i as a fraction of |ā_i| (Ω's a-box). Default 1.
    pub bound_a: f64,
    /// Bound on Δb as a fraction of b̄, < 1 (Ω's ϑb-box). Default 0.5.
    pub bound_b: f64,
    /// k_s, the linear feedback's rate (s⁻¹); default p1/3.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub k_s: Option<f64>,
    /// ε of the robust term (rad²/s⁵); default h_ref²/(4·k_s).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub eps: Option<f64>,
    /// Γ, the diagonal adaptation gain for (a1, a2, a3, ϑb) (units
    /// ϑ_i²·s⁴/rad²); default ϑM_i/(T_a·X_i·Z).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub gamma: Option<[f64; 4]>,
    /// T_a, the adaptation time of the Γ rule (s). Default 1.
    pub adapt_time: f64,
    /// δ, a bound on the unmodelled |Δ| the robust term dominates (rad/s³).
    /// Default 0.
    pub delta: f64,
}

impl Default for ArcConfig {
    fn default() -> Self {
        Self {
            bound_a: 1.0,
            bound_b: 0.5,
            k_s: None,
            eps: None,
            gamma: None,
            adapt_time: 1.0,
            delta: 0.0,
        }
    }
}

/// The ARC's parts.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ArcParts<T = f64> {
    /// Model compensation u_a = v_a/b̄ (V).
    pub u_a: T,
    /// Linear feedback u_s1 = v_s1/b̄ (V).
    pub u_s1: T,
    /// Robust term u_s2 = v_s2/b̄ (V).
    pub u_s2: T,
    /// σ of (10) (rad/s²).
    pub sigma: T,
    /// Tracking error θd − x1 (rad).
    pub e: T,
    /// h, the robust term's bound (rad/s³).
    pub h: T,
    /// â1 in use (s⁻³).
    pub a1_hat: T,
    /// â2 in use (s⁻²).
    pub a2_hat: T,
    /// â3 in use (s⁻¹).
    pub a3_hat: T,
    /// ϑ̂b = b̂/b̄ in use.
    pub b_ratio_hat: T,
    /// Nominal gain b̄(x, sgn v) (1/(V·s³)).
    pub b_bar: T,
}

impl<T: Real> Signals for ArcParts<T> {
    const SIGNALS: &'static [Signal] = &[
        Signal::new("u_a", "u_a_V", "V", "model compensation (N + âᵀx)/(ϑ̂b·b̄)"),
        Signal::new("u_s1", "u_s1_V", "V", "linear feedback k_s·σ/(ϑb_min·b̄)"),
        Signal::new("u_s2", "u_s2_V", "V", "robust term h²σ/(4ε·ϑb_min·b̄)"),
        Signal::new(
            "sigma",
            "sigma_rad_s2",
            "rad/s²",
            "switching function σ (10)",
        ),
        Signal::new("h", "h_rad_s3", "rad/s³", "robust bound h"),
        Signal::new("a1_hat", "a1_hat_1_s3", "1/s³", "estimate â1"),
        Signal::new("a2_hat", "a2_hat_1_s2", "1/s²", "estimate â2"),
        Signal::new("a3_hat", "a3_hat_1_s", "1/s", "estimate â3"),
        Signal::new("b_ratio_hat", "b_ratio_hat", "", "estimate ϑ̂b = b̂/b̄"),
        Signal::new(
            "b_bar",
            "b_bar_V_s3",
            "1/(V·s³)",
            "nominal gain b̄(t) of (9)",
        ),
        Signal::new("e", "", "rad", "tracking error θd − x1"),
    ];
    fn write(&self, out: &mut [f64]) {
        let v = [
            self.u_a,
            self.u_s1,
            self.u_s2,
            self.sigma,
            self.h,
            self.a1_hat,
            self.a2_hat,
            self.a3_hat,
            self.b_ratio_hat,
            self.b_bar,
            self.e,
        ];
        for (o, v) in out.iter_mut().zip(v) {
            *o = v.to_f64();
        }
    }
}

/// The ARC controller, built.
/// Built by [`ArcConfig`] (`kind = "arc"`), whose example evaluates one
/// step of the law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arc<T: Real = f64> {
    model: NominalModel<T>,
    surface: SwitchingSurface<T>,
    k_s: T,
    eps: T,
    gamma: [T; 4],
    delta: T,
    lo: [T; 4],
    hi: [T; 4],
    b_floor: T,
}

/// The reference scales X of the default rules (module doc): the paper's
/// RBF normalising scales, and X_v = āᵀX.
fn reference_scales(a: [f64; 3]) -> [f64; 4] {
    let x = Rbf::paper_scale();
    [x[0], x[1], x[2], a[0] * x[0] + a[1] * x[1] + a[2] * x[2]]
}

impl<T: Real> Arc<T> {
    /// The same controller in another float type (model and surface
    /// recomputed in `U`, every gain and bound rounded to `U`).
    pub fn cast<U: Real>(&self) -> Arc<U> {
        let c = |v: T| U::of(v.to_f64());
        Arc {
            model: self.model.cast(),
            surface: self.surface.cast(),
            k_s: c(self.k_s),
            eps: c(self.eps),
            gamma: self.gamma.map(c),
            delta: c(self.delta),
            lo: self.lo.map(c),
            hi: self.hi.map(c),
            b_floor: c(self.b_floor),
        }
    }

    /// The gains `(k_s, ε, Γ)` in use.
    pub fn gains(&self) -> (T, T, [T; 4]) {
        (self.k_s, self.eps, self.gamma)
    }

    /// The box Ω: `(ϑ_min, ϑ_max)` for (a1, a2, a3, ϑb).
    pub fn bounds(&self) -> ([T; 4], [T; 4]) {
        (self.lo, self.hi)
    }
}

impl Config for ArcConfig {
    const KIND: &'static str = "arc";
    const USES_SURFACE: bool = true;
    /// The feedback rate, the robust term's ε and the adaptation time of
    /// the Γ rule.
    const TUNABLE: &'static [Tunable] = &[
        Tunable::log("k_s", 1.0, 1e3),
        Tunable::log("eps", 1e-3, 1e6),
        Tunable::log("adapt_time", 0.01, 100.0),
    ];
    type Controller = Arc;
    type Law<F: Real> = Arc<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<Arc<F>, ParamError> {
        Ok(self.build(d)?.cast())
    }

    /// k_s, ε and Γ as the rules give them (module doc), when left out.
    fn designed(&self, d: &Design) -> Option<Result<Self, ParamError>> {
        Some(self.build(d).map(|c| {
            let (k_s, eps, gamma) = c.gains();
            Self {
                k_s: Some(k_s),
                eps: Some(eps),
                gamma: Some(gamma),
                ..*self
            }
        }))
    }

    fn build(&self, d: &Design) -> Result<Arc, ParamError> {
        non_negative("bound_a", self.bound_a)?;
        non_negative("bound_b", self.bound_b)?;
        if self.bound_b >= 1.0 {
            return Err(ParamError::new(
                "bound_b",
                "must be < 1: the input gain's estimate must stay positive",
                self.bound_b,
            ));
        }
        non_negative("delta", self.delta)?;
        positive("adapt_time", self.adapt_time)?;
        let a = d.model.coeffs.as_array();
        let mut lo = [0.0; 4];
        let mut hi = [0.0; 4];
        for i in 0..3 {
            lo[i] = a[i] - self.bound_a * a[i].abs();
            hi[i] = a[i] + self.bound_a * a[i].abs();
        }
        lo[3] = 1.0 - self.bound_b;
        hi[3] = 1.0 + self.bound_b;
        let k_s = match self.k_s {
            Some(k) => positive("k_s", k)?,
            None => d.surface.p()[0] / 3.0,
        };
        let x = reference_scales(a);
        let h_ref = (0..4).map(|i| (hi[i] - lo[i]) * x[i]).sum::<f64>() + self.delta;
        let eps = match self.eps {
            Some(e) => positive("eps", e)?,
            None if h_ref > 0.0 => h_ref * h_ref / (4.0 * k_s),
            None => {
                return Err(ParamError::new(
                    "eps",
                    "cannot be designed with bound_a = bound_b = delta = 0: give it",
                    0.0,
                ))
            }
        };
        let gamma = match self.gamma {
            Some(g) => {
                for v in g {
                    non_negative("gamma", v)?;
                }
                g
            }
            None => {
                let [p1, p2, p3] = d.surface.p();
                let x0 = x[0] * x[0] / x[1];
                let z = 0.1 * (x[2] + p1 * x[1] + p2 * x[0] + p3 * x0);
                core::array::from_fn(|i| (hi[i] - lo[i]) / (self.adapt_time * x[i] * z))
            }
        };
        Ok(Arc {
            model: d.model,
            surface: d.surface,
            k_s,
            eps,
            gamma,
            delta: self.delta,
            lo,
            hi,
            b_floor: 1e-3 * d.model.b_at_rest(),
        })
    }
}

impl<T: Real> Controller<T> for Arc<T> {
    /// (∫e, â1, â2, â3, ϑ̂b): ∫e (rad·s) and the raw estimates.
    type State = [T; 5];
    type Parts = ArcParts<T>;

    /// ∫e = 0 and ϑ̂(0) = (ā1, ā2, ā3, 1), the nominal model.
    fn initial_state(&self) -> [T; 5] {
        let a = self.model.coeffs.as_array();
        [T::ZERO, a[0], a[1], a[2], T::ONE]
    }

    #[inline]
    fn law(&self, m: &Measurement<T>, s: &[T; 5], ds: &mut [T; 5]) -> Output<ArcParts<T>, T> {
        let (x, z) = (&m.x, &m.z);
        let st = self.surface.evaluate(x, z, s[0]);
        let [p1, p2, p3] = self.surface.p();
        // The estimates in use: the raw state clamped to Ω (the projection
        // keeps it there in continuous time; a sampled step may overshoot
        // by one increment, which the clamp makes harmless).
        let th: [T; 4] = core::array::from_fn(|i| s[i + 1].clamp(self.lo[i], self.hi[i]));
        let n = z[3] + p1 * st.e_ddot + p2 * st.e_dot + p3 * st.e + self.model.d(x);
        let v_a = (n + th[0] * x[0] + th[1] * x[1] + th[2] * x[2]) / th[3];
        let psi = [x[0], x[1], x[2], -v_a];
        let mut h = self.delta;
        for (i, p) in psi.iter().enumerate() {
            h += (self.hi[i] - self.lo[i]) * p.abs();
        }
        let b_min = self.lo[3];
        let v_s1 = self.k_s * st.sigma / b_min;
        let v_s2 = h * h / (T::of(4.0) * self.eps) * st.sigma / b_min;
        let v = v_a + v_s1 + v_s2;
        let (b_bar, clamped) = self.model.gain_for(x, v, self.b_floor);
        let fl = if clamped {
            flags::VALVE_ROOT_CLAMPED
        } else {
            0
        };
        ds[0] = st.e;
        for i in 0..4 {
            let rate = self.gamma[i] * psi[i] * st.sigma;
            let raw = s[i + 1];
            ds[i + 1] =
                if (raw >= self.hi[i] && rate > T::ZERO) || (raw <= self.lo[i] && rate < T::ZERO) {
                    T::ZERO
                } else {
                    rate
                };
        }
        Output {
            u: v / b_bar,
            flags: fl,
            parts: ArcParts {
                u_a: v_a / b_bar,
                u_s1: v_s1 / b_bar,
                u_s2: v_s2 / b_bar,
                sigma: st.sigma,
                e: st.e,
                h,
                a1_hat: th[0],
                a2_hat: th[1],
                a3_hat: th[2],
                b_ratio_hat: th[3],
                b_bar,
            },
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact zeros of the projection are the point
mod tests {
    use super::*;
    use crate::servo::{Coefficients, Load, ServoParams};

    /// A design with simple numbers: ā = (1, 2, 4), no load (d = 0), the
    /// surface p = (3, 2, 1) (Routh: 3·2 > 1).
    fn simple() -> Design {
        let mut model = NominalModel::new(ServoParams::paper(), Load::none());
        model.coeffs = Coefficients {
            a1: 1.0,
            a2: 2.0,
            a3: 4.0,
        };
        Design {
            model,
            surface: SwitchingSurface::try_new([3.0, 2.0, 1.0]).unwrap(),
            dt: 0.01,
        }
    }

    /// The designed values are the rules' and build the same law: on the
    /// surface p = (3, 2, 1), k_s = p1/3 = 1, and ε = h_ref²/(4·k_s).
    #[test]
    fn designed_fills_the_rules_and_builds_the_same_law() {
        let d = simple();
        let cfg = ArcConfig::default();
        let got = cfg.designed(&d).unwrap().unwrap();
        assert_eq!(got.k_s, Some(1.0));
        let built = cfg.build(&d).unwrap();
        assert_eq!(got.build(&d).unwrap(), built);
        assert!(got.eps.unwrap() > 0.0 && got.gamma.unwrap().iter().all(|g| *g > 0.0));
    }

    fn cfg() -> ArcConfig {
        ArcConfig {
            bound_a: 0.5,
            bound_b: 0.5,
            k_s: Some(2.0),
            eps: Some(0.5),
            gamma: Some([1.0; 4]),
            adapt_time: 1.0,
            delta: 0.1,
        }
    }

    /// x = (0.1, 0.2, 0.3), z = (0, 0.5, 0, 1), ∫e = 0.5,
    /// ϑ̂ = (1, 2, 4, 0.8); bounds (bound_a = bound_b = 0.5):
    /// a ∈ [0.5, 1.5]×[1, 3]×[2, 6], ϑb ∈ [0.5, 1.5], ϑM = (1, 2, 4, 1).
    /// e = −0.1, ė = 0.3, ë = −0.3;
    /// σ = −0.3 + 3·0.3 + 2·(−0.1) + 1·0.5 = 0.9;
    /// N = 1 + 3·(−0.3) + 2·0.3 + 1·(−0.1) + 0 = 0.6;
    /// v_a = (0.6 + 0.1 + 0.4 + 1.2)/0.8 = 2.875;
    /// v_s1 = 2·0.9/0.5 = 3.6;
    /// h = 0.1 + 0.4 + 1.2 + 2.875 + δ 0.1 = 4.675;
    /// v_s2 = 4.675²·0.9/(4·0.5·0.5) = 21.855625·0.9 = 19.6700625;
    /// ϑ̂̇ = Γψσ, ψ = (0.1, 0.2, 0.3, −2.875): (0.09, 0.18, 0.27, −2.5875);
    /// d∫e/dt = e = −0.1.
    #[test]
    fn law_by_hand() {
        let d = simple();
        let c = cfg().build(&d).unwrap();
        let m = Measurement {
            t: 0.0,
            x: [0.1, 0.2, 0.3],
            z: [0.0, 0.5, 0.0, 1.0],
        };
        let mut ds = [0.0; 5];
        let o = c.law(&m, &[0.5, 1.0, 2.0, 4.0, 0.8], &mut ds);
        let close =
            |a: f64, b: f64| assert!((a - b).abs() < 1e-12 * b.abs().max(1.0), "{a} vs {b}");
        close(o.sigma, 0.9);
        close(o.h, 4.675);
        let bb = o.b_bar;
        // b̄ is the valve's gain in the direction of v (> 0 here).
        close(bb, d.model.gain_for(&m.x, 1.0, 0.0).0);
        close(o.u_a * bb, 2.875);
        close(o.u_s1 * bb, 3.6);
        close(o.u_s2 * bb, 19.6700625);
        close(o.u * bb, 26.1450625);
        let want = [-0.1, 0.09, 0.18, 0.27, -2.5875];
        for (g, w) in ds.iter().zip(want) {
            close(*g, w);
        }
    }

    /// The projection: an estimate at its upper bound pushed outwards
    /// stops (â1 = 1.5 with rate +0.09), one at its lower bound pushed
    /// outwards stops (ϑ̂b = 0.5 with rate −Γψ4σ < 0: v_a > 0, σ > 0), one
    /// at a bound pushed inwards moves (â2 = 1 with rate +0.18); a raw
    /// state beyond a bound is used clamped (â3 = 7 → 6).
    #[test]
    fn projection_stops_at_the_bounds() {
        let c = cfg().build(&simple()).unwrap();
        let m = Measurement {
            t: 0.0,
            x: [0.1, 0.2, 0.3],
            z: [0.0, 0.5, 0.0, 1.0],
        };
        let mut ds = [0.0; 5];
        let o = c.law(&m, &[0.5, 1.5, 1.0, 7.0, 0.5], &mut ds);
        assert!(o.sigma > 0.0);
        assert_eq!(ds[1], 0.0);
        assert!((ds[2] - 0.18).abs() < 1e-12);
        assert_eq!(ds[3], 0.0);
        assert_eq!(ds[4], 0.0);
        assert_eq!(
            (o.a1_hat, o.a2_hat, o.a3_hat, o.b_ratio_hat),
            (1.5, 1.0, 6.0, 0.5)
        );
        // Lower bounds of a, pushed down: z = 0, ∫e = 0 gives
        // σ = −0.3 + 3·(−0.2) + 2·(−0.1) = −1.1 < 0.
        let m2 = Measurement { z: [0.0; 4], ..m };
        let o = c.law(&m2, &[0.0, 0.5, 1.0, 2.0, 1.5], &mut ds);
        assert!(o.sigma < 0.0);
        assert_eq!(&ds[1..4], &[0.0; 3]);
    }

    /// Forward-Euler steps of the estimates under a σ that keeps pushing
    /// them outwards (a constant error): each estimate in use stays in Ω
    /// at every step and each raw state ends within one step's increment
    /// of its bound.
    #[test]
    fn projection_keeps_estimates_in_their_bounds() {
        let c = cfg().build(&simple()).unwrap();
        let (lo, hi) = c.bounds();
        // σ = 0.9 > 0 (a pushed up, ϑb down), then σ = −0.6 < 0 (the reverse).
        for z in [[0.0, 0.5, 0.0, 1.0], [0.0, 0.0, 0.0, -1.0]] {
            let m = Measurement {
                t: 0.0,
                x: [0.1, 0.2, 0.3],
                z,
            };
            let mut s = c.initial_state();
            s[0] = 0.5;
            let mut ds = [0.0; 5];
            let mut step = [0.0f64; 5];
            let dt = 0.05;
            for _ in 0..20_000 {
                let o = c.law(&m, &s, &mut ds);
                for (i, v) in [o.a1_hat, o.a2_hat, o.a3_hat, o.b_ratio_hat]
                    .iter()
                    .enumerate()
                {
                    assert!(lo[i] <= *v && *v <= hi[i], "{i}: {v}");
                }
                s[0] = 0.5; // hold ∫e: only the estimates move
                for i in 1..5 {
                    s[i] += dt * ds[i];
                    // Beyond a bound by at most the step that crossed it.
                    step[i] = step[i].max(dt * ds[i].abs());
                    assert!(
                        s[i] <= hi[i - 1] + step[i] && s[i] >= lo[i - 1] - step[i],
                        "{i}: {} {:?}",
                        s[i],
                        ds
                    );
                }
            }
            // Saturated: every estimate sits at (or one step past) a bound.
            let o = c.law(&m, &s, &mut ds);
            for (i, v) in [o.a1_hat, o.a2_hat, o.a3_hat, o.b_ratio_hat]
                .iter()
                .enumerate()
            {
                assert!(*v == lo[i] || *v == hi[i], "{i}: {v} not at a bound");
            }
        }
    }

    /// The default rules (module doc) for the paper's servo: k_s = 30,
    /// h_ref = Σ 2ā_i·X_i + 1·āᵀX = 3·āᵀX (every a_i range is 2|ā_i|,
    /// ϑb's is 1), with āᵀX = 0.39982·0.109083 + 13000.2711·0.685389 + 169.98043·4.306355
    /// = 0.04361 + 8910.24 + 732.00 = 9642.28; h_ref = 28926.8;
    /// ε = h_ref²/120 = 6.973·10⁶;
    /// X0 = 0.109083²/0.685389 = 0.017361,
    /// Z = 0.1·(4.306355 + 90·0.685389 + 2600·0.109083 + 24000·0.017361)
    /// = 0.1·(4.3064 + 61.685 + 283.62 + 416.66) = 76.628.
    #[test]
    fn default_rules_for_the_paper() {
        let d = Design {
            model: NominalModel::new(ServoParams::paper(), Load::paper()),
            surface: SwitchingSurface::paper(),
            dt: 0.01,
        };
        let c = ArcConfig::default().build(&d).unwrap();
        let (k, eps, g) = c.gains();
        assert_eq!(k, 30.0);
        assert!((eps / 6.973e6 - 1.0).abs() < 1e-3, "{eps}");
        // Γ2 = 2·13000.27/(0.685389·76.628) = 26000.54/52.520 = 495.06.
        assert!((g[1] / 495.06 - 1.0).abs() < 1e-3, "{g:?}");
        // Γ4 = 1/(9642.28·76.628) = 1.3534e-6.
        assert!((g[3] / 1.3534e-6 - 1.0).abs() < 1e-3, "{g:?}");
        let bad = |c: ArcConfig| c.build(&d).unwrap_err().name;
        assert_eq!(
            bad(ArcConfig {
                bound_b: 1.0,
                ..ArcConfig::default()
            }),
            "bound_b"
        );
        assert_eq!(
            bad(ArcConfig {
                k_s: Some(0.0),
                ..ArcConfig::default()
            }),
            "k_s"
        );
        assert_eq!(
            bad(ArcConfig {
                gamma: Some([1.0, -1.0, 1.0, 1.0]),
                ..ArcConfig::default()
            }),
            "gamma"
        );
    }
}
