//! Estimators of what the loop does not measure: the state
//! `x = (θ, θ̇, θ̈)` of the third-order servo from the measured angle `θ`
//! alone, run once per sample period `h` at the controller's rate.
//!
//! | type | what it is | model it needs |
//! |---|---|---|
//! | [`Levant`] | Levant's robust exact differentiator of order 2 (sliding-mode, finite-time exact without noise) | none: only `L ≥ sup|θ⃛|` |
//! | [`LinearObserver`] | a linear observer on the discretised nominal model, in predictor/corrector ("current estimator") form; its gain is a Luenberger (pole placement) or a steady-state Kalman gain | `(Φ, Γ)` of the nominal linear model |
//!
//! Both implement [`Estimator`]. They are `Copy`, allocation-free and
//! `no_std`; parameters are validated once at construction with a
//! [`ParamError`] naming the parameter. The gains of the linear observer
//! are designed on the `std` side (`ehservo::observer_design`: matrix
//! exponential, Ackermann, discrete Riccati equation) and handed over as
//! plain arrays through [`LinearObserver::from_matrices`].

use crate::error::{finite, positive, ParamError};
use crate::math::{sgn, Real};

/// What the sampled loop needs of an estimator of `x = (θ, θ̇, θ̈)` from `θ`
/// alone.
///
/// ```
/// use ehservo_core::estimate::{Estimator, Levant};
///
/// // Any estimator, by its two calls: reset at the first angle, then one
/// // update per sample with the command applied over the period before.
/// fn estimate(e: &mut impl Estimator, thetas: &[f64]) -> [f64; 3] {
///     e.reset(thetas[0]);
///     thetas[1..].iter().fold([thetas[0], 0.0, 0.0], |_, &th| e.update(th, 0.0))
/// }
/// // A constant angle is estimated at rest.
/// let x = estimate(&mut Levant::try_new(10.0, 0.01)?, &[0.3; 50]);
/// assert_eq!(x, [0.3, 0.0, 0.0]);
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
pub trait Estimator<T: Real = f64> {
    /// Back to rest at the measured angle θ0 (θ̇ = θ̈ = 0).
    fn reset(&mut self, theta0: T);
    /// One update at t_k with the measured θ_k and the command u_prev that was
    /// applied over [t_{k−1}, t_k); returns the estimate (θ̂, θ̂̇, θ̂̈) at t_k.
    fn update(&mut self, theta: T, u_prev: T) -> [T; 3];
}

