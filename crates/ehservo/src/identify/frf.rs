//! The nonparametric frequency response: Welch's averaged periodograms.
//!
//! Each signal is cut into segments of `L` samples overlapping by 50 %,
//! each segment's linear trend removed (an integrating plant's output
//! drifts), multiplied by the periodic Hann window
//! w_n = ½(1 − cos 2πn/L) and transformed (realfft). With X_i, Y_i the
//! segments' transforms, S_xy = Σ_i Y_i·conj(X_i) (the scale cancels in
//! every ratio below), and
//!
//! ```text
//! H1(f)   = S_yu/S_uu                        (open loop, from the command)
//! γ²(f)   = |S_yu|²/(S_uu·S_yy)              coherence
//! H(f)    = S_yr/S_ur                        (closed loop: indirect, from the reference)
//! ```
//!
//! The indirect estimate is the ratio of the two H1 estimates from the
//! reference r (to y and to u): measurement noise fed back into u is not
//! correlated with r, so it does not bias it the way it biases S_yu/S_uu
//! in a closed loop (Ljung 1999, §13.5; R. Pintelon, J. Schoukens,
//! *System Identification: A Frequency Domain Approach*, 2nd ed.,
//! Wiley-IEEE 2012, §2.6). The coherence reported with it is γ² from r
//! to y. Frequencies are k/(L·h), k = 1..L/2 (DC left out).
//!
//! P. D. Welch, "The use of fast Fourier transform for the estimation of
//! power spectra", *IEEE Trans. Audio Electroacoust.* 15(2), 1967.

use realfft::num_complex::Complex64;
use realfft::RealFftPlanner;
use serde::Serialize;

/// A frequency response estimate.
#[derive(Debug, Clone, Serialize)]
pub struct Frf {
    /// Frequencies (Hz).
    pub f_hz: Vec<f64>,
    /// H(f) (output unit per input unit), as (re, im).
    #[serde(skip)]
    pub h: Vec<Complex64>,
    /// Coherence γ² (–).
    pub coherence: Vec<f64>,
    /// Segment length L (samples).
    pub segment: usize,
    /// Segments averaged.
    pub averages: usize,
    /// `"H1"` or `"indirect"`.
    pub method: &'static str,
}

/// The default segment length: the largest power of two with at least
/// eight 50 %-overlapping segments in `n` samples (≥ 16; at most 8192).
pub fn default_segment(n: usize) -> usize {
    let mut l = 16usize;
    while l * 2 <= 8192 && (n.saturating_sub(l * 2)) / l + 1 >= 8 {
        l *= 2;
    }
    l
}

/// The windowed, detrended transforms of the segments of `x`.
fn segments(x: &[f64], l: usize) -> Vec<Vec<Complex64>> {
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(l);
    let w: Vec<f64> = (0..l)
        .map(|n| 0.5 * (1.0 - (2.0 * std::f64::consts::PI * n as f64 / l as f64).cos()))
        .collect();
    let step = l / 2;
    let count = if x.len() >= l {
        (x.len() - l) / step + 1
    } else {
        0
    };
    // Least-squares line over n = 0..L−1: slope = Σ(n − n̄)(x − x̄)/Σ(n − n̄)².
    let nbar = (l as f64 - 1.0) / 2.0;
    let snn: f64 = (0..l).map(|n| (n as f64 - nbar).powi(2)).sum();
    (0..count)
        .map(|i| {
            let s = &x[i * step..i * step + l];
            let xbar = s.iter().sum::<f64>() / l as f64;
            let slope = s
                .iter()
                .enumerate()
                .map(|(n, v)| (n as f64 - nbar) * (v - xbar))
                .sum::<f64>()
                / snn;
            let mut buf: Vec<f64> = s
                .iter()
                .enumerate()
                .map(|(n, v)| (v - xbar - slope * (n as f64 - nbar)) * w[n])
                .collect();
            let mut out = fft.make_output_vec();
            // The lengths are the plan's own: the transform cannot fail.
            fft.process(&mut buf, &mut out)
                .expect("buffers of the plan's length");
            out
        })
        .collect()
}

/// Σ_i a_i·conj(b_i) per frequency bin 1..L/2.
fn cross(a: &[Vec<Complex64>], b: &[Vec<Complex64>], l: usize) -> Vec<Complex64> {
    (1..=l / 2)
        .map(|k| a.iter().zip(b).map(|(x, y)| x[k] * y[k].conj()).sum())
        .collect()
}

/// Welch's H1 estimate of y/u with its coherence (sample period `h`).
pub fn h1(u: &[f64], y: &[f64], h: f64, l: usize) -> Frf {
    let (su, sy) = (segments(u, l), segments(y, l));
    let suu = cross(&su, &su, l);
    let syy = cross(&sy, &sy, l);
    let syu = cross(&sy, &su, l);
    let f_hz = (1..=l / 2).map(|k| k as f64 / (l as f64 * h)).collect();
    let mut hh = Vec::with_capacity(l / 2);
    let mut coh = Vec::with_capacity(l / 2);
    for k in 0..l / 2 {
        let (uu, yy) = (suu[k].re, syy[k].re);
        hh.push(if uu > 0.0 {
            syu[k] / uu
        } else {
            Complex64::new(f64::NAN, f64::NAN)
        });
        coh.push(if uu > 0.0 && yy > 0.0 {
            (syu[k].norm_sqr() / (uu * yy)).min(1.0)
        } else {
            0.0
        });
    }
    Frf {
        f_hz,
        h: hh,
        coherence: coh,
        segment: l,
        averages: su.len(),
        method: "H1",
    }
}

