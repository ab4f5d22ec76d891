//! The RBF-network-based VSC of Theorem 3 (NNBVSC).
//!
//! ```text
//! u    = u_eq + u_sw                                                   (23)
//! u_eq = {θ⃛d + ā1x1 + ā2x2 + ā3x3 + p1(θ̈d − x3) + p2(θ̇d − x2)
//!         + p3(θd − x1) + WᵀΦ(x, z)}/b̄                                 (24)
//! u_sw = {γ1·σΔ + γ2·σΔ/(|σΔ| + μ)}/(b̄ − β)                            (25)
//! Ẇ    = H⁻¹·(σΔ·Φ − η·|σΔ|·W)                                         (26)
//! σΔ   = σ − Δ·sgn(σ) if |σ| > Δ = ᾱ‖E‖, else 0                         (27)
//! γ2   = η·W²max/4 + ε0‖Φ‖ + ε1 + ε2                                    (34)
//! μ    = (α − ᾱ)·‖E‖·ε2/c,  c = η·W²max/4 + ε0‖Φ‖ + ε1                 (SPEC §5)
//! ```
//!
//! Φ is the 130-entry vector of (20) ([`crate::rbf`]), β = bound_b·b̄,
//! H = h·I. The printed (33) is garbled (read literally μ < 0); SPEC §5 takes
//! the μ that Remark 7 back-solves from (29)–(30), which sits on the bound
//! (32). ξ = ᾱ·EᵀĖ·sgn(σ)/‖E‖ is not part of the law; it is returned for the
//! learning target of (19), plotted in Fig. 2(d).
//!
//! **‖E‖ = 0.** Then Δ = μ = 0 and ξ would divide by zero: the law sets
//! σΔ = μ = ξ = 0 (no switching, no learning) and raises
//! [`flags::ZERO_ERROR_NORM`](crate::control::flags::ZERO_ERROR_NORM).
//! Whenever |σΔ| + μ = 0 the switching fraction is 0, never 0/0.
//!
//! Paper's Fig. 2 values ([`NnVscParams::paper`]): γ1 = 100, η = 0.25,
//! ᾱ = 5, α = 250, Wmax = 4, ε0 = ε1 = 0.1, ε2 = 0.01, h = 1, bound_b = 0.5.
//!
//! The rooms: this file holds the gains, the state, the controller and its
//! [`Controller`] face; `nnvsc/law.rs` the law above, as the equations read;
//! `nnvsc/fast.rs` the fused, dispatched and vector forms that compute the
//! same bits faster (held to the law by `law_euler_is_law_then_euler_to_the_bit`).

mod fast;
mod law;

use super::sliding::SlidingParts;
use super::{Controller, Measurement, Output, Truth};
use crate::error::{non_negative, positive, ParamError};
use crate::math::Real;
use crate::rbf::{Rbf, N_PHI};
use crate::rk4::OdeState;
use crate::servo::NominalModel;
use crate::surface::SwitchingSurface;
use fast::one_pass;

/// How the boundary layer μ(t) of (25) is computed.
///
/// ```
/// use ehservo_core::control::nnvsc::MuRule;
///
/// // As a scenario writes `controller.mu_rule`.
/// assert_eq!(MuRule::parse("literal-33"), Some(MuRule::Literal33));
/// assert_eq!(MuRule::Remark7.as_str(), "remark7");
/// assert_eq!(MuRule::parse("Remark7"), None);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MuRule {
    /// SPEC §5: μ = (α − ᾱ)‖E‖·ε2/c, the value Remark 7 back-solves from
    /// (29)–(30); it sits exactly on the bound (32). The default.
    Remark7,
    /// The printed (33) read literally: μ = (α − ᾱ)‖E‖·{(γ2 − c)/c − 1},
    /// which is negative (γ2 − c = ε2 ≪ c). Kept only to measure what the
    /// erratum would do; |σΔ| + μ can then vanish or change sign.
    Literal33,
    /// μ = 0: the γ2 term becomes γ2·sgn(σΔ) (a discontinuous switching).
    Zero,
}

