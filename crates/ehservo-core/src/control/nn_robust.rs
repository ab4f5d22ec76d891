//! The NNBVSC with a classical robust weight law in place of the paper's
//! dead-zone law (26)–(27): σ-modification, e-modification or projection.
//!
//! Everything but Ẇ is Theorem 3's, computed by [`NnVsc`] itself (this
//! controller holds one and calls its law): the same Φ (20), the same
//! u_eq (24) with WᵀΦ, the same switching part (25) on the dead-zone σΔ
//! (27) with γ2 (34) and μ (SPEC §5). Only the weight law changes, so a
//! comparison with `nnvsc` isolates it. In the paper's symbols (H = h·I,
//! the paper's sign convention Ẇ = +σ·H⁻¹Φ, σ of (10), not σΔ: these laws
//! replace the dead zone, they do not add to it):
//!
//! ```text
//! sigma-mod:  Ẇ = H⁻¹(σ·Φ − σ_mod·W)
//! e-mod:      Ẇ = H⁻¹(σ·Φ − ν·|σ|·W)
//! projection: Ẇ = Proj(H⁻¹σΦ), keeping ‖W‖ ≤ Wmax (the paper's Wmax of (21))
//! ```
//!
//! * **σ-modification**: P. A. Ioannou and P. V. Kokotović, *Adaptive
//!   Systems with Reduced Models*, Springer LNCIS 47, 1983, and "Instability
//!   analysis and improvement of robustness of adaptive control",
//!   *Automatica* 20(5), 1984 (the paper's \[27\]); P. A. Ioannou and J. Sun,
//!   *Robust Adaptive Control*, Prentice Hall, 1996, §8.5. A fixed leakage
//!   −σ_mod·W: W is bounded whatever the excitation, at the price of a bias
//!   (W does not reach W̄ even without disturbance).
//! * **e-modification**: K. S. Narendra and A. M. Annaswamy, "A new adaptive
//!   law for robust adaptation without persistent excitation", *IEEE Trans.
//!   Automatic Control* 32(2), 134–145, 1987 (the paper's \[28\]). The leakage
//!   is scaled by the error, −ν|σ|·W, so it vanishes as the tracking does.
//!   The paper's own (26) is this law with σ replaced by σΔ ("a revision of
//!   ε-modification"): `e-mod` is (26) without its dead zone, and with
//!   ν = η the only difference from `nnvsc` is the dead zone in Ẇ.
//! * **projection**: Ioannou & Sun 1996, §8.5 (parameter projection);
//!   J.-B. Pomet and L. Praly, "Adaptive nonlinear regulation: estimation
//!   from the Lyapunov equation", *IEEE Trans. Automatic Control* 37(6),
//!   729–740, 1992 (the smooth version). Implemented here: the
//!   **discontinuous** norm-ball projection, in its sampled-data form. With
//!   τ = H⁻¹σΦ, T the loop's sample period (the simulation step) and
//!   y = W + T·τ:
//!
//!   ```text
//!   Ẇ = τ                               if ‖y‖ ≤ Wmax
//!   Ẇ = (Wmax·y/‖y‖ − W)/T              otherwise
//!   ```
//!
//!   so the simulator's forward-Euler step W + T·Ẇ is the projection of the
//!   unconstrained step onto the ball ‖W‖ ≤ Wmax (the discrete-time
//!   projection of G. C. Goodwin and K. S. Sin, *Adaptive Filtering,
//!   Prediction and Control*, 1984), to rounding. As T → 0 it tends to the
//!   continuous Proj of Ioannou & Sun: τ inside the ball or pointing in;
//!   on the sphere with Wᵀτ > 0, τ − (Wᵀτ/‖W‖²)·W (Γ = H⁻¹ is a multiple of
//!   I, so the Γ-weighted and the Euclidean projections agree). Why not the
//!   continuous form itself: forward Euler of a tangential Ẇ leaves the
//!   sphere by T²‖τ‖²/(2Wmax) a step, and the continuous Proj never pulls
//!   back, so in the paper's sampled loop (T = 0.01 s, ‖τ‖ ≈ 10³ in the
//!   first samples) ‖W‖ ratchets past Wmax: measured on the Fig. 2 case,
//!   the continuous Proj under the sampled Euler step ends at ‖W‖ = 11.75
//!   (Wmax = 4), and at 4.22 in the continuous reading at a 1-ms RK4 step.
//!   In the continuous reading the sampled-data rate is used with T the
//!   RK4 step; ‖W‖ ≤ Wmax then holds only to O(T²) (max 3.9999999 on
//!   Fig. 2 at 1 ms). Note that the paper's own law takes ‖W‖ to ≈ 72 on
//!   Fig. 2, far outside the Wmax = 4 its (21) and (34) assume, so the
//!   ball is active most of the run and costs tracking (module tests and
//!   the league scenario).
//!
//! **What the paper says about these alternatives** (Section I):
//! "a dead zone in the adaptive law \[24\]–\[26\] guarantees the boundedness of
//! all the signals in the adaptive loop. In addition, \[24\], as well as
//! \[26\], restrict the search region of parameter space by using *a priori*
//! information about the bound of parameter. An extra term of the form −σθ
//! in the adaptive law for adjusting the parameter θ introduced in \[27\] is
//! referred to as σ-modification. In \[28\], an ϵ-modification is designed to
//! improve the performance of the system in all respects, while retaining
//! the advantage of assuring robustness in the presence of disturbances
//! without the requirement of persistent excitation (PE). In this paper, a
//! revision of e-modification using a time-varying dead zone is employed to
//! achieve an exponential stability without the assumption of PE for the
//! uncertainties." And Remark 6: "A salient feature of weight updating law
//! (26) is the time-varying dead zone ᾱ‖E(t)‖. The updating algorithm stops
//! when the operating point is inside the exponential tracking region
//! according to the Theorem 1 … its second term (or revised ε-modification
//! of \[28\]) is used to ensure the boundedness of estimated weight W(t)
//! without the requirement of PE." The paper's case is thus exponential
//! tracking without PE (which an RBF network rarely has, its \[29\]); it does
//! not argue against projection beyond naming it as the use of a priori
//! bounds, though its own γ2 (34) already assumes ‖W̄‖ ≤ Wmax (21) — the
//! bound projection needs.
//!
//! **Default gains (a stated rule, not tuned on a run).** `nu = η` (0.25):
//! e-mod then differs from the paper's law by the dead zone alone.
//! `sigma_mod = η·(1 rad/s²)` (0.25): σ-mod leaks as the paper's law does
//! when |σΔ| = 1 rad/s², and with h = 1 its leakage time constant h/σ_mod
//! = 4 s is four periods of the paper's 1-Hz reference (long enough not to
//! erase within a period what a period teaches, short against the 60-s
//! drift horizon of Fig. 6). Projection uses the paper's Wmax = 4. The
//! switching part keeps η in γ2 (34) and μ: that is the switching gain of
//! Theorem 3, not the weight law.
//!
//! The parts are the NNBVSC's ([`SlidingParts`]: σ, σΔ of the switching
//! part, WᵀΦ, ‖W‖, …) and `leak` = ‖Ẇ − H⁻¹σΦ‖, the size of what the
//! robust modification takes off the gradient law (σ_mod‖W‖/h,
//! ν|σ|‖W‖/h, or the projection's correction; 0 when it is idle).

