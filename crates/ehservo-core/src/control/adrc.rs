//! Active disturbance rejection control: a linear extended state observer
//! (LESO) and a PD-type state feedback, tuned by bandwidth.
//!
//! Reference: Z. Gao, "Scaling and bandwidth-parameterization based
//! controller tuning", *Proceedings of the American Control Conference*,
//! 2003.
//!
//! **The plant as ADRC sees it.** The servo's model (8) is written
//! `θ⃛ = f + b0·u`, where the total disturbance `f` lumps everything but
//! `b0·u`: the plant's own dynamics `−a1θ − a2θ̇ − a3θ̈`, the load `−d`, and
//! `(b − b0)·u`. `b0` defaults to the nominal gain at rest `b̄0 =
//! b(x = 0)` (the controller is linear). Only θ is measured: the LESO
//! estimates z = (θ, θ̇, θ̈, f) from θ and u.
//!
//! ```text
//! ε   = θ − z1
//! ż1  = z2 + β1·ε
//! ż2  = z3 + β2·ε
//! ż3  = z4 + f̄(z) + b0·u + β3·ε
//! ż4  = β4·ε
//! u0  = k1(θd − z1) + k2(θ̇d − z2) + k3(θ̈d − z3) + θ⃛d     (the PD part)
//! v   = (u0 − z4 − f̄(z))/b0,   u = clamp(v, ±u_limit)
//! ```
//!
//! with `f̄ = 0` (the law of Gao's paper, the default) or, with
//! `model_assisted = true`, `f̄(z) = −ā1z1 − ā2z2 − ā3z3`: the nominal
//! model's known part of `f` moved into the observer and the law, so that
//! z4 estimates only what the nominal model misses (Σ Δa_i x_i + d − Δb·u
//! with signs as in (8)). That variant is an adaptation to this plant, not
//! Gao's law: its reason is below.
//!
//! **Gains by bandwidth** (Gao 2003). The feedback places the nominal error
//! dynamics at `(s + ω_c)³`: `k1 = ω_c³, k2 = 3ω_c², k3 = 3ω_c`. The
//! observer's error dynamics `(sI − A + LC)` are placed at `(s + ω_o)⁴`:
//! with `f̄ = 0`, `β1 = 4ω_o, β2 = 6ω_o², β3 = 4ω_o³, β4 = ω_o⁴`; with the
//! model in the observer its characteristic polynomial is
//! `s⁴ + (β1 + ā3)s³ + (β2 + ā3β1 + ā2)s² + (β3 + ā3β2 + ā2β1 + ā1)s + β4`,
//! so `β1 = 4ω_o − ā3`, `β2 = 6ω_o² − ā2 − ā3β1`,
//! `β3 = 4ω_o³ − ā1 − ā2β1 − ā3β2`, `β4 = ω_o⁴`.
//!
//! **Default bandwidths (the stated rule).** ω_o = min(2·max(ā3, ω_h),
//! 1/dt) with ω_h = √ā2, and ω_c = ω_o/4 (Gao's ω_o = 3–5·ω_c, the
//! middle). The plain observer must be faster than the plant dynamics it
//! lumps into f, whose scale is the larger of ā3 (the sum of the plant's
//! own poles: 170 s⁻¹ for the paper's well damped servo) and the hydraulic
//! frequency ω_h (the resonance of a lightly damped axis, whose ā3 is
//! small: a cylinder moving a mass, ζ_h = ā3/(2ω_h) ≈ 0.01, would get an
//! observer a hundred times too slow from ā3 alone). 1/dt is the deadbeat
//! limit of the sampled observer (below). Given only one of ω_c, ω_o, the
//! other follows by the factor 4. For the paper's servo (ā3 = 170 >
//! ω_h = 114) at dt = 0.01 s: ω_o = 100, ω_c = 25; at dt = 0.001 s:
//! ω_o = 340, ω_c = 85. For `scenarios/cylinders/slide.toml` (ā3 = 1.67,
//! ω_h = 108) at 1 ms: ω_o = 216, ω_c = 54.
//!
//! **A lightly damped axis.** Gao's plain ADRC lumps the whole plant,
//! resonance included, into f: on a cylinder moving a mass (ζ_h of
//! 0.01–0.1) f oscillates at ω_h with little damping, and an observer
//! capped by the sample rate does not outrun it. On
//! `scenarios/cylinders/slide.toml` (ω_h = 108 rad/s, ζ_h = 0.0077,
//! h = 1 ms) plain ADRC ends in a sustained oscillation at the resonance
//! for every ω_o tried (216, 500 rad/s) and diverges at ω_o = 1/h, while
//! `model_assisted = true` (the nominal resonance in the observer and the
//! law) settles the step to 1 µm. So, with both bandwidths left to the
//! default, plain ADRC is refused when ζ_h < [`LIGHT_DAMPING`] (0.2), with
//! the reason and `model_assisted = true` as the fix; giving `omega_o` or
//! `omega_c` is taken as the user's own design and not refused.
//!
//! **Which u the observer sees.** A law here is memoryless: it cannot read
//! the u of its previous evaluation. The LESO's input is the law's own u
//! (after `u_limit`) at the same instant, as in continuous-time ADRC: ξ̇ is
//! written from the u the same call returns. In the sampled loop the
//! simulator advances ξ once per sample by forward Euler,
//! `z_{k+1} = z_k + dt·ż(z_k, θ_k, u_k)`, and u_k is the command held over
//! [t_k, t_k + dt): so the observer is the forward-Euler discretisation of
//! the LESO driven by the command actually applied (the "current" ESO).
//! On an integrator chain its error dynamics have the four-fold eigenvalue
//! `1 − ω_o·dt`: stable for ω_o·dt < 2, non-oscillating for ω_o·dt ≤ 1
//! (deadbeat at 1) — hence the default's 1/dt cap; ω_o·dt ≥ 2 is refused.
//! The Euler observer does not match the ZOH plant exactly; the mismatch is
//! O(dt) and lands in z4 like any other disturbance. A valve range applied
//! by the plant after the law is not seen by the observer.
//!
//! **On the paper's Fig. 2 case.** The plain law lumps the servo's fast
//! own dynamics (true a2 = 26000 s⁻², a3 = 340 s⁻¹) into f; to estimate
//! them the observer needs ω_o well above ā3, which the sampled loop at
//! dt = 0.01 s (ω_o·dt < 2) cannot give: the plain ADRC does not track
//! there and is meant for fast loops (dt ≈ 0.001 s). With
//! `model_assisted = true` the observer only sees the model error and the
//! default bandwidths track at 0.01 s (`scenarios/league/adrc-fig2.toml`).

