//! K1 of (18): Sylvester's form of exp(Pt), the profile
//! g(t) = ‖exp((P + K2·I)t)‖₂ (in closed form, [`super::spectral`], or by
//! nalgebra's exp), the golden-section maximum and the search for
//! K1 = sup_t g(t) with its proof-of-bound check.

use super::poles::Pole;
use super::spectral::{exp4, polished_eigenvalues, sylvester_products, SpectralExp};
use nalgebra::{Complex, Matrix3};
use serde::Serialize;

/// Relative tolerance of the proof-of-bound check of K1: no sample of the
/// check grid (nor the tail bound) may exceed K1·(1 + K1_TOLERANCE).
pub const K1_TOLERANCE: f64 = 1e-9;

/// Relative slack of the closed-form search: a grid point whose upper
/// bound (with its rounding margin) is at most the largest g so far times
/// 1 + SLACK is not evaluated — where g has settled on its limit every point
/// ties with the largest to rounding, on either side. On the search grid it
/// is left out of the maximum (which it cannot beat by more than the
/// slack); on the check grid it counts with its bound, so the check's
/// largest g/K1 may exceed the exact one by the slack, never fall below it.
const SLACK: f64 = 2e-12;

/// Points of the search grid (evenly strided, and its last) on which
/// nalgebra's exp is compared with the closed form for `exp_discrepancy`
/// when g comes from the closed form.
const DISCREPANCY_POINTS: usize = 64;

/// ‖m‖₂ by the SVD: the reference path (nalgebra's exp).
fn norm2(m: &Matrix3<f64>) -> f64 {
    super::linalg::norm2_3(m)
}

/// ‖m‖₂ in closed form: the closed-form path.
fn norm2_fast(m: &Matrix3<f64>) -> f64 {
    super::linalg::norm2_3_fast(m)
}

type CMat = Matrix3<Complex<f64>>;