use super::nnvsc::{MuRule, NnState, NnVsc, NnVscParams};
use super::sliding::{RbfConfig, SlidingParts};
use super::{Config, Controller, Design, Measurement, Output, Signal, Signals, Truth, Tunable};
use crate::error::{non_negative, positive, ParamError};
use crate::math::{sqrt, Real};
use crate::rbf::{Rbf, N_PHI};
use crate::rk4::OdeState;
use crate::servo::NominalModel;
use crate::surface::SwitchingSurface;

/// Which robust weight law replaces (26)–(27).
///
/// ```
/// use ehservo_core::control::nn_robust::WeightLaw;
///
/// // As a scenario writes `controller.weight_law`.
/// assert_eq!(WeightLaw::parse("sigma-mod"), Some(WeightLaw::SigmaMod));
/// assert_eq!(WeightLaw::Projection.as_str(), "projection");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WeightLaw {
    /// Ẇ = H⁻¹(σΦ − σ_mod·W) (Ioannou & Kokotović).
    SigmaMod,
    /// Ẇ = H⁻¹(σΦ − ν|σ|·W) (Narendra & Annaswamy).
    EMod,
    /// Ẇ = Proj(H⁻¹σΦ) onto ‖W‖ ≤ Wmax, sampled-data form (module doc).
    Projection,
}

