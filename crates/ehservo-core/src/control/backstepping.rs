//! Adaptive backstepping, the tuning-functions design of M. Krstić,
//! I. Kanellakopoulos, P. Kokotović, *Nonlinear and Adaptive Control
//! Design*, Wiley 1995 (ch. 4: tuning functions; the unknown
//! high-frequency gain estimated through its reciprocal).
//!
//! **The system.** With `v = b̄(x, sgn u)·u` (the nominal gain of (9) times
//! the command, see [`crate::control`]) the plant is in parametric
//! strict-feedback form:
//!
//! ```text
//! x1' = x2,   x2' = x3,   x3' = φ(x)ᵀϑ − d(x) + ϑb·v,
//! φ = (−x1, −x2, −x3),   ϑ = (a1, a2, a3) unknown,   ϑb = b/b̄ > 0 unknown
//! ```
//!
//! d(x), the paper's load term, is known (nominal) and cancelled. The sign
//! of ϑb is known (positive); ϑb itself is handled as in KKK's design for
//! an unknown high-frequency gain: its reciprocal `ϱ = 1/ϑb` is estimated
//! and `v = ϱ̂·ᾱ3`.
//!
//! **The design** (reference y_r = θd with derivatives from z):
//!
//! ```text
//! z1 = x1 − θd                        α1 = −c1·z1 + θ̇d
//! z2 = x2 − α1                        α̇1 = −c1·(x2 − θ̇d) + θ̈d
//! α2 = −z1 − c2·z2 + α̇1              z3 = x3 − α2
//! α̈1 = −c1·(x3 − θ̈d) + θ⃛d            α̇2 = −(x2 − θ̇d) − c2·(x3 − α̇1) + α̈1
//! ᾱ3 = −z2 − c3·z3 − φᵀϑ̂ + d(x) + α̇2
//! v  = ϱ̂·ᾱ3,   u = v/b̄(x, sgn v)
//! τ3 = φ·z3   (τ1 = τ2 = 0: ϑ enters only the last equation)
//! ϑ̂̇ = Γ·τ3,   ϱ̂̇ = −γϱ·sgn(ϑb)·ᾱ3·z3
//! ```
//!
//! The derivatives α̇1, α̇2 are exact here: x3 is measured (Assumption A4)
//! and the α's do not depend on ϑ̂ (ϑ appears only in x3'), so the
//! tuning functions reduce to τ3 = φ·z3 and the ∂α/∂ϑ̂ terms of the
//! general design vanish. With `ϑ̃ = ϑ − ϑ̂`, `ϱ̃ = ϱ − ϱ̂`,
//!
//! ```text
//! z1' = −c1z1 + z2,   z2' = −z1 − c2z2 + z3,   z3' = −z2 − c3z3 + φᵀϑ̃ − ϑb·ϱ̃·ᾱ3
//! V = Σ zi²/2 + ϑ̃ᵀΓ⁻¹ϑ̃/2 + ϑb·ϱ̃²/(2γϱ),   V̇ = −c1z1² − c2z2² − c3z3²
//! ```
//!
//! (the structure of KKK's tuning-functions theorem). No nonlinear damping
//! κ is used.
//!
//! **Projection (`projection`, default false).** The law above is KKK's
//! pure design. With `projection = true` the estimates are kept in the box
//! the paper's VSC and the ARC are given, `ā_i ± bound_a·|ā_i|` and
//! `ϱ ∈ [1/(1 + bound_b), 1/(1 − bound_b)]`, by the same discontinuous
//! projection as [`super::arc`] (the rate of an estimate at a bound and
//! pushed outwards is zeroed; the law uses the estimate clamped to its
//! box). Projection only adds terms `ϑ̃ᵀΓ⁻¹(Γτ − Proj(Γτ)) ≤ 0` to V̇.
//!
//! **Sampling.** The design is continuous-time. On the Fig. 2 case at a
//! 1 ms continuous step it tracks (e_max ≈ 0.004°); in the paper's 0.01 s
//! sampled loop the default gains diverge (the estimates run to the
//! corners of the box with projection, â3 runs negative without), and no
//! adaptation time tried (1–10 s) tracks better than ≈ 0.9°: the example
//! scenario `scenarios/league/backstepping-fig2.toml` therefore runs at
//! 1 ms.
//!
//! **Default gains, by rule.** `c1 = c2 = c3 = 30 s⁻¹`, the mean of the
//! paper's surface poles (−20, −30, −40): with exact parameters
//! `z' = A·z`, `det(sI − A) = (s + c)((s + c)² + 2)`, poles −30 and
//! −30 ± j1.41, as fast as the paper's error dynamics on σ = 0.
//! `Γ_i = ϑM_i/(T_a·X_i·Z)`, `γϱ = ϱM/(T_a·X_v·Z)`: with |φ_i| at the
//! paper's reference scales X = (6.25°, 12.5π °/s, 25π² °/s²) (the RBF's
//! normalising scales), |ᾱ3| at `X_v = āᵀX` and |z3| at `Z` (`error_scale`,
//! default `0.1·(X3 + (c1 + c2)·X2 + (1 + c1·c2)·X1)`, the |z3| of errors
//! at 10 % of their reference scales, since
//! `z3 = −ë − (c1 + c2)·ė − (1 + c1·c2)·e` with e = θd − θ; the ARC's rule
//! with its σ), an estimate crosses the range of its bounds
//! (ϑM_i = 2·bound_a·|ā_i|, ϱM = 1/(1 − bound_b) − 1/(1 + bound_b)) in
//! `T_a` (`adapt_time`, default 1 s). For the paper's servo:
//! Z = 14.371 rad/s², Γ = (0.510, 2640, 5.49), γϱ = 9.62·10⁻⁶.

