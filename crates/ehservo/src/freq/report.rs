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

use super::margins::{self, Margins};
use super::measure::{self, Broadband, Input, Measured, Settings};
use super::oppoint::At;
use super::response::{Discretisation, Responses, CURVES};
use super::ss::C64;
use super::{linearisation_json, Linearised};
use crate::output::Staging;
use crate::plot::{color, ensure_font, png_file, FAMILY};
use crate::scenario::{Scenario, ScenarioError, Setup};

/// The work limit of a run, for a whole measurement.
const MAX_WORK: f64 = 4.0e8;
use anyhow::{anyhow, Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::fmt::Write as _;
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
        }
    }
}

/// The frequency range checks (bad input names the flag).
fn check_range(
    s: &Scenario,
    file: &str,
    lo: (&str, f64),
    hi: (&str, f64),
    n: (&str, usize, usize),
    nyquist: f64,
    h: f64,
) -> Result<(), ScenarioError> {
    let bad = |k: &str, r: String| Err(super::bad(s, file, k, r));
    if !(lo.1.is_finite() && lo.1 > 0.0) {
        return bad(lo.0, format!("{}: must be a frequency > 0 Hz", lo.1));
    }
    if !(hi.1.is_finite() && hi.1 > 0.0) {
        return bad(hi.0, format!("{}: must be a frequency > 0 Hz", hi.1));
    }
    if hi.1 > nyquist {
        return bad(
            hi.0,
            format!(
                "{} Hz is above the Nyquist frequency {nyquist} Hz of simulation.step = {h} s",
                hi.1
            ),
        );
    }
    if lo.1 >= hi.1 {
        return bad(
            lo.0,
            format!(
                "{} Hz to {} = {} Hz is an empty frequency range",
                lo.1, hi.0, hi.1
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
pub fn freq_to_dir(s: &Scenario, file: &str, o: &FreqOptions, dir: &Path) -> Result<FreqSummary> {
    let setup = s.setup()?;
    let h = setup.sim.step;
    let nyq = 0.5 / h;
    let f_max = o.f_max.unwrap_or(0.99 * nyq);
    check_range(
        s,
        file,
        ("--f-min", o.f_min),
        ("--f-max", f_max),
        ("--points", o.points, MAX_POINTS),
        nyq,
        h,
    )?;
    let mf_max = o.measure_f_max.unwrap_or(0.9 * nyq);
    if !o.methods.is_empty() {
        check_range(
            s,
            file,
            ("--measure-f-min", o.measure_f_min),
            ("--measure-f-max", mf_max),
            ("--measure-points", o.measure_points, MAX_MEASURE_POINTS),
            nyq,
            h,
        )?;
        let st = &o.settings;
        for (k, v) in [
            ("--amplitude-deg", st.amplitude),
            ("--disturbance", st.disturbance),
        ] {
            if !(v.is_finite() && v > 0.0) {
                Err(super::bad(s, file, k, format!("{v}: must be > 0")))?;
            }
        }
        if !(st.settle_s.is_finite() && st.settle_s >= 0.0) {
            Err(super::bad(s, file, "--settle", "must be finite and >= 0"))?;
        }
        if st.cycles == 0 || st.cycles > 10_000 {
            Err(super::bad(
                s,
                file,
                "--cycles",
                "must be between 1 and 10000",
            ))?;
        }
        if o.periods < 2 || o.periods > 10_000 {
            Err(super::bad(
                s,
                file,
                "--periods",
                "must be between 2 and 10000",
            ))?;
        }
    }
    // The computed part, where the plant is linearised.
    let computed = match super::oppoint::LinPlant::of(&setup) {
        Err((_, why)) => Err(why),
        Ok(_) => Ok(super::linearise(s, file, o.at, o.side, o.discretisation)?),
    };
    if let Ok(l) = &computed {
        if !super::all_finite(l) {
            return Err(anyhow!("{file}: the linearised models are not finite"));
        }
    }
    let theta0 = match &computed {
        Ok(l) => l.point.theta_deg * ehservo_core::math::DR,
        Err(_) => match o.at {
            Some(At::Trim(t)) => t,
            _ => super::default_at(&setup).theta0(),
        },
    };
    let settings = Settings {
        theta0,
        ..o.settings
    };
    // The measured frequencies and the work, bounded before any run.
    let mgrid: Vec<f64> = if o.methods.is_empty() {
        Vec::new()
    } else {
        (0..o.measure_points)
            .map(|i| {
                o.measure_f_min
                    * (mf_max / o.measure_f_min).powf(i as f64 / (o.measure_points - 1) as f64)
            })
            .collect()
    };
    let mut total = 0.0;
    let welch_plan = |kind| {
        measure::plan_welch(
            kind,
            o.measure_f_min,
            mf_max,
            o.measure_points,
            o.periods,
            h,
            settings.settle_s,
        )
    };
    for m in &o.methods {
        total += 2.0
            * match m {
                Method::Sine => mgrid
                    .iter()
                    .map(|&f| {
                        let p = measure::plan_sine(f, h, &settings);
                        measure::work(&setup, p.settle + p.window)
                    })
                    .sum::<f64>(),
                Method::Multisine => {
                    measure::work(&setup, welch_plan(Broadband::Multisine).samples())
                }
                Method::Chirp => measure::work(&setup, welch_plan(Broadband::Chirp).samples()),
            };
    }
    if total > MAX_WORK {
        Err(super::bad(
            s,
            file,
            "--measure-f-min",
            format!(
                "the measurement is about {total:.2e} law and RK4 evaluations, more than the limit of {MAX_WORK:.0e}: raise --measure-f-min, lower --measure-points, --cycles or --periods"
            ),
        ))?;
    }
    // The output folder is checked before the work.
    let stage = Staging::new(dir)?;
    let mut sets = Vec::new();
    for &m in &o.methods {
        let set = match m {
            Method::Sine => {
                let (tr, di) = rayon::join(
                    || measure::sinestream(&setup, Input::Tracking, &mgrid, &settings),
                    || measure::sinestream(&setup, Input::Disturbance, &mgrid, &settings),
                );
                let plans: Vec<_> = mgrid
                    .iter()
                    .map(|&f| measure::plan_sine(f, h, &settings))
                    .collect();
                MeasuredSet {
                    method: m,
                    tracking: tr,
                    disturbance: di,
                    plan: json!(plans),
                }
            }
            Method::Multisine | Method::Chirp => {
                let kind = if m == Method::Chirp {
                    Broadband::Chirp
                } else {
                    Broadband::Multisine
                };
                let plan = welch_plan(kind);
                let (tr, di) = measure::welch_both(&setup, &plan, &settings);
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
    write(s, &setup, o, &computed, &sets, f_max, settings, stage)
}

impl At {
    /// θ0 of a trim (rad); 0 for a time.
    pub fn theta0(&self) -> f64 {
        match self {
            At::Trim(t) => *t,
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

/// A CSV cell: the number, or empty.
fn cell(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:e}"),
        _ => String::new(),
    }
}

/// The measured −3 dB bandwidth: the first frequency where |H|, log-log
/// interpolated between the measured points, falls 3 dB below the lowest
/// point's. Points are read in order up to the first that is missing (an
/// unbounded run) or of quality below 0.9: past it the bandwidth is only
/// known to be above the last point read.
fn measured_bandwidth(pts: &[Measured]) -> Value {
    let mut good: Vec<(f64, C64)> = Vec::new();
    let mut stop = None;
    for m in pts {
        match m.theta_c() {
            Some(z) if m.quality >= 0.9 => good.push((m.f_hz, z)),
            _ => {
                stop = Some(m);
                break;
            }
        }
    }
    let Some(first) = good.first() else {
        return json!({"bandwidth_Hz": null, "why": "no measured point"});
    };
    let level = first.1.norm() * 10f64.powf(-3.0 / 20.0);
    for w in good.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b.1.norm() < level {
            let (la, lb) = (a.1.norm().ln(), b.1.norm().ln());
            let r = if (lb - la).abs() > 0.0 {
                (level.ln() - la) / (lb - la)
            } else {
                0.0
            };
            return json!({"bandwidth_Hz": (a.0.ln() + r * (b.0.ln() - a.0.ln())).exp()});
        }
    }
    let last = good.last().map(|g| g.0);
    let why = match stop {
        Some(m) if m.diverged_at_s.is_some() => format!(
            "the gain never fell 3 dB up to {:.4} Hz; the run at {:.4} Hz was unbounded",
            last.unwrap_or(0.0),
            m.f_hz
        ),
        Some(m) => format!(
            "the gain never fell 3 dB up to {:.4} Hz; at {:.4} Hz the response is distorted (quality {:.3} < 0.9)",
            last.unwrap_or(0.0),
            m.f_hz,
            m.quality
        ),
        None => format!(
            "the gain never fell 3 dB within the measured band (to {:.4} Hz)",
            last.unwrap_or(0.0)
        ),
    };
    json!({"bandwidth_Hz": null, "above_Hz": last, "why": why})
}

/// Margins of a measured loop L at the points (f, L), by interpolation
/// between neighbours (log |L| against log f, the unwrapped phase linear
/// in log f).
fn measured_margins(pts: &[(f64, Option<C64>, f64)]) -> Value {
    let z: Vec<Option<C64>> = pts.iter().map(|p| p.1).collect();
    let ph = unwrap(&z);
    let mut gains = Vec::new();
    let mut phases = Vec::new();
    for i in 0..pts.len().saturating_sub(1) {
        // Neighbours only: no crossing is read across a missing point.
        let (Some(za), Some(zb), Some(pa), Some(pb)) = (z[i], z[i + 1], ph[i], ph[i + 1]) else {
            continue;
        };
        let (fa, fb) = (pts[i].0, pts[i + 1].0);
        let quality = pts[i].2.min(pts[i + 1].2);
        let (ga, gb) = (za.norm().ln(), zb.norm().ln());
        let at = |r: f64| (fa.ln() + r * (fb.ln() - fa.ln())).exp();
        if ga * gb <= 0.0 && (gb - ga).abs() > 0.0 {
            let r = -ga / (gb - ga);
            let f = at(r);
            let p = pa + r * (pb - pa);
            let pm = (p + 180.0).rem_euclid(360.0);
            let pm = if pm > 180.0 { pm - 360.0 } else { pm };
            let w = 2.0 * PI * f;
            gains.push(json!({
                "f_Hz": f,
                "phase_margin_deg": pm,
                "delay_margin_s": (pm >= 0.0).then(|| pm.to_radians() / w),
                "quality": quality,
            }));
        }
        // Crossings of −180° (mod 360°).
        let k = ((pa.min(pb) + 180.0) / 360.0).ceil();
        let target = -180.0 + 360.0 * k;
        if target <= pa.max(pb) && (pb - pa).abs() > 0.0 && target >= pa.min(pb) {
            let r = (target - pa) / (pb - pa);
            let f = at(r);
            let g = (ga + r * (gb - ga)).exp();
            phases.push(json!({"f_Hz": f, "gain_margin": 1.0 / g, "gain_margin_dB": -20.0 * g.log10(), "quality": quality}));
        }
    }
    let least = |v: &Vec<Value>, key: &str| -> Value {
        v.iter()
            .filter(|x| x[key].is_number())
            .min_by(|a, b| {
                a[key]
                    .as_f64()
                    .unwrap_or(f64::INFINITY)
                    .abs()
                    .total_cmp(&b[key].as_f64().unwrap_or(f64::INFINITY).abs())
            })
            .cloned()
            .unwrap_or(Value::Null)
    };
    let gm = phases
        .iter()
        .min_by(|a, b| {
            let la = a["gain_margin"]
                .as_f64()
                .unwrap_or(f64::INFINITY)
                .ln()
                .abs();
            let lb = b["gain_margin"]
                .as_f64()
                .unwrap_or(f64::INFINITY)
                .ln()
                .abs();
            la.total_cmp(&lb)
        })
        .cloned()
        .unwrap_or(Value::Null);
    json!({
        "gain_margin": gm,
        "phase_margin": least(&gains, "phase_margin_deg"),
        "delay_margin": least(&gains, "delay_margin_s"),
        "gain_crossovers": gains,
        "phase_crossovers": phases,
    })
}

#[allow(clippy::too_many_arguments)]
fn write(
    s: &Scenario,
    setup: &Setup,
    o: &FreqOptions,
    computed: &std::result::Result<Linearised, String>,
    sets: &[MeasuredSet],
    f_max: f64,
    settings: Settings,
    stage: Staging,
) -> Result<FreqSummary> {
    let dirp = stage.path().to_path_buf();
    let mut files = Vec::new();
    let mut text = String::new();
    let h = setup.sim.step;
    let freqs: Vec<f64> = (0..o.points)
        .map(|i| o.f_min * (f_max / o.f_min).powf(i as f64 / (o.points - 1) as f64))
        .collect();
    let mut summary = json!({
        "scenario": s.name,
        "ehservo": env!("CARGO_PKG_VERSION"),
        "controller": s.controller.kind(),
        "mode": setup.sim.mode.as_str(),
        "dt_s": h,
        "nyquist_Hz": 0.5 / h,
        "grid": {"f_min_Hz": o.f_min, "f_max_Hz": f_max, "points": o.points},
        "curves": CURVES.iter().map(|(n, u, d)| json!({"name": n, "unit": u, "what": d, "gain_dB": format!("20·log10 |{n}| re 1 {}", if u.is_empty() { "(dimensionless)" } else { u })})).collect::<Vec<_>>(),
    });
    let mut responses: Vec<Responses> = Vec::new();
    let mut lp_opt = None;
    match computed {
        Ok(l) => {
            let lp = &l.lp;
            lp_opt = Some(lp);
            let lj = linearisation_json(s, l);
            let path = dirp.join("linearization.json");
            std::fs::write(&path, serde_json::to_string_pretty(&lj)? + "\n")
                .with_context(|| format!("writing {}", path.display()))?;
            files.push(PathBuf::from("linearization.json"));
            responses = freqs.iter().map(|&f| lp.at(2.0 * PI * f)).collect();
            let hi = if lp.sampled() {
                lp.nyquist() * (1.0 - 1e-9)
            } else {
                2.0 * PI * f_max
            };
            let lo = lp.lowest();
            let c = |sel: fn(&Responses) -> Option<C64>| move |w: f64| sel(&lp.at(w));
            let m: Option<Margins> = lp
                .loop_l
                .as_ref()
                .map(|_| margins::margins(&c(|r| r.l), lo, hi, lp.sampled().then_some(h)));
            let peak = |sel: fn(&Responses) -> Option<C64>| {
                margins::peak(&c(sel), lo, hi).map(
                    |(w, v)| json!({"value": v, "dB": 20.0 * v.log10(), "f_Hz": w / (2.0 * PI)}),
                )
            };
            let bw = |sel: fn(&Responses) -> Option<C64>| {
                let dc = sel(&lp.at(lo)).map(|z| z.norm())?;
                margins::bandwidth(&c(sel), dc, lo, hi).map(|w| w / (2.0 * PI))
            };
            let computed_json = json!({
                "operating_point": l.point,
                "one_sided": l.side.map(|s| s.as_str()),
                "kinks": lp.kinks.iter().map(|k| k.what.clone()).collect::<Vec<_>>(),
                "notes": lp.notes,
                "discretisation": lp.discretisation.as_str(),
                "linear_controller": lp.controller.is_some(),
                "closed_loop_stable": lp.closed_loop_stable(),
                "margins": m,
                "Ms": lp.loop_l.as_ref().and_then(|_| peak(|r| r.s)),
                "Mt": lp.loop_l.as_ref().and_then(|_| peak(|r| r.t)),
                "tracking_peak": lp.loop_l.as_ref().and_then(|_| peak(|r| r.track)),
                "bandwidth_Hz": {
                    "T": lp.loop_l.as_ref().and_then(|_| bw(|r| r.t)),
                    "tracking": lp.loop_l.as_ref().and_then(|_| bw(|r| r.track)),
                    "G": bw(|r| r.g),
                },
                "dc_gain": {
                    "G_rad_V": lp.g.dc_gain(),
                    "C_V_rad": lp.feedback.as_ref().and_then(|f| f.dc_gain()),
                },
            });
            let _ = writeln!(
                text,
                "computed about the {} point θ = {:.4}°{}:",
                l.point.kind,
                l.point.theta_deg,
                l.point
                    .t_s
                    .map(|t| format!(" (t = {t} s)"))
                    .unwrap_or_default()
            );
            if let Some(m) = &m {
                let _ = writeln!(
                    text,
                    "  L: gain margin {}, phase margin {}, delay margin {}; closed loop {}",
                    m.gain_margin
                        .map(|g| format!("{:.3} dB at {:.3} Hz", g.gain_margin_db, g.f_hz))
                        .unwrap_or("none (no phase crossover)".into()),
                    m.phase_margin
                        .map(|g| format!("{:.3}° at {:.3} Hz", g.phase_margin_deg, g.f_hz))
                        .unwrap_or("none (no gain crossover)".into()),
                    m.delay_margin
                        .and_then(|g| g.delay_margin_s)
                        .map(|d| format!("{:.3} ms", d * 1e3))
                        .unwrap_or("none".into()),
                    match lp.closed_loop_stable() {
                        Some(true) => "stable",
                        Some(false) => "UNSTABLE",
                        None => "?",
                    }
                );
                let bt = computed_json["bandwidth_Hz"]["tracking"].as_f64();
                let _ = writeln!(
                    text,
                    "  Ms {:.3}, Mt {:.3}; −3 dB bandwidth of T {}, of θ/θd {}",
                    computed_json["Ms"]["value"].as_f64().unwrap_or(f64::NAN),
                    computed_json["Mt"]["value"].as_f64().unwrap_or(f64::NAN),
                    computed_json["bandwidth_Hz"]["T"]
                        .as_f64()
                        .map(|b| format!("{b:.3} Hz"))
                        .unwrap_or("beyond the band".into()),
                    bt.map(|b| format!("{b:.3} Hz"))
                        .unwrap_or("beyond the band".into()),
                );
            } else {
                let _ = writeln!(
                    text,
                    "  `{}` is not a linear law: the computed curves are the plant's alone",
                    s.controller.kind()
                );
            }
            summary["computed"] = computed_json;
            write_response_csv(&dirp.join("response.csv"), &responses, &freqs)?;
            files.push(PathBuf::from("response.csv"));
        }
        Err(why) => {
            summary["computed"] = json!({"not_computed": why});
            let _ = writeln!(text, "computed curves: not available ({why})");
        }
    }
    let mut measured_json = serde_json::Map::new();
    for set in sets {
        let name = format!("measured_{}.csv", set.method.as_str());
        write_measured_csv(&dirp.join(&name), set, lp_opt)?;
        files.push(PathBuf::from(&name));
        let loop_pts: Vec<(f64, Option<C64>, f64)> = set
            .disturbance
            .iter()
            .map(|m| {
                let l = m.s_c().filter(|s| s.norm() > 0.0).map(|s| 1.0 / s - 1.0);
                (m.f_hz, l, m.quality.min(m.quality_s.unwrap_or(1.0)))
            })
            .collect();
        let diverged = set
            .tracking
            .iter()
            .chain(&set.disturbance)
            .filter(|m| m.diverged_at_s.is_some())
            .count();
        let q_min = |v: &[Measured]| v.iter().map(|m| m.quality).fold(f64::INFINITY, f64::min);
        let bw = measured_bandwidth(&set.tracking);
        let mm = measured_margins(&loop_pts);
        let _ = writeln!(
            text,
            "measured ({}, {} frequencies): tracking −3 dB bandwidth {}; loop at the plant's input: phase margin {}, delay margin {}{}",
            set.method.as_str(),
            set.tracking.len(),
            bw["bandwidth_Hz"]
                .as_f64()
                .map(|b| format!("{b:.3} Hz"))
                .unwrap_or_else(|| format!("not found ({})", bw["why"].as_str().unwrap_or(""))),
            mm["phase_margin"]["phase_margin_deg"]
                .as_f64()
                .map(|p| format!("{p:.2}°"))
                .unwrap_or("none".into()),
            mm["delay_margin"]["delay_margin_s"]
                .as_f64()
                .map(|d| format!("{:.2} ms", d * 1e3))
                .unwrap_or("none".into()),
            if diverged > 0 {
                format!("; {diverged} runs unbounded")
            } else {
                String::new()
            }
        );
        measured_json.insert(
            set.method.as_str().into(),
            json!({
                "file": name,
                "tracking_bandwidth": bw,
                "loop_margins": mm,
                "unbounded_runs": diverged,
                "least_quality": {"tracking": q_min(&set.tracking), "disturbance": q_min(&set.disturbance)},
                "plan": set.plan,
            }),
        );
    }
    summary["measured"] = json!({
        "settings": {
            "theta0_deg": settings.theta0 / ehservo_core::math::DR,
            "amplitude_deg": settings.amplitude / ehservo_core::math::DR,
            "disturbance_V": settings.disturbance,
            "settle_s": settings.settle_s,
            "settle_cycles": settings.settle_cycles,
            "cycles": settings.cycles,
            "welch_periods": o.periods,
            "f_min_Hz": o.measure_f_min,
            "points": o.measure_points,
        },
        "methods": measured_json,
        "quality": "sinestream: the fundamental fraction, the share of the output's variance at the excited frequency; Welch: the coherence γ²",
    });
    if o.plots {
        if let Some(lp) = lp_opt {
            for ext in ["png", "svg"] {
                let p = dirp.join(format!("bode.{ext}"));
                bode(&p, lp, &responses, &freqs, &summary)?;
                files.push(PathBuf::from(format!("bode.{ext}")));
                if lp.loop_l.is_some() {
                    let p = dirp.join(format!("nyquist.{ext}"));
                    nyquist(&p, &responses, &summary)?;
                    files.push(PathBuf::from(format!("nyquist.{ext}")));
                }
            }
        }
        if !sets.is_empty() {
            for ext in ["png", "svg"] {
                let p = dirp.join(format!("measured.{ext}"));
                measured_plot(&p, sets, lp_opt, &s.name)?;
                files.push(PathBuf::from(format!("measured.{ext}")));
            }
        }
    }
    let path = dirp.join("freq.json");
    std::fs::write(&path, serde_json::to_string_pretty(&summary)? + "\n")
        .with_context(|| format!("writing {}", path.display()))?;
    files.insert(0, PathBuf::from("freq.json"));
    stage.commit()?;
    Ok(FreqSummary { files, text })
}

fn write_response_csv(path: &Path, rs: &[Responses], freqs: &[f64]) -> Result<()> {
    let mut head = vec!["f_Hz".to_string(), "omega_rad_s".to_string()];
    for (n, u, _) in CURVES {
        let u = u.replace('/', "_");
        let suf = if u.is_empty() {
            String::new()
        } else {
            format!("_{u}")
        };
        head.push(format!("{n}_gain_dB"));
        head.push(format!("{n}_phase_deg"));
        head.push(format!("{n}_re{suf}"));
        head.push(format!("{n}_im{suf}"));
    }
    let cols: Vec<Vec<Option<C64>>> = (0..CURVES.len())
        .map(|i| rs.iter().map(|r| r.all()[i]).collect())
        .collect();
    let phases: Vec<Vec<Option<f64>>> = cols.iter().map(|c| unwrap(c)).collect();
    let mut out = head.join(",") + "\n";
    for (k, f) in freqs.iter().enumerate() {
        let mut row = vec![cell(Some(*f)), cell(Some(2.0 * PI * f))];
        for i in 0..CURVES.len() {
            let z = cols[i][k];
            row.push(cell(z.map(db)));
            row.push(cell(phases[i][k]));
            row.push(cell(z.map(|z| z.re)));
            row.push(cell(z.map(|z| z.im)));
        }
        out += &(row.join(",") + "\n");
    }
    std::fs::write(path, out).with_context(|| format!("writing {}", path.display()))
}

fn write_measured_csv(
    path: &Path,
    set: &MeasuredSet,
    lp: Option<&super::response::Loop>,
) -> Result<()> {
    let head = [
        "f_Hz",
        "track_gain_dB",
        "track_phase_deg",
        "track_re",
        "track_im",
        "track_quality",
        "dist_gain_dB",
        "dist_phase_deg",
        "dist_re_rad_V",
        "dist_im_rad_V",
        "S_gain_dB",
        "S_phase_deg",
        "S_re",
        "S_im",
        "L_gain_dB",
        "L_phase_deg",
        "dist_quality",
        "S_quality",
        "track_computed_gain_dB",
        "track_computed_phase_deg",
        "dist_computed_gain_dB",
        "dist_computed_phase_deg",
        "S_computed_gain_dB",
        "S_computed_phase_deg",
        "track_unbounded_at_s",
        "dist_unbounded_at_s",
    ];
    let tr: Vec<Option<C64>> = set.tracking.iter().map(|m| m.theta_c()).collect();
    let di: Vec<Option<C64>> = set.disturbance.iter().map(|m| m.theta_c()).collect();
    let sv: Vec<Option<C64>> = set.disturbance.iter().map(|m| m.s_c()).collect();
    let lv: Vec<Option<C64>> = sv
        .iter()
        .map(|s| s.filter(|s| s.norm() > 0.0).map(|s| 1.0 / s - 1.0))
        .collect();
    let comp: Vec<Option<Responses>> = set
        .tracking
        .iter()
        .map(|m| lp.map(|l| l.at(2.0 * PI * m.f_hz)))
        .collect();
    let ctr: Vec<Option<C64>> = comp.iter().map(|r| r.and_then(|r| r.track)).collect();
    let cdi: Vec<Option<C64>> = comp.iter().map(|r| r.and_then(|r| r.dist)).collect();
    let csv_: Vec<Option<C64>> = comp.iter().map(|r| r.and_then(|r| r.s)).collect();
    let (ptr, pdi, psv, plv, pctr, pcdi, pcs) = (
        unwrap(&tr),
        unwrap(&di),
        unwrap(&sv),
        unwrap(&lv),
        unwrap(&ctr),
        unwrap(&cdi),
        unwrap(&csv_),
    );
    let mut out = head.join(",") + "\n";
    for k in 0..set.tracking.len() {
        let (t, d) = (&set.tracking[k], &set.disturbance[k]);
        let row = [
            cell(Some(t.f_hz)),
            cell(tr[k].map(db)),
            cell(ptr[k]),
            cell(tr[k].map(|z| z.re)),
            cell(tr[k].map(|z| z.im)),
            cell(tr[k].map(|_| t.quality)),
            cell(di[k].map(db)),
            cell(pdi[k]),
            cell(di[k].map(|z| z.re)),
            cell(di[k].map(|z| z.im)),
            cell(sv[k].map(db)),
            cell(psv[k]),
            cell(sv[k].map(|z| z.re)),
            cell(sv[k].map(|z| z.im)),
            cell(lv[k].map(db)),
            cell(plv[k]),
            cell(di[k].map(|_| d.quality)),
            cell(d.quality_s),
            cell(ctr[k].map(db)),
            cell(pctr[k]),
            cell(cdi[k].map(db)),
            cell(pcdi[k]),
            cell(csv_[k].map(db)),
            cell(pcs[k]),
            cell(t.diverged_at_s),
            cell(d.diverged_at_s),
        ];
        out += &(row.join(",") + "\n");
    }
    std::fs::write(path, out).with_context(|| format!("writing {}", path.display()))
}

/// A line of a log-frequency panel.
struct Line {
    label: String,
    x: Vec<f64>,
    y: Vec<Option<f64>>,
    color: usize,
    points: bool,
}

/// A panel with a logarithmic frequency axis.
struct LogPanel {
    title: String,
    y_label: String,
    lines: Vec<Line>,
    marks: Vec<f64>,
}

/// Draws panels on a grid into `path` (PNG or SVG by its extension).
fn draw_log_panels(
    path: &Path,
    title: &str,
    rows: usize,
    cols: usize,
    panels: &[LogPanel],
) -> Result<()> {
    ensure_font();
    let size = (700 * cols as u32, 380 * rows as u32 + 40);
    macro_rules! go {
        ($root:expr) => {{
            let root = $root;
            root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
            let body = root
                .titled(title, (FAMILY, 20).into_font())
                .map_err(|e| anyhow!("{e}"))?;
            for (area, p) in body.split_evenly((rows, cols)).iter().zip(panels) {
                log_panel(area, p)?;
            }
            root.present().map_err(|e| anyhow!("{e}"))?;
        }};
    }
    if path.extension().and_then(|e| e.to_str()) == Some("svg") {
        go!(SVGBackend::new(path, size).into_drawing_area());
        Ok(())
    } else {
        png_file(path, size, |root| {
            go!(root);
            Ok(())
        })
    }
}

fn log_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &LogPanel) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let xs = p
        .lines
        .iter()
        .flat_map(|l| l.x.iter().copied())
        .filter(|x| *x > 0.0 && x.is_finite());
    let (x0, x1) = xs.fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    if !(x0.is_finite() && x1 > x0) {
        return Ok(());
    }
    let ys = p
        .lines
        .iter()
        .flat_map(|l| l.y.iter().flatten().copied())
        .filter(|y| y.is_finite());
    let (mut y0, mut y1) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
        (a.min(y), b.max(y))
    });
    if !(y0.is_finite() && y1.is_finite()) {
        (y0, y1) = (-1.0, 1.0);
    }
    if y1 - y0 < 1e-9 {
        y0 -= 1.0;
        y1 += 1.0;
    }
    let m = 0.05 * (y1 - y0);
    let font = |s: u32| (FAMILY, s).into_font();
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, font(16))
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(64)
        .build_cartesian_2d((x0..x1).log_scale(), (y0 - m)..(y1 + m))
        .map_err(|e| anyhow!("building a chart: {e}"))?;
    chart
        .configure_mesh()
        .x_desc("frequency (Hz)")
        .y_desc(&p.y_label)
        .label_style(font(12))
        .axis_desc_style(font(13))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| anyhow!("drawing axes: {e}"))?;
    for l in &p.lines {
        let c = color(l.color);
        let style = ShapeStyle::from(&c).stroke_width(2);
        let mut first = true;
        let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for (x, y) in l.x.iter().zip(&l.y) {
            match y {
                Some(y) if y.is_finite() && *x > 0.0 => {
                    runs.last_mut().expect("one run").push((*x, *y))
                }
                _ => runs.push(Vec::new()),
            }
        }
        for run in runs.iter().filter(|r| !r.is_empty()) {
            let anno = if l.points {
                chart
                    .draw_series(
                        run.iter()
                            .map(|&(x, y)| Circle::new((x, y), 3, style.filled())),
                    )
                    .map_err(|e| anyhow!("drawing points: {e}"))?
            } else {
                chart
                    .draw_series(LineSeries::new(run.iter().copied(), style))
                    .map_err(|e| anyhow!("drawing a line: {e}"))?
            };
            if first && !l.label.is_empty() {
                let pts = l.points;
                anno.label(&l.label).legend(move |(x, y)| {
                    if pts {
                        Circle::new((x + 10, y), 3, c.filled()).into_dyn()
                    } else {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)).into_dyn()
                    }
                });
            }
            first = false;
        }
    }
    for &mx in p.marks.iter().filter(|m| **m >= x0 && **m <= x1) {
        chart
            .draw_series(DashedLineSeries::new(
                [(mx, y0 - m), (mx, y1 + m)],
                6,
                4,
                ShapeStyle::from(&RGBColor(90, 90, 90)).stroke_width(1),
            ))
            .map_err(|e| anyhow!("drawing a mark: {e}"))?;
    }
    chart
        .configure_series_labels()
        .label_font(font(12))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
        .map_err(|e| anyhow!("drawing the legend: {e}"))?;
    Ok(())
}

