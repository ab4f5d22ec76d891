//! The modified Rosenbrock triple of MATLAB's `ode23s`: a linearly
//! implicit (stiff) method of order 2 with a third-order error estimate,
//! L-stable, from L. F. Shampine and M. W. Reichelt, "The MATLAB ODE
//! suite", *SIAM J. Sci. Comput.* 18(1):1–22, 1997, §4.1 (the formulas
//! of `ode23s`). With J = ∂f/∂y and T = ∂f/∂t at (t, y):
//!
//! ```text
//! d = 1/(2 + √2),  e₃₂ = 6 + √2,  W = I − h·d·J
//! F₀ = f(t, y)                       k₁ = W⁻¹ (F₀ + h·d·T)
//! F₁ = f(t + h/2, y + h/2·k₁)        k₂ = W⁻¹ (F₁ − k₁) + k₁
//! y₁ = y + h·k₂                      (order 2, propagated)
//! F₂ = f(t + h, y₁)                  k₃ = W⁻¹ (F₂ − e₃₂(k₂ − F₁) − 2(k₁ − F₀) + h·d·T)
//! ê  = h/6 · (k₁ − 2k₂ + k₃)         (the local error of y₁, O(h³))
//! ```
//!
//! One LU factorisation of W (partial pivoting, on the stack: at most
//! [`MAX_DIM`] components; the core is `no_std` and allocation-free, so
//! it carries its own 30-line LU rather than nalgebra) and three solves a
//! step. W is singular only where h·d·λ = 1 for an eigenvalue λ of J (a
//! growing mode): such a step is refused ([`Method::trial`] returns
//! `None`), and [`super::Adaptive::integrate`] shrinks it as it does a
//! step whose error is not finite.
//!
//! J comes from a [`JacobianSource`]: the plant's analytic one
//! ([`Analytic`]) or forward differences ([`FiniteDifference`], n
//! evaluations); T is always a forward difference in time (one more).
//!
//! ```
//! use ehservo_core::solver::{rosenbrock23::{Rosenbrock23, FiniteDifference}, Adaptive, StepControl, scaled_rms};
//!
//! // ẏ = −10⁶(y − 1) from 0: y = 1 − e^{−10⁶t}, at y(1) = 1 in a few dozen steps
//! // (an explicit method would need ~10⁶ steps at its stability limit).
//! let m = Rosenbrock23 { jacobian: FiniteDifference::default() };
//! let mut y = [0.0];
//! let mut a = Adaptive::new();
//! let ctl = StepControl { max_step: 1.0, max_steps: 10_000 };
//! let norm = |y0: &[f64; 1], y1: &[f64; 1], e: &[f64; 1]| scaled_rms(&[(y0, y1, e)], 1e-6, &[1e-9]);
//! a.integrate(&m, &ctl, |_t, y: &[f64; 1], d: &mut [f64; 1]| d[0] = -1e6 * (y[0] - 1.0), norm, |_| {}, 0.0, 1.0, &mut y)
//!     .expect("within the budget");
//! assert!((y[0] - 1.0).abs() < 1e-6);
//! assert!(a.counts.total() < 500, "{:?}", a.counts);
//! ```

use super::Method;
use crate::rk4::OdeState;
use core::f64::consts::SQRT_2;

/// The most components of a state the method integrates.
pub const MAX_DIM: usize = 9;

/// A square matrix of up to [`MAX_DIM`] rows, row-major (`m[i][j]` =
/// ∂fᵢ/∂yⱼ for a Jacobian).
pub type Matrix = [[f64; MAX_DIM]; MAX_DIM];

/// d = 1/(2 + √2) (Shampine & Reichelt 1997, §4.1).
pub const D: f64 = 1.0 / (2.0 + SQRT_2);
/// e₃₂ = 6 + √2 (ibid.).
pub const E32: f64 = 6.0 + SQRT_2;

/// √ε: the relative size of a forward-difference increment.
const SQRT_EPS: f64 = 1.4901161193847656e-8;

/// A state read and written component by component (for the Jacobian
/// and the linear solves).
pub trait Components: OdeState {
    /// The number of components.
    fn dim(&self) -> usize;
    /// Component `i` (< dim).
    fn get(&self, i: usize) -> f64;
    /// Sets component `i` (< dim).
    fn set(&mut self, i: usize, v: f64);
}

impl<const N: usize> Components for [f64; N]
where
    [f64; N]: OdeState,
{
    fn dim(&self) -> usize {
        N
    }
    fn get(&self, i: usize) -> f64 {
        self[i]
    }
    fn set(&mut self, i: usize, v: f64) {
        self[i] = v;
    }
}

