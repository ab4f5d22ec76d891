//! The one bisection every search uses (the league's margin, the
//! reproduction's boundary scans): it ends, whatever the tolerance.
//!
//! A bracket [lo, hi] of doubles is halved until it is at most `tol` wide.
//! A tolerance below the spacing of doubles at the bracket can never be
//! reached (the midpoint of two adjacent doubles is one of them), so
//! [`check_tolerance`] refuses it as bad input, and [`bisect`] stops anyway
//! when the midpoint equals an end or after [`MAX_HALVINGS`] halvings.

use crate::scenario::Reason;

/// Most halvings a bisection makes: a bracket of doubles is at most 2¹⁰²⁴
/// wide and its ends are adjacent once it is 2⁻¹⁰⁷⁴ wide, so 2100 halvings
/// (> 1024 + 1074) always reach adjacent ends.
pub const MAX_HALVINGS: u32 = 2100;

/// The spacing of doubles at |x|: the gap from |x| to the next double up
/// (2⁻¹⁰⁷⁴ at 0, 2⁹⁷¹ at `f64::MAX`). `x` finite.
pub fn ulp(x: f64) -> f64 {
    let a = x.abs();
    if a >= f64::MAX {
        // The gap below MAX (the next double up is ∞).
        return a - f64::from_bits(a.to_bits() - 1);
    }
    f64::from_bits(a.to_bits() + 1) - a
}

/// Whether bisecting [lo, hi] (finite, lo < hi) to `tol` can end by the
/// tolerance: `tol` finite, > 0, below hi − lo, and at least twice the
/// spacing of doubles at the bracket's larger end. The error is the reason.
pub fn check_tolerance(lo: f64, hi: f64, tol: f64) -> Result<(), Reason> {
    let span = hi - lo;
    if !span.is_finite() {
        return Err(Reason::Other(format!(
            "the bracket [{lo:e}, {hi:e}] is wider than the largest double: narrow it"
        )));
    }
    if !(tol.is_finite() && tol > 0.0 && tol < span) {
        return Err(Reason::Other(format!(
            "must be > 0 and below high − low = {span} (got {tol:?})"
        )));
    }
    let spacing = 2.0 * ulp(lo.abs().max(hi.abs()));
    if tol < spacing {
        return Err(Reason::Other(format!(
            "{tol:e} is below the spacing of doubles at the bracket (2·ulp({:e}) = {spacing:e}): \
             the bisection could never reach it",
            lo.abs().max(hi.abs())
        )));
    }
    Ok(())
}

/// Halvings needed to bring [lo, hi] to `tol` (bounded by [`MAX_HALVINGS`]).
pub fn halvings(lo: f64, hi: f64, tol: f64) -> u32 {
    let n = ((hi - lo) / tol).log2().ceil();
    if n.is_nan() || n <= 0.0 {
        0
    } else if n >= f64::from(MAX_HALVINGS) {
        MAX_HALVINGS
    } else {
        n as u32
    }
}

/// Bisects [lo, hi] while it is wider than `tol`: `keeps_lo(mid)` says
/// whether mid replaces lo (true) or hi (false). Ends by the tolerance, at
/// adjacent doubles, or after [`MAX_HALVINGS`]; returns the bracket and the
/// number of evaluations.
pub fn bisect<E>(
    mut lo: f64,
    mut hi: f64,
    tol: f64,
    mut keeps_lo: impl FnMut(f64) -> Result<bool, E>,
) -> Result<(f64, f64, u32), E> {
    let mut n = 0;
    while hi - lo > tol && n < MAX_HALVINGS {
        // (lo + hi)/2 as the searches always computed it; halves first
        // where the sum would overflow.
        let mid = if (lo + hi).is_finite() {
            0.5 * (lo + hi)
        } else {
            0.5 * lo + 0.5 * hi
        };
        // The midpoint of adjacent doubles is one of them (or the bracket
        // is not finite): nothing is left to halve.
        if !(mid > lo && mid < hi) {
            break;
        }
        n += 1;
        if keeps_lo(mid)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok((lo, hi, n))
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact doubles are the point
mod tests {
    use super::*;

    /// ulp(1) = 2⁻⁵² (the machine epsilon), ulp(0) = the smallest
    /// subnormal, ulp(MAX) = 2^(1023 − 52).
    #[test]
    fn ulp_by_hand() {
        assert_eq!(ulp(1.0), f64::EPSILON);
        assert_eq!(ulp(-1.0), f64::EPSILON);
        assert_eq!(ulp(0.0), f64::from_bits(1));
        assert_eq!(ulp(f64::MAX), 2f64.powi(971));
        assert_eq!(ulp(1e10), 2f64.powi(33 - 52)); // 2³³ ≤ 1e10 < 2³⁴
    }

    /// A tolerance of 1e-20 at 1e10 (spacing 2·2⁻¹⁹ ≈ 3.8e-6) is refused;
    /// 1e-5 is accepted; a bracket wider than MAX is refused.
    #[test]
    fn unreachable_tolerances_are_refused() {
        let e = check_tolerance(1e10, 1e10 + 1.0, 1e-20).unwrap_err();
        assert!(e.contains("spacing of doubles"), "{e}");
        assert!(check_tolerance(1e10, 1e10 + 1.0, 1e-5).is_ok());
        assert!(check_tolerance(-1e308, 1e308, 1.0)
            .unwrap_err()
            .contains("wider"));
        assert!(check_tolerance(0.0, 1.0, 0.0).is_err());
        assert!(check_tolerance(0.0, 1.0, 2.0).is_err());
    }

    /// √2 on [1, 2] to 2⁻¹⁰: the bracket holds √2 and is 2⁻¹⁰ wide after
    /// exactly 10 halvings.
    #[test]
    fn bisects_to_the_tolerance() {
        let (lo, hi, n) = bisect(1.0, 2.0, 2f64.powi(-10), |x| Ok::<_, ()>(x * x < 2.0)).unwrap();
        assert_eq!(n, 10);
        assert_eq!(hi - lo, 2f64.powi(-10));
        assert!(lo * lo < 2.0 && hi * hi >= 2.0);
    }

    /// A tolerance no bracket of doubles can reach (0) still ends, at
    /// adjacent doubles: [1e10, 1e10 + 1] holds 2¹⁹ spacings of 2⁻¹⁹, so
    /// 19 halvings; [−MAX, MAX] ends too, within 2100.
    #[test]
    fn an_unreachable_tolerance_still_ends_at_adjacent_doubles() {
        let (lo, hi, n) = bisect(1e10, 1e10 + 1.0, 0.0, |x| Ok::<_, ()>(x < 1e10 + 0.3)).unwrap();
        assert_eq!(f64::from_bits(lo.to_bits() + 1), hi);
        assert_eq!(n, 19);
        let (lo, hi, _) = bisect(-f64::MAX, f64::MAX, 0.0, |x| Ok::<_, ()>(x < 1.0)).unwrap();
        assert!(lo < 1.0 && hi >= 1.0 && f64::from_bits(lo.to_bits() + 1) == hi);
    }

    #[test]
    fn halvings_are_bounded() {
        assert_eq!(halvings(0.0, 1.0, 0.25), 2);
        assert_eq!(halvings(0.0, 1.0, 2.0), 0);
        assert_eq!(
            halvings(-f64::MAX, f64::MAX, f64::from_bits(1)),
            MAX_HALVINGS
        );
    }
}
