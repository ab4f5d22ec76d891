//! Goodness of fit: NRMSE, the residuals' whiteness and their
//! cross-correlation with the input, with confidence bands.
//!
//! - NRMSE = 100·‖y − ŷ‖/‖y − ȳ‖ (%), and the "fit" 100 − NRMSE that
//!   MATLAB's `compare` prints (L. Ljung, *System Identification: Theory
//!   for the User*, 2nd ed., Prentice Hall 1999, §16.6).
//! - Whiteness: the normalised autocorrelation r_e(τ) = R_e(τ)/R_e(0),
//!   τ = 1..M, against the band ±z/√N (z = 2.576 for 99 %), and the
//!   Ljung–Box statistic Q = N(N+2)·Σ r_e(τ)²/(N − τ), which a white
//!   residual keeps below the χ²(M) 95 % quantile (G. M. Ljung, G. E. P. Box,
//!   "On a measure of lack of fit in time series models", *Biometrika*
//!   65(2), 1978).
//! - Cross-correlation r_eu(τ) = R_eu(τ)/√(R_e(0)R_u(0)), τ = −M..M, and
//!   the band ±z/√N: residuals independent of past inputs (τ > 0: the input
//!   leads) stay inside it (Ljung 1999, §16.6).

use serde::Serialize;

/// z of the two-sided 99 % normal band (Abramowitz & Stegun, Table 26.1).
pub const Z99: f64 = 2.575_829;
/// z of the two-sided 95 % normal band.
pub const Z95: f64 = 1.959_964;

/// 100·‖y − ŷ‖/‖y − ȳ‖ (%); infinite when y is constant.
pub fn nrmse_pct(y: &[f64], yhat: &[f64]) -> f64 {
    let n = y.len().min(yhat.len());
    if n == 0 {
        return f64::INFINITY;
    }
    let mean = y[..n].iter().sum::<f64>() / n as f64;
    let num: f64 = (0..n).map(|k| (y[k] - yhat[k]).powi(2)).sum();
    let den: f64 = y[..n].iter().map(|v| (v - mean).powi(2)).sum();
    if den > 0.0 {
        100.0 * (num / den).sqrt()
    } else {
        f64::INFINITY
    }
}

/// The χ² quantile of probability p with k degrees of freedom, by Wilson
/// and Hilferty's cube-root normal approximation (E. B. Wilson,
/// M. M. Hilferty, "The distribution of chi-square", *PNAS* 17, 1931):
/// k·(1 − 2/(9k) + z_p·√(2/(9k)))³. Within 0.1 % of the tables for
/// k ≥ 10 at p = 0.95.
pub fn chi2_quantile(k: usize, z_p: f64) -> f64 {
    let k = k.max(1) as f64;
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + z_p * a.sqrt()).powi(3)
}

/// z of the one-sided 95 % normal quantile (for [`chi2_quantile`]).
pub const Z95_ONE_SIDED: f64 = 1.644_854;

