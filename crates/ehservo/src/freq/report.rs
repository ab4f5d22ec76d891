//! `ehservo freq`: the computed and measured frequency responses of a
//! scenario's loop, written whole or not at all (`output::Staging`):
//!
//! - `freq.json` — the operating point, the margins of L with every
//!   crossover, Ms, Mt, the bandwidths, the measured bandwidth and the
//!   margins of the measured loop, the settings;
//! - `linearization.json` — the models (what `ehservo linearize` prints);
//! - `response.csv` — every computed curve on the grid: `f_Hz`,
//!   `omega_rad_s`, then per curve `X_gain_dB`, `X_phase_deg`, `X_re`,
//!   `X_im` (units in `freq.json`'s `curves`);
//! - `measured_<method>.csv` — the measured points with their quality and
//!   the computed values at the same frequencies;
//! - `bode.png/svg`, `nyquist.png/svg`, `measured.png/svg`.
//!
//! A value that does not exist (a curve of a nonlinear controller, a
//! diverged run) is an empty CSV cell and a JSON null, never NaN.
//!
//! Here: the request ([`FreqOptions`], its checks, the bound on the work)
//! and the run; the files in `files`, the measured bandwidth and margins
//! in `measured`, the figures in `figures`.

mod figures;
mod files;
mod measured;

use super::fig;
use super::measure::{self, Broadband, Input, Measured, Settings};
use super::oppoint::At;
use super::response::Discretisation;
use super::ss::C64;
use crate::limits::saturating_sum;
use crate::output::Staging;
use crate::scenario::{Loop, ScenarioError};
use files::write;

/// The work limit of a run, for a whole measurement (evaluations): the
/// run limit of `limits::MAX_RUN_WORK`.
const MAX_WORK: u64 = crate::limits::MAX_RUN_WORK as u64;
use anyhow::{anyhow, Result};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Most points of a computed grid.
pub const MAX_POINTS: usize = 100_000;

/// Most measured frequencies.
pub const MAX_MEASURE_POINTS: usize = 2_000;

/// A measurement method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// One steady sine per frequency.
    Sine,
    /// Welch's H1 on a periodic multisine.
    Multisine,
    /// Welch's H1 on a linear chirp.
    Chirp,
}

impl Method {
    /// The command-line spelling.
    pub fn as_str(&self) -> &'static str {
        match self {
            Method::Sine => "sine",
            Method::Multisine => "multisine",
            Method::Chirp => "chirp",
        }
    }

    /// From the command line's spelling.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "sine" | "sinestream" => Some(Method::Sine),
            "multisine" => Some(Method::Multisine),
            "chirp" => Some(Method::Chirp),
            _ => None,
        }
    }
}

/// What `ehservo freq` is asked for.
#[derive(Debug, Clone)]
pub struct FreqOptions {
    /// The operating point (None: a trim at θd(0)).
    pub at: Option<At>,
    /// The side of a one-sided model at a kink.
    pub side: Option<super::linearize::Side>,
    /// How G is discretised.
    pub discretisation: Discretisation,
    /// The computed grid (Hz): lowest, highest (None: 0.99 of Nyquist), points.
    pub f_min: f64,
    /// Highest computed frequency (Hz).
    pub f_max: Option<f64>,
    /// Computed points.
    pub points: usize,
    /// Measurement methods.
    pub methods: Vec<Method>,
    /// The measured grid (Hz).
    pub measure_f_min: f64,
    /// Highest measured frequency (None: 0.9 of Nyquist).
    pub measure_f_max: Option<f64>,
    /// Measured frequencies (sinestream) or bins (Welch).
    pub measure_points: usize,
    /// The excitation's sizes and timing.
    pub settings: Settings,
    /// Periods (segments) of a Welch measurement.
    pub periods: u64,
    /// Draw the figures.
    pub plots: bool,
    /// The flag the tracking amplitude came from (for its error).
    pub amplitude_flag: &'static str,
}