/// Levant's robust exact differentiator of order 2 (A. Levant, *Higher-order
/// sliding modes, differentiation and output-feedback control*, Int. J.
/// Control 76(9/10), 924–941, 2003, in its recursive form (the first-order
/// case is Levant, *Robust exact differentiation via sliding mode
/// technique*, Automatica 34(3), 1998)):
///
/// ```text
/// ż0 = v0,  v0 = −λ2·L^{1/3}·|z0 − f|^{2/3}·sgn(z0 − f) + z1
/// ż1 = v1,  v1 = −λ1·L^{1/2}·|z1 − v0|^{1/2}·sgn(z1 − v0) + z2
/// ż2 = −λ0·L·sgn(z2 − v1)
/// ```
///
/// with `f = θ` the measured signal and `L ≥ sup|f⃛|` (a Lipschitz constant
/// of `f̈`). Then `z0, z1, z2 → f, ḟ, f̈` in finite time and stay exact
/// without noise. The default parameters are `λ0 = 1.1, λ1 = 1.5, λ2 = 2`,
/// the first three of the sequence quoted for the recursive form
/// (1.1, 1.5, 2, 3, 5, 8, for orders up to 5). They agree with the
/// non-recursive form of Levant's later papers, whose order-2 gains are
/// `(λ̃2, λ̃1, λ̃0) = (2, 2.12, 1.1)` with `λ̃1 = λ1·λ2^{1/2} = 1.5·√2`.
/// (The 2003 text itself was not at hand when this was written; some
/// order-2 examples in the literature use `λ2 = 3`, which is
/// accepted through [`Levant::with_lambdas`].
///
/// **Choosing L.** `L` must bound `|θ⃛|` of the motion to be
/// differentiated: for the paper's reference `θ = 5°·sin(2πt)`,
/// `max|θ⃛| = 5°·(2π)³ ≈ 21.6 rad/s³`; take a margin (×1.5–2, e.g.
/// `L = 30..45`). A larger `L` converges faster but multiplies every
/// error: Levant's accuracy with sampling period `τ` is
/// `|z_i − f^{(i)}| ≤ μ_i·L·τ^{3−i}` (no noise), and with noise of
/// magnitude ε, `μ_i·L^{i/3}·ε^{(3−i)/3}` (Levant 2003, its accuracy theorem
/// for noisy measurements).
///
/// **Discretisation.** The proper discretisation of M. Livne and
/// A. Levant, *Proper discretization of homogeneous differentiators*,
/// Automatica 50(8), 2007–2014, 2014: forward Euler with step `τ` plus the
/// Taylor term `τ²/2·z2` in `z0`,
///
/// ```text
/// z0⁺ = z0 + τ·v0 + τ²/2·z2,   z1⁺ = z1 + τ·v1,   z2⁺ = z2 − τ·λ0·L·sgn(z2 − v1)
/// ```
///
/// with `v0, v1` evaluated at the sample `f(t_j)`. Plain Euler loses the
/// accuracy of the continuous differentiator (its `z1` lags by about
/// `τ/2`, an error `|f̈|·τ/2` that `L` does not bound: measured 0.032
/// rad/s at h = 0.01 on the sine of the tests); with the Taylor term
/// the sampled accuracy is `|z_i − f^{(i)}(t)| ≤ μ_i·L·τ^{3−i}` (Levant
/// 2003, for sampled measurements; Livne & Levant 2014).
///
/// By default `τ = h`, one step per sample (`substeps = 1`): each
/// [`Estimator::update`] at `t_k` advances `z` from `t_{k−1}` to `t_k`
/// with the previous sample `θ_{k−1}` and stores `θ_k` for the next one,
/// so the estimate at `t_k` is built from the samples up to `θ_{k−1}` (a
/// one-sample prediction, within the bound above). With `substeps = n > 1`
/// the period is split into `n` steps of `τ = h/n` and the input is the
/// straight line from `θ_{k−1}` to `θ_k` (first-order hold), evaluated at
/// each sub-step's start; this shrinks the chattering of `z2` (its step is
/// `λ0·L·τ`) and at coarse `h` the sampling error (measured on the sine,
/// h = 0.01: 0.0017 rad/s and 0.30 rad/s² with n = 10 against 0.020 and
/// 1.3 with n = 1), but the interpolated input is not the signal, so the
/// `τ^{3−i}` order no longer holds (at h = 1e-4 n = 10 is worse than
/// n = 1). Sub-steps do not filter noise. Holding the newest sample
/// instead (zero-order hold) makes `z` chase a staircase: measured `θ̇`
/// errors 3× (h = 0.01) to 70× (h = 1e-3) larger, of order h. The command `u_prev` is not used: the
/// differentiator is model-free.
///
/// ```
/// use ehservo_core::estimate::{Estimator, Levant};
///
/// // θ = 5°·sin(2πt), sampled at 1 kHz; L = 40 ≥ max|θ⃛| = A·ω³ ≈ 21.6.
/// let (a, w, h) = (5f64.to_radians(), 2.0 * std::f64::consts::PI, 1e-3);
/// let mut lev = Levant::try_new(40.0, h)?;
/// lev.reset(0.0);
/// let mut x = [0.0; 3];
/// for k in 1..=2000 {
///     x = lev.update(a * (w * k as f64 * h).sin(), 0.0);
/// }
/// // At t = 2 s, against the derivatives in closed form: θ̇ = Aω·cos ωt = Aω,
/// // to 0.1 % of it ...
/// assert!((x[1] - a * w).abs() < 1e-3 * a * w, "{x:?}");
/// // ... and θ̈ = −Aω²·sin ωt = 0, to 10 % of Aω² (z2 moves in steps of
/// // λ0·L·h = 1.1·40·1e-3 = 0.044 rad/s², a chattering of a few steps).
/// assert!(x[2].abs() < 0.1 * a * w * w, "{x:?}");
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Levant<T: Real = f64> {
    lipschitz: T,
    h: T,
    substeps: u32,
    lambda: [T; 3],
    // Derived: the Euler step and the gains λ2·L^{1/3}, λ1·L^{1/2}, λ0·L.
    tau: T,
    half_tau2: T,
    k: [T; 3],
    z: [T; 3],
    // The previous sample θ_{k−1}.
    last: T,
}

