//! The iterative linear algebra of the analysis, bounded: every matrix is
//! checked for finiteness first and every iteration has a limit, so an
//! extreme parameter gives "not computed", never a hang (nalgebra's
//! `complex_eigenvalues` and `exp` loop forever on a non-finite matrix).

use nalgebra::{Complex, SMatrix, Schur, SVD};

/// Iterations allowed to the Schur and SVD algorithms (they need tens).
const MAX_ITER: usize = 10_000;

/// Whether every entry is finite.
pub fn finite<const N: usize>(m: &SMatrix<f64, N, N>) -> bool {
    m.iter().all(|v| v.is_finite())
}

macro_rules! bounded {
    ($eig:ident, $norm:ident, $n:literal) => {
        /// The eigenvalues of `m`; None when `m` is not finite or the Schur
        /// iteration does not converge within its limit.
        pub fn $eig(m: &SMatrix<f64, $n, $n>) -> Option<Vec<Complex<f64>>> {
            if !finite(m) {
                return None;
            }
            let ev: Vec<Complex<f64>> = Schur::try_new(*m, f64::EPSILON, MAX_ITER)?
                .complex_eigenvalues()
                .iter()
                .copied()
                .collect();
            ev.iter()
                .all(|z| z.re.is_finite() && z.im.is_finite())
                .then_some(ev)
        }

        /// The spectral norm ‖m‖₂; NaN when `m` is not finite or the SVD
        /// does not converge.
        #[allow(dead_code)]
        pub fn $norm(m: &SMatrix<f64, $n, $n>) -> f64 {
            if !finite(m) {
                return f64::NAN;
            }
            SVD::try_new(*m, false, false, f64::EPSILON, MAX_ITER)
                .map(|s| s.singular_values.max())
                .unwrap_or(f64::NAN)
        }
    };
}

bounded!(eigenvalues3, norm2_3, 3);
bounded!(eigenvalues4, norm2_4, 4);

/// exp(m); None when `m` is not finite (nalgebra's scaling and squaring
/// would not end) or the result overflows.
pub fn expm3(m: &SMatrix<f64, 3, 3>) -> Option<SMatrix<f64, 3, 3>> {
    if !finite(m) {
        return None;
    }
    let e = m.exp();
    finite(&e).then_some(e)
}

/// The symmetric G = aᵀa of a = m/s (s = the largest |m_ij|, so G cannot
/// overflow) with q = tr G/3 and p = sqrt(‖G − qI‖_F²/6): its eigenvalues
/// are q + 2p·cos(φ + 2πk/3), so λ_max ≤ q + 2p (tight to ≈ (σ₂/σ₁)⁴/4
/// relative when the two smaller singular values are small).
struct Gram {
    s: f64,
    g: [f64; 6],
    q: f64,
    p: f64,
}

/// None for a zero matrix; s = NaN when m is not finite.
fn gram(m: &SMatrix<f64, 3, 3>) -> Option<Gram> {
    let s = m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if s == 0.0 {
        return None;
    }
    if !s.is_finite() {
        return Some(Gram {
            s: f64::NAN,
            g: [f64::NAN; 6],
            q: f64::NAN,
            p: f64::NAN,
        });
    }
    let inv = 1.0 / s;
    // Columns of m/s; G_ij = column i · column j.
    let c: [[f64; 3]; 3] =
        std::array::from_fn(|j| [m[(0, j)] * inv, m[(1, j)] * inv, m[(2, j)] * inv]);
    let dot = |x: &[f64; 3], y: &[f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let g = [
        dot(&c[0], &c[0]),
        dot(&c[1], &c[1]),
        dot(&c[2], &c[2]),
        dot(&c[0], &c[1]),
        dot(&c[0], &c[2]),
        dot(&c[1], &c[2]),
    ];
    let q = (g[0] + g[1] + g[2]) / 3.0;
    let (d0, d1, d2) = (g[0] - q, g[1] - q, g[2] - q);
    let p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * (g[3] * g[3] + g[4] * g[4] + g[5] * g[5]);
    Some(Gram {
        s,
        g,
        q,
        p: (p2 / 6.0).sqrt(),
    })
}

/// ‖m‖₂ of a 3×3 real matrix in closed form: the square root of the
/// largest eigenvalue of G = mᵀm by the trigonometric solution of its
/// characteristic cubic (Smith, CACM 1961): with q = tr G/3,
/// p = sqrt(‖G − qI‖_F²/6), B = (G − qI)/p and r = det B/2 ∈ [−1, 1],
/// λ_max = q + 2p·cos(acos(r)/3). A few hundred instructions against the
/// thousands of an iterative SVD.
///
/// Accuracy: m is first scaled by its largest entry (no overflow in G); the
/// three terms of λ_max are non-negative (cos(acos(r)/3) ≥ 1/2), so it is
/// accurate to a few ε relative unless r is near −1 (the two largest
/// eigenvalues nearly equal), where acos loses digits: an error δr ≈ 4ε in
/// r moves λ_max by ≤ 0.5·δr/sqrt(1 + r) relative. Below 1 + r = 1e-4
/// (error then ≤ 1e-13) the SVD ([`norm2_3`]) is used instead. NaN when m
/// is not finite, as [`norm2_3`].
pub fn norm2_3_fast(m: &SMatrix<f64, 3, 3>) -> f64 {
    let Some(Gram { s, g, q, p }) = gram(m) else {
        return 0.0;
    };
    if !s.is_finite() {
        return f64::NAN;
    }
    if p == 0.0 {
        return s * q.sqrt();
    }
    let ip = 1.0 / p;
    let (b00, b11, b22) = ((g[0] - q) * ip, (g[1] - q) * ip, (g[2] - q) * ip);
    let (b01, b02, b12) = (g[3] * ip, g[4] * ip, g[5] * ip);
    let det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02)
        + b02 * (b01 * b12 - b11 * b02);
    let r = (det / 2.0).clamp(-1.0, 1.0);
    if r < -1.0 + 1e-4 {
        return norm2_3(m);
    }
    let lambda = q + 2.0 * p * (r.acos() / 3.0).cos();
    s * lambda.sqrt()
}

