//! `ehservo excite` and `identify`: an identification experiment designed, and
//! logged data turned into a scenario (docs/identification.md).

use super::StdoutError;
use crate::output;
use anyhow::Result;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// `ehservo excite`.
#[derive(clap::Args)]
pub(super) struct ExciteArgs {
    /// The signal.
    #[arg(long, value_enum, default_value = "multisine")]
    signal: crate::identify::excite::Signal,
    /// Open loop (the signal is the valve command, V) or closed loop (the reference, rad, of u = kp·(r − θ)).
    #[arg(long = "loop", value_enum, default_value = "open")]
    loop_kind: crate::identify::excite::Loop,
    /// Peak amplitude (V in open loop, rad in closed loop).
    #[arg(long, default_value_t = 0.05)]
    amplitude: f64,
    /// Band start (Hz): chirp, multisine.
    #[arg(long, default_value_t = 0.5)]
    f0: f64,
    /// Band end (Hz): chirp, multisine; below rate/2.
    #[arg(long, default_value_t = 40.0)]
    f1: f64,
    /// Duration (s).
    #[arg(long, default_value_t = 20.0)]
    duration: f64,
    /// Sample rate (Hz).
    #[arg(long, default_value_t = 1000.0)]
    rate: f64,
    /// Multisine period (samples).
    #[arg(long, default_value_t = 4096)]
    period: usize,
    /// Multisine phases.
    #[arg(long, value_enum, default_value = "crest")]
    phases: crate::identify::excite::Phases,
    /// PRBS register length (3 to 18).
    #[arg(long, default_value_t = 10)]
    order: u32,
    /// PRBS samples per bit.
    #[arg(long, default_value_t = 5)]
    clock: usize,
    /// Steps: seconds per level.
    #[arg(long, default_value_t = 0.5)]
    hold: f64,
    /// Seed of the steps' levels.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Closed loop: the proportional gain (V/rad); default a fifth of the prior's stability limit.
    #[arg(long)]
    kp: Option<f64>,
    /// The plant the scenario simulates (default: the paper's servo).
    #[arg(long)]
    prior: Option<PathBuf>,
    /// Override a key of the prior (repeatable), e.g. --set sensor.resolution=[9.5874e-5,0,0].
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    set: Vec<String>,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
}

/// `ehservo identify`.
#[derive(clap::Args)]
pub(super) struct IdentifyArgs {
    /// Logged experiments (CSV with a header row), fitted together.
    #[arg(required = true)]
    data: Vec<PathBuf>,
    /// Validation experiments (repeatable): simulated with the fitted model.
    #[arg(long)]
    validate: Vec<PathBuf>,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
    /// Time column (default t_s, t, time_s, time).
    #[arg(long)]
    time: Option<String>,
    /// Command column (default u_V, u).
    #[arg(long)]
    input: Option<String>,
    /// Position column (default theta_meas_rad/deg, theta_rad/deg, y_m, y_mm, position_m).
    #[arg(long)]
    output: Option<String>,
    /// Reference column of a closed-loop experiment, or none.
    #[arg(long)]
    reference: Option<String>,
    /// Load-pressure column (default p_load_Pa, p_load_bar, p_load_MPa), or none.
    #[arg(long)]
    pressure: Option<String>,
    /// Measured-velocity column (none by default).
    #[arg(long)]
    velocity: Option<String>,
    /// Largest deviation of a sample time from the uniform grid, as a fraction of the period.
    #[arg(long, default_value_t = 0.05)]
    period_tolerance: f64,
    /// Use only the rows from this time on (s, in the time column's clock).
    #[arg(long, value_name = "S")]
    from: Option<f64>,
    /// Use only the rows up to this time (s, in the time column's clock).
    #[arg(long, value_name = "S")]
    to: Option<f64>,
    /// The prior scenario: its plant and load start the grey-box and hold what is fixed or unidentifiable (default: the paper's).
    #[arg(long)]
    prior: Option<PathBuf>,
    /// Override a key of the prior (repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    set: Vec<String>,
    /// Hold a parameter at a value (repeatable), e.g. --fix Vt=1.639e-4 or --fix a1=0.
    #[arg(long, value_name = "KEY=VALUE")]
    fix: Vec<String>,
    /// The grey-box's free parameters, comma-separated (default beta_e,Kce,Jt,Bm,Kv,G on a rotary axis; bulk_modulus,viscous,rated_flow on a cylinder: docs/identification.md).
    #[arg(long, value_delimiter = ',')]
    free: Option<Vec<String>>,
    /// Fit the load terms d1, d2 of d = d1·sin(kθ) + d2·cos(kθ)·θ̇ in the linear model (k: the prior's load.wavenumber).
    #[arg(long)]
    load_terms: bool,
    /// Welch segment length (samples; default the largest power of two with 8 segments).
    #[arg(long)]
    segment: Option<usize>,
    /// Identifiability threshold: a direction the data fix to no better than this relative standard error is unidentifiable.
    #[arg(long, default_value_t = 0.3)]
    ident_threshold: f64,
    /// Most residual evaluations of one Levenberg–Marquardt run (1 to 100000); a fit that runs out has not converged (exit 1).
    #[arg(long, default_value_t = 400)]
    max_evaluations: usize,
    /// Bootstrap resamples of one experiment for the bounds of A1 (0: none).
    #[arg(long, default_value_t = 0)]
    bootstrap: usize,
    /// Seed of the bootstrap.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Skip the grey-box fit.
    #[arg(long)]
    no_greybox: bool,
    /// Lags of the residual tests.
    #[arg(long, default_value_t = 25)]
    lags: usize,
    /// Do not draw plots.
    #[arg(long)]
    no_plot: bool,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
}