/// Sylvester's formula: for pairwise distinct eigenvalues λ_i of P,
/// exp(Pt) = Σ_i e^(λ_i t)·A_i with A_i = Π_{j≠i}(P − λ_j I)/(λ_i − λ_j).
/// None when two eigenvalues are closer than 1e-4 of the largest |λ| (the
/// formula is then ill-conditioned, or a Jordan block makes it wrong).
pub fn sylvester_terms(p: &Matrix3<f64>, poles: &[Pole; 3]) -> Option<[CMat; 3]> {
    // The eigenvalues polished by Newton's method: the coefficients A_i
    // magnify an eigenvalue's error by ‖P‖/gap.
    let l = polished_eigenvalues(p, poles);
    // Relative to the poles' own size (slow distinct poles are not repeated).
    let scale = poles.iter().map(|q| q.wn).fold(0.0, f64::max);
    for i in 0..3 {
        for j in i + 1..3 {
            if (l[i] - l[j]).norm() <= 1e-4 * scale {
                return None;
            }
        }
    }
    Some(sylvester_products(p, &l))
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
    /// Largest g(t)/K1 on the check grid (in closed form an upper bound of
    /// it, above it by at most 2e-12 relative).
    pub check_max_ratio: f64,
    /// Largest relative difference between g from nalgebra's exp and g
    /// from the closed form, over 64 evenly strided points of the search
    /// grid and its last (over every point, against Sylvester's complex
    /// form, when g itself comes from exp): the accuracy of the arithmetic
    /// itself (None without Sylvester's form).
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
/// 2. g is evaluated on a linear grid of 4001 points
///    and a geometric grid of 1000 points from 10⁻³/max|λ| (the fast
///    transients) to the span = max(40/gap, ten periods of the dominant
///    oscillation, 10/K2), gap = distance from the dominant real part to the
///    next: by then every faster mode has decayed by e^(−40) (longer if
///    Sylvester's coefficients of the faster modes are large: until they
///    fall below 1e-12 of the dominant ones). g comes from the closed form
///    of exp((P + K2 I)t) ([`SpectralExp`]: three exponentials, from tables
///    on the uniform grids, and a closed-form 3×3 norm), or from nalgebra's
///    `exp` and the SVD when two poles are too close for it
///    ([`super::SEPARATION`]). In closed form only the largest sample is
///    needed exactly: a point whose upper bounds of g ([`screen`]) put it
///    below the largest value so far, or within [`SLACK`] of it, skips the
///    spectral norm.
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
///    cannot be sharper than the arithmetic). In closed form the check's
///    largest g/K1 may exceed the exact one by [`SLACK`] (never fall
///    below it): a check point whose upper bound is within that of the
///    largest g counts with its bound rather than its norm, which spares
///    the norms of every point where g has settled on its limit.
pub fn k1(p: &Matrix3<f64>, poles: &[Pole; 3], k2: f64) -> K1 {
    k1_with(p, poles, k2, true)
}

/// [`k1`] with g from nalgebra's `exp` and the SVD everywhere: the path
/// [`k1`] falls back to when the poles are too close for the closed form,
/// and the reference the closed form is tested and measured against (about
/// twenty times slower).
pub fn k1_expm(p: &Matrix3<f64>, poles: &[Pole; 3], k2: f64) -> K1 {
    k1_with(p, poles, k2, false)
}

fn k1_with(p: &Matrix3<f64>, poles: &[Pole; 3], k2: f64, closed_form: bool) -> K1 {
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
    if repeated(&dom, tol) {
        return K1::INFINITE;
    }
    let terms = sylvester_terms(p, poles);
    let omega = dom.iter().map(|q| q.im.abs()).fold(0.0, f64::max);
    let span = search_span(poles, terms.as_ref(), tol, omega, k2);
    // g(t) in closed form when the poles allow it (spectral module doc),
    // else by nalgebra's exp.
    let s = Search {
        p,
        poles,
        k2,
        dominant,
        tol,
        omega,
        span,
        t0: 1e-3 / scale,
        closed: if closed_form {
            SpectralExp::new(p, poles, k2)
        } else {
            None
        },
    };

    // 2. The search grid and its largest g.
    let (points, geometric) = s.grid();
    let grid_len = points.len();
    let t_at = |i: usize| points[i].0;
    let (best, sampled) = s.grid_max(&points, &geometric);
    let (imax, vmax) = best.unwrap_or((0, 1.0));
    // 3. Refinement between the neighbours of the best sample.
    let lo = t_at(imax.saturating_sub(1));
    let hi = t_at((imax + 1).min(grid_len - 1));
    let (tr, vr) = if hi > lo {
        golden_max(|t| s.g(t), lo, hi)
    } else {
        (t_at(imax), vmax)
    };
    let (mut t_star, mut k1v) = if vr > vmax {
        (tr, vr)
    } else {
        (t_at(imax), vmax)
    };

    // 4. The limit and the tail bound from Sylvester's terms.
    let (limit, tail_bound) = match &terms {
        Some(a) => {
            let (lim, tail) = s.limit_and_tail(a);
            (Some(lim), Some(tail))
        }
        None => (None, None),
    };
    let discrepancy = terms.as_ref().map(|a| s.discrepancy(a, &sampled, &points));
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
    if !approached && limit.is_none() && s.g(span) >= k1v * (1.0 - tolerance) {
        approached = true;
    }

    // 5. Independent check: 3× denser, offset, over twice the span.
    let worst = match &s.closed {
        None => s.check_exp(k1v),
        Some(c) => s.check_closed(c, k1v, t_star),
    };
    let tail_ok = tail_bound.is_none_or(|b| b <= k1v * (1.0 + tolerance));
    K1 {
        value: Some(k1v),
        at_t: if approached { None } else { Some(t_star) },
        span,
        grid_points: grid_len,
        limit,
        tail_bound,
        check_points: CHECK_LINEAR + CHECK_GEOMETRIC,
        check_max_ratio: worst,
        exp_discrepancy: discrepancy,
        tolerance,
        verified: worst <= 1.0 + tolerance && tail_ok,
    }
}

/// Whether two of the dominant poles `dom` coincide (within `tol`).
fn repeated(dom: &[&Pole], tol: f64) -> bool {
    dom.iter()
        .enumerate()
        .any(|(i, a)| dom[i + 1..].iter().any(|b| (a.im - b.im).abs() <= tol))
}

impl K1 {
    /// K1 of a repeated dominant pole: infinite.
    const INFINITE: K1 = K1 {
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

/// Points of the search grid's linear part (intervals) and its geometric
/// part.
const SEARCH_LINEAR: usize = 4000;
const SEARCH_GEOMETRIC: usize = 1000;
/// Points of the check grid's linear and geometric parts: three times
/// denser than the search's.
const CHECK_LINEAR: usize = 3 * SEARCH_LINEAR;
const CHECK_GEOMETRIC: usize = 3 * SEARCH_GEOMETRIC;

/// The span of the search grid: max(40/gap, ten periods of the dominant
/// oscillation, 10/K2), longer when Sylvester's coefficients of the faster
/// modes are large, at most 10⁶/K2; gap = distance from the dominant real
/// part to the next.
fn search_span(poles: &[Pole; 3], terms: Option<&[CMat; 3]>, tol: f64, omega: f64, k2: f64) -> f64 {
    let dominant = poles[0].re;
    let gap = poles
        .iter()
        .filter(|q| dominant - q.re > tol)
        .map(|q| dominant - q.re)
        .fold(f64::INFINITY, f64::min);
    let mut span: f64 = if gap.is_finite() { 40.0 / gap } else { 0.0 };
    if omega > 0.0 {
        span = span.max(10.0 * 2.0 * std::f64::consts::PI / omega);
    }
    // Long enough for the slower-decaying terms to fall below 1e-12 of the
    // dominant ones even when Sylvester's coefficients are large.
    if let (Some(a), true) = (terms, gap.is_finite()) {
        let big: f64 = a.iter().map(|m| m.norm()).sum();
        let small = a
            .iter()
            .zip(poles)
            .filter(|(_, q)| (q.re - dominant).abs() <= tol)
            .map(|(m, _)| m.norm())
            .fold(f64::INFINITY, f64::min);
        span = span.max((big / (1e-12 * small)).ln().max(0.0) / gap);
    }
    span.max(10.0 / k2.max(1e-12)).min(1e6 / k2.max(1e-12))
}

/// Points of a grid: (t, its index on the linear grid, or GEO + its index
/// on the geometric one).
type Points = Vec<(f64, usize)>;

/// g at points of the search grid: (index, g).
type Sampled = Vec<(usize, f64)>;

/// The search for K1 of one P: its poles, K2, the dominant real part, the
/// tolerance that tells poles apart, the dominant oscillation's frequency,
/// the span, the first geometric point, and g's closed form (when used).
struct Search<'a> {
    p: &'a Matrix3<f64>,
    poles: &'a [Pole; 3],
    k2: f64,
    dominant: f64,
    tol: f64,
    omega: f64,
    span: f64,
    t0: f64,
    closed: Option<SpectralExp>,
}

impl Search<'_> {
    /// g(t), in closed form or by nalgebra's exp.
    fn g(&self, t: f64) -> f64 {
        match &self.closed {
            Some(c) => c.norm(t),
            None => k1_profile(self.p, self.k2, t),
        }
    }

    /// The search grid, linear ∪ geometric, sorted; each point with its
    /// index on the linear grid, or GEO + its index on the geometric one.
    /// Also the geometric points alone.
    fn grid(&self) -> (Points, Points) {
        let (span, t0) = (self.span, self.t0);
        let (n_lin, n_geo) = (SEARCH_LINEAR, SEARCH_GEOMETRIC);
        let linear = (0..=n_lin).map(|i| (span * i as f64 / n_lin as f64, i));
        let geometric: Vec<(f64, usize)> = if t0 < span {
            let ratio = (span / t0).ln();
            geometric_times(t0, ratio, n_geo, 0.0)
                .into_iter()
                .enumerate()
                .map(|(j, t)| (t, GEO + j))
                .collect()
        } else {
            Vec::new()
        };
        // Both runs are ascending: merged (a linear point first on a tie), as
        // a stable sort of their concatenation would order them.
        let mut points: Vec<(f64, usize)> = Vec::with_capacity(n_lin + 1 + geometric.len());
        let mut geo = geometric.iter().copied().peekable();
        for l in linear {
            while let Some(g) = geo.next_if(|g| g.0.total_cmp(&l.0).is_lt()) {
                points.push(g);
            }
            points.push(l);
        }
        points.extend(geo);
        if !points.is_sorted_by(|a, b| a.0.total_cmp(&b.0).is_le()) {
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        points.dedup_by(|a, b| a.0.to_bits() == b.0.to_bits());
        (points, geometric)
    }

    /// The largest g of the search grid with its index (the last of equal
    /// ones, as `max_by` picks), and g at every point (nalgebra's exp) or
    /// at the points compared with nalgebra's exp only (closed form), for
    /// the discrepancy.
    fn grid_max(
        &self,
        points: &[(f64, usize)],
        geometric: &[(f64, usize)],
    ) -> (Option<(usize, f64)>, Sampled) {
        let grid_len = points.len();
        // The points where nalgebra's exp is compared with the closed form.
        let stride = grid_len.div_ceil(DISCREPANCY_POINTS).max(1);
        let compared = |i: usize| i % stride == 0 || i + 1 == grid_len;
        let mut sampled: Vec<(usize, f64)> = Vec::new();
        let best = match &self.closed {
            None => {
                sampled = points.iter().map(|q| self.g(q.0)).enumerate().collect();
                sampled.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1))
            }
            Some(c) => {
                // Only the largest value matters (and the compared ones): a
                // point screened out (below the largest so far, or within
                // SLACK of it) counts as −∞. The last point (t = span)
                // first: a profile that rises to its limit has its largest
                // values there.
                let lin = c.uniform(self.span / SEARCH_LINEAR as f64, 0.0, SEARCH_LINEAR + 1);
                // The geometric points' coefficients, four at a time.
                let geo_t: Vec<f64> = geometric.iter().map(|q| q.0).collect();
                let geo_c = c.coefficients_many(&geo_t);
                let m_at = |&(t, i): &(f64, usize)| match (&lin, i) {
                    (_, i) if i >= GEO => c.combine(geo_c[i - GEO]),
                    (Some(u), i) => u.exp(i),
                    (None, _) => c.exp(t),
                };
                let mut floor = points.last().map_or(0.0, |q| norm2_fast(&m_at(q)));
                sampled.reserve(DISCREPANCY_POINTS + 1);
                points
                    .iter()
                    .enumerate()
                    .map(|(i, q)| {
                        let m = m_at(q);
                        let v = if compared(i) {
                            let v = norm2_fast(&m);
                            sampled.push((i, v));
                            v
                        } else {
                            match screen(&m, floor) {
                                Screen::Exact(v) => v,
                                Screen::Below | Screen::Near(_) => f64::NEG_INFINITY,
                            }
                        };
                        floor = floor.max(v);
                        (i, v)
                    })
                    .max_by(|a, b| a.1.total_cmp(&b.1))
            }
        };
        (best, sampled)
    }

    /// The limit of g as t → ∞ from Sylvester's terms `a` (the dominant
    /// ones' largest norm over a period), and the bound of g beyond the
    /// span (the limit and the faster terms at the span).
    fn limit_and_tail(&self, a: &[CMat; 3]) -> (f64, f64) {
        let (poles, dominant, tol, omega) = (self.poles, self.dominant, self.tol, self.omega);
        let is_dom: [bool; 3] = std::array::from_fn(|i| (poles[i].re - dominant).abs() <= tol);
        let d_at = |t: f64| {
            let mut m = CMat::zeros();
            for i in 0..3 {
                if is_dom[i] {
                    m += a[i] * Complex::new(0.0, poles[i].im * t).exp();
                }
            }
            let m = m.map(|c| c.re);
            if self.closed.is_some() {
                norm2_fast(&m)
            } else {
                norm2(&m)
            }
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
            .map(|i| cnorm2(&a[i]) * ((poles[i].re + self.k2) * self.span).exp())
            .sum();
        (lim, lim + rest)
    }

    /// The arithmetic's own accuracy: nalgebra's exp against the closed
    /// form on the search grid. The check cannot be sharper than their
    /// disagreement (≈ 1e-13 for well-separated poles, ≈ 1e-8 for poles
    /// 0.5 s⁻¹ apart, where the scaling and squaring of a large,
    /// non-normal (P + K2 I)t loses digits).
    fn discrepancy(&self, a: &[CMat; 3], sampled: &[(usize, f64)], points: &[(f64, usize)]) -> f64 {
        let t_at = |i: usize| points[i].0;
        if self.closed.is_some() {
            // g came from the closed form: nalgebra's exp, the reference,
            // on the strided points of the search grid (the disagreement is
            // smooth in t; the whole grid would cost what the closed form
            // saves).
            return sampled
                .iter()
                .map(|&(i, v)| {
                    let e = k1_profile(self.p, self.k2, t_at(i));
                    (v - e).abs() / v
                })
                .fold(0.0, f64::max);
        }
        sampled
            .iter()
            .map(|&(i, v)| {
                let t = t_at(i);
                let mut m = CMat::zeros();
                for (ai, q) in a.iter().zip(self.poles) {
                    m += ai * (Complex::new(q.re + self.k2, q.im) * t).exp();
                }
                let exact = norm2(&m.map(|c| c.re));
                (v - exact).abs() / exact
            })
            .fold(0.0, f64::max)
    }

    /// The check grid's linear time i: offset to the midpoints, over twice
    /// the span.
    fn check_t(&self, i: usize) -> f64 {
        2.0 * self.span * (i as f64 + 0.5) / CHECK_LINEAR as f64
    }

    /// The check grid's geometric part's log-ratio (None when it is empty).
    fn check_geometric(&self) -> Option<f64> {
        (self.t0 < 2.0 * self.span).then(|| (2.0 * self.span / self.t0).ln())
    }

    /// The largest g/K1 on the check grid, g by nalgebra's exp.
    fn check_exp(&self, k1v: f64) -> f64 {
        let mut worst: f64 = 0.0;
        for i in 0..CHECK_LINEAR {
            worst = worst.max(self.g(self.check_t(i)) / k1v);
        }
        if let Some(ratio) = self.check_geometric() {
            for t in geometric_times(self.t0, ratio, CHECK_GEOMETRIC, 0.5) {
                worst = worst.max(self.g(t) / k1v);
            }
        }
        worst
    }

    /// The largest g/K1 on the check grid in closed form: first the points
    /// likeliest to hold it (the last one, and those around the search's
    /// maximum `t_star`), then every point not screened out. A point within
    /// the slack counts with its bound: the result is the largest g/K1, or
    /// above it by at most SLACK, never below.
    fn check_closed(&self, c: &SpectralExp, k1v: f64, t_star: f64) -> f64 {
        let (span, m_lin) = (self.span, CHECK_LINEAR);
        let lin = c.uniform(2.0 * span / m_lin as f64, 0.5, m_lin);
        let m_at = |i: usize| match &lin {
            Some(u) => u.exp(i),
            None => c.exp(self.check_t(i)),
        };
        let mut best: f64 = norm2_fast(&m_at(m_lin - 1));
        if t_star.is_finite() && t_star < 2.0 * span {
            let j = (t_star / (2.0 * span) * m_lin as f64 - 0.5)
                .floor()
                .max(0.0) as usize;
            for i in [j, j + 1] {
                if i < m_lin {
                    best = best.max(norm2_fast(&m_at(i)));
                }
            }
        }
        let mut bound: f64 = 0.0;
        // A point screened: its bound or its norm taken.
        macro_rules! take {
            ($screen:expr) => {
                match $screen {
                    Screen::Below => {}
                    Screen::Near(b) => bound = bound.max(b),
                    Screen::Exact(v) => best = best.max(v),
                }
            };
        }
        match &lin {
            Some(u) => {
                // Four points at a time, screened in order.
                let mut i = 0;
                while i + 4 <= m_lin {
                    for (l, f2) in u.frobenius2_4(i).into_iter().enumerate() {
                        take!(screen_f2(f2, || u.exp(i + l), best));
                    }
                    i += 4;
                }
                for i in i..m_lin {
                    take!(screen(&u.exp(i), best));
                }
            }
            None => {
                for i in 0..m_lin {
                    take!(screen(&m_at(i), best));
                }
            }
        }
        if let Some(ratio) = self.check_geometric() {
            let t = geometric_times(self.t0, ratio, CHECK_GEOMETRIC, 0.5);
            let mut chunks = t.chunks_exact(4);
            for q in &mut chunks {
                for m in c.exp4([q[0], q[1], q[2], q[3]]) {
                    take!(screen(&m, best));
                }
            }
            for &t in chunks.remainder() {
                take!(screen(&c.exp(t), best));
            }
        }
        best.max(bound) / k1v
    }
}

/// The tag of a geometric point's index on the search grid.
const GEO: usize = 1 << (usize::BITS - 1);

/// The geometric grid t0·e^(ratio·(i + offset)/n), i < n, its exponentials
/// four at a time ([`exp4`]: the same bits as one by one).
fn geometric_times(t0: f64, ratio: f64, n: usize, offset: f64) -> Vec<f64> {
    let arg = |i: usize| ratio * (i as f64 + offset) / n as f64;
    let mut out = Vec::with_capacity(n);
    let mut i = 0;
    while i + 4 <= n {
        out.extend(exp4(std::array::from_fn(|k| arg(i + k))).map(|e| t0 * e));
        i += 4;
    }
    out.extend((i..n).map(|i| t0 * arg(i).exp()));
    out
}

/// A grid point's g against `floor` (the largest g so far).
enum Screen {
    /// Below it: an upper bound of g is.
    Below,
    /// Within [`SLACK`] of it (above or below), by an upper bound of g
    /// (returned): the point ties with the largest to within the slack, its
    /// norm is not needed.
    Near(f64),
    /// Possibly above it by more than the slack: g itself.
    Exact(f64),
}

/// Screens a point by two upper bounds of ‖m‖₂ before computing it, both compared in squares (no root, no division):
/// the Frobenius norm, then q + 2p of mᵀm ([`super::linalg::gram_q_p2`]).
/// They are computed with an error of a few ε, the norm within 1e-13
/// ([`norm2_fast`]); the margin 1e-12 keeps "below" true of the computed
/// norm too.
fn screen(m: &Matrix3<f64>, floor: f64) -> Screen {
    screen_f2(m.iter().map(|v| v * v).sum(), || *m, floor)
}

/// [`screen`] given the squared Frobenius norm `f2` of the matrix (as
/// `screen` sums it), the matrix made only if it is needed.
#[inline]
fn screen_f2(f2: f64, m: impl FnOnce() -> Matrix3<f64>, floor: f64) -> Screen {
    const MARGIN: f64 = 1.0 + 1e-12;
    // Thresholds on ‖m‖₂².
    let below = (floor / MARGIN) * (floor / MARGIN);
    let near = {
        let n = floor * (1.0 + SLACK) / MARGIN;
        n * n
    };
    if f2 < below {
        return Screen::Below;
    }
    if f2 <= near {
        return Screen::Near(f2.sqrt() * MARGIN);
    }
    let m = &m();
    let Some((q, p2)) = super::linalg::gram_q_p2(m) else {
        return Screen::Exact(norm2_fast(m));
    };
    // q + 2p ≤ x without the root of p².
    let at_most = |x: f64| q <= x && p2 <= 0.25 * (x - q) * (x - q);
    if at_most(below) {
        Screen::Below
    } else if at_most(near) {
        Screen::Near((q + 2.0 * p2.sqrt()).sqrt() * MARGIN)
    } else {
        Screen::Exact(norm2_fast(m))
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

    /// The geometric grids four exponentials at a time: the bits of the
    /// formula point by point, for counts with and without a remainder.
    #[test]
    fn geometric_times_are_the_formula_to_the_bit() {
        for (t0, span, n, offset) in [
            (1e-3f64 / 20.0, 4.0f64, 8usize, 0.0f64),
            (1e-3 / 40.0, 4.0, 1000, 0.0),
            (1e-3 / 40.0, 8.0, 3000, 0.5),
            (2.5e-5, 3.07, 7, 0.0),
            (1e-6, 1e4, 1, 0.5),
        ] {
            let ratio = (span / t0).ln();
            let t = geometric_times(t0, ratio, n, offset);
            assert_eq!(t.len(), n);
            for (i, t) in t.iter().enumerate() {
                let want = t0 * (ratio * (i as f64 + offset) / n as f64).exp();
                assert_eq!(t.to_bits(), want.to_bits(), "n = {n}, i = {i}");
            }
        }
    }

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
