//! exp((P + s·I)t) in closed form from the eigenvalues of P: the spectral
//! (Sylvester/Vandermonde) decomposition for distinct eigenvalues, written
//! in real arithmetic for a complex pair, and the confluent (Hermite) form
//! for a repeated one.
//!
//! Every case is M(t) = Σ_k B_k·c_k(t) with three constant real matrices B_k
//! and scalar functions c_k, so one evaluation is three exponentials (or one
//! exponential and a sine and cosine) and 27 multiply-adds, against a Padé
//! approximant with scaling and squaring for nalgebra's `exp`. With μ = λ + s:
//!
//! - three distinct real λ_i: B_i = A_i = Π_{j≠i}(P − λ_j I)/(λ_i − λ_j)
//!   (Sylvester; for a companion matrix A_i = v_i·w_iᵀ with v_i = (1, λ_i,
//!   λ_i²) the i-th column of the Vandermonde matrix V and w_iᵀ the i-th row
//!   of V⁻¹, i.e. exp(Pt) = V·diag(e^(λt))·V⁻¹), c_i = e^(μ_i t);
//! - a real λ_0 and a pair σ ± iω: A e^(λt) + Ā e^(λ̄t) = 2Re(A e^(λt)), so
//!   B_1 = 2·Re A, B_2 = −2·Im A, c_1 = e^(μt)·cos ωt, c_2 = e^(μt)·sin ωt
//!   (μ = σ + s): real arithmetic, the result real by construction;
//! - a simple a and a double c (Hermite interpolation of e^(λt) with the
//!   multiplicities of the characteristic polynomial, valid for any P with
//!   those eigenvalues): B_0 = (P − cI)²/(a − c)², B_1 = I − B_0,
//!   B_2 = (P − aI)(P − cI)/(c − a); c_0 = e^(μ_a t), c_1 = e^(μ_c t),
//!   c_2 = t·e^(μ_c t);
//! - a triple a: e^(μt)·[I + tN + t²N²/2] with N = P − aI.
//!
//! **When it is used.** The distinct form divides by the gaps λ_i − λ_j:
//! its rounding grows like (scale/gap)², where scale = max|λ|, from the
//! cancellation in Σ A_i e^(μ_i t) (‖A_i‖ ~ (scale/gap)², the sum ~ 1 at
//! t = 0), until it costs more digits than the Padé approximant loses.
//! [`SEPARATION`] is about there (measured, see its doc); closer pairs that
//! are not equal return None and the caller falls back to nalgebra's `exp`.
//! Equal eigenvalues (a user's `surface.poles` such as [−20, −40, −40])
//! take the confluent form, exact there. Computed roots of a repeated pole
//! come out split by ~sqrt(ε) and are not equal: `exp` then.

use super::poles::Pole;
use nalgebra::{Complex, Matrix3};

/// Four `exp`s with the bits of four calls ([`Real::exp4`]).
///
/// [`Real::exp4`]: ehservo_core::math::Real::exp4
#[inline]
pub(super) fn exp4(v: [f64; 4]) -> [f64; 4] {
    <f64 as ehservo_core::math::Real>::exp4(v)
}

/// Least gap |λ_i − λ_j|/max|λ| at which distinct eigenvalues take the
/// closed form.
///
/// Its rounding error, measured against mpmath (50 digits) on
/// g(t) = ‖exp((P + 20I)t)‖₂ at nine times from 1e-4 to 10 s, for
/// (−20, −20 − δ, −40) and (−20, −40, −40 − δ) (the `dump_for_mpmath` test
/// of tests/it/k1_closed_form.rs prints both paths), grows like
/// (max|λ|/gap)² — largest relative error, dominant pair / fast pair:
///
/// | δ (gap/scale)  | closed form  | nalgebra's exp |
/// |----------------|--------------|----------------|
/// | 10 (0.2)       | 3e-14, 3e-13 | 4e-13, 6e-13   |
/// | 0.5 (1.2e-2)   | 1e-13, 2e-12 | 1e-11, 2e-13   |
/// | 0.1 (2.5e-3)   | 3e-11, 4e-11 | 8e-12, 4e-13   |
/// | 0.04 (1e-3)    | 7e-11, 3e-11 | 5e-11, 5e-13   |
/// | 0.01 (2.5e-4)  | 3e-10, 3e-10 | 3e-11, 4e-13   |
///
/// At 5e-3 it is ≈ 1e-11, a hundred times inside the 1e-9 asked of K1,
/// and below it `exp` is the more accurate of the two: closer pairs that
/// are not equal return None and the caller uses `exp`, whose results for
/// them this module leaves as they were.
pub const SEPARATION: f64 = 5e-3;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Modes {
    /// Three simple real eigenvalues, shifted: μ_0, μ_1, μ_2.
    Real([f64; 3]),
    /// A real μ_0 and a pair μ ± iω (ω > 0).
    Pair { real: f64, mu: f64, omega: f64 },
    /// A simple μ_a and a double μ_c.
    Double { simple: f64, double: f64 },
    /// A triple μ.
    Triple(f64),
}

