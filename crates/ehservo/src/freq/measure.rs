//! Frequency responses measured on the simulator, for any controller (the
//! NNBVSC and the other nonlinear laws included): the scenario's own
//! `Simulation` — plant, variation, actuator, sensors, estimator, sampled
//! controller — excited about a constant reference θ0 (the trim angle) by
//!
//! - a **tracking** input: the reference `θd = θ0 + e(t)` with its
//!   derivatives exact (`z = (θd, ė, ë, e⃛)`), measuring θ/θd;
//! - a **disturbance** d(t) added to the controller's command (V) before
//!   the valve range, held with it by the sampled loop (and delayed with it
//!   by a computation delay): an input ("load") disturbance. Measured: θ/d,
//!   and S = u/d where u is the whole command (law + d), so that
//!   `L = 1/S − 1` is the loop measured at the plant's input. The
//!   disturbance is added by wrapping the controller ([`Disturbed`]); no
//!   scenario key is needed.
//!
//! Two methods:
//!
//! - **sinestream** (as Simulink's `frestimate`): one run per frequency, a
//!   steady sine `e(t) = A·sin ωt`; after a settling time, M whole periods
//!   in N samples (the frequency is moved to `M/(N·h)`, the nearest one with
//!   a whole number of periods in a whole number of samples, so the Fourier
//!   coefficient has no leakage) give `Y(ω)/X(ω)` from the samples θ_k, u_k.
//!   Its quality index, the **fundamental fraction**, is the share of the
//!   output's variance (over the window, mean removed) at the excited
//!   frequency: 1 for a linear loop in steady state; harmonics, noise,
//!   chattering or drift lower it.
//! - **Welch's H1** with its **coherence**, from one long run: a periodic
//!   multisine (Schroeder phases, period N samples, components on
//!   log-spaced bins of N) averaged over whole periods (boxcar windows, no
//!   overlap: no leakage for the periodic steady state), or a linear chirp
//!   with Hann windows overlapping by half. `H1 = Σ X̄·Y / Σ |X|²`,
//!   `γ² = |Σ X̄·Y|² / (Σ|X|²·Σ|Y|²)` over the segments; the spectra by
//!   realfft.
//!
//! Frequencies (sinestream) and the two inputs (Welch) run in parallel
//! with rayon, each a pure function of the scenario and its frequency,
//! collected in order: the same numbers on any thread count. The work is
//! bounded before any run (`scenario::MAX_WORK` per measurement).

use super::ss::C64;
use crate::limits::{count_from_f64, sample_evaluations, work_of, CountError};
use crate::plant::Plant;
use crate::scenario::{ControllerConfig, Loop, LoopPlant, LoopVisit, Typed};
use crate::simulation::{Simulation, Stop};
use ehservo_core::control::{Controller, Measurement, Output, Truth};
use ehservo_core::reference::{Chirp, Reference};
use rayon::prelude::*;
use realfft::RealFftPlanner;
use serde::Serialize;
use std::f64::consts::PI;
use std::sync::Arc;

/// What is excited.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Input {
    /// The reference.
    Tracking,
    /// A disturbance on the command.
    Disturbance,
}

/// An excitation signal e(t) with its first three derivatives.
#[derive(Debug, Clone, PartialEq)]
pub enum Excitation {
    /// Nothing.
    None,
    /// `A·sin(ω·t)`.
    Sine {
        /// Amplitude.
        amp: f64,
        /// rad/s.
        w: f64,
    },
    /// `Σ A_i·sin(ω_i·t + φ_i)`.
    Multisine(Vec<(f64, f64, f64)>),
    /// A linear chirp starting at `t0` (zero before).
    Chirp {
        /// The sweep.
        chirp: Chirp,
        /// Its start (s).
        t0: f64,
    },
}