impl MuRule {
    /// The scenario spelling (`controller.mu_rule`).
    pub const fn as_str(&self) -> &'static str {
        match self {
            MuRule::Remark7 => "remark7",
            MuRule::Literal33 => "literal-33",
            MuRule::Zero => "zero",
        }
    }

    /// From the scenario spelling.
    pub fn parse(s: &str) -> Option<Self> {
        [MuRule::Remark7, MuRule::Literal33, MuRule::Zero]
            .into_iter()
            .find(|r| r.as_str() == s)
    }
}

/// Gains of the NNBVSC.
///
/// ```
/// use ehservo_core::control::nnvsc::NnVscParams;
///
/// let p = NnVscParams::paper();
/// assert!(p.validate().is_ok());
/// // Theorem 3 needs 0 ≤ ᾱ < α.
/// let bad = NnVscParams { alpha_bar: 300.0, ..p };
/// assert_eq!(bad.validate().unwrap_err().name, "alpha_bar");
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NnVscParams<T = f64> {
    /// γ1 > 0, the linear switching gain.
    pub gamma1: T,
    /// η ≥ 0, the revised ε-modification gain.
    pub eta: T,
    /// α > ᾱ, the exponential-tracking rate parameter of Theorem 2.
    pub alpha: T,
    /// ᾱ ≥ 0, the dead-zone slope.
    pub alpha_bar: T,
    /// Wmax ≥ 0, the assumed bound on ‖W̄‖ (21).
    pub w_max: T,
    /// ε0 ≥ 0 of (22).
    pub eps0: T,
    /// ε1 ≥ 0 of (22).
    pub eps1: T,
    /// ε2 > 0 of (34).
    pub eps2: T,
    /// h > 0, H = h·I in (26).
    pub h: T,
    /// β = bound_b·b̄, 0 ≤ bound_b < 1.
    pub bound_b: T,
    /// The boundary-layer rule (SPEC §5 by default).
    pub mu_rule: MuRule,
}

impl NnVscParams<f64> {
    /// The Fig. 2 values.
    pub const fn paper() -> Self {
        Self {
            gamma1: 100.0,
            eta: 0.25,
            alpha: 250.0,
            alpha_bar: 5.0,
            w_max: 4.0,
            eps0: 0.1,
            eps1: 0.1,
            eps2: 0.01,
            h: 1.0,
            bound_b: 0.5,
            mu_rule: MuRule::Remark7,
        }
    }
}

impl<T: Real> NnVscParams<T> {
    /// The same gains in another float type.
    pub fn cast<U: Real>(&self) -> NnVscParams<U> {
        let c = |v: T| U::of(v.to_f64());
        NnVscParams {
            gamma1: c(self.gamma1),
            eta: c(self.eta),
            alpha: c(self.alpha),
            alpha_bar: c(self.alpha_bar),
            w_max: c(self.w_max),
            eps0: c(self.eps0),
            eps1: c(self.eps1),
            eps2: c(self.eps2),
            h: c(self.h),
            bound_b: c(self.bound_b),
            mu_rule: self.mu_rule,
        }
    }

    /// Checks every gain; the error names the first one that is wrong.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("gamma1", self.gamma1)?;
        non_negative("eta", self.eta)?;
        positive("alpha", self.alpha)?;
        non_negative("alpha_bar", self.alpha_bar)?;
        if self.alpha_bar >= self.alpha {
            return Err(ParamError::new(
                "alpha_bar",
                "must be < alpha (Theorem 3: 0 ≤ ᾱ < α)",
                self.alpha_bar.to_f64(),
            ));
        }
        non_negative("w_max", self.w_max)?;
        non_negative("eps0", self.eps0)?;
        non_negative("eps1", self.eps1)?;
        positive("eps2", self.eps2)?;
        positive("h", self.h)?;
        non_negative("bound_b", self.bound_b)?;
        if self.bound_b >= T::ONE {
            return Err(ParamError::new(
                "bound_b",
                "must be < 1 (Assumption A1: β < b̄)",
                self.bound_b.to_f64(),
            ));
        }
        // c = ηW²/4 + ε0‖Φ‖ + ε1 ≥ ηW²/4 + ε0 + ε1 (‖Φ‖ ≥ 1): μ divides by it.
        if self.eta * self.w_max * self.w_max / T::of(4.0) + self.eps0 + self.eps1 <= T::ZERO {
            return Err(ParamError::new(
                "eps1",
                "η·Wmax²/4 + ε0 + ε1 must be > 0 (μ(t) divides by it)",
                self.eps1.to_f64(),
            ));
        }
        Ok(())
    }
}

