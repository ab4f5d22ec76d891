//! The modified radial-basis vector Φ(x, z) of (20).
//!
//! ```text
//! Φ = [1, φ1(x), …, φ125(x), θd, θ̇d, θ̈d, θ⃛d]ᵀ                 (130 entries)
//! φj = exp(−‖x̃ − cj‖²/δ²),  x̃ = [x1/s1, x2/s2, x3/s3]
//! ```
//!
//! The paper normalises with s = (6.25°, 12.5π °/s, 25π² °/s²) in radians,
//! places the 125 centres on the grid {−1, −0.5, 0, 0.5, 1}³ (the first
//! component varies slowest, so φ1 is the centre (−1, −1, −1)) and takes
//! δ = 0.5. Index 0 of Φ is the bias; the paper's w_1 is the first Gaussian
//! and w_128 the weight of θ̈d.
//!
//! Because the centres form a grid, each Gaussian factors into one term per
//! axis: `φ(i1,i2,i3) = g1[i1]·g2[i2]·g3[i3]` with `gk[i] = exp(−(x̃k − L[i])²/δ²)`.
//! The network therefore costs 15 exponentials and 150 products, not 125
//! exponentials; [`Rbf::phi_direct`] keeps the textbook form for tests.

use crate::error::{positive, ParamError};
use crate::math::{exp, DR};

/// Number of Gaussian kernels (5³).
pub const N_KERNELS: usize = 125;
/// Length of Φ: bias + kernels + the four reference terms.
pub const N_PHI: usize = 1 + N_KERNELS + 4;
/// Levels of the grid along each axis.
pub const N_LEVELS: usize = 5;

/// The network's fixed configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rbf {
    levels: [f64; N_LEVELS],
    width: f64,
    scale: [f64; 3],
    inv_scale: [f64; 3],
    inv_width_sq: f64,
}

impl Rbf {
    /// The paper's network: levels {−1, −0.5, 0, 0.5, 1}, δ = 0.5,
    /// scales (6.25·dr, 12.5π·dr, 25π²·dr).
    pub fn paper() -> Self {
        Self::try_new([-1.0, -0.5, 0.0, 0.5, 1.0], 0.5, Self::paper_scale())
            .expect("paper values are valid")
    }

    /// The paper's normalising scales in rad, rad/s, rad/s².
    pub fn paper_scale() -> [f64; 3] {
        let pi = core::f64::consts::PI;
        [6.25 * DR, 12.5 * pi * DR, 25.0 * pi * pi * DR]
    }

    /// A network on the grid `levels`³ with width δ = `width` and
    /// normalising scales `scale`.
    pub fn try_new(
        levels: [f64; N_LEVELS],
        width: f64,
        scale: [f64; 3],
    ) -> Result<Self, ParamError> {
        for &l in &levels {
            crate::error::finite("rbf.levels", l)?;
        }
        positive("rbf.width", width)?;
        for &s in &scale {
            positive("rbf.scale", s)?;
        }
        Ok(Self {
            levels,
            width,
            scale,
            inv_scale: [1.0 / scale[0], 1.0 / scale[1], 1.0 / scale[2]],
            inv_width_sq: 1.0 / (width * width),
        })
    }

    /// The grid levels.
    pub fn levels(&self) -> [f64; N_LEVELS] {
        self.levels
    }

    /// δ.
    pub fn width(&self) -> f64 {
        self.width
    }

    /// The normalising scales.
    pub fn scale(&self) -> [f64; 3] {
        self.scale
    }

    /// Centre `j` (0-based, 0..125) in normalised coordinates; the first
    /// component varies slowest: `j = 25·i1 + 5·i2 + i3`.
    pub fn centre(&self, j: usize) -> [f64; 3] {
        [
            self.levels[j / 25],
            self.levels[(j / 5) % 5],
            self.levels[j % 5],
        ]
    }

