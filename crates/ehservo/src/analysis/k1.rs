//! K1 of (18): Sylvester's form of exp(Pt), the profile
//! g(t) = ‖exp((P + K2·I)t)‖₂, the golden-section maximum and the search
//! for K1 = sup_t g(t) with its proof-of-bound check.

use super::poles::Pole;
use nalgebra::{Complex, Matrix3};
use serde::Serialize;

/// Relative tolerance of the proof-of-bound check of K1: no sample of the
/// check grid (nor the tail bound) may exceed K1·(1 + K1_TOLERANCE).
pub const K1_TOLERANCE: f64 = 1e-9;

fn norm2(m: &Matrix3<f64>) -> f64 {
    super::linalg::norm2_3(m)
}

type CMat = Matrix3<Complex<f64>>;

/// Sylvester's formula: for pairwise distinct eigenvalues λ_i of P,
/// exp(Pt) = Σ_i e^(λ_i t)·A_i with A_i = Π_{j≠i}(P − λ_j I)/(λ_i − λ_j).
/// None when two eigenvalues are closer than 1e-4 of the largest |λ| (the
/// formula is then ill-conditioned, or a Jordan block makes it wrong).
pub fn sylvester_terms(p: &Matrix3<f64>, poles: &[Pole; 3]) -> Option<[CMat; 3]> {
    // The eigenvalues, polished by Newton's method on det(sI − P) =
    // s³ + c2 s² + c1 s + c0 (c2 = −tr P, c1 = Σ principal 2×2 minors,
    // c0 = −det P): the coefficients A_i magnify an eigenvalue's error by
    // ‖P‖/gap.
    let c2 = -p.trace();
    let c1 = p[(0, 0)] * p[(1, 1)] - p[(0, 1)] * p[(1, 0)] + p[(0, 0)] * p[(2, 2)]
        - p[(0, 2)] * p[(2, 0)]
        + p[(1, 1)] * p[(2, 2)]
        - p[(1, 2)] * p[(2, 1)];
    let c0 = -p.determinant();
    let l: [Complex<f64>; 3] = std::array::from_fn(|i| {
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
    });
    // Relative to the poles' own size (slow distinct poles are not repeated).
    let scale = poles.iter().map(|q| q.wn).fold(0.0, f64::max);
    for i in 0..3 {
        for j in i + 1..3 {
            if (l[i] - l[j]).norm() <= 1e-4 * scale {
                return None;
            }
        }
    }
    let pc: CMat = p.map(|v| Complex::new(v, 0.0));
    let id = CMat::identity();
    Some(std::array::from_fn(|i| {
        let mut m = id;
        for (j, lj) in l.iter().enumerate() {
            if j != i {
                m = m * (pc - id * *lj) / (l[i] - *lj);
            }
        }
        m
    }))
}

/// K1 of (18) and how it was obtained and checked.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct K1 {
    /// K1, or None if infinite (repeated dominant pole).
    pub value: Option<f64>,
    /// Where the supremum is reached (s); None when approached as t → ∞.
    pub at_t: Option<f64>,
    /// Span of the search grid (s).
    pub span: f64,
    /// Points of the search grid (linear and geometric together).
    pub grid_points: usize,
    /// lim sup of g(t) as t → ∞ from Sylvester's formula: ‖A_dom‖ for a
    /// simple real dominant pole, the largest ‖2·Re(A e^(iωt))‖ over a
    /// period for a complex pair (None when two poles coincide).
    pub limit: Option<f64>,
    /// Upper bound of g(t) for every t ≥ span: limit + Σ_faster ‖A_j‖e^((Re λ_j + K2)·span).
    pub tail_bound: Option<f64>,
    /// Points of the independent check grid (over twice the span).
    pub check_points: usize,
    /// Largest g(t)/K1 on the check grid.
    pub check_max_ratio: f64,
    /// Largest relative difference, over the search grid, between g from
    /// nalgebra's exp and g from Sylvester's closed form: the accuracy of
    /// the arithmetic itself (None without Sylvester's form).
    pub exp_discrepancy: Option<f64>,
    /// The relative tolerance of the check: [`K1_TOLERANCE`], or four times
    /// `exp_discrepancy` when that is larger.
    pub tolerance: f64,
    /// No check point and no tail bound exceeds K1·(1 + tolerance).
    pub verified: bool,
}

