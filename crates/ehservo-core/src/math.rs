//! Small scalar helpers shared by the laws (`libm` underneath, so `no_std`).

/// The paper's `sgn`: −1, 0 or +1 (`sgn(0) = 0`, and `sgn(NaN) = 0`).
#[inline]
pub fn sgn(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// The saturation `sat(v) = v` for `|v| ≤ 1`, else `sgn(v)` (Remark 2).
#[inline]
pub fn sat(v: f64) -> f64 {
    v.clamp(-1.0, 1.0)
}

/// `exp`, from `libm`.
#[inline]
pub fn exp(v: f64) -> f64 {
    libm::exp(v)
}

/// `sqrt`, from `libm`.
#[inline]
pub fn sqrt(v: f64) -> f64 {
    libm::sqrt(v)
}

/// `sin`, from `libm`.
#[inline]
pub fn sin(v: f64) -> f64 {
    libm::sin(v)
}

/// `cos`, from `libm`.
#[inline]
pub fn cos(v: f64) -> f64 {
    libm::cos(v)
}

/// `tanh`, from `libm`.
#[inline]
pub fn tanh(v: f64) -> f64 {
    libm::tanh(v)
}

/// Euclidean norm of a slice.
#[inline]
pub fn norm(v: &[f64]) -> f64 {
    sqrt(v.iter().map(|a| a * a).sum())
}

/// Degrees to radians, `dr = π/180` in the paper.
pub const DR: f64 = core::f64::consts::PI / 180.0;

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    #[test]
    fn sgn_and_sat_by_hand() {
        assert_eq!(sgn(3.0), 1.0);
        assert_eq!(sgn(-0.1), -1.0);
        assert_eq!(sgn(0.0), 0.0);
        assert_eq!(sgn(f64::NAN), 0.0);
        assert_eq!(sat(0.25), 0.25);
        assert_eq!(sat(7.0), 1.0);
        assert_eq!(sat(-7.0), -1.0);
        // 3-4-5 triangle.
        assert!((norm(&[3.0, 4.0]) - 5.0).abs() < 1e-15);
    }
}
