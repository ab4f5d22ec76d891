//! Desired trajectories with their first three derivatives.
//!
//! The laws need `z = [θd, θ̇d, θ̈d, θ⃛d]` (Assumption A3; the last entry is the
//! leading term of (12) and (24), and the last four entries of Φ in (20)).
//! The paper's reference is `θd(t) = 5°·sin(2πt)`.

use crate::error::{positive, ParamError};
use crate::math::{Real, DR};

/// A trajectory known with its first three derivatives.
///
/// ```
/// use ehservo_core::reference::{Reference, Sine};
///
/// // Any reference, by its z(t): here the peak |θ⃛d| over one period.
/// fn peak_jerk(r: &impl Reference, period: f64) -> f64 {
///     (0..1000).map(|k| r.z(k as f64 * period / 1000.0)[3].abs()).fold(0.0, f64::max)
/// }
/// // 5°·sin(2πt): max |θ⃛d| = A·ω³ = (5π/180)·(2π)³ ≈ 21.6 rad/s³, at t = 0.
/// let a_w3 = 5f64.to_radians() * (2.0 * std::f64::consts::PI).powi(3);
/// assert!((peak_jerk(&Sine::paper(), 1.0) - a_w3).abs() < 1e-9 * a_w3);
/// ```
pub trait Reference<T = f64> {
    /// `z(t) = [θd, θ̇d, θ̈d, θ⃛d]` (rad, rad/s, rad/s², rad/s³).
    fn z(&self, t: T) -> [T; 4];
}

/// `θd(t) = A·sin(ω·t)`, differentiated analytically.
///
/// ```
/// use ehservo_core::reference::{Reference, Sine};
///
/// let r = Sine::paper(); // 5°·sin(2πt)
/// let (a, w) = (5f64.to_radians(), 2.0 * std::f64::consts::PI);
/// // A quarter period: θd at its peak, θ̇d = 0, θ̈d = −Aω².
/// let z = r.z(0.25);
/// assert!((z[0] - a).abs() < 1e-15 && z[1].abs() < 1e-12);
/// assert!((z[2] + a * w * w).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sine<T = f64> {
    /// Amplitude A (rad).
    pub amplitude: T,
    /// Angular frequency ω (rad/s).
    pub omega: T,
}

impl<T: Real> Sine<T> {
    /// From an amplitude in degrees and a frequency in hertz.
    pub fn from_deg_hz(amplitude_deg: T, frequency_hz: T) -> Self {
        Self {
            amplitude: amplitude_deg * T::of(DR),
            omega: T::of(2.0) * T::PI * frequency_hz,
        }
    }

    /// The same reference in another float type.
    pub fn cast<U: Real>(&self) -> Sine<U> {
        Sine {
            amplitude: U::of(self.amplitude.to_f64()),
            omega: U::of(self.omega.to_f64()),
        }
    }
}

impl Sine<f64> {
    /// The paper's `5°·sin(2πt)`.
    pub fn paper() -> Self {
        Self::from_deg_hz(5.0, 1.0)
    }
}

impl<T: Real> Reference<T> for Sine<T> {
    #[inline]
    fn z(&self, t: T) -> [T; 4] {
        let (s, c) = (self.omega * t).sin_cos();
        let a = self.amplitude;
        let w = self.omega;
        [a * s, a * w * c, -a * w * w * s, -a * w * w * w * c]
    }
}

