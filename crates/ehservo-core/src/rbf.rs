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
//! exponentials. With equally spaced levels (the paper's) it costs four:
//! each axis is expanded about its nearest level (see `Spacing`), so only
//! `q = exp(2Δd/δ²)` per axis and the nearest kernel itself are
//! exponentials. [`Rbf::phi_direct`] keeps the textbook form for tests.

use crate::error::{positive, ParamError};
use crate::math::{exp, Real, DR};

/// Number of Gaussian kernels (5³).
pub const N_KERNELS: usize = 125;
/// Length of Φ: bias + kernels + the four reference terms.
pub const N_PHI: usize = 1 + N_KERNELS + 4;
/// Levels of the grid along each axis.
pub const N_LEVELS: usize = 5;

/// The network's fixed configuration.
///
/// ```
/// use ehservo_core::rbf::{Rbf, N_PHI};
///
/// let rbf = Rbf::paper();
/// let z = [0.1, 0.2, 0.3, 0.4];
/// let mut phi = [0.0; N_PHI];
/// rbf.phi(&[0.0; 3], &z, &mut phi);
/// // Φ = [1, φ1 … φ125, z]: the bias, then the kernels, then the reference.
/// assert_eq!(phi[0], 1.0);
/// assert_eq!(phi[126..], z);
/// // x = 0 sits on the grid's centre (0, 0, 0), kernel j = 25·2 + 5·2 + 2 = 62,
/// // so φ = exp(0) = 1 there; its neighbour (0, 0, 0.5) is exp(−0.5²/δ²) = e⁻¹.
/// assert_eq!(rbf.centre(62), [0.0; 3]);
/// assert!((phi[1 + 62] - 1.0).abs() < 1e-15);
/// assert!((phi[1 + 63] - (-1f64).exp()).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rbf<T = f64> {
    levels: [T; N_LEVELS],
    width: T,
    scale: [T; 3],
    inv_scale: [T; 3],
    inv_width_sq: T,
    spacing: Option<Spacing<T>>,
}

/// Equally spaced, increasing levels `L[i] = L[0] + i·Δ`. Expand each
/// axis about its nearest level `L[m]`: with `d = x̃ − L[m]` (|d| ≤ Δ/2 on
/// the grid), `(d − jΔ)² = d² − 2jΔd + j²Δ²`, so
/// `g[m + j] = exp(−d²/δ²)·q^j·C_|j|` with `q = exp(2Δd/δ²)` and the
/// constants `C_j = exp(−j²Δ²/δ²)`: two exponentials per axis instead of
/// five (six for Φ instead of fifteen), and the largest factor, `g[m]`, is
/// the direct one to the bit. Expanding about the nearest level keeps the
/// exponents of `exp(−d²/δ²)` and `q` small, so their rounding stays at a
/// few ulp of the factors near 1 (the centre of the grid would cost ~4 ulp
/// more at the outer levels).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Spacing<T> {
    first: T,
    inv_step: T,
    q_coef: T,
    /// `C_|j|` for j = −4..=4.
    c: [T; 2 * N_LEVELS - 1],
}

/// The two-exponential form is used only while every factor it multiplies
/// lies in [e^−S, e^S] with S = [`Real::EXP_SPAN`] (300 for f64, 80 for
/// f32) (`d²/δ² ≤ S`, `4·2|Δd|/δ² ≤ S` for q⁴, `16Δ²/δ² ≤ S` for C_4):
/// nothing overflows, so no `0·∞ = NaN`; results below the type's smallest
/// normal underflow to (sub)normals or 0 as the direct form's do. Outside,
/// and for NaN or infinite inputs, the five direct exponentials are taken.
#[inline(always)]
fn spaced_max<T: Real>() -> T {
    T::EXP_SPAN
}

impl Rbf<f64> {
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
}

impl<T: Real> Rbf<T> {
    /// The same network in another float type (its derived constants
    /// recomputed in `U`); fails only if a value does not survive the cast
    /// (a width or scale that rounds to 0 or ∞).
    pub fn cast<U: Real>(&self) -> Result<Rbf<U>, ParamError> {
        let c = |v: T| U::of(v.to_f64());
        Rbf::try_new(self.levels.map(c), c(self.width), self.scale.map(c))
    }