impl WeightLaw {
    const ALL: [WeightLaw; 3] = [WeightLaw::SigmaMod, WeightLaw::EMod, WeightLaw::Projection];

    /// The scenario spelling (`controller.weight_law`).
    pub const fn as_str(&self) -> &'static str {
        match self {
            WeightLaw::SigmaMod => "sigma-mod",
            WeightLaw::EMod => "e-mod",
            WeightLaw::Projection => "projection",
        }
    }

    /// From the scenario spelling.
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|r| r.as_str() == s)
    }
}

#[cfg(feature = "serde")]
serde_by_name!(
    WeightLaw,
    "one of `sigma-mod`, `e-mod`, `projection`",
    ["sigma-mod", "e-mod", "projection"]
);

/// The weight law's own gains (the rest are the NNBVSC's).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WeightLawParams<T = f64> {
    /// Which law.
    pub law: WeightLaw,
    /// σ_mod ≥ 0, the σ-modification leakage (units of η·|σ|).
    pub sigma_mod: T,
    /// ν ≥ 0, the e-modification gain (units of η).
    pub nu: T,
}

impl<T: Real> WeightLawParams<T> {
    /// Checks the gains (every one, whichever law reads it).
    pub fn validate(&self) -> Result<(), ParamError> {
        non_negative("sigma_mod", self.sigma_mod)?;
        non_negative("nu", self.nu)?;
        Ok(())
    }
}

/// The parts: the NNBVSC's, and the weight law's robust term.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RobustParts<T = f64> {
    /// The NNBVSC's parts (σΔ is the switching part's).
    pub sliding: SlidingParts<T>,
    /// ‖Ẇ − H⁻¹σΦ‖: the leakage (σ-mod, e-mod) or the projection's
    /// correction; 0 when idle.
    pub leak: T,
}

impl<T> core::ops::Deref for RobustParts<T> {
    type Target = SlidingParts<T>;
    fn deref(&self) -> &SlidingParts<T> {
        &self.sliding
    }
}

const N_SLIDING: usize = <SlidingParts<f64> as Signals>::SIGNALS.len();

const ROBUST_SIGNALS: [Signal; N_SLIDING + 1] = {
    let s = <SlidingParts<f64> as Signals>::SIGNALS;
    let leak = Signal::new(
        "leak",
        "leak",
        "",
        "‖Ẇ − H⁻¹σΦ‖: the weight law's leakage or projection term",
    );
    let mut a = [leak; N_SLIDING + 1];
    let mut i = 0;
    while i < N_SLIDING {
        a[i] = s[i];
        i += 1;
    }
    a
};

impl<T: Real> Signals for RobustParts<T> {
    const SIGNALS: &'static [Signal] = &ROBUST_SIGNALS;

    fn write(&self, out: &mut [f64]) {
        self.sliding.write(&mut out[..N_SLIDING]);
        out[N_SLIDING] = self.leak.to_f64();
    }

    /// The inverse of [`RobustParts::write`].
    fn rebuild<F: Real>(v: &[F]) -> Option<Self> {
        if v.len() < Self::SIGNALS.len() {
            return None;
        }
        Some(RobustParts {
            sliding: SlidingParts::rebuild(&v[..N_SLIDING])?,
            leak: T::of(v[N_SLIDING].to_f64()),
        })
    }
}

/// Theorem 3's controller with a classical robust weight law.
/// Built by [`NnRobustConfig`] (`kind = "nn-robust"`), whose example evaluates one
/// step of the law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NnRobust<T: Real = f64> {
    nn: NnVsc<T>,
    wl: WeightLawParams<T>,
    /// 1/h.
    inv_h: T,
    /// T, the sample period (projection).
    dt: T,
    /// 1/T.
    inv_dt: T,
}

impl<T: Real> NnRobust<T> {
    /// The same controller in another float type: the NNBVSC cast
    /// ([`NnVsc::cast`]), the weight law's gains rounded to `U` and its
    /// constants recomputed in `U`.
    pub fn cast<U: Real>(&self) -> Result<NnRobust<U>, ParamError> {
        let c = |v: T| U::of(v.to_f64());
        let nn = self.nn.cast::<U>()?;
        NnRobust::try_new(
            *nn.model(),
            *nn.surface(),
            *nn.params(),
            *nn.rbf(),
            WeightLawParams {
                law: self.wl.law,
                sigma_mod: c(self.wl.sigma_mod),
                nu: c(self.wl.nu),
            },
            c(self.dt),
        )
    }