impl Excitation {
    /// `(e, ė, ë, e⃛)` at t.
    pub fn z(&self, t: f64) -> [f64; 4] {
        match self {
            Excitation::None => [0.0; 4],
            Excitation::Sine { amp, w } => {
                let (s, c) = (w * t).sin_cos();
                [amp * s, amp * w * c, -amp * w * w * s, -amp * w * w * w * c]
            }
            Excitation::Multisine(comps) => {
                let mut z = [0.0; 4];
                for &(a, w, p) in comps {
                    let (s, c) = (w * t + p).sin_cos();
                    z[0] += a * s;
                    z[1] += a * w * c;
                    z[2] -= a * w * w * s;
                    z[3] -= a * w * w * w * c;
                }
                z
            }
            Excitation::Chirp { chirp, t0 } => {
                if t < *t0 {
                    [0.0; 4]
                } else {
                    chirp.z(t - t0)
                }
            }
        }
    }
}

/// The reference `θ0 + e(t)`.
#[derive(Debug, Clone)]
pub struct Excited {
    /// θ0 (rad).
    pub theta0: f64,
    /// e (rad).
    pub e: Arc<Excitation>,
}

impl Reference for Excited {
    #[inline]
    fn z(&self, t: f64) -> [f64; 4] {
        let mut z = self.e.z(t);
        z[0] += self.theta0;
        z
    }
}

/// A controller whose command gets `d(t)` (V) added, at the sample's time:
/// what the sampled loop holds, clamps to the valve range and (with a
/// computation delay) delays is the law's command plus d. The law's own
/// state sees only its own command (an ADRC's observer does not see d).
#[derive(Debug, Clone)]
pub struct Disturbed<C> {
    /// The law.
    pub inner: C,
    /// d (V).
    pub d: Arc<Excitation>,
}

impl<C: Controller> Controller for Disturbed<C> {
    type State = C::State;
    type Parts = C::Parts;
    fn initial_state(&self) -> C::State {
        self.inner.initial_state()
    }
    fn initial_state_at(&self, x: &[f64; 3]) -> C::State {
        self.inner.initial_state_at(x)
    }
    #[inline]
    fn law(&self, m: &Measurement, s: &C::State, ds: &mut C::State) -> Output<C::Parts> {
        let mut o = self.inner.law(m, s, ds);
        o.u += self.d.z(m.t)[0];
        o
    }
    fn weights<'a>(&self, s: &'a C::State) -> &'a [f64] {
        self.inner.weights(s)
    }
    fn annotate(&self, s: &C::State, out: &mut Output<C::Parts>, truth: &dyn Truth) {
        self.inner.annotate(s, out, truth)
    }
}

/// Settings of a measurement.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Settings {
    /// The constant reference the loop is excited about (rad).
    pub theta0: f64,
    /// Amplitude of the tracking excitation (rad).
    pub amplitude: f64,
    /// Amplitude of the disturbance (V).
    pub disturbance: f64,
    /// Settling time before the window (s); at least `settle_cycles` periods.
    pub settle_s: f64,
    /// Settling periods (sinestream).
    pub settle_cycles: f64,
    /// Periods in the window (sinestream), at least.
    pub cycles: u32,
    /// Fewest samples in a window (sinestream).
    pub min_window: u64,
}

/// What a run records over its window.
#[derive(Debug, Clone, Default)]
pub struct Record {
    /// θ_k − θ0 (rad), the true plant.
    pub theta: Vec<f64>,
    /// The whole command u_k (V).
    pub u: Vec<f64>,
    /// The excitation at t_k.
    pub input: Vec<f64>,
    /// When the run diverged (s), if it did.
    pub diverged_at_s: Option<f64>,
}

/// The loop of `setup` run for `steps` samples under the excitation,
/// recording the samples `skip..steps`.
pub fn run(
    setup: &Loop,
    input: Input,
    e: Arc<Excitation>,
    s: &Settings,
    skip: u64,
    steps: u64,
) -> Record {
    setup.simulate(Runner {
        setup,
        input,
        e,
        theta0: s.theta0,
        skip,
        steps,
    })
}

struct Runner<'a> {
    setup: &'a Loop,
    input: Input,
    e: Arc<Excitation>,
    theta0: f64,
    skip: u64,
    steps: u64,
}