/// The NNBVSC state: ∫e and the 130 weights (`W[0]` is the bias weight, the
/// paper's w_1 is `W[1]`, w_128 is `W[128]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NnState<T = f64> {
    /// ∫e.
    pub int_e: T,
    /// Connection weights W.
    pub w: [T; N_PHI],
}

impl<T: Real> OdeState<T> for NnState<T> {
    #[inline]
    fn zero() -> Self {
        Self {
            int_e: T::ZERO,
            w: [T::ZERO; N_PHI],
        }
    }
    #[inline]
    fn axpy(&mut self, a: T, o: &Self) {
        self.int_e += a * o.int_e;
        self.w.axpy(a, &o.w);
    }
    #[inline]
    fn set_axpy(&mut self, base: &Self, a: T, o: &Self) {
        self.int_e = base.int_e + a * o.int_e;
        self.w.set_axpy(&base.w, a, &o.w);
    }
    #[inline]
    fn all_finite(&self) -> bool {
        // 0·v is ±0 for a finite v and NaN for ±∞ or NaN, so the sum is NaN
        // exactly when some entry is not finite. Branch-free, in eight lanes
        // (four SIMD pairs, short addition chains); 130 tests with a branch
        // each cost as much as the rest of the hardware step's bookkeeping.
        let mut lane = [T::ZERO; 8];
        for chunk in self.w.chunks_exact(8) {
            for (l, &v) in lane.iter_mut().zip(chunk) {
                *l += T::ZERO * v;
            }
        }
        let mut sum = T::ZERO * self.int_e;
        for &v in &self.w[N_PHI - N_PHI % 8..] {
            sum += T::ZERO * v;
        }
        for l in lane {
            sum += l;
        }
        sum.is_finite()
    }
    #[inline]
    fn axpy_finite(&mut self, a: T, o: &Self) -> bool {
        let v = self.int_e + a * o.int_e;
        if v.is_finite() && crate::rk4::axpy_results_finite(&self.w, a, &o.w) {
            self.int_e = v;
            self.w.axpy(a, &o.w);
            true
        } else {
            false
        }
    }
    #[inline(always)]
    fn euler_from(&mut self, base: &Self, a: T) -> bool {
        self.int_e = base.int_e + a * self.int_e;
        let w_ok = crate::rk4::euler_results_finite(&mut self.w, &base.w, a);
        w_ok && self.int_e.is_finite()
    }
}

/// The NNBVSC of Theorem 3; in a scenario, `kind = "nnvsc"`
/// ([`NnVscConfig`](super::sliding::NnVscConfig)).
///
/// ```
/// use ehservo_core::prelude::*;
///
/// let model = NominalModel::new(ServoParams::paper(), Load::paper());
/// let nn = NnVsc::try_new(model, SwitchingSurface::paper(), NnVscParams::paper(), Rbf::paper())?;
/// // On the reference at rest, ‖E‖ = 0: no switching, no learning, flagged.
/// let m = Measurement::default();
/// let (s, mut ds) = (NnState::zero(), NnState::zero());
/// let out = nn.law(&m, &s, &mut ds);
/// assert_eq!(out.u, 0.0);
/// assert_ne!(out.flags & ehservo_core::control::flags::ZERO_ERROR_NORM, 0);
/// assert!(ds.w.iter().all(|&w| w == 0.0));
/// // The same law in f32, for a board.
/// let board: NnVsc<f32> = nn.cast()?;
/// assert_eq!(board.params().gamma1, 100.0f32);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NnVsc<T: Real = f64> {
    model: NominalModel<T>,
    surface: SwitchingSurface<T>,
    params: NnVscParams<T>,
    rbf: Rbf<T>,
    c_fixed: T,
    b_floor: T,
    /// α − ᾱ (in μ).
    alpha_gap: T,
    /// 1/h (H⁻¹ in (26)).
    inv_h: T,
    /// 1 − bound_b (b̄ − β = b̄·(1 − bound_b)).
    one_minus_bb: T,
}