/// A linear frequency sweep `θd(t) = A·sin φ(t)` from `f0` to `f1` over
/// `duration` T, differentiated analytically:
///
/// - `φ(t) = 2π(f0·t + (f1 − f0)·t²/(2T))` for 0 ≤ t ≤ T, so the
///   instantaneous frequency φ̇/2π runs linearly from f0 to f1;
/// - after T the frequency is held at f1: `φ(t) = φ(T) + 2π·f1·(t − T)`;
///   before 0 it is f0: `φ(t) = 2π·f0·t`.
///
/// With φ̇, φ̈ (φ⃛ = 0): θ̇d = A·cos φ·φ̇, θ̈d = A(−sin φ·φ̇² + cos φ·φ̈),
/// θ⃛d = A(−cos φ·φ̇³ − 3 sin φ·φ̇·φ̈). φ̈ = 2π(f1 − f0)/T inside the sweep
/// and 0 outside, so θ̈d steps by −A·cos φ(T)·2π(f1 − f0)/T at t = T (and
/// θ⃛d is not defined there): keep the horizon within the sweep to avoid it.
///
/// ```
/// use ehservo_core::reference::{Chirp, Reference};
///
/// // 1 → 5 Hz over 4 s, amplitude 0.01 rad.
/// let c = Chirp::try_new(0.01, 1.0, 5.0, 4.0)?;
/// // Half way, the frequency is half way: (1 + 5)/2 = 3 Hz.
/// assert!((c.frequency_at(2.0) - 3.0).abs() < 1e-12);
/// // At t = 0: θd = 0 and θ̇d = A·2πf0.
/// let z = c.z(0.0);
/// assert_eq!(z[0], 0.0);
/// assert!((z[1] - 0.01 * 2.0 * std::f64::consts::PI).abs() < 1e-15);
/// assert_eq!(Chirp::try_new(0.01, 0.0, 5.0, 4.0).unwrap_err().name, "f0");
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chirp {
    /// Amplitude A (rad).
    pub amplitude: f64,
    /// Start frequency f0 (Hz).
    pub f0: f64,
    /// End frequency f1 (Hz).
    pub f1: f64,
    /// Sweep duration T (s), > 0.
    pub duration: f64,
}

impl Chirp {
    /// Checked: finite amplitude, frequencies finite and > 0, duration finite and > 0.
    pub fn try_new(amplitude: f64, f0: f64, f1: f64, duration: f64) -> Result<Self, ParamError> {
        if !amplitude.is_finite() {
            return Err(ParamError::new("amplitude", "must be finite", amplitude));
        }
        positive("f0", f0)?;
        positive("f1", f1)?;
        positive("duration", duration)?;
        Ok(Self {
            amplitude,
            f0,
            f1,
            duration,
        })
    }

    /// The instantaneous frequency at t (Hz).
    pub fn frequency_at(&self, t: f64) -> f64 {
        if t <= 0.0 {
            self.f0
        } else if t >= self.duration {
            self.f1
        } else {
            self.f0 + (self.f1 - self.f0) * t / self.duration
        }
    }

    /// (φ, φ̇, φ̈) at t.
    fn phase(&self, t: f64) -> (f64, f64, f64) {
        let tp = 2.0 * core::f64::consts::PI;
        let k = (self.f1 - self.f0) / self.duration;
        if t <= 0.0 {
            (tp * self.f0 * t, tp * self.f0, 0.0)
        } else if t <= self.duration {
            (
                tp * (self.f0 * t + 0.5 * k * t * t),
                tp * (self.f0 + k * t),
                tp * k,
            )
        } else {
            let end = tp * (self.f0 * self.duration + 0.5 * k * self.duration * self.duration);
            (end + tp * self.f1 * (t - self.duration), tp * self.f1, 0.0)
        }
    }
}

impl Reference<f64> for Chirp {
    fn z(&self, t: f64) -> [f64; 4] {
        let (p, w, dw) = self.phase(t);
        let (s, c) = libm::sincos(p);
        let a = self.amplitude;
        [
            a * s,
            a * c * w,
            a * (-s * w * w + c * dw),
            a * (-c * w * w * w - 3.0 * s * w * dw),
        ]
    }
}

/// Most components of a [`Multisine`].
pub const MAX_COMPONENTS: usize = 8;

/// One component `A·sin(2π·f·t + p)` of a [`Multisine`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Component {
    /// Amplitude A (rad).
    pub amplitude: f64,
    /// Frequency f (Hz).
    pub frequency: f64,
    /// Phase p (rad).
    pub phase: f64,
}

