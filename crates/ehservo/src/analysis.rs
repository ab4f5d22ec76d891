//! What the theory says about a scenario before it runs.
//!
//! - **Plant**: the nominal coefficients ā_i (9), b̄ at Pl = 0, the two
//!   coefficients of d(t), and the open-loop poles (roots of
//!   s³ + ā3 s² + ā2 s + ā1) with damping ratios and natural frequencies.
//! - **Surface and Theorem 2**: p, the poles of the sliding dynamics, the
//!   matrix P of (16), K2 = −max Re λ(P) and K1 = the least constant with
//!   ‖exp(Pt)‖₂ ≤ K1·e^(−K2·t) for all t ≥ 0 (18), hence the bound
//!   0 < α < K2/K1 of Theorem 2 and a verdict on the scenario's α.
//!   K1 = sup_t ‖exp(Pt)‖₂·e^(K2·t) is computed with nalgebra's matrix
//!   exponential on a grid long enough for every faster mode to have died
//!   (40/gap, gap the distance between the dominant real part and the next),
//!   refined by golden section around the maximum, then *checked* on an
//!   independent, three times denser grid over twice the span: the report
//!   says whether any point exceeds K1. A repeated dominant pole makes the
//!   product grow like t (P is a companion matrix, so a repeated eigenvalue
//!   is always a Jordan block): K1 is then infinite.
//! - **Weights (Remark 6)**: the radius Wmax/2 + sqrt(Wmax²/4 + (ε0‖Φ‖ + ε1)/η)
//!   of the invariant set of W̃ = W̄ − W, at ‖Φ‖ = 1 (its least value: the
//!   bias entry) and at the largest ‖Φ‖ the scenario's reference and the
//!   compact set Ω can give; infinite for η = 0. Also the ball
//!   ‖W‖ ≤ sup‖Φ‖/η that the law (26) itself keeps invariant (for
//!   ‖W‖ > ‖Φ‖/η, d‖W‖²/dt = 2σΔ·WᵀΦ − 2η|σΔ|‖W‖² < 0).
//! - **The closed loop, linearised** about rest with W = 0, σΔ = σ and the
//!   γ2 term left out (bounded by γ2, a few units): in the error coordinates
//!   (∫e, e, ė, ë) with the true a = ā + Δa (bias part) and b = r·b̄,
//!   r = 1 + b_reference·b_bias, and the load's slopes ∂d/∂θ, ∂d/∂θ̇ at θ = 0,
//!
//!   ```text
//!   ë' = −(a + d' − r·ā)·(e, ė, ë) − r·(p3 e + p2 ė + p1 ë) − r·γ1/(1 − bound_b)·σ
//!   ```
//!
//!   Three eigenvalues sit near the surface poles, one is the fast σ mode,
//!   ≈ −r·γ1/(1 − bound_b) − (a3 − p1) + r·(ā3 − p1) (−400 s⁻¹ for Fig. 2's
//!   γ1 = 100, −650 for 200; SPEC §7 estimates −410 and −660). The σ-loop
//!   gain is b/(b̄ − β)·γ1 = r·γ1/(1 − bound_b).
//! - **The integrator**: in continuous mode every eigenvalue λ must satisfy
//!   |R(hλ)| < 1 with RK4's R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 (on the real
//!   axis: h·λ > −2.785); in sampled mode the exact linearised one-sample
//!   map — the plant under a held u advanced by `substeps` RK4 steps, ∫e by
//!   Euler — must have spectral radius < 1. A warning says when not.
//!   For the traditional VSC the loop is discontinuous (sgn) and the linear
//!   check does not apply; for `vsc-sat` it uses the boundary layer's slope.
//! - **After a run** ([`diagnostics`]): the share of samples where
//!   condition 4) of Theorem 3 holds — f + ᾱ‖E‖ < α‖E‖ < c/γ1 + ᾱ‖E‖ with
//!   f from (29)–(31) and the μ(t), γ2(t) the controller used — each half
//!   apart, and the share spent in the dead zone (σΔ = 0).

use crate::scenario::{ControllerKind, Scenario};
use crate::sim::Sample;
use ehservo_core::rbf::N_PHI;
use ehservo_core::reference::Reference;
use ehservo_core::servo::NominalModel;
use nalgebra::{Complex, Matrix3, Matrix4, SMatrix};
use serde::Serialize;
use std::fmt::Write;