/// The residual tests of one experiment.
#[derive(Debug, Clone, Serialize)]
pub struct ResidualTests {
    /// Lags tested, M.
    pub lags: usize,
    /// Samples, N.
    pub samples: usize,
    /// The 99 % band ±2.576/√N of a normalised correlation.
    pub band_99: f64,
    /// r_e(τ), τ = 1..M.
    pub autocorrelation: Vec<f64>,
    /// Largest |r_e(τ)|.
    pub max_abs_autocorrelation: f64,
    /// The Ljung–Box Q over the M lags.
    pub ljung_box_q: f64,
    /// The χ²(M) 95 % quantile.
    pub chi2_95: f64,
    /// Q below the quantile.
    pub white: bool,
    /// r_eu(τ), τ = −M..M.
    pub cross_correlation: Vec<f64>,
    /// Largest |r_eu(τ)|.
    pub max_abs_cross_correlation: f64,
    /// Every |r_eu(τ)| inside the 99 % band.
    pub independent_of_input: bool,
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

/// R_xy(τ) = (1/N)·Σ_k x_{k+τ}·y_k over the overlap (means removed).
fn corr(x: &[f64], y: &[f64], tau: isize) -> f64 {
    let n = x.len().min(y.len());
    let (mut s, mut k) = (0.0, 0usize);
    while k < n {
        let i = k as isize + tau;
        if i >= 0 && (i as usize) < n {
            s += x[i as usize] * y[k];
        }
        k += 1;
    }
    s / n as f64
}

/// The whiteness and input-independence tests of residuals `e` for input `u`.
pub fn residual_tests(e: &[f64], u: &[f64], lags: usize) -> ResidualTests {
    let n = e.len().min(u.len());
    let me = mean(&e[..n]);
    let mu = mean(&u[..n]);
    let e: Vec<f64> = e[..n].iter().map(|v| v - me).collect();
    let u: Vec<f64> = u[..n].iter().map(|v| v - mu).collect();
    let m = lags.min(n.saturating_sub(2)).max(1);
    let r0 = corr(&e, &e, 0);
    let u0 = corr(&u, &u, 0);
    let auto: Vec<f64> = (1..=m)
        .map(|t| {
            if r0 > 0.0 {
                corr(&e, &e, t as isize) / r0
            } else {
                0.0
            }
        })
        .collect();
    let nf = n as f64;
    let q = nf
        * (nf + 2.0)
        * auto
            .iter()
            .enumerate()
            .map(|(i, r)| r * r / (nf - (i + 1) as f64))
            .sum::<f64>();
    let chi2 = chi2_quantile(m, Z95_ONE_SIDED);
    let scale = (r0 * u0).sqrt();
    // τ > 0: e at k + τ against u at k (the input leads the residual).
    let cross: Vec<f64> = (-(m as isize)..=m as isize)
        .map(|t| {
            if scale > 0.0 {
                corr(&e, &u, t) / scale
            } else {
                0.0
            }
        })
        .collect();
    let band = Z99 / nf.sqrt();
    let max_auto = auto.iter().fold(0.0f64, |a, r| a.max(r.abs()));
    let max_cross = cross.iter().fold(0.0f64, |a, r| a.max(r.abs()));
    ResidualTests {
        lags: m,
        samples: n,
        band_99: band,
        autocorrelation: auto,
        max_abs_autocorrelation: max_auto,
        ljung_box_q: q,
        chi2_95: chi2,
        white: q <= chi2,
        cross_correlation: cross,
        max_abs_cross_correlation: max_cross,
        independent_of_input: max_cross <= band,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Published χ² 95 % quantiles (NIST/SEMATECH e-Handbook, Table 1.3.6.7.4):
    /// k = 10: 18.307, k = 25: 37.652, k = 50: 67.505.
    #[test]
    fn chi2_against_the_table() {
        for (k, q) in [(10, 18.307), (25, 37.652), (50, 67.505)] {
            let a = chi2_quantile(k, Z95_ONE_SIDED);
            assert!((a - q).abs() / q < 1e-3, "k = {k}: {a} vs {q}");
        }
    }

    /// NRMSE by hand: y = (1, 2, 3), ŷ = (1, 2, 4): ‖y − ŷ‖ = 1,
    /// ‖y − ȳ‖ = √2, NRMSE = 100/√2 = 70.71 %.
    #[test]
    fn nrmse_by_hand() {
        let v = nrmse_pct(&[1.0, 2.0, 3.0], &[1.0, 2.0, 4.0]);
        assert!((v - 70.710_678).abs() < 1e-5, "{v}");
        assert!(nrmse_pct(&[1.0, 1.0], &[1.0, 1.0]).is_infinite());
    }

    /// White noise passes; a residual that is the input delayed fails both
    /// tests.
    #[test]
    fn white_passes_and_coloured_fails() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let n = 4000;
        let u: Vec<f64> = (0..n).map(|_| rng.random::<f64>() - 0.5).collect();
        let e: Vec<f64> = (0..n).map(|_| rng.random::<f64>() - 0.5).collect();
        let t = residual_tests(&e, &u, 25);
        assert!(t.white, "Q = {} vs {}", t.ljung_box_q, t.chi2_95);
        assert!(t.independent_of_input, "{}", t.max_abs_cross_correlation);
        // e_k = u_{k−2} + 0.3·noise: correlated with the input at τ = 2,
        // and (u being white) still white: the cross test must fail.
        let e2: Vec<f64> = (0..n)
            .map(|k| if k >= 2 { u[k - 2] } else { 0.0 } + 0.3 * e[k])
            .collect();
        let t2 = residual_tests(&e2, &u, 25);
        assert!(!t2.independent_of_input);
        // The peak sits at τ = +2, index M + 2.
        let peak = t2
            .cross_correlation
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .unwrap()
            .0;
        assert_eq!(peak, 25 + 2);
        // A moving average is not white.
        let ma: Vec<f64> = (1..n).map(|k| e[k] + e[k - 1]).collect();
        assert!(!residual_tests(&ma, &u[1..], 25).white);
    }
}
