//! `ehservo excite`: an identification experiment, written twice: as a
//! CSV signal for a rig (`excitation.csv`: `t_s,u_V` in open loop,
//! `t_s,reference_rad` in closed loop) and as a scenario that simulates the
//! same experiment on the prior's plant (`scenario.toml`, with
//! `reference.csv` beside it when the signal is a table).
//!
//! Signals, sampled at `rate` (Hz) over `duration` (s):
//!
//! - `chirp`: A·sin φ(t), the frequency swept linearly from f0 to f1 (the
//!   scenario uses the `chirp` reference kind, the same formula);
//! - `multisine`: Σ_k A_k·sin(2πk·f_r·t + φ_k) over every harmonic k·f_r of
//!   the period's resolution f_r = rate/period in [f0, f1], equal
//!   amplitudes, with Schroeder's phases φ_k = −πk(k−1)/K (M. R. Schroeder,
//!   "Synthesis of low-peak-factor signals and binary sequences with low
//!   autocorrelation", *IEEE Trans. Inf. Theory* 16(1), 1970, eq. 11) or
//!   phases whose crest factor is minimised by Van der Ouderaa,
//!   Schoukens and Renneboog's iteration (clip the time signal at a level
//!   below its peak, restore the amplitude spectrum, keep the new phases,
//!   up to 200 times, the best kept: "Peak factor minimization using a
//!   time-frequency domain swapping algorithm", *IEEE Trans. Instrum.
//!   Meas.* 37(1), 1988); scaled so that its peak is A;
//! - `prbs`: a maximum-length binary sequence ±A of an LFSR of order n,
//!   one bit every `clock` samples (feedback taps from P. Alfke, "Efficient
//!   shift registers, LFSR counters, and long pseudo-random sequence
//!   generators", Xilinx XAPP 052, 1996, Table 3);
//! - `steps`: levels drawn uniformly in [−A, A] (seeded ChaCha8), each held
//!   `hold` s.
//!
//! Closed loop (`--loop closed`): the signal is the reference (rad) of a
//! proportional controller u = kp·(r − θ) (the scenario's `pid` kind with
//! ki = kd = 0 and no feedforward), which keeps an integrating servo in
//! range. kp defaults to a fifth of the prior's stability limit of the
//! continuous loop, kp_max = (a2·a3 − a1)/b (Routh–Hurwitz on
//! s³ + a3s² + a2s + a1 + b·kp).
//!
//! On a linear axis (a cylinder prior) the same in its units: the
//! closed loop's reference in m (`reference_m`, the scenario's table in
//! mm), kp in V/m; the open loop's table holds the command in V as mm at
//! `volts_per_mm` = 1 (the open loop's gain on a linear axis).
//!
//! The design is simulated on the prior's linear model before it is
//! written: the predicted peak |θ| is reported and sets the scenario's
//! `theta_limit` (at least the prior's, three times the peak).

use super::oe::rk4;
use crate::error::InputError;
use anyhow::Result;
use ehservo_sim::axis::Axis;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use realfft::num_complex::Complex64;
use realfft::RealFftPlanner;
use serde::Serialize;
use std::fmt::Write as _;

/// The kinds of signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Signal {
    /// A linear frequency sweep.
    Chirp,
    /// A sum of harmonics with low crest factor.
    Multisine,
    /// A maximum-length pseudo-random binary sequence.
    Prbs,
    /// Random steps.
    Steps,
}

/// Multisine phases.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Phases {
    /// Schroeder's formula.
    Schroeder,
    /// Crest factor minimised (clipping iteration from Schroeder's).
    Crest,
}

/// Open or closed loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Loop {
    /// The signal is the valve command (V).
    Open,
    /// The signal is the reference (rad) of a proportional controller.
    Closed,
}