/// RK4's stability limit on the negative real axis: R(z) = 1 at z ≈ −2.7853.
pub const RK4_REAL_LIMIT: f64 = -2.785_293_563_405_282;

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

/// K1 of (18) and how it was checked.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct K1 {
    /// K1, or None if infinite (repeated dominant pole).
    pub value: Option<f64>,
    /// Where the supremum is reached (s); None when approached as t → ∞.
    pub at_t: Option<f64>,
    /// Span of the search grid (s).
    pub span: f64,
    /// Points of the search grid.
    pub grid_points: usize,
    /// Largest ‖exp(Pt)‖·e^(K2 t)/K1 on the independent check grid.
    pub check_max_ratio: f64,
    /// The check found no point above K1·(1 + 1e-9).
    pub verified: bool,
}

fn g(p: &Matrix3<f64>, k2: f64, t: f64) -> f64 {
    norm2(&(p * t).exp()) * (k2 * t).exp()
}

/// K1 = sup over t ≥ 0 of ‖exp(Pt)‖₂·e^(K2·t) (see the module doc).
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
    // A repeated dominant eigenvalue (same re and im): Jordan block, t·e^(λt).
    for (i, a) in dom.iter().enumerate() {
        for b in &dom[i + 1..] {
            if (a.im - b.im).abs() <= tol {
                return K1 {
                    value: None,
                    at_t: None,
                    span: f64::INFINITY,
                    grid_points: 0,
                    check_max_ratio: f64::INFINITY,
                    verified: false,
                };
            }
        }
    }
    let gap = poles
        .iter()
        .filter(|q| dominant - q.re > tol)
        .map(|q| dominant - q.re)
        .fold(f64::INFINITY, f64::min);
    let mut span = if gap.is_finite() { 40.0 / gap } else { 0.0 };
    if let Some(w) = dom
        .iter()
        .map(|q| q.im.abs())
        .filter(|w| *w > 0.0)
        .reduce(f64::max)
    {
        span = span.max(10.0 * 2.0 * std::f64::consts::PI / w);
    }
    span = span.max(10.0 / k2.max(1e-12)).min(1e6 / k2.max(1e-12));
    let n = 4_000usize;
    let mut best = (0.0, 1.0);
    for i in 0..=n {
        let t = span * i as f64 / n as f64;
        let v = g(p, k2, t);
        if v > best.1 {
            best = (t, v);
        }
    }
    // Golden-section refinement around the grid maximum.
    let h = span / n as f64;
    let (mut a, mut b) = ((best.0 - h).max(0.0), (best.0 + h).min(span));
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..80 {
        let c = b - phi * (b - a);
        let d = a + phi * (b - a);
        if g(p, k2, c) > g(p, k2, d) {
            b = d;
        } else {
            a = c;
        }
    }
    let tr = 0.5 * (a + b);
    let vr = g(p, k2, tr);
    let (t_star, k1v) = if vr > best.1 { (tr, vr) } else { best };
    // A supremum approached as t → ∞ shows as a plateau up to the span's end.
    let at_end = g(p, k2, span) >= k1v * (1.0 - 1e-9);
    // Independent check: 3× denser, twice the span, offset from the grid.
    let m = 3 * n;
    let mut worst: f64 = 0.0;
    for i in 0..m {
        let t = 2.0 * span * (i as f64 + 0.5) / m as f64;
        worst = worst.max(g(p, k2, t) / k1v);
    }
    K1 {
        value: Some(k1v),
        at_t: if at_end { None } else { Some(t_star) },
        span,
        grid_points: n + 1,
        check_max_ratio: worst,
        verified: worst <= 1.0 + 1e-9,
    }
}

/// The switching surface and Theorem 2.
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceAnalysis {
    /// p1, p2, p3.
    pub p: [f64; 3],
    /// Poles of the sliding dynamics.
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
    /// Plain-language verdict.
    pub verdict: String,
}

/// Remark 6's invariant set.
#[derive(Debug, Clone, Serialize)]
pub struct WeightAnalysis {
    /// η.
    pub eta: f64,
    /// Wmax.
    pub w_max: f64,
    /// Largest ‖Φ‖ over the reference and Ω.
    pub phi_norm_max: f64,
    /// Radius on ‖W̃‖ at ‖Φ‖ = 1 (None: unbounded, η = 0).
    pub radius_min: Option<f64>,
    /// Radius on ‖W̃‖ at the largest ‖Φ‖.
    pub radius_max: Option<f64>,
    /// The ball ‖W‖ ≤ sup‖Φ‖/η kept invariant by the law (26) itself.
    pub law_ball: Option<f64>,
    /// Plain-language note.
    pub note: String,
}

