//! Small scalar helpers shared by the laws, and [`Real`], the float type
//! the core computes in (`f64` or `f32`).
//!
//! **f64** is the simulator's type: its results are the reference, and the
//! `std` feature gives it the platform's `exp` (glibc's on Linux, faster).
//! **f32** is a Cortex-M4F's: its single-precision FPU does `+ − × ÷ √` in
//! hardware (f64 would be emulated in software, tens of times slower). For
//! f32 every transcendental (`exp`, `sin`, `cos`, `tanh`) is `libm`'s, with
//! or without `std`, so a host build and a board compute the same bits.

use core::fmt::{Debug, Display};
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for f64 {}
}

/// The float type of the core: `f64` or `f32` (sealed).
///
/// Constants in the laws are written `T::of(2.0)`: exact for f64 (so f64
/// results are bit for bit those of plain f64 code), rounded to nearest for
/// f32.
pub trait Real:
    sealed::Sealed
    + Copy
    + Default
    + Debug
    + Display
    + PartialEq
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + Send
    + Sync
    + 'static
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// +∞.
    const INFINITY: Self;
    /// NaN.
    const NAN: Self;
    /// π.
    const PI: Self;
    /// The largest exponent the RBF's factorised Gaussians may form
    /// (`exp(±SPAN)` must be finite and its reciprocal normal): 300 for
    /// f64, 80 for f32 (whose `exp` overflows past 88.7).
    const EXP_SPAN: Self;
    /// The type's name (`"f64"`, `"f32"`).
    const NAME: &'static str;

    /// From an f64, rounded to nearest (exact for f64).
    fn of(v: f64) -> Self;
    /// From a count (exact below 2²⁴ for f32, 2⁵³ for f64).
    fn of_usize(n: usize) -> Self;
    /// To f64 (exact).
    fn to_f64(self) -> f64;
    /// |v|.
    fn abs(self) -> Self;
    /// Finite (not ±∞ nor NaN).
    fn is_finite(self) -> bool;
    /// NaN.
    fn is_nan(self) -> bool;
    /// The larger (the non-NaN one if one is NaN).
    fn max(self, o: Self) -> Self;
    /// The smaller (the non-NaN one if one is NaN).
    fn min(self, o: Self) -> Self;
    /// Clamped to `[lo, hi]`.
    fn clamp(self, lo: Self, hi: Self) -> Self;
    /// √v.
    fn sqrt(self) -> Self;
    /// eᵛ.
    fn exp(self) -> Self;
    /// sin v.
    fn sin(self) -> Self;
    /// cos v.
    fn cos(self) -> Self;
    /// `(sin v, cos v)` in one argument reduction; the same bits as
    /// `(v.sin(), v.cos())`.
    fn sin_cos(self) -> (Self, Self);
    /// tanh v.
    fn tanh(self) -> Self;
}

macro_rules! real_common {
    ($t:ty) => {
        const ZERO: Self = 0.0;
        const ONE: Self = 1.0;
        const INFINITY: Self = <$t>::INFINITY;
        const NAN: Self = <$t>::NAN;
        #[inline(always)]
        fn of_usize(n: usize) -> Self {
            n as $t
        }
        #[inline(always)]
        fn to_f64(self) -> f64 {
            self as f64
        }
        #[inline(always)]
        fn abs(self) -> Self {
            <$t>::abs(self)
        }
        #[inline(always)]
        fn is_finite(self) -> bool {
            <$t>::is_finite(self)
        }
        #[inline(always)]
        fn is_nan(self) -> bool {
            <$t>::is_nan(self)
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            <$t>::max(self, o)
        }
        #[inline(always)]
        fn min(self, o: Self) -> Self {
            <$t>::min(self, o)
        }
        #[inline(always)]
        fn clamp(self, lo: Self, hi: Self) -> Self {
            <$t>::clamp(self, lo, hi)
        }
    };
}

impl Real for f64 {
    real_common!(f64);
    const PI: Self = core::f64::consts::PI;
    const EXP_SPAN: Self = 300.0;
    const NAME: &'static str = "f64";
    #[inline(always)]
    fn of(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        libm::sqrt(self)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        #[cfg(feature = "std")]
        {
            f64::exp(self)
        }
        #[cfg(not(feature = "std"))]
        {
            libm::exp(self)
        }
    }
    #[inline(always)]
    fn sin(self) -> Self {
        libm::sin(self)
    }
    #[inline(always)]
    fn cos(self) -> Self {
        libm::cos(self)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        libm::sincos(self)
    }
    #[inline(always)]
    fn tanh(self) -> Self {
        libm::tanh(self)
    }
}

impl Real for f32 {
    real_common!(f32);
    const PI: Self = core::f32::consts::PI;
    const EXP_SPAN: Self = 80.0;
    const NAME: &'static str = "f32";
    #[inline(always)]
    fn of(v: f64) -> Self {
        v as f32
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        libm::sqrtf(self)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        libm::expf(self)
    }
    #[inline(always)]
    fn sin(self) -> Self {
        libm::sinf(self)
    }
    #[inline(always)]
    fn cos(self) -> Self {
        libm::cosf(self)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        libm::sincosf(self)
    }
    #[inline(always)]
    fn tanh(self) -> Self {
        libm::tanhf(self)
    }
}

/// The paper's `sgn`: −1, 0 or +1 (`sgn(0) = 0`, and `sgn(NaN) = 0`).
#[inline]
pub fn sgn<T: Real>(v: T) -> T {
    if v > T::ZERO {
        T::ONE
    } else if v < T::ZERO {
        -T::ONE
    } else {
        T::ZERO
    }
}

/// The saturation `sat(v) = v` for `|v| ≤ 1`, else `sgn(v)` (Remark 2).
#[inline]
pub fn sat<T: Real>(v: T) -> T {
    v.clamp(-T::ONE, T::ONE)
}

/// `exp` ([`Real::exp`]).
#[inline]
pub fn exp<T: Real>(v: T) -> T {
    v.exp()
}

/// `sqrt` ([`Real::sqrt`]).
#[inline]
pub fn sqrt<T: Real>(v: T) -> T {
    v.sqrt()
}

/// `sin` ([`Real::sin`]).
#[inline]
pub fn sin<T: Real>(v: T) -> T {
    v.sin()
}

/// `cos` ([`Real::cos`]).
#[inline]
pub fn cos<T: Real>(v: T) -> T {
    v.cos()
}

/// `tanh` ([`Real::tanh`]).
#[inline]
pub fn tanh<T: Real>(v: T) -> T {
    v.tanh()
}

/// Euclidean norm of a slice. The squares are summed in four interleaved
/// partial sums (entry i into sum i mod 4), so the additions do not wait on
/// each other; the result may differ from a left-to-right sum in the last
/// bit.
#[inline]
pub fn norm<T: Real>(v: &[T]) -> T {
    let mut lane = [T::ZERO; 4];
    let chunks = v.chunks_exact(4);
    let rest = chunks.remainder();
    for c in chunks {
        for (l, &a) in lane.iter_mut().zip(c) {
            *l += a * a;
        }
    }
    let mut sum = (lane[0] + lane[1]) + (lane[2] + lane[3]);
    for &a in rest {
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
        assert_eq!(norm::<f64>(&[]), 0.0);
    }
}