/// `ehservo excite`.
pub(super) fn excite(a: ExciteArgs, w: &mut impl Write) -> Result<()> {
    use crate::identify::excite::{excite_to_dir, Spec};
    let spec = Spec {
        signal: a.signal,
        loop_kind: a.loop_kind,
        amplitude: a.amplitude,
        f0: a.f0,
        f1: a.f1,
        duration: a.duration,
        rate: a.rate,
        period: a.period,
        phases: a.phases,
        order: a.order,
        clock: a.clock,
        hold: a.hold,
        seed: a.seed,
        kp: a.kp,
    };
    let wr = excite_to_dir(&spec, a.prior.as_deref(), &a.set, &a.out)?;
    out!(
        w,
        "{:?} ({} loop{}): {} samples at {} Hz, peak {:.4}, RMS {:.4}, crest factor {:.3}; predicted peak |position| {:.4} {} on the prior",
        spec.signal,
        if wr.kp.is_some() { "closed" } else { "open" },
        wr.kp
            .map_or(String::new(), |k| format!(", kp = {k:.4} V/{}", wr.unit)),
        wr.design.values.len(),
        spec.rate,
        wr.design.peak,
        wr.design.rms,
        wr.design.crest_factor,
        wr.predicted_peak_rad,
        wr.unit
    );
    out!(
        w,
        "wrote {}/{{excitation.csv, scenario.toml, excite.json}}; simulate it with: ehservo run {}/scenario.toml",
        a.out.display(),
        a.out.display()
    );
    Ok(())
}

/// `--free` and `--fix` agree with themselves and each other, before any
/// file is read: no empty or repeated name in `--free` (a column twice in
/// the Jacobian makes it singular), no key fixed twice (which value?), no
/// key both fixed and free.
fn check_free_and_fix(free: Option<&[String]>, fix: &[(String, f64)]) -> Result<()> {
    let free = free.unwrap_or_default();
    for (i, f) in free.iter().enumerate() {
        if f.trim().is_empty() {
            crate::bad_input!(
                "--free: an empty name in the list (give names separated by single commas)"
            );
        }
        if free[..i].contains(f) {
            crate::bad_input!("--free {f}: named twice (each parameter is free once)");
        }
    }
    for (i, (k, _)) in fix.iter().enumerate() {
        if fix[..i].iter().any(|(j, _)| j == k) {
            crate::bad_input!("--fix {k}: given twice (one value holds it)");
        }
        if free.contains(k) {
            crate::bad_input!(
                "--fix {k} and --free {k}: a parameter is either held or fitted, not both"
            );
        }
    }
    Ok(())
}

