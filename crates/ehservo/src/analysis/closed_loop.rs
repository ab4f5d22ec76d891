//! The linearised σ-loop (derivation in the `analysis` module doc): the
//! loop matrix, RK4's amplification, the sampled one-sample map and
//! [`LoopAnalysis`], whether the simulation scheme is stable on it.

use super::fmt_sig;
use super::poles::{sort_poles, Pole};
use super::{paper_law, PaperLaw};
use crate::scenario::{Loop, Scenario, SimulationCfg};
use crate::simulation::Mode;
use ehservo_core::control::sliding::SlidingConfig;
use ehservo_core::reference::Reference;
use ehservo_core::servo::NominalModel;
use ehservo_sim::plant::UncertaintySpec;
use nalgebra::{Complex, Matrix3, Matrix4, Vector3};
use serde::Serialize;

/// RK4's stability limit on the negative real axis: R(z) = 1 at z ≈ −2.7853.
pub const RK4_REAL_LIMIT: f64 = -2.785_293_563_405_282;

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

/// The σ-loop of a controller that is not one of the paper's laws: not
/// computed.
fn not_applicable(lp: &Loop) -> LoopAnalysis {
    let s = lp.scenario();
    let u = &lp.stages().uncertainty;
    LoopAnalysis {
        controller: s.controller.kind().into(),
        mode: s.simulation.mode.as_str().into(),
        step: s.simulation.step,
        substeps: s.simulation.substeps,
        b_ratio: 1.0 + u.b_reference * u.b_bias,
        b_ratio_worst: 1.0 + u.b_reference * (u.b_bias + u.b_random.abs()),
        switching_slope: None,
        vsc_sat_kb: None,
        sigma_gain: None,
        sigma_gain_worst: None,
        load_slopes: [0.0; 3],
        eigenvalues: Vec::new(),
        fast: None,
        fast_estimate: None,
        fast_worst: None,
        h_lambda: None,
        growth: None,
        stable: None,
        check: "none".into(),
        verdict: format!(
            "not applicable: the linearised σ-loop is the paper's sliding-mode laws' (vsc, vsc-sat, nnvsc), not `{}`'s",
            s.controller.kind()
        ),
        warning: None,
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
/// largest over one period (of a sine; the whole horizon for another kind).
fn vsc_kb_range(lp: &Loop, c: &SlidingConfig, model: &NominalModel) -> [f64; 2] {
    let abar = model.coeffs.as_array();
    let bb = c.bound_b;
    let ba = c.bound_a;
    let surf = lp.design().surface;
    let r = lp.reference();
    // One period of a sine (as it always was), else the whole horizon,
    // finer.
    let period = lp.reference_span();
    let n = if r.as_sine().is_some() { 2000 } else { 20_000 };
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

pub(super) fn loop_analysis(lp: &Loop, model: &NominalModel, p: [f64; 3]) -> LoopAnalysis {
    let s = lp.scenario();
    let sim = &s.simulation;
    let Some((law, c)) = paper_law(s) else {
        return not_applicable(lp);
    };
    let abar = model.coeffs.as_array();
    let u = &lp.stages().uncertainty;
    let h = sim.step;
    let Variation {
        bias,
        corners,
        r_worst,
    } = Variation::of(&abar, u);
    let dd = load_slopes(model);
    let bb = c.bound_b;
    let (slope, kb_range) = match law {
        PaperLaw::Nnvsc => (Some(c.gamma1 / (1.0 - bb)), None),
        PaperLaw::VscSat => {
            let kb = vsc_kb_range(lp, c, model);
            (Some(kb[1] / c.mu), Some(kb))
        }
        PaperLaw::Vsc => (None, None),
    };
    let mut out = LoopAnalysis {
        controller: s.controller.kind().into(),
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
    // A parameter extreme enough to overflow the loop matrix: not computed.
    let eig = |v: &Truth| -> Vec<Complex<f64>> {
        super::linalg::eigenvalues4(&loop_matrix(&abar, v, &dd, gs, p)).unwrap_or_default()
    };
    let fast_of = |ev: &[Complex<f64>]| ev.iter().map(|z| z.re).fold(f64::INFINITY, f64::min);
    let ev_bias = eig(&bias);
    if ev_bias.is_empty() || corners.iter().any(|v| eig(v).is_empty()) {
        out.check = "none".into();
        out.verdict = "not computed: the linearised loop's matrix is not finite (parameters beyond the range where it can be represented)".into();
        return out;
    }
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
    let varied = u.a_random != 0.0 || u.b_random != 0.0;
    let sat = law == PaperLaw::VscSat;
    (out.check, out.verdict, out.warning) = loop_texts(sim, sat, varied, fast_worst, growth);
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

/// The plant's parameter variation as the loop sees it: the bias, the
/// corners bias ± |random| of the a and b variations, and the worst b/b̄.
struct Variation {
    bias: Truth,
    corners: Vec<Truth>,
    r_worst: f64,
}

impl Variation {
    /// The variation `u` of the nominal coefficients `abar`.
    fn of(abar: &[f64; 3], u: &UncertaintySpec) -> Variation {
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
        Variation {
            bias,
            corners,
            r_worst,
        }
    }
}

/// The load's slopes at θ = 0 (module doc): the sine load and the viscous
/// friction.
fn load_slopes(model: &NominalModel) -> [f64; 3] {
    let load = model.load;
    let amp_k = load.amplitude * load.wavenumber;
    let bv = load.friction.map(|f| f.viscous).unwrap_or(0.0);
    let kd = model.params.d_per_torque();
    let jt = model.params.jt;
    [kd * amp_k, amp_k / jt + kd * bv, bv / jt]
}

/// The check made, the verdict and the warning of an unstable loop, from
/// the worst fast eigenvalue and growth (over the corners when the
/// variation is `varied`); `sat`: the boundary-layer law.
fn loop_texts(
    sim: &SimulationCfg,
    sat: bool,
    varied: bool,
    fast_worst: f64,
    growth: f64,
) -> (String, String, Option<String>) {
    let h = sim.step;
    let stable = growth < 1.0;
    let corner_note = if varied {
        " (worst over the corners bias ± |random| of the variation)"
    } else {
        ""
    };
    let check = match sim.mode {
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
    let verdict = match (stable, sat) {
        (true, false) => format!("stable: {what}"),
        (false, false) => format!("unstable: {what}"),
        (true, true) => format!(
            "stable inside the boundary layer: {what}; outside it the law is Theorem 1's sgn law, which no linear check covers: a necessary condition for a smooth loop, not a sufficient one"
        ),
        (false, true) => format!(
            "unstable inside the boundary layer: {what}; u will chatter across the layer as with sgn(σ) (bounded by ±k in continuous mode; a sampled loop can diverge as the sgn law does)"
        ),
    };
    let warning = (!stable).then(|| match sim.mode {
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
    (check, verdict, warning)
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
    super::linalg::eigenvalues4(&mm)
        .map(|ev| ev.iter().map(|z| z.norm()).fold(0.0, f64::max))
        .unwrap_or(f64::INFINITY)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::analyze;

    /// RK4's real-axis limit solves R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 = 1,
    /// i.e. z³/24 + z²/6 + z/2 + 1 = 0: z = −2.785293563 (R(−2.7853) = 1).
    #[test]
    fn rk4_limit() {
        let r = rk4_amplification(Complex::new(RK4_REAL_LIMIT, 0.0));
        assert!((r.re - 1.0).abs() < 1e-12 && r.im.abs() < 1e-15);
        assert!(rk4_amplification(Complex::new(-2.7, 0.0)).norm() < 1.0);
        assert!(rk4_amplification(Complex::new(-2.9, 0.0)).norm() > 1.0);
    }

    fn paper_scenario(set: &[&str]) -> Loop {
        let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        Loop::parse_with("", "<unit>", &set).unwrap()
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
}