    /// Validates every gain and builds the controller; `dt` is the loop's
    /// sample period (the simulation step), used by the projection.
    pub fn try_new(
        model: NominalModel<T>,
        surface: SwitchingSurface<T>,
        params: NnVscParams<T>,
        rbf: Rbf<T>,
        wl: WeightLawParams<T>,
        dt: T,
    ) -> Result<Self, ParamError> {
        let nn = NnVsc::try_new(model, surface, params, rbf)?;
        wl.validate()?;
        positive("dt", dt)?;
        if wl.law == WeightLaw::Projection {
            positive("w_max", params.w_max)?;
        }
        Ok(Self {
            nn,
            wl,
            inv_h: T::ONE / params.h,
            dt,
            inv_dt: T::ONE / dt,
        })
    }

    /// The NNBVSC whose Φ, u_eq and switching this controller uses.
    pub fn nnvsc(&self) -> &NnVsc<T> {
        &self.nn
    }

    /// The weight law's gains.
    pub fn weight_law(&self) -> &WeightLawParams<T> {
        &self.wl
    }
}

impl<T: Real> Controller<T> for NnRobust<T> {
    type State = NnState<T>;
    type Parts = RobustParts<T>;

    fn initial_state(&self) -> NnState<T> {
        NnState::zero()
    }

    fn law(
        &self,
        m: &Measurement<T>,
        s: &NnState<T>,
        ds: &mut NnState<T>,
    ) -> Output<RobustParts<T>, T> {
        // Theorem 3's u, parts and ∫e' = e; its Ẇ (26) is overwritten below.
        let out = self.nn.law(m, s, ds);
        let mut phi = [T::ZERO; N_PHI];
        self.nn.rbf().phi(&m.x, &m.z, &mut phi);
        let a = out.sigma * self.inv_h; // τ = a·Φ = H⁻¹σΦ
        let w = &s.w;
        let dw = &mut ds.w;
        let mut leak2 = T::ZERO;
        match self.wl.law {
            WeightLaw::SigmaMod | WeightLaw::EMod => {
                let k = if self.wl.law == WeightLaw::SigmaMod {
                    self.wl.sigma_mod * self.inv_h
                } else {
                    self.wl.nu * out.sigma.abs() * self.inv_h
                };
                for ((d, &wi), &fi) in dw.iter_mut().zip(w).zip(&phi) {
                    *d = a * fi - k * wi;
                    leak2 += (k * wi) * (k * wi);
                }
            }
            WeightLaw::Projection => {
                // y = W + T·τ; onto the ball if outside.
                let mut y2 = T::ZERO;
                for (&wi, &fi) in w.iter().zip(&phi) {
                    let y = wi + self.dt * (a * fi);
                    y2 += y * y;
                }
                let wm = self.nn.params().w_max;
                if y2 > wm * wm {
                    let sc = wm / sqrt(y2);
                    for ((d, &wi), &fi) in dw.iter_mut().zip(w).zip(&phi) {
                        let tau = a * fi;
                        *d = (sc * (wi + self.dt * tau) - wi) * self.inv_dt;
                        leak2 += (*d - tau) * (*d - tau);
                    }
                } else {
                    for (d, &fi) in dw.iter_mut().zip(&phi) {
                        *d = a * fi;
                    }
                }
            }
        }
        Output {
            u: out.u,
            flags: out.flags,
            parts: RobustParts {
                sliding: out.parts,
                leak: sqrt(leak2),
            },
        }
    }

    fn weights<'a>(&self, s: &'a NnState<T>) -> &'a [T] {
        &s.w
    }

    fn annotate(&self, s: &NnState<T>, out: &mut Output<RobustParts<T>, T>, truth: &dyn Truth) {
        let mut o = Output {
            u: out.u,
            flags: out.flags,
            parts: out.parts.sliding,
        };
        SlidingParts::annotate(&mut o, &s.w, truth);
        out.parts.sliding = o.parts;
    }
}