use super::{flags, Config, Controller, Design, Measurement, Output, Signal, Signals, Tunable};
use crate::error::{non_negative, positive, ParamError};
use crate::math::Real;
use crate::rbf::Rbf;
use crate::servo::NominalModel;

/// `kind = "backstepping"`: the `[controller]` keys. Values left out are
/// designed by the rules of the module doc.
///
/// ```
/// use ehservo_core::control::backstepping::BacksteppingConfig;
/// use ehservo_core::prelude::*;
///
/// // No load, so d(x) = 0.
/// let model = NominalModel::new(ServoParams::paper(), Load::none());
/// let design = Design { model, surface: SwitchingSurface::paper(), dt: 0.01 };
/// let bs = BacksteppingConfig::default().build(&design)?; // c1 = c2 = c3 = 30
/// // θ = 0.01 at rest on the reference θd ≡ 0, estimates at the nominal model:
/// // z1 = 0.01, α1 = −c1·z1 = −0.3, z2 = 0 − α1 = 0.3, α2 = −z1 − c2·z2 = −9.01,
/// // z3 = 0 − α2 = 9.01, the reference and the state's derivatives being 0;
/// // ᾱ3 = −z2 − c3·z3 + â1·θ = −0.3 − 270.3 + 0.01·ā1, and b̄·u = ϱ̂·ᾱ3 with ϱ̂ = 1.
/// let m = Measurement { t: 0.0, x: [0.01, 0.0, 0.0], z: [0.0; 4] };
/// let out = bs.law(&m, &bs.initial_state(), &mut [0.0; 4]);
/// let alpha3 = -0.3 - 270.3 + 0.01 * model.coeffs.a1;
/// assert!((out.z2 - 0.3).abs() < 1e-12 && (out.z3 - 9.01).abs() < 1e-12);
/// assert!((out.alpha3 - alpha3).abs() < 1e-9);
/// assert!((out.u * out.b_bar - alpha3).abs() < 1e-9);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct BacksteppingConfig {
    /// c1 (s⁻¹). Default 30.
    pub c1: f64,
    /// c2 (s⁻¹). Default 30.
    pub c2: f64,
    /// c3 (s⁻¹). Default 30.
    pub c3: f64,
    /// Γ, the diagonal adaptation gain for (a1, a2, a3) (units
    /// ϑ_i²·s⁴/rad²); default ϑM_i/(T_a·X_i·Z).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub gamma: Option<[f64; 3]>,
    /// γϱ, the adaptation gain of ϱ̂ = 1/ϑ̂b (s⁴/rad²); default
    /// ϱM/(T_a·X_v·Z).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub gamma_rho: Option<f64>,
    /// Bound on Δa_i as a fraction of |ā_i|, for the Γ rule and the
    /// projection. Default 1.
    pub bound_a: f64,
    /// Bound on Δb as a fraction of b̄, < 1, for the γϱ rule and the
    /// projection. Default 0.5.
    pub bound_b: f64,
    /// T_a, the adaptation time of the Γ rule (s). Default 1.
    pub adapt_time: f64,
    /// Z, the z3 scale of the Γ rule (rad/s²); default
    /// 0.1·(X3 + (c1 + c2)·X2 + (1 + c1·c2)·X1).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub error_scale: Option<f64>,
    /// Keep the estimates in the bound_a/bound_b box by discontinuous
    /// projection. Default false (KKK's pure law).
    pub projection: bool,
}