impl<T: Real> NnVsc<T> {
    /// Validates the gains and builds the controller.
    pub fn try_new(
        model: NominalModel<T>,
        surface: SwitchingSurface<T>,
        params: NnVscParams<T>,
        rbf: Rbf<T>,
    ) -> Result<Self, ParamError> {
        params.validate()?;
        Ok(Self {
            model,
            surface,
            rbf,
            c_fixed: params.eta * params.w_max * params.w_max / T::of(4.0) + params.eps1,
            b_floor: T::of(1e-3) * model.b_at_rest(),
            alpha_gap: params.alpha - params.alpha_bar,
            inv_h: T::ONE / params.h,
            one_minus_bb: T::ONE - params.bound_b,
            params,
        })
    }

    /// The same controller in another float type: model, surface, gains
    /// and network cast, and its constants recomputed in `U`.
    pub fn cast<U: Real>(&self) -> Result<NnVsc<U>, ParamError> {
        NnVsc::try_new(
            self.model.cast(),
            self.surface.cast(),
            self.params.cast(),
            self.rbf.cast()?,
        )
    }

    /// The gains.
    pub fn params(&self) -> &NnVscParams<T> {
        &self.params
    }

    /// The network.
    pub fn rbf(&self) -> &Rbf<T> {
        &self.rbf
    }

    /// The switching surface.
    pub fn surface(&self) -> &SwitchingSurface<T> {
        &self.surface
    }

    /// The nominal model.
    pub fn model(&self) -> &NominalModel<T> {
        &self.model
    }
}

impl<T: Real> Controller<T> for NnVsc<T> {
    type State = NnState<T>;
    type Parts = SlidingParts<T>;

    fn initial_state(&self) -> NnState<T> {
        NnState::zero()
    }

