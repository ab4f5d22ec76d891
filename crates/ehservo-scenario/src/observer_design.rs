//! Design of the linear state observers of [`ehservo_core::estimate`]: the
//! nominal linear model discretised exactly, a Luenberger gain by pole
//! placement (Ackermann) and a steady-state Kalman gain (discrete algebraic
//! Riccati equation), plus the observers' theoretical noise gains.
//!
//! **Model.** `x = (θ, θ̇, θ̈)`, `ẋ = A·x + B·u`, `θ = C·x` with
//!
//! ```text
//!     ⎡  0    1    0 ⎤       ⎡ 0  ⎤
//! A = ⎢  0    0    1 ⎥,  B = ⎢ 0  ⎥,  C = [1 0 0],
//!     ⎣ −a1  −a2  −a3⎦       ⎣ b0 ⎦
//! ```
//!
//! `a_i = model.coeffs.a_i` and `b0 = model.b_at_rest()` — the plant's
//! `ẋ3 = −a1·x1 − a2·x2 − a3·x3 + b·u − d` at zero load pressure, with the
//! load term `d` (and the variation of `b` with the load pressure) left out:
//! for the observers they are unmodelled disturbances that bias the
//! estimate.
//!
//! **Discretisation** (zero-order-held `u`, period `h`): `Φ = e^{A·h}`,
//! `Γ = ∫₀ʰ e^{A·s} ds·B`, both read off the exponential of the augmented
//! matrix `[[A, B], [0, 0]]·h` (C. Van Loan, *Computing integrals involving
//! the matrix exponential*, IEEE Trans. Autom. Control 23(3), 1978). Every
//! computation runs in the scaled state `x' = S·x`, `S = diag(1, h, h²)`,
//! whose entries are of one size (for the triple integrator `Φ'` is that of
//! `h = 1`): at `h = 1e-4` the unscaled `Φ13 = h²/2` and the process noise
//! covariance's `Q11 = q·h⁵/20` would otherwise sit at the exponential's
//! absolute rounding level.
//!
//! **Observer form.** The predictor/corrector ("current estimator") of
//! [`LinearObserver`]: error `e_k = (I − K·C)·Φ·e_{k−1} + K·v_k`.

use ehservo_core::error::ParamError;
use ehservo_core::estimate::LinearObserver;
use ehservo_core::servo::NominalModel;
use nalgebra::{Matrix3, Matrix4, Matrix6, RowVector3, SMatrix, Vector3};

/// Largest number of Riccati iterations [`kalman`] runs.
pub const DARE_MAX_ITERATIONS: usize = 1_000_000;

/// `(a, b0)`: `[a1, a2, a3]` and `b0` of the nominal linear model.
pub fn nominal_linear(model: &NominalModel) -> ([f64; 3], f64) {
    (model.coeffs.as_array(), model.b_at_rest())
}

fn check_h(h: f64) -> Result<(), ParamError> {
    if h.is_finite() && h > 0.0 {
        Ok(())
    } else {
        Err(ParamError::new("h", "must be finite and > 0", h))
    }
}

fn check_model(a: [f64; 3], b0: f64) -> Result<(), ParamError> {
    for (name, v) in [("a1", a[0]), ("a2", a[1]), ("a3", a[2]), ("b0", b0)] {
        if !v.is_finite() {
            return Err(ParamError::new(name, "must be finite", v));
        }
    }
    Ok(())
}

/// `S = diag(1, h, h²)` as its diagonal.
fn scale(h: f64) -> [f64; 3] {
    [1.0, h, h * h]
}

/// `S·M·S⁻¹` (or with `inv`, `S⁻¹·M·S`).
fn similar(m: &Matrix3<f64>, s: [f64; 3], inv: bool) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| {
        if inv {
            m[(i, j)] * s[j] / s[i]
        } else {
            m[(i, j)] * s[i] / s[j]
        }
    })
}

/// The scaled continuous matrices times `h`: `A'·h = S·A·S⁻¹·h` and
/// `S·B·h`.
fn scaled_continuous(a: [f64; 3], b0: f64, h: f64) -> (Matrix3<f64>, Vector3<f64>) {
    let ah = Matrix3::new(
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        1.0,
        -a[0] * h * h * h,
        -a[1] * h * h,
        -a[2] * h,
    );
    (ah, Vector3::new(0.0, 0.0, b0 * h * h * h))
}

/// The scaled `(Φ', Γ')` from the augmented exponential.
fn scaled_discrete(a: [f64; 3], b0: f64, h: f64) -> (Matrix3<f64>, Vector3<f64>) {
    let (ah, bh) = scaled_continuous(a, b0, h);
    let mut m = Matrix4::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&ah);
    m.fixed_view_mut::<3, 1>(0, 3).copy_from(&bh);
    let e = m.exp();
    (
        e.fixed_view::<3, 3>(0, 0).into_owned(),
        e.fixed_view::<3, 1>(0, 3).into_owned(),
    )
}