impl Default for BacksteppingConfig {
    fn default() -> Self {
        Self {
            c1: 30.0,
            c2: 30.0,
            c3: 30.0,
            gamma: None,
            gamma_rho: None,
            bound_a: 1.0,
            bound_b: 0.5,
            adapt_time: 1.0,
            error_scale: None,
            projection: false,
        }
    }
}

/// The adaptive backstepping's parts.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BacksteppingParts<T = f64> {
    /// z1 = x1 − θd (rad).
    pub z1: T,
    /// z2 = x2 − α1 (rad/s).
    pub z2: T,
    /// z3 = x3 − α2 (rad/s²).
    pub z3: T,
    /// α1 (rad/s).
    pub alpha1: T,
    /// α2 (rad/s²).
    pub alpha2: T,
    /// ᾱ3, the acceleration rate asked of ϑb·v (rad/s³).
    pub alpha3: T,
    /// â1 (s⁻³).
    pub a1_hat: T,
    /// â2 (s⁻²).
    pub a2_hat: T,
    /// â3 (s⁻¹).
    pub a3_hat: T,
    /// ϱ̂, the estimate of b̄/b.
    pub rho_hat: T,
    /// Nominal gain b̄(x, sgn v) (1/(V·s³)).
    pub b_bar: T,
}

impl<T: Real> Signals for BacksteppingParts<T> {
    const SIGNALS: &'static [Signal] = &[
        Signal::new("z1", "z1_rad", "rad", "z1 = θ − θd"),
        Signal::new("z2", "z2_rad_s", "rad/s", "z2 = θ̇ − α1"),
        Signal::new("z3", "z3_rad_s2", "rad/s²", "z3 = θ̈ − α2"),
        Signal::new("alpha1", "alpha1_rad_s", "rad/s", "virtual control α1"),
        Signal::new("alpha2", "alpha2_rad_s2", "rad/s²", "virtual control α2"),
        Signal::new("alpha3", "alpha3_rad_s3", "rad/s³", "ᾱ3 (v = ϱ̂·ᾱ3)"),
        Signal::new("a1_hat", "a1_hat_1_s3", "1/s³", "estimate â1"),
        Signal::new("a2_hat", "a2_hat_1_s2", "1/s²", "estimate â2"),
        Signal::new("a3_hat", "a3_hat_1_s", "1/s", "estimate â3"),
        Signal::new("rho_hat", "rho_hat", "", "estimate ϱ̂ of b̄/b"),
        Signal::new(
            "b_bar",
            "b_bar_V_s3",
            "1/(V·s³)",
            "nominal gain b̄(t) of (9)",
        ),
    ];
    fn write(&self, out: &mut [f64]) {
        let v = [
            self.z1,
            self.z2,
            self.z3,
            self.alpha1,
            self.alpha2,
            self.alpha3,
            self.a1_hat,
            self.a2_hat,
            self.a3_hat,
            self.rho_hat,
            self.b_bar,
        ];
        for (o, v) in out.iter_mut().zip(v) {
            *o = v.to_f64();
        }
    }
}

/// The adaptive backstepping controller, built.
/// Built by [`BacksteppingConfig`] (`kind = "backstepping"`), whose example evaluates one
/// step of the law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Backstepping<T: Real = f64> {
    model: NominalModel<T>,
    c: [T; 3],
    gamma: [T; 3],
    gamma_rho: T,
    lo: [T; 4],
    hi: [T; 4],
    b_floor: T,
}