impl<T: Real> Levant<T> {
    /// The default number of Euler sub-steps per sample period.
    pub const DEFAULT_SUBSTEPS: u32 = 1;
    /// The default `[λ0, λ1, λ2]` = `[1.1, 1.5, 2]` (see the type's doc).
    pub fn default_lambdas() -> [T; 3] {
        [T::of(1.1), T::of(1.5), T::of(2.0)]
    }

    /// A differentiator at rest at 0 for signals with `|f⃛| ≤ lipschitz`,
    /// updated every `h` seconds, with the default λ and
    /// [`Levant::DEFAULT_SUBSTEPS`].
    pub fn try_new(lipschitz: T, h: T) -> Result<Self, ParamError> {
        positive("lipschitz", lipschitz)?;
        positive("h", h)?;
        let mut s = Self {
            lipschitz,
            h,
            substeps: Self::DEFAULT_SUBSTEPS,
            lambda: Self::default_lambdas(),
            tau: T::ZERO,
            half_tau2: T::ZERO,
            k: [T::ZERO; 3],
            z: [T::ZERO; 3],
            last: T::ZERO,
        };
        s.derive();
        Ok(s)
    }

    /// The same with `n ≥ 1` Euler sub-steps per period (the input
    /// linearly interpolated between samples; see the type's doc).
    pub fn with_substeps(mut self, n: u32) -> Result<Self, ParamError> {
        if n == 0 {
            return Err(ParamError::new("substeps", "must be >= 1", 0.0));
        }
        self.substeps = n;
        self.derive();
        Ok(self)
    }

    /// The same with `[λ0, λ1, λ2]` (each finite and > 0).
    pub fn with_lambdas(mut self, lambda: [T; 3]) -> Result<Self, ParamError> {
        positive("lambda0", lambda[0])?;
        positive("lambda1", lambda[1])?;
        positive("lambda2", lambda[2])?;
        self.lambda = lambda;
        self.derive();
        Ok(self)
    }

    fn derive(&mut self) {
        let l = self.lipschitz;
        self.tau = self.h / T::of_u32(self.substeps);
        self.half_tau2 = self.tau * self.tau / T::of(2.0);
        self.k = [
            self.lambda[2] * l.cbrt(),
            self.lambda[1] * l.sqrt(),
            self.lambda[0] * l,
        ];
    }

    /// `L`.
    pub fn lipschitz(&self) -> T {
        self.lipschitz
    }
    /// The sample period `h`.
    pub fn h(&self) -> T {
        self.h
    }
    /// Euler sub-steps per period.
    pub fn substeps(&self) -> u32 {
        self.substeps
    }
    /// `[λ0, λ1, λ2]`.
    pub fn lambdas(&self) -> [T; 3] {
        self.lambda
    }
    /// The current `(z0, z1, z2)`.
    pub fn state(&self) -> [T; 3] {
        self.z
    }

    /// One forward-Euler step of `tau` with the input `f`.
    #[inline]
    fn euler(&mut self, f: T) {
        let [z0, z1, z2] = self.z;
        let e0 = z0 - f;
        // |e0|^{2/3} = ∛(e0²).
        let v0 = -self.k[0] * (e0 * e0).cbrt() * sgn(e0) + z1;
        let e1 = z1 - v0;
        let v1 = -self.k[1] * e1.abs().sqrt() * sgn(e1) + z2;
        let d2 = -self.k[2] * sgn(z2 - v1);
        // Livne & Levant's Taylor term τ²/2·z2 in z0 (see the type's doc).
        self.z = [
            z0 + self.tau * v0 + self.half_tau2 * z2,
            z1 + self.tau * v1,
            z2 + self.tau * d2,
        ];
    }
}

impl<T: Real> Estimator<T> for Levant<T> {
    fn reset(&mut self, theta0: T) {
        self.z = [theta0, T::ZERO, T::ZERO];
        self.last = theta0;
    }