/// The exact discretisation `(Φ, Γ)` of `ẋ = A·x + B·u` (module doc) for
/// coefficients `a = [a1, a2, a3]` and gain `b0`, period `h`.
pub fn discretise(
    a: [f64; 3],
    b0: f64,
    h: f64,
) -> Result<(Matrix3<f64>, Vector3<f64>), ParamError> {
    check_h(h)?;
    check_model(a, b0)?;
    let s = scale(h);
    let (phi, gamma) = scaled_discrete(a, b0, h);
    Ok((
        similar(&phi, s, true),
        Vector3::from_fn(|i, _| gamma[i] / s[i]),
    ))
}

/// The process-noise covariance of a white jerk of intensity `q` on `ẋ3`,
/// `Q = ∫₀ʰ e^{A·s}·G·q·Gᵀ·e^{Aᵀ·s} ds` with `G = (0, 0, 1)`, by Van Loan's
/// method: `E = exp([[−A, G·q·Gᵀ], [0, Aᵀ]]·h)`, `Q = E22ᵀ·E12`.
pub fn process_covariance(a: [f64; 3], q: f64, h: f64) -> Result<Matrix3<f64>, ParamError> {
    check_h(h)?;
    check_model(a, 0.0)?;
    let s = scale(h);
    let qs = scaled_process_covariance(a, q, h);
    Ok(Matrix3::from_fn(|i, j| qs[(i, j)] / (s[i] * s[j])))
}

/// `Q' = S·Q·S`.
fn scaled_process_covariance(a: [f64; 3], q: f64, h: f64) -> Matrix3<f64> {
    let (ah, _) = scaled_continuous(a, 0.0, h);
    // S·G = h²·e3; the intensity term of the scaled system times h.
    let w = q * h.powi(4) * h;
    let mut m = Matrix6::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-ah));
    m[(2, 5)] = w;
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(&ah.transpose());
    let e = m.exp();
    let e12 = e.fixed_view::<3, 3>(0, 3).into_owned();
    let e22 = e.fixed_view::<3, 3>(3, 3).into_owned();
    let qd = e22.transpose() * e12;
    (qd + qd.transpose()) * 0.5
}

/// A Luenberger observer of the nominal model with continuous poles
/// `poles` (rad/s, real and < 0), mapped to `z_i = e^{p_i·h}`.
pub fn luenberger(
    model: &NominalModel,
    poles: [f64; 3],
    h: f64,
) -> Result<LinearObserver, ParamError> {
    let (a, b0) = nominal_linear(model);
    luenberger_coeffs(a, b0, poles, h)
}

/// [`luenberger`] from the coefficients `[a1, a2, a3]` and `b0`.
///
/// The gain is Ackermann's formula for the current estimator (Franklin,
/// Powell & Workman, *Digital Control of Dynamic Systems*, 3rd ed., §8.2):
/// the error matrix `Φ − K·(C·Φ)` is the predictor form for the pair
/// `(Φ, C·Φ)`, so `K = α(Φ)·[C·Φ; C·Φ²; C·Φ³]⁻¹·(0, 0, 1)ᵀ` with
/// `α(z) = (z − z1)(z − z2)(z − z3)`; computed in the scaled state and
/// mapped back, `K = S⁻¹·K'`.
pub fn luenberger_coeffs(
    a: [f64; 3],
    b0: f64,
    poles: [f64; 3],
    h: f64,
) -> Result<LinearObserver, ParamError> {
    check_h(h)?;
    check_model(a, b0)?;
    for &p in &poles {
        if !(p.is_finite() && p < 0.0) {
            return Err(ParamError::new(
                "poles",
                "must be real, finite and < 0 (Hurwitz)",
                p,
            ));
        }
    }
    let s = scale(h);
    let (phi, gamma) = scaled_discrete(a, b0, h);
    let i3 = Matrix3::identity();
    let alpha = poles
        .iter()
        .fold(i3, |acc, &p| acc * (phi - i3 * (p * h).exp()));
    let c = RowVector3::new(1.0, 0.0, 0.0);
    let o = Matrix3::from_rows(&[c * phi, c * phi * phi, c * phi * phi * phi]);
    let e3 = Vector3::new(0.0, 0.0, 1.0);
    let y = o.lu().solve(&e3).ok_or(ParamError::new(
        "poles",
        "the model is not observable from θ at this h",
        f64::NAN,
    ))?;
    let k = alpha * y;
    build(phi, gamma, k, s)
}