/// The linearised closed loop and the integrator.
#[derive(Debug, Clone, Serialize)]
pub struct LoopAnalysis {
    /// b/(b̄ − β)·γ1 (or its VSC-sat analogue); None for the sgn VSC.
    pub sigma_gain: Option<f64>,
    /// Eigenvalues of the linearised error dynamics (continuous time).
    pub eigenvalues: Vec<Pole>,
    /// The fast (σ) eigenvalue.
    pub fast: Option<f64>,
    /// h·λ_fast.
    pub h_lambda: Option<f64>,
    /// Continuous mode: max |R(hλ)| over the eigenvalues; sampled mode:
    /// spectral radius of the one-sample map.
    pub growth: Option<f64>,
    /// Whether the simulation scheme is stable on the linearised loop.
    pub stable: Option<bool>,
    /// Plain-language verdict.
    pub verdict: String,
    /// Set when the scheme is not stable.
    pub warning: Option<String>,
}

/// Everything [`analyze`] computes.
#[derive(Debug, Clone, Serialize)]
pub struct Analysis {
    /// ā1, ā2, ā3.
    pub a_nominal: [f64; 3],
    /// b̄ at Pl = 0.
    pub b_at_rest: f64,
    /// d = d_tl·Tl + d_tldot·Ṫl: [4βe·Kce/(Vt·Jt), 1/Jt].
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

fn order(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor();
    if (-1.0..4.0).contains(&e) {
        format!("{x:.4}")
    } else {
        format!("{x:.3e}")
    }
}

/// Largest ‖Φ‖ for the scenario: the kernels' part maximised over a grid of
/// the normalised state in [−1.25, 1.25]³ (Ω of Section IV is ±1.25 of the
/// scales), the reference part over one period.
pub fn phi_norm_max(s: &Scenario) -> f64 {
    let Ok(rbf) = s.rbf() else { return f64::NAN };
    let scale = rbf.scale();
    let mut out = [0.0; N_PHI];
    let mut kern: f64 = 0.0;
    let n = 21;
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let c = |q: usize| -1.25 + 2.5 * q as f64 / (n - 1) as f64;
                let x = [c(i) * scale[0], c(j) * scale[1], c(k) * scale[2]];
                let nrm = rbf.phi(&x, &[0.0; 4], &mut out);
                kern = kern.max(nrm * nrm - 1.0);
            }
        }
    }
    let r = s.reference();
    let period = 1.0 / s.reference.frequency_hz;
    let zmax = (0..1000)
        .map(|i| {
            let z = r.z(period * i as f64 / 1000.0);
            z.iter().map(|v| v * v).sum::<f64>()
        })
        .fold(0.0, f64::max);
    (1.0 + kern + zmax).sqrt()
}