/// exp((P + s·I)t) = Σ_k B_k·c_k(t) (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralExp {
    b: [Matrix3<f64>; 3],
    modes: Modes,
}

/// The eigenvalues of P polished by Newton's method on
/// det(sI − P) = s³ + c2 s² + c1 s + c0 (c2 = −tr P, c1 = Σ principal 2×2
/// minors, c0 = −det P), starting from `poles`: the coefficients A_i
/// magnify an eigenvalue's error by ‖P‖/gap. A step is kept only when it
/// lowers the residual.
pub(super) fn polished_eigenvalues(p: &Matrix3<f64>, poles: &[Pole; 3]) -> [Complex<f64>; 3] {
    let c2 = -p.trace();
    let c1 = p[(0, 0)] * p[(1, 1)] - p[(0, 1)] * p[(1, 0)] + p[(0, 0)] * p[(2, 2)]
        - p[(0, 2)] * p[(2, 0)]
        + p[(1, 1)] * p[(2, 2)]
        - p[(1, 2)] * p[(2, 1)];
    let c0 = -p.determinant();
    std::array::from_fn(|i| {
        let mut z = Complex::new(poles[i].re, poles[i].im);
        for _ in 0..3 {
            let f = ((z + c2) * z + c1) * z + c0;
            let d = (z * 3.0 + 2.0 * c2) * z + c1;
            if d.norm() > 0.0 {
                let next = z - f / d;
                if (((next + c2) * next + c1) * next + c0).norm() < f.norm() {
                    z = next;
                }
            }
        }
        z
    })
}

/// Sylvester's A_i = Π_{j≠i}(P − λ_j I)/(λ_i − λ_j) for distinct `l`.
pub(super) fn sylvester_products(
    p: &Matrix3<f64>,
    l: &[Complex<f64>; 3],
) -> [Matrix3<Complex<f64>>; 3] {
    let pc: Matrix3<Complex<f64>> = p.map(|v| Complex::new(v, 0.0));
    let id = Matrix3::<Complex<f64>>::identity();
    std::array::from_fn(|i| {
        let mut m = id;
        for (j, lj) in l.iter().enumerate() {
            if j != i {
                m = m * (pc - id * *lj) / (l[i] - *lj);
            }
        }
        m
    })
}

/// Whether two eigenvalues are the same number: exact equality is the
/// point (equal ones take the confluent form, close ones do not).
#[allow(clippy::float_cmp)]
fn equal(a: &Pole, b: &Pole) -> bool {
    a.re == b.re && a.im == b.im
}

impl SpectralExp {
    /// The closed form of exp((P + shift·I)t) for P with the eigenvalues
    /// `poles` (a real cubic's roots: real, or a conjugate pair); None when
    /// two distinct eigenvalues are closer than [`SEPARATION`]·max|λ|, when
    /// a value is not finite, or when the result would not be (the caller
    /// then uses nalgebra's `exp`).
    pub fn new(p: &Matrix3<f64>, poles: &[Pole; 3], shift: f64) -> Option<Self> {
        Self::with_separation(p, poles, shift, SEPARATION)
    }