fn build(
    phi_s: Matrix3<f64>,
    gamma_s: Vector3<f64>,
    k_s: Vector3<f64>,
    s: [f64; 3],
) -> Result<LinearObserver, ParamError> {
    let phi = similar(&phi_s, s, true);
    let arr = |v: Vector3<f64>| [v[0] / s[0], v[1] / s[1], v[2] / s[2]];
    let phi_a: [[f64; 3]; 3] = core::array::from_fn(|i| core::array::from_fn(|j| phi[(i, j)]));
    LinearObserver::from_matrices(phi_a, arr(gamma_s), arr(k_s))
}

/// The a-priori steady-state covariance `P` of the filter Riccati equation
/// `P = Φ·P·Φᵀ − Φ·P·Cᵀ·(C·P·Cᵀ + r)⁻¹·C·P·Φᵀ + Q`, iterated from `P = Q`
/// to convergence (relative change ≤ 1e-15, at most
/// [`DARE_MAX_ITERATIONS`]), then checked: relative residual ≤ 1e-9.
fn dare(phi: &Matrix3<f64>, q: &Matrix3<f64>, r: f64) -> Result<Matrix3<f64>, ParamError> {
    let mut p = *q;
    for _ in 0..DARE_MAX_ITERATIONS {
        let next = riccati_step(phi, &p, q, r);
        let change = (next - p).norm();
        p = next;
        if !p.iter().all(|v| v.is_finite()) {
            break;
        }
        if change <= 1e-15 * p.norm() {
            let res = (riccati_step(phi, &p, q, r) - p).norm() / p.norm();
            if res <= 1e-9 {
                return Ok(p);
            }
            break;
        }
    }
    Err(ParamError::new(
        "process_noise",
        "the Riccati iteration did not converge (poles too slow for h, or noise ratio too extreme)",
        f64::NAN,
    ))
}

/// One step of the filter Riccati recursion (`C = [1 0 0]`).
fn riccati_step(phi: &Matrix3<f64>, p: &Matrix3<f64>, q: &Matrix3<f64>, r: f64) -> Matrix3<f64> {
    let pc = p.column(0).into_owned();
    let m = p - pc * pc.transpose() / (p[(0, 0)] + r);
    let next = phi * m * phi.transpose() + q;
    (next + next.transpose()) * 0.5
}

/// The a-priori steady-state covariance `P` of [`kalman_coeffs`]'s filter
/// (the DARE's solution), unscaled.
pub fn kalman_covariance(
    a: [f64; 3],
    b0: f64,
    process_noise: f64,
    measurement_noise: f64,
    h: f64,
) -> Result<Matrix3<f64>, ParamError> {
    let (s, _, _, p) = kalman_parts(a, b0, process_noise, measurement_noise, h)?;
    Ok(Matrix3::from_fn(|i, j| p[(i, j)] / (s[i] * s[j])))
}

type KalmanParts = ([f64; 3], Matrix3<f64>, Vector3<f64>, Matrix3<f64>);

fn kalman_parts(a: [f64; 3], b0: f64, q: f64, r: f64, h: f64) -> Result<KalmanParts, ParamError> {
    check_h(h)?;
    check_model(a, b0)?;
    if !(q.is_finite() && q > 0.0) {
        return Err(ParamError::new(
            "process_noise",
            "must be finite and > 0",
            q,
        ));
    }
    if !(r.is_finite() && r > 0.0) {
        return Err(ParamError::new(
            "measurement_noise",
            "must be finite and > 0",
            r,
        ));
    }
    let s = scale(h);
    let (phi, gamma) = scaled_discrete(a, b0, h);
    let qs = scaled_process_covariance(a, q, h);
    let p = dare(&phi, &qs, r)?;
    Ok((s, phi, gamma, p))
}

/// A steady-state Kalman filter of the nominal model: process noise a white
/// jerk of continuous intensity `process_noise = q` (rad²/s⁵) on `ẋ3`,
/// discretised exactly ([`process_covariance`], not the `q·h·G·Gᵀ`
/// approximation), and measurement noise of variance
/// `measurement_noise = r = σ²` (rad²) on each sample.
pub fn kalman(
    model: &NominalModel,
    process_noise: f64,
    measurement_noise: f64,
    h: f64,
) -> Result<LinearObserver, ParamError> {
    let (a, b0) = nominal_linear(model);
    kalman_coeffs(a, b0, process_noise, measurement_noise, h)
}

