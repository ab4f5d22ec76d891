//! What the theory says about a scenario before it runs (`ehservo analyze`).
//!
//! [`analyze`] computes, for a validated [`Scenario`]:
//!
//! - **Plant**: the nominal coefficients ā_i of (9), b̄ at Pl = 0
//!   ([`NominalModel::b_at_rest`]), the two coefficients of
//!   d(t) = 4βe·Kce/(Vt·Jt)·Tl + (1/Jt)·Ṫl, and the open-loop poles (roots of
//!   s³ + ā3 s² + ā2 s + ā1) with damping ratios and natural frequencies.
//! - **Surface and Theorem 2**: p, the poles of the sliding dynamics, the
//!   matrix P of (16), K2 = −max Re λ(P) and K1 = the least constant with
//!   ‖exp(Pt)‖₂ ≤ K1·e^(−K2·t) for all t ≥ 0 (18), i.e.
//!   K1 = sup_t g(t), g(t) = ‖exp((P + K2·I)t)‖₂ = e^(K2 t)‖exp(Pt)‖₂
//!   (the shifted form cannot overflow). See [`k1`] for the grid, the
//!   refinement, the asymptote and the proof-of-bound check. Then the bound
//!   0 < α < K2/K1 of Theorem 2 and a plain verdict on the scenario's α.
//! - **Weights (Remark 6)**: the radius
//!   r(‖Φ‖) = Wmax/2 + sqrt(Wmax²/4 + (ε0‖Φ‖ + ε1)/η) of the invariant set
//!   of W̃ = W̄ − W at ‖Φ‖ = 1 (its least value, Φ's bias entry), along the
//!   scenario's reference and at the largest ‖Φ‖ over the compact set Ω
//!   printed in Section IV; unbounded for η = 0. Also the ball
//!   ‖W‖ ≤ sup‖Φ‖/η that the law (26) itself keeps invariant (for
//!   ‖W‖ > ‖Φ‖/η, d‖W‖²/dt = 2|σΔ|(±WᵀΦ − η‖W‖²)/h < 0).
//! - **The σ-loop, linearised** (derivation below) and whether the
//!   simulation scheme of the scenario (continuous RK4, or the sampled
//!   loop) is stable on it, with a warning when it is not.
//! - **After a run** ([`diagnostics`]): the share of samples where
//!   condition 4) of Theorem 3 holds, each half apart, and the share spent
//!   in the dead zone (σΔ = 0).
//!
//! # The σ-loop of the NNBVSC, linearised
//!
//! With σ = ë + p1ė + p2e + p3∫e, the true plant ẋ3 = −a·x − d(x) + b·u
//! (a = ā + Δa, b = r·b̄) and the law b̄u = N + WᵀΦ + [γ1σΔ + γ2σΔ/(|σΔ| + μ)]/(1 − β̂)
//! (β̂ = bound_b, N = θ⃛d + ā·x + p1ë + p2ė + p3e, SPEC §5):
//!
//! ```text
//! σ̇ = θ⃛d − ẋ3 + p1ë + p2ė + p3e
//!   = (1 − r)θ⃛d + (a − r·ā)·x + d(x) − (r − 1)(p1ë + p2ė + p3e)
//!     − r·WᵀΦ − r·[γ1σΔ + γ2σΔ/(|σΔ| + μ)]/(1 − β̂)
//! ```
//!
//! Linearised about rest (θd = 0, so x = −(e, ė, ë)): W = 0 (its own loop,
//! δ(WᵀΦ)˙ = ‖Φ(0)‖²σΔ/h ≈ 3σΔ, is an integral action that moves the fast
//! eigenvalue by about r·3/400 ≈ 0.01 s⁻¹), σΔ = σ (the dead zone only
//! lowers the gain), the γ2 term left out (it is bounded by
//! r·γ2/(1 − β̂) ≈ 8 rad/s³: a smoothed relay that makes a small limit
//! cycle, not a growing mode), d linearised at θ = 0 (d' = (4βeKce/(VtJt)·Ak,
//! Ak/Jt + 4βeKce/(VtJt)·Bv, Bv/Jt) for Tl = A·sin kθ + friction, of which
//! only the viscous slope Bv is kept: the tanh regularisation's slope lives
//! in a band of a few mrad/s), and b̄'s dependence on x dropped (it
//! multiplies u = 0 at rest). With c = a + d' − r·ā and k = r·γ1/(1 − β̂),
//! the σ-loop gain b/(b̄ − β)·γ1:
//!
//! ```text
//! ë' = −c·(e, ė, ë) − r·(p3e + p2ė + p1ë) − k·σ
//! ```
//!
//! In y = ∫e this is
//!
//! ```text
//! y⁗ + (c3 + r p1 + k)y‴ + (c2 + r p2 + k p1)y″ + (c1 + r p3 + k p2)y′ + k p3 y = 0.
//! ```
//!
//! Substituting ë = σ − p1ė − p2e − p3∫e into σ̇ gives the one-dimensional
//! estimate of the fast root,
//!
//! ```text
//! λ_fast ≈ −[k + c3 + (r − 1)p1] = −[r·γ1/(1 − β̂) + Δa3 + (Δb/b̄)(p1 − ā3)]
//! ```
//!
//! (SPEC §7's three terms). Fig. 2: r = 1.25, Δa3 = ā3 = 169.980,
//! (Δb/b̄)(p1 − ā3) = 0.25·(90 − 169.980) = −19.995, so λ ≈ −399.99 for
//! γ1 = 100 and −649.99 for γ1 = 200. The 4×4 loop gives −406.3 and −655.1:
//! its trace is −(c3 + r p1 + k) and the three slow roots move from the
//! surface poles' sum −90 to ≈ −84 (γ1 = 100) as the σ-loop is not
//! infinitely fast. SPEC's "near −410 and −660" are these, rounded.
//!
//! **Variation.** The analysis uses the bias part of the true variation
//! (r = 1 + b_reference·b_bias, Δa_i = |ā_i|·a_bias) and, for the worst
//! case, the corners bias ± |random| of both (b_bias + |b_random| gives the
//! largest gain).
//!
//! **vsc-sat.** Inside the boundary layer |σ| < μ the switching term is
//! linear, b·u_sw = r·kb·σ/μ with kb = b̄·k = [Σα_i|x_i| + |d| + β̂|N|]/(1 − β̂),
//! so the same loop holds with k = r·kb/μ. kb depends on the state; it is
//! evaluated along the reference (perfect tracking) and the check is made
//! with its largest value (frozen gain). An unstable layer makes u chatter
//! across it as with sgn(σ). Outside the layer the law is Theorem 1's sgn
//! law, so a stable layer is necessary for a smooth loop, not sufficient.
//! Measured on the Fig. 2 case (third-order plant, 10 s): continuous at
//! h = 1 ms, the check says unstable for μ = 1, 5, 10 and stable for 20, and
//! the chattering index `c[u]` is 0.13, 0.025, 0.024 against 0.006; sampled at
//! 0.01 s it says stable from μ ≈ 20, but the run diverges up to μ = 30
//! (at t ≈ 0.09 s, as the sgn law does) and is bounded at μ = 50. The sgn
//! VSC is discontinuous: no linear check applies.
//!
//! **The integrator.** Continuous mode: every eigenvalue must satisfy
//! |R(hλ)| < 1 with RK4's R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 (on the real
//! axis: h·λ > [`RK4_REAL_LIMIT`] ≈ −2.785). Sampled mode: the controller
//! is a discrete map, so the RK4 region does not apply; the check is the
//! exact linearised one-sample map — the true plant under the held u
//! advanced by `substeps` RK4 steps, ∫e by forward Euler — whose spectral
//! radius must be < 1.