/// The indirect estimate S_yr/S_ur from the reference `r`, with γ² from r to y.
pub fn indirect(r: &[f64], u: &[f64], y: &[f64], h: f64, l: usize) -> Frf {
    let (sr, su, sy) = (segments(r, l), segments(u, l), segments(y, l));
    let srr = cross(&sr, &sr, l);
    let syy = cross(&sy, &sy, l);
    let syr = cross(&sy, &sr, l);
    let sur = cross(&su, &sr, l);
    let f_hz = (1..=l / 2).map(|k| k as f64 / (l as f64 * h)).collect();
    let mut hh = Vec::with_capacity(l / 2);
    let mut coh = Vec::with_capacity(l / 2);
    for k in 0..l / 2 {
        hh.push(if sur[k].norm() > 0.0 {
            syr[k] / sur[k]
        } else {
            Complex64::new(f64::NAN, f64::NAN)
        });
        let (rr, yy) = (srr[k].re, syy[k].re);
        coh.push(if rr > 0.0 && yy > 0.0 {
            (syr[k].norm_sqr() / (rr * yy)).min(1.0)
        } else {
            0.0
        });
    }
    Frf {
        f_hz,
        h: hh,
        coherence: coh,
        segment: l,
        averages: sr.len(),
        method: "indirect",
    }
}

/// Gains (dB) and unwrapped phases (deg) of a response.
pub fn bode(h: &[Complex64]) -> (Vec<f64>, Vec<f64>) {
    let gain = h.iter().map(|z| 20.0 * z.norm().log10()).collect();
    let mut phase = Vec::with_capacity(h.len());
    let mut prev: Option<f64> = None;
    for z in h {
        let mut p = z.arg().to_degrees();
        if let Some(q) = prev.filter(|q| q.is_finite() && p.is_finite()) {
            // The turn that puts p within 180° of q, in one step (no loop
            // whose count grows with the phase already accumulated).
            p -= 360.0 * ((p - q) / 360.0).round();
        }
        prev = Some(p);
        phase.push(p);
    }
    // The whole curve moved by the multiple of 360° that puts its mean in
    // (−360°, 0°] (a bin below the band may have started it a turn off).
    let fin: Vec<f64> = phase.iter().copied().filter(|p| p.is_finite()).collect();
    if !fin.is_empty() {
        let mean = fin.iter().sum::<f64>() / fin.len() as f64;
        let turns = (mean / 360.0).ceil();
        for p in phase.iter_mut() {
            *p -= 360.0 * turns;
        }
    }
    (gain, phase)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// y_k = a·y_{k−1} + c·u_{k−1} driven by white noise: H(z) = c·z⁻¹/(1 − a·z⁻¹),
    /// evaluated at z = e^{j2πf·h}. Without noise the estimate is within
    /// the Hann window's leakage of it and γ² ≈ 1.
    #[test]
    fn h1_recovers_a_first_order_filter() {
        let (a, c, h) = (0.9, 0.5, 1e-3);
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let n = 1 << 16;
        let u: Vec<f64> = (0..n).map(|_| rng.random::<f64>() - 0.5).collect();
        let mut y = vec![0.0; n];
        for k in 1..n {
            y[k] = a * y[k - 1] + c * u[k - 1];
        }
        let l = 1024;
        let e = h1(&u, &y, h, l);
        assert_eq!(e.f_hz.len(), l / 2);
        assert!((e.f_hz[0] - 1.0 / (l as f64 * h)).abs() < 1e-12);
        for (k, f) in e.f_hz.iter().enumerate().step_by(7) {
            let z = Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * f * h);
            let exact = c / z / (1.0 - a / z);
            let rel = (e.h[k] - exact).norm() / exact.norm();
            assert!(rel < 0.03, "f = {f}: {} vs {exact} ({rel})", e.h[k]);
            assert!(e.coherence[k] > 0.98, "f = {f}: γ² = {}", e.coherence[k]);
        }
    }

    /// Closed loop y = G·u measured as y_m = y + n, u = r − y_m: the
    /// measurement noise n is fed back into u, which pulls H1 = S_{y_m u}/S_uu
    /// toward −1/C (here C = 1); the indirect estimate S_{y_m r}/S_ur is not
    /// pulled.
    #[test]
    fn indirect_is_unbiased_in_closed_loop() {
        let (a, c, h) = (0.95, 0.2, 1e-3);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let n = 1 << 16;
        let r: Vec<f64> = (0..n).map(|_| rng.random::<f64>() - 0.5).collect();
        let noise: Vec<f64> = (0..n).map(|_| 0.5 * (rng.random::<f64>() - 0.5)).collect();
        let (mut y, mut u) = (vec![0.0; n], vec![0.0; n]);
        let mut x = 0.0;
        for k in 0..n {
            if k > 0 {
                x = a * x + c * u[k - 1];
            }
            y[k] = x + noise[k];
            u[k] = r[k] - y[k];
        }
        let l = 512;
        let ind = indirect(&r, &u, &y, h, l);
        let direct = h1(&u, &y, h, l);
        let k = 20;
        let f = ind.f_hz[k];
        let z = Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * f * h);
        let exact = c / z / (1.0 - a / z);
        let e_ind = (ind.h[k] - exact).norm() / exact.norm();
        let e_dir = (direct.h[k] - exact).norm() / exact.norm();
        assert!(e_ind < 0.05, "indirect off by {e_ind}, H1 by {e_dir}");
        assert!(e_dir > 3.0 * e_ind, "H1 {e_dir} vs indirect {e_ind}");
    }

    #[test]
    fn segment_default_keeps_eight_averages() {
        assert_eq!(default_segment(20_001), 4096);
        assert_eq!(default_segment(100), 16);
    }
}