/// Analyses a validated scenario.
pub fn analyze(s: &Scenario) -> Analysis {
    let servo = s.plant.params.to_servo();
    let load = s.load_model();
    let model = NominalModel::new(servo, load);
    let a = model.coeffs.as_array();
    let surface = s
        .surface()
        .map(|x| x.p())
        .unwrap_or([90.0, 2600.0, 24000.0]);
    let pm = p_matrix(surface);
    let sp = cubic_roots(surface[0], surface[1], surface[2]);
    let k2 = -sp[0].re;
    let k1v = k1(&pm, &sp, k2);
    let bound = k1v.value.map(|v| k2 / v).unwrap_or(0.0);
    let nn = s.controller.kind == ControllerKind::Nnvsc;
    let alpha = if nn { Some(s.controller.alpha) } else { None };
    let holds = alpha.map(|al| al > 0.0 && al < bound);
    let verdict = match (alpha, holds) {
        (Some(al), Some(true)) => format!(
            "holds: α = {} < K2/K1 = {}; Theorem 2's exponential rate K2 − αK1 = {} s⁻¹",
            order(al),
            order(bound),
            order(k2 - al * k1v.value.unwrap_or(f64::INFINITY))
        ),
        (Some(al), Some(false)) => {
            let decades = if bound > 0.0 {
                (al / bound).log10()
            } else {
                f64::INFINITY
            };
            format!(
                "violated: α = {} exceeds K2/K1 = {} by {:.1} decades; α then acts as a tuning number of μ(t), not a certified rate",
                order(al),
                order(bound),
                decades
            )
        }
        _ => format!(
            "the traditional VSC has no α; Theorem 2 would admit 0 < α < {}",
            order(bound)
        ),
    };
    let surface_analysis = SurfaceAnalysis {
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
        verdict,
    };

    let weights = nn.then(|| {
        let c = &s.controller;
        let pmax = phi_norm_max(s);
        let radius = |phi: f64| {
            (c.eta > 0.0).then(|| c.w_max / 2.0 + (c.w_max * c.w_max / 4.0 + (c.eps0 * phi + c.eps1) / c.eta).sqrt())
        };
        WeightAnalysis {
            eta: c.eta,
            w_max: c.w_max,
            phi_norm_max: pmax,
            radius_min: radius(1.0),
            radius_max: radius(pmax),
            law_ball: (c.eta > 0.0).then(|| pmax / c.eta),
            note: if c.eta > 0.0 {
                format!(
                    "‖W̄ − W‖ stays below {} (at ‖Φ‖ = 1) to {} (at ‖Φ‖ = {:.2}); with ‖W̄‖ ≤ Wmax = {} that bounds ‖W‖ by {}. The law (26) alone keeps ‖W‖ ≤ sup‖Φ‖/η = {}.",
                    order(radius(1.0).unwrap_or(f64::NAN)),
                    order(radius(pmax).unwrap_or(f64::NAN)),
                    pmax,
                    order(c.w_max),
                    order(c.w_max + radius(pmax).unwrap_or(f64::NAN)),
                    order(pmax / c.eta)
                )
            } else {
                "η = 0: the invariant set is unbounded (Remark 6: W_in → ∞ as η → 0); the weights may drift without bound.".into()
            },
        }
    });

    let closed_loop = loop_analysis(s, &model);
    Analysis {
        a_nominal: a,
        b_at_rest: model.b_at_rest(),
        d_coefficients: [servo.d_per_torque(), 1.0 / servo.jt],
        open_loop_poles: open_loop_poles(a),
        surface: surface_analysis,
        weights,
        closed_loop,
    }
}

/// RK4's amplification R(z) = 1 + z + z²/2 + z³/6 + z⁴/24.
pub fn rk4_amplification(z: Complex<f64>) -> Complex<f64> {
    let one = Complex::new(1.0, 0.0);
    one + z + z * z / 2.0 + z * z * z / 6.0 + z * z * z * z / 24.0
}