/// [`kalman`] from the coefficients `[a1, a2, a3]` and `b0`. The gain is
/// the measurement update's `K = P·Cᵀ/(C·P·Cᵀ + r)` with `P` the a-priori
/// solution of the DARE `P = Φ·P·Φᵀ − Φ·P·Cᵀ·(C·P·Cᵀ + r)⁻¹·C·P·Φᵀ + Q`
/// (iterated to convergence, at most [`DARE_MAX_ITERATIONS`] times, and
/// rejected unless its relative residual is ≤ 1e-9), which makes the
/// current-estimator form of [`LinearObserver`] the steady-state filter
/// (B. D. O. Anderson, J. B. Moore, *Optimal Filtering*, 1979, ch. 4).
pub fn kalman_coeffs(
    a: [f64; 3],
    b0: f64,
    process_noise: f64,
    measurement_noise: f64,
    h: f64,
) -> Result<LinearObserver, ParamError> {
    let (s, phi, gamma, p) = kalman_parts(a, b0, process_noise, measurement_noise, h)?;
    let k = p.column(0).into_owned() / (p[(0, 0)] + measurement_noise);
    build(phi, gamma, k, s)
}

/// The steady-state covariance `Σ` of an observer's estimation error driven
/// by white measurement noise of unit variance (exact model, no process
/// noise): the discrete Lyapunov equation `Σ = F·Σ·Fᵀ + K·Kᵀ`,
/// `F = (I − K·C)·Φ`, solved through `vec Σ = (I − F⊗F)⁻¹·vec(K·Kᵀ)` in the
/// scaled state of period `h`. Errors when `F` is not Schur-stable.
pub fn noise_covariance(obs: &LinearObserver, h: f64) -> Result<Matrix3<f64>, ParamError> {
    check_h(h)?;
    let s = scale(h);
    let phi = Matrix3::from_fn(|i, j| obs.phi()[i][j]);
    let k = Vector3::from_fn(|i, _| obs.gain()[i] * s[i]);
    let phi_s = similar(&phi, s, false);
    let kc = Matrix3::from_fn(|i, j| if j == 0 { k[i] } else { 0.0 });
    let f = (Matrix3::identity() - kc) * phi_s;
    if f.complex_eigenvalues()
        .iter()
        .any(|z| z.norm().is_nan() || z.norm() >= 1.0)
    {
        return Err(ParamError::new(
            "gain",
            "the observer's error dynamics are not stable",
            f64::NAN,
        ));
    }
    let ff: SMatrix<f64, 9, 9> = f.kronecker(&f);
    let lhs = SMatrix::<f64, 9, 9>::identity() - ff;
    let kk = k * k.transpose();
    let rhs = SMatrix::<f64, 9, 1>::from_column_slice(kk.as_slice());
    let x = lhs.lu().solve(&rhs).ok_or(ParamError::new(
        "gain",
        "singular Lyapunov equation",
        f64::NAN,
    ))?;
    let sig = Matrix3::from_column_slice(x.as_slice());
    Ok(Matrix3::from_fn(|i, j| {
        0.5 * (sig[(i, j)] + sig[(j, i)]) / (s[i] * s[j])
    }))
}

/// The noise gains `(σ_θ̂/σ, σ_θ̂̇/σ, σ_θ̂̈/σ)`: standard deviations of the
/// estimate errors per unit standard deviation of white measurement noise
/// ([`noise_covariance`]'s diagonal, square-rooted).
pub fn noise_gains(obs: &LinearObserver, h: f64) -> Result<[f64; 3], ParamError> {
    let s = noise_covariance(obs, h)?;
    Ok([s[(0, 0)].sqrt(), s[(1, 1)].sqrt(), s[(2, 2)].sqrt()])
}

#[cfg(test)]
mod tests {
    use super::*;
    use ehservo_core::estimate::{Estimator, Levant};
    use ehservo_core::servo::{Load, ServoParams};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn paper() -> NominalModel {
        NominalModel::new(ServoParams::paper(), Load::paper())
    }

    /// Standard normal draws by Box–Muller from a seeded ChaCha8.
    struct Gauss(ChaCha8Rng);
    impl Gauss {
        fn new(seed: u64) -> Self {
            Self(ChaCha8Rng::seed_from_u64(seed))
        }
        fn uniform(&mut self) -> f64 {
            // (0, 1]: 53 random bits, never 0.
            ((self.0.next_u64() >> 11) as f64 + 1.0) / (1u64 << 53) as f64
        }
        fn next(&mut self) -> f64 {
            let (u1, u2) = (self.uniform(), self.uniform());
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        }
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(a.abs())
    }

