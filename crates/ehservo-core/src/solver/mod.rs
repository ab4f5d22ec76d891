//! Embedded explicit Runge–Kutta pairs with error control: the adaptive
//! integrators beside [`crate::rk4`], over the same [`OdeState`].
//!
//! One step of an s-stage pair (c, A, b, b̂) of orders p(p̂) from (t, y):
//!
//! ```text
//! kᵢ = f(t + cᵢ·h, y + h·Σⱼ aᵢⱼ·kⱼ)          i = 1..s
//! y₁ = y + h·Σ bᵢ·kᵢ                          (order p, propagated)
//! ê  = h·Σ (bᵢ − b̂ᵢ)·kᵢ                       (the local error estimate)
//! err = √( 1/n · Σ (êᵢ / (atolᵢ + rtol·max(|yᵢ|, |y₁ᵢ|)))² )
//! ```
//!
//! The step is accepted when err ≤ 1. The next step comes from Gustafsson's
//! PI controller as Hairer and Wanner's DOPRI5 code has it (Hairer, Nørsett
//! & Wanner, *Solving ODEs I*, §II.4; Hairer & Wanner, *Solving ODEs II*,
//! §IV.2, eq. (2.43c)):
//!
//! ```text
//! h_new = h · clamp(0.9 · err^(−α) · err_old^β, 0.2, 10),   α = 1/(p̂+1) − 0.75·β
//! ```
//!
//! with err_old the last accepted step's error (at least 10⁻⁴); after a
//! rejection the step only shrinks (by at most 5×), and a step that follows
//! a rejection does not grow. The first step of a run is Hairer's starting
//! guess (*Solving ODEs I*, §II.4, p. 169). [`Adaptive::integrate`]
//! integrates exactly to an end time (the last step is cut to land on it)
//! and keeps the step size for the next call.
//!
//! Every step, accepted or rejected, is counted in saturating arithmetic
//! against [`StepControl::max_steps`]: beyond it, and when the step falls
//! below ten ulps of the time, the integration stops with a [`Failure`]
//! (a result, never a panic or a hang). A trial whose solution or error
//! is not finite is rejected like a too-large error.
//!
//! ```
//! use ehservo_core::solver::{dopri5::DOPRI5, Adaptive, StepControl, scaled_rms};
//!
//! // ẏ = −y from y(0) = 1 to t = 1 at rtol 1e-8: e⁻¹ within a few 1e-8.
//! let mut y = [1.0];
//! let mut a = Adaptive::new();
//! let ctl = StepControl { max_step: 1.0, max_steps: 10_000 };
//! let norm = |y0: &[f64; 1], y1: &[f64; 1], e: &[f64; 1]| scaled_rms(&[(y0, y1, e)], 1e-8, &[1e-12]);
//! a.integrate(&DOPRI5, &ctl, |_t, y: &[f64; 1], d: &mut [f64; 1]| d[0] = -y[0], norm, |_| {}, 0.0, 1.0, &mut y)
//!     .expect("within the budget");
//! assert!((y[0] - (-1f64).exp()).abs() < 1e-7);
//! assert!(a.counts.accepted > 1);
//! ```

pub mod bs32;
pub mod dopri5;
pub mod rosenbrock23;

use crate::rk4::OdeState;

/// The most stages of a pair here (Dormand–Prince's seven).
pub const MAX_STAGES: usize = 7;

/// The step's safety factor.
const SAFETY: f64 = 0.9;
/// The most a step may shrink in one go (h_new ≥ 0.2·h).
const FAC_MIN: f64 = 0.2;
/// The most a step may grow in one go (h_new ≤ 10·h).
const FAC_MAX: f64 = 10.0;
/// The floor of the PI controller's memory of the last error.
const ERR_OLD_MIN: f64 = 1e-4;