/// Where J = ∂f/∂y comes from.
pub trait JacobianSource<S> {
    /// J at (t, y), with `f0` = f(t, y) and the step `h` about to be
    /// taken, into the top-left dim × dim block of `j`.
    fn jacobian<F: FnMut(f64, &S, &mut S)>(
        &self,
        f: &mut F,
        t: f64,
        y: &S,
        f0: &S,
        h: f64,
        j: &mut Matrix,
    );
    /// Right-hand side evaluations it takes for `dim` components.
    fn evaluations(&self, dim: usize) -> usize;
}

/// Forward differences, one evaluation per column: column j is
/// (f(t, y + δⱼeⱼ) − f(t, y))/δⱼ with δⱼ = √ε·max(|yⱼ|, |h·fⱼ|, floorⱼ)
/// (the component's size, how far the step moves it, or its floor; √ε
/// when all three are 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiniteDifference {
    /// Each component's smallest typical size, in its unit.
    pub floor: [f64; MAX_DIM],
}

impl Default for FiniteDifference {
    /// No floor: the increment follows the component and the step.
    fn default() -> Self {
        Self {
            floor: [0.0; MAX_DIM],
        }
    }
}

impl<S: Components> JacobianSource<S> for FiniteDifference {
    fn jacobian<F: FnMut(f64, &S, &mut S)>(
        &self,
        f: &mut F,
        t: f64,
        y: &S,
        f0: &S,
        h: f64,
        j: &mut Matrix,
    ) {
        let n = y.dim().min(MAX_DIM);
        let mut fp = S::zero();
        for c in 0..n {
            let yc = y.get(c);
            let size = yc.abs().max((h * f0.get(c)).abs()).max(self.floor[c]);
            let size = if size > 0.0 && size.is_finite() {
                size
            } else {
                1.0
            };
            let mut yp = *y;
            yp.set(c, yc + SQRT_EPS * size);
            // The increment as represented (yc + δ rounds).
            let delta = yp.get(c) - yc;
            f(t, &yp, &mut fp);
            for (r, row) in j.iter_mut().enumerate().take(n) {
                row[c] = (fp.get(r) - f0.get(r)) / delta;
            }
        }
    }
    fn evaluations(&self, dim: usize) -> usize {
        dim
    }
}

/// An analytic Jacobian: `J(t, y, j)` writes ∂f/∂y at (t, y).
#[derive(Debug, Clone, Copy)]
pub struct Analytic<J>(pub J);

impl<S, J: Fn(f64, &S, &mut Matrix)> JacobianSource<S> for Analytic<J> {
    fn jacobian<F: FnMut(f64, &S, &mut S)>(
        &self,
        _f: &mut F,
        t: f64,
        y: &S,
        _f0: &S,
        _h: f64,
        j: &mut Matrix,
    ) {
        (self.0)(t, y, j);
    }
    fn evaluations(&self, _dim: usize) -> usize {
        0
    }
}

/// The `ode23s` triple with its Jacobian's source.
#[derive(Debug, Clone, Copy)]
pub struct Rosenbrock23<J> {
    /// Where J comes from.
    pub jacobian: J,
}

/// The method's name as a scenario spells it.
pub const NAME: &str = "rosenbrock23";

/// An LU factorisation with partial pivoting of an n × n block.
struct Lu {
    m: Matrix,
    piv: [usize; MAX_DIM],
    n: usize,
}

impl Lu {
    /// Factors the top-left n × n block of `m` = W = I − h·d·J; `None`
    /// when a pivot is below n·ε times max(1, the largest entry) (singular
    /// to working precision: W holds I, so 1 is its least scale) or
    /// not finite.
    fn new(mut m: Matrix, n: usize) -> Option<Self> {
        let big = m
            .iter()
            .take(n)
            .flat_map(|r| r[..n].iter())
            .fold(1.0f64, |a, v| a.max(v.abs()));
        if !(big.is_finite() && big > 0.0) {
            return None;
        }
        let tiny = n as f64 * f64::EPSILON * big;
        let mut piv = [0usize; MAX_DIM];
        for k in 0..n {
            let p = (k..n)
                .max_by(|&a, &b| m[a][k].abs().total_cmp(&m[b][k].abs()))
                .unwrap_or(k);
            let pivot = m[p][k].abs();
            if pivot.is_nan() || pivot <= tiny {
                return None;
            }
            m.swap(k, p);
            piv[k] = p;
            let row_k = m[k];
            for row in m.iter_mut().take(n).skip(k + 1) {
                let l = row[k] / row_k[k];
                row[k] = l;
                for (x, r) in row[k + 1..n].iter_mut().zip(&row_k[k + 1..n]) {
                    *x -= l * r;
                }
            }
        }
        Some(Self { m, piv, n })
    }

