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

/// Roots of `s³ + c2·s² + c1·s + c0`, as the eigenvalues of its companion
/// matrix, sorted by real part then imaginary part (descending).
pub fn cubic_roots(c2: f64, c1: f64, c0: f64) -> [Pole; 3] {
    let m = Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -c0, -c1, -c2);
    let ev = m.complex_eigenvalues();
    let mut poles = [Pole::from(ev[0]), Pole::from(ev[1]), Pole::from(ev[2])];
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
