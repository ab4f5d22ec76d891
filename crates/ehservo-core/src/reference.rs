//! Desired trajectories with their first three derivatives.
//!
//! The laws need `z = [θd, θ̇d, θ̈d, θ⃛d]` (Assumption A3; the last entry is the
//! leading term of (12) and (24), and the last four entries of Φ in (20)).
//! The paper's reference is `θd(t) = 5°·sin(2πt)`.

use crate::math::{Real, DR};

/// A trajectory known with its first three derivatives.
pub trait Reference<T = f64> {
    /// `z(t) = [θd, θ̇d, θ̈d, θ⃛d]` (rad, rad/s, rad/s², rad/s³).
    fn z(&self, t: T) -> [T; 4];
}

/// `θd(t) = A·sin(ω·t)`, differentiated analytically.
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
}