/// An experiment's design.
#[derive(Debug, Clone, Serialize)]
pub struct Spec {
    /// The signal.
    pub signal: Signal,
    /// Open or closed loop.
    pub loop_kind: Loop,
    /// Peak amplitude A (V open loop, rad closed loop).
    pub amplitude: f64,
    /// Band start (Hz): chirp, multisine.
    pub f0: f64,
    /// Band end (Hz): chirp, multisine.
    pub f1: f64,
    /// Duration (s).
    pub duration: f64,
    /// Sample rate (Hz).
    pub rate: f64,
    /// Multisine period (samples).
    pub period: usize,
    /// Multisine phases.
    pub phases: Phases,
    /// PRBS order n (register length).
    pub order: u32,
    /// PRBS samples per bit.
    pub clock: usize,
    /// Steps: hold time (s).
    pub hold: f64,
    /// Seed (steps).
    pub seed: u64,
    /// Proportional gain (V/rad), closed loop; default from the prior.
    pub kp: Option<f64>,
}

/// Most samples of a design: 2·10⁶.
pub const MAX_SAMPLES: usize = 2_000_000;

/// XAPP 052 Table 3: taps (1-based) of maximum-length XNOR/XOR LFSRs.
const TAPS: &[(u32, &[u32])] = &[
    (3, &[3, 2]),
    (4, &[4, 3]),
    (5, &[5, 3]),
    (6, &[6, 5]),
    (7, &[7, 6]),
    (8, &[8, 6, 5, 4]),
    (9, &[9, 5]),
    (10, &[10, 7]),
    (11, &[11, 9]),
    (12, &[12, 6, 4, 1]),
    (13, &[13, 4, 3, 1]),
    (14, &[14, 5, 3, 1]),
    (15, &[15, 14]),
    (16, &[16, 15, 13, 4]),
    (17, &[17, 14]),
    (18, &[18, 11]),
];

fn bad(msg: String) -> anyhow::Error {
    anyhow::Error::from(InputError::Request(msg))
}

/// The designed signal and what describes it.
#[derive(Debug, Clone, Serialize)]
pub struct Design {
    /// The samples (V or rad), one per 1/rate s.
    #[serde(skip)]
    pub values: Vec<f64>,
    /// Multisine frequencies (Hz).
    pub frequencies_hz: Vec<f64>,
    /// Multisine phases (rad).
    pub phases_rad: Vec<f64>,
    /// Peak |value|.
    pub peak: f64,
    /// RMS.
    pub rms: f64,
    /// Crest factor peak/RMS.
    pub crest_factor: f64,
    /// Clipping iterations run (crest-factor phases).
    pub iterations: usize,
}

/// Checks the spec before any work.
pub fn check(s: &Spec) -> Result<usize> {
    let pos = |k: &str, v: f64| -> Result<f64> {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(bad(format!("--{k} {v}: must be finite and > 0")))
        }
    };
    pos("rate", s.rate)?;
    pos("duration", s.duration)?;
    pos("amplitude", s.amplitude)?;
    let n = (s.duration * s.rate).round() + 1.0;
    if n > MAX_SAMPLES as f64 {
        return Err(bad(format!(
            "--duration {} at --rate {}: {n} samples, more than the limit of {MAX_SAMPLES}",
            s.duration, s.rate
        )));
    }
    let n = n as usize;
    let nyq = s.rate / 2.0;
    if matches!(s.signal, Signal::Chirp | Signal::Multisine) {
        pos("f0", s.f0)?;
        pos("f1", s.f1)?;
        if s.f1 >= nyq {
            return Err(bad(format!(
                "--f1 {} Hz: the excitation band reaches the Nyquist frequency {nyq} Hz of --rate {} Hz",
                s.f1, s.rate
            )));
        }
        if s.f0 >= s.f1 {
            return Err(bad(format!(
                "--f0 {} Hz: must be below --f1 {} Hz",
                s.f0, s.f1
            )));
        }
    }
    if s.signal == Signal::Multisine {
        if s.period < 16 || s.period > n {
            return Err(bad(format!(
                "--period {}: a multisine period must be 16 to {n} samples (the whole duration)",
                s.period
            )));
        }
        let fr = s.rate / s.period as f64;
        if (s.f1 / fr).floor() < (s.f0 / fr).ceil() {
            return Err(bad(format!(
                "--f0 {} .. --f1 {} Hz: no harmonic of the period's resolution {fr} Hz in the band: widen it or lengthen --period",
                s.f0, s.f1
            )));
        }
    }
    if s.signal == Signal::Prbs {
        if !TAPS.iter().any(|t| t.0 == s.order) {
            return Err(bad(format!(
                "--order {}: a PRBS order must be 3 to 18",
                s.order
            )));
        }
        if s.clock == 0 || s.clock > n {
            return Err(bad(format!(
                "--clock {}: must be 1 to {n} samples",
                s.clock
            )));
        }
    }
    if s.signal == Signal::Steps {
        pos("hold", s.hold)?;
        if s.hold < 1.0 / s.rate {
            return Err(bad(format!(
                "--hold {} s: shorter than a sample (1/{} s)",
                s.hold, s.rate
            )));
        }
    }
    if let Some(k) = s.kp {
        pos("kp", k)?;
    }
    Ok(n)
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

