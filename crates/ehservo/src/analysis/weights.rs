//! The weights (Remark 6): ‖Φ‖ along the reference and over the compact set
//! Ω of Section IV, the largest Σφ_j² over a box, the radius of the
//! invariant set of W̃ = W̄ − W and the ball that the law (26) keeps.

use super::fmt_sig;
use super::k1::golden_max;
use crate::scenario::{Loop, Scenario};
use ehservo_core::control::sliding::SlidingConfig;
use ehservo_core::rbf::Rbf;
use ehservo_core::reference::Reference;
use serde::Serialize;

/// The compact set Ω of Section IV: |x1| ≤ 2 rad, |x2| ≤ 4 rad/s,
/// |x3| ≤ 16 rad/s².
pub const OMEGA_X: [f64; 3] = [2.0, 4.0, 16.0];

/// The compact set Ω of Section IV: |z| ≤ 30, read as the Euclidean norm of
/// z = (θd, θ̇d, θ̈d, θ⃛d) (the paper writes |x1| for scalars, |z| for the
/// vector).
pub const OMEGA_Z: f64 = 30.0;

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

/// Σ_l exp(−2(u − c_l)²/δ²): one axis's factor of Σ_j φ_j² (the kernels
/// are products over the axes, so their squares are too).
fn axis_sq_sum(levels: &[f64], width: f64, u: f64) -> f64 {
    levels
        .iter()
        .map(|c| (-2.0 * (u - c) * (u - c) / (width * width)).exp())
        .sum()
}

/// [`axis_sq_sum`] at four points, the same bits: each level's four
/// exponentials in one `exp4` (glibc's `exp` in four lanes where it has
/// the platform's bits), summed in the same order.
fn axis_sq_sum4(levels: &[f64], width: f64, u: [f64; 4]) -> [f64; 4] {
    // `Iterator::sum` of f64 folds from −0.0.
    let mut acc = [-0.0; 4];
    for c in levels {
        let e = super::spectral::exp4(u.map(|u| -2.0 * (u - c) * (u - c) / (width * width)));
        for k in 0..4 {
            acc[k] += e[k];
        }
    }
    acc
}

/// The largest Σ_j φ_j(x)² over the box |x_a| ≤ bound_a (physical units),
/// and where: the product over the axes of each axis's largest factor.
///
/// Each axis: the better box edge, a grid of 4001 points over the levels'
/// reach ±4δ (clipped to the box) and a golden-section refinement around
/// the best. The grid's best and the refinement depend on the axis only
/// through the clipping, so axes whose boxes reach past the levels (all
/// three of Ω in Section IV) share one computation: the same numbers, a
/// third of the exponentials.
pub fn kernel_sq_max(rbf: &Rbf, bound: [f64; 3]) -> (f64, [f64; 3]) {
    let levels = rbf.levels();
    let w = rbf.width();
    let scale = rbf.scale();
    let lmin = levels.iter().copied().fold(f64::INFINITY, f64::min);
    let lmax = levels.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let f = |u: f64| axis_sq_sum(&levels, w, u);
    let n = 4000;
    // (lo, hi) → the first grid point with the grid's largest value.
    let mut grid_memo: Option<((f64, f64), (f64, f64))> = None;
    // Refinement bracket → golden section's result.
    let mut golden_memo: Option<((f64, f64), (f64, f64))> = None;
    let mut prod = 1.0;
    let mut arg = [0.0; 3];
    for a in 0..3 {
        let b = bound[a] / scale[a];
        let (lo, hi) = ((lmin - 4.0 * w).max(-b), (lmax + 4.0 * w).min(b));
        let (mut bu, mut bv) = if f(-b) >= f(b) {
            (-b, f(-b))
        } else {
            (b, f(b))
        };
        if hi > lo {
            let h = (hi - lo) / n as f64;
            let (gu, gv) = match grid_memo {
                Some((key, best)) if key == (lo, hi) => best,
                _ => {
                    let (mut gu, mut gv) = (lo, f64::NEG_INFINITY);
                    let at = |i: usize| lo + h * i as f64;
                    // Four points at a time, then the rest one by one; in
                    // order, the first of equal values kept.
                    let mut i = 0;
                    while i + 4 <= n + 1 {
                        let u: [f64; 4] = std::array::from_fn(|k| at(i + k));
                        for (u, v) in u.into_iter().zip(axis_sq_sum4(&levels, w, u)) {
                            if v > gv {
                                (gu, gv) = (u, v);
                            }
                        }
                        i += 4;
                    }
                    for u in (i..=n).map(at) {
                        let v = f(u);
                        if v > gv {
                            (gu, gv) = (u, v);
                        }
                    }
                    grid_memo = Some(((lo, hi), (gu, gv)));
                    (gu, gv)
                }
            };
            // The edge stands unless a grid point beats it (the first
            // grid point with the grid's largest value then wins).
            if gv > bv {
                (bu, bv) = (gu, gv);
            }
            let bracket = ((bu - h).max(-b), (bu + h).min(b));
            let (u, v) = match golden_memo {
                Some((key, best)) if key == bracket => best,
                _ => {
                    let best = golden_max(f, bracket.0, bracket.1);
                    golden_memo = Some((bracket, best));
                    best
                }
            };
            if v > bv {
                (bu, bv) = (u, v);
            }
        }
        prod *= bv;
        arg[a] = bu * scale[a];
    }
    (prod, arg)
}