use crate::scenario::{ControllerKind, Scenario};
use crate::sim::{Mode, Sample};
use ehservo_core::rbf::{Rbf, N_PHI};
use ehservo_core::reference::Reference;
use ehservo_core::servo::NominalModel;
use nalgebra::{Complex, Matrix3, Matrix4, Vector3};
use serde::Serialize;

mod report;

/// RK4's stability limit on the negative real axis: R(z) = 1 at z ≈ −2.7853.
pub const RK4_REAL_LIMIT: f64 = -2.785_293_563_405_282;

/// Relative tolerance of the proof-of-bound check of K1: no sample of the
/// check grid (nor the tail bound) may exceed K1·(1 + K1_TOLERANCE).
pub const K1_TOLERANCE: f64 = 1e-9;

/// The compact set Ω of Section IV: |x1| ≤ 2 rad, |x2| ≤ 4 rad/s,
/// |x3| ≤ 16 rad/s².
pub const OMEGA_X: [f64; 3] = [2.0, 4.0, 16.0];

/// The compact set Ω of Section IV: |z| ≤ 30, read as the Euclidean norm of
/// z = (θd, θ̇d, θ̈d, θ⃛d) (the paper writes |x1| for scalars, |z| for the
/// vector).
pub const OMEGA_Z: f64 = 30.0;

/// A pole with its damping ratio and natural frequency.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pole {
    /// Real part (1/s).
    pub re: f64,
    /// Imaginary part (rad/s).
    pub im: f64,
    /// Natural frequency |λ| (rad/s).
    pub wn: f64,
    /// Damping ratio −Re λ/|λ| (1 for a real stable pole).
    pub zeta: f64,
}

impl From<Complex<f64>> for Pole {
    fn from(c: Complex<f64>) -> Self {
        let wn = c.norm();
        Self {
            re: c.re,
            im: c.im,
            wn,
            zeta: if wn > 0.0 { -c.re / wn } else { 1.0 },
        }
    }
}

fn sort_poles(poles: &mut [Pole]) {
    poles.sort_by(|a, b| b.re.total_cmp(&a.re).then(b.im.total_cmp(&a.im)));
}

/// Roots of `s³ + c2·s² + c1·s + c0`, as the eigenvalues of its companion
/// matrix, sorted by real part then imaginary part (descending).
pub fn cubic_roots(c2: f64, c1: f64, c0: f64) -> [Pole; 3] {
    let m = Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -c0, -c1, -c2);
    let ev = m.complex_eigenvalues();
    let mut poles = [Pole::from(ev[0]), Pole::from(ev[1]), Pole::from(ev[2])];
    sort_poles(&mut poles);
    poles
}

/// Open-loop poles of the nominal third-order model (8):
/// roots of `s³ + ā3·s² + ā2·s + ā1`.
pub fn open_loop_poles(a: [f64; 3]) -> [Pole; 3] {
    cubic_roots(a[2], a[1], a[0])
}

/// The matrix P of (16) for p = (p1, p2, p3).
pub fn p_matrix(p: [f64; 3]) -> Matrix3<f64> {
    Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -p[2], -p[1], -p[0])
}

fn norm2(m: &Matrix3<f64>) -> f64 {
    m.singular_values().max()
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
    let scale = poles.iter().map(|q| q.wn).fold(1.0, f64::max);
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
    norm2(&((p + Matrix3::identity() * k2) * t).exp())
}

