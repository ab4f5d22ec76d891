//! One classic fourth-order Runge–Kutta step over a fixed-size state.
//!
//! ```text
//! k1 = f(t, y)
//! k2 = f(t + h/2, y + h/2·k1)
//! k3 = f(t + h/2, y + h/2·k2)
//! k4 = f(t + h,   y + h·k3)
//! y ← y + h/6·(k1 + 2k2 + 2k3 + k4)
//! ```
//!
//! The state is any [`OdeState`]: a `Copy` value on the stack with an
//! `axpy`, so the step never allocates. The derivative is a pure function
//! `f(t, y, dy)` that writes into `dy` (as ode_solvers' `System`). The
//! caller owns time: it passes `t` and never accumulates it.

use crate::math::Real;

/// A state RK4 can integrate: copyable, with `self += a·other`.
///
/// Fixed-size arrays are states; a struct of several is one with an
/// `axpy` over its parts:
///
/// ```
/// use ehservo_core::rk4::{rk4_step, OdeState};
///
/// /// A position and a velocity, kept apart.
/// #[derive(Clone, Copy)]
/// struct Body { x: f64, v: f64 }
///
/// impl OdeState for Body {
///     fn zero() -> Self { Body { x: 0.0, v: 0.0 } }
///     fn axpy(&mut self, a: f64, o: &Self) { self.x += a * o.x; self.v += a * o.v; }
///     fn all_finite(&self) -> bool { self.x.is_finite() && self.v.is_finite() }
/// }
///
/// // ẍ = −1 from rest at x = 1: x(t) = cos t.
/// let mut y = Body { x: 1.0, v: 0.0 };
/// let h = 0.01;
/// let f = |_t: f64, s: &Body, ds: &mut Body| *ds = Body { x: s.v, v: -s.x };
/// for k in 0..100 {
///     rk4_step(f, k as f64 * h, &mut y, h);
/// }
/// // RK4's global error is O(h⁴): 1e-8 is ample at h = 0.01.
/// assert!((y.x - 1f64.cos()).abs() < 1e-8 && (y.v + 1f64.sin()).abs() < 1e-8);
/// ```
pub trait OdeState<T: Real = f64>: Copy {
    /// The zero state.
    fn zero() -> Self;
    /// `self ← self + a·other`.
    fn axpy(&mut self, a: T, other: &Self);
    /// Every component is finite.
    fn all_finite(&self) -> bool;
    /// `self ← base + a·other`, computed as `axpy` computes it (the same
    /// bits as copying `base` and calling `axpy`). The default does that;
    /// implementations write each component once instead, so that an RK4
    /// stage never reloads a copy it has just half-updated (a wide load
    /// across narrower stores stalls the store forwarding on x86).
    #[inline]
    fn set_axpy(&mut self, base: &Self, a: T, other: &Self) {
        *self = *base;
        self.axpy(a, other);
    }
    /// `self ← self + a·other` only if every component of the result is
    /// finite; returns whether it was applied (self is untouched if not).
    /// The default copies the state; implementations may check first and
    /// write second instead.
    #[inline]
    fn axpy_finite(&mut self, a: T, other: &Self) -> bool {
        let mut next = *self;
        next.axpy(a, other);
        if next.all_finite() {
            *self = next;
            true
        } else {
            false
        }
    }
    /// `self ← base + a·self` (an Euler step from `base` with the
    /// derivative in `self`, computed as `axpy` computes it), returning
    /// whether every component of the result is finite. `self` is written
    /// either way. The default copies the state; implementations may do it
    /// in one pass.
    #[inline]
    fn euler_from(&mut self, base: &Self, a: T) -> bool {
        let mut next = *base;
        next.axpy(a, self);
        *self = next;
        self.all_finite()
    }
}