fn bode(
    path: &Path,
    lp: &super::response::Loop,
    rs: &[Responses],
    f: &[f64],
    summary: &Value,
) -> Result<()> {
    let pick = [(0usize, 0usize), (3, 1), (4, 2), (5, 3), (6, 4), (7, 5)];
    let curves: Vec<(usize, Vec<Option<C64>>)> = pick
        .iter()
        .map(|&(i, c)| (c, rs.iter().map(|r| r.all()[i]).collect::<Vec<_>>()))
        .filter(|(_, v)| v.iter().any(|z| z.is_some()))
        .collect();
    let labels = ["G (rad/V)", "L", "S", "T", "θ/θd", "θ/d (rad/V)"];
    let mut gains = Vec::new();
    let mut phases = Vec::new();
    for (c, v) in &curves {
        gains.push(Line {
            label: labels[*c].into(),
            x: f.to_vec(),
            y: v.iter().map(|z| z.map(db)).collect(),
            color: *c,
            points: false,
        });
        phases.push(Line {
            label: labels[*c].into(),
            x: f.to_vec(),
            y: unwrap(v),
            color: *c,
            points: false,
        });
    }
    let m = &summary["computed"]["margins"];
    let mut marks = Vec::new();
    for k in ["gain_margin", "phase_margin"] {
        if let Some(x) = m[k]["f_Hz"].as_f64() {
            marks.push(x);
        }
    }
    let fmt = |v: Option<f64>, u: &str| v.map(|x| format!("{x:.2}{u}")).unwrap_or("—".into());
    let title = format!(
        "{}: {} loop about θ = {:.3}° — GM {}, PM {}, DM {}",
        summary["scenario"].as_str().unwrap_or(""),
        summary["controller"].as_str().unwrap_or(""),
        summary["computed"]["operating_point"]["theta_deg"]
            .as_f64()
            .unwrap_or(0.0),
        fmt(m["gain_margin"]["gain_margin_dB"].as_f64(), " dB"),
        fmt(m["phase_margin"]["phase_margin_deg"].as_f64(), "°"),
        fmt(
            m["delay_margin"]["delay_margin_s"]
                .as_f64()
                .map(|d| d * 1e3),
            " ms"
        ),
    );
    let _ = lp;
    draw_log_panels(
        path,
        &title,
        2,
        1,
        &[
            LogPanel {
                title: "gain".into(),
                y_label: "gain (dB)".into(),
                lines: gains,
                marks: marks.clone(),
            },
            LogPanel {
                title: "phase".into(),
                y_label: "phase (deg)".into(),
                lines: phases,
                marks,
            },
        ],
    )
}