/// `kind = "nn-robust"`: the `[controller]` keys — the NNBVSC's (same
/// names, same defaults as `nnvsc`: the paper's Fig. 2 values) and the
/// weight law's.
///
/// ```
/// use ehservo_core::control::nn_robust::NnRobustConfig;
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// let nr = NnRobustConfig::default().build(&design)?; // e-modification
/// // At rest, z = (0, 0.5, 0, 0), W = 0: σ = 90·0.5 = 45, and the switching
/// // part's dead zone (27) gives σΔ = 45 − ᾱ·‖E‖ = 45 − 5·0.5 = 42.5.
/// let m = Measurement { t: 0.0, x: [0.0; 3], z: [0.0, 0.5, 0.0, 0.0] };
/// let (s, mut ds) = (nr.initial_state(), nr.initial_state());
/// let out = nr.law(&m, &s, &mut ds);
/// assert!((out.sigma_delta - 42.5).abs() < 1e-12);
/// // The weights learn from σ itself, no dead zone: Ẇ = σΦ − ν|σ|W = 45·Φ
/// // (h = 1, W = 0), and Φ's first entry is the bias 1; nothing leaks yet.
/// assert!((ds.w[0] - 45.0).abs() < 1e-12);
/// assert_eq!(out.parts.leak, 0.0);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct NnRobustConfig {
    /// `"sigma-mod"`, `"e-mod"` (default) or `"projection"`.
    pub weight_law: WeightLaw,
    /// σ_mod of `sigma-mod` (units of η·|σ|, η's × rad/s²). Default 0.25
    /// (= η·1 rad/s², module doc).
    pub sigma_mod: f64,
    /// ν of `e-mod` (units of η). Default 0.25 (= η).
    pub nu: f64,
    /// Bound the controller knows on Δb: β = bound_b·|b̄| (switching part).
    /// Default 0.5.
    pub bound_b: f64,
    /// γ1 of (25). Default 100.
    pub gamma1: f64,
    /// η, in γ2 (34) and μ only (the switching part). Default 0.25.
    pub eta: f64,
    /// α (μ of SPEC §5). Default 250.
    pub alpha: f64,
    /// ᾱ, the dead zone of σΔ in the switching part (27). Default 5.
    pub alpha_bar: f64,
    /// Wmax: in γ2 (34) and the radius of `projection`'s ball. Default 4.
    pub w_max: f64,
    /// ε0 of (34). Default 0.1.
    pub eps0: f64,
    /// ε1 of (34). Default 0.1.
    pub eps1: f64,
    /// ε2 of (34). Default 0.01.
    pub eps2: f64,
    /// h (H = h·I). Default 1.
    pub h: f64,
    /// Boundary-layer rule of (25): `"remark7"` (default), `"literal-33"`,
    /// `"zero"`.
    pub mu_rule: MuRule,
    /// `[controller.rbf]`.
    pub rbf: RbfConfig,
}

impl Default for NnRobustConfig {
    fn default() -> Self {
        let p = NnVscParams::paper();
        Self {
            weight_law: WeightLaw::EMod,
            sigma_mod: p.eta,
            nu: p.eta,
            bound_b: p.bound_b,
            gamma1: p.gamma1,
            eta: p.eta,
            alpha: p.alpha,
            alpha_bar: p.alpha_bar,
            w_max: p.w_max,
            eps0: p.eps0,
            eps1: p.eps1,
            eps2: p.eps2,
            h: p.h,
            mu_rule: p.mu_rule,
            rbf: RbfConfig::default(),
        }
    }
}

impl NnRobustConfig {
    /// The NNBVSC gains.
    pub fn nnvsc(&self) -> NnVscParams {
        NnVscParams {
            gamma1: self.gamma1,
            eta: self.eta,
            alpha: self.alpha,
            alpha_bar: self.alpha_bar,
            w_max: self.w_max,
            eps0: self.eps0,
            eps1: self.eps1,
            eps2: self.eps2,
            h: self.h,
            bound_b: self.bound_b,
            mu_rule: self.mu_rule,
        }
    }

    /// The weight law's gains.
    pub fn weight_law(&self) -> WeightLawParams {
        WeightLawParams {
            law: self.weight_law,
            sigma_mod: self.sigma_mod,
            nu: self.nu,
        }
    }
}