use super::{
    flags, Config, Controller, Design, LinearForm, Measurement, Output, Signal, Signals, Tunable,
};
use crate::error::{positive, ParamError};
use crate::math::Real;

/// `kind = "adrc"`: the `[controller]` keys. Bandwidths left out follow the
/// module doc's rule.
///
/// ```
/// use ehservo_core::control::adrc::AdrcConfig;
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// let adrc = AdrcConfig::default().build(&design)?;
/// // The rule at dt = 0.01 s: ω_o = min(2·max(ā3, ω_h), 1/dt) = min(340, 100) = 100,
/// // ω_c = ω_o/4 = 25; (s + 25)³ gives k = (25³, 3·25², 3·25).
/// assert_eq!(adrc.bandwidths(), (25.0, 100.0));
/// assert_eq!(adrc.feedback_gains(), [15625.0, 1875.0, 75.0]);
/// // Observer at rest, θd = 0.01: u0 = k1·θd = 156.25, so b0·u = 156.25,
/// // and the LESO's ż3 = z4 + b0·u + β3·(θ − z1) = 156.25.
/// let m = Measurement { t: 0.0, x: [0.0; 3], z: [0.01, 0.0, 0.0, 0.0] };
/// let mut ds = [0.0; 4];
/// let out = adrc.law(&m, &[0.0; 4], &mut ds);
/// assert!((out.u * adrc.b0() - 156.25).abs() < 1e-9);
/// assert!((ds[2] - 156.25).abs() < 1e-9);
/// // ω_o·dt ≥ 2: the forward-Euler observer would be unstable.
/// let fast = AdrcConfig { omega_o: Some(200.0), ..AdrcConfig::default() };
/// assert_eq!(fast.build(&design).unwrap_err().name, "omega_o");
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct AdrcConfig {
    /// ω_c, the controller bandwidth (rad/s); default ω_o/4.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub omega_c: Option<f64>,
    /// ω_o, the observer bandwidth (rad/s); default min(2·max(ā3, √ā2), 1/dt), or
    /// 4·ω_c when ω_c is given.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub omega_o: Option<f64>,
    /// b0, the input gain the law assumes (1/(V·s³)); default b̄ at rest.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub b0: Option<f64>,
    /// Output limit ±u_limit (V); none by default.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub u_limit: Option<f64>,
    /// Move the nominal model's −ā·z into the observer and the law (module
    /// doc). Default false (Gao's law).
    pub model_assisted: bool,
}