    /// [`SpectralExp::new`] with another least gap than [`SEPARATION`]
    /// (relative to max|λ|): for studies of that threshold.
    pub fn with_separation(
        p: &Matrix3<f64>,
        poles: &[Pole; 3],
        shift: f64,
        separation: f64,
    ) -> Option<Self> {
        if !(super::linalg::finite(p)
            && shift.is_finite()
            && poles.iter().all(|q| q.re.is_finite() && q.im.is_finite()))
        {
            return None;
        }
        let scale = poles.iter().map(|q| q.wn).fold(0.0, f64::max);
        if scale == 0.0 || !scale.is_finite() {
            return None;
        }
        let id = Matrix3::identity();
        let (b, modes) = if equal(&poles[0], &poles[1]) && equal(&poles[1], &poles[2]) {
            let a = poles[0];
            if a.im != 0.0 {
                return None;
            }
            let n = p - id * a.re;
            ([id, n, n * n * 0.5], Modes::Triple(a.re + shift))
        } else if let Some((s, d)) = [(0, 1), (1, 2), (2, 0)]
            .iter()
            .find(|&&(i, j)| equal(&poles[i], &poles[j]))
            .map(|&(i, j)| (3 - i - j, i))
        {
            let (a, c) = (poles[s], poles[d]);
            if a.im != 0.0 || c.im != 0.0 || (a.re - c.re).abs() < separation * scale {
                return None;
            }
            let (pa, pc) = (p - id * a.re, p - id * c.re);
            let ea = pc * pc / ((a.re - c.re) * (a.re - c.re));
            (
                [ea, id - ea, pa * pc / (c.re - a.re)],
                Modes::Double {
                    simple: a.re + shift,
                    double: c.re + shift,
                },
            )
        } else {
            let l = polished_eigenvalues(p, poles);
            for i in 0..3 {
                for j in i + 1..3 {
                    if (l[i] - l[j]).norm() < separation * scale {
                        return None;
                    }
                }
            }
            let a = sylvester_products(p, &l);
            match poles.iter().position(|q| q.im > 0.0) {
                None => (
                    a.map(|m| m.map(|z| z.re)),
                    Modes::Real(l.map(|z| z.re + shift)),
                ),
                Some(k) => {
                    // The real one is the pole with im = 0 (cubic_roots
                    // zeroes a round-off imaginary part).
                    let r = poles.iter().position(|q| q.im == 0.0)?;
                    (
                        [
                            a[r].map(|z| z.re),
                            a[k].map(|z| 2.0 * z.re),
                            a[k].map(|z| -2.0 * z.im),
                        ],
                        Modes::Pair {
                            real: l[r].re + shift,
                            mu: l[k].re + shift,
                            omega: l[k].im,
                        },
                    )
                }
            }
        };
        if !b.iter().all(super::linalg::finite) {
            return None;
        }
        Some(Self { b, modes })
    }

    /// The real rates ν_j whose exponentials the coefficients are made of
    /// (unused ones 0) and the angular frequency ω of a pair (0 if none).
    fn rates(&self) -> ([f64; 3], f64) {
        match self.modes {
            Modes::Real(mu) => (mu, 0.0),
            Modes::Pair { real, mu, omega } => ([real, mu, 0.0], omega),
            Modes::Double { simple, double } => ([simple, double, 0.0], 0.0),
            Modes::Triple(mu) => ([mu, 0.0, 0.0], 0.0),
        }
    }

    /// c_k(t) of the module doc from e = (e^(ν_j t)) and (cos ωt, sin ωt).
    fn coefficients_from(&self, t: f64, e: [f64; 3], (c, s): (f64, f64)) -> [f64; 3] {
        match self.modes {
            Modes::Real(_) => e,
            Modes::Pair { .. } => [e[0], e[1] * c, e[1] * s],
            Modes::Double { .. } => [e[0], e[1], t * e[1]],
            Modes::Triple(_) => [e[0], t * e[0], t * t * e[0]],
        }
    }

    /// c_k(t) of the module doc.
    fn coefficients(&self, t: f64) -> [f64; 3] {
        match self.modes {
            Modes::Real(mu) => mu.map(|m| (m * t).exp()),
            Modes::Pair { real, mu, omega } => {
                let e = (mu * t).exp();
                let (s, c) = (omega * t).sin_cos();
                [(real * t).exp(), e * c, e * s]
            }
            Modes::Double { simple, double } => {
                let e = (double * t).exp();
                [(simple * t).exp(), e, t * e]
            }
            Modes::Triple(mu) => {
                let e = (mu * t).exp();
                [e, t * e, t * t * e]
            }
        }
    }