/// `d[i] ← b[i] + a·d[i]` for every i, returning whether every result is
/// finite: one pass (the sum of 0·v in eight lanes is NaN exactly when
/// some v is ±∞ or NaN; see [`axpy_results_finite`]).
#[inline(always)]
pub fn euler_results_finite<T: Real>(d: &mut [T], b: &[T], a: T) -> bool {
    let mut lane = [T::ZERO; 8];
    let n = d.len().min(b.len());
    let (d, b) = (&mut d[..n], &b[..n]);
    let mut dc = d.chunks_exact_mut(8);
    let mut bc = b.chunks_exact(8);
    for (cd, cb) in (&mut dc).zip(&mut bc) {
        for ((l, x), y) in lane.iter_mut().zip(cd).zip(cb) {
            let v = *y + a * *x;
            *x = v;
            *l += T::ZERO * v;
        }
    }
    let mut sum = T::ZERO;
    for (x, y) in dc.into_remainder().iter_mut().zip(bc.remainder()) {
        let v = *y + a * *x;
        *x = v;
        sum += T::ZERO * v;
    }
    for l in lane {
        sum += l;
    }
    sum == T::ZERO
}

/// Whether every `s[i] + a·o[i]` is finite, without writing: 0·v is ±0 for
/// a finite v and NaN otherwise, so the lane sums are NaN exactly when some
/// result is not finite (branch-free, eight lanes).
#[inline]
pub fn axpy_results_finite<T: Real>(s: &[T], a: T, o: &[T]) -> bool {
    let mut lane = [T::ZERO; 8];
    let n = s.len().min(o.len());
    let (sc, oc) = (s[..n].chunks_exact(8), o[..n].chunks_exact(8));
    let (sr, or) = (sc.remainder(), oc.remainder());
    for (cs, co) in sc.zip(oc) {
        for ((l, x), y) in lane.iter_mut().zip(cs).zip(co) {
            *l += T::ZERO * (*x + a * *y);
        }
    }
    let mut sum = T::ZERO;
    for (x, y) in sr.iter().zip(or) {
        sum += T::ZERO * (*x + a * *y);
    }
    for l in lane {
        sum += l;
    }
    sum == T::ZERO
}

impl<T: Real, const N: usize> OdeState<T> for [T; N] {
    #[inline]
    fn zero() -> Self {
        [T::ZERO; N]
    }
    #[inline]
    fn axpy(&mut self, a: T, other: &Self) {
        for (s, &o) in self.iter_mut().zip(other.iter()) {
            *s += a * o;
        }
    }
    #[inline]
    fn set_axpy(&mut self, base: &Self, a: T, other: &Self) {
        for ((s, &b), &o) in self.iter_mut().zip(base.iter()).zip(other.iter()) {
            *s = b + a * o;
        }
    }
    #[inline]
    fn all_finite(&self) -> bool {
        self.iter().all(|v| v.is_finite())
    }
    #[inline]
    fn axpy_finite(&mut self, a: T, other: &Self) -> bool {
        if axpy_results_finite(self, a, other) {
            self.axpy(a, other);
            true
        } else {
            false
        }
    }
    #[inline]
    fn euler_from(&mut self, base: &Self, a: T) -> bool {
        euler_results_finite(self, base, a)
    }
}

/// One RK4 step of size `h` from `(t, y)`, in place.
///
/// ```
/// use ehservo_core::rk4::rk4_step;
///
/// // ẏ = −y: on a linear ODE one RK4 step is the Taylor polynomial of
/// // e^{−h} to degree 4, 1 − h + h²/2 − h³/6 + h⁴/24.
/// let h = 0.1;
/// let mut y = [1.0];
/// rk4_step(|_t, y: &[f64; 1], dy: &mut [f64; 1]| dy[0] = -y[0], 0.0, &mut y, h);
/// let taylor = 1.0 - h + h * h / 2.0 - h.powi(3) / 6.0 + h.powi(4) / 24.0;
/// assert!((y[0] - taylor).abs() < 1e-15);
/// ```
#[inline]
pub fn rk4_step<T: Real, S: OdeState<T>, F: FnMut(T, &S, &mut S)>(mut f: F, t: T, y: &mut S, h: T) {
    let mut k1 = S::zero();
    f(t, y, &mut k1);
    rk4_step_with_k1(f, t, y, &k1, h);
}