/// An embedded pair's Butcher tableau.
#[derive(Debug)]
pub struct Tableau {
    /// The method's name as a scenario spells it (`"dopri5"`).
    pub name: &'static str,
    /// The nodes cᵢ.
    pub c: &'static [f64],
    /// The rows of A below the diagonal (row i has i entries).
    pub a: &'static [&'static [f64]],
    /// The weights of the propagated solution.
    pub b: &'static [f64],
    /// The error weights bᵢ − b̂ᵢ.
    pub e: &'static [f64],
    /// The order p of the propagated solution.
    pub order: u32,
    /// The order p̂ of the embedded one (the error's exponent is 1/(p̂+1)).
    pub error_order: u32,
    /// The PI controller's β.
    pub beta: f64,
}

impl Tableau {
    /// The number of stages s (function evaluations per step).
    pub fn stages(&self) -> usize {
        self.b.len()
    }
}

/// A one-step method with an embedded error estimate, as
/// [`Adaptive::integrate`] drives it: an explicit pair ([`Tableau`]) or a
/// linearly implicit one ([`rosenbrock23::Rosenbrock23`]).
pub trait Method<S: OdeState> {
    /// The order p of the propagated solution (the first step's guess).
    fn order(&self) -> u32;
    /// The order p̂ whose local error the estimate is (exponent 1/(p̂+1)).
    fn error_order(&self) -> u32;
    /// The PI controller's β.
    fn beta(&self) -> f64;
    /// The factor the caller's error norm is multiplied by at the relative
    /// tolerance `rtol` (1: the norm as it is). A method that propagates
    /// the lower-order solution sets it above 1 so that its global error
    /// stays proportional to the tolerance
    /// ([`rosenbrock23::Rosenbrock23`]).
    fn error_weight(&self, _rtol: f64) -> f64 {
        1.0
    }
    /// Right-hand side evaluations a step takes for a state of `dim`
    /// components (the work a step counts against a run's limit).
    fn evaluations(&self, dim: usize) -> usize;
    /// One trial step from (t, y) with `f0` = f(t, y): the solution y₁ and
    /// the error estimate ê, or `None` when no step of size `h` can be
    /// formed there (a singular iteration matrix): the step is then
    /// rejected and shrunk like one whose error is not finite.
    fn trial<F: FnMut(f64, &S, &mut S)>(
        &self,
        f: &mut F,
        t: f64,
        y: &S,
        f0: &S,
        h: f64,
    ) -> Option<(S, S)>;
}

impl<S: OdeState> Method<S> for Tableau {
    fn order(&self) -> u32 {
        self.order
    }
    fn error_order(&self) -> u32 {
        self.error_order
    }
    fn beta(&self) -> f64 {
        self.beta
    }
    fn evaluations(&self, _dim: usize) -> usize {
        self.stages()
    }
    fn trial<F: FnMut(f64, &S, &mut S)>(
        &self,
        f: &mut F,
        t: f64,
        y: &S,
        f0: &S,
        h: f64,
    ) -> Option<(S, S)> {
        let mut k = [S::zero(); MAX_STAGES];
        k[0] = *f0;
        Some(trial(self, f, t, y, &mut k, h))
    }
}

/// The bounds of the step size and of the work.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepControl {
    /// The largest step (s).
    pub max_step: f64,
    /// The most steps, accepted and rejected, that [`Adaptive::counts`]
    /// may reach (it carries over calls: a run's whole budget).
    pub max_steps: u64,
}

/// Steps taken so far, counted in saturating arithmetic.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StepCounts {
    /// Steps whose error was within the tolerance.
    pub accepted: u64,
    /// Steps tried and refused (the error too large or not finite).
    pub rejected: u64,
}

impl StepCounts {
    /// Accepted and rejected steps together (saturating).
    pub fn total(&self) -> u64 {
        self.accepted.saturating_add(self.rejected)
    }
}

/// Why an integration stopped before its end time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Failure {
    /// The step budget [`StepControl::max_steps`] was spent at time `t`.
    StepBudget {
        /// Where the integration had come to (s).
        t: f64,
    },
    /// The step needed fell below ten ulps of the time at `t` (a
    /// singularity, or a right-hand side with no finite solution there).
    StepTooSmall {
        /// Where the integration had come to (s).
        t: f64,
        /// The step it would have needed (s).
        h: f64,
    },
}