impl FreqOptions {
    /// The defaults for a scenario of sample period `h`.
    pub fn defaults() -> Self {
        Self {
            at: None,
            side: None,
            discretisation: Discretisation::Zoh,
            f_min: 0.01,
            f_max: None,
            points: 400,
            methods: vec![Method::Sine],
            measure_f_min: 0.1,
            measure_f_max: None,
            measure_points: 40,
            settings: Settings {
                theta0: 0.0,
                amplitude: 0.5 * ehservo_core::math::DR,
                disturbance: 0.05,
                settle_s: 2.0,
                settle_cycles: 2.0,
                cycles: 4,
                min_window: 64,
            },
            periods: 4,
            plots: true,
            amplitude_flag: "--amplitude",
        }
    }
}

/// The frequency range checks (bad input names the flag).
fn check_range(
    file: &str,
    lo: (&str, f64),
    hi: (&str, f64),
    n: (&str, usize, usize),
    nyquist: f64,
    h: f64,
) -> Result<(), ScenarioError> {
    let bad = |k: &str, r: String| Err(super::bad(file, k, r));
    if !(lo.1.is_finite() && lo.1 > 0.0) {
        return bad(lo.0, format!("{}: must be a frequency > 0 Hz", fig(lo.1)));
    }
    if !(hi.1.is_finite() && hi.1 > 0.0) {
        return bad(hi.0, format!("{}: must be a frequency > 0 Hz", fig(hi.1)));
    }
    if hi.1 > nyquist {
        return bad(
            hi.0,
            format!(
                "{} Hz is above the Nyquist frequency {} Hz of simulation.step = {} s",
                fig(hi.1),
                fig(nyquist),
                fig(h)
            ),
        );
    }
    if lo.1 >= hi.1 {
        return bad(
            lo.0,
            format!(
                "{} Hz to {} = {} Hz is an empty frequency range",
                fig(lo.1),
                hi.0,
                fig(hi.1)
            ),
        );
    }
    if n.1 < 2 || n.1 > n.2 {
        return bad(n.0, format!("{}: must be between 2 and {}", n.1, n.2));
    }
    Ok(())
}

/// What was written.
#[derive(Debug, Clone)]
pub struct FreqSummary {
    /// The files, in the output folder.
    pub files: Vec<PathBuf>,
    /// A few lines for the terminal.
    pub text: String,
}

/// A measured set: its method and its two inputs' points.
struct MeasuredSet {
    method: Method,
    tracking: Vec<Measured>,
    disturbance: Vec<Measured>,
    plan: Value,
}

/// Runs `ehservo freq` on a loaded scenario into `dir`.
pub fn freq_to_dir(setup: &Loop, file: &str, o: &FreqOptions, dir: &Path) -> Result<FreqSummary> {
    super::position_loop(setup, file)?;
    let h = setup.sim().step;
    let nyq = 0.5 / h;
    let f_max = o.f_max.unwrap_or(0.99 * nyq);
    check_range(
        file,
        ("--f-min", o.f_min),
        ("--f-max", f_max),
        ("--points", o.points, MAX_POINTS),
        nyq,
        h,
    )?;
    let mf_max = o.measure_f_max.unwrap_or(0.9 * nyq);
    if !o.methods.is_empty() {
        let per = crate::limits::sample_evaluations(setup.sim(), setup.stages());
        check_measure_options(file, o, mf_max, h, per)?;
    }
    // The computed part, where the plant is linearised.
    let computed = match super::oppoint::LinPlant::of(setup) {
        Err(e) => Err(e.reason.to_string()),
        Ok(_) => Ok(super::linearise(
            setup,
            file,
            o.at,
            o.side,
            o.discretisation,
        )?),
    };
    if let Ok(l) = &computed {
        if !super::all_finite(l) {
            return Err(anyhow!("{file}: the linearised models are not finite"));
        }
    }
    let theta0 = match &computed {
        Ok(l) => l.point.position(),
        Err(_) => match o.at {
            Some(At::Trim(t)) | Some(At::Moving(t, _)) => t,
            _ => super::default_at(setup).theta0(),
        },
    };
    let settings = Settings {
        theta0,
        ..o.settings
    };
    // The measured frequencies and the work, bounded before any run.
    let plans = plan_measurements(setup, file, o, mf_max, &settings)?;
    // The output folder is checked before the work.
    let stage = Staging::new(dir)?;
    let mut sets = Vec::new();
    for (m, plan) in plans {
        let set = match plan {
            Plan::Sine(plans) => {
                let (tr, di) = rayon::join(
                    || measure::sinestream_planned(setup, Input::Tracking, &plans, &settings),
                    || measure::sinestream_planned(setup, Input::Disturbance, &plans, &settings),
                );
                MeasuredSet {
                    method: m,
                    tracking: tr,
                    disturbance: di,
                    plan: json!(plans),
                }
            }
            Plan::Welch(plan) => {
                let (tr, di) = measure::welch_both(setup, &plan, &settings);
                MeasuredSet {
                    method: m,
                    tracking: tr,
                    disturbance: di,
                    plan: json!(plan),
                }
            }
        };
        sets.push(set);
    }
    write(setup, o, &computed, &sets, f_max, settings, stage)
}