fn loop_analysis(s: &Scenario, model: &NominalModel) -> LoopAnalysis {
    let c = &s.controller;
    let p = s
        .surface()
        .map(|x| x.p())
        .unwrap_or([90.0, 2600.0, 24000.0]);
    let abar = model.coeffs.as_array();
    let u = &s.uncertainty;
    let a: [f64; 3] = std::array::from_fn(|i| abar[i] + abar[i].abs() * u.a_bias);
    let r = 1.0 + u.b_reference * u.b_bias;
    let bb = c.bound_b;
    // The switching slope: γ1/(1 − bb) for the NNBVSC; k·b̄/μ for vsc-sat at rest.
    let slope = match c.kind {
        ControllerKind::Nnvsc => Some(c.gamma1 / (1.0 - bb)),
        ControllerKind::VscSat => {
            // k·b̄ at rest = [γ + bb·|N|]/(1 − bb) → only γ = |d(0)| = 0 is left:
            // the layer's slope is that of N's bound term, which vanishes at rest.
            // Use the slope of sat(σ/μ)·kb with kb from the Fig. 2 amplitude of u_eq.
            None
        }
        ControllerKind::Vsc => None,
    };
    // Load slopes at θ = 0: d ≈ kd·(A·k)·θ + (A·k/Jt)·θ̇.
    let amp_k = s.load.amplitude * s.load.wavenumber;
    let dd = [
        model.params.d_per_torque() * amp_k,
        amp_k / model.params.jt,
        0.0,
    ];
    let Some(gs) = slope else {
        return LoopAnalysis {
            sigma_gain: None,
            eigenvalues: Vec::new(),
            fast: None,
            h_lambda: None,
            growth: None,
            stable: None,
            verdict: match c.kind {
                ControllerKind::Vsc => "the traditional VSC switches with sgn(σ): the loop is discontinuous and a linear stability check does not apply (its sampled behaviour is measured by `ehservo reproduce`'s breaking-point search)".into(),
                _ => "vsc-sat: the boundary-layer slope k/μ depends on the state (k grows with |u_eq|); no linear check".into(),
            },
            warning: None,
        };
    };
    // Error dynamics in (∫e, e, ė, ë), reference terms dropped.
    let mut m = Matrix4::<f64>::zeros();
    m[(0, 1)] = 1.0;
    m[(1, 2)] = 1.0;
    m[(2, 3)] = 1.0;
    for (j, col) in [1usize, 2, 3].iter().enumerate() {
        // −(a + d' − r·ā)_j − r·p_{3−j}
        let pj = [p[2], p[1], p[0]][j];
        m[(3, *col)] = -(a[j] + dd[j] - r * abar[j]) - r * pj;
    }
    // − r·γs·σ, σ = ë + p1 ė + p2 e + p3 ∫e
    let k = r * gs;
    m[(3, 0)] -= k * p[2];
    m[(3, 1)] -= k * p[1];
    m[(3, 2)] -= k * p[0];
    m[(3, 3)] -= k;
    let ev = m.complex_eigenvalues();
    let mut eigs: Vec<Pole> = ev.iter().map(|z| Pole::from(*z)).collect();
    sort_poles(&mut eigs);
    let fast = eigs.iter().map(|q| q.re).fold(f64::INFINITY, f64::min);
    let h = s.simulation.step;
    let (growth, scheme) = match s.simulation.mode {
        crate::sim::Mode::Continuous => {
            let g = ev
                .iter()
                .map(|z| rk4_amplification(z * h).norm())
                .fold(0.0, f64::max);
            (g, format!("continuous RK4 at h = {h} s: max |R(hλ)| = {g:.4} (h·λ_fast = {:.3}; the real-axis limit is {RK4_REAL_LIMIT:.3})", h * fast))
        }
        crate::sim::Mode::Sampled => {
            let g = sampled_radius(s, model, &a, &dd, r, gs, p);
            (
                g,
                format!(
                    "sampled at h = {h} s with {} RK4 sub-step(s): spectral radius of the one-sample map = {g:.4}",
                    s.simulation.substeps
                ),
            )
        }
    };
    let stable = growth < 1.0;
    LoopAnalysis {
        sigma_gain: Some(r * gs),
        eigenvalues: eigs,
        fast: Some(fast),
        h_lambda: Some(h * fast),
        growth: Some(growth),
        stable: Some(stable),
        verdict: format!(
            "{scheme}: {}",
            if stable { "stable" } else { "UNSTABLE — the run will blow up or chatter" }
        ),
        warning: (!stable).then(|| {
            format!(
                "the {} scheme is outside its stability region on the linearised loop (fast eigenvalue {:.1} s⁻¹); use a smaller step{}",
                s.simulation.mode.as_str(),
                fast,
                if s.simulation.mode == crate::sim::Mode::Continuous {
                    format!(" (h < {:.2e} s)", RK4_REAL_LIMIT / fast)
                } else {
                    String::new()
                }
            )
        }),
    }
}