    /// Solves W·x = b in place.
    fn solve(&self, b: &mut [f64; MAX_DIM]) {
        let n = self.n;
        for k in 0..n {
            b.swap(k, self.piv[k]);
        }
        for i in 1..n {
            let s: f64 = (0..i).map(|c| self.m[i][c] * b[c]).sum();
            b[i] -= s;
        }
        for i in (0..n).rev() {
            let s: f64 = (i + 1..n).map(|c| self.m[i][c] * b[c]).sum();
            b[i] = (b[i] - s) / self.m[i][i];
        }
    }
}

/// The components of `s` in a stack vector.
fn vec_of<S: Components>(s: &S) -> [f64; MAX_DIM] {
    let mut v = [0.0; MAX_DIM];
    for (i, x) in v.iter_mut().enumerate().take(s.dim().min(MAX_DIM)) {
        *x = s.get(i);
    }
    v
}

/// The vector (g(0), …, g(n−1), 0, …).
fn build(n: usize, g: impl Fn(usize) -> f64) -> [f64; MAX_DIM] {
    let mut v = [0.0; MAX_DIM];
    for (i, x) in v.iter_mut().enumerate().take(n) {
        *x = g(i);
    }
    v
}

/// A state with the components of `v`.
fn state_of<S: Components>(v: &[f64; MAX_DIM]) -> S {
    let mut s = S::zero();
    for (i, x) in v.iter().enumerate().take(s.dim().min(MAX_DIM)) {
        s.set(i, *x);
    }
    s
}

impl<S: Components, J: JacobianSource<S>> Method<S> for Rosenbrock23<J> {
    fn order(&self) -> u32 {
        2
    }
    /// ê estimates y₁'s local error, O(h³): the exponent is 1/3.
    fn error_order(&self) -> u32 {
        2
    }
    fn beta(&self) -> f64 {
        // The explicit pairs' β (Hairer's DOPRI5 default).
        0.04
    }
    /// 1/√rtol: the local error is held to rtol^(3/2) (atol·√rtol). An
    /// order-2 method that propagates its order-2 solution under per-step
    /// control has a global error ∝ tol^(2/3) (N ∝ tol^(−1/3) steps each
    /// adding tol); asking tol^(3/2) of each step makes it ∝ tol
    /// (Shampine's tolerance proportionality), measured in
    /// `solver::tests::rosenbrock23_holds_the_closed_forms_to_the_tolerance`.
    fn error_weight(&self, rtol: f64) -> f64 {
        if rtol > 0.0 {
            1.0 / libm::sqrt(rtol)
        } else {
            1.0
        }
    }
    /// F₀, ∂f/∂t's difference, F₁, F₂ and the Jacobian's.
    fn evaluations(&self, dim: usize) -> usize {
        4 + self.jacobian.evaluations(dim)
    }
    fn trial<F: FnMut(f64, &S, &mut S)>(
        &self,
        f: &mut F,
        t: f64,
        y: &S,
        f0: &S,
        h: f64,
    ) -> Option<(S, S)> {
        let n = y.dim();
        if n > MAX_DIM {
            return None;
        }
        let mut j = [[0.0; MAX_DIM]; MAX_DIM];
        self.jacobian.jacobian(f, t, y, f0, h, &mut j);
        // W = I − h·d·J.
        for (r, row) in j.iter_mut().enumerate().take(n) {
            for (c, w) in row.iter_mut().enumerate().take(n) {
                *w = f64::from(u8::from(r == c)) - h * D * *w;
            }
        }
        let lu = Lu::new(j, n)?;
        // h·d·T, T = (f(t + δ, y) − F₀)/δ.
        let dt = SQRT_EPS * t.abs().max(h);
        let mut ft = S::zero();
        f(t + dt, y, &mut ft);
        let (yv, f0v, ftv) = (vec_of(y), vec_of(f0), vec_of(&ft));
        let hdt = build(n, |i| h * D * (ftv[i] - f0v[i]) / dt);
        let mut k1 = build(n, |i| f0v[i] + hdt[i]);
        lu.solve(&mut k1);
        let mut f1 = S::zero();
        f(
            t + 0.5 * h,
            &state_of(&build(n, |i| yv[i] + 0.5 * h * k1[i])),
            &mut f1,
        );
        let f1v = vec_of(&f1);
        let mut k2 = build(n, |i| f1v[i] - k1[i]);
        lu.solve(&mut k2);
        let k2 = build(n, |i| k2[i] + k1[i]);
        let y1s: S = state_of(&build(n, |i| yv[i] + h * k2[i]));
        let mut f2 = S::zero();
        f(t + h, &y1s, &mut f2);
        let f2v = vec_of(&f2);
        let mut k3 = build(n, |i| {
            f2v[i] - E32 * (k2[i] - f1v[i]) - 2.0 * (k1[i] - f0v[i]) + hdt[i]
        });
        lu.solve(&mut k3);
        let e = build(n, |i| h / 6.0 * (k1[i] - 2.0 * k2[i] + k3[i]));
        Some((y1s, state_of(&e)))
    }
}