/// The scenario's own plant and controller, typed (θ is the plant's
/// position on its axis).
impl LoopVisit for Runner<'_> {
    type Out = Record;
    fn visit<P: LoopPlant, K: ControllerConfig>(self, t: Typed<'_, P, K>) -> Record {
        let (plant, ctrl) = (t.plant, t.controller);
        match self.input {
            Input::Tracking => self.go(
                plant,
                ctrl,
                Excited {
                    theta0: self.theta0,
                    e: self.e.clone(),
                },
            ),
            Input::Disturbance => self.go(
                plant,
                Disturbed {
                    inner: ctrl,
                    d: self.e.clone(),
                },
                Excited {
                    theta0: self.theta0,
                    e: Arc::new(Excitation::None),
                },
            ),
        }
    }
}

impl Runner<'_> {
    fn go<P: Plant, C: Controller>(&self, plant: P, ctrl: C, reference: Excited) -> Record {
        let s = self.setup;
        let settings = s
            .settings()
            .clone()
            .with_steps(self.steps)
            .with_x0([self.theta0, 0.0, 0.0]);
        let mut sim = Simulation::from_settings(plant, ctrl, reference, settings);
        let n = (self.steps - self.skip) as usize;
        let mut r = Record {
            theta: Vec::with_capacity(n),
            u: Vec::with_capacity(n),
            input: Vec::with_capacity(n),
            diverged_at_s: None,
        };
        let h = s.sim().step;
        while let Some(smp) = sim.step() {
            if smp.k >= self.skip && smp.k < self.steps {
                r.theta.push(smp.x[0] - self.theta0);
                r.u.push(smp.u);
                r.input.push(self.e.z(smp.k as f64 * h)[0]);
            }
        }
        if let Some(Stop::Diverged(d)) = sim.stopped() {
            r.diverged_at_s = Some(d.t);
        }
        r
    }
}

/// The Fourier coefficient `Σ x_k·e^{−j2π·m·k/n}` of a window of `n`
/// samples at bin `m` (a single-bin DFT: the correlation with the
/// excited frequency).
pub fn coefficient(x: &[f64], m: u64) -> C64 {
    let n = x.len() as f64;
    let mut acc = C64::new(0.0, 0.0);
    for (k, &v) in x.iter().enumerate() {
        // The angle reduced exactly in integers before the float product.
        let idx = ((k as u128 * m as u128) % x.len() as u128) as f64;
        acc += C64::from_polar(v, -2.0 * PI * idx / n);
    }
    acc
}

/// The fraction of the variance of `x` (mean removed) at bin `m`.
pub fn fundamental_fraction(x: &[f64], m: u64) -> f64 {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var: f64 = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    let c = coefficient(x, m);
    let at = 2.0 * c.norm_sqr() / (n * n);
    if var > 0.0 {
        (at / var).min(1.0)
    } else {
        0.0
    }
}

/// One frequency of a sinestream.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SinePlan {
    /// The frequency measured (Hz): `cycles/(window·h)`.
    #[serde(rename = "f_Hz")]
    pub f_hz: f64,
    /// Periods in the window.
    pub cycles: u64,
    /// Samples in the window.
    pub window: u64,
    /// Samples before it.
    pub settle: u64,
}

/// The plan of a sinestream at `f` Hz: at least `cycles` periods and
/// `min_window` samples in the window, the frequency moved to the nearest
/// whole number of periods in a whole number of samples. A count beyond
/// what a plan can hold is refused with the flag that asked for it
/// (`--measure-f-min` for the window, `--settle` or `--measure-f-min` for
/// the settling).
pub fn plan_sine(f: f64, h: f64, s: &Settings) -> Result<SinePlan, CountError> {
    let per = 1.0 / (f * h); // samples per period
    let window = count_from_f64(
        "--measure-f-min",
        "samples in a sine's window",
        (f64::from(s.cycles) * per).round(),
    )?
    .max(s.min_window);
    let cycles = count_from_f64(
        "--measure-f-min",
        "periods in a sine's window",
        (f * h * window as f64).round(),
    )?
    .max(1);
    let f_hz = cycles as f64 / (window as f64 * h);
    let by_cycles = s.settle_cycles / f_hz;
    let (key, settle_t) = if s.settle_s >= by_cycles {
        ("--settle", s.settle_s)
    } else {
        ("--measure-f-min", by_cycles)
    };
    Ok(SinePlan {
        f_hz,
        cycles,
        window,
        settle: count_from_f64(key, "settling samples", (settle_t / h).ceil())?,
    })
}