/// `θd(t) = Σ A_i·sin(ω_i·t + p_i)`, up to [`MAX_COMPONENTS`] terms, in a
/// fixed array; each term differentiated analytically (as [`Sine`]).
///
/// ```
/// use ehservo_core::reference::{Component, Multisine, Reference};
///
/// // 1 Hz and 3 Hz, the second a quarter turn ahead.
/// let half_pi = std::f64::consts::FRAC_PI_2;
/// let m = Multisine::try_new(&[
///     Component { amplitude: 0.02, frequency: 1.0, phase: 0.0 },
///     Component { amplitude: 0.01, frequency: 3.0, phase: half_pi },
/// ])?;
/// // t = 0: θd = 0.02·sin 0 + 0.01·sin(π/2) = 0.01,
/// // θ̇d = 0.02·2π·cos 0 + 0.01·6π·cos(π/2) = 0.04π.
/// let z = m.z(0.0);
/// assert!((z[0] - 0.01).abs() < 1e-15);
/// assert!((z[1] - 0.04 * std::f64::consts::PI).abs() < 1e-15);
/// assert_eq!(Multisine::try_new(&[]).unwrap_err().name, "components");
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Multisine {
    comps: [Component; MAX_COMPONENTS],
    n: usize,
}

impl Multisine {
    /// Checked: 1..=8 components, amplitudes and phases finite, frequencies
    /// finite and > 0.
    pub fn try_new(components: &[Component]) -> Result<Self, ParamError> {
        if components.is_empty() || components.len() > MAX_COMPONENTS {
            return Err(ParamError::new(
                "components",
                "must hold 1 to 8 components",
                components.len() as f64,
            ));
        }
        let mut comps = [Component::default(); MAX_COMPONENTS];
        for (c, o) in components.iter().zip(comps.iter_mut()) {
            if !c.amplitude.is_finite() {
                return Err(ParamError::new("amplitude", "must be finite", c.amplitude));
            }
            if !c.phase.is_finite() {
                return Err(ParamError::new("phase", "must be finite", c.phase));
            }
            positive("frequency", c.frequency)?;
            *o = *c;
        }
        Ok(Self {
            comps,
            n: components.len(),
        })
    }

    /// The components.
    pub fn components(&self) -> &[Component] {
        &self.comps[..self.n]
    }
}

impl Reference<f64> for Multisine {
    fn z(&self, t: f64) -> [f64; 4] {
        let mut z = [0.0; 4];
        for c in self.components() {
            let w = 2.0 * core::f64::consts::PI * c.frequency;
            let (s, co) = libm::sincos(w * t + c.phase);
            let a = c.amplitude;
            z[0] += a * s;
            z[1] += a * w * co;
            z[2] -= a * w * w * s;
            z[3] -= a * w * w * w * co;
        }
        z
    }
}

/// A knot `(t, v)` of a piecewise-linear signal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Knot {
    /// Time (s).
    pub t: f64,
    /// Value (rad).
    pub v: f64,
}

/// The prefilter's state `[x1, x2, x3, x4]` (rad) at a knot.
pub type LagState = [f64; 4];

/// Order of the prefilter: four identical first-order lags.
pub const PREFILTER_ORDER: usize = 4;