/// An adaptive integration's memory between calls: the step size to try
/// next, the PI controller's last error, and the counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adaptive {
    /// The next step to try; 0 before the first step (then guessed).
    h: f64,
    /// The last accepted step's error (PI memory).
    err_old: f64,
    /// The steps taken so far.
    pub counts: StepCounts,
}

impl Default for Adaptive {
    fn default() -> Self {
        Self::new()
    }
}

/// Σ over the parts (y₀, y₁, ê) of (êᵢ / (atolᵢ + rtol·max(|y₀ᵢ|, |y₁ᵢ|)))²,
/// divided by the number of components, square-rooted: the error norm
/// above. `atol` holds one value for every component, or one per
/// component across the parts in order (a shorter list repeats its last
/// value). A component whose ê is exactly 0 adds 0, whatever its
/// tolerance; NaN when any ê is not finite.
pub fn scaled_rms(parts: &[(&[f64], &[f64], &[f64])], rtol: f64, atol: &[f64]) -> f64 {
    let mut sum = 0.0;
    let mut n = 0usize;
    for (y0, y1, e) in parts {
        for ((a, b), d) in y0.iter().zip(y1.iter()).zip(e.iter()) {
            let at = atol.get(n).or(atol.last()).copied().unwrap_or(0.0);
            let sc = at + rtol * a.abs().max(b.abs());
            // A zero estimate is no error even where the tolerance is 0
            // (atol 0 on a state that stays at 0): 0/0 would be NaN and
            // reject every step. A nonzero one against 0 is infinite.
            let r = if *d == 0.0 { 0.0 } else { d / sc };
            sum += r * r;
            n += 1;
        }
    }
    if n == 0 {
        return 0.0;
    }
    libm::sqrt(sum / n as f64)
}

impl Adaptive {
    /// Before the first step: the step will be guessed.
    pub const fn new() -> Self {
        Self {
            h: 0.0,
            err_old: ERR_OLD_MIN,
            counts: StepCounts {
                accepted: 0,
                rejected: 0,
            },
        }
    }

    /// The step size the next call will try first (0 before any).
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// Integrates `ẏ = f(t, y)` from `t0` to exactly `t1` with the method
    /// `tab` (a pair's [`Tableau`], or any [`Method`]), the error norm `norm(y₀, y₁, ê)` (1 = at the tolerance,
    /// e.g. [`scaled_rms`]) and `limit` applied to the state after every
    /// accepted step (a limited integrator's bounds). No step crosses
    /// `t1`; the step size carries over to the next call.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate<S, M, F, N, L>(
        &mut self,
        tab: &M,
        ctl: &StepControl,
        mut f: F,
        norm: N,
        mut limit: L,
        t0: f64,
        t1: f64,
        y: &mut S,
    ) -> Result<(), Failure>
    where
        S: OdeState,
        M: Method<S>,
        F: FnMut(f64, &S, &mut S),
        N: Fn(&S, &S, &S) -> f64,
        L: FnMut(&mut S),
    {
        if t1 <= t0 || t1.is_nan() || t0.is_nan() {
            return Ok(());
        }
        let mut f0 = S::zero();
        let mut t = t0;
        f(t, y, &mut f0);
        if !(self.h > 0.0 && self.h.is_finite()) {
            let cap = ctl.max_step.min(t1 - t0);
            self.h = initial_step(tab.order(), &mut f, &norm, t, y, &f0, cap);
        }
        let beta = tab.beta();
        let expo = 1.0 / f64::from(tab.error_order() + 1) - 0.75 * beta;
        let mut after_reject = false;
        // Bounded: every pass counts a step against max_steps, or returns.
        loop {
            let rest = t1 - t;
            let mut h = self.h.min(ctl.max_step);
            // Land on t1; never leave a sliver of under 1% of a step (nor
            // step beyond max_step to avoid one, but for the rounding of
            // t1 − t: a sample's first step is max_step = step exactly).
            let last = h * 1.01 >= rest && rest <= ctl.max_step * (1.0 + 1e-9);
            if last {
                h = rest;
            }
            if h <= 10.0 * f64::EPSILON * t1.abs().max(f64::MIN_POSITIVE) {
                return Err(Failure::StepTooSmall { t, h });
            }
            if self.counts.total() >= ctl.max_steps {
                return Err(Failure::StepBudget { t });
            }
            let err = match tab.trial(&mut f, t, y, &f0, h) {
                Some((y1, e)) => {
                    let err = norm(y, &y1, &e);
                    if err.is_finite() && y1.all_finite() {
                        Some((err, y1))
                    } else {
                        None
                    }
                }
                None => None,
            };
            let (err, y1) = err.unwrap_or((f64::INFINITY, *y));
            // err^α, 0 for a zero error (the growth is then FAC_MAX).
            let fac11 = libm::pow(err, expo);
            if err <= 1.0 {
                self.counts.accepted = self.counts.accepted.saturating_add(1);
                let fac = (fac11 / libm::pow(self.err_old, beta) / SAFETY)
                    .clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
                let mut h_new = h / fac;
                if after_reject {
                    h_new = h_new.min(h);
                }
                self.err_old = err.max(ERR_OLD_MIN);
                *y = y1;
                limit(y);
                after_reject = false;
                if last {
                    // A step cut to land on t1 says little of the next:
                    // keep the larger of its proposal and the step tried.
                    self.h = h_new.max(self.h.min(ctl.max_step));
                    return Ok(());
                }
                self.h = h_new;
                t += h;
                f(t, y, &mut f0);
            } else {
                self.counts.rejected = self.counts.rejected.saturating_add(1);
                let shrink = (fac11 / SAFETY).min(1.0 / FAC_MIN);
                // A NaN error shrinks by the most (fac11 = ∞ or NaN).
                let shrink = if shrink.is_nan() {
                    1.0 / FAC_MIN
                } else {
                    shrink
                };
                self.h = h / shrink;
                after_reject = true;
            }
        }
    }
}