impl SinePlan {
    /// Samples in the run: the settling and the window (saturating).
    pub fn samples(&self) -> u64 {
        self.settle.saturating_add(self.window)
    }
}

/// One measured point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Measured {
    /// Frequency (Hz).
    #[serde(rename = "f_Hz")]
    pub f_hz: f64,
    /// θ/θd (tracking) — or θ/d for a disturbance (rad/V).
    pub theta: Option<[f64; 2]>,
    /// u/d = S (disturbance only).
    pub s: Option<[f64; 2]>,
    /// The quality: the fundamental fraction (sinestream, the least of the
    /// outputs) or the coherence γ² (Welch).
    pub quality: f64,
    /// The coherence of u/d (Welch, disturbance).
    pub quality_s: Option<f64>,
    /// When the run diverged (s).
    pub diverged_at_s: Option<f64>,
}

impl Measured {
    /// θ's response as a complex number.
    pub fn theta_c(&self) -> Option<C64> {
        self.theta.map(|p| C64::new(p[0], p[1]))
    }
    /// S as a complex number.
    pub fn s_c(&self) -> Option<C64> {
        self.s.map(|p| C64::new(p[0], p[1]))
    }
}

/// The work of a plan of `samples` samples, in evaluations (the law, the
/// plant's RK4 sub-steps, an estimator's sub-steps: as
/// [`crate::limits::sample_evaluations`] counts them), saturating.
pub fn work(setup: &Loop, samples: u64) -> u64 {
    work_of(samples, sample_evaluations(setup.sim(), setup.stages()))
}

/// A sinestream at `freqs` (Hz) of one input: one run per frequency, in
/// parallel, in order (a count that cannot be planned is refused before
/// any run).
pub fn sinestream(
    setup: &Loop,
    input: Input,
    freqs: &[f64],
    s: &Settings,
) -> Result<Vec<Measured>, CountError> {
    let h = setup.sim().step;
    let plans = freqs
        .iter()
        .map(|&f| plan_sine(f, h, s))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(sinestream_planned(setup, input, &plans, s))
}

/// A sinestream of checked plans (one run per plan, in parallel, in
/// order).
pub fn sinestream_planned(
    setup: &Loop,
    input: Input,
    plans: &[SinePlan],
    s: &Settings,
) -> Vec<Measured> {
    plans
        .par_iter()
        .map(|p| {
            let w = 2.0 * PI * p.f_hz;
            let amp = match input {
                Input::Tracking => s.amplitude,
                Input::Disturbance => s.disturbance,
            };
            let e = Arc::new(Excitation::Sine { amp, w });
            let r = run(setup, input, e, s, p.settle, p.samples());
            sine_point(p, input, &r)
        })
        .collect()
}

fn sine_point(p: &SinePlan, input: Input, r: &Record) -> Measured {
    if r.diverged_at_s.is_some() || r.theta.len() != p.window as usize {
        return Measured {
            f_hz: p.f_hz,
            theta: None,
            s: None,
            quality: 0.0,
            quality_s: None,
            diverged_at_s: r.diverged_at_s,
        };
    }
    let m = p.cycles;
    let x = coefficient(&r.input, m);
    let y = coefficient(&r.theta, m);
    let mut quality = fundamental_fraction(&r.theta, m);
    let s = match input {
        Input::Tracking => None,
        Input::Disturbance => {
            quality = quality.min(fundamental_fraction(&r.u, m));
            let u = coefficient(&r.u, m);
            Some(u / x)
        }
    };
    let th = y / x;
    Measured {
        f_hz: p.f_hz,
        theta: Some([th.re, th.im]),
        s: s.map(|z| [z.re, z.im]),
        quality,
        quality_s: None,
        diverged_at_s: None,
    }
}