/// Largest ‖Φ‖ and ‖z‖ along the reference over one period (of a sine; the
/// whole horizon for another kind), with the state
/// on the reference (perfect tracking).
pub fn phi_norm_reference(lp: &Loop) -> (f64, f64) {
    let Ok(rbf) = sliding(lp.scenario()).rbf.build() else {
        return (f64::NAN, f64::NAN);
    };
    let r = lp.reference();
    // One period of a sine (as it always was), else the whole horizon,
    // finer.
    let period = lp.reference_span();
    let n = if r.as_sine().is_some() { 2000 } else { 20_000 };
    (0..n).fold((1.0, 0.0), |(pm, zm), i| {
        let z = r.z(period * i as f64 / n as f64);
        let nrm = rbf.phi_norm(&[z[0], z[1], z[2]], &z);
        let zn = z.iter().map(|v| v * v).sum::<f64>().sqrt();
        (f64::max(pm, nrm), f64::max(zm, zn))
    })
}

/// Largest ‖Φ‖ over Ω of Section IV: sqrt(1 + sup_Ω Σφ_j² + [`OMEGA_Z`]²).
pub fn phi_norm_omega(s: &Scenario) -> f64 {
    let Ok(rbf) = sliding(s).rbf.build() else {
        return f64::NAN;
    };
    (1.0 + kernel_sq_max(&rbf, OMEGA_X).0 + OMEGA_Z * OMEGA_Z).sqrt()
}

/// The scenario's sliding-mode table (the paper's defaults for any other
/// controller kind, whose network this is not).
fn sliding(s: &Scenario) -> SlidingConfig {
    super::paper_law(s).map(|(_, c)| *c).unwrap_or_default()
}

/// Remark 6: r(‖Φ‖) = Wmax/2 + sqrt(Wmax²/4 + (ε0‖Φ‖ + ε1)/η); None
/// (unbounded) for η = 0.
pub fn invariant_radius(eta: f64, w_max: f64, eps0: f64, eps1: f64, phi_norm: f64) -> Option<f64> {
    (eta > 0.0).then(|| w_max / 2.0 + (w_max * w_max / 4.0 + (eps0 * phi_norm + eps1) / eta).sqrt())
}

pub(super) fn weight_analysis(lp: &Loop, c: &SlidingConfig) -> WeightAnalysis {
    let (pref, zref) = phi_norm_reference(lp);
    let pom = phi_norm_omega(lp.scenario());
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

#[cfg(test)]
mod tests {
    use super::*;
    use ehservo_core::rbf::N_PHI;

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

    /// The four-point sum gives the one-point sum's bits, near the levels
    /// (the vector exp's range) and far from them (exponents below −512,
    /// where it falls back to four calls), on the paper's levels and on
    /// levels of another count.
    #[test]
    fn axis_sum_four_at_a_time_is_one_at_a_time() {
        let paper = Rbf::paper();
        let odd = [-1.5, -0.2, 0.3, 0.9, 1.7, 2.2, 4.0];
        for (levels, w) in [
            (paper.levels().to_vec(), paper.width()),
            (odd.to_vec(), 0.37),
        ] {
            for u in [
                [-3.0, -1.0, 0.0, 0.2],
                [0.123_456_789, 1.0e-9, -2.5, 2.75],
                [-40.0, 0.5, 40.0, 1e3],
                [-1e3, -1e3, -1e3, -1e3],
            ] {
                let four = axis_sq_sum4(&levels, w, u);
                for k in 0..4 {
                    let one = axis_sq_sum(&levels, w, u[k]);
                    assert_eq!(four[k].to_bits(), one.to_bits(), "u = {}", u[k]);
                }
            }
        }
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
}