impl<T: Real> Backstepping<T> {
    /// The same controller in another float type (model recomputed in `U`,
    /// every gain and bound rounded to `U`).
    pub fn cast<U: Real>(&self) -> Backstepping<U> {
        let c = |v: T| U::of(v.to_f64());
        Backstepping {
            model: self.model.cast(),
            c: self.c.map(c),
            gamma: self.gamma.map(c),
            gamma_rho: c(self.gamma_rho),
            lo: self.lo.map(c),
            hi: self.hi.map(c),
            b_floor: c(self.b_floor),
        }
    }

    /// The projection's box `(min, max)` for (a1, a2, a3, ϱ) (±∞ without
    /// projection).
    pub fn bounds(&self) -> ([T; 4], [T; 4]) {
        (self.lo, self.hi)
    }

    /// The gains `(c, Γ, γϱ)` in use.
    pub fn gains(&self) -> ([T; 3], [T; 3], T) {
        (self.c, self.gamma, self.gamma_rho)
    }
}

impl BacksteppingConfig {
    /// Z's rule, `0.1·(X3 + (c1 + c2)·X2 + (1 + c1·c2)·X1)` at the paper's
    /// scales X.
    fn z_rule(&self) -> f64 {
        let x = Rbf::paper_scale();
        let (c1, c2) = (self.c1, self.c2);
        0.1 * (x[2] + (c1 + c2) * x[1] + (1.0 + c1 * c2) * x[0])
    }
}

impl Config for BacksteppingConfig {
    const KIND: &'static str = "backstepping";
    const USES_SURFACE: bool = false;
    /// The three error gains and the adaptation time of the Γ rule.
    const TUNABLE: &'static [Tunable] = &[
        Tunable::log("c1", 1.0, 300.0),
        Tunable::log("c2", 1.0, 300.0),
        Tunable::log("c3", 1.0, 300.0),
        Tunable::log("adapt_time", 0.01, 100.0),
    ];
    type Controller = Backstepping;
    type Law<F: Real> = Backstepping<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<Backstepping<F>, ParamError> {
        Ok(self.build(d)?.cast())
    }

    /// Γ, γϱ and the z3 scale Z of their rules (module doc), when left out.
    fn designed(&self, d: &Design) -> Option<Result<Self, ParamError>> {
        Some(self.build(d).map(|c| {
            let (_, gamma, gamma_rho) = c.gains();
            Self {
                gamma: Some(gamma),
                gamma_rho: Some(gamma_rho),
                error_scale: Some(self.error_scale.unwrap_or_else(|| self.z_rule())),
                ..*self
            }
        }))
    }

    fn build(&self, d: &Design) -> Result<Backstepping, ParamError> {
        let c1 = positive("c1", self.c1)?;
        let c2 = positive("c2", self.c2)?;
        let c3 = positive("c3", self.c3)?;
        non_negative("bound_a", self.bound_a)?;
        non_negative("bound_b", self.bound_b)?;
        if self.bound_b >= 1.0 {
            return Err(ParamError::new(
                "bound_b",
                "must be < 1: b's sign must be known",
                self.bound_b,
            ));
        }
        positive("adapt_time", self.adapt_time)?;
        let a = d.model.coeffs.as_array();
        let x = Rbf::paper_scale();
        let xv = a[0] * x[0] + a[1] * x[1] + a[2] * x[2];
        let z = match self.error_scale {
            Some(z) => positive("error_scale", z)?,
            None => self.z_rule(),
        };
        let gamma = match self.gamma {
            Some(g) => {
                for v in g {
                    non_negative("gamma", v)?;
                }
                g
            }
            None => core::array::from_fn(|i| {
                2.0 * self.bound_a * a[i].abs() / (self.adapt_time * x[i] * z)
            }),
        };
        let gamma_rho = match self.gamma_rho {
            Some(g) => non_negative("gamma_rho", g)?,
            None => {
                let range = 1.0 / (1.0 - self.bound_b) - 1.0 / (1.0 + self.bound_b);
                range / (self.adapt_time * xv * z)
            }
        };
        let (mut lo, mut hi) = ([f64::NEG_INFINITY; 4], [f64::INFINITY; 4]);
        if self.projection {
            for i in 0..3 {
                lo[i] = a[i] - self.bound_a * a[i].abs();
                hi[i] = a[i] + self.bound_a * a[i].abs();
            }
            lo[3] = 1.0 / (1.0 + self.bound_b);
            hi[3] = 1.0 / (1.0 - self.bound_b);
        }
        Ok(Backstepping {
            model: d.model,
            lo,
            hi,
            c: [c1, c2, c3],
            gamma,
            gamma_rho,
            b_floor: 1e-3 * d.model.b_at_rest(),
        })
    }
}