/// The checked plan of one measurement method.
enum Plan {
    /// One plan per frequency.
    Sine(Vec<measure::SinePlan>),
    /// One long run.
    Welch(measure::WelchPlan),
}

/// The plans of every method, their counts checked (a count that cannot
/// be planned names its flag and figure) and their work, summed with
/// saturating arithmetic over both inputs, within [`MAX_WORK`].
fn plan_measurements(
    setup: &Loop,
    file: &str,
    o: &FreqOptions,
    mf_max: f64,
    settings: &Settings,
) -> Result<Vec<(Method, Plan)>, ScenarioError> {
    let h = setup.sim().step;
    let counted = |e: crate::limits::CountError| super::bad(file, &e.key, e.to_string());
    let mgrid = measure_grid(o, mf_max);
    let mut plans = Vec::new();
    for &m in &o.methods {
        let plan = match m {
            Method::Sine => Plan::Sine(
                mgrid
                    .iter()
                    .map(|&f| measure::plan_sine(f, h, settings))
                    .collect::<Result<_, _>>()
                    .map_err(counted)?,
            ),
            Method::Multisine | Method::Chirp => Plan::Welch(
                measure::plan_welch(
                    if m == Method::Chirp {
                        Broadband::Chirp
                    } else {
                        Broadband::Multisine
                    },
                    o.measure_f_min,
                    mf_max,
                    o.measure_points,
                    o.periods,
                    h,
                    settings.settle_s,
                )
                .map_err(counted)?,
            ),
        };
        plans.push((m, plan));
    }
    // Each input (tracking, disturbance) runs every plan.
    let total = saturating_sum(plans.iter().map(|(_, p)| match p {
        Plan::Sine(v) => saturating_sum(v.iter().map(|p| measure::work(setup, p.samples()))),
        Plan::Welch(p) => measure::work(setup, p.samples()),
    }))
    .saturating_mul(2);
    if total > MAX_WORK {
        let (flag, what) = if o.settings.settle_s > 0.0 && settle_dominates(&plans) {
            ("--settle", "lower --settle")
        } else {
            (
                "--measure-f-min",
                "raise --measure-f-min, lower --measure-points, --cycles or --periods",
            )
        };
        return Err(super::bad(
            file,
            flag,
            format!(
                "the measurement is about {:.2e} law and RK4 evaluations, more than the limit of {:.0e}: {what}",
                total as f64,
                MAX_WORK as f64
            ),
        ));
    }
    Ok(plans)
}

/// Whether the settling samples are most of the plans' samples.
fn settle_dominates(plans: &[(Method, Plan)]) -> bool {
    let (settle, all) = plans.iter().fold((0u64, 0u64), |(s, a), (_, p)| match p {
        Plan::Sine(v) => v.iter().fold((s, a), |(s, a), p| {
            (s.saturating_add(p.settle), a.saturating_add(p.samples()))
        }),
        Plan::Welch(p) => (s.saturating_add(p.settle), a.saturating_add(p.samples())),
    });
    settle > all / 2
}

/// The lowest frequency (Hz) a measured record within [`MAX_WORK`] can
/// resolve for `o`'s methods: a record of `per` evaluations a sample holds
/// at most `N = MAX_WORK / (2·per)` samples (both inputs run it), `N·h`
/// seconds, and must hold whole periods of the frequency: `cycles` plus
/// the 2 settling periods of a sinestream, 4 in each of the `periods`
/// segments of a Welch measurement. Returns the frequency, the record's
/// length (s) and the periods.
fn lowest_resolvable(o: &FreqOptions, per: u64, h: f64) -> (f64, f64, f64) {
    let periods = o
        .methods
        .iter()
        .map(|m| match m {
            Method::Sine => f64::from(o.settings.cycles) + o.settings.settle_cycles,
            Method::Multisine | Method::Chirp => 4.0 * o.periods as f64,
        })
        .fold(0.0, f64::max);
    let record_s = MAX_WORK as f64 / (2.0 * per.max(1) as f64) * h;
    (periods / record_s, record_s, periods)
}