fn nyquist(path: &Path, rs: &[Responses], summary: &Value) -> Result<()> {
    ensure_font();
    let l: Vec<(f64, f64)> = rs
        .iter()
        .filter_map(|r| r.l)
        .filter(|z| z.re.is_finite() && z.im.is_finite())
        .map(|z| (z.re, z.im))
        .collect();
    let size = (800u32, 800u32);
    let (lo, hi) = (-3.0, 1.5);
    let title = format!(
        "{}: Nyquist curve of L (ω > 0 solid, its mirror dashed), −1 marked",
        summary["scenario"].as_str().unwrap_or("")
    );
    macro_rules! go {
        ($root:expr) => {{
            let root = $root;
            root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
            let font = |s: u32| (FAMILY, s).into_font();
            let mut chart = ChartBuilder::on(&root)
                .caption(&title, font(16))
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(50)
                .build_cartesian_2d(lo..hi, -2.25..2.25)
                .map_err(|e| anyhow!("building a chart: {e}"))?;
            chart
                .configure_mesh()
                .x_desc("Re L")
                .y_desc("Im L")
                .label_style(font(12))
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(|e| anyhow!("drawing axes: {e}"))?;
            let circle: Vec<(f64, f64)> = (0..=360)
                .map(|i| {
                    let a = i as f64 * PI / 180.0;
                    (a.cos(), a.sin())
                })
                .collect();
            chart
                .draw_series(DashedLineSeries::new(
                    circle,
                    4,
                    4,
                    ShapeStyle::from(&RGBColor(150, 150, 150)),
                ))
                .map_err(|e| anyhow!("{e}"))?;
            // Clip the curve to the box: split where it leaves.
            let inside = |p: &(f64, f64)| p.0 >= lo && p.0 <= hi && p.1.abs() <= 2.25;
            let style = ShapeStyle::from(&color(1)).stroke_width(2);
            for pts in l.split(|p| !inside(p)).filter(|r| r.len() > 1) {
                chart
                    .draw_series(LineSeries::new(pts.iter().copied(), style))
                    .map_err(|e| anyhow!("{e}"))?;
                chart
                    .draw_series(DashedLineSeries::new(
                        pts.iter().map(|p| (p.0, -p.1)),
                        6,
                        4,
                        ShapeStyle::from(&color(1)),
                    ))
                    .map_err(|e| anyhow!("{e}"))?;
            }
            chart
                .draw_series(std::iter::once(Cross::new(
                    (-1.0, 0.0),
                    8,
                    ShapeStyle::from(&BLACK).stroke_width(2),
                )))
                .map_err(|e| anyhow!("{e}"))?;
            root.present().map_err(|e| anyhow!("{e}"))?;
        }};
    }
    if path.extension().and_then(|e| e.to_str()) == Some("svg") {
        go!(SVGBackend::new(path, size).into_drawing_area());
        Ok(())
    } else {
        png_file(path, size, |root| {
            go!(root);
            Ok(())
        })
    }
}