fn peak(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

/// One period of the multisine with harmonics `ks` and phases `ph` (unit amplitude).
fn period_of(l: usize, ks: &[usize], ph: &[f64]) -> Vec<f64> {
    let mut planner = RealFftPlanner::<f64>::new();
    let inv = planner.plan_fft_inverse(l);
    let mut spec = inv.make_input_vec();
    for (&k, &p) in ks.iter().zip(ph) {
        // x_n = Σ sin(2πkn/L + p) = Σ Re(e^{j(2πkn/L + p − π/2)}): bin k of
        // the inverse real transform (which sums X_k·e^{j2πkn/L} + c.c.).
        spec[k] = Complex64::from_polar(0.5, p - std::f64::consts::FRAC_PI_2);
    }
    let mut out = inv.make_output_vec();
    inv.process(&mut spec, &mut out)
        .expect("buffers of the plan's length");
    out
}

/// The designed signal.
pub fn design(s: &Spec) -> Result<Design> {
    let n = check(s)?;
    let h = 1.0 / s.rate;
    let (mut values, freqs, phases, iterations) = match s.signal {
        Signal::Chirp => (chirp(s, n, h)?, vec![], vec![], 0),
        Signal::Multisine => multisine(s, n),
        Signal::Prbs => (prbs(s, n), vec![], vec![], 0),
        Signal::Steps => (steps(s, n), vec![], vec![], 0),
    };
    // Scaled to the peak A (a chirp is A·sin φ as its reference kind is).
    let pk = if s.signal == Signal::Chirp {
        1.0
    } else {
        peak(&values)
    };
    if pk.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(bad("the designed signal is zero everywhere".into()));
    }
    for v in values.iter_mut() {
        *v *= s.amplitude / pk;
    }
    let (p, r) = (peak(&values), rms(&values));
    Ok(Design {
        values,
        frequencies_hz: freqs,
        phases_rad: phases,
        peak: p,
        rms: r,
        crest_factor: p / r,
        iterations,
    })
}

/// `n` samples of the unit chirp from f0 to f1, as the chirp reference is.
fn chirp(s: &Spec, n: usize, h: f64) -> Result<Vec<f64>> {
    let c = ehservo_core::reference::Chirp::try_new(1.0, s.f0, s.f1, s.duration)
        .map_err(|e| bad(format!("chirp: {e}")))?;
    use ehservo_core::reference::Reference;
    Ok((0..n).map(|k| c.z(k as f64 * h)[0]).collect::<Vec<f64>>())
}

/// `n` samples of the multisine: the harmonics of the period between f0
/// and f1 with Schroeder's phases, or the crest-minimised ones; also its
/// frequencies (Hz), phases (rad) and the iterations that minimised them.
fn multisine(s: &Spec, n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>, usize) {
    let l = s.period;
    let fr = s.rate / l as f64;
    let ks: Vec<usize> = ((s.f0 / fr).ceil() as usize..=(s.f1 / fr).floor() as usize)
        .filter(|&k| k >= 1 && k < l / 2)
        .collect();
    let kk = ks.len() as f64;
    let mut ph: Vec<f64> = (1..=ks.len())
        .map(|i| -std::f64::consts::PI * (i as f64) * (i as f64 - 1.0) / kk)
        .collect();
    let mut iters = 0;
    if s.phases == Phases::Crest {
        (ph, iters) = crest_phases(l, &ks, ph);
    }
    let one = period_of(l, &ks, &ph);
    (
        (0..n).map(|k| one[k % l]).collect(),
        ks.iter().map(|&k| k as f64 * fr).collect(),
        ph,
        iters,
    )
}

