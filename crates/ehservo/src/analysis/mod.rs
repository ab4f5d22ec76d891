//! What the theory says about a scenario before it runs (`ehservo analyze`).
//!
//! [`analyze`] computes, for a built scenario ([`Loop`]):
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

use crate::scenario::{Loop, Scenario};
use ehservo_core::control::sliding::{NnVscConfig, SlidingConfig, VscConfig, VscSatConfig};
use nalgebra::Matrix3;
use serde::Serialize;

mod closed_loop;
mod diagnostics;
mod k1;
mod linalg;
mod poles;
mod report;
mod spectral;
pub mod step;
mod weights;

pub use closed_loop::{rk4_amplification, LoopAnalysis, RK4_REAL_LIMIT};
pub use diagnostics::{diagnostics, f_of, DiagRecorder, DiagSample, RunDiagnostics};
pub use k1::{k1, k1_expm, k1_profile, sylvester_terms, K1, K1_TOLERANCE};
pub use poles::{cubic_roots, open_loop_poles, p_matrix, Pole};
pub use spectral::{SpectralExp, SEPARATION};
pub use weights::{
    invariant_radius, kernel_sq_max, phi_norm_omega, phi_norm_reference, WeightAnalysis, OMEGA_X,
    OMEGA_Z,
};

use closed_loop::loop_analysis;
use weights::weight_analysis;

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

/// Everything [`analyze`] computes.
#[derive(Debug, Clone, Serialize)]
pub struct Analysis {
    /// The axis, `"rotary"` or `"linear"`: b̄ is in rad or m per V·s³, and
    /// d's load is a torque Tl (N·m, Jt the inertia) or a force F (N, Jt
    /// the moving mass M: the cylinder's nominal model, docs/cylinder.md §2).
    pub axis: &'static str,
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

fn fmt_sig(x: f64, n: usize) -> String {
    report::sig(x, n)
}

fn theorem2(s: &Scenario, pm: &Matrix3<f64>, sp: [Pole; 3], surface: [f64; 3]) -> SurfaceAnalysis {
    // A repeated root comes out of the eigenvalue solver split by
    // ~sqrt(ε)·|λ|; the mean of the cluster is accurate to ~ε.
    // Relative to the poles' own size: slow distinct poles are not a cluster.
    let scale = sp.iter().map(|q| q.wn).fold(0.0, f64::max);
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
    let alpha = match paper_law(s) {
        Some((PaperLaw::Nnvsc, c)) => Some(c.alpha),
        _ => None,
    };
    let holds = alpha.map(|al| al > 0.0 && al < bound);
    let decades_over = match (alpha, holds) {
        // As a difference of logs where α/bound overflows (α = 1e308):
        // never "by inf decades".
        (Some(al), Some(false)) if bound > 0.0 && al > 0.0 => Some(match al / bound {
            r if r.is_finite() => r.log10(),
            _ => al.log10() - bound.log10(),
        }),
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
        _ if paper_law(s).is_some() => format!(
            "not applicable: the traditional VSC has no α (Theorem 2 would admit 0 < α < {})",
            fmt_sig(bound, 3)
        ),
        _ => format!(
            "not applicable: controller kind `{}` has no switching surface (for the [surface] shown, Theorem 2 would admit 0 < α < {})",
            s.controller.kind(),
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

/// Which of the paper's laws a scenario runs: the theory of this module
/// is theirs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PaperLaw {
    /// Theorem 1 with sgn(σ).
    Vsc,
    /// Theorem 1 with sat(σ/μ) (Remark 2).
    VscSat,
    /// Theorem 3.
    Nnvsc,
}

/// The paper's law a scenario runs and its `[controller]` table; None for
/// any other controller kind (the theory then does not apply).
pub fn paper_law(s: &Scenario) -> Option<(PaperLaw, &SlidingConfig)> {
    let c = &s.controller;
    c.get::<NnVscConfig>()
        .map(|k| (PaperLaw::Nnvsc, &k.0))
        .or_else(|| c.get::<VscConfig>().map(|k| (PaperLaw::Vsc, &k.0)))
        .or_else(|| c.get::<VscSatConfig>().map(|k| (PaperLaw::VscSat, &k.0)))
}

/// Analyses a built scenario (see the module doc), on the nominal model
/// and the surface its controller was designed with.
pub fn analyze(lp: &Loop) -> Analysis {
    let s = lp.scenario();
    let model = *lp.model();
    let servo = model.params;
    let a = model.coeffs.as_array();
    let surface = lp.design().surface.p();
    let pm = p_matrix(surface);
    // Poles the user gave are exact; the computed roots of p stand in only
    // when p was given (and agree with given poles to round-off otherwise).
    let sp = match s.surface.poles {
        Some(given) => {
            let mut q = given.map(|r| Pole::from(nalgebra::Complex::new(r, 0.0)));
            poles::sort_poles(&mut q);
            q
        }
        None => cubic_roots(surface[0], surface[1], surface[2]),
    };
    Analysis {
        axis: lp.axis().name(),
        a_nominal: a,
        b_at_rest: model.b_at_rest(),
        d_coefficients: [servo.d_per_torque(), 1.0 / servo.jt],
        open_loop_poles: open_loop_poles(a),
        surface: theorem2(s, &pm, sp, surface),
        weights: match paper_law(s) {
            Some((PaperLaw::Nnvsc, c)) => Some(weight_analysis(lp, c)),
            _ => None,
        },
        closed_loop: loop_analysis(lp, &model, surface),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