/// The observer gains β1..β4 placing the LESO's error poles at −ω_o (four
/// times), with the nominal coefficients `a` in the observer when
/// `model` (module doc).
///
/// ```
/// use ehservo_core::control::adrc::observer_gains;
///
/// let w = 100.0;
/// // Gao's plain LESO: (s + ω)⁴ = s⁴ + 4ωs³ + 6ω²s² + 4ω³s + ω⁴.
/// assert_eq!(observer_gains(w, [0.4, 13000.0, 170.0], false), [400.0, 6e4, 4e6, 1e8]);
/// // With the model a = (a1, a2, a3) in the observer, its polynomial
/// // s⁴ + (β1 + a3)s³ + (β2 + a3β1 + a2)s² + (β3 + a3β2 + a2β1 + a1)s + β4
/// // is still (s + ω)⁴.
/// let [a1, a2, a3] = [0.4, 13000.0, 170.0];
/// let [b1, b2, b3, b4] = observer_gains(w, [a1, a2, a3], true);
/// let got = [b1 + a3, b2 + a3 * b1 + a2, b3 + a3 * b2 + a2 * b1 + a1, b4];
/// for (g, want) in got.into_iter().zip([400.0, 6e4, 4e6, 1e8]) {
///     assert!((g - want).abs() <= 1e-12 * want);
/// }
/// ```
pub fn observer_gains(omega_o: f64, a: [f64; 3], model: bool) -> [f64; 4] {
    let w = omega_o;
    let [a1, a2, a3] = if model { a } else { [0.0; 3] };
    let b1 = 4.0 * w - a3;
    let b2 = 6.0 * w * w - a2 - a3 * b1;
    let b3 = 4.0 * w * w * w - a1 - a2 * b1 - a3 * b2;
    [b1, b2, b3, w * w * w * w]
}

/// The ADRC's parts.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AdrcParts<T = f64> {
    /// z1, the estimate of θ (rad).
    pub z1: T,
    /// z2, the estimate of θ̇ (rad/s).
    pub z2: T,
    /// z3, the estimate of θ̈ (rad/s²).
    pub z3: T,
    /// z4, the estimate of the total disturbance f (rad/s³).
    pub z4: T,
    /// The PD part u0/b0 (V).
    pub u_pd: T,
    /// The disturbance compensation −z4/b0 (V).
    pub u_dist: T,
    /// The model part −f̄(z)/b0 (V); 0 without `model_assisted`.
    pub u_model: T,
    /// The command before the output limit (V).
    pub u_unsat: T,
}