/// The phases of harmonics `ks` of period `l` that minimise the crest
/// factor, from Schroeder's `ph`: 200 rounds of clipping at 90 % of the
/// peak and keeping the phases the clipping gives; the best seen, and the
/// rounds made.
fn crest_phases(l: usize, ks: &[usize], mut ph: Vec<f64>) -> (Vec<f64>, usize) {
    let mut iters = 0;
    let mut planner = RealFftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(l);
    let mut best = (
        peak(&period_of(l, ks, &ph)) / rms(&period_of(l, ks, &ph)),
        ph.clone(),
    );
    for it in 0..200 {
        iters = it + 1;
        let mut x = period_of(l, ks, &ph);
        let (p, r) = (peak(&x), rms(&x));
        if p / r < best.0 {
            best = (p / r, ph.clone());
        }
        // Clip at 90 % of the peak, keep the phases the clipping gives.
        let c = 0.9 * p;
        for v in x.iter_mut() {
            *v = v.clamp(-c, c);
        }
        let mut spec = fwd.make_output_vec();
        fwd.process(&mut x, &mut spec)
            .expect("buffers of the plan's length");
        for (i, &k) in ks.iter().enumerate() {
            ph[i] = spec[k].arg() + std::f64::consts::FRAC_PI_2;
        }
    }
    let x = period_of(l, ks, &ph);
    if peak(&x) / rms(&x) < best.0 {
        best = (peak(&x) / rms(&x), ph.clone());
    }
    (best.1, iters)
}

/// `n` samples of the maximum-length sequence of the register's order,
/// ±1, each bit held `clock` samples.
fn prbs(s: &Spec, n: usize) -> Vec<f64> {
    let taps = TAPS
        .iter()
        .find(|t| t.0 == s.order)
        .map(|t| t.1)
        .unwrap_or(&[]);
    let mut reg: u32 = (1u32 << s.order) - 1;
    let mut bits = Vec::with_capacity(n / s.clock + 1);
    while bits.len() * s.clock < n {
        bits.push(reg & 1);
        // XOR of the taps (1-based from the output end), shifted in.
        let fb = taps
            .iter()
            .fold(0u32, |a, &t| a ^ ((reg >> (s.order - t)) & 1));
        reg = (reg >> 1) | (fb << (s.order - 1));
    }
    (0..n)
        .map(|k| if bits[k / s.clock] == 1 { 1.0 } else { -1.0 })
        .collect()
}

/// `n` samples of random levels in [−1, 1), each held `hold` seconds
/// (seeded ChaCha8).
fn steps(s: &Spec, n: usize) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(s.seed);
    let per = (s.hold * s.rate).round().max(1.0) as usize;
    let levels: Vec<f64> = (0..n / per + 1)
        .map(|_| 2.0 * rng.random::<f64>() - 1.0)
        .collect();
    (0..n).map(|k| levels[k / per]).collect()
}

/// The default proportional gain: a fifth of (a2·a3 − a1)/b.
pub fn default_kp(a: [f64; 3], b: f64) -> f64 {
    0.2 * (a[1] * a[2] - a[0]) / b
}

/// Peak |θ| of the prior's effective linear model under the design (open
/// loop: the command; closed loop: the reference under u = kp·(r − θ)).
pub fn predicted_peak(a: [f64; 3], b: f64, values: &[f64], h: f64, kp: Option<f64>) -> f64 {
    let rho = super::model::spectral_radius(a).max(kp.map_or(0.0, |k| (b * k).abs().cbrt()));
    let m = super::model::substeps(h, rho);
    let hs = h / m as f64;
    let mut x = [0.0f64; 3];
    let mut pk = 0.0f64;
    for &v in values {
        let u = match kp {
            Some(k) => k * (v - x[0]),
            None => v,
        };
        for _ in 0..m {
            x = rk4(&x, hs, |s| {
                [s[1], s[2], -a[0] * s[0] - a[1] * s[1] - a[2] * s[2] + b * u]
            });
        }
        if !x[0].is_finite() {
            return f64::INFINITY;
        }
        pk = pk.max(x[0].abs());
    }
    pk
}