/// `ehservo identify`.
pub(super) fn identify(a: IdentifyArgs, w: &mut impl Write) -> Result<()> {
    use crate::identify::{data, fit, identify, report, Options};
    let mut fix = Vec::new();
    for f in &a.fix {
        let Some((k, v)) = f.split_once('=') else {
            crate::bad_input!("--fix {f}: expected KEY=VALUE");
        };
        let v: f64 = v.trim().parse().map_err(|_| {
            crate::error::InputError::Request(format!("--fix {f}: `{}` is not a number", v.trim()))
        })?;
        fix.push((k.trim().to_string(), v));
    }
    check_free_and_fix(a.free.as_deref(), &fix)?;
    if !(a.period_tolerance.is_finite() && a.period_tolerance > 0.0 && a.period_tolerance < 0.5) {
        crate::bad_input!(
            "--period-tolerance {}: must be in (0, 0.5)",
            a.period_tolerance
        );
    }
    let window = match (a.from, a.to) {
        (None, None) => None,
        (f, t) => {
            let (f, t) = (f.unwrap_or(f64::NEG_INFINITY), t.unwrap_or(f64::INFINITY));
            if f.is_nan() || t.is_nan() || f >= t {
                crate::bad_input!("--from {f} --to {t}: the window must have from < to");
            }
            Some([f, t])
        }
    };
    if !(a.ident_threshold.is_finite() && a.ident_threshold > 0.0) {
        crate::bad_input!(
            "--ident-threshold {}: must be finite and > 0",
            a.ident_threshold
        );
    }
    if !(1..=100_000).contains(&a.max_evaluations) {
        crate::bad_input!(
            "--max-evaluations {}: must be 1 to 100000",
            a.max_evaluations
        );
    }
    if !(1..=10_000).contains(&a.lags) {
        crate::bad_input!("--lags {}: must be 1 to 10000", a.lags);
    }
    // The output folder is checked before the fits.
    output::probe_destination(&a.out)?;
    let opts = Options {
        files: a.data.clone(),
        validate: a.validate.clone(),
        map: data::ColumnMap {
            time: a.time.clone(),
            input: a.input.clone(),
            output: a.output.clone(),
            reference: a.reference.clone(),
            pressure: a.pressure.clone(),
            velocity: a.velocity.clone(),
        },
        read: data::ReadOptions {
            tolerance: a.period_tolerance,
            min_rows: 64,
            window,
        },
        prior: a.prior.clone(),
        set: a.set.clone(),
        fix,
        free: a.free.clone(),
        load_terms: a.load_terms,
        segment: a.segment,
        fit: fit::FitOptions {
            ident_threshold: a.ident_threshold,
            max_evaluations: a.max_evaluations,
        },
        bootstrap: a.bootstrap,
        seed: a.seed,
        no_greybox: a.no_greybox,
        lags: a.lags,
    };
    let start = Instant::now();
    let o = identify(&opts)?;
    let files = report::write(&o, &opts, &a.out, !a.no_plot)?;
    if !a.quiet {
        put!(w, "{}", report::summary(&o));
        let names: Vec<String> = files
            .iter()
            .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect();
        out!(
            w,
            "identified in {:.2} s; wrote {}/{{{}}}",
            start.elapsed().as_secs_f64(),
            a.out.display(),
            names.join(", ")
        );
    }
    // A fit that did not converge is not a result: the outputs say where it
    // stopped (identify.json's `converged`, `termination`, `evaluations`),
    // no identified.toml is written from it, and the command exits 1.
    let failed = report::not_converged(&o);
    if !failed.is_empty() {
        anyhow::bail!(
            "identify: {} (wrote {}/identify.json; no identified.toml from it)",
            failed.join("; "),
            a.out.display()
        );
    }
    Ok(())
}