    // (Not inlined: the body is large, and a caller's loop compiled worse
    // around it, +300 instructions a law in `step_count`.)
    #[inline(never)]
    fn law(
        &self,
        m: &Measurement<T>,
        s: &NnState<T>,
        ds: &mut NnState<T>,
    ) -> Output<SlidingParts<T>, T> {
        // On an x86-64 with AVX2 and FMA, the body compiled for them (see
        // `law_euler`).
        #[cfg(all(any(test, feature = "std"), target_arch = "x86_64"))]
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports AVX2 and FMA (detected just above).
            #[allow(unsafe_code)]
            return unsafe { self.law_avx2(m, s, ds) };
        }
        self.law_baseline(m, s, ds)
    }

    /// The law and the Euler step, with no zeroed ξ̇ buffer (the law writes
    /// every component). On Arm (a Cortex-M: in order, no SIMD) in one
    /// pass: ξ + dt·ξ̇ is written as ξ̇'s components are formed, each
    /// weight loaded once (−320 instructions a step on a Cortex-M4F).
    /// Elsewhere the law's passes and a vectorised Euler pass (the one
    /// pass, scalar, cost an x86-64 host 7 % more instructions); on an
    /// x86-64 with AVX2 and FMA (detected at run time, with `std`) that
    /// code compiled for them, since the default x86-64 target has only
    /// SSE2 (−30 % instructions a sampled step; with the exponentials in
    /// one vector, −6 % more). All give the same bits; f32 always takes
    /// the one pass, whose weight update is folded ([`Real::FOLDED_EULER`]).
    #[inline]
    fn law_euler(
        &self,
        m: &Measurement<T>,
        s: &NnState<T>,
        next: &mut NnState<T>,
        dt: T,
    ) -> (Output<SlidingParts<T>, T>, bool) {
        if one_pass::<T>() {
            self.law_euler_one_pass(m, s, next, dt)
        } else {
            #[cfg(all(any(test, feature = "std"), target_arch = "x86_64"))]
            if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
                // SAFETY: the CPU supports AVX2 and FMA (detected just above).
                #[allow(unsafe_code)]
                return unsafe { self.law_then_euler_avx2(m, s, next, dt) };
            }
            self.law_then_euler_baseline(m, s, next, dt)
        }
    }

    fn weights<'a>(&self, s: &'a NnState<T>) -> &'a [T] {
        &s.w
    }

    fn annotate(&self, s: &NnState<T>, out: &mut Output<SlidingParts<T>, T>, truth: &dyn Truth) {
        SlidingParts::annotate(out, &s.w, truth);
    }

    /// ‖W‖ was computed by `law_euler` beside its Euler pass, except in
    /// the one-pass form (`one_pass`), where it is computed here as
    /// `annotate` does.
    #[inline]
    fn annotate_stepped(
        &self,
        s: &NnState<T>,
        out: &mut Output<SlidingParts<T>, T>,
        truth: &dyn Truth,
    ) {
        if one_pass::<T>() {
            SlidingParts::annotate(out, &s.w, truth);
        } else {
            SlidingParts::annotate_but_norm(out, &s.w, truth);
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use crate::control::flags;
    use crate::reference::{Reference, Sine};
    use crate::servo::{Load, ServoParams};

    fn paper_nn(load: Load) -> NnVsc {
        NnVsc::try_new(
            NominalModel::new(ServoParams::paper(), load),
            SwitchingSurface::paper(),
            NnVscParams::paper(),
            Rbf::paper(),
        )
        .unwrap()
    }

    /// The first sample of the Fig. 2 run, by hand. x = 0, W = 0, ∫e = 0,
    /// t = 0: z = (0, A·2π, 0, −A·(2π)³) with A = 5° = 0.08726646 rad, so
    /// θ̇d = 0.54831136, θ⃛d = −21.6464647.
    /// e = 0, ė = 0.54831136, ë = 0 → σ = 90·0.54831136 = 49.348022;
    /// ‖E‖ = 0.54831136; Δ = 5·‖E‖ = 2.7415568; σΔ = 46.606465.
    /// Φ at x = 0: the 125 Gaussians are exp(−r²/0.25) over the grid, and
    /// Σφ² factors per axis: (Σ_l exp(−2l²/0.25))³ over l ∈ {−1,−.5,0,.5,1}
    /// = (1 + 2e^−2 + 2e^−8)³ = 1.2713415³ = 2.0548809; plus 1 (bias) and
    /// z·z = 0.3006453 + 468.56943 → ‖Φ‖² = 471.92496, ‖Φ‖ = 21.723834.
    /// c = 0.25·4²/4 + 0.1·21.723834 + 0.1 = 3.2723834; γ2 = 3.2823834;
    /// μ = (250 − 5)·0.54831136·0.01/3.2723834 = 0.4105151.
    /// sw = 100·46.606465 + 3.2823834·46.606465/(46.606465 + 0.4105151)
    ///    = 4660.6465 + 3.2537242 = 4663.9002;
    /// N = θ⃛d + p2·θ̇d = −21.6464647 + 2600·0.54831136 = 1403.96306;
    /// v = N + sw/0.5 = 10731.7636 > 0, so b̄ = b(0, +) = 17911.7547 (Pl = 0);
    /// u_eq = 1403.96306/17911.7547 = 0.0783822; u_sw = 9327.8005/17911.7547
    /// = 0.5207642; u = 0.5991464.
    /// Ẇ[0] = σΔ·1 = 46.606465 (W = 0, so no η term); Ẇ[129] = σΔ·θ⃛d
    /// = −1008.8652.
    #[test]
    fn first_sample_of_fig2_by_hand() {
        let c = paper_nn(Load::paper());
        let m = Measurement {
            t: 0.0,
            x: [0.0; 3],
            z: Sine::paper().z(0.0),
        };
        let mut ds = NnState::zero();
        let o = c.law(&m, &NnState::zero(), &mut ds);
        let close = |a: f64, b: f64, tol: f64| assert!((a - b).abs() < tol, "{a} vs {b}");
        close(o.sigma, 49.348022, 1e-5);
        close(o.sigma_delta, 46.606465, 1e-5);
        close(o.phi_norm, 21.723834, 1e-5);
        close(o.gain, 3.2823834, 1e-6);
        close(o.mu, 0.4105151, 1e-6);
        close(o.u_eq, 0.0783822, 1e-6);
        close(o.u_sw, 0.5207642, 1e-6);
        close(o.u, 0.5991464, 1e-6);
        close(ds.w[0], 46.606465, 1e-5);
        close(ds.w[129], -1008.8652, 1e-3);
        assert_eq!(o.wphi, 0.0);
        assert_eq!(ds.int_e, 0.0);
    }

    /// NnState's set_axpy (the continuous mode's RK4 stages) gives the
    /// bits of a copy and axpy in every field.
    #[test]
    fn nn_state_set_axpy_is_copy_then_axpy() {
        let base = NnState {
            int_e: -0.0,
            w: core::array::from_fn(|i| (i as f64 - 60.0) * 0.37),
        };
        let o = NnState {
            int_e: 2.5,
            w: core::array::from_fn(|i| {
                if i == 77 {
                    f64::INFINITY
                } else {
                    1.0 / (1.0 + i as f64)
                }
            }),
        };
        let mut want = base;
        want.axpy(0.005, &o);
        let mut got = NnState {
            int_e: f64::NAN,
            w: [f64::NAN; N_PHI],
        };
        got.set_axpy(&base, 0.005, &o);
        assert_eq!(got.int_e.to_bits(), want.int_e.to_bits());
        assert_eq!(got.w.map(f64::to_bits), want.w.map(f64::to_bits));
    }

    /// Inside the dead zone (|σ| ≤ ᾱ‖E‖) σΔ = 0 exactly: no learning, no
    /// switching, u = u_eq. Here ∫e = 0.01 makes ‖E‖ ≥ 0.01 while σ = 0
    /// by choice of ë: x = 0, z = (0, 0, θ̈d, 0) with
    /// σ = θ̈d + p3·0.01 = 0 → θ̈d = −240.
    #[test]
    fn dead_zone_is_exact() {
        let c = paper_nn(Load::none());
        let m = Measurement {
            t: 0.0,
            x: [0.0; 3],
            z: [0.0, 0.0, -240.0, 0.0],
        };
        let s = NnState {
            int_e: 0.01,
            w: [0.3; N_PHI],
        };
        let mut ds = NnState::zero();
        let o = c.law(&m, &s, &mut ds);
        assert_eq!(o.sigma, 0.0);
        assert_eq!(o.sigma_delta, 0.0);
        assert_eq!(o.u_sw, 0.0);
        assert_eq!(o.u, o.u_eq);
        assert!(ds.w.iter().all(|&d| d == 0.0));
    }

    /// The literal (33) is negative: for the first Fig. 2 sample (see above)
    /// μ = 245·0.54831136·(0.01/3.2723834 − 1) = −133.93, against the
    /// default 0.4105151.
    #[test]
    fn literal_33_is_negative() {
        let p = NnVscParams {
            mu_rule: MuRule::Literal33,
            ..NnVscParams::paper()
        };
        let c = NnVsc::try_new(
            NominalModel::new(ServoParams::paper(), Load::paper()),
            SwitchingSurface::paper(),
            p,
            Rbf::paper(),
        )
        .unwrap();
        let m = Measurement {
            t: 0.0,
            x: [0.0; 3],
            z: Sine::paper().z(0.0),
        };
        let o = c.law(&m, &NnState::zero(), &mut NnState::zero());
        assert!((o.mu + 133.93).abs() < 0.01, "{}", o.mu);
    }

    /// ‖E‖ = 0: no division, σΔ = μ = ξ = 0, flag raised, u finite.
    #[test]
    fn zero_error_norm_is_guarded() {
        let c = paper_nn(Load::paper());
        let m = Measurement {
            t: 0.0,
            x: [0.0, 0.0, 1.0],
            z: [0.0, 0.0, 0.0, 0.0],
        };
        let o = c.law(&m, &NnState::zero(), &mut NnState::zero());
        assert_eq!(o.norm_e, 0.0);
        assert_eq!(o.sigma_delta, 0.0);
        assert_eq!(o.mu, 0.0);
        assert_eq!(o.xi, 0.0);
        assert!(o.u.is_finite());
        assert_ne!(o.flags & flags::ZERO_ERROR_NORM, 0);
    }

    /// The ε-modification pulls W toward 0: with Φ's direction removed
    /// (compare two weight vectors), Ẇ(W) − Ẇ(0) = −η|σΔ|W/h.
    #[test]
    fn epsilon_modification_sign() {
        let c = paper_nn(Load::paper());
        let m = Measurement {
            t: 0.0,
            x: [0.0; 3],
            z: Sine::paper().z(0.0),
        };
        let mut d0 = NnState::zero();
        let mut d1 = NnState::zero();
        let mut s1 = NnState::zero();
        s1.w[5] = 2.0;
        let o = c.law(&m, &NnState::zero(), &mut d0);
        let _ = c.law(&m, &s1, &mut d1);
        // σΔ does not depend on W, so the difference is −0.25·|σΔ|·2.
        let expect = -0.25 * o.sigma_delta.abs() * 2.0;
        assert!((d1.w[5] - d0.w[5] - expect).abs() < 1e-9);
    }

    /// The branch-free finiteness test agrees with the entry-by-entry one.
    #[test]
    fn state_finiteness() {
        let mut s = NnState::zero();
        assert!(s.all_finite());
        s.w = [1e300; N_PHI];
        assert!(s.all_finite());
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for k in [0, 1, 63, 127, 128, 129] {
                let mut t = NnState::zero();
                t.w[k] = bad;
                assert!(!t.all_finite(), "{bad} at {k}");
            }
            let t = NnState {
                int_e: bad,
                w: [0.0; N_PHI],
            };
            assert!(!t.all_finite());
        }
    }

    #[test]
    fn rejects_bad_gains() {
        let bad = |p: NnVscParams| {
            NnVsc::try_new(
                NominalModel::new(ServoParams::paper(), Load::paper()),
                SwitchingSurface::paper(),
                p,
                Rbf::paper(),
            )
            .unwrap_err()
            .name
        };
        let p = NnVscParams::paper();
        assert_eq!(bad(NnVscParams { gamma1: 0.0, ..p }), "gamma1");
        assert_eq!(
            bad(NnVscParams {
                alpha_bar: 250.0,
                ..p
            }),
            "alpha_bar"
        );
        assert_eq!(bad(NnVscParams { eps2: 0.0, ..p }), "eps2");
        assert_eq!(bad(NnVscParams { eta: f64::NAN, ..p }), "eta");
        assert_eq!(
            bad(NnVscParams {
                eta: 0.0,
                eps0: 0.0,
                eps1: 0.0,
                ..p
            }),
            "eps1"
        );
    }

    /// law_euler (and the one pass) is law + euler_from to the bit,
    /// in f64 and f32, with weights of both signs; its finiteness verdict
    /// too: an overflowing sum of finite results is still finite, an
    /// overflowing weight is not. For f32 (`Real::FOLDED_EULER`) the one
    /// pass and law_euler give the law's outputs to the bit and each
    /// weight within the rounding of the two orders of w + dt·(A − B),
    /// A = a·Φᵢ, B = bw·wᵢ: each form rounds at most six times (dt·a or
    /// a·g1g2, ·g3, dt·bw or bw·w, its product, the difference, the sum),
    /// each by at most u = 2⁻²⁴ of a term no larger than |w| + |dt·A| +
    /// |dt·B| to first order, so the two differ by at most 12u times that;
    /// 16u is allowed.
    #[test]
    fn law_euler_is_law_then_euler_to_the_bit() {
        fn check<T: Real>(c: &NnVsc<T>, dt: T, s: &NnState<T>, m: &Measurement<T>) -> bool {
            let mut ds = NnState::zero();
            let o = c.law(m, s, &mut ds);
            let ds_law = ds;
            let ok = ds.euler_from(s, dt);
            let bits = |o: &Output<SlidingParts<T>, T>| {
                let p = &o.parts;
                [o.u, p.u_eq, p.u_sw, p.wphi, p.sigma_delta, p.b_bar]
                    .into_iter()
                    .chain([p.phi_norm, p.mu, p.xi, p.gain, p.norm_e])
                    .map(|v| v.to_f64().to_bits())
                    .collect::<Vec<_>>()
            };
            let state_bits = |x: &NnState<T>| {
                core::iter::once(x.int_e)
                    .chain(x.w)
                    .map(|v| v.to_f64().to_bits())
                    .collect::<Vec<_>>()
            };
            // `law` on this target (on an x86-64 with AVX2 and FMA: that
            // copy) is the plain body to the bit. (Both take Φ's
            // exponentials from `Real::exp4`; that it gives `exp`'s bits is
            // exp4's own test, and the golden runs' in `crates/ehservo`.)
            let mut ds_plain = NnState::zero();
            let o_plain = c.law_body(m, s, &mut ds_plain);
            assert_eq!((bits(&o), o.flags), (bits(&o_plain), o_plain.flags));
            assert_eq!(state_bits(&ds_law), state_bits(&ds_plain));
            // The one pass (a Cortex-M's), law_euler on this target (on an
            // x86-64 with AVX2 and FMA: that copy) and the plain two passes.
            for variant in 0..3 {
                let mut next = NnState::zero();
                let (o2, ok2) = match variant {
                    0 => c.law_euler_one_pass(m, s, &mut next, dt),
                    1 => c.law_euler(m, s, &mut next, dt),
                    _ => c.law_then_euler(m, s, &mut next, dt),
                };
                assert_eq!((bits(&o), o.flags), (bits(&o2), o2.flags));
                if variant == 2 || (variant == 1 && !one_pass::<T>()) {
                    // law_euler's ‖W‖ is `annotate`'s to the bit (the one
                    // pass leaves it to `annotate_stepped`).
                    let n = crate::math::norm(&s.w);
                    assert_eq!(o2.parts.w_norm.to_f64().to_bits(), n.to_f64().to_bits());
                }
                assert_eq!(ok, ok2);
                if T::FOLDED_EULER && variant < 2 {
                    assert_eq!(next.int_e.to_f64().to_bits(), ds.int_e.to_f64().to_bits());
                    // |dt·B| = dt·η|σΔ|/h·|w|, and |dt·A| = |dt·ẇ + dt·B|.
                    let p = c.params();
                    let sd = o.parts.sigma_delta.to_f64();
                    let (dt, h) = (dt.to_f64(), p.h.to_f64());
                    let u = f64::from(f32::EPSILON) / 2.0;
                    for i in 0..N_PHI {
                        let w = s.w[i].to_f64();
                        let db = dt * p.eta.to_f64() * sd.abs() / h * w.abs();
                        let da = (dt * ds_law.w[i].to_f64()).abs() + db;
                        let tol = 16.0 * u * (w.abs() + da + db);
                        let diff = (next.w[i].to_f64() - ds.w[i].to_f64()).abs();
                        assert!(diff <= tol, "w[{i}]: {diff:e} > {tol:e}");
                    }
                } else {
                    assert_eq!(state_bits(&next), state_bits(&ds));
                }
            }
            ok
        }
        let c = paper_nn(Load::paper());
        let c32 = c.cast::<f32>().unwrap();
        let r = Sine::paper();
        for k in 0..40 {
            let t = 0.013 * f64::from(k);
            let x = [0.02 * (t * 3.0).sin(), 0.3 * t.cos(), -5.0 + 0.7 * t];
            let m = Measurement { t, x, z: r.z(t) };
            let mut s = NnState::zero();
            s.int_e = 1e-3 * t;
            for (i, w) in s.w.iter_mut().enumerate() {
                *w = (i as f64 * 0.37 + t).sin() * 0.8;
            }
            assert!(check(&c, 1e-4, &s, &m));
            let m32 = Measurement {
                t: t as f32,
                x: x.map(|v| v as f32),
                z: m.z.map(|v| v as f32),
            };
            let s32 = NnState {
                int_e: s.int_e as f32,
                w: s.w.map(|v| v as f32),
            };
            assert!(check(&c32, 1e-4f32, &s32, &m32));
            // Finite results whose sum overflows (26 of 1e307 a lane; at
            // t = 0, x = 0, η|σΔ| = 11.7, so η|σΔ|·W stays finite): finite.
            let big = NnState {
                int_e: 0.0,
                w: [1e307; N_PHI],
            };
            let m0 = Measurement {
                t: 0.0,
                x: [0.0; 3],
                z: r.z(0.0),
            };
            assert!(check(&c, 1e-12, &big, &m0));
            // A result that overflows (dt·Ẇ[129] = 1e306·σΔ·θ⃛d): not finite.
            assert!(!check(&c, 1e306, &s, &m0));
        }
    }
}