/// g(t) = ‖exp((P + K2 I)t)‖₂ = e^(K2 t)·‖exp(Pt)‖₂ with nalgebra's
/// matrix exponential.
pub fn k1_profile(p: &Matrix3<f64>, k2: f64, t: f64) -> f64 {
    super::linalg::expm3(&((p + Matrix3::identity() * k2) * t))
        .map(|e| norm2(&e))
        .unwrap_or(f64::NAN)
}

/// Golden-section search for the maximum of `f` on [a, b].
pub(super) fn golden_max(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> (f64, f64) {
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - phi * (b - a);
    let mut d = a + phi * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..100 {
        if fc > fd {
            b = d;
            d = c;
            fd = fc;
            c = b - phi * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + phi * (b - a);
            fd = f(d);
        }
        if b - a <= 1e-15 * b.abs().max(1e-300) {
            break;
        }
    }
    if fc > fd {
        (c, fc)
    } else {
        (d, fd)
    }
}

/// K1 = sup over t ≥ 0 of g(t) = ‖exp(Pt)‖₂·e^(K2·t), for P with the
/// (sorted) eigenvalues `poles` and K2 = −Re of the first.
///
/// 1. A repeated dominant eigenvalue (P is a companion matrix, so a repeated
///    eigenvalue is always a Jordan block) makes g grow like t: K1 = ∞.
/// 2. g is evaluated with nalgebra's `exp` on a linear grid of 4001 points
///    and a geometric grid of 1000 points from 10⁻³/max|λ| (the fast
///    transients) to the span = max(40/gap, ten periods of the dominant
///    oscillation, 10/K2), gap = distance from the dominant real part to the
///    next: by then every faster mode has decayed by e^(−40) (longer if
///    Sylvester's coefficients of the faster modes are large: until they
///    fall below 1e-12 of the dominant ones).
/// 3. The largest sample is refined by golden section between its
///    neighbours.
/// 4. Sylvester's formula gives the limit of g as t → ∞ (for distinct real
///    eigenvalues g settles to ‖A_dom‖ — the supremum is then approached,
///    not reached) and a bound on g beyond the span.
/// 5. Proof-of-bound check: an independent grid, three times denser, offset
///    to the midpoints and over twice the span, must stay below
///    K1·(1 + tolerance), and so must the tail bound; the tolerance is
///    [`K1_TOLERANCE`] unless exp and Sylvester's form disagree by more
///    than a quarter of it (then four times their disagreement: the check
///    cannot be sharper than the arithmetic).
pub fn k1(p: &Matrix3<f64>, poles: &[Pole; 3], k2: f64) -> K1 {
    let dominant = poles[0].re;
    // Relative to the poles' own size (slow distinct poles are not repeated).
    let scale = poles.iter().map(|q| q.wn).fold(0.0, f64::max);
    // Eigenvalues of a repeated root come out split by ~sqrt(ε)·|λ|; anything
    // within 1e-4 of the scale is taken as repeated (a near-repeated pair
    // would give a K1 of order 1/gap anyway).
    let tol = 1e-4 * scale;
    let dom: Vec<&Pole> = poles
        .iter()
        .filter(|q| (q.re - dominant).abs() <= tol)
        .collect();
    for (i, a) in dom.iter().enumerate() {
        for b in &dom[i + 1..] {
            if (a.im - b.im).abs() <= tol {
                return K1 {
                    value: None,
                    at_t: None,
                    span: f64::INFINITY,
                    grid_points: 0,
                    limit: None,
                    tail_bound: None,
                    check_points: 0,
                    check_max_ratio: f64::INFINITY,
                    exp_discrepancy: None,
                    tolerance: K1_TOLERANCE,
                    verified: false,
                };
            }
        }
    }
    let terms = sylvester_terms(p, poles);
    let gap = poles
        .iter()
        .filter(|q| dominant - q.re > tol)
        .map(|q| dominant - q.re)
        .fold(f64::INFINITY, f64::min);
    let omega = dom.iter().map(|q| q.im.abs()).fold(0.0, f64::max);
    let mut span: f64 = if gap.is_finite() { 40.0 / gap } else { 0.0 };
    if omega > 0.0 {
        span = span.max(10.0 * 2.0 * std::f64::consts::PI / omega);
    }
    // Long enough for the slower-decaying terms to fall below 1e-12 of the
    // dominant ones even when Sylvester's coefficients are large.
    if let (Some(a), true) = (&terms, gap.is_finite()) {
        let big: f64 = a.iter().map(|m| m.norm()).sum();
        let small = a
            .iter()
            .zip(poles)
            .filter(|(_, q)| (q.re - dominant).abs() <= tol)
            .map(|(m, _)| m.norm())
            .fold(f64::INFINITY, f64::min);
        span = span.max((big / (1e-12 * small)).ln().max(0.0) / gap);
    }
    let span = span.max(10.0 / k2.max(1e-12)).min(1e6 / k2.max(1e-12));
    let g = |t: f64| k1_profile(p, k2, t);

    // 2. Search grid: linear ∪ geometric, sorted.
    let n_lin = 4000usize;
    let n_geo = 1000usize;
    let t0 = 1e-3 / scale;
    let mut grid: Vec<f64> = (0..=n_lin)
        .map(|i| span * i as f64 / n_lin as f64)
        .collect();
    if t0 < span {
        let ratio = (span / t0).ln();
        grid.extend((0..n_geo).map(|i| t0 * (ratio * i as f64 / n_geo as f64).exp()));
    }
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    let values: Vec<f64> = grid.iter().map(|&t| g(t)).collect();
    let (imax, &vmax) = values
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap_or((0, &1.0));
    // 3. Refinement between the neighbours of the best sample.
    let lo = grid[imax.saturating_sub(1)];
    let hi = grid[(imax + 1).min(grid.len() - 1)];
    let (tr, vr) = if hi > lo {
        golden_max(g, lo, hi)
    } else {
        (grid[imax], vmax)
    };
    let (mut t_star, mut k1v) = if vr > vmax {
        (tr, vr)
    } else {
        (grid[imax], vmax)
    };

    // 4. The limit and the tail bound from Sylvester's terms.
    let (limit, tail_bound) = match &terms {
        Some(a) => {
            let is_dom: [bool; 3] = std::array::from_fn(|i| (poles[i].re - dominant).abs() <= tol);
            let d_at = |t: f64| {
                let mut m = CMat::zeros();
                for i in 0..3 {
                    if is_dom[i] {
                        m += a[i] * Complex::new(0.0, poles[i].im * t).exp();
                    }
                }
                norm2(&m.map(|c| c.re))
            };
            let lim = if omega > 0.0 {
                let period = 2.0 * std::f64::consts::PI / omega;
                let n = 2000;
                let (ib, vb) = (0..n)
                    .map(|i| (i, d_at(period * i as f64 / n as f64)))
                    .fold((0, f64::NEG_INFINITY), |b, x| if x.1 > b.1 { x } else { b });
                let h = period / n as f64;
                let (_, vg) = golden_max(d_at, ib as f64 * h - h, ib as f64 * h + h);
                vb.max(vg)
            } else {
                d_at(0.0)
            };
            let rest: f64 = (0..3)
                .filter(|&i| !is_dom[i])
                .map(|i| cnorm2(&a[i]) * ((poles[i].re + k2) * span).exp())
                .sum();
            (Some(lim), Some(lim + rest))
        }
        None => (None, None),
    };
    // The arithmetic's own accuracy: nalgebra's exp against Sylvester's
    // closed form on the search grid. The check cannot be sharper than
    // their disagreement (≈ 1e-13 for well-separated poles, ≈ 1e-8 for
    // poles 0.5 s⁻¹ apart, where the scaling and squaring of a large,
    // non-normal (P + K2 I)t loses digits).
    let discrepancy = terms.as_ref().map(|a| {
        grid.iter()
            .zip(&values)
            .map(|(&t, &v)| {
                let mut m = CMat::zeros();
                for (ai, q) in a.iter().zip(poles) {
                    m += ai * (Complex::new(q.re + k2, q.im) * t).exp();
                }
                let exact = norm2(&m.map(|c| c.re));
                (v - exact).abs() / exact
            })
            .fold(0.0, f64::max)
    });
    let tolerance = K1_TOLERANCE.max(4.0 * discrepancy.unwrap_or(0.0));
    let mut approached = false;
    if let Some(l) = limit {
        if omega == 0.0 && l >= k1v * (1.0 - tolerance) {
            // Distinct real poles and no sample above the limit (beyond the
            // arithmetic's noise): g rises to ‖A_dom‖, the supremum is that
            // limit, approached as t → ∞, and Sylvester's value is the
            // accurate one.
            approached = true;
            k1v = l;
            t_star = f64::INFINITY;
        }
    }
    if let (Some(l), true) = (limit, omega > 0.0) {
        if l > k1v {
            // A dominant complex pair whose periodic part peaks above every
            // sample: the supremum is approached along those peaks.
            approached = true;
            k1v = l;
        }
    }
    if !approached && limit.is_none() && g(span) >= k1v * (1.0 - tolerance) {
        approached = true;
    }

    // 5. Independent check: 3× denser, offset, over twice the span.
    let m_lin = 3 * n_lin;
    let m_geo = 3 * n_geo;
    let mut worst: f64 = 0.0;
    for i in 0..m_lin {
        let t = 2.0 * span * (i as f64 + 0.5) / m_lin as f64;
        worst = worst.max(g(t) / k1v);
    }
    if t0 < 2.0 * span {
        let ratio = (2.0 * span / t0).ln();
        for i in 0..m_geo {
            let t = t0 * (ratio * (i as f64 + 0.5) / m_geo as f64).exp();
            worst = worst.max(g(t) / k1v);
        }
    }
    let tail_ok = tail_bound.is_none_or(|b| b <= k1v * (1.0 + tolerance));
    K1 {
        value: Some(k1v),
        at_t: if approached { None } else { Some(t_star) },
        span,
        grid_points: grid.len(),
        limit,
        tail_bound,
        check_points: m_lin + m_geo,
        check_max_ratio: worst,
        exp_discrepancy: discrepancy,
        tolerance,
        verified: worst <= 1.0 + tolerance && tail_ok,
    }
}

/// Spectral norm of a complex 3×3 matrix.
fn cnorm2(m: &CMat) -> f64 {
    m.singular_values().max()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{cubic_roots, p_matrix};
    use nalgebra::Vector3;

    /// Sylvester's A_i for the paper's P are the spectral projectors:
    /// Σ A_i = I, Σ λ_i A_i = P, A_i² = A_i and A_i A_j = 0.
    #[test]
    fn sylvester_terms_are_the_spectral_projectors() {
        let p = p_matrix([90.0, 2600.0, 24000.0]);
        let poles = cubic_roots(90.0, 2600.0, 24000.0);
        let a = sylvester_terms(&p, &poles).unwrap();
        let re = |m: &CMat| m.map(|c| c.re);
        let sum = re(&(a[0] + a[1] + a[2]));
        assert!((sum - Matrix3::identity()).abs().max() < 1e-9);
        let lam = re(&(a[0] * Complex::new(-20.0, 0.0)
            + a[1] * Complex::new(-30.0, 0.0)
            + a[2] * Complex::new(-40.0, 0.0)));
        assert!((lam - p).abs().max() < 1e-7 * 24000.0);
        for i in 0..3 {
            let sq = re(&(a[i] * a[i]));
            assert!((sq - re(&a[i])).abs().max() < 1e-6 * re(&a[i]).abs().max());
            for j in 0..3 {
                if i != j {
                    assert!(re(&(a[i] * a[j])).abs().max() < 1e-6 * re(&a[i]).abs().max());
                }
            }
        }
        // A repeated pole: no Sylvester form.
        let rep = cubic_roots(80.0, 2000.0, 16000.0); // (s + 20)²(s + 40)
        assert!(sylvester_terms(&p_matrix([80.0, 2000.0, 16000.0]), &rep).is_none());
    }

    /// A normal (diagonal) P: ‖exp(Pt)‖·e^(K2 t) = max_i e^((λ_i + K2)t) = 1
    /// for all t, so K1 = 1 exactly and Theorem 2 admits α < K2.
    #[test]
    fn k1_of_a_normal_matrix_is_one() {
        let p = Matrix3::from_diagonal(&Vector3::new(-1.0, -2.0, -3.0));
        let poles = [
            Pole::from(Complex::new(-1.0, 0.0)),
            Pole::from(Complex::new(-2.0, 0.0)),
            Pole::from(Complex::new(-3.0, 0.0)),
        ];
        let k = k1(&p, &poles, 1.0);
        assert!((k.value.unwrap() - 1.0).abs() < 1e-12, "{k:?}");
        assert!(k.verified && k.at_t.is_none());
    }
}