/// A piecewise-linear signal u(t) through a prefilter of four identical
/// first-order lags of time constant τ (`τ·ẋ1 = u − x1`, `τ·ẋk = x(k−1) − xk`,
/// transfer function 1/(τs + 1)⁴: critically damped, unit DC gain), with
/// `θd = x4`. θd is C³ even where u jumps, so θ⃛d exists and is bounded.
///
/// **The signal.** Knots `(t_i, v_i)` with non-decreasing times; between
/// two knots u is linear; a jump is two knots at the same time (the value
/// just before and just after). Before the first knot u = v_0 (the filter
/// starts at rest there, x = v_0), after the last u = v_last.
///
/// **Exact evaluation.** On a segment u(s) = a + b·s (s = t − t_i) the
/// ramp-following solution is `xk_ss(s) = a + b·(s − kτ)` (k = 1..4), and
/// the deviation d = x − x_ss obeys the homogeneous chain, whose transition
/// matrix is lower-triangular Toeplitz: with σ = s/τ,
/// `d_k(s) = e^{−σ} Σ_{j=0}^{k−1} d_{k−j}(0)·σ^j/j!`.
/// The state at every knot is precomputed once ([`Prefiltered::fill_states`],
/// into a caller-owned buffer); `z(t)` finds the segment by binary search and
/// applies the closed form. The derivatives follow from the chain:
///
/// - θ̇d = ẋ4 = (x3 − x4)/τ = b + (d3 − d4)/τ,
/// - θ̈d = (x2 − 2x3 + x4)/τ² = (d2 − 2d3 + d4)/τ²,
/// - θ⃛d = (x1 − 3x2 + 3x3 − x4)/τ³ = (d1 − 3d2 + 3d3 − d4)/τ³
///
/// (the ramp-following parts cancel in the differences, which keeps them
/// accurate far from a knot). Since the impulse response is positive,
/// |θd| ≤ max |v_i|.
///
/// ```
/// use ehservo_core::reference::{Knot, LagState, Prefiltered, Reference};
///
/// // A unit step at t = 0 (two knots at the same time), τ = 0.1 s.
/// let knots = [Knot { t: 0.0, v: 0.0 }, Knot { t: 0.0, v: 1.0 }];
/// let mut states = [LagState::default(); 2];
/// Prefiltered::fill_states(&knots, 0.1, &mut states)?;
/// let r = Prefiltered::new(&knots, &states, 0.1)?;
/// // The step response of 1/(τs + 1)⁴ (an Erlang distribution's CDF), σ = t/τ:
/// // θd = 1 − e^{−σ}(1 + σ + σ²/2 + σ³/6), θ̇d = e^{−σ}σ³/(6τ).
/// for t in [0.05, 0.1, 0.4] {
///     let s: f64 = t / 0.1;
///     let e = (-s).exp();
///     let z = r.z(t);
///     assert!((z[0] - (1.0 - e * (1.0 + s + s * s / 2.0 + s.powi(3) / 6.0))).abs() < 1e-12);
///     assert!((z[1] - e * s.powi(3) / 0.6).abs() < 1e-10);
/// }
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
#[derive(Debug, Clone, Copy)]
pub struct Prefiltered<'a> {
    knots: &'a [Knot],
    states: &'a [LagState],
    tau: f64,
}

/// e^{−σ}·σ^j/j! for j = 0..3 (0 once e^{−σ} underflows).
fn poisson(sigma: f64) -> [f64; 4] {
    if sigma > 700.0 {
        return [0.0; 4];
    }
    let e = libm::exp(-sigma);
    [
        e,
        e * sigma,
        e * sigma * sigma / 2.0,
        e * sigma * sigma * sigma / 6.0,
    ]
}

/// The deviation d(s) from d(0) (transition of the homogeneous chain).
fn propagate(d0: &LagState, sigma: f64) -> LagState {
    let p = poisson(sigma);
    let mut d = [0.0; 4];
    for k in 0..4 {
        for j in 0..=k {
            d[k] += p[j] * d0[k - j];
        }
    }
    d
}

impl<'a> Prefiltered<'a> {
    /// Checks the knots (at least one, finite, times non-decreasing) and τ
    /// (finite, > 0), and writes the filter's state at every knot into
    /// `states` (as long as `knots`). O(n), no allocation.
    pub fn fill_states(
        knots: &[Knot],
        tau: f64,
        states: &mut [LagState],
    ) -> Result<(), ParamError> {
        positive("tau", tau)?;
        if knots.is_empty() {
            return Err(ParamError::new("knots", "need at least one knot", 0.0));
        }
        if states.len() != knots.len() {
            return Err(ParamError::new(
                "states",
                "must be as long as the knots",
                states.len() as f64,
            ));
        }
        for (i, k) in knots.iter().enumerate() {
            if !(k.t.is_finite() && k.v.is_finite()) {
                return Err(ParamError::new("knots", "must be finite", i as f64));
            }
            if i > 0 && k.t < knots[i - 1].t {
                return Err(ParamError::new(
                    "knots",
                    "times must not decrease (index given)",
                    i as f64,
                ));
            }
            // A segment's slope, and time measured from the first knot,
            // must be finite: (v1 − v0)/∞ would be a silent 0.
            if i > 0 && !(k.t - knots[0].t).is_finite() {
                return Err(ParamError::new(
                    "knots",
                    "the time span from the first knot overflows (index given)",
                    i as f64,
                ));
            }
            if i > 0 && k.t > knots[i - 1].t {
                let p = knots[i - 1];
                if !((k.v - p.v) / (k.t - p.t)).is_finite() {
                    return Err(ParamError::new(
                        "knots",
                        "the slope to this knot overflows (index given)",
                        i as f64,
                    ));
                }
            }
        }
        states[0] = [knots[0].v; 4];
        for i in 0..knots.len() - 1 {
            let (k0, k1) = (knots[i], knots[i + 1]);
            let dt = k1.t - k0.t;
            let x = states[i];
            states[i + 1] = if dt == 0.0 {
                x
            } else {
                Self::advance(&x, k0.v, (k1.v - k0.v) / dt, tau, dt)
            };
        }
        Ok(())
    }

