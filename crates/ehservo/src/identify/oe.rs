//! The linear third-order model (8) fitted in continuous time by output
//! error:
//!
//! ```text
//! θ⃛ = −a1·θ − a2·θ̇ − a3·θ̈ + b·(u + u_offset) − d(θ, θ̇)
//! d  = d1·sin(kθ) + d2·cos(kθ)·θ̇          (with --load-terms; else d = 0)
//! ```
//!
//! d is the paper's load term (9) for Tl = A·sin(kθ): d1 = 4βe·Kce·A/(Vt·Jt)
//! (rad/s³) and d2 = A·k/Jt (s⁻²), the wavenumber k given (the prior
//! scenario's `load.wavenumber`). Without them a load is absorbed into the
//! effective a1 (+d1·k) and a2 (+d2) of its linearisation.
//!
//! **The start.** Output error is not convex. The start is the best (by
//! the output-error cost) of the prior scenario's coefficients, the grid
//! of [`grid_start`] (without load terms) and a frequency-domain fit to
//! the nonparametric estimate: Levy's linear least
//! squares on H(jω)·D(jω) = b over the bins with γ² ≥ 0.5 below 0.4× the
//! Nyquist frequency, iterated three times with Sanathanan and Koerner's
//! weights 1/|D_prev(jω)| (E. C. Levy, "Complex-curve fitting", *IRE
//! Trans. Autom. Control* 4, 1959; C. K. Sanathanan, J. Koerner,
//! "Transfer function synthesis as a ratio of two complex polynomials",
//! *IEEE Trans. Autom. Control* 8(1), 1963), with the zero-order hold's
//! half-sample delay taken out first: H_c(jω) ≈ H_d(e^{jωh})·e^{jωh/2}.

use super::data::Experiment;
use super::frf::Frf;
use super::model::{divergence_limit, spectral_radius, substeps, Model, SimOut};
use realfft::num_complex::Complex64;

/// The most implicit-shift QR sweeps a singular value decomposition of a
/// matrix with `n` columns may take: LAPACK's bound of 6 per singular
/// value on each of n (`dbdsqr`'s MAXITR = 6, times n²), and at least 100.
/// nalgebra's `svd` has none and loops forever on some data (a log with a
/// 10⁻²⁰⁰ s period): past the bound the decomposition is `None` and the
/// start it served is not used.
pub fn svd_sweeps(n: usize) -> usize {
    n.saturating_mul(n).saturating_mul(6).max(100)
}

/// The linear model on a set of experiments.
#[derive(Debug, Clone)]
pub struct Linear {
    /// Whether d1, d2 are parameters (indices 4, 5).
    pub load_terms: bool,
    /// The load's wavenumber k (1/rad).
    pub wavenumber: f64,
    /// RK4 steps per sample, per experiment.
    pub substeps: Vec<usize>,
    /// |θ| beyond which a run has diverged.
    pub limit: f64,
}

impl Linear {
    /// Number of model parameters before the nuisance ones.
    pub fn n_model(&self) -> usize {
        if self.load_terms {
            6
        } else {
            4
        }
    }

    /// The model for `experiments`, with substeps from the coefficients `a`.
    pub fn new(experiments: &[Experiment], load_terms: bool, wavenumber: f64, a: [f64; 3]) -> Self {
        let rho = spectral_radius(a);
        Self {
            load_terms,
            wavenumber,
            substeps: experiments.iter().map(|e| substeps(e.h, rho)).collect(),
            limit: divergence_limit(experiments),
        }
    }

    /// θ⃛ at x under the held input `u`.
    #[inline]
    fn jerk(&self, p: &[f64], x: &[f64; 3], u: f64) -> f64 {
        let mut j = -p[0] * x[0] - p[1] * x[1] - p[2] * x[2] + p[3] * u;
        if self.load_terms {
            let (s, c) = (self.wavenumber * x[0]).sin_cos();
            j -= p[4] * s + p[5] * c * x[1];
        }
        j
    }
}

/// One RK4 step of ẋ = f(x) with step `h`.
#[inline]
pub fn rk4(x: &[f64; 3], h: f64, f: impl Fn(&[f64; 3]) -> [f64; 3]) -> [f64; 3] {
    let k1 = f(x);
    let x2 = std::array::from_fn(|i| x[i] + 0.5 * h * k1[i]);
    let k2 = f(&x2);
    let x3 = std::array::from_fn(|i| x[i] + 0.5 * h * k2[i]);
    let k3 = f(&x3);
    let x4 = std::array::from_fn(|i| x[i] + h * k3[i]);
    let k4 = f(&x4);
    std::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}