    /// A network on the grid `levels`³ with width δ = `width` and
    /// normalising scales `scale`.
    pub fn try_new(levels: [T; N_LEVELS], width: T, scale: [T; 3]) -> Result<Self, ParamError> {
        for &l in &levels {
            crate::error::finite("rbf.levels", l)?;
        }
        positive("rbf.width", width)?;
        for &s in &scale {
            positive("rbf.scale", s)?;
        }
        let inv_width_sq = T::ONE / (width * width);
        Ok(Self {
            levels,
            width,
            scale,
            inv_scale: [T::ONE / scale[0], T::ONE / scale[1], T::ONE / scale[2]],
            inv_width_sq,
            spacing: Self::spacing(&levels, inv_width_sq),
        })
    }

    /// The equal-spacing constants, if the levels are increasing and
    /// equally spaced (to the last bit) and the constants are in the range
    /// of [`Real::EXP_SPAN`].
    #[allow(clippy::float_cmp)] // equal spacing to the last bit is the point
    fn spacing(levels: &[T; N_LEVELS], k: T) -> Option<Spacing<T>> {
        let first = levels[0];
        let step = levels[1] - levels[0];
        let equal = levels
            .iter()
            .enumerate()
            .all(|(i, &l)| l == first + T::of_usize(i) * step);
        let q_coef = T::of(2.0) * step * k;
        let a1 = step * step * k;
        // (k and the levels are finite, so a1 is finite or +∞.)
        if !equal
            || step <= T::ZERO
            || !k.is_finite()
            || !q_coef.is_finite()
            || T::of(16.0) * a1 > spaced_max()
        {
            return None;
        }
        let mut c = [T::ONE; 2 * N_LEVELS - 1];
        for (i, ci) in c.iter_mut().enumerate() {
            let j = i.abs_diff(N_LEVELS - 1);
            *ci = exp(-T::of_usize(j * j) * a1);
        }
        Some(Spacing {
            first,
            inv_step: T::ONE / step,
            q_coef,
            c,
        })
    }

    /// The grid levels.
    pub fn levels(&self) -> [T; N_LEVELS] {
        self.levels
    }

    /// δ.
    pub fn width(&self) -> T {
        self.width
    }

    /// The normalising scales.
    pub fn scale(&self) -> [T; 3] {
        self.scale
    }

    /// Centre `j` (0-based, 0..125) in normalised coordinates; the first
    /// component varies slowest: `j = 25·i1 + 5·i2 + i3`.
    pub fn centre(&self, j: usize) -> [T; 3] {
        [
            self.levels[j / 25],
            self.levels[(j / 5) % 5],
            self.levels[j % 5],
        ]
    }

    /// The per-axis factors `g[k][i] = exp(−(x̃k − L[i])²/δ²)`: the kernel
    /// `j = 25·i1 + 5·i2 + i3` is `g[0][i1]·g[1][i2]·g[2][i3]`.
    // (Always inlined on x86-64: into the NNBVSC's AVX2 + FMA law,
    // `Real::exp4`'s vector code is inlined in turn, its arguments and
    // results staying in registers. Elsewhere as before: on a Cortex-M4F
    // always inlining it cost the f32 step 10 instructions and 88 B.)
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    pub(crate) fn gaussians(&self, x: &[T; 3]) -> [[T; N_LEVELS]; 3] {
        let xt = [
            x[0] * self.inv_scale[0],
            x[1] * self.inv_scale[1],
            x[2] * self.inv_scale[2],
        ];
        if let Some(sp) = &self.spacing {
            if let Some(g) = self.gaussians_spaced(sp, &xt) {
                return g;
            }
        }
        let mut g = [[T::ZERO; N_LEVELS]; 3];
        for (gk, &xk) in g.iter_mut().zip(&xt) {
            for (gi, &l) in gk.iter_mut().zip(&self.levels) {
                let d = xk - l;
                *gi = exp(-d * d * self.inv_width_sq);
            }
        }
        g
    }

