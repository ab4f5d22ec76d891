//! `ehservo linearize` and `freq`: the loop linearised at an operating point,
//! and its frequency responses computed and measured (docs/frequency.md).

use super::{check_threads, default_out, load, StdoutError};
use anyhow::Result;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// `ehservo linearize`.
#[derive(clap::Args)]
pub(super) struct LinearizeArgs {
    /// The scenario file (TOML).
    scenario: PathBuf,
    /// At this time along the run (s).
    #[arg(long, conflicts_with = "trim")]
    at: Option<f64>,
    /// At a trim point for the constant reference at this position, in the axis's unit: degrees on a rotary axis, mm on a linear one (without a value θd(0), the default).
    #[arg(long, value_name = "X", num_args = 0..=1, allow_negative_numbers = true)]
    trim: Option<Option<f64>>,
    /// The trim in steady motion at this speed (the axis's unit per second: mm/s on a linear axis); the cylinder's only.
    #[arg(
        long,
        value_name = "V",
        conflicts_with = "at",
        allow_negative_numbers = true
    )]
    velocity: Option<f64>,
    /// At a point that is not differentiable, the one-sided model from below or above.
    #[arg(long, value_parser = ["minus", "plus"])]
    side: Option<String>,
    /// The plant's discretisation: exact under a zero-order hold, or the simulator's RK4 map.
    #[arg(long, default_value = "zoh", value_parser = ["zoh", "rk4"])]
    discretise: String,
    /// Also write DIR/linearization.json.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Override a key (repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    set: Vec<String>,
}

/// `ehservo freq`.
#[derive(clap::Args)]
pub(super) struct FreqArgs {
    /// The scenario file (TOML).
    scenario: PathBuf,
    /// Output directory (default: out/<scenario name>-freq).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Linearise at this time along the run (s).
    #[arg(long, conflicts_with = "trim")]
    at: Option<f64>,
    /// Linearise at a trim point for the constant reference at this position, in the axis's unit: degrees on a rotary axis, mm on a linear one (without a value θd(0), the default); the measurements excite the loop about it.
    #[arg(long, value_name = "X", num_args = 0..=1, allow_negative_numbers = true)]
    trim: Option<Option<f64>>,
    /// The trim in steady motion at this speed (the axis's unit per second: mm/s on a linear axis); the cylinder's only, for the computed curves.
    #[arg(
        long,
        value_name = "V",
        conflicts_with = "at",
        allow_negative_numbers = true
    )]
    velocity: Option<f64>,
    /// At a point that is not differentiable, the one-sided model from below or above.
    #[arg(long, value_parser = ["minus", "plus"])]
    side: Option<String>,
    /// The plant's discretisation: exact under a zero-order hold, or the simulator's RK4 map.
    #[arg(long, default_value = "zoh", value_parser = ["zoh", "rk4"])]
    discretise: String,
    /// Lowest computed frequency (Hz).
    #[arg(long, default_value_t = 0.01)]
    f_min: f64,
    /// Highest computed frequency (Hz; default 0.99 of Nyquist).
    #[arg(long)]
    f_max: Option<f64>,
    /// Computed frequencies, log-spaced.
    #[arg(long, default_value_t = 400)]
    points: usize,
    /// Measurements on the simulator: sine (a sinestream), multisine, chirp (Welch's H1 and coherence), none; comma-separated.
    #[arg(long, default_value = "sine")]
    measure: Vec<String>,
    /// Lowest measured frequency (Hz).
    #[arg(long, default_value_t = 0.1)]
    measure_f_min: f64,
    /// Highest measured frequency (Hz; default 0.9 of Nyquist).
    #[arg(long)]
    measure_f_max: Option<f64>,
    /// Measured frequencies (sinestream) or bins (Welch), log-spaced.
    #[arg(long, default_value_t = 40)]
    measure_points: usize,
    /// Amplitude of the tracking excitation, in the axis's unit: degrees on a rotary axis, mm on a linear one (default 0.5).
    #[arg(long, value_name = "A")]
    amplitude: Option<f64>,
    /// Amplitude of the tracking excitation (deg), on a rotary axis only (the older spelling of --amplitude there).
    #[arg(long, value_name = "DEG", conflicts_with = "amplitude")]
    amplitude_deg: Option<f64>,
    /// Amplitude of the disturbance on the command (V).
    #[arg(long, default_value_t = 0.05)]
    disturbance: f64,
    /// Settling time before each measurement window (s; at least two periods).
    #[arg(long, default_value_t = 2.0)]
    settle: f64,
    /// Periods in each sinestream window.
    #[arg(long, default_value_t = 4)]
    cycles: u32,
    /// Segments (periods) of a Welch measurement.
    #[arg(long, default_value_t = 4)]
    periods: u64,
    /// Worker threads, 1 to 1024 (default: every core).
    #[arg(long)]
    threads: Option<usize>,
    /// Do not draw the figures.
    #[arg(long)]
    no_plot: bool,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
    /// Override a key (repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    set: Vec<String>,
}

