//! Small scalar helpers shared by the laws, and [`Real`], the float type
//! the core computes in (`f64` or `f32`).
//!
//! **f64** is the simulator's type: its results are the reference, and the
//! `std` feature gives it the platform's `exp` (glibc's on Linux, faster;
//! on an x86-64 host with FMA and AVX2 and glibc ≥ 2.28, [`Real::exp4`]
//! computes four of them at once in AVX2 lanes, to glibc's bit, after a
//! self-test on first use).
//! **f32** is a Cortex-M4F's: its single-precision FPU does `+ − × ÷ √` in
//! hardware (f64 would be emulated in software, tens of times slower). For
//! f32 the same portable code runs with or without `std`, so a host build
//! and a board compute the same bits: `exp` and `tanh` are `libm`'s (pure
//! f32), `sin`/`cos` are Cephes' single-precision kernels in f32 arithmetic
//! ([`sin_cos_f32`]: libm's `sinf`/`cosf` and fpmath's evaluate in f64, which
//! a Cortex-M4F does in software, about 500–1500 instructions a call), and
//! `sqrt` is the FPU's `VSQRT.F32` on hard-float Arm targets, `libm::sqrtf`
//! elsewhere — both correctly rounded (IEEE 754), so the same bits.

use core::fmt::{Debug, Display};
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

#[cfg(all(
    feature = "std",
    target_arch = "x86_64",
    target_os = "linux",
    target_env = "gnu"
))]
mod exp4;

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
///
/// ```
/// use ehservo_core::math::{sat, Real};
///
/// // One generic function for the host's f64 and the board's f32.
/// fn boundary_layer<T: Real>(sigma: T, mu: T) -> T {
///     T::of(2.0) * sat(sigma / mu)
/// }
/// assert_eq!(boundary_layer(0.5f64, 1.0), 1.0); // inside the layer: 2·0.5
/// assert_eq!(boundary_layer(-3.0f32, 1.0), -2.0); // outside: 2·sgn
/// ```
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
    /// Whether the RBF's factorised Gaussians, when one axis is outside
    /// [`Real::EXP_SPAN`], handle that axis alone (f32: zeros when it is
    /// so far that every kernel is below e^−S, else its five direct
    /// exponentials, 8 in all instead of 15) or fall back to direct
    /// exponentials for all three (f64: its results stay those of the
    /// reference, bit for bit).
    const RBF_AXIS_FALLBACK: bool;
    /// Whether the NNBVSC's Euler step keeps the reference's operations,
    /// `w + dt·(a·g − bw·w)` (f64: its results are the independently
    /// checked reference's, bit for bit), or folds dt into the step's
    /// factors, `(w − (dt·bw)·w) + (dt·a)·g`: four operations a weight
    /// instead of five (f32: −117 instructions a step on average on a
    /// Cortex-M4F; its results are held to f64's by the measured tolerance
    /// of docs/float-types.md).
    const FOLDED_EULER: bool;
    /// The type's name (`"f64"`, `"f32"`).
    const NAME: &'static str;

    /// From an f64, rounded to nearest (exact for f64).
    fn of(v: f64) -> Self;
    /// From a count (exact below 2²⁴ for f32, 2⁵³ for f64).
    fn of_usize(n: usize) -> Self;
    /// From a u32, converted directly (no detour through f64, which a
    /// Cortex-M4F does in software); exact below 2²⁴ for f32.
    fn of_u32(n: u32) -> Self;
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
    /// ∛v (real, odd: ∛(−v) = −∛v); `libm`'s `cbrt`/`cbrtf`.
    fn cbrt(self) -> Self;
    /// eᵛ.
    fn exp(self) -> Self;
    /// `[e^v0, e^v1, e^v2, e^v3]`: the same bits as four [`Real::exp`]s.
    /// For f64 with `std` on an x86-64 host with FMA and AVX2 and glibc
    /// ≥ 2.28, glibc's `exp` in four AVX2 lanes when every argument is in
    /// its fast path (2⁻⁵⁴ ≤ |v| < 512) and a self-test on first use finds
    /// the platform's `exp` giving its bits (`math/exp4.rs`); otherwise
    /// four calls.
    #[inline(always)]
    fn exp4(v: [Self; 4]) -> [Self; 4] {
        v.map(Self::exp)
    }
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
        fn of_u32(n: u32) -> Self {
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
    const RBF_AXIS_FALLBACK: bool = false;
    const FOLDED_EULER: bool = false;
    const NAME: &'static str = "f64";
    #[inline(always)]
    fn of(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // With std, the compiler's own square root (one instruction, encoded
        // for the function's target features); `libm::sqrt` on x86-64 is an
        // inline-asm SSE `sqrtsd`, whose legacy encoding inside AVX code
        // (the NNBVSC's AVX2 step) stalls on the AVX/SSE transition. Both
        // round correctly (IEEE 754), so they agree to the bit.
        #[cfg(feature = "std")]
        {
            f64::sqrt(self)
        }
        #[cfg(not(feature = "std"))]
        {
            libm::sqrt(self)
        }
    }
    #[inline(always)]
    fn cbrt(self) -> Self {
        libm::cbrt(self)
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
    fn exp4(v: [Self; 4]) -> [Self; 4] {
        // Where `exp` is glibc's and the CPU has what its FMA copy needs.
        #[cfg(all(
            feature = "std",
            target_arch = "x86_64",
            target_os = "linux",
            target_env = "gnu"
        ))]
        if let Some(e) = exp4::exp4(v) {
            return e;
        }
        v.map(Self::exp)
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
    const RBF_AXIS_FALLBACK: bool = true;
    const FOLDED_EULER: bool = true;
    const NAME: &'static str = "f32";
    #[inline(always)]
    fn of(v: f64) -> Self {
        v as f32
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        sqrt_f32(self)
    }
    #[inline(always)]
    fn cbrt(self) -> Self {
        libm::cbrtf(self)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        libm::expf(self)
    }
    #[inline(always)]
    fn sin(self) -> Self {
        sin_cos_f32(self).0
    }
    #[inline(always)]
    fn cos(self) -> Self {
        sin_cos_f32(self).1
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        sin_cos_f32(self)
    }
    #[inline(always)]
    fn tanh(self) -> Self {
        libm::tanhf(self)
    }
}

