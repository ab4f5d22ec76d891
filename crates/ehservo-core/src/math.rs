//! Small scalar helpers shared by the laws (`libm` underneath, so `no_std`;
//! with the `std` feature `exp` is the platform's).

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

/// `exp`: the platform's (`f64::exp`) with the `std` feature, where it is
/// the faster one (glibc's on Linux); `libm`'s without (`no_std` boards).
/// Both are faithfully rounded (error below 1 ulp); they may differ in the
/// last bit.
#[inline]
pub fn exp(v: f64) -> f64 {
    #[cfg(feature = "std")]
    {
        v.exp()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::exp(v)
    }
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

/// Euclidean norm of a slice. The squares are summed in four interleaved
/// partial sums (entry i into sum i mod 4), so the additions do not wait on
/// each other; the result may differ from a left-to-right sum in the last
/// bit.
#[inline]
pub fn norm(v: &[f64]) -> f64 {
    let mut lane = [0.0; 4];
    let chunks = v.chunks_exact(4);
    let rest = chunks.remainder();
    for c in chunks {
        for (l, a) in lane.iter_mut().zip(c) {
            *l += a * a;
        }
    }
    let mut sum = (lane[0] + lane[1]) + (lane[2] + lane[3]);
    for a in rest {
        sum += a * a;
    }
    sqrt(sum)
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
        // 3-4-5 triangle; 1..=9 (sum of squares 285) crosses the lanes.
        assert!((norm(&[3.0, 4.0]) - 5.0).abs() < 1e-15);
        let v: [f64; 9] = core::array::from_fn(|i| (i + 1) as f64);
        assert!((norm(&v) - 285f64.sqrt()).abs() < 1e-14);
        assert_eq!(norm(&[]), 0.0);
    }
}