impl<T: Real> Signals for AdrcParts<T> {
    const SIGNALS: &'static [Signal] = &[
        Signal::new("z1", "z1_rad", "rad", "LESO estimate of θ"),
        Signal::new("z2", "z2_rad_s", "rad/s", "LESO estimate of θ̇"),
        Signal::new("z3", "z3_rad_s2", "rad/s²", "LESO estimate of θ̈"),
        Signal::new(
            "z4",
            "z4_rad_s3",
            "rad/s³",
            "LESO estimate of the total disturbance f",
        ),
        Signal::new("u_pd", "u_pd_V", "V", "PD part u0/b0"),
        Signal::new("u_dist", "u_dist_V", "V", "disturbance compensation −z4/b0"),
        Signal::new("u_model", "u_model_V", "V", "nominal-model part −f̄(z)/b0"),
        Signal::new(
            "u_unsat",
            "u_unsat_V",
            "V",
            "command before the output limit",
        ),
    ];
    fn write(&self, out: &mut [f64]) {
        let v = [
            self.z1,
            self.z2,
            self.z3,
            self.z4,
            self.u_pd,
            self.u_dist,
            self.u_model,
            self.u_unsat,
        ];
        for (o, v) in out.iter_mut().zip(v) {
            *o = v.to_f64();
        }
    }
}

/// The ADRC, built.
/// Built by [`AdrcConfig`] (`kind = "adrc"`), whose example evaluates one
/// step of the law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adrc<T: Real = f64> {
    k: [T; 3],
    beta: [T; 4],
    b0: T,
    /// ā, or 0 without the model in the observer.
    a: [T; 3],
    u_limit: T,
    omega: (T, T),
}

impl<T: Real> Adrc<T> {
    /// `(ω_c, ω_o)` in use (rad/s).
    pub fn bandwidths(&self) -> (T, T) {
        self.omega
    }

    /// `(k1, k2, k3)`.
    pub fn feedback_gains(&self) -> [T; 3] {
        self.k
    }

    /// `(β1, β2, β3, β4)`.
    pub fn observer_gains(&self) -> [T; 4] {
        self.beta
    }

    /// b0 in use.
    pub fn b0(&self) -> T {
        self.b0
    }

    /// The same controller in another float type.
    pub fn cast<U: Real>(&self) -> Adrc<U> {
        let c = |v: T| U::of(v.to_f64());
        Adrc {
            k: self.k.map(c),
            beta: self.beta.map(c),
            b0: c(self.b0),
            a: self.a.map(c),
            u_limit: c(self.u_limit),
            omega: (c(self.omega.0), c(self.omega.1)),
        }
    }
}

/// ζ_h below which the default design refuses plain ADRC (module doc):
/// the usual bound of a "lightly damped" hydraulic resonance (Jelali &
/// Kroll 2003 give ζ_h of valve-controlled cylinders as 0.05–0.2).
pub const LIGHT_DAMPING: f64 = 0.2;