    /// [`Self::coefficients`] at four times, the same bits: each rate's four
    /// exponentials in one [`exp4`] (glibc's `exp` in four lanes where it
    /// has the platform's bits, four calls elsewhere).
    fn coefficients4(&self, t: [f64; 4]) -> [[f64; 3]; 4] {
        let at = |rate: f64| exp4(t.map(|t| rate * t));
        match self.modes {
            Modes::Real(mu) => {
                let e = mu.map(at);
                std::array::from_fn(|i| [e[0][i], e[1][i], e[2][i]])
            }
            Modes::Pair { real, mu, omega } => {
                let (r, e) = (at(real), at(mu));
                std::array::from_fn(|i| {
                    let (s, c) = (omega * t[i]).sin_cos();
                    [r[i], e[i] * c, e[i] * s]
                })
            }
            Modes::Double { simple, double } => {
                let (a, e) = (at(simple), at(double));
                std::array::from_fn(|i| [a[i], e[i], t[i] * e[i]])
            }
            Modes::Triple(mu) => {
                let e = at(mu);
                std::array::from_fn(|i| [e[i], t[i] * e[i], t[i] * t[i] * e[i]])
            }
        }
    }

    /// The coefficients c_k at each of `t` (for [`Self::combine`]), four
    /// at a time ([`Self::coefficients4`]): the same bits as
    /// [`Self::exp`]'s at each.
    pub(super) fn coefficients_many(&self, t: &[f64]) -> Vec<[f64; 3]> {
        let mut out = Vec::with_capacity(t.len());
        let mut chunks = t.chunks_exact(4);
        for c in &mut chunks {
            out.extend(self.coefficients4([c[0], c[1], c[2], c[3]]));
        }
        out.extend(chunks.remainder().iter().map(|&t| self.coefficients(t)));
        out
    }

    /// exp((P + shift·I)t) at four times: the same bits as four
    /// [`Self::exp`]s.
    pub fn exp4(&self, t: [f64; 4]) -> [Matrix3<f64>; 4] {
        self.coefficients4(t).map(|c| self.combine(c))
    }

    /// Σ B_k c_k.
    pub(super) fn combine(&self, c: [f64; 3]) -> Matrix3<f64> {
        self.b[0] * c[0] + self.b[1] * c[1] + self.b[2] * c[2]
    }

    /// exp((P + shift·I)t).
    pub fn exp(&self, t: f64) -> Matrix3<f64> {
        self.combine(self.coefficients(t))
    }

    /// ‖exp((P + shift·I)t)‖₂ ([`super::linalg::norm2_3_fast`]).
    pub fn norm(&self, t: f64) -> f64 {
        super::linalg::norm2_3_fast(&self.exp(t))
    }

    /// The same on the uniform grid t_i = (i + offset)·dt, i < n, with the
    /// exponentials from tables; None if a table entry is not finite.
    pub fn uniform(&self, dt: f64, offset: f64, n: usize) -> Option<UniformExp<'_>> {
        let (nu, omega) = self.rates();
        let entry = |tau: f64| {
            let e = nu.map(|v| (v * tau).exp());
            let (s, c) = if omega != 0.0 {
                (omega * tau).sin_cos()
            } else {
                (0.0, 1.0)
            };
            [e[0], e[1], e[2], c, s]
        };
        let lo: Vec<[f64; 5]> = (0..TABLE)
            .map(|j| entry((j as f64 + offset) * dt))
            .collect();
        let hi: Vec<[f64; 5]> = (0..n.div_ceil(TABLE).max(1))
            .map(|k| entry((k * TABLE) as f64 * dt))
            .collect();
        let ok = lo.iter().chain(&hi).flatten().all(|v| v.is_finite());
        ok.then_some(UniformExp {
            f: self,
            dt,
            offset,
            lo,
            hi,
        })
    }
}

/// Entries of the low table of [`UniformExp`] (a power of two).
const TABLE: usize = 64;

/// exp((P + s·I)t_i) on a uniform grid t_i = (i + offset)·dt: e^(ν t_i) =
/// e^(ν·64k·dt)·e^(ν(j + offset)dt) with i = 64k + j, one product of two
/// table entries (each within half an ulp) instead of an exponential, so
/// within 1.5 ulp; cos and sin of a pair by the addition formulas. The
/// tables hold n/64 + 64 entries.
pub struct UniformExp<'a> {
    f: &'a SpectralExp,
    dt: f64,
    offset: f64,
    lo: Vec<[f64; 5]>,
    hi: Vec<[f64; 5]>,
}