impl Model for Linear {
    fn simulate(&self, p: &[f64], i: usize, e: &Experiment, out: &mut SimOut) -> bool {
        let nm = self.n_model();
        let u_off = p[nm];
        let theta0 = p[nm + 1 + i];
        let m = self.substeps[i];
        let hs = e.h / m as f64;
        let n = e.len();
        out.y.clear();
        out.v.clear();
        out.p.clear();
        let mut x = [theta0, 0.0, 0.0];
        for k in 0..n {
            out.y.push(x[0]);
            out.v.push(x[1]);
            if k + 1 == n {
                break;
            }
            let u = e.u.values[k] + u_off;
            for _ in 0..m {
                x = rk4(&x, hs, |s| [s[1], s[2], self.jerk(p, s, u)]);
            }
            if !(x.iter().all(|v| v.is_finite()) && x[0].abs() <= self.limit) {
                return false;
            }
        }
        true
    }

    fn has_pressure(&self) -> bool {
        false
    }
}

/// Levy/Sanathanan–Koerner fit of b/(s³ + a3s² + a2s + a1) to `frf`
/// (module doc): `[a1, a2, a3, b]`, or `None` when too few bins are
/// coherent or the fit is not a stable, positive-gain third order.
pub fn frequency_fit(frf: &Frf, h: f64) -> Option<[f64; 4]> {
    let nyq = 0.5 / h;
    let bins: Vec<usize> = (0..frf.f_hz.len())
        .filter(|&k| {
            frf.coherence[k] >= 0.5
                && frf.f_hz[k] < 0.4 * nyq
                && frf.h[k].re.is_finite()
                && frf.h[k].im.is_finite()
        })
        .collect();
    if bins.len() < 4 {
        return None;
    }
    let mut weight: Vec<f64> = vec![1.0; bins.len()];
    let mut sol = None;
    for _ in 0..3 {
        // Rows: Re and Im of H·a1 + H·(jω)·a2 + H·(jω)²·a3 − b = −H·(jω)³.
        let mut a = nalgebra::DMatrix::<f64>::zeros(2 * bins.len(), 4);
        let mut rhs = nalgebra::DVector::<f64>::zeros(2 * bins.len());
        for (r, &k) in bins.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * frf.f_hz[k];
            let hc = frf.h[k] * Complex64::from_polar(1.0, w * h / 2.0);
            let jw = Complex64::new(0.0, w);
            // Each row scaled to unit size by |H|·ω³ and the SK weight.
            let s = weight[r] / (hc.norm() * w.powi(3)).max(f64::MIN_POSITIVE);
            let cols = [hc, hc * jw, hc * jw * jw, Complex64::new(-1.0, 0.0)];
            let y = -hc * jw * jw * jw;
            for (c, v) in cols.iter().enumerate() {
                a[(2 * r, c)] = v.re * s;
                a[(2 * r + 1, c)] = v.im * s;
            }
            rhs[2 * r] = y.re * s;
            rhs[2 * r + 1] = y.im * s;
        }
        // Columns scaled to unit norm before the solve (a1 and a3 differ by
        // ω² in size).
        let norms: Vec<f64> = (0..4)
            .map(|c| a.column(c).norm().max(f64::MIN_POSITIVE))
            .collect();
        for (c, nc) in norms.iter().enumerate() {
            let mut col = a.column_mut(c);
            col /= *nc;
        }
        let x = a
            .try_svd(true, true, f64::EPSILON, svd_sweeps(4))?
            .solve(&rhs, 1e-12)
            .ok()?;
        let p = [
            x[0] / norms[0],
            x[1] / norms[1],
            x[2] / norms[2],
            x[3] / norms[3],
        ];
        if !p.iter().all(|v| v.is_finite()) {
            return None;
        }
        for (r, &k) in bins.iter().enumerate() {
            let jw = Complex64::new(0.0, 2.0 * std::f64::consts::PI * frf.f_hz[k]);
            let d = jw * jw * jw + p[2] * jw * jw + p[1] * jw + p[0];
            let w3 = jw.im.powi(3);
            weight[r] = w3 / d.norm().max(f64::MIN_POSITIVE);
        }
        sol = Some(p);
    }
    let p = sol?;
    (p[1] > 0.0 && p[2] > 0.0 && p[0] > -0.1 * p[1] * p[2] && p[3] != 0.0).then_some(p)
}