impl Config for AdrcConfig {
    const KIND: &'static str = "adrc";
    const USES_SURFACE: bool = false;
    /// The two bandwidths (rad/s); an observer beyond the sampled limit
    /// ω_o·dt < 2 is refused (a tuner scores it +∞).
    const TUNABLE: &'static [Tunable] = &[
        Tunable::log("omega_c", 1.0, 500.0),
        Tunable::log("omega_o", 5.0, 2000.0),
    ];
    type Controller = Adrc;
    type Law<F: Real> = Adrc<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<Adrc<F>, ParamError> {
        Ok(self.build(d)?.cast())
    }

    /// The observer and the static law, with the nominal a_i when
    /// `model_assisted`.
    fn linear(&self, d: &Design) -> Option<Result<LinearForm, ParamError>> {
        Some(self.build(d).map(|c| LinearForm::Eso {
            k: c.feedback_gains(),
            beta: c.observer_gains(),
            b0: c.b0(),
            a: if self.model_assisted {
                d.model.coeffs.as_array()
            } else {
                [0.0; 3]
            },
            u_limit: self.u_limit.unwrap_or(f64::INFINITY),
        }))
    }

    /// The bandwidths ω_c, ω_o and the input gain b0, as designed.
    fn designed(&self, d: &Design) -> Option<Result<Self, ParamError>> {
        Some(self.build(d).map(|adrc| {
            let (wc, wo) = adrc.bandwidths();
            Self {
                omega_c: Some(wc),
                omega_o: Some(wo),
                b0: Some(adrc.b0()),
                ..*self
            }
        }))
    }

    fn build(&self, d: &Design) -> Result<Adrc, ParamError> {
        let a = d.model.coeffs.as_array();
        let wc_given = self.omega_c.map(|w| positive("omega_c", w)).transpose()?;
        let wo_given = self.omega_o.map(|w| positive("omega_o", w)).transpose()?;
        let (wc, wo) = match (wc_given, wo_given) {
            (Some(c), Some(o)) => (c, o),
            (Some(c), None) => (c, 4.0 * c),
            (None, Some(o)) => (o / 4.0, o),
            (None, None) => {
                // The scale of the lumped dynamics (module doc).
                let wh = if a[1] > 0.0 {
                    crate::math::sqrt(a[1])
                } else {
                    0.0
                };
                if !self.model_assisted && wh > 0.0 && a[2] / (2.0 * wh) < LIGHT_DAMPING {
                    return Err(ParamError::new(
                        "model_assisted",
                        "plain ADRC lumps this lightly damped resonance (ζ_h < 0.2) into its disturbance, which no observer within the sample rate outruns: set model_assisted = true (the nominal resonance in the observer), or give omega_o and omega_c",
                        f64::NAN,
                    ));
                }
                let o = (2.0 * a[2].max(wh)).min(1.0 / d.dt);
                (o / 4.0, o)
            }
        };
        positive("omega_o", wo)?;
        if wo * d.dt >= 2.0 {
            return Err(ParamError::new(
                "omega_o",
                "ω_o·dt must be < 2: the sampled (forward-Euler) observer is unstable beyond",
                wo,
            ));
        }
        let b0 = match self.b0 {
            Some(b) => positive("b0", b)?,
            None => d.model.b_at_rest(),
        };
        let u_limit = match self.u_limit {
            Some(l) => positive("u_limit", l)?,
            None => f64::INFINITY,
        };
        Ok(Adrc {
            k: [wc * wc * wc, 3.0 * wc * wc, 3.0 * wc],
            beta: observer_gains(wo, a, self.model_assisted),
            b0,
            a: if self.model_assisted { a } else { [0.0; 3] },
            u_limit,
            omega: (wc, wo),
        })
    }
}

impl<T: Real> Controller<T> for Adrc<T> {
    /// (z1, z2, z3, z4): the LESO's estimates.
    type State = [T; 4];
    type Parts = AdrcParts<T>;

    fn initial_state(&self) -> [T; 4] {
        [T::ZERO; 4]
    }

    /// The ESO starts at the plant's state (z1, z2, z3) = x and f = 0: a
    /// zero start would read a loop started at θ(0) ≠ 0 as an observer
    /// error of the whole θ(0) and kick the command to its limit.
    fn initial_state_at(&self, x: &[T; 3]) -> [T; 4] {
        [x[0], x[1], x[2], T::ZERO]
    }