/// √v in f32, correctly rounded: the FPU's `VSQRT.F32` on a hard-float
/// Arm target (one instruction, 14 cycles on a Cortex-M4F, where
/// `libm::sqrtf` is about 150 instructions of integer code), `libm::sqrtf`
/// elsewhere (SSE's `sqrtss` on x86_64). IEEE 754 requires both to round
/// correctly, so they agree to the bit.
#[inline(always)]
fn sqrt_f32(v: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    {
        // rustc's `sreg` operand class asks for the double-precision `vfp2`
        // feature, which a Cortex-M4F (single-precision VFPv4) lacks: the
        // value goes through a core register and s15, which is declared
        // clobbered (a caller-saved register: the compiler keeps nothing
        // live in it across this, at no cost, where saving it around the
        // root with vpush/vpop cost about 6 cycles a root).
        let bits: u32;
        // SAFETY: register moves and one VSQRT.F32, which touch no memory
        // and no register but s15, declared clobbered; VSQRT may set
        // FPSCR's sticky exception flags (inexact, invalid), which is why
        // `preserves_flags` is not claimed.
        #[allow(unsafe_code)]
        unsafe {
            core::arch::asm!(
                "vmov s15, {x}",
                "vsqrt.f32 s15, s15",
                "vmov {x}, s15",
                x = inout(reg) v.to_bits() => bits,
                out("s15") _,
                options(pure, nomem, nostack)
            );
        }
        f32::from_bits(bits)
    }
    #[cfg(all(not(all(target_arch = "arm", target_abi = "eabihf")), feature = "std"))]
    {
        f32::sqrt(v) // (as for f64: the compiler's instruction)
    }
    #[cfg(not(any(all(target_arch = "arm", target_abi = "eabihf"), feature = "std")))]
    {
        libm::sqrtf(v)
    }
}

/// `(sin x, cos x)` in f32 arithmetic only: Cephes' `sinf`/`cosf`
/// (S. L. Moshier): x reduced by the octant j = ⌊4|x|/π⌋ (made even) with
/// π/4 in three parts (exact products for |x| ≤ 8192), then the minimax
/// polynomials of sin and cos on [−π/4, π/4]. Cephes states a peak
/// relative error of about 1 ulp there; the tests bound it by 2 ulp
/// against f64. Beyond 8192 rad, or for ±∞ and NaN, `libm::sincosf`.
#[inline]
pub fn sin_cos_f32(x: f32) -> (f32, f32) {
    const FOPI: f32 = 1.273_239_5; // 4/π
    const DP1: f32 = 0.785_156_25;
    const DP2: f32 = 2.418_756_5e-4;
    const DP3: f32 = 3.774_895e-8;
    let ax = x.abs();
    if ax.is_nan() || ax > 8192.0 {
        return libm::sincosf(x);
    }
    let mut j = (ax * FOPI) as u32;
    let mut y = j as f32;
    if j & 1 == 1 {
        j += 1;
        y += 1.0;
    }
    j &= 7;
    let (mut s_neg, mut c_neg) = (x < 0.0, false);
    if j > 3 {
        j -= 4;
        s_neg = !s_neg;
        c_neg = !c_neg;
    }
    if j > 1 {
        c_neg = !c_neg;
    }
    let z = ((ax - y * DP1) - y * DP2) - y * DP3;
    let zz = z * z;
    let sp = ((-1.951_529_6e-4 * zz + 8.332_161e-3) * zz - 1.666_665_5e-1) * zz * z + z;
    let cp =
        ((2.443_315_7e-5 * zz - 1.388_731_6e-3) * zz + 4.166_664_6e-2) * zz * zz - 0.5 * zz + 1.0;
    let (s, c) = if j == 1 || j == 2 { (cp, sp) } else { (sp, cp) };
    (if s_neg { -s } else { s }, if c_neg { -c } else { c })
}