    /// The state `s` after x on u(s) = a + b·s.
    fn advance(x: &LagState, a: f64, b: f64, tau: f64, s: f64) -> LagState {
        let d = Self::deviation(x, a, b, tau, s);
        core::array::from_fn(|k| d[k] + a + b * (s - (k + 1) as f64 * tau))
    }

    /// d(s) from x(0) on u(s) = a + b·s.
    fn deviation(x: &LagState, a: f64, b: f64, tau: f64, s: f64) -> LagState {
        let d0: LagState = core::array::from_fn(|k| x[k] - (a - b * (k + 1) as f64 * tau));
        propagate(&d0, s / tau)
    }

    /// The knots, their states (from [`Prefiltered::fill_states`] with the
    /// same knots and τ) and τ. Checks only the lengths and τ: states that
    /// do not come from `fill_states` give a wrong (but finite) trajectory.
    pub fn new(knots: &'a [Knot], states: &'a [LagState], tau: f64) -> Result<Self, ParamError> {
        positive("tau", tau)?;
        if knots.is_empty() || states.len() != knots.len() {
            return Err(ParamError::new(
                "states",
                "need one state per knot and at least one knot",
                states.len() as f64,
            ));
        }
        Ok(Self { knots, states, tau })
    }

    /// The time constant τ (s).
    pub fn tau(&self) -> f64 {
        self.tau
    }
}

