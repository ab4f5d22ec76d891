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
}