impl<T: Real> Controller<T> for Backstepping<T> {
    /// (â1, â2, â3, ϱ̂).
    type State = [T; 4];
    type Parts = BacksteppingParts<T>;

    /// ϑ̂(0) = (ā1, ā2, ā3), ϱ̂(0) = 1: the nominal model.
    fn initial_state(&self) -> [T; 4] {
        let a = self.model.coeffs.as_array();
        [a[0], a[1], a[2], T::ONE]
    }

    #[inline]
    fn law(
        &self,
        m: &Measurement<T>,
        s: &[T; 4],
        ds: &mut [T; 4],
    ) -> Output<BacksteppingParts<T>, T> {
        let (x, r) = (&m.x, &m.z);
        let [c1, c2, c3] = self.c;
        let z1 = x[0] - r[0];
        let alpha1 = -c1 * z1 + r[1];
        let z2 = x[1] - alpha1;
        let dalpha1 = -c1 * (x[1] - r[1]) + r[2];
        let alpha2 = -z1 - c2 * z2 + dalpha1;
        let z3 = x[2] - alpha2;
        let ddalpha1 = -c1 * (x[2] - r[2]) + r[3];
        let dalpha2 = -(x[1] - r[1]) - c2 * (x[2] - dalpha1) + ddalpha1;
        // The estimates in use (clamped to the box with projection).
        let th: [T; 4] = core::array::from_fn(|i| s[i].clamp(self.lo[i], self.hi[i]));
        // −φᵀϑ̂ = â1x1 + â2x2 + â3x3.
        let ax = th[0] * x[0] + th[1] * x[1] + th[2] * x[2];
        let alpha3 = -z2 - c3 * z3 + ax + self.model.d(x) + dalpha2;
        let v = th[3] * alpha3;
        let (b_bar, clamped) = self.model.gain_for(x, v, self.b_floor);
        let fl = if clamped {
            flags::VALVE_ROOT_CLAMPED
        } else {
            0
        };
        // ϑ̂̇ = Γ·φ·z3 with φ = −x; ϱ̂̇ = −γϱ·ᾱ3·z3; then the projection.
        let rates = [
            -self.gamma[0] * x[0] * z3,
            -self.gamma[1] * x[1] * z3,
            -self.gamma[2] * x[2] * z3,
            -self.gamma_rho * alpha3 * z3,
        ];
        for i in 0..4 {
            let (r, raw) = (rates[i], s[i]);
            ds[i] = if (raw >= self.hi[i] && r > T::ZERO) || (raw <= self.lo[i] && r < T::ZERO) {
                T::ZERO
            } else {
                r
            };
        }
        Output {
            u: v / b_bar,
            flags: fl,
            parts: BacksteppingParts {
                z1,
                z2,
                z3,
                alpha1,
                alpha2,
                alpha3,
                a1_hat: th[0],
                a2_hat: th[1],
                a3_hat: th[2],
                rho_hat: th[3],
                b_bar,
            },
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact zeros of the projection are the point
mod tests {
    use super::*;
    use crate::servo::{Load, ServoParams};
    use crate::surface::SwitchingSurface;

    fn design(load: Load) -> Design {
        Design {
            model: NominalModel::new(ServoParams::paper(), load),
            surface: SwitchingSurface::paper(),
            dt: 0.01,
        }
    }

    /// The designed values are the rules' and build the same law. By hand
    /// at the paper's scales X = (6.25°, 12.5π°/s, 25π²°/s²) in rad =
    /// (0.109083, 0.685389, 4.306427) and c1 = c2 = 30:
    /// Z = 0.1·(4.306427 + 60·0.685389 + 901·0.109083) = 14.371363.
    #[test]
    fn designed_fills_the_rules_and_builds_the_same_law() {
        let d = design(Load::paper());
        let cfg = BacksteppingConfig::default();
        let got = cfg.designed(&d).unwrap().unwrap();
        let z = got.error_scale.unwrap();
        assert!((z - 14.371363).abs() < 1e-6, "{z}");
        assert!(got.gamma.is_some() && got.gamma_rho.is_some());
        assert_eq!(got.build(&d).unwrap(), cfg.build(&d).unwrap());
        // A given Z is kept as given.
        let given = BacksteppingConfig {
            error_scale: Some(3.0),
            ..cfg
        };
        assert_eq!(given.designed(&d).unwrap().unwrap().error_scale, Some(3.0));
    }

    /// c = (1, 2, 3), Γ = (10, 20, 30), γϱ = 2, no load (d = 0),
    /// x = (0.1, 0.2, 0.3), (θd, θ̇d, θ̈d, θ⃛d) = (0, 0.5, 0, 1),
    /// ϑ̂ = (1, 2, 3), ϱ̂ = 0.5:
    /// z1 = 0.1; α1 = −0.1 + 0.5 = 0.4; z2 = 0.2 − 0.4 = −0.2;
    /// α̇1 = −(0.2 − 0.5) + 0 = 0.3; α2 = −0.1 − 2·(−0.2) + 0.3 = 0.6;
    /// z3 = 0.3 − 0.6 = −0.3; α̈1 = −(0.3 − 0) + 1 = 0.7;
    /// α̇2 = −(0.2 − 0.5) − 2·(0.3 − 0.3) + 0.7 = 1.0;
    /// −φᵀϑ̂ = 0.1 + 0.4 + 0.9 = 1.4;
    /// ᾱ3 = 0.2 + 0.9 + 1.4 + 0 + 1.0 = 3.5; v = 0.5·3.5 = 1.75;
    /// ϑ̂̇ = −Γ·x·z3 = (0.3, 1.2, 2.7); ϱ̂̇ = −2·3.5·(−0.3) = 2.1.
    /// Check of the error dynamics: z1' = x2 − θ̇d = −0.3 = −c1z1 + z2. ✓
    #[test]
    fn law_by_hand() {
        let d = design(Load::none());
        let c = BacksteppingConfig {
            c1: 1.0,
            c2: 2.0,
            c3: 3.0,
            gamma: Some([10.0, 20.0, 30.0]),
            gamma_rho: Some(2.0),
            projection: false,
            ..BacksteppingConfig::default()
        }
        .build(&d)
        .unwrap();
        let m = Measurement {
            t: 0.0,
            x: [0.1, 0.2, 0.3],
            z: [0.0, 0.5, 0.0, 1.0],
        };
        let mut ds = [0.0; 4];
        let o = c.law(&m, &[1.0, 2.0, 3.0, 0.5], &mut ds);
        let close = |a: f64, b: f64| assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        close(o.z1, 0.1);
        close(o.alpha1, 0.4);
        close(o.z2, -0.2);
        close(o.alpha2, 0.6);
        close(o.z3, -0.3);
        close(o.alpha3, 3.5);
        close(o.b_bar, d.model.gain_for(&m.x, 1.0, 0.0).0);
        close(o.u * o.b_bar, 1.75);
        for (g, w) in ds.iter().zip([0.3, 1.2, 2.7, 2.1]) {
            close(*g, w);
        }
        // With projection (box 2ā, ϱ ≤ 2) and every estimate at its upper
        // bound: z3 is still −0.3, ᾱ3 > 0 (â2x2 = 5200 dominates), so every
        // rate points outwards and is zeroed; from above the box the law
        // uses the bound.
        let p = BacksteppingConfig {
            projection: true,
            ..BacksteppingConfig {
                c1: 1.0,
                c2: 2.0,
                c3: 3.0,
                gamma: Some([10.0, 20.0, 30.0]),
                gamma_rho: Some(2.0),
                ..BacksteppingConfig::default()
            }
        }
        .build(&d)
        .unwrap();
        let (_, hi) = p.bounds();
        let o = p.law(&m, &hi, &mut ds);
        close(o.z3, -0.3);
        assert!(o.alpha3 > 0.0);
        assert_eq!(ds, [0.0; 4]);
        let above = [hi[0] + 1.0, hi[1] + 1.0, hi[2] + 1.0, hi[3] + 1.0];
        let o2 = p.law(&m, &above, &mut ds);
        assert_eq!((o2.a2_hat, o2.rho_hat), (hi[1], hi[3]));
        assert_eq!(o2.u, o.u);
    }

    /// With exact parameters (ϑ̂ = ϑ, ϱ̂ = 1/ϑb) the closed loop is
    /// z' = A·z: integrate the true plant (no load, ϑb = 1) with the law by
    /// small Euler steps and check V = Σzi²/2 decays as V̇ = −Σ ci·zi².
    #[test]
    fn exact_parameters_give_the_linear_error_dynamics() {
        let d = design(Load::none());
        let c = BacksteppingConfig {
            gamma: Some([0.0; 3]),
            gamma_rho: Some(0.0),
            ..BacksteppingConfig::default()
        }
        .build(&d)
        .unwrap();
        let a = d.model.coeffs.as_array();
        let s = c.initial_state();
        let mut x = [0.01, 0.0, 0.0];
        let dt = 1e-6;
        let vz = |o: &Output<BacksteppingParts>| 0.5 * (o.z1 * o.z1 + o.z2 * o.z2 + o.z3 * o.z3);
        let mut ds = [0.0; 4];
        let m = |x: [f64; 3]| Measurement {
            t: 0.0,
            x,
            z: [0.0; 4],
        };
        let v0 = vz(&c.law(&m(x), &s, &mut ds));
        for _ in 0..10_000 {
            let o = c.law(&m(x), &s, &mut ds);
            let b = d.model.b(&x, o.u.signum()).0;
            let j = -a[0] * x[0] - a[1] * x[1] - a[2] * x[2] + b * o.u;
            x = [x[0] + dt * x[1], x[1] + dt * x[2], x[2] + dt * j];
        }
        let v1 = vz(&c.law(&m(x), &s, &mut ds));
        // With c1 = c2 = c3 = 30, V̇ = −60·V exactly: after 0.01 s,
        // V = V0·exp(−0.6) (1 % slack for the Euler steps).
        let want = v0 * (-0.6f64).exp();
        assert!((v1 / want - 1.0).abs() < 0.01, "{v0} → {v1}, want {want}");
    }

    /// The default rules for the paper's servo (module doc):
    /// Z = 0.1·(4.306355 + 60·0.685389 + 901·0.109083)
    /// = 0.1·(4.30636 + 41.12334 + 98.28378) = 14.37135;
    /// Γ1 = 2·0.39982/(0.109083·14.37135) = 0.79964/1.56767 = 0.51008;
    /// Γ2 = 2·13000.27/(0.685389·14.37135) = 26000.54/9.85004 = 2639.6;
    /// Γ3 = 2·169.98/(4.306355·14.37135) = 339.96/61.8881 = 5.4932;
    /// γϱ = (2 − 2/3)/(9642.28·14.37135) = 1.33333/138572 = 9.6218·10⁻⁶;
    /// the box: ϱ ∈ [1/1.5, 1/0.5] = [0.6667, 2].
    #[test]
    fn default_rules_for_the_paper() {
        let d = design(Load::paper());
        let c = BacksteppingConfig::default().build(&d).unwrap();
        let (cs, g, gr) = c.gains();
        assert_eq!(cs, [30.0; 3]);
        let rel = |a: f64, b: f64| assert!((a / b - 1.0).abs() < 1e-3, "{a} vs {b}");
        rel(g[0], 0.51008);
        rel(g[1], 2639.6);
        rel(g[2], 5.4932);
        rel(gr, 9.6218e-6);
        assert_eq!(c.bounds().0, [f64::NEG_INFINITY; 4]);
        let c = BacksteppingConfig {
            projection: true,
            ..BacksteppingConfig::default()
        }
        .build(&d)
        .unwrap();
        let (lo, hi) = c.bounds();
        rel(lo[3], 2.0 / 3.0);
        rel(hi[3], 2.0);
        assert_eq!(lo[1], 0.0);
        let bad = |c: BacksteppingConfig| c.build(&d).unwrap_err().name;
        assert_eq!(
            bad(BacksteppingConfig {
                c2: 0.0,
                ..BacksteppingConfig::default()
            }),
            "c2"
        );
        assert_eq!(
            bad(BacksteppingConfig {
                gamma_rho: Some(-1.0),
                ..BacksteppingConfig::default()
            }),
            "gamma_rho"
        );
    }
}