    /// Triple integrator (a = 0, b0 = 1), by hand: Φ = e^{Nh} = I + N·h +
    /// N²h²/2, Γ = (h³/6, h²/2, h), and for a white jerk of intensity q
    /// Q = q·∫₀ʰ (s²/2, s, 1)ᵀ(s²/2, s, 1) ds =
    /// q·[[h⁵/20, h⁴/8, h³/6], [h⁴/8, h³/3, h²/2], [h³/6, h²/2, h]].
    #[test]
    fn triple_integrator_discretisation_by_hand() {
        for h in [0.01, 1e-3, 1e-4] {
            let (phi, gamma) = discretise([0.0; 3], 1.0, h).unwrap();
            let want = Matrix3::new(1.0, h, h * h / 2.0, 0.0, 1.0, h, 0.0, 0.0, 1.0);
            for i in 0..3 {
                for j in 0..3 {
                    assert!(
                        (phi[(i, j)] - want[(i, j)]).abs() <= 1e-14 * want[(i, j)].abs(),
                        "Φ {i}{j} at h = {h}"
                    );
                }
            }
            let g = [h.powi(3) / 6.0, h * h / 2.0, h];
            for i in 0..3 {
                assert!(close(gamma[i], g[i], 1e-13), "Γ {i} at h = {h}");
            }
            let q = 2.5;
            let qd = process_covariance([0.0; 3], q, h).unwrap();
            let want = Matrix3::new(
                h.powi(5) / 20.0,
                h.powi(4) / 8.0,
                h.powi(3) / 6.0,
                h.powi(4) / 8.0,
                h.powi(3) / 3.0,
                h * h / 2.0,
                h.powi(3) / 6.0,
                h * h / 2.0,
                h,
            ) * q;
            for i in 0..3 {
                for j in 0..3 {
                    assert!(
                        close(qd[(i, j)], want[(i, j)], 1e-12),
                        "Q {i}{j} at h = {h}"
                    );
                }
            }
        }
    }

    /// Ackermann for the triple integrator, by hand. In the scaled state
    /// (Φ' that of h = 1, w = z − 1) the characteristic polynomial of
    /// Φ' − K'·C·Φ' is w³ + (k1 + k2 + k3/2)·w² + (k2 + 3k3/2)·w + k3 (the
    /// deadbeat test of `ehservo_core::estimate`); matching it with
    /// Π(w − (z_i − 1)) = w³ − s1·w² + s2·w − s3 (s_j the elementary
    /// symmetric functions of z_i − 1) gives k3 = −s3, k2 = s2 − 3k3/2,
    /// k1 = −s1 − k2 − k3/2, and K = (k1, k2/h, k3/h²).
    #[test]
    fn ackermann_triple_integrator_by_hand() {
        for h in [0.01, 1e-3, 1e-4] {
            let poles = [-20.0, -35.0, -60.0];
            let obs = luenberger_coeffs([0.0; 3], 1.0, poles, h).unwrap();
            let d: Vec<f64> = poles.iter().map(|p| (p * h).exp() - 1.0).collect();
            let s1 = d[0] + d[1] + d[2];
            let s2 = d[0] * d[1] + d[0] * d[2] + d[1] * d[2];
            let s3 = d[0] * d[1] * d[2];
            let k3 = -s3;
            let k2 = s2 - 1.5 * k3;
            let k1 = -s1 - k2 - 0.5 * k3;
            let want = [k1, k2 / h, k3 / (h * h)];
            let k = obs.gain();
            for i in 0..3 {
                assert!(close(k[i], want[i], 1e-8), "h = {h}: K {k:?} vs {want:?}");
            }
        }
    }

    /// The characteristic polynomial of F = (I − K·C)·Φ from its trace,
    /// principal 2×2 minors and determinant, in the scaled state.
    fn char_poly(obs: &LinearObserver, h: f64) -> [f64; 3] {
        let s = [1.0, h, h * h];
        let phi = obs.phi();
        let k = obs.gain();
        let f = |i: usize, j: usize| {
            let fij = phi[i][j] - k[i] * phi[0][j];
            fij * s[i] / s[j]
        };
        let tr = f(0, 0) + f(1, 1) + f(2, 2);
        let m2 = |a: usize, b: usize| f(a, a) * f(b, b) - f(a, b) * f(b, a);
        let minors = m2(0, 1) + m2(0, 2) + m2(1, 2);
        let det = f(0, 0) * m2(1, 2) - f(0, 1) * (f(1, 0) * f(2, 2) - f(1, 2) * f(2, 0))
            + f(0, 2) * (f(1, 0) * f(2, 1) - f(1, 1) * f(2, 0));
        [tr, minors, det]
    }