/// The measurement's options: its frequency range and points, the
/// excitation's amplitudes, the settling time, the cycles and the Welch
/// periods, and the lowest frequency a record can resolve (`mf_max` the
/// highest measured frequency, `h` the period, `per` the evaluations of a
/// sample).
fn check_measure_options(file: &str, o: &FreqOptions, mf_max: f64, h: f64, per: u64) -> Result<()> {
    let nyq = 0.5 / h;
    check_range(
        file,
        ("--measure-f-min", o.measure_f_min),
        ("--measure-f-max", mf_max),
        ("--measure-points", o.measure_points, MAX_MEASURE_POINTS),
        nyq,
        h,
    )?;
    let st = &o.settings;
    for (k, v) in [
        (o.amplitude_flag, st.amplitude),
        ("--disturbance", st.disturbance),
    ] {
        if !(v.is_finite() && v > 0.0) {
            Err(super::bad(file, k, format!("{v}: must be > 0")))?;
        }
    }
    if !(st.settle_s.is_finite() && st.settle_s >= 0.0) {
        Err(super::bad(file, "--settle", "must be finite and >= 0"))?;
    }
    if st.cycles == 0 || st.cycles > 10_000 {
        Err(super::bad(file, "--cycles", "must be between 1 and 10000"))?;
    }
    if o.periods < 2 || o.periods > 10_000 {
        Err(super::bad(file, "--periods", "must be between 2 and 10000"))?;
    }
    let (lowest, record_s, periods) = lowest_resolvable(o, per, h);
    if o.measure_f_min < lowest {
        Err(super::bad(
            file,
            "--measure-f-min",
            format!(
                "{} Hz is below what a record can resolve: {:.0e} evaluations at most, {record_s:.3e} s at simulation.step = {} s, must hold {periods} periods; allowed: {lowest:.3e} to {} Hz",
                fig(o.measure_f_min),
                MAX_WORK as f64,
                fig(h),
                fig(nyq)
            ),
        ))?;
    }
    Ok(())
}

/// The measured frequencies (Hz), log-spaced up to `mf_max`; none without
/// a measurement.
fn measure_grid(o: &FreqOptions, mf_max: f64) -> Vec<f64> {
    if o.methods.is_empty() {
        return Vec::new();
    }
    (0..o.measure_points)
        .map(|i| {
            o.measure_f_min
                * (mf_max / o.measure_f_min).powf(i as f64 / (o.measure_points - 1) as f64)
        })
        .collect()
}

impl At {
    /// θ0 of a trim (rad); 0 for a time.
    pub fn theta0(&self) -> f64 {
        match self {
            At::Trim(t) | At::Moving(t, _) => *t,
            At::Time(_) => 0.0,
        }
    }
}

fn db(z: C64) -> f64 {
    20.0 * z.norm().log10()
}

/// Unwrapped phases (deg) of a curve: the principal value at the first
/// point, continuous after it; None where the value is.
fn unwrap(v: &[Option<C64>]) -> Vec<Option<f64>> {
    let mut out = Vec::with_capacity(v.len());
    let mut last: Option<f64> = None;
    for z in v {
        match z {
            Some(z) if z.norm() > 0.0 => {
                let mut p = z.arg().to_degrees();
                if let Some(l) = last {
                    p += 360.0 * ((l - p) / 360.0).round();
                }
                last = Some(p);
                out.push(Some(p));
            }
            _ => out.push(None),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unwrapping keeps the phase continuous across ±180°.
    #[test]
    fn unwrap_is_continuous() {
        let z: Vec<Option<C64>> = [170.0f64, 179.0, -179.0, -170.0, 10.0]
            .iter()
            .map(|d| Some(C64::from_polar(1.0, d.to_radians())))
            .collect();
        let u = unwrap(&z);
        let want = [170.0, 179.0, 181.0, 190.0, 370.0];
        for (a, b) in u.iter().zip(want) {
            assert!((a.unwrap() - b).abs() < 1e-9, "{u:?}");
        }
    }
}