/// Spectral radius of the linearised one-sample map of the sampled mode:
/// plant state x (3) and ∫e, with θd = 0; u held over the sample, the plant
/// advanced by `substeps` RK4 steps (the exact RK4 map of a linear system
/// with constant input), ∫e by Euler.
fn sampled_radius(
    s: &Scenario,
    model: &NominalModel,
    a: &[f64; 3],
    dd: &[f64; 3],
    r: f64,
    gs: f64,
    p: [f64; 3],
) -> f64 {
    let abar = model.coeffs.as_array();
    let bbar = model.b_at_rest();
    let h = s.simulation.step;
    let m = s.simulation.substeps.max(1);
    let hs = h / m as f64;
    // ẋ = A x + B u (true plant, load linearised).
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
    let bm = nalgebra::Vector3::new(0.0, 0.0, r * bbar);
    let i3 = Matrix3::identity();
    let za = am * hs;
    let rmat = i3 + za + za * za / 2.0 + za * za * za / 6.0 + za * za * za * za / 24.0;
    let smat = (i3 + za / 2.0 + za * za / 6.0 + za * za * za / 24.0) * hs;
    // After m sub-steps: x+ = R^m x + Σ R^k S B u.
    let mut rm = i3;
    let mut acc = Matrix3::zeros();
    for _ in 0..m {
        acc = rmat * acc + smat;
        rm = rmat * rm;
    }
    let gu = acc * bm;
    // u = K·[x; ∫e] with e = −x1, ė = −x2, ë = −x3 (θd = 0):
    // b̄u = ā·x + p1·ë + p2·ė + p3·e + gs·σ, σ = ë + p1 ė + p2 e + p3 ∫e.
    let kx = [
        abar[0] - p[2] - gs * p[1],
        abar[1] - p[1] - gs * p[0],
        abar[2] - p[0] - gs,
    ];
    let ki = gs * p[2];
    let mut mm = SMatrix::<f64, 4, 4>::zeros();
    for i in 0..3 {
        for j in 0..3 {
            mm[(i, j)] = rm[(i, j)] + gu[i] * kx[j] / bbar;
        }
        mm[(i, 3)] = gu[i] * ki / bbar;
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
    /// Samples examined.
    pub samples: usize,
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
}

/// f of (29)–(31) for one sample.
pub fn f_of(s: &Scenario, smp: &Sample) -> f64 {
    let c = &s.controller;
    let o = &smp.out;
    let cc = c.eta * c.w_max * c.w_max / 4.0 + c.eps0 * o.phi_norm + c.eps1;
    let f1 = (o.mu + o.gain / c.gamma1
        - c.eta * c.w_max * c.w_max / (4.0 * c.gamma1)
        - (c.eps0 * o.phi_norm + c.eps1) / c.gamma1)
        / 2.0;
    let f2 = cc * o.mu / c.gamma1;
    (f1 * f1 + f2).sqrt() - f1
}

/// Condition 4) of Theorem 3 and the dead zone along a trace (NNBVSC).
pub fn diagnostics(s: &Scenario, trace: &[Sample]) -> Option<RunDiagnostics> {
    if s.controller.kind != ControllerKind::Nnvsc || trace.is_empty() {
        return None;
    }
    let c = &s.controller;
    let tol = 1e-9 * s.simulation.horizon.max(1.0);
    let eval = |smp: &Sample| {
        let o = &smp.out;
        let cc = c.eta * c.w_max * c.w_max / 4.0 + c.eps0 * o.phi_norm + c.eps1;
        let left = f_of(s, smp) + c.alpha_bar * o.norm_e < c.alpha * o.norm_e;
        let right = c.alpha * o.norm_e < cc / c.gamma1 + c.alpha_bar * o.norm_e;
        (left && right, left, right, o.sigma_delta == 0.0)
    };
    let share = |it: &mut dyn Iterator<Item = &Sample>| {
        let mut n = 0usize;
        let mut k = [0usize; 4];
        for smp in it {
            let (a, b, cc, d) = eval(smp);
            n += 1;
            for (slot, v) in k.iter_mut().zip([a, b, cc, d]) {
                *slot += v as usize;
            }
        }
        let nn = n.max(1) as f64;
        (
            n,
            [
                k[0] as f64 / nn,
                k[1] as f64 / nn,
                k[2] as f64 / nn,
                k[3] as f64 / nn,
            ],
        )
    };
    let (n, all) = share(&mut trace.iter());
    let (_, after) = share(&mut trace.iter().filter(|x| x.t >= s.simulation.settle - tol));
    Some(RunDiagnostics {
        samples: n,
        condition4: all[0],
        condition4_left: all[1],
        condition4_right: all[2],
        dead_zone: all[3],
        after_settle: after,
    })
}

impl RunDiagnostics {
    /// Terminal text.
    pub fn to_text(&self) -> String {
        let pc = |v: f64| format!("{:.1} %", 100.0 * v);
        let mut t = String::new();
        let _ = writeln!(
            t,
            "After the run ({} samples; in brackets: t ≥ settle)",
            self.samples
        );
        let _ = writeln!(
            t,
            "  condition 4) of Theorem 3 holds        {:>8}  [{}]",
            pc(self.condition4),
            pc(self.after_settle[0])
        );
        let _ = writeln!(
            t,
            "    left  f + ᾱ‖E‖ < α‖E‖               {:>8}  [{}]",
            pc(self.condition4_left),
            pc(self.after_settle[1])
        );
        let _ = writeln!(
            t,
            "    right α‖E‖ < c/γ1 + ᾱ‖E‖            {:>8}  [{}]",
            pc(self.condition4_right),
            pc(self.after_settle[2])
        );
        let _ = writeln!(
            t,
            "  in the dead zone (σΔ = 0)              {:>8}  [{}]",
            pc(self.dead_zone),
            pc(self.after_settle[3])
        );
        t
    }
}

impl Analysis {
    /// Terminal text.
    pub fn to_text(&self) -> String {
        let mut t = String::new();
        let p = |q: &Pole| {
            if q.im.abs() > 0.0 {
                format!(
                    "{:.4} {} j{:.4}  (ζ = {:.4}, ωn = {:.4} rad/s)",
                    q.re,
                    if q.im < 0.0 { "−" } else { "+" },
                    q.im.abs(),
                    q.zeta,
                    q.wn
                )
            } else {
                format!("{:.6e}  (real)", q.re)
            }
        };
        let _ = writeln!(t, "Plant (nominal, Pl = 0)");
        let _ = writeln!(
            t,
            "  ā1 = {:.5} s⁻³   ā2 = {:.4} s⁻²   ā3 = {:.5} s⁻¹",
            self.a_nominal[0], self.a_nominal[1], self.a_nominal[2]
        );
        let _ = writeln!(t, "  b̄ = {:.3} s⁻³V⁻¹ at Pl = 0", self.b_at_rest);
        let _ = writeln!(
            t,
            "  d = {:.4}·Tl + {:.4}·Ṫl  (4βe·Kce/(Vt·Jt), 1/Jt)",
            self.d_coefficients[0], self.d_coefficients[1]
        );
        for q in &self.open_loop_poles {
            let _ = writeln!(t, "  open-loop pole {}", p(q));
        }
        let s = &self.surface;
        let _ = writeln!(t, "\nSwitching surface and Theorem 2");
        let _ = writeln!(t, "  p = ({}, {}, {})", s.p[0], s.p[1], s.p[2]);
        for q in &s.poles {
            let _ = writeln!(t, "  sliding pole {}", p(q));
        }
        let _ = writeln!(
            t,
            "  P = [{:?}, {:?}, {:?}]",
            s.p_matrix[0], s.p_matrix[1], s.p_matrix[2]
        );
        let _ = writeln!(t, "  K2 = {}", order(s.k2));
        match s.k1.value {
            Some(v) => {
                let _ = writeln!(
                    t,
                    "  K1 = {} ({}; grid of {} points over {} s, checked on an independent grid: {} (max ratio {:.12}))",
                    order(v),
                    match s.k1.at_t {
                        Some(tt) => format!("reached at t = {tt:.5} s"),
                        None => "approached as t → ∞".into(),
                    },
                    s.k1.grid_points,
                    order(s.k1.span),
                    if s.k1.verified { "verified" } else { "NOT verified" },
                    s.k1.check_max_ratio
                );
            }
            None => {
                let _ = writeln!(
                    t,
                    "  K1 = ∞ (repeated dominant pole: ‖exp(Pt)‖·e^(K2 t) grows like t)"
                );
            }
        }
        let _ = writeln!(
            t,
            "  Theorem 2 needs 0 < α < K2/K1 = {}",
            order(s.alpha_bound)
        );
        let _ = writeln!(t, "  verdict: {}", s.verdict);
        if let Some(w) = &self.weights {
            let _ = writeln!(t, "\nWeights (Remark 6), η = {}, Wmax = {}", w.eta, w.w_max);
            let _ = writeln!(t, "  {}", w.note);
        }
        let l = &self.closed_loop;
        let _ = writeln!(
            t,
            "\nClosed loop, linearised (W = 0, σΔ = σ, γ2 term left out)"
        );
        if let Some(gain) = l.sigma_gain {
            let _ = writeln!(t, "  σ-loop gain b/(b̄ − β)·γ1 = {}", order(gain));
        }
        for q in &l.eigenvalues {
            let _ = writeln!(t, "  eigenvalue {}", p(q));
        }
        let _ = writeln!(t, "  {}", l.verdict);
        if let Some(w) = &l.warning {
            let _ = writeln!(t, "warning: {w}");
        }
        t
    }
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
}