    /// The factors by [`Spacing`], or `None` when an axis is outside the
    /// range of [`Real::EXP_SPAN`] (or NaN). Four exponentials: the nearest
    /// kernel `G = exp(−‖x̃ − c_m‖²/δ²)` (computed as [`Rbf::phi_direct`]
    /// does, so it is that kernel to the bit) and one `q` per axis; the
    /// factors are `G·h1[i]`, `h2[i]`, `h3[i]` with `h[m + j] = C_|j|·q^j`,
    /// the ratio of each level's factor to the nearest one's (≤ 1).
    ///
    /// With [`Real::RBF_AXIS_FALLBACK`] (f32) an axis farther than √S·δ
    /// from its nearest level makes every kernel smaller than e^−S, and
    /// every factor is taken as zero (no exponential); otherwise (a grid
    /// spaced wider than δ, where q leaves the range first) only the
    /// axes outside the range take the five direct exponentials: `G` is
    /// then the nearest kernel over the axes in range and multiplies the
    /// first of them (one axis out of range costs 8 exponentials, not 15);
    /// `None` only when no axis is in range. Without it (f64) one axis out
    /// of range gives `None`, and every factor is direct.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    fn gaussians_spaced(&self, sp: &Spacing<T>, xt: &[T; 3]) -> Option<[[T; N_LEVELS]; 3]> {
        let mut m = [0; 3];
        let mut dist2 = T::ZERO;
        let mut arg_q = [T::ZERO; 3];
        let mut direct = [false; 3];
        for k in 0..3 {
            // Nearest level: the number of midpoints at or below x̃ (NaN → 0;
            // the range check below then fails).
            let r = (xt[k] - sp.first) * sp.inv_step + T::of(0.5);
            m[k] = (1..N_LEVELS)
                .map(|i| usize::from(r >= T::of_usize(i)))
                .sum();
            let d = xt[k] - self.levels[m[k]];
            arg_q[k] = sp.q_coef * d;
            let in_range = d * d * self.inv_width_sq <= spaced_max()
                && arg_q[k].abs() <= T::of(0.25) * spaced_max();
            if !in_range {
                // (also for NaN)
                if !T::RBF_AXIS_FALLBACK {
                    return None;
                }
                direct[k] = true;
                continue;
            }
            dist2 += d * d;
        }
        if T::RBF_AXIS_FALLBACK && direct != [false; 3] {
            return self.axis_fallback(sp, xt, &m, &arg_q, dist2, &direct);
        }
        // The four exponentials together: independent, so they overlap
        // (and for f64 on an x86-64 Linux host with AVX2 and FMA, in one
        // vector with glibc's bits: `Real::exp4`).
        let [big_g, q0, q1, q2] =
            T::exp4([-dist2 * self.inv_width_sq, arg_q[0], arg_q[1], arg_q[2]]);
        let q = [q0, q1, q2];
        Some([
            Self::ratios(sp, m[0], q[0]).map(|h| h * big_g),
            Self::ratios(sp, m[1], q[1]),
            Self::ratios(sp, m[2], q[2]),
        ])
    }

    /// [`Self::gaussians_spaced`] when an axis is out of range, with
    /// [`Real::RBF_AXIS_FALLBACK`] (f32). Out of line and cold: the
    /// start-up transient's steps take it, and inlined it cost every
    /// other step of the Cortex-M4F 24 instructions of register traffic.
    #[cold]
    #[inline(never)]
    fn axis_fallback(
        &self,
        sp: &Spacing<T>,
        xt: &[T; 3],
        m: &[usize; 3],
        arg_q: &[T; 3],
        dist2: T,
        direct: &[bool; 3],
    ) -> Option<[[T; N_LEVELS]; 3]> {
        // An axis whose nearest level is more than √S·δ away has every
        // factor below e^−S (f32: 1.8e-35), and so has every kernel:
        // all are taken as zero, with no exponential. (Not for NaN, which
        // stays NaN; an infinite coordinate gives the zeros exp(−∞)
        // gave.) For the paper's grid (Δ = δ) every axis out of range is
        // that far; the direct exponentials below serve grids spaced
        // wider than δ, where q leaves the range first.
        let far = |k: usize| {
            let d = xt[k] - self.levels[m[k]];
            direct[k] && d * d * self.inv_width_sq > spaced_max()
        };
        if (far(0) || far(1) || far(2)) && !xt.iter().any(|v| v.is_nan()) {
            return Some([[T::ZERO; N_LEVELS]; 3]);
        }
        let first = direct.iter().position(|&dk| !dk)?;
        let big_g = exp(-dist2 * self.inv_width_sq);
        let mut g = [0, 1, 2].map(|k| {
            if direct[k] {
                self.levels.map(|l| {
                    let d = xt[k] - l;
                    exp(-d * d * self.inv_width_sq)
                })
            } else {
                Self::ratios(sp, m[k], exp(arg_q[k]))
            }
        });
        for gf in g[first].iter_mut() {
            *gf *= big_g;
        }
        Some(g)
    }

    /// `h[i] = C_|i−m|·q^(i−m)`, i = 0..5: an axis's factors relative to
    /// its nearest level `m`'s.
    #[inline(always)]
    fn ratios(sp: &Spacing<T>, m: usize, q: T) -> [T; N_LEVELS] {
        const TOP: usize = N_LEVELS - 1;
        let qi = T::ONE / q;
        let (q2, qi2) = (q * q, qi * qi);
        // q^j for j = −4..=4; the window j = i − m, i = 0..5, picked by
        // a match (an indexed window would be stored and loaded back,
        // and wide loads of narrow stores wait for the stores to retire).
        let p = [qi2 * qi2, qi2 * qi, qi2, qi, T::ONE, q, q2, q2 * q, q2 * q2];
        let p = match m {
            0 => [p[4], p[5], p[6], p[7], p[8]],
            1 => [p[3], p[4], p[5], p[6], p[7]],
            2 => [p[2], p[3], p[4], p[5], p[6]],
            3 => [p[1], p[2], p[3], p[4], p[5]],
            _ => [p[0], p[1], p[2], p[3], p[4]],
        };
        let w = TOP - m;
        let c = &sp.c[w..w + N_LEVELS];
        [
            c[0] * p[0],
            c[1] * p[1],
            c[2] * p[2],
            c[3] * p[3],
            c[4] * p[4],
        ]
    }

    /// ‖Φ‖ from the per-axis factors and z, without forming Φ: the kernels'
    /// sum of squares factors as `Π_k Σ_i g[k][i]²` (it is a sum over the
    /// 5³ products `g1·g2·g3`), so it costs 15 squares, not 125.
    #[inline]
    pub(crate) fn norm_from(g: &[[T; N_LEVELS]; 3], z: &[T; 4]) -> T {
        let sq = |gk: &[T; N_LEVELS]| {
            (gk[0] * gk[0] + gk[1] * gk[1]) + (gk[2] * gk[2] + gk[3] * gk[3]) + gk[4] * gk[4]
        };
        let mut sum_sq = T::ONE + sq(&g[0]) * sq(&g[1]) * sq(&g[2]);
        for &zi in z {
            sum_sq += zi * zi;
        }
        crate::math::sqrt(sum_sq)
    }

    /// ‖Φ(x, z)‖ without Φ: what [`Rbf::phi`] returns, the same bits (the
    /// same factors and the same operations), for a caller that needs only
    /// the norm (15 squares instead of 125 products and a store).
    #[inline]
    pub fn phi_norm(&self, x: &[T; 3], z: &[T; 4]) -> T {
        Self::norm_from(&self.gaussians(x), z)
    }

    /// Fills `out` with Φ(x, z) and returns ‖Φ‖.
    #[inline]
    pub fn phi(&self, x: &[T; 3], z: &[T; 4], out: &mut [T; N_PHI]) -> T {
        let g = self.gaussians(x);
        Self::fill_phi(&g, z, out);
        Self::norm_from(&g, z)
    }

    /// Φ from the per-axis factors and z.
    #[inline]
    fn fill_phi(g: &[[T; N_LEVELS]; 3], z: &[T; 4], out: &mut [T; N_PHI]) {
        out[0] = T::ONE;
        for (i1, &g1) in g[0].iter().enumerate() {
            for (i2, &g2) in g[1].iter().enumerate() {
                let g12 = g1 * g2;
                let j = 1 + N_LEVELS * (N_LEVELS * i1 + i2);
                for (o, &g3) in out[j..j + N_LEVELS].iter_mut().zip(&g[2]) {
                    *o = g12 * g3;
                }
            }
        }
        out[1 + N_KERNELS..].copy_from_slice(z);
    }

    /// Φ by the textbook formula `exp(−‖x̃ − cj‖²/δ²)`, one exponential per
    /// kernel. For tests and for readers; [`Rbf::phi`] is the one to use.
    pub fn phi_direct(&self, x: &[T; 3], z: &[T; 4], out: &mut [T; N_PHI]) {
        out[0] = T::ONE;
        for j in 0..N_KERNELS {
            let c = self.centre(j);
            let mut d2 = T::ZERO;
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

    /// `phi_norm` is the norm `phi` returns, to the bit, and the norm of
    /// the textbook Φ (one exponential per kernel) to rounding: on the
    /// grid, between its levels, far from it, with the equal-spacing form
    /// and without it (uneven levels).
    #[test]
    fn phi_norm_is_the_norm_of_phi() {
        let s = Rbf::paper_scale();
        let uneven = Rbf::try_new([-1.0, -0.4, 0.0, 0.5, 1.0], 0.5, s).unwrap();
        let z = [0.05, -0.3, 2.0, -20.0];
        for rbf in [Rbf::paper(), uneven] {
            for x in [
                [0.0; 3],
                [0.03, -0.4, 2.0],
                [-0.11, 0.7, -4.1],
                [1.9, 3.9, 15.0],
                [40.0, -80.0, 1e3],
            ] {
                let (mut a, mut b) = ([0.0; N_PHI], [0.0; N_PHI]);
                let norm = rbf.phi(&x, &z, &mut a);
                assert_eq!(rbf.phi_norm(&x, &z).to_bits(), norm.to_bits(), "{x:?}");
                rbf.phi_direct(&x, &z, &mut b);
                let direct = b.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!((norm - direct).abs() <= 1e-14 * direct, "{x:?}");
            }
        }
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

    /// The equal-spacing form (four exponentials) against the textbook one,
    /// on and off the grid, on both sides of its range guard, and with
    /// levels that are not equally spaced (the direct form is then used).
    #[test]
    fn spaced_form_equals_direct_everywhere() {
        let s = Rbf::paper_scale();
        let uneven = Rbf::try_new([-1.0, -0.4, 0.0, 0.5, 1.0], 0.5, s).unwrap();
        let wide = Rbf::try_new([-3.0, -1.5, 0.0, 1.5, 3.0], 0.7, s).unwrap();
        assert!(Rbf::paper().spacing.is_some() && wide.spacing.is_some());
        assert!(uneven.spacing.is_none());
        let z = [0.05, -0.3, 2.0, -20.0];
        // x̃ from −9 to 9 in steps of 0.37 on each axis (|d| up to 8: the
        // guard d²/δ² ≤ 300 switches at |d| = 8.66 for δ = 0.5).
        let mut n = 0;
        for rbf in [Rbf::paper(), uneven, wide] {
            for i in 0..49 {
                for j in [0, 7, 24, 41, 48] {
                    let xt = [-9.0 + 0.37 * i as f64, -9.0 + 0.37 * j as f64, 0.31];
                    let x = [xt[0] * s[0], xt[1] * s[1], xt[2] * s[2]];
                    let (mut a, mut b) = ([0.0; N_PHI], [0.0; N_PHI]);
                    rbf.phi(&x, &z, &mut a);
                    rbf.phi_direct(&x, &z, &mut b);
                    for k in 0..N_PHI {
                        assert!(
                            (a[k] - b[k]).abs() <= 1e-15 * (1.0 + b[k].abs()),
                            "{x:?} {k}"
                        );
                    }
                    n += 1;
                }
            }
        }
        assert_eq!(n, 3 * 49 * 5);
    }

    /// Far, infinite and NaN states never give NaN where the direct form
    /// does not: far away every kernel is 0 (or subnormal) and ‖Φ‖ finite.
    #[test]
    fn spaced_form_has_no_nan_far_away() {
        let rbf = Rbf::paper();
        let z = [0.0, 0.5, 0.0, -20.0];
        for v in [8.0, 9.0, 40.0, 1e3, 1e10, 1e300, f64::MAX, f64::INFINITY] {
            for x in [[v, 0.0, 0.0], [0.0, -v, 0.0], [v, v, -v]] {
                let (mut a, mut b) = ([0.0; N_PHI], [0.0; N_PHI]);
                let norm = rbf.phi(&x, &z, &mut a);
                rbf.phi_direct(&x, &z, &mut b);
                assert!(norm.is_finite(), "{x:?}");
                for k in 0..N_PHI {
                    assert!(!a[k].is_nan(), "{x:?} {k}");
                    assert!(
                        (a[k] - b[k]).abs() <= 1e-15 * (1.0 + b[k].abs()),
                        "{x:?} {k}"
                    );
                }
            }
        }
        // A NaN measurement gives NaN kernels, as the direct form does.
        let mut a = [0.0; N_PHI];
        rbf.phi(&[f64::NAN, 0.0, 0.0], &z, &mut a);
        assert!(a[1..=N_KERNELS].iter().all(|v| v.is_nan()));
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