impl UniformExp<'_> {
    /// c_k(t_i) of the module doc.
    fn coefficients(&self, i: usize) -> [f64; 3] {
        let (h, l) = (&self.hi[i / TABLE], &self.lo[i % TABLE]);
        let e = [h[0] * l[0], h[1] * l[1], h[2] * l[2]];
        let c = h[3] * l[3] - h[4] * l[4];
        let s = h[4] * l[3] + h[3] * l[4];
        let t = (i as f64 + self.offset) * self.dt;
        self.f.coefficients_from(t, e, (c, s))
    }

    /// exp((P + shift·I)t_i).
    pub fn exp(&self, i: usize) -> Matrix3<f64> {
        self.f.combine(self.coefficients(i))
    }

    /// The squared Frobenius norms Σ m_jk² (summed in the order of
    /// `Matrix3::iter`, as `Iterator::sum` does) of exp((P + shift·I)t) at
    /// t_i, …, t_(i+3), without the matrices: the bits of that sum over
    /// [`Self::exp`] at each, computed side by side across the four points.
    /// The four must be on the grid: i + 4 ≤ n of [`SpectralExp::uniform`].
    pub fn frobenius2_4(&self, i: usize) -> [f64; 4] {
        // c_k of the module doc at the four points, as `coefficients` has
        // them: the tables' products, then the mode's own combination.
        let h: [&[f64; 5]; 4] = std::array::from_fn(|l| &self.hi[(i + l) / TABLE]);
        let lo: [&[f64; 5]; 4] = std::array::from_fn(|l| &self.lo[(i + l) % TABLE]);
        let e = |k: usize| -> [f64; 4] { std::array::from_fn(|l| h[l][k] * lo[l][k]) };
        let t =
            || -> [f64; 4] { std::array::from_fn(|l| ((i + l) as f64 + self.offset) * self.dt) };
        let c: [[f64; 4]; 3] = match self.f.modes {
            Modes::Real(_) => [e(0), e(1), e(2)],
            Modes::Pair { .. } => {
                let e1 = e(1);
                let cos: [f64; 4] =
                    std::array::from_fn(|l| h[l][3] * lo[l][3] - h[l][4] * lo[l][4]);
                let sin: [f64; 4] =
                    std::array::from_fn(|l| h[l][4] * lo[l][3] + h[l][3] * lo[l][4]);
                [
                    e(0),
                    std::array::from_fn(|l| e1[l] * cos[l]),
                    std::array::from_fn(|l| e1[l] * sin[l]),
                ]
            }
            Modes::Double { .. } => {
                let (e1, t) = (e(1), t());
                [e(0), e1, std::array::from_fn(|l| t[l] * e1[l])]
            }
            Modes::Triple(_) => {
                let (e0, t) = (e(0), t());
                [
                    e0,
                    std::array::from_fn(|l| t[l] * e0[l]),
                    std::array::from_fn(|l| t[l] * t[l] * e0[l]),
                ]
            }
        };
        let b = &self.f.b;
        let mut f2 = [-0.0; 4];
        // Entry by entry, in `Matrix3::iter`'s order (column by column);
        // indexed rather than zipped, which LLVM vectorises across the
        // four points (the zipped form measured 0.9 M instructions more
        // in a Fig. 2 run).
        #[allow(clippy::needless_range_loop)]
        for k in 0..9 {
            let (b0, b1, b2) = (b[0][k], b[1][k], b[2][k]);
            for l in 0..4 {
                // As `combine`: (B0·c0 + B1·c1) + B2·c2, entry by entry.
                let v = b0 * c[0][l] + b1 * c[1][l] + b2 * c[2][l];
                f2[l] += v * v;
            }
        }
        f2
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{cubic_roots, p_matrix};

    fn pole(re: f64, im: f64) -> Pole {
        Pole::from(Complex::new(re, im))
    }

    fn rel_diff(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
        (a - b).abs().max() / b.abs().max()
    }

    /// A triple pole −q: P = p_matrix([3q, 3q², q³]) and, with N = P + qI,
    /// exp(Pt) = e^(−qt)(I + tN + t²N²/2). Its first row, written out:
    /// N = [[q, 1, 0], [0, q, 1], [−q³, −3q², −2q]], N² first row
    /// (q², 2q, 1), so exp(Pt)[0] = e^(−qt)·(1 + qt + q²t²/2, t + qt², t²/2);
    /// and the last row of exp(Pt) is the second derivative of the first:
    /// exp(Pt)[2][2] = d²/dt²(t²/2·e^(−qt)) = e^(−qt)(1 − 2qt + q²t²/2).
    #[test]
    fn triple_pole_against_its_polynomials() {
        for q in [0.5, 20.0, 300.0] {
            let p = p_matrix([3.0 * q, 3.0 * q * q, q * q * q]);
            let poles = [pole(-q, 0.0); 3];
            let f = SpectralExp::new(&p, &poles, 0.0).unwrap();
            for t in [0.0, 0.1 / q, 1.0 / q, 5.0 / q, 30.0 / q] {
                let e = f.exp(t);
                let x = q * t;
                let ex = (-x).exp();
                let want = [
                    ex * (1.0 + x + x * x / 2.0),
                    ex * (t + q * t * t),
                    ex * t * t / 2.0,
                ];
                for (j, w) in want.iter().enumerate() {
                    assert!(
                        (e[(0, j)] - w).abs() <= 1e-15 * w.abs().max(1e-300) + 1e-300,
                        "q = {q}, t = {t}, j = {j}: {} vs {w}",
                        e[(0, j)]
                    );
                }
                let w22 = ex * (1.0 - 2.0 * x + x * x / 2.0);
                assert!((e[(2, 2)] - w22).abs() <= 1e-14 * (1.0 + x * x) * ex + 1e-300);
                // nalgebra's exp agrees.
                let n = (p * t).exp();
                assert!(rel_diff(&e, &n) < 1e-12, "q = {q}, t = {t}");
            }
            // The shift: exp((P + qI)t) = e^(qt)·exp(Pt), polynomial in t.
            let g = SpectralExp::new(&p, &poles, q).unwrap();
            let e = g.exp(2.0 / q);
            assert!((e[(0, 0)] - (1.0 + 2.0 + 2.0)).abs() < 1e-13);
        }
    }

    /// The four-at-a-time path gives each time the bits of the one-at-a-time
    /// one, in every mode (distinct real, a pair, a double and a triple
    /// pole), at times whose exponents fall in the vector exp's range and
    /// outside it (t = 0, tiny t, exponents below −512).
    #[test]
    fn four_at_a_time_is_one_at_a_time_to_the_bit() {
        let cases: [([f64; 3], [Pole; 3]); 4] = [
            ([90.0, 2600.0, 24000.0], cubic_roots(90.0, 2600.0, 24000.0)),
            ([40.0, 900.0, 10000.0], cubic_roots(40.0, 900.0, 10000.0)),
            (
                [70.0, 1500.0, 9000.0],
                [pole(-10.0, 0.0), pole(-30.0, 0.0), pole(-30.0, 0.0)],
            ),
            ([60.0, 1200.0, 8000.0], [pole(-20.0, 0.0); 3]),
        ];
        let times = [
            0.0, 1e-300, 3e-3, 0.017, 0.25, 1.0, 2.5, 7.0, 40.0, 1e3, 0.125, 3.75,
        ];
        for (k, (a, poles)) in cases.iter().enumerate() {
            let p = p_matrix(*a);
            for shift in [0.0, 10.0] {
                let f = SpectralExp::new(&p, poles, shift).unwrap();
                let mode = std::mem::discriminant(&f.modes);
                let bits = |m: &Matrix3<f64>| m.map(f64::to_bits);
                for q in times.chunks_exact(4) {
                    let m4 = f.exp4([q[0], q[1], q[2], q[3]]);
                    for (m, &t) in m4.iter().zip(q) {
                        assert_eq!(bits(m), bits(&f.exp(t)), "case {k}, t = {t}, {mode:?}");
                    }
                }
                // On a uniform grid (whose tables span several low-table
                // periods): the squared Frobenius norms, four at a time.
                let n = 203;
                let u = f.uniform(0.037, 0.5, n).unwrap();
                for i in (0..n - 3).step_by(5) {
                    let f2 = u.frobenius2_4(i);
                    for (l, f2) in f2.iter().enumerate() {
                        let m = u.exp(i + l);
                        let want: f64 = m.iter().map(|v| v * v).sum();
                        assert_eq!(f2.to_bits(), want.to_bits(), "case {k}, i = {}", i + l);
                    }
                }
                // Eleven times: two chunks of four and a remainder of three.
                let c = f.coefficients_many(&times[..11]);
                for (c, &t) in c.iter().zip(&times[..11]) {
                    assert_eq!(bits(&f.combine(*c)), bits(&f.exp(t)), "case {k}, t = {t}");
                }
            }
        }
    }

    /// Sylvester's terms with exact roots: for the paper's poles the first
    /// column of exp(Pt) is (6e^(−20t) − 8e^(−30t) + 3e^(−40t), …) (see
    /// tests/it/analysis.rs for the hand derivation).
    #[test]
    fn distinct_real_poles_by_hand() {
        let p = p_matrix([90.0, 2600.0, 24000.0]);
        let poles = cubic_roots(90.0, 2600.0, 24000.0);
        let f = SpectralExp::new(&p, &poles, 0.0).unwrap();
        assert!(matches!(f.modes, Modes::Real(_)));
        for t in [0.0, 0.01, 0.05, 0.2, 1.0] {
            let e = f.exp(t);
            let (a, b, c) = ((-20.0 * t).exp(), (-30.0 * t).exp(), (-40.0 * t).exp());
            assert!((e[(0, 0)] - (6.0 * a - 8.0 * b + 3.0 * c)).abs() < 1e-13);
            assert!((e[(1, 0)] - (-120.0 * a + 240.0 * b - 120.0 * c)).abs() < 1e-11);
        }
    }

    /// exp((P + sI)t) against nalgebra's exp on every structure the module
    /// handles: distinct real, a complex pair (dominant or not), a double
    /// pole (simple one dominant or not), well separated and at the edge of
    /// [`SEPARATION`]; None for a near-repeated pair that is not equal.
    #[test]
    fn closed_form_against_nalgebra_exp() {
        // (p, shift, tolerance of the comparison: nalgebra's own accuracy)
        let cases: [([f64; 3], f64); 6] = [
            ([90.0, 2600.0, 24000.0], 20.0),          // −20, −30, −40
            ([30.0, 425.0, 3750.0], 6.0189819169542), // −10, −10 ± j17.3
            ([3001.0, 2_003_000.0, 2e6], 1.0),        // −1, −1000, −2000
            ([42.0, 580.0, 1000.0], 2.0),             // −2, −20 ± j10
            ([16.0, 65.0, 50.0], 1.0),                // −1, −5, −10
            ([22.0, 137.0, 350.0], 0.0),              // −4 ± j3, −14
        ];
        for (c, shift) in cases {
            let p = p_matrix(c);
            let poles = cubic_roots(c[0], c[1], c[2]);
            let f = SpectralExp::new(&p, &poles, shift).unwrap();
            for t in [0.0, 1e-4, 1e-3, 0.01, 0.1, 0.5, 2.0] {
                let n = ((p + Matrix3::identity() * shift) * t).exp();
                let e = f.exp(t);
                assert!(rel_diff(&e, &n) < 1e-11, "{c:?} t = {t}: {e} vs {n}");
            }
        }
        // Exactly repeated, not dominant: −20, −40, −40 (p = (100, 3200,
        // 32000)); and dominant: −20, −20, −40 (p = (80, 2000, 16000)).
        for (c, poles) in [
            (
                [100.0, 3200.0, 32000.0],
                [pole(-20.0, 0.0), pole(-40.0, 0.0), pole(-40.0, 0.0)],
            ),
            (
                [80.0, 2000.0, 16000.0],
                [pole(-20.0, 0.0), pole(-20.0, 0.0), pole(-40.0, 0.0)],
            ),
        ] {
            let p = p_matrix(c);
            let f = SpectralExp::new(&p, &poles, 20.0).unwrap();
            assert!(matches!(f.modes, Modes::Double { .. }));
            for t in [0.0, 1e-3, 0.05, 0.3, 1.0] {
                let n = ((p + Matrix3::identity() * 20.0) * t).exp();
                assert!(rel_diff(&f.exp(t), &n) < 1e-12, "{c:?} t = {t}");
            }
        }
        // Near-repeated but not equal: no closed form.
        let p = p_matrix([100.0, 3200.0, 32000.0]);
        let split = [pole(-20.0, 0.0), pole(-40.0, 0.0), pole(-40.001, 0.0)];
        assert!(SpectralExp::new(&p, &split, 20.0).is_none());
        let cx = [pole(-20.0, 0.0), pole(-40.0, 1e-3), pole(-40.0, -1e-3)];
        assert!(SpectralExp::new(&p, &cx, 20.0).is_none());
        // Not finite.
        let bad = [pole(f64::NAN, 0.0), pole(-1.0, 0.0), pole(-2.0, 0.0)];
        assert!(SpectralExp::new(&p, &bad, 0.0).is_none());
    }
}