    /// On the paper's nominal model, the observer's eigenvalues are
    /// z_i = e^{p_i·h}: the characteristic polynomial of F equals
    /// Π(z − z_i) (coefficients z1+z2+z3, z1z2+z1z3+z2z3, z1z2z3).
    #[test]
    fn luenberger_places_the_poles() {
        let m = paper();
        for h in [0.01, 1e-3, 1e-4] {
            let poles = [-50.0, -80.0, -120.0];
            let obs = luenberger(&m, poles, h).unwrap();
            let z: Vec<f64> = poles.iter().map(|p| (p * h).exp()).collect();
            let want = [
                z[0] + z[1] + z[2],
                z[0] * z[1] + z[0] * z[2] + z[1] * z[2],
                z[0] * z[1] * z[2],
            ];
            let got = char_poly(&obs, h);
            for i in 0..3 {
                assert!(
                    (got[i] - want[i]).abs() < 1e-9,
                    "h = {h}: {got:?} vs {want:?}"
                );
            }
        }
    }

    /// The truth: the continuous nominal model integrated by classic RK4
    /// with 100 steps a period and u held over each period (independent of
    /// the matrix exponential). From x(0) = (0.05, 0.5, 5) with the
    /// observer reset at θ(0) (so an initial error of (0, −0.5, −5)), the
    /// error must be gone to the truth's accuracy after 1 s, and not before
    /// the slowest pole allows (still > 1e-3 of it after 20 ms).
    fn converges(obs: &mut LinearObserver, h: f64, slowest: f64) {
        let (a, b0) = nominal_linear(&paper());
        let deriv = |x: &[f64; 3], u: f64| {
            [
                x[1],
                x[2],
                -a[0] * x[0] - a[1] * x[1] - a[2] * x[2] + b0 * u,
            ]
        };
        let mut x = [0.05, 0.5, 5.0];
        obs.reset(x[0]);
        let n = (1.0 / h).round() as usize;
        let sub = 100;
        let hs = h / sub as f64;
        let mut early = 0.0f64;
        let mut est = obs.state();
        for k in 0..n {
            // A voltage of a few mV (the paper's commands are of this order
            // over b0 ≈ 1.8e4).
            let u = 2e-3 * (7.0 * k as f64 * h).sin() + 1e-3;
            for _ in 0..sub {
                let k1 = deriv(&x, u);
                let y = |kk: [f64; 3], c: f64| core::array::from_fn(|i| x[i] + c * hs * kk[i]);
                let k2 = deriv(&y(k1, 0.5), u);
                let k3 = deriv(&y(k2, 0.5), u);
                let k4 = deriv(&y(k3, 1.0), u);
                x = core::array::from_fn(|i| {
                    x[i] + hs / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
                });
            }
            est = obs.update(x[0], u);
            if ((k + 1) as f64 * h - 0.02).abs() < 0.5 * h {
                early = (est[2] - x[2]).abs();
            }
        }
        let e = [est[0] - x[0], est[1] - x[1], est[2] - x[2]];
        // e^{slowest·1 s} times a polynomial factor, floor 1e-7 (RK4).
        let bound = (slowest.exp() * 1e6).max(1e-7);
        assert!(
            e[0].abs() < bound * 1e-2 && e[1].abs() < bound && e[2].abs() < bound * 1e2,
            "h = {h}: error {e:?} after 1 s"
        );
        assert!(early > 5e-3, "h = {h}: error {early} after 20 ms");
    }

    #[test]
    fn luenberger_and_kalman_converge_on_the_nominal_model() {
        let m = paper();
        for h in [0.01, 1e-3] {
            let mut obs = luenberger(&m, [-40.0, -60.0, -80.0], h).unwrap();
            converges(&mut obs, h, -40.0);
            // Kalman: q = 1e4 rad²/s⁵, σ = 1e-4 rad. Its poles are not
            // placed by hand: the slowest is read off the error matrix.
            let mut obs = kalman(&m, 1e4, 1e-8, h).unwrap();
            let cp = char_poly(&obs, h);
            let roots = nalgebra::Matrix3::new(cp[0], -cp[1], cp[2], 1.0, 0.0, 0.0, 0.0, 1.0, 0.0)
                .complex_eigenvalues();
            let slowest = roots
                .iter()
                .map(|z| z.norm().ln() / h)
                .fold(f64::MIN, f64::max);
            assert!(slowest < -10.0, "{slowest}");
            converges(&mut obs, h, slowest);
        }
    }