/// Golden-section search for the maximum of `f` on [a, b].
fn golden_max(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> (f64, f64) {
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
    let scale = poles.iter().map(|q| q.wn).fold(1.0, f64::max);
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

/// The switching surface and Theorem 2.
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceAnalysis {
    /// p1, p2, p3.
    pub p: [f64; 3],
    /// Poles of the sliding dynamics (eigenvalues of P).
    pub poles: [Pole; 3],
    /// P of (16), row-major.
    pub p_matrix: [[f64; 3]; 3],
    /// K2 = −max Re λ(P).
    pub k2: f64,
    /// K1 of (18).
    pub k1: K1,
    /// K2/K1 (0 if K1 is infinite).
    pub alpha_bound: f64,
    /// The scenario's α (NNBVSC; None for the VSC).
    pub alpha: Option<f64>,
    /// Whether 0 < α < K2/K1.
    pub holds: Option<bool>,
    /// log10(α/(K2/K1)) when violated.
    pub decades_over: Option<f64>,
    /// Plain-language verdict ("holds: …" or "violated: …").
    pub verdict: String,
}

/// Remark 6's invariant set of the weight error (NNBVSC).
#[derive(Debug, Clone, Serialize)]
pub struct WeightAnalysis {
    /// η.
    pub eta: f64,
    /// Wmax.
    pub w_max: f64,
    /// ε0.
    pub eps0: f64,
    /// ε1.
    pub eps1: f64,
    /// Largest ‖Φ‖ along the reference (perfect tracking, x = (θd, θ̇d, θ̈d)),
    /// over one period.
    pub phi_norm_reference: f64,
    /// Largest ‖z‖ along the reference.
    pub z_norm_reference: f64,
    /// Largest ‖Φ‖ over Ω of Section IV ([`OMEGA_X`], [`OMEGA_Z`]):
    /// sqrt(1 + sup_x Σφ_j² + 30²).
    pub phi_norm_omega: f64,
    /// The larger of the two.
    pub phi_norm_max: f64,
    /// Which set gives `phi_norm_max`.
    pub phi_norm_max_from: String,
    /// Radius on ‖W̃‖ at ‖Φ‖ = 1, its least value (None: unbounded, η = 0).
    pub radius_min: Option<f64>,
    /// Radius at the reference's largest ‖Φ‖.
    pub radius_reference: Option<f64>,
    /// Radius at `phi_norm_max`.
    pub radius_max: Option<f64>,
    /// The ball ‖W‖ ≤ phi_norm_max/η that the law (26) keeps invariant.
    pub law_ball: Option<f64>,
    /// Plain-language note.
    pub note: String,
}

/// The linearised σ-loop and the simulation scheme (module doc).
#[derive(Debug, Clone, Serialize)]
pub struct LoopAnalysis {
    /// Controller kind (`nnvsc`, `vsc`, `vsc-sat`).
    pub controller: String,
    /// Simulation mode (`continuous`, `sampled`).
    pub mode: String,
    /// Step h (s), the sample period in sampled mode.
    pub step: f64,
    /// RK4 sub-steps per sample (sampled mode).
    pub substeps: u32,
    /// True b/b̄ of the bias part: 1 + b_reference·b_bias.
    pub b_ratio: f64,
    /// The largest b/b̄: 1 + b_reference·(b_bias + |b_random|).
    pub b_ratio_worst: f64,
    /// The switching slope of b̄u in σ: γ1/(1 − bound_b) (NNBVSC) or the
    /// largest kb/μ along the reference (vsc-sat); None for the sgn VSC.
    pub switching_slope: Option<f64>,
    /// vsc-sat: the least and largest kb = b̄·k of (14) along the reference.
    pub vsc_sat_kb: Option<[f64; 2]>,
    /// The σ-loop gain b/(b̄ − β)·γ1 = b_ratio·switching_slope.
    pub sigma_gain: Option<f64>,
    /// The same with b_ratio_worst.
    pub sigma_gain_worst: Option<f64>,
    /// Load slopes ∂d/∂(θ, θ̇, θ̈) at θ = 0.
    pub load_slopes: [f64; 3],
    /// Eigenvalues of the linearised error dynamics (bias variation).
    pub eigenvalues: Vec<Pole>,
    /// The fast (σ) eigenvalue (bias variation).
    pub fast: Option<f64>,
    /// Its one-dimensional estimate −[k + c3 + (r − 1)p1].
    pub fast_estimate: Option<f64>,
    /// The most negative fast eigenvalue over the corners bias ± |random|.
    pub fast_worst: Option<f64>,
    /// h·λ with λ = `fast_worst` (against RK4's −2.785 in continuous mode).
    pub h_lambda: Option<f64>,
    /// Continuous mode: max |R(hλ)| over the eigenvalues; sampled mode:
    /// spectral radius of the one-sample map; the worst over the corners.
    pub growth: Option<f64>,
    /// Whether the simulation scheme is stable on the linearised loop.
    pub stable: Option<bool>,
    /// What was checked.
    pub check: String,
    /// Plain-language verdict.
    pub verdict: String,
    /// Set when the scheme is not stable.
    pub warning: Option<String>,
}

/// Everything [`analyze`] computes.
#[derive(Debug, Clone, Serialize)]
pub struct Analysis {
    /// ā1, ā2, ā3 (s⁻³, s⁻², s⁻¹).
    pub a_nominal: [f64; 3],
    /// b̄ at Pl = 0 (s⁻³V⁻¹).
    pub b_at_rest: f64,
    /// `d = d_coefficients[0]·Tl + d_coefficients[1]·Ṫl`: 4βe·Kce/(Vt·Jt) and 1/Jt.
    pub d_coefficients: [f64; 2],
    /// Open-loop poles.
    pub open_loop_poles: [Pole; 3],
    /// Surface and Theorem 2.
    pub surface: SurfaceAnalysis,
    /// Remark 6 (NNBVSC only).
    pub weights: Option<WeightAnalysis>,
    /// The linearised loop and the integrator.
    pub closed_loop: LoopAnalysis,
}

/// Σ_l exp(−2(u − c_l)²/δ²): one axis's factor of Σ_j φ_j² (the kernels
/// are products over the axes, so their squares are too).
fn axis_sq_sum(levels: &[f64], width: f64, u: f64) -> f64 {
    levels
        .iter()
        .map(|c| (-2.0 * (u - c) * (u - c) / (width * width)).exp())
        .sum()
}

/// The largest Σ_j φ_j(x)² over the box |x_a| ≤ bound_a (physical units),
/// and where: the product over the axes of each axis's largest factor.
pub fn kernel_sq_max(rbf: &Rbf, bound: [f64; 3]) -> (f64, [f64; 3]) {
    let levels = rbf.levels();
    let w = rbf.width();
    let scale = rbf.scale();
    let lmin = levels.iter().copied().fold(f64::INFINITY, f64::min);
    let lmax = levels.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut prod = 1.0;
    let mut arg = [0.0; 3];
    for a in 0..3 {
        let b = bound[a] / scale[a];
        let (lo, hi) = ((lmin - 4.0 * w).max(-b), (lmax + 4.0 * w).min(b));
        let f = |u: f64| axis_sq_sum(&levels, w, u);
        let (mut bu, mut bv) = if f(-b) >= f(b) {
            (-b, f(-b))
        } else {
            (b, f(b))
        };
        if hi > lo {
            let n = 4000;
            let h = (hi - lo) / n as f64;
            for i in 0..=n {
                let u = lo + h * i as f64;
                if f(u) > bv {
                    (bu, bv) = (u, f(u));
                }
            }
            let (u, v) = golden_max(f, (bu - h).max(-b), (bu + h).min(b));
            if v > bv {
                (bu, bv) = (u, v);
            }
        }
        prod *= bv;
        arg[a] = bu * scale[a];
    }
    (prod, arg)
}

/// Largest ‖Φ‖ and ‖z‖ along the reference over one period, with the state
/// on the reference (perfect tracking).
pub fn phi_norm_reference(s: &Scenario) -> (f64, f64) {
    let Ok(rbf) = s.rbf() else {
        return (f64::NAN, f64::NAN);
    };
    let r = s.reference();
    let period = 1.0 / s.reference.frequency_hz;
    let mut out = [0.0; N_PHI];
    let n = 2000;
    (0..n).fold((1.0, 0.0), |(pm, zm), i| {
        let z = r.z(period * i as f64 / n as f64);
        let nrm = rbf.phi(&[z[0], z[1], z[2]], &z, &mut out);
        let zn = z.iter().map(|v| v * v).sum::<f64>().sqrt();
        (f64::max(pm, nrm), f64::max(zm, zn))
    })
}

/// Largest ‖Φ‖ over Ω of Section IV: sqrt(1 + sup_Ω Σφ_j² + [`OMEGA_Z`]²).
pub fn phi_norm_omega(s: &Scenario) -> f64 {
    let Ok(rbf) = s.rbf() else { return f64::NAN };
    (1.0 + kernel_sq_max(&rbf, OMEGA_X).0 + OMEGA_Z * OMEGA_Z).sqrt()
}

/// Remark 6: r(‖Φ‖) = Wmax/2 + sqrt(Wmax²/4 + (ε0‖Φ‖ + ε1)/η); None
/// (unbounded) for η = 0.
pub fn invariant_radius(eta: f64, w_max: f64, eps0: f64, eps1: f64, phi_norm: f64) -> Option<f64> {
    (eta > 0.0).then(|| w_max / 2.0 + (w_max * w_max / 4.0 + (eps0 * phi_norm + eps1) / eta).sqrt())
}

fn fmt_sig(x: f64, n: usize) -> String {
    report::sig(x, n)
}

fn theorem2(s: &Scenario, pm: &Matrix3<f64>, sp: [Pole; 3], surface: [f64; 3]) -> SurfaceAnalysis {
    // A repeated root comes out of the eigenvalue solver split by
    // ~sqrt(ε)·|λ|; the mean of the cluster is accurate to ~ε.
    let scale = sp.iter().map(|q| q.wn).fold(1.0, f64::max);
    let cluster: Vec<f64> = sp
        .iter()
        .filter(|q| {
            (q.re - sp[0].re).abs() <= 1e-4 * scale
                && (q.im.abs() - sp[0].im.abs()).abs() <= 1e-4 * scale
        })
        .map(|q| q.re)
        .collect();
    let k2 = -cluster.iter().sum::<f64>() / cluster.len() as f64;
    let k1v = k1(pm, &sp, k2);
    let bound = k1v.value.map(|v| k2 / v).unwrap_or(0.0);
    let alpha = (s.controller.kind == ControllerKind::Nnvsc).then_some(s.controller.alpha);
    let holds = alpha.map(|al| al > 0.0 && al < bound);
    let decades_over = match (alpha, holds) {
        (Some(al), Some(false)) if bound > 0.0 && al > 0.0 => Some((al / bound).log10()),
        _ => None,
    };
    let verdict = match (alpha, holds) {
        (Some(al), Some(true)) => format!(
            "holds: α = {} < K2/K1 = {}; Theorem 2 then gives e(t) → 0 at the rate K2 − α·K1 = {} s⁻¹",
            fmt_sig(al, 3),
            fmt_sig(bound, 3),
            fmt_sig(k2 - al * k1v.value.unwrap_or(f64::INFINITY), 3)
        ),
        (Some(al), Some(false)) => match (k1v.value, decades_over) {
            (None, _) => format!(
                "violated: K1 is infinite (repeated dominant pole of P), so no α > 0 satisfies 0 < α < K2/K1; α = {} acts as a tuning number of μ(t), not a certified rate",
                fmt_sig(al, 3)
            ),
            (Some(_), Some(d)) => format!(
                "violated: α = {} exceeds K2/K1 = {} by {:.1} decades; α acts as a tuning number of μ(t), not a certified rate",
                fmt_sig(al, 3),
                fmt_sig(bound, 2),
                d
            ),
            (Some(_), None) => format!(
                "violated: α = {} is not in (0, K2/K1 = {})",
                fmt_sig(al, 3),
                fmt_sig(bound, 3)
            ),
        },
        _ => format!(
            "not applicable: the traditional VSC has no α (Theorem 2 would admit 0 < α < {})",
            fmt_sig(bound, 3)
        ),
    };
    SurfaceAnalysis {
        p: surface,
        poles: sp,
        p_matrix: [
            [pm[(0, 0)], pm[(0, 1)], pm[(0, 2)]],
            [pm[(1, 0)], pm[(1, 1)], pm[(1, 2)]],
            [pm[(2, 0)], pm[(2, 1)], pm[(2, 2)]],
        ],
        k2,
        k1: k1v,
        alpha_bound: bound,
        alpha,
        holds,
        decades_over,
        verdict,
    }
}

fn weight_analysis(s: &Scenario) -> WeightAnalysis {
    let c = &s.controller;
    let (pref, zref) = phi_norm_reference(s);
    let pom = phi_norm_omega(s);
    let (pmax, from) = if pref > pom {
        (pref, "the reference (it leaves Ω of Section IV)")
    } else {
        (
            pom,
            "Ω of Section IV (|x1| ≤ 2, |x2| ≤ 4, |x3| ≤ 16, ‖z‖ ≤ 30)",
        )
    };
    let radius = |phi: f64| invariant_radius(c.eta, c.w_max, c.eps0, c.eps1, phi);
    let note = if c.eta > 0.0 {
        let rmax = radius(pmax).unwrap_or(f64::NAN);
        format!(
            "‖W̄ − W‖ is kept below {} at ‖Φ‖ = 1, {} along the reference (‖Φ‖ ≤ {}) and {} over Ω (‖Φ‖ ≤ {}); with ‖W̄‖ ≤ Wmax = {} that bounds ‖W‖ by {}. The law (26) alone keeps ‖W‖ ≤ ‖Φ‖/η: {} along the reference, {} over Ω.",
            fmt_sig(radius(1.0).unwrap_or(f64::NAN), 5),
            fmt_sig(radius(pref).unwrap_or(f64::NAN), 5),
            fmt_sig(pref, 4),
            fmt_sig(rmax, 5),
            fmt_sig(pmax, 4),
            fmt_sig(c.w_max, 3),
            fmt_sig(c.w_max + rmax, 4),
            fmt_sig(pref / c.eta, 4),
            fmt_sig(pmax / c.eta, 4),
        )
    } else {
        "η = 0: the invariant set is unbounded (Remark 6: W_in → ∞ as η → 0); nothing in the law keeps the weights bounded.".into()
    };
    WeightAnalysis {
        eta: c.eta,
        w_max: c.w_max,
        eps0: c.eps0,
        eps1: c.eps1,
        phi_norm_reference: pref,
        z_norm_reference: zref,
        phi_norm_omega: pom,
        phi_norm_max: pmax,
        phi_norm_max_from: from.into(),
        radius_min: radius(1.0),
        radius_reference: radius(pref),
        radius_max: radius(pmax),
        law_ball: (c.eta > 0.0).then(|| pmax / c.eta),
        note,
    }
}

/// Analyses a validated scenario (see the module doc).
pub fn analyze(s: &Scenario) -> Analysis {
    let servo = s.plant.params.to_servo();
    let model = NominalModel::new(servo, s.load_model());
    let a = model.coeffs.as_array();
    let surface = s
        .surface()
        .map(|x| x.p())
        .unwrap_or([90.0, 2600.0, 24000.0]);
    let pm = p_matrix(surface);
    let sp = cubic_roots(surface[0], surface[1], surface[2]);
    Analysis {
        a_nominal: a,
        b_at_rest: model.b_at_rest(),
        d_coefficients: [servo.d_per_torque(), 1.0 / servo.jt],
        open_loop_poles: open_loop_poles(a),
        surface: theorem2(s, &pm, sp, surface),
        weights: (s.controller.kind == ControllerKind::Nnvsc).then(|| weight_analysis(s)),
        closed_loop: loop_analysis(s, &model, surface),
    }
}

/// RK4's amplification R(z) = 1 + z + z²/2 + z³/6 + z⁴/24.
pub fn rk4_amplification(z: Complex<f64>) -> Complex<f64> {
    let one = Complex::new(1.0, 0.0);
    one + z * (one + z * (one / 2.0 + z * (one / 6.0 + z / 24.0)))
}

/// A true variation: a = ā + Δa and r = b/b̄.
#[derive(Debug, Clone, Copy)]
struct Truth {
    a: [f64; 3],
    r: f64,
}

/// The error dynamics in (∫e, e, ė, ë) (module doc): rows 0–2 are the
/// chain of integrators, row 3 is ë' = −c·(e, ė, ë) − r(p3e + p2ė + p1ë) − kσ.
fn loop_matrix(abar: &[f64; 3], v: &Truth, dd: &[f64; 3], gs: f64, p: [f64; 3]) -> Matrix4<f64> {
    let mut m = Matrix4::<f64>::zeros();
    m[(0, 1)] = 1.0;
    m[(1, 2)] = 1.0;
    m[(2, 3)] = 1.0;
    let pj = [p[2], p[1], p[0]];
    for j in 0..3 {
        m[(3, j + 1)] = -(v.a[j] + dd[j] - v.r * abar[j]) - v.r * pj[j];
    }
    let k = v.r * gs;
    m[(3, 0)] -= k * p[2];
    m[(3, 1)] -= k * p[1];
    m[(3, 2)] -= k * p[0];
    m[(3, 3)] -= k;
    m
}

/// kb = b̄·k of (14) along the reference with the state on it: least and
/// largest over one period.
fn vsc_kb_range(s: &Scenario, model: &NominalModel) -> [f64; 2] {
    let abar = model.coeffs.as_array();
    let bb = s.controller.bound_b;
    let ba = s.controller.bound_a;
    let Ok(surf) = s.surface() else {
        return [f64::NAN; 2];
    };
    let r = s.reference();
    let period = 1.0 / s.reference.frequency_hz;
    let n = 2000;
    (0..n).fold([f64::INFINITY, 0.0], |[lo, hi], i| {
        let z = r.z(period * i as f64 / n as f64);
        let x = [z[0], z[1], z[2]];
        let nn = surf.equivalent_numerator(&abar, &x, &z);
        let kb = (ba
            * (abar[0].abs() * x[0].abs()
                + abar[1].abs() * x[1].abs()
                + abar[2].abs() * x[2].abs())
            + model.d(&x).abs()
            + bb * nn.abs())
            / (1.0 - bb);
        [lo.min(kb), hi.max(kb)]
    })
}

fn loop_analysis(s: &Scenario, model: &NominalModel, p: [f64; 3]) -> LoopAnalysis {
    let c = &s.controller;
    let sim = &s.simulation;
    let abar = model.coeffs.as_array();
    let u = &s.uncertainty;
    let h = sim.step;
    let r_of = |fb: f64| 1.0 + u.b_reference * fb;
    let a_of = |fa: f64| -> [f64; 3] { std::array::from_fn(|i| abar[i] + abar[i].abs() * fa) };
    let bias = Truth {
        a: a_of(u.a_bias),
        r: r_of(u.b_bias),
    };
    let mut corners = Vec::new();
    for fa in [u.a_bias - u.a_random.abs(), u.a_bias + u.a_random.abs()] {
        for fb in [u.b_bias - u.b_random.abs(), u.b_bias + u.b_random.abs()] {
            corners.push(Truth {
                a: a_of(fa),
                r: r_of(fb),
            });
        }
    }
    let r_worst = r_of(u.b_bias + u.b_random.abs());
    // Load slopes at θ = 0 (module doc): sine load and the viscous friction.
    let amp_k = s.load.amplitude * s.load.wavenumber;
    let bv = s.load.friction.map(|f| f.viscous).unwrap_or(0.0);
    let kd = model.params.d_per_torque();
    let jt = model.params.jt;
    let dd = [kd * amp_k, amp_k / jt + kd * bv, bv / jt];
    let bb = c.bound_b;
    let (slope, kb_range) = match c.kind {
        ControllerKind::Nnvsc => (Some(c.gamma1 / (1.0 - bb)), None),
        ControllerKind::VscSat => {
            let kb = vsc_kb_range(s, model);
            (Some(kb[1] / c.mu), Some(kb))
        }
        ControllerKind::Vsc => (None, None),
    };
    let mut out = LoopAnalysis {
        controller: c.kind.as_str().into(),
        mode: sim.mode.as_str().into(),
        step: h,
        substeps: sim.substeps,
        b_ratio: bias.r,
        b_ratio_worst: r_worst,
        switching_slope: slope,
        vsc_sat_kb: kb_range,
        sigma_gain: slope.map(|g| bias.r * g),
        sigma_gain_worst: slope.map(|g| r_worst * g),
        load_slopes: dd,
        eigenvalues: Vec::new(),
        fast: None,
        fast_estimate: None,
        fast_worst: None,
        h_lambda: None,
        growth: None,
        stable: None,
        check: String::new(),
        verdict: String::new(),
        warning: None,
    };
    let Some(gs) = slope else {
        out.check = "none".into();
        out.verdict = "not applicable: the traditional VSC switches with sgn(σ), so the loop is discontinuous and a linear (RK4 or sampled-map) stability check does not apply; its sampled behaviour is measured by `ehservo reproduce`'s breaking-point search".into();
        return out;
    };
    let eig = |v: &Truth| -> Vec<Complex<f64>> {
        loop_matrix(&abar, v, &dd, gs, p)
            .complex_eigenvalues()
            .iter()
            .copied()
            .collect()
    };
    let fast_of = |ev: &[Complex<f64>]| ev.iter().map(|z| z.re).fold(f64::INFINITY, f64::min);
    let ev_bias = eig(&bias);
    let mut eigs: Vec<Pole> = ev_bias.iter().map(|z| Pole::from(*z)).collect();
    sort_poles(&mut eigs);
    let fast = fast_of(&ev_bias);
    let growth_of = |v: &Truth| -> f64 {
        match sim.mode {
            Mode::Continuous => eig(v)
                .iter()
                .map(|z| rk4_amplification(z * h).norm())
                .fold(0.0, f64::max),
            Mode::Sampled => sampled_radius(s, model, v, &dd, gs, p),
        }
    };
    let mut fast_worst = fast;
    let mut growth = growth_of(&bias);
    for v in &corners {
        fast_worst = fast_worst.min(fast_of(&eig(v)));
        growth = growth.max(growth_of(v));
    }
    let stable = growth < 1.0;
    let corner_note = if u.a_random != 0.0 || u.b_random != 0.0 {
        " (worst over the corners bias ± |random| of the variation)"
    } else {
        ""
    };
    out.check = match sim.mode {
        Mode::Continuous => format!(
            "continuous RK4 at h = {} s: every eigenvalue must have |R(hλ)| < 1 (real axis: h·λ > {:.3}){corner_note}",
            fmt_sig(h, 3),
            RK4_REAL_LIMIT
        ),
        Mode::Sampled => format!(
            "sampled at h = {} s with {} RK4 sub-step(s): the linearised one-sample map (plant under the held u, ∫e by Euler) must have spectral radius < 1; RK4's real-axis limit applies to the continuous mode only{corner_note}",
            fmt_sig(h, 3),
            sim.substeps
        ),
    };
    let what = match sim.mode {
        Mode::Continuous => format!(
            "h·λ_fast = {} against {:.3}, max |R(hλ)| = {}",
            fmt_sig(h * fast_worst, 4),
            RK4_REAL_LIMIT,
            fmt_sig(growth, 4)
        ),
        Mode::Sampled => format!(
            "spectral radius of the one-sample map {} (h·λ_fast = {})",
            fmt_sig(growth, 4),
            fmt_sig(h * fast_worst, 4)
        ),
    };
    let sat = c.kind == ControllerKind::VscSat;
    out.verdict = match (stable, sat) {
        (true, false) => format!("stable: {what}"),
        (false, false) => format!("unstable: {what}"),
        (true, true) => format!(
            "stable inside the boundary layer: {what}; outside it the law is Theorem 1's sgn law, which no linear check covers: a necessary condition for a smooth loop, not a sufficient one"
        ),
        (false, true) => format!(
            "unstable inside the boundary layer: {what}; u will chatter across the layer as with sgn(σ) (bounded by ±k in continuous mode; a sampled loop can diverge as the sgn law does)"
        ),
    };
    out.warning = (!stable).then(|| match sim.mode {
        Mode::Continuous => format!(
            "continuous RK4 at h = {} s is outside its stability region on the linearised σ-loop (fast eigenvalue {:.1} s⁻¹, h·λ = {:.2} < {:.3}): the run will blow up{}; use h < {} s",
            fmt_sig(h, 3),
            fast_worst,
            h * fast_worst,
            RK4_REAL_LIMIT,
            if sat { " or chatter" } else { "" },
            fmt_sig(RK4_REAL_LIMIT / fast_worst, 2)
        ),
        Mode::Sampled => format!(
            "the sampled loop at h = {} s is unstable on its linearised one-sample map (spectral radius {}): expect chattering or divergence; use a shorter sample period{}",
            fmt_sig(h, 3),
            fmt_sig(growth, 4),
            if sat { " or a wider boundary layer μ" } else { " or a smaller γ1" }
        ),
    });
    out.fast_estimate =
        Some(-(bias.r * gs + (bias.a[2] + dd[2] - bias.r * abar[2]) + (bias.r - 1.0) * p[0]));
    out.eigenvalues = eigs;
    out.fast = Some(fast);
    out.fast_worst = Some(fast_worst);
    out.h_lambda = Some(h * fast_worst);
    out.growth = Some(growth);
    out.stable = Some(stable);
    out
}

/// Spectral radius of the linearised one-sample map of the sampled mode:
/// plant state x (3) and ∫e, with θd = 0; u held over the sample, the plant
/// advanced by `substeps` RK4 steps (the exact RK4 map of a linear system
/// with constant input), ∫e by Euler.
fn sampled_radius(
    s: &Scenario,
    model: &NominalModel,
    v: &Truth,
    dd: &[f64; 3],
    gs: f64,
    p: [f64; 3],
) -> f64 {
    let abar = model.coeffs.as_array();
    let a = v.a;
    let h = s.simulation.step;
    let m = s.simulation.substeps.max(1);
    let hs = h / m as f64;
    // ẋ = A x + B·(b̄u) with the true plant (load linearised) and b = r·b̄.
    let am = Matrix3::new(
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        1.0,
        -(a[0] + dd[0]),
        -(a[1] + dd[1]),
        -(a[2] + dd[2]),
    );
    let bm = Vector3::new(0.0, 0.0, v.r);
    let i3 = Matrix3::identity();
    let za = am * hs;
    let za2 = za * za;
    let za3 = za2 * za;
    // One RK4 step of ẋ = Ax + Bw with w held: x+ = R(hA)x + S·B·w.
    let rmat = i3 + za + za2 / 2.0 + za3 / 6.0 + za3 * za / 24.0;
    let smat = (i3 + za / 2.0 + za2 / 6.0 + za3 / 24.0) * hs;
    let mut rm = i3;
    let mut acc = Matrix3::zeros();
    for _ in 0..m {
        acc = rmat * acc + smat;
        rm = rmat * rm;
    }
    let gu = acc * bm;
    // w = b̄u = ā·x + p1ë + p2ė + p3e + gs·σ with e = −x1, ė = −x2, ë = −x3,
    // σ = ë + p1ė + p2e + p3∫e.
    let kx = [
        abar[0] - p[2] - gs * p[1],
        abar[1] - p[1] - gs * p[0],
        abar[2] - p[0] - gs,
    ];
    let ki = gs * p[2];
    let mut mm = Matrix4::<f64>::zeros();
    for i in 0..3 {
        for j in 0..3 {
            mm[(i, j)] = rm[(i, j)] + gu[i] * kx[j];
        }
        mm[(i, 3)] = gu[i] * ki;
    }
    // ∫e+ = ∫e + h·e = ∫e − h·x1.
    mm[(3, 0)] = -h;
    mm[(3, 3)] = 1.0;
    mm.complex_eigenvalues()
        .iter()
        .map(|z| z.norm())
        .fold(0.0, f64::max)
}

/// Condition 4) and the dead zone along a run.
#[derive(Debug, Clone, Serialize)]
pub struct RunDiagnostics {
    /// Samples examined (those kept in the trace).
    pub samples: usize,
    /// Samples with t ≥ settle.
    pub samples_after_settle: usize,
    /// Share where condition 4) holds (both halves).
    pub condition4: f64,
    /// Share where f + ᾱ‖E‖ < α‖E‖.
    pub condition4_left: f64,
    /// Share where α‖E‖ < c/γ1 + ᾱ‖E‖.
    pub condition4_right: f64,
    /// Share in the dead zone (σΔ = 0).
    pub dead_zone: f64,
    /// The same four after the transient (t ≥ settle).
    pub after_settle: [f64; 4],
    /// Median ‖E‖ over the samples.
    pub norm_e_median: f64,
    /// Median over the samples of c/(γ1·(α − ᾱ)): the right half holds iff
    /// ‖E‖ is below it.
    pub right_half_limit_median: f64,
}

/// f of (29)–(31) for one sample, with the μ(t), γ2(t) and ‖Φ‖ the
/// controller used. f = sqrt(f1² + f2) − f1 is evaluated as
/// f2/(sqrt(f1² + f2) + f1) when f1 > 0 (no cancellation when f2 ≪ f1²).
/// NaN when f1² + f2 < 0 (a negative μ, `mu_rule = "literal-33"`).
pub fn f_of(s: &Scenario, smp: &Sample) -> f64 {
    let c = &s.controller;
    let o = &smp.out;
    let cc = c.eta * c.w_max * c.w_max / 4.0 + c.eps0 * o.phi_norm + c.eps1;
    let f1 = (o.mu + o.gain / c.gamma1 - cc / c.gamma1) / 2.0;
    let f2 = cc * o.mu / c.gamma1;
    let root = (f1 * f1 + f2).sqrt();
    if f1 > 0.0 {
        f2 / (root + f1)
    } else {
        root - f1
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Condition 4) of Theorem 3,
/// f(t) + ᾱ‖E‖ < α‖E‖ < c/γ1 + ᾱ‖E‖ with c = ηW²max/4 + ε0‖Φ‖ + ε1,
/// and the dead zone along a trace (NNBVSC; None for the VSC or an empty
/// trace). The shares are over the samples of the trace (a decimated trace
/// gives the shares of its samples), and again over t ≥ settle.
pub fn diagnostics(s: &Scenario, trace: &[Sample]) -> Option<RunDiagnostics> {
    if s.controller.kind != ControllerKind::Nnvsc || trace.is_empty() {
        return None;
    }
    let c = &s.controller;
    let tol = 1e-9 * s.simulation.horizon.max(1.0);
    let cc_of = |smp: &Sample| c.eta * c.w_max * c.w_max / 4.0 + c.eps0 * smp.out.phi_norm + c.eps1;
    let eval = |smp: &Sample| {
        let o = &smp.out;
        let cc = cc_of(smp);
        let left = f_of(s, smp) + c.alpha_bar * o.norm_e < c.alpha * o.norm_e;
        let right = c.alpha * o.norm_e < cc / c.gamma1 + c.alpha_bar * o.norm_e;
        [left && right, left, right, o.sigma_delta == 0.0]
    };
    let share = |it: &mut dyn Iterator<Item = &Sample>| {
        let mut n = 0usize;
        let mut k = [0usize; 4];
        for smp in it {
            n += 1;
            for (slot, v) in k.iter_mut().zip(eval(smp)) {
                *slot += usize::from(v);
            }
        }
        let nn = n.max(1) as f64;
        (n, k.map(|x| x as f64 / nn))
    };
    let (n, all) = share(&mut trace.iter());
    let (n_after, after) = share(&mut trace.iter().filter(|x| x.t >= s.simulation.settle - tol));
    Some(RunDiagnostics {
        samples: n,
        samples_after_settle: n_after,
        condition4: all[0],
        condition4_left: all[1],
        condition4_right: all[2],
        dead_zone: all[3],
        after_settle: after,
        norm_e_median: median(trace.iter().map(|x| x.out.norm_e).collect()),
        right_half_limit_median: median(
            trace
                .iter()
                .map(|x| cc_of(x) / (c.gamma1 * (c.alpha - c.alpha_bar)))
                .collect(),
        ),
    })
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use ehservo_core::servo::ServoParams;

    /// The paper prints the poles 0, −84.9902 ± j76.0061 (Section IV); SPEC
    /// notes the "0" is −3.075e-5 exactly: for a small root r ≈ −ā1/ā2 =
    /// −0.39982/13000.27 = −3.0755e-5. The complex pair: sum of the roots is
    /// −ā3 = −169.98043, so 2·Re = −169.98043 + 3.1e-5 → Re = −84.99020;
    /// the sum of pairwise products is ā2 = |λ|² + 2·r·Re λ, so
    /// |λ|² = 13000.2711 − 2·3.0755e-5·84.9902 = 13000.2659 and
    /// Im = sqrt(13000.2659 − 84.9902²) = sqrt(5776.932) = 76.0061.
    #[test]
    fn open_loop_poles_match_the_paper() {
        let p = open_loop_poles(ServoParams::paper().coefficients().as_array());
        assert!(
            p[0].im.abs() < 1e-12 && (p[0].re + 3.0755e-5).abs() < 1e-8,
            "{:?}",
            p[0]
        );
        assert!(
            (p[1].re + 84.9902).abs() < 0.5e-4 && (p[1].im - 76.0061).abs() < 0.5e-4,
            "{:?}",
            p[1]
        );
        assert!(
            (p[2].re + 84.9902).abs() < 0.5e-4 && (p[2].im + 76.0061).abs() < 0.5e-4,
            "{:?}",
            p[2]
        );
        // ζ = −Re/|λ| = 84.9902/sqrt(13000.2659) = 84.9902/114.0187 = 0.74541.
        assert!((p[1].zeta - 0.74541).abs() < 1e-4);
    }

    /// (s+20)(s+30)(s+40) has the roots −20, −30, −40.
    #[test]
    fn surface_poles_roundtrip() {
        let p = cubic_roots(90.0, 2600.0, 24000.0);
        for (pole, want) in p.iter().zip([-20.0, -30.0, -40.0]) {
            assert!((pole.re - want).abs() < 1e-9 && pole.im.abs() < 1e-9);
        }
    }

    /// RK4's real-axis limit solves R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 = 1,
    /// i.e. z³/24 + z²/6 + z/2 + 1 = 0: z = −2.785293563 (R(−2.7853) = 1).
    #[test]
    fn rk4_limit() {
        let r = rk4_amplification(Complex::new(RK4_REAL_LIMIT, 0.0));
        assert!((r.re - 1.0).abs() < 1e-12 && r.im.abs() < 1e-15);
        assert!(rk4_amplification(Complex::new(-2.7, 0.0)).norm() < 1.0);
        assert!(rk4_amplification(Complex::new(-2.9, 0.0)).norm() > 1.0);
    }

    fn paper_scenario(set: &[&str]) -> Scenario {
        let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        Scenario::parse_with("", "<unit>", &set).unwrap()
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

    /// One axis's factor of Σφ² at a level (u = 0):
    /// 1 + 2e^(−2) + 2e^(−8) = 1.2713414917; the kernels' sup is its cube,
    /// 2.0548809349, at x = 0, where ‖Φ(0, 0)‖² = 1 + 2.0548809349.
    #[test]
    fn kernel_sum_of_squares_by_hand() {
        let rbf = Rbf::paper();
        let (k, arg) = kernel_sq_max(&rbf, OMEGA_X);
        let s0 = 1.0 + 2.0 * (-2f64).exp() + 2.0 * (-8f64).exp();
        assert!((s0 - 1.2713414917).abs() < 1e-10);
        assert!((k - s0.powi(3)).abs() < 1e-12, "{k}");
        assert!(arg.iter().all(|v| v.abs() < 1e-9), "{arg:?}");
        let mut out = [0.0; N_PHI];
        let n = rbf.phi(&[0.0; 3], &[0.0; 4], &mut out);
        assert!((n * n - (1.0 + k)).abs() < 1e-12);
        // A box that excludes the centres' neighbourhood on one axis: the
        // factor there is at the box's edge, not at a level.
        let tiny = [0.25 * rbf.scale()[0], OMEGA_X[1], OMEGA_X[2]];
        let (k2, arg2) = kernel_sq_max(&rbf, tiny);
        assert!(k2 <= k + 1e-15);
        assert!(arg2[0].abs() <= tiny[0] + 1e-15);
    }

    /// Remark 6 by hand: 2 + sqrt(4 + 0.2/0.25) = 2 + sqrt(4.8) = 4.19089023;
    /// η = 0 → unbounded.
    #[test]
    fn invariant_radius_by_hand() {
        let r = invariant_radius(0.25, 4.0, 0.1, 0.1, 1.0).unwrap();
        assert!((r - (2.0 + 4.8f64.sqrt())).abs() < 1e-15);
        assert!((r - 4.190_890_230).abs() < 1e-9);
        assert!(invariant_radius(0.0, 4.0, 0.1, 0.1, 1.0).is_none());
        // ‖Φ‖ = 10: 2 + sqrt(4 + 1.1/0.25) = 2 + sqrt(8.4) = 4.8982753.
        let r10 = invariant_radius(0.25, 4.0, 0.1, 0.1, 10.0).unwrap();
        assert!((r10 - 4.898_275_349).abs() < 1e-9);
    }

    /// f of (31) is the positive root of F(s) = s² + 2f1·s − f2 (A5), and
    /// with Remark 7's μ it is below (α − ᾱ)‖E‖.
    #[test]
    fn f_is_the_root_of_a5() {
        let s = paper_scenario(&[]);
        let c = &s.controller;
        let phi = 5.0;
        let cc = c.eta * c.w_max * c.w_max / 4.0 + c.eps0 * phi + c.eps1; // 1 + 0.5 + 0.1 = 1.6
        assert!((cc - 1.6).abs() < 1e-12);
        for norm_e in [1e-6, 1e-4, 1e-2, 1.0] {
            let mu = (c.alpha - c.alpha_bar) * norm_e * c.eps2 / cc;
            let mut smp = Sample::default();
            smp.out.mu = mu;
            smp.out.gain = cc + c.eps2;
            smp.out.phi_norm = phi;
            smp.out.norm_e = norm_e;
            let f = f_of(&s, &smp);
            let f1 = (mu + c.eps2 / c.gamma1) / 2.0;
            let f2 = cc * mu / c.gamma1;
            assert!(
                (f * f + 2.0 * f1 * f - f2).abs() <= 1e-12 * f2.max(1e-300),
                "{norm_e}"
            );
            assert!(f > 0.0 && f < (c.alpha - c.alpha_bar) * norm_e);
        }
        // μ = 0: f = 0.
        let mut smp = Sample::default();
        smp.out.gain = cc + c.eps2;
        smp.out.phi_norm = phi;
        assert!(f_of(&s, &smp).abs() < 1e-300);
    }

    /// The matrix of the linearised loop has the characteristic polynomial
    /// of the module doc: s⁴ + (c3 + r p1 + k)s³ + (c2 + r p2 + k p1)s² +
    /// (c1 + r p3 + k p2)s + k p3.
    #[test]
    fn loop_matrix_characteristic_polynomial() {
        let abar = [0.4, 13000.0, 170.0];
        let v = Truth {
            a: [0.8, 26000.0, 340.0],
            r: 1.25,
        };
        let dd = [2830.0, 141.5, 0.0];
        let p = [90.0, 2600.0, 24000.0];
        let gs = 200.0;
        let m = loop_matrix(&abar, &v, &dd, gs, p);
        let k = v.r * gs;
        let c: [f64; 3] = std::array::from_fn(|j| v.a[j] + dd[j] - v.r * abar[j]);
        let coef = [
            1.0,
            c[2] + v.r * p[0] + k,
            c[1] + v.r * p[1] + k * p[0],
            c[0] + v.r * p[2] + k * p[1],
            k * p[2],
        ];
        for s in [-1.0, -50.0, 3.0, -400.0] {
            let want = (((coef[0] * s + coef[1]) * s + coef[2]) * s + coef[3]) * s + coef[4];
            let got = (Matrix4::identity() * s - m).determinant();
            assert!(
                (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                "s = {s}: {got} vs {want}"
            );
        }
    }

    /// The sampled map and the continuous loop agree as h → 0: the spectral
    /// radius tends to e^(h·max Re λ) (here the slow complex pair,
    /// Re λ = −11.5642 for Fig. 2): at h = 1e-5, 1 − 1.15642e-4.
    #[test]
    fn sampled_map_tends_to_the_continuous_loop() {
        let a = analyze(&paper_scenario(&["simulation.step=1e-5"]));
        let l = &a.closed_loop;
        let slow = l.eigenvalues[0].re;
        assert!((slow + 11.5642).abs() < 1e-3, "{slow}");
        let g = l.growth.unwrap();
        assert!((g - (1e-5 * slow).exp()).abs() < 1e-7, "{g}");
    }

    #[test]
    fn significant_digits() {
        assert_eq!(report::sig(250.0, 3), "250");
        assert_eq!(report::sig(8.3088e-3, 2), "8.3e-3");
        assert_eq!(report::sig(5e-3, 3), "5e-3");
        assert_eq!(report::sig(2407.0914258758, 8), "2407.0914");
        assert_eq!(report::sig(-406.31182, 5), "-406.31");
        assert_eq!(report::sig(0.25, 6), "0.25");
        assert_eq!(report::sig(f64::INFINITY, 3), "∞");
        assert_eq!(report::sig(0.0, 3), "0");
    }

    #[test]
    fn medians() {
        assert!(median(Vec::new()).is_nan());
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