/// The paper's `sgn`: −1, 0 or +1 (`sgn(0) = 0`, and `sgn(NaN) = 0`).
///
/// ```
/// use ehservo_core::math::sgn;
///
/// assert_eq!([sgn(-2.5), sgn(0.0), sgn(f64::NAN), sgn(1e-300)], [-1.0, 0.0, 0.0, 1.0]);
/// ```
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
///
/// ```
/// use ehservo_core::math::sat;
///
/// assert_eq!([sat(-3.0), sat(0.25), sat(7.0)], [-1.0, 0.25, 1.0]);
/// ```
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
///
/// ```
/// use ehservo_core::math::norm;
///
/// // 3-4-5, and 1 in each of 16 entries: √16 = 4.
/// assert_eq!(norm(&[3.0, 4.0]), 5.0);
/// assert_eq!(norm(&[1.0f32; 16]), 4.0);
/// ```
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
///
/// ```
/// use ehservo_core::math::DR;
///
/// assert!((180.0 * DR - std::f64::consts::PI).abs() < 1e-15);
/// ```
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

    /// f32's sin_cos is (sin, cos) to the bit, each within 2 f32 ulp of
    /// f64's over ±4π and at 10⁵ points to 8192 rad; exp within one ulp;
    /// sqrt correctly rounded.
    #[test]
    fn f32_transcendentals_against_f64() {
        let ulp = |v: f32| f32::from_bits(v.abs().to_bits() + 1) - v.abs();
        for i in -20_000..=20_000 {
            let v = i as f32 * (4.0 * core::f32::consts::PI / 20_000.0);
            let (s, c) = Real::sin_cos(v);
            assert_eq!(
                (s.to_bits(), c.to_bits()),
                (Real::sin(v).to_bits(), Real::cos(v).to_bits())
            );
            let (s64, c64) = (f64::from(v).sin(), f64::from(v).cos());
            // 2 ulp of the result, or 2 ulp of 2⁻²⁶ near a zero (where the
            // reduced argument's own rounding, 6e-8·|x|/2²⁴, dominates).
            let tol = |r: f64| {
                2.0 * f64::from(ulp(r as f32)).max(1.5e-8 * f64::from(v.abs()).max(1.0) / 16.0)
            };
            assert!(
                (f64::from(s) - s64).abs() <= tol(s64),
                "sin {v}: {s} vs {s64}"
            );
            assert!(
                (f64::from(c) - c64).abs() <= tol(c64),
                "cos {v}: {c} vs {c64}"
            );
            let e = Real::exp(v / 4.0);
            assert!(
                (f64::from(e) - (f64::from(v) / 4.0).exp()).abs() <= f64::from(ulp(e)),
                "exp {v}"
            );
            let r = Real::sqrt(v.abs());
            assert_eq!(r, (f64::from(v.abs()).sqrt()) as f32, "sqrt {v}");
        }
        let mut worst = 0.0f64;
        for i in 0..100_000 {
            let v = (i as f32 * 0.081_92) * if i % 2 == 0 { 1.0 } else { -1.0 };
            let (s, c) = sin_cos_f32(v);
            let (s64, c64) = (f64::from(v).sin(), f64::from(v).cos());
            for (a, b) in [(s, s64), (c, c64)] {
                let err = (f64::from(a) - b).abs()
                    / f64::from(ulp(b as f32))
                        .max(f64::from(ulp(1.0)) * f64::from(v.abs()) / 2f64.powi(24));
                worst = worst.max(err);
            }
        }
        assert!(worst <= 2.0, "{worst} ulp");
    }
}