impl Config for NnRobustConfig {
    const KIND: &'static str = "nn-robust";
    const USES_SURFACE: bool = true;
    /// The NNBVSC's γ1 and α, and the leakage of σ- and e-modification
    /// (the law not chosen ignores its own).
    const TUNABLE: &'static [Tunable] = &[
        Tunable::log("gamma1", 1.0, 1e4),
        Tunable::log("alpha", 10.0, 1e4),
        Tunable::log("sigma_mod", 1e-3, 10.0),
        Tunable::log("nu", 1e-3, 10.0),
    ];
    type Controller = NnRobust;
    type Law<F: Real> = NnRobust<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<NnRobust<F>, ParamError> {
        self.build(d)?.cast()
    }
    fn build(&self, d: &Design) -> Result<NnRobust, ParamError> {
        self.nnvsc().validate()?;
        self.weight_law().validate()?;
        let rbf = self.rbf.build()?;
        NnRobust::try_new(
            d.model,
            d.surface,
            self.nnvsc(),
            rbf,
            self.weight_law(),
            d.dt,
        )
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)]
mod tests {
    use super::*;
    use crate::reference::{Reference, Sine};
    use crate::servo::{Load, ServoParams};

    fn ctrl(law: WeightLaw, dt: f64) -> NnRobust {
        NnRobust::try_new(
            NominalModel::new(ServoParams::paper(), Load::paper()),
            SwitchingSurface::paper(),
            NnVscParams::paper(),
            Rbf::paper(),
            WeightLawParams {
                law,
                sigma_mod: 0.25,
                nu: 0.25,
            },
            dt,
        )
        .unwrap()
    }

    fn first_sample() -> Measurement {
        Measurement {
            t: 0.0,
            x: [0.0; 3],
            z: Sine::paper().z(0.0),
        }
    }

    fn close(a: f64, b: f64, tol: f64) {
        assert!((a - b).abs() < tol, "{a} vs {b}");
    }

    /// W[0] = 2 (the bias weight), every other weight 0.
    fn bias_state(w0: f64) -> NnState {
        let mut s = NnState::zero();
        s.w[0] = w0;
        s
    }

    // The first Fig. 2 sample by hand (see nnvsc's `first_sample_of_fig2_by_hand`):
    // x = 0, t = 0, A = 5° = 0.0872664626 rad; θ̇d = 2πA = 0.54831136,
    // θ⃛d = −(2π)³A = −21.6464647; e = ë = ∫e = 0, so σ = 90·θ̇d = 49.348022.
    // Φ[0] = 1, Φ[129] = θ⃛d; ‖Φ‖² = (1 + 2e⁻² + 2e⁻⁸)³ + 1 + θ̇d² + θ⃛d²
    // = 471.92496. σ·θ⃛d = −1068.2102.

    /// σ-mod, h = 1, σ_mod = 0.25, W[0] = 2: Ẇ[0] = σ·1 − 0.25·2 = 48.848022;
    /// Ẇ[129] = σ·θ⃛d − 0 = −1068.2102; leak = 0.25·‖W‖ = 0.5. The command is
    /// Theorem 3's at the same state (the law only changes Ẇ).
    #[test]
    fn sigma_mod_derivative_by_hand() {
        let c = ctrl(WeightLaw::SigmaMod, 0.01);
        let s = bias_state(2.0);
        let mut ds = NnState::zero();
        let o = c.law(&first_sample(), &s, &mut ds);
        close(o.sigma, 49.348022, 1e-5);
        close(ds.w[0], 48.848022, 1e-5);
        close(ds.w[129], -1068.2102, 1e-3);
        close(o.parts.leak, 0.5, 1e-12);
        assert_eq!(ds.int_e, 0.0);
        let mut dn = NnState::zero();
        let on = c.nnvsc().law(&first_sample(), &s, &mut dn);
        assert_eq!(
            (o.u, o.u_eq, o.u_sw, o.wphi),
            (on.u, on.u_eq, on.u_sw, on.wphi)
        );
        // …and it is not the paper's Ẇ (σΔ = 46.606465, η|σΔ|·2 = 23.303233).
        close(dn.w[0], 46.606465 - 23.303233, 1e-5);
    }