/// (q, p²) of G = mᵀm, unscaled (see [`Gram`]): ‖m‖₂² ≤ q + 2p. None
/// when they are not finite (m huge or not finite). For a cheap test of the
/// bound against a threshold x: q + 2p ≤ x ⟺ q ≤ x and p² ≤ ((x − q)/2)².
pub fn gram_q_p2(m: &SMatrix<f64, 3, 3>) -> Option<(f64, f64)> {
    let col = |j: usize| [m[(0, j)], m[(1, j)], m[(2, j)]];
    let (c0, c1, c2) = (col(0), col(1), col(2));
    let dot = |x: &[f64; 3], y: &[f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let (g00, g11, g22) = (dot(&c0, &c0), dot(&c1, &c1), dot(&c2, &c2));
    let (g01, g02, g12) = (dot(&c0, &c1), dot(&c0, &c2), dot(&c1, &c2));
    let q = (g00 + g11 + g22) / 3.0;
    let (d0, d1, d2) = (g00 - q, g11 - q, g22 - q);
    let p2 = (d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * (g01 * g01 + g02 * g02 + g12 * g12)) / 6.0;
    (q.is_finite() && p2.is_finite()).then_some((q, p2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Matrix4};

    #[test]
    fn non_finite_matrices_give_none_not_a_hang() {
        let mut m = Matrix4::<f64>::identity();
        m[(2, 3)] = f64::INFINITY;
        assert!(eigenvalues4(&m).is_none());
        let mut n = Matrix3::<f64>::identity();
        n[(0, 1)] = f64::NAN;
        assert!(norm2_3(&n).is_nan());
        assert!(expm3(&n).is_none());
        // exp of a finite matrix that overflows.
        assert!(expm3(&(Matrix3::<f64>::identity() * 1e3)).is_none());
        // A plain case: diag(1, 2, 3) has eigenvalues 1, 2, 3 and ‖·‖₂ = 3.
        let d = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 2.0, 3.0));
        let mut ev: Vec<f64> = eigenvalues3(&d).unwrap().iter().map(|z| z.re).collect();
        ev.sort_by(f64::total_cmp);
        assert!(
            (ev[0] - 1.0).abs() < 1e-12 && (ev[2] - 3.0).abs() < 1e-12,
            "{ev:?}"
        );
        assert!((norm2_3(&d) - 3.0).abs() < 1e-12);
    }

    /// The closed-form norm against the SVD on random matrices of entries
    /// spread over ten decades, on rank-one, orthogonal and nearly
    /// degenerate ones (two equal largest singular values: the SVD branch).
    #[test]
    fn closed_form_norm_against_the_svd() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut worst: f64 = 0.0;
        for k in 0..20_000 {
            let e = 10f64.powf(5.0 * next());
            let mut m = Matrix3::from_fn(|_, _| next() * e);
            match k % 4 {
                // Rank one.
                1 => {
                    let (u, v) = (m.column(0).into_owned(), m.row(1).into_owned());
                    m = u * v;
                }
                // Two equal largest singular values: diag(1, 1, d) rotated.
                2 => {
                    let q = m.qr().q();
                    let d = Matrix3::from_diagonal(&nalgebra::Vector3::new(e, e, e * next()));
                    m = q * d * q.transpose();
                }
                // Nearly so.
                3 => {
                    let q = m.qr().q();
                    let d = Matrix3::from_diagonal(&nalgebra::Vector3::new(
                        e,
                        e * (1.0 - 1e-3 * next().abs()),
                        e * next(),
                    ));
                    m = q * d;
                }
                _ => {}
            }
            let (a, b) = (norm2_3_fast(&m), norm2_3(&m));
            worst = worst.max((a - b).abs() / b);
            // The screening bound: ‖m‖₂ ≤ sqrt(q + 2p) ≤ sqrt(3)·‖m‖₂.
            if let Some((q, p2)) = gram_q_p2(&m) {
                let up = (q + 2.0 * p2.sqrt()).sqrt();
                assert!(up >= b * (1.0 - 1e-14) && up <= b * 3f64.sqrt() * (1.0 + 1e-14));
            }
        }
        assert!(worst < 1e-14, "{worst}");
        assert!(norm2_3_fast(&Matrix3::zeros()) == 0.0);
        assert!((norm2_3_fast(&(Matrix3::identity() * 3.0)) - 3.0).abs() < 1e-15);
        assert!((norm2_3_fast(&(Matrix3::identity() * 1e300)) - 1e300).abs() < 1e286);
        let mut n = Matrix3::<f64>::identity();
        n[(2, 1)] = f64::INFINITY;
        assert!(norm2_3_fast(&n).is_nan());
    }
}