    /// Fills `out` with Φ(x, z) and returns ‖Φ‖.
    #[inline]
    pub fn phi(&self, x: &[f64; 3], z: &[f64; 4], out: &mut [f64; N_PHI]) -> f64 {
        let mut g = [[0.0; N_LEVELS]; 3];
        for (k, gk) in g.iter_mut().enumerate() {
            let xt = x[k] * self.inv_scale[k];
            for (i, gi) in gk.iter_mut().enumerate() {
                let d = xt - self.levels[i];
                *gi = exp(-d * d * self.inv_width_sq);
            }
        }
        out[0] = 1.0;
        let mut sum_sq = 1.0;
        let mut j = 1;
        for &g1 in &g[0] {
            for &g2 in &g[1] {
                let g12 = g1 * g2;
                for &g3 in &g[2] {
                    let v = g12 * g3;
                    out[j] = v;
                    sum_sq += v * v;
                    j += 1;
                }
            }
        }
        for (i, &zi) in z.iter().enumerate() {
            out[1 + N_KERNELS + i] = zi;
            sum_sq += zi * zi;
        }
        crate::math::sqrt(sum_sq)
    }

    /// Φ by the textbook formula `exp(−‖x̃ − cj‖²/δ²)`, one exponential per
    /// kernel. For tests and for readers; [`Rbf::phi`] is the one to use.
    pub fn phi_direct(&self, x: &[f64; 3], z: &[f64; 4], out: &mut [f64; N_PHI]) {
        out[0] = 1.0;
        for j in 0..N_KERNELS {
            let c = self.centre(j);
            let mut d2 = 0.0;
            for k in 0..3 {
                let d = x[k] * self.inv_scale[k] - c[k];
                d2 += d * d;
            }
            out[1 + j] = exp(-d2 * self.inv_width_sq);
        }
        out[1 + N_KERNELS..].copy_from_slice(z);
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    /// At x = 0 the normalised state is the centre (0,0,0) = kernel j = 62
    /// (i1 = i2 = i3 = 2 → 25·2 + 5·2 + 2), so φ63 (1-based Φ index 63) = 1.
    /// Its neighbour (0, 0, 0.5) is at distance 0.5 = δ: φ = e^−1.
    /// The corner (−1, −1, −1), the paper's φ1: ‖x̃ − c‖² = 3, φ = e^(−3/0.25) = e^−12.
    #[test]
    fn kernel_values_by_hand() {
        let rbf = Rbf::paper();
        let mut phi = [0.0; N_PHI];
        let z = [0.1, 0.2, 0.3, 0.4];
        let norm = rbf.phi(&[0.0; 3], &z, &mut phi);
        assert_eq!(phi[0], 1.0);
        assert_eq!(rbf.centre(62), [0.0, 0.0, 0.0]);
        assert!((phi[63] - 1.0).abs() < 1e-15);
        assert!((phi[64] - (-1.0f64).exp()).abs() < 1e-15);
        assert!((phi[1] - (-12.0f64).exp()).abs() < 1e-18);
        assert_eq!(&phi[126..130], &z);
        let direct: f64 = phi.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((norm - direct).abs() < 1e-14);
    }

    /// The separable evaluation equals the textbook one.
    #[test]
    fn separable_equals_direct() {
        let rbf = Rbf::paper();
        let z = [0.05, -0.3, 2.0, -20.0];
        for x in [[0.03, -0.4, 2.0], [-0.11, 0.7, -4.1], [1.9, 3.9, 15.0]] {
            let (mut a, mut b) = ([0.0; N_PHI], [0.0; N_PHI]);
            rbf.phi(&x, &z, &mut a);
            rbf.phi_direct(&x, &z, &mut b);
            for i in 0..N_PHI {
                assert!((a[i] - b[i]).abs() <= 1e-15 * (1.0 + b[i].abs()), "i={i}");
            }
        }
    }

    /// The paper's x1 scale is 6.25° = 0.109083 rad; x2: 12.5π° = 0.685389 rad/s;
    /// x3: 25π²° = 246.74° = 4.306427 rad/s².
    #[test]
    fn paper_scales_by_hand() {
        let s = Rbf::paper_scale();
        assert!((s[0] - 0.109083).abs() < 1e-6);
        assert!((s[1] - 0.685389).abs() < 1e-6);
        assert!((s[2] - 4.306427).abs() < 1e-6);
    }
}
