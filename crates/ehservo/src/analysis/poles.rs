//! Poles: [`Pole`] (damping ratio, natural frequency), the roots of a cubic,
//! the open-loop poles of the nominal model (8) and the matrix P of (16).

use nalgebra::{Complex, Matrix3};
use serde::Serialize;

/// A pole with its damping ratio and natural frequency.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pole {
    /// Real part (1/s).
    pub re: f64,
    /// Imaginary part (rad/s).
    pub im: f64,
    /// Natural frequency |λ| (rad/s).
    pub wn: f64,
    /// Damping ratio −Re λ/|λ| (1 for a real stable pole).
    pub zeta: f64,
}

impl From<Complex<f64>> for Pole {
    fn from(c: Complex<f64>) -> Self {
        let wn = c.norm();
        Self {
            re: c.re,
            im: c.im,
            wn,
            zeta: if wn > 0.0 { -c.re / wn } else { 1.0 },
        }
    }
}

pub(super) fn sort_poles(poles: &mut [Pole]) {
    poles.sort_by(|a, b| b.re.total_cmp(&a.re).then(b.im.total_cmp(&a.im)));
}

/// Roots of `s³ + c2·s² + c1·s + c0`, sorted by real part then imaginary
/// part (descending); NaN poles when a coefficient is not finite or the
/// roots cannot be computed.
///
/// The companion matrix of a fast polynomial is badly scaled (for poles of
/// order 10⁴, c0 ~ 10¹²): its eigenvalues then come out shifted, or as a
/// false complex pair. So the polynomial is first balanced — with
/// κ = max(|c2|, |c1|^½, |c0|^⅓), the roots of `s'³ + (c2/κ)s'² +
/// (c1/κ²)s' + c0/κ³` are O(1) and `s = κ·s'` — then each root is polished
/// by Newton's method on the original polynomial, keeping a step only when
/// it lowers the residual relative to the polynomial's scale.
pub fn cubic_roots(c2: f64, c1: f64, c0: f64) -> [Pole; 3] {
    let nan = Pole::from(Complex::new(f64::NAN, f64::NAN));
    if !(c2.is_finite() && c1.is_finite() && c0.is_finite()) {
        return [nan; 3];
    }
    let k = c2.abs().max(c1.abs().sqrt()).max(c0.abs().cbrt());
    if k == 0.0 {
        return [Pole::from(Complex::new(0.0, 0.0)); 3];
    }
    let m = Matrix3::new(
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        1.0,
        -c0 / (k * k * k),
        -c1 / (k * k),
        -c2 / k,
    );
    let Some(ev) = super::linalg::eigenvalues3(&m) else {
        return [nan; 3];
    };
    let c = [1.0, c2, c1, c0];
    let poly = |z: Complex<f64>| {
        c.iter()
            .fold(Complex::new(0.0, 0.0), |acc, &ci| acc * z + ci)
    };
    let dpoly = |z: Complex<f64>| Complex::new(3.0, 0.0) * z * z + z * (2.0 * c2) + c1;
    let mut roots: Vec<Complex<f64>> = ev.iter().map(|z| z * k).collect();
    for r in roots.iter_mut() {
        for _ in 0..8 {
            let (f, d) = (poly(*r), dpoly(*r));
            if d.norm() == 0.0 {
                break;
            }
            let next = *r - f / d;
            if !(next.re.is_finite() && next.im.is_finite()) || poly(next).norm() >= f.norm() {
                break;
            }
            *r = next;
        }
    }
    // A real cubic's roots are real or conjugate pairs: a pair whose
    // imaginary parts are round-off of the root's size is real.
    for r in roots.iter_mut() {
        if r.im.abs() <= 1e-12 * r.norm() {
            r.im = 0.0;
        }
    }
    let mut poles = [
        Pole::from(roots[0]),
        Pole::from(roots[1]),
        Pole::from(roots[2]),
    ];
    sort_poles(&mut poles);
    poles
}

/// Open-loop poles of the nominal third-order model (8):
/// roots of `s³ + ā3·s² + ā2·s + ā1`.
pub fn open_loop_poles(a: [f64; 3]) -> [Pole; 3] {
    cubic_roots(a[2], a[1], a[0])
}

/// The matrix P of (16) for p = (p1, p2, p3).
pub fn p_matrix(p: [f64; 3]) -> Matrix3<f64> {
    Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -p[2], -p[1], -p[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Poles far from 1, fast and slow: (s + a)(s + 2a)(s + 3a) has
    /// c2 = 6a, c1 = 11a², c0 = 6a³; the roots must come back as −a, −2a,
    /// −3a to a relative 1e-9, real, for a from 1e-6 to 1e6 (the unbalanced
    /// companion matrix shifts them from about 1e4 on).
    #[test]
    fn fast_and_slow_distinct_poles_come_back_exactly() {
        for e in -6..=6 {
            let a = 10f64.powi(e);
            let p = cubic_roots(6.0 * a, 11.0 * a * a, 6.0 * a * a * a);
            for (pole, want) in p.iter().zip([-a, -2.0 * a, -3.0 * a]) {
                assert!(
                    (pole.re - want).abs() <= 1e-9 * a && pole.im == 0.0,
                    "a = {a}: {p:?}"
                );
            }
        }
        assert!(cubic_roots(f64::INFINITY, 1.0, 1.0)[0].re.is_nan());
    }
    use ehservo_core::servo::ServoParams;

    /// The paper prints the poles 0, −84.9902 ± j76.0061 (Section IV); SPEC
    /// notes the "0" is −3.075e-5 exactly: for a small root r ≈ −ā1/ā2 =
    /// −0.39982/13000.27 = −3.0755e-5. The complex pair: sum of the roots is
    /// −ā3 = −169.98043, so 2·Re = −169.98043 + 3.1e-5 → Re = −84.99020;
    /// the sum of pairwise products is ā2 = |λ|² + 2·r·Re λ, so
    /// |λ|² = 13000.2711 − 2·3.0755e-5·84.9902 = 13000.2659 and
    /// Im = sqrt(13000.2659 − 84.9902²) = sqrt(5776.932) = 76.0061.
    #[test]
    fn open_loop_poles_match_the_paper() {
        let p = open_loop_poles(ServoParams::paper().coefficients().as_array());
        assert!(
            p[0].im.abs() < 1e-12 && (p[0].re + 3.0755e-5).abs() < 1e-8,
            "{:?}",
            p[0]
        );
        assert!(
            (p[1].re + 84.9902).abs() < 0.5e-4 && (p[1].im - 76.0061).abs() < 0.5e-4,
            "{:?}",
            p[1]
        );
        assert!(
            (p[2].re + 84.9902).abs() < 0.5e-4 && (p[2].im + 76.0061).abs() < 0.5e-4,
            "{:?}",
            p[2]
        );
        // ζ = −Re/|λ| = 84.9902/sqrt(13000.2659) = 84.9902/114.0187 = 0.74541.
        assert!((p[1].zeta - 0.74541).abs() < 1e-4);
    }

    /// (s+20)(s+30)(s+40) has the roots −20, −30, −40.
    #[test]
    fn surface_poles_roundtrip() {
        let p = cubic_roots(90.0, 2600.0, 24000.0);
        for (pole, want) in p.iter().zip([-20.0, -30.0, -40.0]) {
            assert!((pole.re - want).abs() < 1e-9 && pole.im.abs() < 1e-9);
        }
    }
}