fn measured_plot(
    path: &Path,
    sets: &[MeasuredSet],
    lp: Option<&super::response::Loop>,
    name: &str,
) -> Result<()> {
    let mut panels = Vec::new();
    type Sel = fn(&Measured) -> Option<C64>;
    let th: Sel = |m| m.theta_c();
    let sv: Sel = |m| m.s_c();
    type Spec = (
        &'static str,
        &'static str,
        bool,
        Sel,
        fn(&Responses) -> Option<C64>,
    );
    let specs: [Spec; 3] = [
        ("θ/θd (tracking)", "", true, th, |r| r.track),
        (
            "θ/d (disturbance on the command)",
            "rad/V",
            false,
            th,
            |r| r.dist,
        ),
        ("S = u/d", "", false, sv, |r| r.s),
    ];
    for (title, unit, tracking, sel, csel) in specs {
        let mut g = Vec::new();
        let mut p = Vec::new();
        for (i, set) in sets.iter().enumerate() {
            let pts = if tracking {
                &set.tracking
            } else {
                &set.disturbance
            };
            let x: Vec<f64> = pts.iter().map(|m| m.f_hz).collect();
            let z: Vec<Option<C64>> = pts.iter().map(sel).collect();
            g.push(Line {
                label: format!("measured ({})", set.method.as_str()),
                x: x.clone(),
                y: z.iter().map(|v| v.map(db)).collect(),
                color: 1 + i,
                points: true,
            });
            p.push(Line {
                label: format!("measured ({})", set.method.as_str()),
                x,
                y: unwrap(&z),
                color: 1 + i,
                points: true,
            });
        }
        if let Some(lp) = lp {
            let f: Vec<f64> = sets[0].tracking.iter().map(|m| m.f_hz).collect();
            let lo = f.first().copied().unwrap_or(0.1);
            let hi = f.last().copied().unwrap_or(1.0);
            let fine: Vec<f64> = (0..300)
                .map(|i| lo * (hi / lo).powf(i as f64 / 299.0))
                .collect();
            let z: Vec<Option<C64>> = fine.iter().map(|&f| csel(&lp.at(2.0 * PI * f))).collect();
            if z.iter().any(|v| v.is_some()) {
                g.push(Line {
                    label: "computed".into(),
                    x: fine.clone(),
                    y: z.iter().map(|v| v.map(db)).collect(),
                    color: 0,
                    points: false,
                });
                p.push(Line {
                    label: "computed".into(),
                    x: fine,
                    y: unwrap(&z),
                    color: 0,
                    points: false,
                });
            }
        }
        let u = if unit.is_empty() {
            String::new()
        } else {
            format!(" re 1 {unit}")
        };
        panels.push(LogPanel {
            title: format!("{title}: gain"),
            y_label: format!("gain (dB{u})"),
            lines: g,
            marks: Vec::new(),
        });
        panels.push(LogPanel {
            title: format!("{title}: phase"),
            y_label: "phase (deg)".into(),
            lines: p,
            marks: Vec::new(),
        });
    }
    draw_log_panels(
        path,
        &format!("{name}: measured frequency responses"),
        3,
        2,
        &panels,
    )
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

    /// Measured margins of L = 1/(s(s + 1)²) sampled at 200 log-spaced
    /// points: the interpolated crossovers land within a grid cell of the
    /// exact ones (PM 21.386° at 0.682 rad/s, GM 2 at 1 rad/s).
    #[test]
    fn measured_margins_interpolate() {
        let pts: Vec<(f64, Option<C64>, f64)> = (0..200)
            .map(|i| {
                let f = 0.01 * 10f64.powf(3.0 * i as f64 / 199.0);
                let s = C64::new(0.0, 2.0 * PI * f);
                (f, Some(1.0 / (s * (s + 1.0) * (s + 1.0))), 1.0)
            })
            .collect();
        let m = measured_margins(&pts);
        let pm = m["phase_margin"]["phase_margin_deg"].as_f64().unwrap();
        assert!((pm - 21.386).abs() < 0.1, "{pm}");
        let gm = m["gain_margin"]["gain_margin"].as_f64().unwrap();
        assert!((gm - 2.0).abs() < 0.02, "{gm}");
    }
}