/// A start that needs neither the prior nor a coherent frequency
/// response: over a grid of denominators (s + p)·(s² + 2ζω·s + ω²) the
/// output is linear in b, b·u_offset and each experiment's θ0, which are
/// solved by linear least squares (variable projection); the denominator
/// with the least squared output error wins. First p = 0 (a pure
/// integrator, a1 = 0) with ω log-spaced from ω_lo = 2π·2/T (T the
/// shortest record) to 0.4× the Nyquist frequency and ζ from 0.05 to 1;
/// then, at the best (ω, ζ), a real pole p log-spaced from ω_lo/100 to ω
/// (a load stiffness: a1 = p·ω² ≠ 0). Returns `[a1, a2, a3, b]`,
/// u_offset and the θ0s, or `None` when no candidate simulates.
pub fn grid_start(experiments: &[Experiment]) -> Option<([f64; 4], f64, Vec<f64>)> {
    use rayon::prelude::*;
    let h = experiments.iter().map(|e| e.h).fold(0.0f64, f64::max);
    let t = experiments
        .iter()
        .map(|e| e.h * e.len() as f64)
        .fold(f64::INFINITY, f64::min);
    let (lo, hi) = (
        2.0 * std::f64::consts::PI * 2.0 / t,
        2.0 * std::f64::consts::PI * 0.2 / h,
    );
    if !(lo.is_finite() && hi > lo) {
        return None;
    }
    const N_OMEGA: usize = 32;
    const N_POLE: usize = 12;
    const ZETAS: [f64; 4] = [0.05, 0.2, 0.5, 1.0];
    let log_step = |a: f64, b: f64, i: usize, n: usize| a * (b / a).powf(i as f64 / (n - 1) as f64);
    let cands: Vec<(f64, f64, f64)> = (0..N_OMEGA)
        .flat_map(|i| {
            let w = log_step(lo, hi, i, N_OMEGA);
            ZETAS.iter().map(move |&z| (w, z, 0.0))
        })
        .collect();
    let pick = |cands: &[(f64, f64, f64)]| {
        cands
            .par_iter()
            .filter_map(|&(w, z, p)| {
                let a = [p * w * w, w * w + 2.0 * z * w * p, 2.0 * z * w + p];
                grid_candidate(experiments, a).map(|c| (c, (w, z)))
            })
            .min_by(|p, q| p.0 .0.total_cmp(&q.0 .0))
    };
    let (integrator, (w, z)) = pick(&cands)?;
    let poles: Vec<(f64, f64, f64)> = (0..N_POLE)
        .map(|i| (w, z, log_step(lo / 100.0, w, i, N_POLE)))
        .collect();
    let best = match pick(&poles) {
        Some((stiff, _)) if stiff.0 < integrator.0 => stiff,
        _ => integrator,
    };
    Some((best.1, best.2, best.3))
}

/// One denominator of [`grid_start`]: its least squared output error, the
/// coefficients with b solved, u_offset and the θ0s.
type GridFit = (f64, [f64; 4], f64, Vec<f64>);

/// The output error of the denominator s³ + a[2]s² + a[1]s + a[0], with b,
/// b·u_offset and the θ0s solved by linear least squares.
fn grid_candidate(experiments: &[Experiment], a: [f64; 3]) -> Option<GridFit> {
    let ne = experiments.len();
    // The constant command's size: the commands' RMS (keeps the column's
    // scale that of the input's).
    let us = {
        let (s2, n) = experiments.iter().fold((0.0, 0usize), |(s, n), e| {
            (
                s + e.u.values.iter().map(|v| v * v).sum::<f64>(),
                n + e.len(),
            )
        });
        (s2 / n.max(1) as f64).sqrt().max(f64::MIN_POSITIVE)
    };
    let m: usize = experiments.iter().map(Experiment::len).sum();
    let model = Linear::new(experiments, false, 0.0, a);
    // Columns: the response to u (b = 1), to a unit constant
    // command, and each experiment's θ0.
    let mut x = nalgebra::DMatrix::<f64>::zeros(m, 2 + ne);
    let mut y = nalgebra::DVector::<f64>::zeros(m);
    let mut row = 0;
    let mut sim = SimOut::default();
    for (i, e) in experiments.iter().enumerate() {
        let mut p = vec![a[0], a[1], a[2], 1.0, 0.0];
        p.extend(std::iter::repeat_n(0.0, ne));
        if !model.simulate(&p, i, e, &mut sim) {
            return None;
        }
        let g1 = sim.y.clone();
        p[4] = us;
        if !model.simulate(&p, i, e, &mut sim) {
            return None;
        }
        for k in 0..e.len() {
            x[(row + k, 0)] = g1[k];
            x[(row + k, 1)] = sim.y[k] - g1[k];
            x[(row + k, 2 + i)] = 1.0;
            y[row + k] = e.y.values[k];
        }
        row += e.len();
    }
    let c = x
        .clone()
        .try_svd(true, true, f64::EPSILON, svd_sweeps(2 + ne))?
        .solve(&y, 1e-12)
        .ok()?;
    let cost = (&x * &c - &y).norm_squared();
    (cost.is_finite() && c[0].is_finite() && c[0] != 0.0).then(|| {
        (
            cost,
            [a[0], a[1], a[2], c[0]],
            c[1] * us / c[0],
            c.iter().skip(2).copied().collect::<Vec<f64>>(),
        )
    })
}