    fn update(&mut self, theta: T, _u_prev: T) -> [T; 3] {
        let n = T::of_u32(self.substeps);
        let df = theta - self.last;
        for j in 0..self.substeps {
            self.euler(self.last + df * (T::of_u32(j) / n));
        }
        self.last = theta;
        self.z
    }
}

/// A linear observer on the discretised nominal model
/// `x_k = Φ·x_{k−1} + Γ·u_{k−1}`, `θ_k = C·x_k` with `C = [1 0 0]` (exact
/// for a zero-order-held `u`), in predictor/corrector form — the "current
/// estimator" of G. F. Franklin, J. D. Powell, M. Workman, *Digital Control
/// of Dynamic Systems*, 3rd ed., 1998, §8.2:
///
/// ```text
/// x̄_k = Φ·x̂_{k−1} + Γ·u_{k−1}            (predict)
/// x̂_k = x̄_k + K·(θ_k − C·x̄_k)             (correct with the newest θ_k)
/// ```
///
/// so the estimate at `t_k` uses `θ_k`, and the error `e = x̂ − x` obeys
/// `e_k = (I − K·C)·Φ·e_{k−1} + K·v_k` for measurement noise `v`. The
/// eigenvalues of `(I − K·C)·Φ` (those of `Φ − K·C·Φ`) are the observer's
/// poles. The same form is the steady-state Kalman filter when
/// `K = P⁻·Cᵀ/(C·P⁻·Cᵀ + r)` with `P⁻` the a-priori covariance of the
/// discrete algebraic Riccati equation. For the servo, the load term `d`
/// and every model error are unmodelled disturbances: the estimate is
/// biased by them.
///
/// ```
/// use ehservo_core::estimate::{Estimator, LinearObserver};
///
/// // The triple integrator θ⃛ = u sampled at h, exactly (zero-order hold):
/// // Φ = [[1, h, h²/2], [0, 1, h], [0, 0, 1]], Γ = [h³/6, h²/2, h].
/// let h = 0.01;
/// let phi = [[1.0, h, h * h / 2.0], [0.0, 1.0, h], [0.0, 0.0, 1.0]];
/// let gamma = [h * h * h / 6.0, h * h / 2.0, h];
/// // The deadbeat gain: (I − KC)Φ is nilpotent for K = [1, 3/(2h), 1/h²]
/// // (its trace and determinant on the lower block vanish), so the
/// // estimate is exact from the third sample on.
/// let mut obs = LinearObserver::from_matrices(phi, gamma, [1.0, 1.5 / h, 1.0 / (h * h)])?;
/// obs.reset(0.0);
/// // u = 1 from rest: θ = t³/6, θ̇ = t²/2, θ̈ = t.
/// for k in 1..=5 {
///     let t = k as f64 * h;
///     let x = obs.update(t * t * t / 6.0, 1.0);
///     if k >= 3 {
///         assert!((x[1] - t * t / 2.0).abs() < 1e-12 && (x[2] - t).abs() < 1e-9, "{k}: {x:?}");
///     }
/// }
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearObserver<T: Real = f64> {
    phi: [[T; 3]; 3],
    gamma: [T; 3],
    gain: [T; 3],
    x: [T; 3],
}

impl<T: Real> LinearObserver<T> {
    /// An observer at rest at 0 from `Φ` (row-major), `Γ` and the gain `K`;
    /// every entry must be finite.
    pub fn from_matrices(
        phi: [[T; 3]; 3],
        gamma: [T; 3],
        gain: [T; 3],
    ) -> Result<Self, ParamError> {
        for row in &phi {
            for &v in row {
                finite("phi", v)?;
            }
        }
        for &v in &gamma {
            finite("gamma", v)?;
        }
        for &v in &gain {
            finite("gain", v)?;
        }
        Ok(Self {
            phi,
            gamma,
            gain,
            x: [T::ZERO; 3],
        })
    }

    /// The same observer in another float type (entries rounded to
    /// nearest), at rest at 0.
    pub fn cast<U: Real>(&self) -> LinearObserver<U> {
        let c = |v: T| U::of(v.to_f64());
        LinearObserver {
            phi: self.phi.map(|r| r.map(c)),
            gamma: self.gamma.map(c),
            gain: self.gain.map(c),
            x: [U::ZERO; 3],
        }
    }