impl Reference<f64> for Prefiltered<'_> {
    fn z(&self, t: f64) -> [f64; 4] {
        let k = self.knots;
        let first = k[0];
        if t.is_nan() || t < first.t {
            return [first.v, 0.0, 0.0, 0.0];
        }
        // The last knot at or before t.
        let i = k.partition_point(|p| p.t <= t) - 1;
        let (a, b) = if i + 1 < k.len() {
            (k[i].v, (k[i + 1].v - k[i].v) / (k[i + 1].t - k[i].t))
        } else {
            (k[i].v, 0.0)
        };
        let tau = self.tau;
        let d = Self::deviation(&self.states[i], a, b, tau, t - k[i].t);
        let x4 = d[3] + a + b * (t - k[i].t - 4.0 * tau);
        [
            x4,
            b + (d[2] - d[3]) / tau,
            (d[1] - 2.0 * d[2] + d[3]) / (tau * tau),
            (d[0] - 3.0 * d[1] + 3.0 * d[2] - d[3]) / (tau * tau * tau),
        ]
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    /// 5° = 0.0872665 rad; at t = 0: θ̇d = A·2π = 0.548311 rad/s and
    /// θ⃛d = −A·(2π)³ = −21.6464 rad/s³; at t = 0.25 s: θd = A,
    /// θ̈d = −A·(2π)² = −3.44514 rad/s².
    #[test]
    fn paper_reference_by_hand() {
        let r = Sine::paper();
        let z0 = r.z(0.0);
        assert!(z0[0].abs() < 1e-15);
        assert!((z0[1] - 0.548311).abs() < 1e-6);
        assert!(z0[2].abs() < 1e-15);
        assert!((z0[3] + 21.6464).abs() < 1e-4);
        let z = r.z(0.25);
        assert!((z[0] - 0.0872665).abs() < 1e-7);
        assert!((z[2] + 3.44514).abs() < 1e-5);
    }

    /// Each entry is the derivative of the one before (central differences).
    #[test]
    fn derivatives_are_consistent() {
        let r = Sine::from_deg_hz(3.0, 1.7);
        let h = 1e-6;
        for &t in &[0.1, 0.37, 1.9] {
            let (zp, zm, z) = (r.z(t + h), r.z(t - h), r.z(t));
            for i in 0..3 {
                let fd = (zp[i] - zm[i]) / (2.0 * h);
                assert!((fd - z[i + 1]).abs() < 1e-6 * (1.0 + z[i + 1].abs()));
            }
        }
    }
    /// A unit step at t = 0.3 through four lags of τ = 0.05: by hand,
    /// θd = 1 − e^{−σ}(1 + σ + σ²/2 + σ³/6), θ̇d = e^{−σ}σ³/(6τ),
    /// θ̈d = e^{−σ}σ²(3 − σ)/(6τ²), θ⃛d = e^{−σ}σ(6 − 6σ + σ²)/(6τ³), σ = (t − 0.3)/τ.
    #[test]
    fn prefiltered_step_is_the_four_lag_step_response() {
        let knots = [Knot { t: 0.3, v: 0.0 }, Knot { t: 0.3, v: 1.0 }];
        let mut st = [[0.0; 4]; 2];
        let tau = 0.05;
        Prefiltered::fill_states(&knots, tau, &mut st).unwrap();
        let r = Prefiltered::new(&knots, &st, tau).unwrap();
        assert_eq!(r.z(0.1), [0.0; 4]);
        for &t in &[0.3, 0.31, 0.35, 0.4, 0.5, 0.8, 2.0] {
            let sg: f64 = (t - 0.3) / tau;
            let e = (-sg).exp();
            let want = [
                1.0 - e * (1.0 + sg + sg * sg / 2.0 + sg * sg * sg / 6.0),
                e * sg.powi(3) / (6.0 * tau),
                e * sg * sg * (3.0 - sg) / (6.0 * tau * tau),
                e * sg * (6.0 - 6.0 * sg + sg * sg) / (6.0 * tau.powi(3)),
            ];
            let z = r.z(t);
            for i in 0..4 {
                let scale = tau.powi(-(i as i32));
                assert!(
                    (z[i] - want[i]).abs() < 1e-12 * scale,
                    "t = {t}, entry {i}: {} vs {}",
                    z[i],
                    want[i]
                );
            }
        }
    }

    /// A ramp of slope 2 from t = 1: far after, θd = 2(t − 1 − 4τ), θ̇d = 2.
    #[test]
    fn prefiltered_ramp_lags_by_four_tau() {
        let tau = 0.1;
        let knots = [Knot { t: 1.0, v: 0.0 }, Knot { t: 21.0, v: 40.0 }];
        let mut st = [[0.0; 4]; 2];
        Prefiltered::fill_states(&knots, tau, &mut st).unwrap();
        let r = Prefiltered::new(&knots, &st, tau).unwrap();
        let z = r.z(10.0);
        assert!((z[0] - 2.0 * (10.0 - 1.0 - 0.4)).abs() < 1e-9, "{z:?}");
        assert!((z[1] - 2.0).abs() < 1e-9);
        assert!(z[2].abs() < 1e-9 && z[3].abs() < 1e-9);
        // The state carried across the last knot: held at 40 after it.
        assert!((r.z(40.0)[0] - 40.0).abs() < 1e-9);
    }

    fn consistent(r: &impl Reference<f64>, ts: &[f64]) {
        let h = 1e-6;
        for &t in ts {
            let (zp, zm, z) = (r.z(t + h), r.z(t - h), r.z(t));
            for i in 0..3 {
                let fd = (zp[i] - zm[i]) / (2.0 * h);
                assert!(
                    (fd - z[i + 1]).abs() < 1e-5 * (1.0 + z[i + 1].abs()),
                    "t = {t}, entry {i}: {fd} vs {}",
                    z[i + 1]
                );
            }
        }
    }

    #[test]
    fn new_kinds_have_consistent_derivatives() {
        let c = Chirp::try_new(0.1, 0.2, 3.0, 5.0).unwrap();
        consistent(&c, &[0.1, 1.3, 4.9, 6.0, 8.5]);
        let m = Multisine::try_new(&[
            Component {
                amplitude: 0.03,
                frequency: 0.5,
                phase: 0.2,
            },
            Component {
                amplitude: 0.01,
                frequency: 2.3,
                phase: -1.0,
            },
        ])
        .unwrap();
        consistent(&m, &[0.0, 0.77, 3.1]);
        // Steps, kinks and ramps, between knots.
        let knots = [
            Knot { t: 0.0, v: 0.0 },
            Knot { t: 0.0, v: 0.1 },
            Knot { t: 0.5, v: 0.1 },
            Knot { t: 1.0, v: -0.05 },
            Knot { t: 1.0, v: 0.02 },
            Knot { t: 2.0, v: 0.02 },
        ];
        let mut st = [[0.0; 4]; 6];
        Prefiltered::fill_states(&knots, 0.03, &mut st).unwrap();
        let p = Prefiltered::new(&knots, &st, 0.03).unwrap();
        consistent(&p, &[0.01, 0.2, 0.51, 0.75, 1.02, 1.5, 2.1, 3.0]);
        // C³ across knots: θ⃛d continuous at a jump of u.
        let (l, r) = (p.z(1.0 - 1e-12), p.z(1.0 + 1e-12));
        assert!((l[3] - r[3]).abs() < 1e-6 * (1.0 + l[3].abs()));
    }

    #[test]
    fn chirp_by_hand() {
        // A = 1, f0 = 1, f1 = 3, T = 2: at t = 1, φ = 2π(1 + 0.5) = 3π,
        // φ̇ = 2π·2, φ̈ = 2π: θd = 0, θ̇d = −4π, θ̈d = −2π, θ⃛d = (4π)³.
        let c = Chirp::try_new(1.0, 1.0, 3.0, 2.0).unwrap();
        let z = c.z(1.0);
        let pi = core::f64::consts::PI;
        assert!(z[0].abs() < 1e-12);
        assert!((z[1] + 4.0 * pi).abs() < 1e-12);
        assert!((z[2] + 2.0 * pi).abs() < 1e-11);
        assert!((z[3] - (4.0 * pi).powi(3)).abs() < 1e-9);
        assert_eq!(c.frequency_at(10.0), 3.0);
        assert!(Chirp::try_new(1.0, 0.0, 1.0, 1.0).is_err());
        assert!(Multisine::try_new(&[]).is_err());
    }

    #[test]
    fn bad_knots_are_refused() {
        let mut st = [[0.0; 4]; 2];
        let k = [Knot { t: 1.0, v: 0.0 }, Knot { t: 0.5, v: 1.0 }];
        assert!(Prefiltered::fill_states(&k, 0.1, &mut st).is_err());
        let k = [
            Knot { t: 0.0, v: 0.0 },
            Knot {
                t: 0.5,
                v: f64::NAN,
            },
        ];
        assert!(Prefiltered::fill_states(&k, 0.1, &mut st).is_err());
        let k = [Knot { t: 0.0, v: 0.0 }, Knot { t: 0.5, v: 1.0 }];
        assert!(Prefiltered::fill_states(&k, -0.1, &mut st).is_err());
        assert!(Prefiltered::fill_states(&k, 0.1, &mut st[..1]).is_err());
    }

    /// Knots at ±1e308: their span 2e308 overflows, and the slope
    /// 1/(t1 − t0) would be 1/∞ = 0, a flat θd = 0 instead of the ramp the
    /// table describes: refused, as is a slope of 1/5e-324 = ∞. A jump
    /// (two knots at one time) is not a slope and stays allowed.
    #[test]
    fn knots_whose_slope_or_span_overflows_are_refused() {
        let mut st = [[0.0; 4]; 2];
        let k = [Knot { t: -1e308, v: -1.0 }, Knot { t: 1e308, v: 1.0 }];
        let e = Prefiltered::fill_states(&k, 0.1, &mut st).unwrap_err();
        assert!(e.reason.contains("span"), "{e:?}");
        let k = [
            Knot { t: 0.0, v: 0.0 },
            Knot {
                t: f64::from_bits(1),
                v: 1.0,
            },
        ];
        let e = Prefiltered::fill_states(&k, 0.1, &mut st).unwrap_err();
        assert!(e.reason.contains("slope"), "{e:?}");
        let k = [Knot { t: 1.0, v: 0.0 }, Knot { t: 1.0, v: 1.0 }];
        assert!(Prefiltered::fill_states(&k, 0.1, &mut st).is_ok());
    }
}