    /// The DARE's solution satisfies the equation to ~1e-9 relative, is
    /// symmetric positive definite, and for the triple integrator at small
    /// h the gain tends to the continuous Kalman filter's: with
    /// measurement noise of spectral density r·h and ω = (q/(r·h))^{1/6},
    /// the continuous filter's poles are the third-order Butterworth ones,
    /// s³ + 2ω·s² + 2ω²·s + ω³, and its gain is (2ω, 2ω², ω³); the
    /// discrete gain is h times it to O(ω·h).
    #[test]
    fn kalman_riccati_residual_and_continuous_limit() {
        let m = paper();
        let (a, b0) = nominal_linear(&m);
        for (aa, bb) in [(a, b0), ([0.0; 3], 1.0)] {
            for h in [0.01, 1e-3, 1e-4] {
                let (q, r) = (1e4, 1e-8);
                let p = kalman_covariance(aa, bb, q, r, h).unwrap();
                let (phi, _) = discretise(aa, bb, h).unwrap();
                let qd = process_covariance(aa, q, h).unwrap();
                let pc = p.column(0).into_owned();
                let rhs = phi * (p - pc * pc.transpose() / (p[(0, 0)] + r)) * phi.transpose() + qd;
                // Relative entry by entry, each against √(P_ii·P_jj).
                for i in 0..3 {
                    for j in 0..3 {
                        let scale = (p[(i, i)] * p[(j, j)]).sqrt();
                        assert!(
                            (rhs[(i, j)] - p[(i, j)]).abs() <= 1e-9 * scale,
                            "h = {h}: residual {i}{j}"
                        );
                        assert!((p[(i, j)] - p[(j, i)]).abs() <= 1e-12 * scale);
                    }
                }
                assert!(p.cholesky().is_some(), "P not positive definite");
            }
        }
        let h = 1e-4;
        let w = 50.0f64;
        let r = 1e-6;
        let q = w.powi(6) * r * h;
        let obs = kalman_coeffs([0.0; 3], 1.0, q, r, h).unwrap();
        let want = [2.0 * w * h, 2.0 * w * w * h, w.powi(3) * h];
        let k = obs.gain();
        for i in 0..3 {
            assert!(close(k[i], want[i], 0.02), "K {k:?} vs {want:?}");
        }
    }

    /// Runs `est` on `f(t) + σ·n_k` and returns the standard deviations of
    /// the errors of θ̂̇ and θ̂̈ per unit σ over samples after `settle`.
    fn measured_gain(
        est: &mut impl Estimator,
        h: f64,
        sigma: f64,
        seconds: f64,
        settle: f64,
        seed: u64,
        f: impl Fn(f64) -> [f64; 3],
    ) -> [f64; 2] {
        let mut g = Gauss::new(seed);
        est.reset(f(0.0)[0]);
        let n = (seconds / h).round() as usize;
        let (mut s1, mut s2, mut cnt) = ([0.0; 2], [0.0; 2], 0.0);
        for k in 1..=n {
            let t = k as f64 * h;
            let x = f(t);
            let e = est.update(x[0] + sigma * g.next(), 0.0);
            if t > settle {
                for i in 0..2 {
                    let d = e[i + 1] - x[i + 1];
                    s1[i] += d;
                    s2[i] += d * d;
                }
                cnt += 1.0;
            }
        }
        core::array::from_fn(|i| {
            let mean = s1[i] / cnt;
            (s2[i] / cnt - mean * mean).sqrt() / sigma
        })
    }

    /// Linear observers: by superposition the error to noise alone is the
    /// error (θ = 0, u = 0). The measured std per unit σ must match the
    /// discrete Lyapunov equation's (the independent check) to 4 %
    /// (200 000 correlated samples), and the printed values are the
    /// notes' table.
    #[test]
    fn noise_gains_of_the_linear_observers() {
        let m = paper();
        let sigma = 1e-4;
        for h in [0.01, 1e-3] {
            let designs = [
                (
                    "luenberger [-40,-60,-80]",
                    luenberger(&m, [-40.0, -60.0, -80.0], h).unwrap(),
                ),
                (
                    "kalman q=1e4 r=1e-8",
                    kalman(&m, 1e4, sigma * sigma, h).unwrap(),
                ),
            ];
            for (name, mut obs) in designs {
                let theory = noise_gains(&obs, h).unwrap();
                let got =
                    measured_gain(&mut obs, h, sigma, 200_000.0 * h, 50.0 * h, 7, |_| [0.0; 3]);
                eprintln!(
                    "{name} h = {h}: measured σ_θ̇/σ = {:.4e}, σ_θ̈/σ = {:.4e}; Lyapunov {:.4e}, {:.4e}",
                    got[0], got[1], theory[1], theory[2]
                );
                assert!(
                    close(got[0], theory[1], 0.04),
                    "{name} h = {h}: {got:?} vs {theory:?}"
                );
                assert!(
                    close(got[1], theory[2], 0.04),
                    "{name} h = {h}: {got:?} vs {theory:?}"
                );
            }
        }
    }