/// `ehservo linearize`.
pub(super) fn linearize(a: LinearizeArgs, w: &mut impl Write) -> Result<()> {
    let LinearizeArgs {
        scenario,
        at,
        trim,
        velocity,
        side,
        discretise,
        out,
        set,
    } = a;
    use crate::freq::cli;
    let text = cli::linearize_cmd(
        &scenario,
        &set,
        cli::PointFlags { at, trim, velocity },
        cli::side(side.as_deref()),
        cli::discretisation(&discretise),
        out.as_deref(),
    )?;
    put!(w, "{text}");
    Ok(())
}

/// `ehservo freq`.
pub(super) fn freq(a: FreqArgs, w: &mut impl Write) -> Result<()> {
    let FreqArgs {
        scenario,
        out,
        at,
        trim,
        velocity,
        side,
        discretise,
        f_min,
        f_max,
        points,
        measure,
        measure_f_min,
        measure_f_max,
        measure_points,
        amplitude,
        amplitude_deg,
        disturbance,
        settle,
        cycles,
        periods,
        threads,
        no_plot,
        quiet,
        set,
    } = a;
    use crate::freq::cli;
    check_threads(threads)?;
    let lp = load(&scenario, &set)?;
    let s = lp.scenario();
    let dir = match out {
        Some(d) => d,
        None => default_out(&format!("{}-freq", s.name))?,
    };
    let mut o = crate::freq::report::FreqOptions::defaults();
    o.at = cli::PointFlags { at, trim, velocity }.resolve(&lp);
    o.side = cli::side(side.as_deref());
    o.discretisation = cli::discretisation(&discretise);
    (o.f_min, o.f_max, o.points) = (f_min, f_max, points);
    o.methods = cli::methods(&measure, &scenario.display().to_string())?;
    (o.measure_f_min, o.measure_f_max, o.measure_points) =
        (measure_f_min, measure_f_max, measure_points);
    let file = scenario.display().to_string();
    (o.settings.amplitude, o.amplitude_flag) =
        cli::amplitude(lp.axis(), amplitude, amplitude_deg, &file)?;
    o.settings.disturbance = disturbance;
    o.settings.settle_s = settle;
    o.settings.cycles = cycles;
    o.periods = periods;
    o.plots = !no_plot;
    let start = Instant::now();
    let r = cli::freq_cmd(&lp, &scenario, &o, &dir, threads)?;
    if !quiet {
        put!(
            w,
            "{}: {} ({:.2} s)\n{}",
            s.name,
            s.controller.kind(),
            start.elapsed().as_secs_f64(),
            r.text
        );
        let names: Vec<String> = r.files.iter().map(|f| f.display().to_string()).collect();
        out!(w, "wrote {}/{{{}}}", dir.display(), names.join(", "));
    }
    Ok(())
}