/// One RK4 step when the first stage `k1 = f(t, y)` is already known (the
/// simulator evaluates it together with the logged control law).
///
/// ```
/// use ehservo_core::rk4::{rk4_step, rk4_step_with_k1};
///
/// // The same step as `rk4_step`, its first stage computed beforehand.
/// let f = |_t: f64, y: &[f64; 2], dy: &mut [f64; 2]| *dy = [y[1], -y[0]];
/// let (mut a, mut b) = ([1.0, 0.0], [1.0, 0.0]);
/// rk4_step(f, 0.0, &mut a, 0.1);
/// let k1 = [b[1], -b[0]];
/// rk4_step_with_k1(f, 0.0, &mut b, &k1, 0.1);
/// assert_eq!(a, b);
/// ```
#[inline]
pub fn rk4_step_with_k1<T: Real, S: OdeState<T>, F: FnMut(T, &S, &mut S)>(
    mut f: F,
    t: T,
    y: &mut S,
    k1: &S,
    h: T,
) {
    let half = T::of(0.5) * h;
    let mut k2 = S::zero();
    let mut k3 = S::zero();
    let mut k4 = S::zero();
    let mut ys = S::zero();
    ys.set_axpy(y, half, k1);
    f(t + half, &ys, &mut k2);
    ys.set_axpy(y, half, &k2);
    f(t + half, &ys, &mut k3);
    ys.set_axpy(y, h, &k3);
    f(t + h, &ys, &mut k4);
    let sixth = h / T::of(6.0);
    y.axpy(sixth, k1);
    y.axpy(T::of(2.0) * sixth, &k2);
    y.axpy(T::of(2.0) * sixth, &k3);
    y.axpy(sixth, &k4);
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    /// y' = y from y(0) = 1: one step of h gives the degree-4 Taylor
    /// polynomial 1 + h + h²/2 + h³/6 + h⁴/24 exactly (classic RK4 property).
    #[test]
    fn exponential_one_step_is_taylor_4() {
        let h = 0.1;
        let mut y = [1.0];
        rk4_step(
            |_, y: &[f64; 1], dy: &mut [f64; 1]| dy[0] = y[0],
            0.0,
            &mut y,
            h,
        );
        let taylor = 1.0 + h + h * h / 2.0 + h * h * h / 6.0 + h * h * h * h / 24.0;
        assert!((y[0] - taylor).abs() < 1e-15);
    }

    /// Harmonic oscillator x'' = −x over one period: global error O(h⁴);
    /// halving h divides the error by ≈ 16.
    #[test]
    fn fourth_order_convergence() {
        let err = |n: usize| {
            let h = 2.0 * core::f64::consts::PI / n as f64;
            let mut y = [1.0, 0.0];
            for k in 0..n {
                rk4_step(
                    |_, y: &[f64; 2], dy: &mut [f64; 2]| {
                        dy[0] = y[1];
                        dy[1] = -y[0];
                    },
                    k as f64 * h,
                    &mut y,
                    h,
                );
            }
            ((y[0] - 1.0).powi(2) + y[1].powi(2)).sqrt()
        };
        let ratio = err(50) / err(100);
        assert!((ratio - 16.0).abs() < 1.0, "ratio {ratio}");
    }

    /// axpy_finite applies a finite update and refuses one that overflows
    /// or carries a NaN, leaving the state as it was.
    #[test]
    fn axpy_finite_refuses_non_finite_results() {
        let mut s = [1.0; 11];
        assert!(s.axpy_finite(0.5, &[2.0; 11]));
        assert_eq!(s, [2.0; 11]);
        let mut bad = [0.0; 11];
        bad[10] = f64::NAN;
        assert!(!s.axpy_finite(0.5, &bad));
        assert_eq!(s, [2.0; 11]);
        let mut big = [0.0; 11];
        big[3] = f64::MAX;
        assert!(!s.axpy_finite(2.0, &big), "overflow to +inf is refused");
        assert_eq!(s, [2.0; 11]);
    }

    /// euler_from writes base + a·self as axpy computes it, and reports a
    /// non-finite or overflowing component in any position.
    #[test]
    fn euler_from_is_axpy_and_checks_every_component() {
        let base: [f64; 19] = core::array::from_fn(|i| 0.3 * i as f64 - 2.0);
        let d: [f64; 19] = core::array::from_fn(|i| 1.7 - 0.11 * (i * i) as f64);
        let mut want = base;
        want.axpy(0.01, &d);
        let mut got = d;
        assert!(got.euler_from(&base, 0.01));
        assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits));
        for k in [0, 7, 8, 15, 16, 18] {
            for bad in [f64::NAN, f64::INFINITY, f64::MAX] {
                let mut got = d;
                got[k] = bad;
                let ok = got.euler_from(&base, 2.0);
                assert!(!ok, "{bad} at {k}");
            }
        }
    }

    /// set_axpy writes base + a·other with the bits of a copy and axpy,
    /// signed zeros, infinities and NaN included, and reads nothing of
    /// what it overwrites.
    #[test]
    fn set_axpy_is_copy_then_axpy() {
        let base: [f64; 11] = [
            -0.0,
            0.0,
            1.5,
            -2.25,
            f64::MIN_POSITIVE,
            1e300,
            -1e300,
            3.0,
            f64::INFINITY,
            0.1,
            7.0,
        ];
        let o: [f64; 11] = [
            0.0,
            -0.0,
            -1.5,
            1e-310,
            2.0,
            1e300,
            -1e10,
            f64::NAN,
            1.0,
            0.2,
            -0.0,
        ];
        for a in [0.5, -0.5, 1e-3, 0.0, -0.0, 1e10] {
            let mut want = base;
            want.axpy(a, &o);
            let mut got = [f64::NAN; 11];
            got.set_axpy(&base, a, &o);
            assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "a = {a}");
        }
    }

    /// The RK4 step gives the bits of its textbook form, in which each
    /// stage's state is a copy of y updated by axpy (a nonlinear system,
    /// two states, with and without the known k1).
    #[test]
    fn stages_built_by_set_axpy_change_no_bit() {
        let f = |t: f64, y: &[f64; 2], dy: &mut [f64; 2]| {
            dy[0] = y[1] - 0.3 * y[0] * y[0] + t.sin();
            dy[1] = -y[0] / (1.0 + y[1] * y[1]);
        };
        let textbook = |t: f64, y: &mut [f64; 2], h: f64| {
            let (mut k1, mut k2, mut k3, mut k4) = ([0.0; 2], [0.0; 2], [0.0; 2], [0.0; 2]);
            f(t, y, &mut k1);
            let half = 0.5 * h;
            let mut ys = *y;
            ys.axpy(half, &k1);
            f(t + half, &ys, &mut k2);
            ys = *y;
            ys.axpy(half, &k2);
            f(t + half, &ys, &mut k3);
            ys = *y;
            ys.axpy(h, &k3);
            f(t + h, &ys, &mut k4);
            let sixth = h / 6.0;
            y.axpy(sixth, &k1);
            y.axpy(2.0 * sixth, &k2);
            y.axpy(2.0 * sixth, &k3);
            y.axpy(sixth, &k4);
        };
        let (mut a, mut b, mut c) = ([0.7, -1.3], [0.7, -1.3], [0.7, -1.3]);
        for k in 0..200 {
            let t = 0.01 * k as f64;
            textbook(t, &mut a, 0.01);
            rk4_step(f, t, &mut b, 0.01);
            let mut k1 = [0.0; 2];
            f(t, &c, &mut k1);
            rk4_step_with_k1(f, t, &mut c, &k1, 0.01);
            assert_eq!(b.map(f64::to_bits), a.map(f64::to_bits), "step {k}");
            assert_eq!(c.map(f64::to_bits), a.map(f64::to_bits), "step {k}");
        }
    }

    /// The time argument of each stage: f = t integrates to t²/2 exactly.
    #[test]
    fn stage_times() {
        let mut y = [0.0];
        rk4_step(
            |t, _: &[f64; 1], dy: &mut [f64; 1]| dy[0] = t,
            1.0,
            &mut y,
            0.5,
        );
        // ∫_1^1.5 t dt = (2.25 − 1)/2 = 0.625
        assert!((y[0] - 0.625).abs() < 1e-15);
    }
}