/// Welch's excitation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Broadband {
    /// A periodic multisine.
    Multisine,
    /// A linear chirp.
    Chirp,
}

/// The plan of a Welch measurement.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WelchPlan {
    /// The excitation.
    pub kind: Broadband,
    /// Samples per segment (the multisine's period), a power of two.
    pub nperseg: u64,
    /// Whole periods (multisine) or the sweep's length in segments (chirp).
    pub periods: u64,
    /// Samples before the first segment.
    pub settle: u64,
    /// The bins reported (and, for the multisine, excited).
    pub bins: Vec<u64>,
}

impl WelchPlan {
    /// Samples in the run.
    pub fn samples(&self) -> u64 {
        self.settle
            .saturating_add(work_of(self.periods, self.nperseg))
    }
}

/// The plan over `[f_lo, f_hi]` Hz: segments of a power of two samples,
/// at least 4 periods of `f_lo` (and `4·points`), `periods` of them after
/// the settling time; `points` log-spaced bins. A count beyond what a plan
/// can hold is refused with its flag (`--measure-f-min`, `--settle`).
pub fn plan_welch(
    kind: Broadband,
    f_lo: f64,
    f_hi: f64,
    points: usize,
    periods: u64,
    h: f64,
    settle_s: f64,
) -> Result<WelchPlan, CountError> {
    let need = (4.0 / (f_lo * h)).max(4.0 * points as f64);
    let key = "--measure-f-min";
    let nperseg = count_from_f64(key, "samples per segment", need.ceil())?;
    // ≤ 2⁵³, so its next power of two is at most 2⁵³ too.
    let nperseg = nperseg.next_power_of_two().max(64);
    let df = 1.0 / (nperseg as f64 * h);
    let k_lo = count_from_f64(key, "bins below it", (f_lo / df).ceil())?.max(1);
    let k_hi = count_from_f64("--measure-f-max", "bins below it", (f_hi / df).floor())?
        .min(nperseg / 2 - 1)
        .max(k_lo);
    let mut bins: Vec<u64> = (0..points.max(1))
        .map(|i| {
            let r = if points > 1 {
                i as f64 / (points - 1) as f64
            } else {
                0.0
            };
            // Between k_lo and k_hi, both counts.
            (k_lo as f64 * (k_hi as f64 / k_lo as f64).powf(r)).round() as u64
        })
        .collect();
    bins.dedup();
    Ok(WelchPlan {
        kind,
        nperseg,
        periods: periods.max(2),
        settle: count_from_f64("--settle", "settling samples", (settle_s / h).ceil())?,
        bins,
    })
}

/// The excitation of a plan: the multisine with amplitude `amp` at its
/// samples' peak, or the chirp over the segments.
pub fn broadband(plan: &WelchPlan, amp: f64, h: f64) -> Excitation {
    let n = plan.nperseg as f64;
    match plan.kind {
        Broadband::Multisine => {
            let k = plan.bins.len() as f64;
            let comps: Vec<(f64, f64, f64)> = plan
                .bins
                .iter()
                .enumerate()
                .map(|(i, &b)| {
                    // Schroeder's phases for equal amplitudes.
                    let i = i as f64 + 1.0;
                    (1.0, 2.0 * PI * b as f64 / (n * h), -PI * i * (i - 1.0) / k)
                })
                .collect();
            let e = Excitation::Multisine(comps.clone());
            let peak = (0..plan.nperseg)
                .map(|j| e.z(j as f64 * h)[0].abs())
                .fold(0.0, f64::max);
            let scale = if peak > 0.0 { amp / peak } else { 0.0 };
            Excitation::Multisine(comps.iter().map(|&(a, w, p)| (a * scale, w, p)).collect())
        }
        Broadband::Chirp => {
            let df = 1.0 / (n * h);
            let f0 = plan.bins[0] as f64 * df;
            let f1 = plan.bins[plan.bins.len() - 1] as f64 * df;
            let dur = plan.periods as f64 * n * h;
            Excitation::Chirp {
                chirp: Chirp::try_new(amp, f0, f1, dur).expect("a checked plan"),
                t0: plan.settle as f64 * h,
            }
        }
    }
}