    #[inline]
    fn law(&self, m: &Measurement<T>, s: &[T; 4], ds: &mut [T; 4]) -> Output<AdrcParts<T>, T> {
        let z = &m.z;
        let [k1, k2, k3] = self.k;
        let [b1, b2, b3, b4] = self.beta;
        let fbar = -(self.a[0] * s[0] + self.a[1] * s[1] + self.a[2] * s[2]);
        let u0 = k1 * (z[0] - s[0]) + k2 * (z[1] - s[1]) + k3 * (z[2] - s[2]) + z[3];
        let v = (u0 - s[3] - fbar) / self.b0;
        let (u, fl) = if v.abs() > self.u_limit {
            (v.clamp(-self.u_limit, self.u_limit), flags::SATURATED)
        } else {
            (v, 0)
        };
        let eps = m.x[0] - s[0];
        ds[0] = s[1] + b1 * eps;
        ds[1] = s[2] + b2 * eps;
        ds[2] = s[3] + fbar + self.b0 * u + b3 * eps;
        ds[3] = b4 * eps;
        Output {
            u,
            flags: fl,
            parts: AdrcParts {
                z1: s[0],
                z2: s[1],
                z3: s[2],
                z4: s[3],
                u_pd: u0 / self.b0,
                u_dist: -s[3] / self.b0,
                u_model: -fbar / self.b0,
                u_unsat: v,
            },
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use crate::rk4::rk4_step;
    use crate::servo::{Load, NominalModel, ServoParams};
    use crate::surface::SwitchingSurface;

    fn design(dt: f64) -> Design {
        Design {
            model: NominalModel::new(ServoParams::paper(), Load::paper()),
            surface: SwitchingSurface::paper(),
            dt,
        }
    }

    fn close(a: f64, b: f64, tol: f64) {
        assert!((a - b).abs() <= tol, "{a} vs {b}");
    }

    /// One evaluation by hand: ω_c = ω_o = 1 (k = (1, 3, 3), β = (4, 6, 4,
    /// 1)), b0 = 2, plain observer, z = (0.1, 0.2, 0.3, 0.4), θ = 0.15,
    /// reference (0.5, 0.25, 0.1, 1.05):
    /// u0 = 0.4 + 3·0.05 + 3·(−0.2) + 1.05 = 1.0; u = (1.0 − 0.4)/2 = 0.3;
    /// ε = 0.05: ż1 = 0.2 + 0.2 = 0.4, ż2 = 0.3 + 0.3 = 0.6,
    /// ż3 = 0.4 + 2·0.3 + 0.2 = 1.2, ż4 = 0.05.
    /// With u_limit = 0.1: u = 0.1 and ż3 = 0.4 + 0.2 + 0.2 = 0.8.
    #[test]
    fn law_by_hand() {
        let cfg = AdrcConfig {
            omega_c: Some(1.0),
            omega_o: Some(1.0),
            b0: Some(2.0),
            ..AdrcConfig::default()
        };
        let c = cfg.build(&design(0.01)).unwrap();
        assert_eq!(c.feedback_gains(), [1.0, 3.0, 3.0]);
        assert_eq!(c.observer_gains(), [4.0, 6.0, 4.0, 1.0]);
        let m = Measurement {
            t: 0.0,
            x: [0.15, 9.0, 9.0],
            z: [0.5, 0.25, 0.1, 1.05],
        };
        let s = [0.1, 0.2, 0.3, 0.4];
        let mut ds = [0.0; 4];
        let o = c.law(&m, &s, &mut ds);
        close(o.u, 0.3, 1e-12);
        close(o.u_pd, 0.5, 1e-12);
        close(o.u_dist, -0.2, 1e-12);
        assert_eq!(o.u_model, 0.0);
        for (d, h) in ds.iter().zip([0.4, 0.6, 1.2, 0.05]) {
            close(*d, h, 1e-12);
        }
        assert_eq!(o.flags, 0);
        let lim = AdrcConfig {
            u_limit: Some(0.1),
            ..cfg
        }
        .build(&design(0.01))
        .unwrap();
        let o = lim.law(&m, &s, &mut ds);
        close(o.u, 0.1, 1e-12);
        close(o.u_unsat, 0.3, 1e-12);
        close(ds[2], 0.8, 1e-12);
        assert_ne!(o.flags & flags::SATURATED, 0);
    }

    /// The model-assisted law by hand: ω_c = 10, ω_o = 100, b0 = b̄0,
    /// state z = (0, 1, 0, 0), θ = 0, reference 0: u0 = −k2 = −300,
    /// f̄ = −ā2 = −13000.2711 (ā2 of the paper, servo.rs),
    /// u = (−300 + 13000.2711)/17911.75 = 0.709044; β1 = 400 − ā3 =
    /// 230.01957, β2 = 60000 − ā2 − ā3·β1 = 60000 − 13000.2711 −
    /// 39098.83 = 7900.90; ż3 = 0 + (−13000.2711) + b0·u = −300.
    #[test]
    fn model_assisted_by_hand() {
        let d = design(0.001);
        let c = AdrcConfig {
            omega_c: Some(10.0),
            omega_o: Some(100.0),
            model_assisted: true,
            ..AdrcConfig::default()
        }
        .build(&d)
        .unwrap();
        let beta = c.observer_gains();
        close(beta[0], 230.01957, 1e-5);
        close(beta[1], 7900.90, 0.01);
        let m = Measurement {
            t: 0.0,
            x: [0.0; 3],
            z: [0.0; 4],
        };
        let mut ds = [0.0; 4];
        let o = c.law(&m, &[0.0, 1.0, 0.0, 0.0], &mut ds);
        close(o.u, 12700.2711 / 17911.75, 1e-5);
        close(o.u_model, 13000.2711 / 17911.75, 1e-5);
        close(ds[2], -300.0, 1e-3);
        close(ds[0], 1.0, 1e-12);
    }

    /// The default rule: ω_o = min(2·max(ā3, ω_h), 1/dt), ω_c = ω_o/4;
    /// for the paper's servo ā3 = 169.98 > ω_h = 114.02, 2ā3 = 339.96; a
    /// model with ā2 = 10⁴ (ω_h = 100) and small ā3 gets 2ω_h = 200, and
    /// below ζ_h = 0.2 only model-assisted.
    #[test]
    fn default_bandwidths_follow_the_rule() {
        let c = AdrcConfig::default().build(&design(0.01)).unwrap();
        assert_eq!(c.bandwidths(), (25.0, 100.0));
        let c = AdrcConfig::default().build(&design(0.001)).unwrap();
        close(c.bandwidths().1, 339.96086, 1e-4);
        // ā2 = 10⁴: ω_h = 100. At ā3 = 41, ζ_h = 0.205: 2ω_h = 200 rules.
        let mut light = design(0.001);
        light.model.coeffs.a2 = 1e4;
        light.model.coeffs.a3 = 41.0;
        let c = AdrcConfig::default().build(&light).unwrap();
        assert_eq!(c.bandwidths(), (50.0, 200.0));
        // At ā3 = 2, ζ_h = 0.01: plain ADRC refused, model-assisted built
        // on the same rule.
        light.model.coeffs.a3 = 2.0;
        let e = AdrcConfig::default().build(&light).unwrap_err();
        assert_eq!(e.name, "model_assisted");
        let c = AdrcConfig {
            model_assisted: true,
            ..AdrcConfig::default()
        }
        .build(&light)
        .unwrap();
        assert_eq!(c.bandwidths(), (50.0, 200.0));
        // The user's own bandwidths are not refused.
        let c = AdrcConfig {
            omega_o: Some(400.0),
            ..AdrcConfig::default()
        }
        .build(&light)
        .unwrap();
        assert_eq!(c.bandwidths(), (100.0, 400.0));
        close(c.b0(), 17911.75, 0.01);
        let c = AdrcConfig {
            omega_c: Some(10.0),
            ..AdrcConfig::default()
        }
        .build(&design(0.01))
        .unwrap();
        assert_eq!(c.bandwidths(), (10.0, 40.0));
        let bad = |c: AdrcConfig| c.build(&design(0.01)).unwrap_err().name;
        assert_eq!(
            bad(AdrcConfig {
                omega_o: Some(200.0),
                ..AdrcConfig::default()
            }),
            "omega_o"
        );
        assert_eq!(
            bad(AdrcConfig {
                omega_c: Some(-1.0),
                ..AdrcConfig::default()
            }),
            "omega_c"
        );
        assert_eq!(
            bad(AdrcConfig {
                b0: Some(0.0),
                ..AdrcConfig::default()
            }),
            "b0"
        );
        assert_eq!(
            bad(AdrcConfig {
                u_limit: Some(f64::NAN),
                ..AdrcConfig::default()
            }),
            "u_limit"
        );
    }

    /// Integrates the plant `θ⃛ = plant(x, u)` and the controller together
    /// (the law inside every RK4 stage) from rest; calls `check(t, z)`.
    fn closed_loop(
        c: &Adrc,
        zref: [f64; 4],
        plant: impl Fn(&[f64; 3], f64) -> f64,
        h: f64,
        n: usize,
        mut check: impl FnMut(f64, &[f64; 7], f64),
    ) {
        let mut y = [0.0; 7];
        let f = |t: f64, y: &[f64; 7], dy: &mut [f64; 7]| {
            let x = [y[0], y[1], y[2]];
            let m = Measurement { t, x, z: zref };
            let s = [y[3], y[4], y[5], y[6]];
            let mut ds = [0.0; 4];
            let o = c.law(&m, &s, &mut ds);
            *dy = [y[1], y[2], plant(&x, o.u), ds[0], ds[1], ds[2], ds[3]];
        };
        for k in 0..n {
            let t = k as f64 * h;
            rk4_step(&f, t, &mut y, h);
            let s = [y[3], y[4], y[5], y[6]];
            let u = c
                .law(
                    &Measurement {
                        t,
                        x: [y[0], y[1], y[2]],
                        z: zref,
                    },
                    &s,
                    &mut [0.0; 4],
                )
                .u;
            check(t + h, &y, u);
        }
    }

    /// The LESO's error obeys ε̇ = (A − LC)ε whatever the control when the
    /// plant is θ⃛ = b0·u + F with F constant (the observer's model exactly):
    /// from x(0) = 0, z(0) = 0 the error starts at (0, 0, 0, F), so
    /// ε1 = F/(s + ω)⁴ and ε4 = [F − β4ε1]/s = F[(s + ω)⁴ − ω⁴]/(s(s + ω)⁴),
    /// i.e. z4(t) = F·(1 − e^{−ωt}(1 + ωt + (ωt)²/2 + (ωt)³/6)).
    #[test]
    fn disturbance_estimate_converges_in_closed_form() {
        let (w, b0, f) = (100.0, 2.0, -50.0);
        let c = AdrcConfig {
            omega_c: Some(20.0),
            omega_o: Some(w),
            b0: Some(b0),
            ..AdrcConfig::default()
        }
        .build(&design(1e-4))
        .unwrap();
        let mut worst: f64 = 0.0;
        closed_loop(
            &c,
            [0.01, 0.0, 0.0, 0.0],
            |_, u| b0 * u + f,
            1e-4,
            1000,
            |t, y, _| {
                let wt = w * t;
                let exact =
                    f * (1.0 - (-wt).exp() * (1.0 + wt + wt * wt / 2.0 + wt * wt * wt / 6.0));
                worst = worst.max((y[6] - exact).abs());
            },
        );
        assert!(worst < 1e-6 * f.abs(), "worst {worst}");
    }

    /// On the nominal linear plant θ⃛ = −ā1θ − ā2θ̇ − ā3θ̈ + b̄0·u − w with a
    /// constant injected disturbance w and a constant set point θd, the
    /// steady state has θ = θd, θ̇ = θ̈ = 0, so f = −ā1θd − w, and the LESO's
    /// fixed point (ż = 0) gives z1 = θ, z2 = z3 = 0, z4 = −b0·u; hence
    /// z4 → −ā1θd − w and u → (ā1θd + w)/b̄0. With θd = 0.05, w = 300:
    /// z4 → −300.019991, u → 0.0167499.
    #[test]
    fn disturbance_estimate_converges_on_the_nominal_plant() {
        let d = design(1e-4);
        let a = d.model.coeffs.as_array();
        let b0 = d.model.b_at_rest();
        let (theta_d, w) = (0.05, 300.0);
        let c = AdrcConfig {
            omega_c: Some(50.0),
            omega_o: Some(400.0),
            ..AdrcConfig::default()
        }
        .build(&d)
        .unwrap();
        let mut last = ([0.0; 7], 0.0);
        closed_loop(
            &c,
            [theta_d, 0.0, 0.0, 0.0],
            |x, u| -a[0] * x[0] - a[1] * x[1] - a[2] * x[2] + b0 * u - w,
            1e-4,
            20_000,
            |_, y, u| last = (*y, u),
        );
        let (y, u) = last;
        close(y[6], -a[0] * theta_d - w, 1e-6 * w);
        close(y[6], -300.019991, 1e-5);
        close(u, (a[0] * theta_d + w) / b0, 1e-9);
        close(u, 0.0167499, 1e-7);
        close(y[0], theta_d, 1e-9);
    }
}