    /// Levant: the noise gain is not a constant (the differentiator is
    /// nonlinear): its errors scale as L^{i/3}·ε^{(3−i)/3} (Levant 2003), so
    /// eight times the noise must multiply the θ̇ error by 8^{2/3} = 4 and
    /// the θ̈ error by 8^{1/3} = 2 (h = 1e-3, where noise dominates the
    /// sampling error). The gains per unit σ at σ = 1e-4 rad are printed.
    #[test]
    fn noise_gains_of_levant() {
        let (a, w) = (5.0 * ehservo_core::math::DR, 2.0 * std::f64::consts::PI);
        let sine = move |t: f64| {
            let (s, c) = (w * t).sin_cos();
            [a * s, a * w * c, -a * w * w * s]
        };
        let l = 40.0;
        let mut at = [[0.0; 2]; 2];
        for (ih, h) in [0.01, 1e-3].into_iter().enumerate() {
            for (j, sigma) in [1e-4, 8e-4].into_iter().enumerate() {
                let mut d = Levant::try_new(l, h).unwrap();
                let got = measured_gain(&mut d, h, sigma, 200.0, 2.0, 11, sine);
                eprintln!(
                    "levant L = {l} h = {h} σ = {sigma}: σ_θ̇/σ = {:.4e}, σ_θ̈/σ = {:.4e}",
                    got[0], got[1]
                );
                if ih == 1 {
                    at[j] = [got[0] * sigma, got[1] * sigma];
                }
            }
        }
        // Regression bands around the measured gains at h = 1e-3, σ = 1e-4
        // (seed 11): 67.1 and 4425. In Levant's form μ_i·L^{i/3}·σ^{(3−i)/3}
        // these are μ1 ≈ 0.91, μ2 ≈ 0.81.
        let g = [at[0][0] / 1e-4, at[0][1] / 1e-4];
        assert!((50.0..85.0).contains(&g[0]), "σ_θ̇/σ = {}", g[0]);
        assert!((3300.0..5500.0).contains(&g[1]), "σ_θ̈/σ = {}", g[1]);
        // The noise-free (sampling) error, for comparison.
        for h in [0.01, 1e-3] {
            let mut d = Levant::try_new(l, h).unwrap();
            let tiny = 1e-30;
            let got = measured_gain(&mut d, h, tiny, 20.0, 2.0, 11, sine);
            eprintln!(
                "levant L = {l} h = {h} no noise: std of θ̇ error {:.3e}, of θ̈ error {:.3e}",
                got[0] * tiny,
                got[1] * tiny
            );
        }
        let r1 = at[1][0] / at[0][0];
        let r2 = at[1][1] / at[0][1];
        eprintln!("levant h = 1e-3 ratios for 8× noise: θ̇ {r1:.3}, θ̈ {r2:.3}");
        assert!((3.0..5.0).contains(&r1), "θ̇ ratio {r1}");
        assert!((1.5..2.6).contains(&r2), "θ̈ ratio {r2}");
    }

    #[test]
    fn bad_parameters_are_named() {
        let m = paper();
        let e = |r: Result<LinearObserver, ParamError>| r.unwrap_err().name;
        assert_eq!(e(luenberger(&m, [-1.0, 0.0, -3.0], 0.01)), "poles");
        assert_eq!(e(luenberger(&m, [-1.0, 2.0, -3.0], 0.01)), "poles");
        assert_eq!(e(luenberger(&m, [-1.0, f64::NAN, -3.0], 0.01)), "poles");
        assert_eq!(e(luenberger(&m, [-1.0, -2.0, -3.0], 0.0)), "h");
        assert_eq!(e(luenberger(&m, [-1.0, -2.0, -3.0], -1e-3)), "h");
        assert_eq!(e(kalman(&m, f64::INFINITY, 1e-8, 0.01)), "process_noise");
        assert_eq!(e(kalman(&m, f64::NAN, 1e-8, 0.01)), "process_noise");
        assert_eq!(e(kalman(&m, -1.0, 1e-8, 0.01)), "process_noise");
        assert_eq!(e(kalman(&m, 1e4, 0.0, 0.01)), "measurement_noise");
        assert_eq!(e(kalman(&m, 1e4, -1e-8, 0.01)), "measurement_noise");
        assert_eq!(e(kalman(&m, 1e4, f64::NAN, 0.01)), "measurement_noise");
        assert_eq!(e(kalman(&m, 1e4, 1e-8, f64::NAN)), "h");
        // An unstable gain has no steady noise covariance.
        let (phi, gamma) = discretise([0.0; 3], 1.0, 0.01).unwrap();
        let arr: [[f64; 3]; 3] = core::array::from_fn(|i| core::array::from_fn(|j| phi[(i, j)]));
        let obs = LinearObserver::from_matrices(arr, gamma.into(), [0.0; 3]).unwrap();
        assert_eq!(noise_gains(&obs, 0.01).unwrap_err().name, "gain");
    }
}