/// Welch's averaged spectra at the plan's bins: `(H1, γ²)` of y over x.
pub fn welch(plan: &WelchPlan, x: &[f64], y: &[f64]) -> Vec<(C64, f64)> {
    let n = plan.nperseg as usize;
    let (window, step): (Vec<f64>, usize) = match plan.kind {
        Broadband::Multisine => (vec![1.0; n], n),
        Broadband::Chirp => (
            (0..n)
                .map(|i| 0.5 - 0.5 * (2.0 * PI * i as f64 / n as f64).cos())
                .collect(),
            n / 2,
        ),
    };
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(n);
    let mut buf = fft.make_input_vec();
    let mut sx = fft.make_output_vec();
    let mut sy = fft.make_output_vec();
    let nb = plan.bins.len();
    let (mut pxy, mut pxx, mut pyy) = (vec![C64::new(0.0, 0.0); nb], vec![0.0; nb], vec![0.0; nb]);
    let mut start = 0;
    while start + n <= x.len().min(y.len()) {
        for (b, (v, w)) in buf.iter_mut().zip(x[start..start + n].iter().zip(&window)) {
            *b = v * w;
        }
        fft.process(&mut buf, &mut sx)
            .expect("sizes from the planner");
        for (b, (v, w)) in buf.iter_mut().zip(y[start..start + n].iter().zip(&window)) {
            *b = v * w;
        }
        fft.process(&mut buf, &mut sy)
            .expect("sizes from the planner");
        for (i, &k) in plan.bins.iter().enumerate() {
            let (a, b) = (sx[k as usize], sy[k as usize]);
            pxy[i] += a.conj() * b;
            pxx[i] += a.norm_sqr();
            pyy[i] += b.norm_sqr();
        }
        start += step;
    }
    (0..nb)
        .map(|i| {
            let h1 = if pxx[i] > 0.0 {
                pxy[i] / pxx[i]
            } else {
                C64::new(f64::NAN, f64::NAN)
            };
            let g = if pxx[i] > 0.0 && pyy[i] > 0.0 {
                (pxy[i].norm_sqr() / (pxx[i] * pyy[i])).min(1.0)
            } else {
                0.0
            };
            (h1, g)
        })
        .collect()
}

/// A Welch measurement of one input.
pub fn welch_measure(setup: &Loop, input: Input, plan: &WelchPlan, s: &Settings) -> Vec<Measured> {
    let h = setup.sim().step;
    let amp = match input {
        Input::Tracking => s.amplitude,
        Input::Disturbance => s.disturbance,
    };
    let e = Arc::new(broadband(plan, amp, h));
    let r = run(setup, input, e, s, plan.settle, plan.samples());
    let df = 1.0 / (plan.nperseg as f64 * h);
    if r.diverged_at_s.is_some() || (r.theta.len() as u64) < work_of(plan.periods, plan.nperseg) {
        return plan
            .bins
            .iter()
            .map(|&k| Measured {
                f_hz: k as f64 * df,
                theta: None,
                s: None,
                quality: 0.0,
                quality_s: None,
                diverged_at_s: r.diverged_at_s,
            })
            .collect();
    }
    let th = welch(plan, &r.input, &r.theta);
    let su = match input {
        Input::Disturbance => Some(welch(plan, &r.input, &r.u)),
        Input::Tracking => None,
    };
    plan.bins
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            let (h1, g) = th[i];
            Measured {
                f_hz: k as f64 * df,
                theta: h1.re.is_finite().then_some([h1.re, h1.im]),
                s: su.as_ref().and_then(|v| {
                    let z = v[i].0;
                    z.re.is_finite().then_some([z.re, z.im])
                }),
                quality: g,
                quality_s: su.as_ref().map(|v| v[i].1),
                diverged_at_s: None,
            }
        })
        .collect()
}