    /// `Φ` (row-major).
    pub fn phi(&self) -> [[T; 3]; 3] {
        self.phi
    }
    /// `Γ`.
    pub fn gamma(&self) -> [T; 3] {
        self.gamma
    }
    /// The gain `K`.
    pub fn gain(&self) -> [T; 3] {
        self.gain
    }
    /// The current estimate `x̂`.
    pub fn state(&self) -> [T; 3] {
        self.x
    }
}

impl<T: Real> Estimator<T> for LinearObserver<T> {
    fn reset(&mut self, theta0: T) {
        self.x = [theta0, T::ZERO, T::ZERO];
    }

    fn update(&mut self, theta: T, u_prev: T) -> [T; 3] {
        let x = self.x;
        let mut pred = [T::ZERO; 3];
        for (p, (row, &g)) in pred.iter_mut().zip(self.phi.iter().zip(&self.gamma)) {
            *p = row[0] * x[0] + row[1] * x[1] + row[2] * x[2] + g * u_prev;
        }
        let innov = theta - pred[0];
        for (xi, (&p, &k)) in self.x.iter_mut().zip(pred.iter().zip(&self.gain)) {
            *xi = p + k * innov;
        }
        self.x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The triple integrator's exact discretisation (by hand, `e^{Nh}` with
    /// `N³ = 0`): `Φ = [[1, h, h²/2], [0, 1, h], [0, 0, 1]]`,
    /// `Γ = [h³/6, h²/2, h]`.
    fn triple(h: f64) -> ([[f64; 3]; 3], [f64; 3]) {
        (
            [[1.0, h, h * h / 2.0], [0.0, 1.0, h], [0.0, 0.0, 1.0]],
            [h * h * h / 6.0, h * h / 2.0, h],
        )
    }

    /// Runs `est` on `f(t)` sampled every `h` from t = h to `t_end`, and
    /// returns the largest |error| of θ̂̇ and θ̂̈ against `df`, `ddf` over
    /// `t ≥ t_from`.
    fn worst(
        est: &mut impl Estimator<f64>,
        h: f64,
        t_end: f64,
        t_from: f64,
        f: impl Fn(f64) -> [f64; 3],
    ) -> [f64; 2] {
        est.reset(f(0.0)[0]);
        let n = (t_end / h).round() as usize;
        let mut w = [0.0f64; 2];
        for k in 1..=n {
            let t = k as f64 * h;
            let [y, dy, ddy] = f(t);
            let x = est.update(y, 0.0);
            assert!(x.iter().all(|v| v.is_finite()), "diverged at t = {t}");
            if t >= t_from {
                w[0] = w[0].max((x[1] - dy).abs());
                w[1] = w[1].max((x[2] - ddy).abs());
            }
        }
        w
    }

    /// θ = A·sin ωt with A = 5°, ω = 2π (the paper's reference):
    /// θ̇ = Aω·cos ωt (amplitude 0.548 rad/s), θ̈ = −Aω²·sin ωt (3.44 rad/s²),
    /// |θ⃛| ≤ Aω³ = 21.6 rad/s³; L = 40 (margin ×1.85).
    ///
    /// Bands: the sampled accuracy `|z_i − f^{(i)}| ≤ μ_i·L·h^{3−i}`
    /// (Levant 2003; Livne & Levant 2014). The μ_i are not given in closed
    /// form; the bands take μ1 = 10, μ2 = 6, about twice the measured ones
    /// (worst errors after 2 s of settling: 0.0197 rad/s and 1.30 rad/s²
    /// at h = 0.01, 2.09e-4 and 0.139 at h = 1e-3, i.e. μ1 ≈ 5, μ2 ≈ 3.3),
    /// and the test checks the order in h: ten times smaller h must give
    /// errors ~100× (θ̇) and ~10× (θ̈) smaller.
    #[test]
    fn levant_on_a_sine() {
        let (a, w) = (5.0 * crate::math::DR, 2.0 * core::f64::consts::PI);
        let sine = |t: f64| {
            let (s, c) = (w * t).sin_cos();
            [a * s, a * w * c, -a * w * w * s]
        };
        let l = 40.0;
        let mut errs = [[0.0; 2]; 2];
        for (i, h) in [0.01, 1e-3].into_iter().enumerate() {
            let mut d = Levant::try_new(l, h).unwrap();
            let e = worst(&mut d, h, 4.0, 2.0, sine);
            assert!(e[0] < 10.0 * l * h * h, "h = {h}: θ̇ error {}", e[0]);
            assert!(e[1] < 6.0 * l * h, "h = {h}: θ̈ error {}", e[1]);
            errs[i] = e;
        }
        let r1 = errs[0][0] / errs[1][0];
        let r2 = errs[0][1] / errs[1][1];
        assert!((50.0..200.0).contains(&r1), "θ̇ order: ratio {r1}");
        assert!((5.0..20.0).contains(&r2), "θ̈ order: ratio {r2}");
    }

    /// A smoothed step: θ = A·s(t/T) for t in [0, T], A after, with the
    /// quintic s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ (s' = 30τ² − 60τ³ + 30τ⁴,
    /// s'' = 60τ − 180τ² + 120τ³, s''' = 60 − 360τ + 360τ², largest 60 at
    /// τ = 0 and 1). A = 5°, T = 0.5 s: |θ⃛| ≤ 60·A/T³ = 41.9 rad/s³; L = 60.
    /// The differentiator starts exact (at rest, like the signal), so the
    /// bands hold throughout and after the step (where θ̇ = θ̈ = 0).
    #[test]
    fn levant_on_a_smoothed_step() {
        let (a, tt) = (5.0 * crate::math::DR, 0.5);
        let step = |t: f64| {
            let tau = (t / tt).min(1.0);
            let (s, ds, dds) = (
                tau.powi(3) * (10.0 - 15.0 * tau + 6.0 * tau * tau),
                tau * tau * (30.0 - 60.0 * tau + 30.0 * tau * tau),
                tau * (60.0 - 180.0 * tau + 120.0 * tau * tau),
            );
            if t >= tt {
                [a, 0.0, 0.0]
            } else {
                [a * s, a * ds / tt, a * dds / (tt * tt)]
            }
        };
        let l = 60.0;
        for h in [0.01, 1e-3] {
            let mut d = Levant::try_new(l, h).unwrap();
            let e = worst(&mut d, h, 2.0, 0.0, step);
            assert!(e[0] < 10.0 * l * h * h, "h = {h}: θ̇ error {}", e[0]);
            assert!(e[1] < 6.0 * l * h, "h = {h}: θ̈ error {}", e[1]);
        }
    }

    /// Within the same bands with ten interpolated sub-steps, and with
    /// λ2 = 3 (the value of some of Levant's examples).
    #[test]
    fn levant_substeps_and_lambda_three() {
        let (a, w) = (5.0 * crate::math::DR, 2.0 * core::f64::consts::PI);
        let sine = |t: f64| {
            let (s, c) = (w * t).sin_cos();
            [a * s, a * w * c, -a * w * w * s]
        };
        for h in [0.01, 1e-3] {
            let mut d = Levant::try_new(40.0, h).unwrap().with_substeps(10).unwrap();
            let e = worst(&mut d, h, 4.0, 2.0, sine);
            assert!(e[0] < 10.0 * 40.0 * h * h && e[1] < 6.0 * 40.0 * h, "{e:?}");
            let mut d = Levant::try_new(40.0, h)
                .unwrap()
                .with_lambdas([1.1, 1.5, 3.0])
                .unwrap();
            let e = worst(&mut d, h, 4.0, 2.0, sine);
            assert!(e[0] < 10.0 * 40.0 * h * h && e[1] < 6.0 * 40.0 * h, "{e:?}");
        }
    }

    /// Deadbeat current estimator of the triple integrator, by hand. With
    /// h = 1 (the general case by the scaling x' = (x1, h·x2, h²·x3)),
    /// Φ = I + N and w = z − 1, det(zI − Φ + K·C·Φ) =
    /// w³ + (k1 + k2 + k3/2)·w² + (k2 + 3k3/2)·w + k3; setting it to z³ =
    /// (w + 1)³ gives k3 = 1, k2 = 3/2, k1 = 1, so K = (1, 3/(2h), 1/h²).
    /// Deadbeat: any initial error is gone after three samples.
    #[test]
    fn deadbeat_triple_integrator_by_hand() {
        let h = 0.01;
        let (phi, gamma) = triple(h);
        let gain = [1.0, 1.5 / h, 1.0 / (h * h)];
        let mut obs = LinearObserver::from_matrices(phi, gamma, gain).unwrap();
        obs.reset(0.0);
        // True motion: x(0) = (0.1, −2, 30), u = 5 constant (x3 ramps).
        let mut x = [0.1, -2.0, 30.0];
        let u = 5.0;
        let mut est = [0.0; 3];
        for _ in 0..3 {
            x = [
                x[0] + h * x[1] + h * h / 2.0 * x[2] + h * h * h / 6.0 * u,
                x[1] + h * x[2] + h * h / 2.0 * u,
                x[2] + h * u,
            ];
            est = obs.update(x[0], u);
        }
        for i in 0..3 {
            assert!(
                (est[i] - x[i]).abs() < 1e-9 * (1.0 + x[i].abs()) / h.powi(i as i32),
                "{i}: {est:?} vs {x:?}"
            );
        }
        // And it stays exact.
        for _ in 0..100 {
            x = [
                x[0] + h * x[1] + h * h / 2.0 * x[2] + h * h * h / 6.0 * u,
                x[1] + h * x[2] + h * h / 2.0 * u,
                x[2] + h * u,
            ];
            est = obs.update(x[0], u);
        }
        assert!((est[2] - x[2]).abs() < 1e-6, "{est:?} vs {x:?}");
    }

    /// f32: both types build, run and track (looser bands).
    #[test]
    fn f32_smoke() {
        let (a, w) = (
            5.0f32 * core::f32::consts::PI / 180.0,
            2.0 * core::f32::consts::PI,
        );
        let h = 1e-3f32;
        let mut d = Levant::<f32>::try_new(40.0, h).unwrap();
        d.reset(0.0);
        let mut e = [0.0f32; 2];
        for k in 1..=4000 {
            let t = k as f32 * h;
            let (s, c) = Real::sin_cos(w * t);
            let x = d.update(a * s, 0.0);
            if t >= 2.0 {
                e[0] = e[0].max((x[1] - a * w * c).abs());
                e[1] = e[1].max((x[2] + a * w * w * s).abs());
            }
        }
        assert!(e[0] < 0.01 && e[1] < 0.5, "{e:?}");

        let (phi, gamma) = triple(0.01);
        let obs64 = LinearObserver::from_matrices(phi, gamma, [1.0, 150.0, 1.0e4]).unwrap();
        let mut obs = obs64.cast::<f32>();
        obs.reset(0.5);
        let mut x = obs.state();
        for _ in 0..3 {
            x = obs.update(0.5, 0.0);
        }
        assert!(
            (x[0] - 0.5).abs() < 1e-5 && x[1].abs() < 1e-3 && x[2].abs() < 0.1,
            "{x:?}"
        );
    }

    #[test]
    fn bad_parameters_are_named() {
        assert_eq!(Levant::try_new(-1.0, 0.01).unwrap_err().name, "lipschitz");
        assert_eq!(
            Levant::try_new(f64::NAN, 0.01).unwrap_err().name,
            "lipschitz"
        );
        assert_eq!(Levant::try_new(30.0, 0.0).unwrap_err().name, "h");
        assert_eq!(Levant::try_new(30.0, -1e-3).unwrap_err().name, "h");
        let d = Levant::try_new(30.0, 0.01).unwrap();
        assert_eq!(d.with_substeps(0).unwrap_err().name, "substeps");
        assert_eq!(d.with_lambdas([1.1, 0.0, 2.0]).unwrap_err().name, "lambda1");
        let (phi, gamma) = triple(0.01);
        let mut bad = phi;
        bad[1][2] = f64::INFINITY;
        let e = LinearObserver::from_matrices(bad, gamma, [0.0; 3]).unwrap_err();
        assert_eq!(e.name, "phi");
        let e = LinearObserver::from_matrices(phi, [0.0, f64::NAN, 0.0], [0.0; 3]);
        assert_eq!(e.unwrap_err().name, "gamma");
        let e = LinearObserver::from_matrices(phi, gamma, [0.0, 0.0, f64::NAN]);
        assert_eq!(e.unwrap_err().name, "gain");
    }
}