/// The discrete (zero-order hold) frequency response of the linear model
/// without load terms at `f_hz`: C(zI − Φ)⁻¹Γ at z = e^{j2πfh}, with
/// Φ = e^{Ah} and Γ = ∫₀ʰ e^{As}ds·B from the exponential of the
/// augmented matrix [[A, B], [0, 0]]·h.
pub fn discrete_response(a: [f64; 3], b: f64, h: f64, f_hz: &[f64]) -> Vec<Complex64> {
    let mut m = nalgebra::Matrix4::<f64>::zeros();
    m[(0, 1)] = 1.0;
    m[(1, 2)] = 1.0;
    m[(2, 0)] = -a[0];
    m[(2, 1)] = -a[1];
    m[(2, 2)] = -a[2];
    m[(2, 3)] = b;
    let e = (m * h).exp();
    let phi = e.fixed_view::<3, 3>(0, 0).into_owned();
    let gamma = e.fixed_view::<3, 1>(0, 3).into_owned();
    f_hz.iter()
        .map(|f| {
            let z = Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * f * h);
            let mut zi = nalgebra::Matrix3::<Complex64>::identity() * z;
            zi -= phi.map(|v| Complex64::new(v, 0.0));
            let g = gamma.map(|v| Complex64::new(v, 0.0));
            match zi.lu().solve(&g) {
                Some(x) => x[0],
                None => Complex64::new(f64::NAN, f64::NAN),
            }
        })
        .collect()
}

/// The roots of s³ + a3·s² + a2·s + a1 as a complex pair's natural
/// frequency ω_n (rad/s) and damping ζ and the real root (1/s), when the
/// polynomial has a complex pair.
pub fn pair(a: [f64; 3]) -> Option<(f64, f64, f64)> {
    let m = nalgebra::Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -a[0], -a[1], -a[2]);
    let ev = m.complex_eigenvalues();
    let c = ev.iter().find(|z| z.im > 0.0)?;
    let real = ev
        .iter()
        .min_by(|x, y| x.im.abs().total_cmp(&y.im.abs()))
        .map_or(f64::NAN, |z| z.re);
    let wn = c.norm();
    Some((wn, -c.re / wn, real))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The discrete response at low frequency equals the continuous one
    /// delayed by half a sample: b/(jω)³+… at f = 1 Hz, h = 1 ms.
    #[test]
    fn discrete_response_near_the_continuous() {
        let a = [0.4, 13000.27, 169.98];
        let b = 17911.75;
        let h = 1e-3;
        let f = 1.0;
        let w = 2.0 * std::f64::consts::PI * f;
        let jw = Complex64::new(0.0, w);
        let hc = b / (jw * jw * jw + a[2] * jw * jw + a[1] * jw + a[0]);
        let hd = discrete_response(a, b, h, &[f])[0];
        let shifted = hc * Complex64::from_polar(1.0, -w * h / 2.0);
        assert!(
            (hd - shifted).norm() / hc.norm() < 1e-4,
            "{hd} vs {shifted}"
        );
    }

    /// The frequency-domain start recovers the paper's coefficients from
    /// their exact discrete response (coherence 1) to within the
    /// half-sample approximation of the hold.
    #[test]
    fn frequency_fit_of_an_exact_response() {
        let (a, b, h) = ([0.39982, 13000.2711, 169.98043], 17911.75, 1e-3);
        let f: Vec<f64> = (1..200).map(|k| k as f64 * 0.25).collect();
        let frf = Frf {
            h: discrete_response(a, b, h, &f),
            coherence: vec![1.0; f.len()],
            f_hz: f,
            segment: 4000,
            averages: 1,
            method: "H1",
        };
        let p = frequency_fit(&frf, h).expect("a fit");
        assert!((p[1] / a[1] - 1.0).abs() < 0.01, "{p:?}");
        assert!((p[2] / a[2] - 1.0).abs() < 0.01, "{p:?}");
        assert!((p[3] / b - 1.0).abs() < 0.01, "{p:?}");
    }

    /// (s + 2)(s² + 2·0.3·10·s + 100) = s³ + 8s² + 112s + 200.
    #[test]
    fn pair_of_a_known_cubic() {
        let (wn, z, r) = pair([200.0, 112.0, 8.0]).unwrap();
        assert!((wn - 10.0).abs() < 1e-9 && (z - 0.3).abs() < 1e-9 && (r + 2.0).abs() < 1e-9);
    }
}