/// The two inputs of a Welch measurement, in parallel.
pub fn welch_both(setup: &Loop, plan: &WelchPlan, s: &Settings) -> (Vec<Measured>, Vec<Measured>) {
    rayon::join(
        || welch_measure(setup, Input::Tracking, plan, s),
        || welch_measure(setup, Input::Disturbance, plan, s),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The coefficient of A·sin(2π·m·k/n + φ) at bin m is
    /// (n/2)·A·e^{j(φ − π/2)}, and no other bin sees it.
    #[test]
    fn coefficient_of_a_sine_by_hand() {
        let (n, m, a, phi) = (240usize, 7u64, 0.3, 0.4);
        let x: Vec<f64> = (0..n)
            .map(|k| a * (2.0 * PI * m as f64 * k as f64 / n as f64 + phi).sin())
            .collect();
        let c = coefficient(&x, m);
        let want = C64::from_polar(n as f64 / 2.0 * a, phi - PI / 2.0);
        assert!((c - want).norm() < 1e-11, "{c} vs {want}");
        assert!(coefficient(&x, m + 1).norm() < 1e-11);
        assert!((fundamental_fraction(&x, m) - 1.0).abs() < 1e-12);
        // Half the variance in a third harmonic of equal amplitude.
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(k, v)| v + a * (2.0 * PI * 3.0 * m as f64 * k as f64 / n as f64).sin())
            .collect();
        assert!((fundamental_fraction(&y, m) - 0.5).abs() < 1e-12);
    }

    /// The plan moves the frequency to a whole number of periods: at
    /// h = 0.01 s, 3 Hz has 33.3 samples per period; 4 periods round to
    /// 133 samples, 3.99 → 4 periods, f = 4/1.33 = 3.00752 Hz.
    #[test]
    fn sine_plan_by_hand() {
        let s = Settings {
            theta0: 0.0,
            amplitude: 0.01,
            disturbance: 0.01,
            settle_s: 1.0,
            settle_cycles: 2.0,
            cycles: 4,
            min_window: 10,
        };
        let p = plan_sine(3.0, 0.01, &s).unwrap();
        assert_eq!((p.window, p.cycles), (133, 4));
        assert!((p.f_hz - 4.0 / 1.33).abs() < 1e-12);
        assert_eq!(p.settle, 100);
    }

    /// Welch's H1 of y = a scaled, delayed copy of a periodic multisine is
    /// the scale times e^{−jωτ} at every excited bin, with coherence 1.
    #[test]
    fn welch_of_a_delay_by_hand() {
        let h = 0.01;
        let plan = plan_welch(Broadband::Multisine, 0.5, 20.0, 12, 4, h, 0.0).unwrap();
        let e = broadband(&plan, 1.0, h);
        let n = plan.samples() as usize;
        let x: Vec<f64> = (0..n).map(|k| e.z(k as f64 * h)[0]).collect();
        let d = 3usize; // samples of delay (the multisine is periodic)
        let y: Vec<f64> = (0..n)
            .map(|k| 2.5 * e.z((k as f64 - d as f64) * h)[0])
            .collect();
        for (i, (h1, g)) in welch(&plan, &x, &y).iter().enumerate() {
            let w = 2.0 * PI * plan.bins[i] as f64 / (plan.nperseg as f64 * h);
            let want = C64::from_polar(2.5, -w * d as f64 * h);
            assert!(
                (h1 - want).norm() < 1e-9,
                "bin {}: {h1} vs {want}",
                plan.bins[i]
            );
            assert!((g - 1.0).abs() < 1e-9);
        }
    }
}