    /// e-mod, ν = 0.25, W[0] = 2: Ẇ[0] = σ − 0.25·|σ|·2 = σ/2 = 24.674011;
    /// Ẇ[129] = σ·θ⃛d = −1068.2102; leak = 0.25·|σ|·2 = 24.674011.
    #[test]
    fn e_mod_derivative_by_hand() {
        let c = ctrl(WeightLaw::EMod, 0.01);
        let mut ds = NnState::zero();
        let o = c.law(&first_sample(), &bias_state(2.0), &mut ds);
        close(ds.w[0], 24.674011, 1e-5);
        close(ds.w[129], -1068.2102, 1e-3);
        close(o.parts.leak, 24.674011, 1e-5);
        // W = 0: no leakage, the gradient law σΦ.
        let o = c.law(&first_sample(), &NnState::zero(), &mut ds);
        close(ds.w[0], 49.348022, 1e-5);
        assert_eq!(o.parts.leak, 0.0);
    }

    /// Projection inside the ball: W = 0, T = 10⁻⁴: ‖W + Tτ‖ = 10⁻⁴·σ‖Φ‖
    /// = 10⁻⁴·49.348022·21.723834 = 0.1072 < 4, so Ẇ = τ = σΦ, leak 0.
    #[test]
    fn projection_idle_inside_the_ball() {
        let c = ctrl(WeightLaw::Projection, 1e-4);
        let mut ds = NnState::zero();
        let o = c.law(&first_sample(), &NnState::zero(), &mut ds);
        close(ds.w[0], 49.348022, 1e-5);
        close(ds.w[129], -1068.2102, 1e-3);
        assert_eq!(o.parts.leak, 0.0);
    }

    /// Projection on the sphere: W[0] = Wmax = 4, T = 0.01. y = W + Tτ:
    /// y[0] = 4 + 0.01σ = 4.4934802, the rest 0.01σΦ_k, so
    /// ‖y‖² = 4.4934802² + (0.01σ)²(‖Φ‖² − 1) = 20.191365 + 0.24352273·470.92496
    /// = 134.87230, ‖y‖ = 11.613453, s = 4/‖y‖ = 0.34442813.
    /// Ẇ[0] = (s·y[0] − 4)/T = −245.23190; Ẇ[129] = s·σ·θ⃛d = −367.92165;
    /// leak = ‖Ẇ − τ‖ = (1 − s)‖y‖/T = (‖y‖ − 4)/T = 761.34532.
    /// And the Euler step lands on the sphere: ‖W + T·Ẇ‖ = 4.
    #[test]
    fn projection_derivative_by_hand() {
        let c = ctrl(WeightLaw::Projection, 0.01);
        let s = bias_state(4.0);
        let mut ds = NnState::zero();
        let o = c.law(&first_sample(), &s, &mut ds);
        close(ds.w[0], -245.23190, 1e-4);
        close(ds.w[129], -367.92165, 1e-4);
        close(o.parts.leak, 761.34532, 1e-4);
        let mut next = s;
        next.axpy(0.01, &ds);
        close(crate::math::norm(&next.w), 4.0, 1e-12);
    }

    #[test]
    fn rejects_bad_gains() {
        let mut cfg = NnRobustConfig::default();
        let d = Design {
            model: NominalModel::new(ServoParams::paper(), Load::paper()),
            surface: SwitchingSurface::paper(),
            dt: 0.01,
        };
        assert!(cfg.build(&d).is_ok());
        cfg.sigma_mod = -1.0;
        assert_eq!(cfg.build(&d).unwrap_err().name, "sigma_mod");
        cfg.sigma_mod = 0.25;
        cfg.nu = f64::NAN;
        assert_eq!(cfg.build(&d).unwrap_err().name, "nu");
        cfg.nu = 0.25;
        cfg.weight_law = WeightLaw::Projection;
        cfg.w_max = 0.0;
        assert_eq!(cfg.build(&d).unwrap_err().name, "w_max");
        cfg.w_max = 4.0;
        cfg.gamma1 = 0.0;
        assert_eq!(cfg.build(&d).unwrap_err().name, "gamma1");
    }

    #[test]
    fn signals_are_the_nnvscs_and_leak() {
        let s = <RobustParts as Signals>::SIGNALS;
        assert_eq!(s.len(), <SlidingParts as Signals>::SIGNALS.len() + 1);
        assert_eq!(s[2].key, "sigma");
        assert_eq!(s[s.len() - 1].key, "leak");
        let p = RobustParts {
            sliding: SlidingParts {
                u_eq: 1.0,
                ..SlidingParts::default()
            },
            leak: 7.0,
        };
        let mut out = [0.0; 17];
        p.write(&mut out);
        assert_eq!((out[0], out[16]), (1.0, 7.0));
    }
}