/// One trial step of `tab` from (t, y) with k[0] = f(t, y) given: the
/// propagated solution and the error estimate ê.
fn trial<S: OdeState, F: FnMut(f64, &S, &mut S)>(
    tab: &Tableau,
    f: &mut F,
    t: f64,
    y: &S,
    k: &mut [S; MAX_STAGES],
    h: f64,
) -> (S, S) {
    let s = tab.stages();
    for i in 1..s {
        let mut ys = *y;
        for (j, a) in tab.a[i].iter().enumerate() {
            if *a != 0.0 {
                ys.axpy(h * a, &k[j]);
            }
        }
        f(t + tab.c[i] * h, &ys, &mut k[i]);
    }
    let mut y1 = *y;
    let mut e = S::zero();
    for ((ki, b), ei) in k.iter().zip(tab.b).zip(tab.e) {
        if *b != 0.0 {
            y1.axpy(h * b, ki);
        }
        if *ei != 0.0 {
            e.axpy(h * ei, ki);
        }
    }
    (y1, e)
}

/// Hairer's starting step (*Solving ODEs I*, §II.4, p. 169): from the
/// sizes of y and f in the error norm, one explicit Euler step to gauge
/// f's change, at most `cap`.
fn initial_step<S: OdeState, F: FnMut(f64, &S, &mut S), N: Fn(&S, &S, &S) -> f64>(
    order: u32,
    f: &mut F,
    norm: &N,
    t: f64,
    y: &S,
    f0: &S,
    cap: f64,
) -> f64 {
    let d0 = norm(y, y, y);
    let d1 = norm(y, y, f0);
    let h0 = if d0 < 1e-5 || d1 < 1e-5 || !(d0.is_finite() && d1.is_finite()) {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    let h0 = h0.min(cap);
    let mut y1 = *y;
    y1.axpy(h0, f0);
    let mut f1 = S::zero();
    f(t + h0, &y1, &mut f1);
    let mut df = f1;
    df.axpy(-1.0, f0);
    let d2 = norm(y, y, &df) / h0;
    let dm = d1.max(d2);
    let h1 = if dm <= 1e-15 || !dm.is_finite() {
        (h0 * 1e-3).max(1e-6)
    } else {
        libm::pow(0.01 / dm, 1.0 / f64::from(order))
    };
    (100.0 * h0).min(h1).min(cap)
}

#[cfg(test)]
mod tests;