mod write;
pub use write::{excite_to_dir, Written};

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(signal: Signal) -> Spec {
        Spec {
            signal,
            loop_kind: Loop::Open,
            amplitude: 0.1,
            f0: 0.5,
            f1: 20.0,
            duration: 4.095,
            rate: 1000.0,
            period: 1024,
            phases: Phases::Schroeder,
            order: 7,
            clock: 3,
            hold: 0.1,
            seed: 1,
            kp: None,
        }
    }

    /// A multisine has exactly the harmonics asked for: its spectrum over
    /// one period is zero outside the band and equal inside; the crest
    /// factor of Schroeder's phases is well below a zero-phase sum's √(2K)
    /// (its peak K·A over its RMS A·√(K/2)), and the clipping iteration
    /// does not make it worse.
    #[test]
    fn multisine_band_and_crest() {
        let s = spec(Signal::Multisine);
        let d = design(&s).unwrap();
        let fr = 1000.0 / 1024.0;
        let k0 = (0.5f64 / fr).ceil() as usize;
        let k1 = (20.0f64 / fr).floor() as usize;
        assert_eq!(d.frequencies_hz.len(), k1 - k0 + 1);
        let mut planner = RealFftPlanner::<f64>::new();
        let fwd = planner.plan_fft_forward(1024);
        let mut x = d.values[..1024].to_vec();
        let mut spec_ = fwd.make_output_vec();
        fwd.process(&mut x, &mut spec_).unwrap();
        let inband = spec_[k0].norm();
        for (k, z) in spec_.iter().enumerate() {
            if (k0..=k1).contains(&k) {
                assert!((z.norm() - inband).abs() < 1e-9 * inband, "k = {k}");
            } else {
                assert!(z.norm() < 1e-9 * inband, "k = {k}: {}", z.norm());
            }
        }
        let kk = (k1 - k0 + 1) as f64;
        assert!(
            d.crest_factor < 0.5 * (2.0 * kk).sqrt(),
            "{}",
            d.crest_factor
        );
        assert!((d.peak - 0.1).abs() < 1e-12);
        let c = design(&Spec {
            phases: Phases::Crest,
            ..s
        })
        .unwrap();
        assert!(
            c.crest_factor <= d.crest_factor + 1e-12,
            "{} vs {}",
            c.crest_factor,
            d.crest_factor
        );
    }

    /// An order-7 maximum-length sequence repeats after 2⁷ − 1 = 127 bits
    /// and has 64 ones and 63 zeros per period.
    #[test]
    fn prbs_is_maximum_length() {
        let s = Spec {
            clock: 1,
            duration: 0.253,
            ..spec(Signal::Prbs)
        };
        let d = design(&s).unwrap();
        let v = &d.values;
        assert!(v.len() >= 254);
        for k in 0..127 {
            assert_eq!(v[k].to_bits(), v[k + 127].to_bits(), "k = {k}");
        }
        let ones = v[..127].iter().filter(|x| **x > 0.0).count();
        assert_eq!(ones, 64);
        // No shorter period.
        for p in 1..127 {
            assert!(
                (0..127).any(|k| v[k].to_bits() != v[k + p].to_bits()),
                "period {p}"
            );
        }
    }

    #[test]
    fn bad_bands_are_refused() {
        let e = design(&Spec {
            f1: 600.0,
            ..spec(Signal::Chirp)
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("Nyquist"), "{e}");
        let e = design(&Spec {
            f0: 30.0,
            ..spec(Signal::Chirp)
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("below --f1"), "{e}");
        let e = design(&Spec {
            order: 40,
            ..spec(Signal::Prbs)
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("order"), "{e}");
    }

    /// The P loop's limit by hand for the paper's servo: (13000.27·169.98 −
    /// 0.4)/17911.75 = 123.37 V/rad; the default is a fifth, 24.67.
    #[test]
    fn default_gain_of_the_paper_servo() {
        let k = default_kp([0.39982, 13000.2711, 169.98043], 17911.75);
        assert!((k - 24.674).abs() < 0.01, "{k}");
    }
}
