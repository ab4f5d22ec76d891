//! The `ehservo` command line.
//!
//! Exit codes:
//! - 0: done;
//! - 1: the machine failed: an output that cannot be written, a full
//!   disk, standard output that cannot be written (`> /dev/full`: one line,
//!   `error: writing to stdout: …`) or that was closed by its reader
//!   (`| head -1`, `| true`: no message at all, the reader has gone);
//! - 2: bad input (a scenario, a flag, an output folder that is not ours,
//!   an input file that is missing, unreadable, not a file or too large);
//! - 130: interrupted by `SIGINT`, `SIGTERM` or `SIGHUP`; the staging
//!   folders of the outputs being written are removed, the previous outputs
//!   stay as they were ([`ehservo::signals`]).

use anyhow::Result;
use clap::{Parser, Subcommand};
use ehservo::output;
use ehservo::run::{run, Keep};
use ehservo::scenario::Scenario;
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// Most worker threads `--threads` accepts.
const MAX_THREADS: usize = 1024;

/// A failed write to standard output, kept apart from other I/O errors: a
/// closed pipe ends the command quietly.
#[derive(Debug)]
struct StdoutError(std::io::Error);

impl std::fmt::Display for StdoutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "writing to stdout: {}", self.0)
    }
}

impl std::error::Error for StdoutError {}

/// `writeln!` to the command's output, returning a [`StdoutError`] from the
/// enclosing function when it fails (where `println!` would panic).
macro_rules! out {
    ($w:expr) => {
        writeln!($w).map_err(StdoutError)?
    };
    ($w:expr, $($arg:tt)*) => {
        writeln!($w, $($arg)*).map_err(StdoutError)?
    };
}

/// `write!` to the command's output, like [`out!`] without the newline.
macro_rules! put {
    ($w:expr, $($arg:tt)*) => {
        write!($w, $($arg)*).map_err(StdoutError)?
    };
}

/// A line on standard error; if even that fails there is nowhere left to
/// say so.
macro_rules! note {
    ($($arg:tt)*) => {
        let _ = writeln!(std::io::stderr(), $($arg)*);
    };
}

/// Simulate and control electrohydraulic servo systems (Hwang's NNBVSC).
#[derive(Parser)]
#[command(
    name = "ehservo",
    version = concat!(env!("CARGO_PKG_VERSION"), " (commit ", env!("EHSERVO_COMMIT"), ")"),
    about,
    long_about = None
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run one scenario: print a summary, write trace.csv, summary.json and trace.png.
    #[command(
        after_help = "Example:\n  ehservo run scenarios/paper/fig2.toml --set simulation.horizon=5 --no-plot --out out/fig2"
    )]
    Run {
        /// The scenario file (TOML).
        scenario: PathBuf,
        /// Output directory (default: out/<scenario name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a key, e.g. --set controller.gamma1=200 (repeatable).
        #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
        set: Vec<String>,
        /// Do not write trace.png.
        #[arg(long)]
        no_plot: bool,
        /// Print nothing but errors.
        #[arg(long, short)]
        quiet: bool,
        /// The controller's float type: f64 (the simulator's own) or f32
        /// (the PIL board's code, computed here: what `ehservo pil` must
        /// match to the bit).
        #[arg(long, default_value = "f64", value_parser = ["f32", "f64"])]
        float: String,
    },
    /// Processor-in-the-loop: the controller on a board (QEMU's Cortex-M4F or a serial port), the rest simulated here in lock-step; writes run's outputs and pil.csv.
    #[command(
        after_help = "Example:\n  ehservo pil scenarios/paper/fig2.toml --set simulation.step=0.001 --qemu   (after: cd examples/firmware-pil && cargo build --release)"
    )]
    Pil {
        /// The scenario file (TOML).
        scenario: PathBuf,
        /// Output directory (default: out/<scenario name>-pil).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a key (repeatable).
        #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
        set: Vec<String>,
        /// Start QEMU (mps2-an386) with the PIL firmware, and stop it at the end.
        #[arg(long, conflicts_with = "port")]
        qemu: bool,
        /// A real board's serial port (e.g. /dev/ttyACM0).
        #[arg(long)]
        port: Option<String>,
        /// The serial port's rate.
        #[arg(long, default_value_t = 115_200)]
        baud: u32,
        /// Reach the board over TCP at HOST:PORT (a proxy, a QEMU started elsewhere, a serial server).
        #[arg(long, value_name = "HOST:PORT")]
        connect: Option<String>,
        /// With --qemu: listen here for QEMU's UART (or a proxy in front of it) to connect.
        #[arg(long, value_name = "HOST:PORT")]
        listen: Option<String>,
        /// With --qemu: QEMU's -serial backend, verbatim (e.g. tcp:127.0.0.1:5556,server=on,wait=on with --connect to a proxy).
        #[arg(long, value_name = "SPEC")]
        qemu_serial: Option<String>,
        /// The firmware ELF (default: target/thumbv7em-none-eabihf/release/ehservo-firmware-pil).
        #[arg(long)]
        firmware: Option<PathBuf>,
        /// The float type the board computes in.
        #[arg(long, default_value = "f32", value_parser = ["f32", "f64"])]
        float: String,
        /// How long to wait for each reply (ms) before applying the fault policy.
        #[arg(long, default_value_t = 200.0)]
        timeout_ms: f64,
        /// Inject a fault between host and board at sample K (testing): KIND@K with KIND one of corrupt-request, corrupt-reply, drop-request, drop-reply, late-reply, reset-board (repeatable).
        #[arg(long, value_name = "KIND@K")]
        inject: Vec<String>,
        /// Do not write trace.png.
        #[arg(long)]
        no_plot: bool,
        /// Print nothing but errors.
        #[arg(long, short)]
        quiet: bool,
    },
    /// What the theory says about a scenario: poles, K1/K2 and Theorem 2's bound, Remark 6, the σ-loop and the integrator.
    #[command(
        after_help = "Example:\n  ehservo analyze scenarios/paper/fig2.toml --set controller.gamma1=200"
    )]
    Analyze {
        /// The scenario file (TOML).
        scenario: PathBuf,
        /// Override a key (repeatable).
        #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
        set: Vec<String>,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        /// Also run the scenario and report condition 4) of Theorem 3 and the dead zone along the run.
        #[arg(long)]
        run: bool,
    },
    /// Parse and validate a scenario and print it with every default filled in.
    #[command(
        after_help = "Example:\n  ehservo check scenarios/examples/step.toml --set reference.amplitude_deg=2"
    )]
    Check {
        /// The scenario file (TOML).
        scenario: PathBuf,
        /// Override a key (repeatable).
        #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
        set: Vec<String>,
    },
    /// Re-run the paper's Section IV: every case, every claim scored, figures and a report.
    #[command(after_help = "Example:\n  ehservo reproduce --out out/reproduce")]
    Reproduce {
        /// Output directory.
        #[arg(long, default_value = "out/reproduce")]
        out: PathBuf,
        /// Directory with manifest.toml and the case files.
        #[arg(long, default_value = "scenarios/paper")]
        paper_dir: PathBuf,
        /// No progress bar, no summary.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Run a study (grid sweep and/or Monte Carlo) in parallel: results.csv, study.json, plots.
    #[command(
        after_help = "Example:\n  ehservo sweep scenarios/studies/gamma1-eta.toml --out out/gamma1-eta --shard 0/4"
    )]
    Sweep {
        /// The study file (TOML).
        study: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Run only the K-th of N contiguous slices (K from 0), e.g. --shard 0/4.
        #[arg(long, value_name = "K/N")]
        shard: Option<String>,
        /// Worker threads, 1 to 1024 (default: every core).
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bar, no summary.
        #[arg(long, short)]
        quiet: bool,
        /// Do not draw plots.
        #[arg(long)]
        no_plot: bool,
        /// Skip the sweep if --out already holds its output whole (the same
        /// study.json, every row of results.csv checked as merge does);
        /// otherwise run it, replacing what is there. For resubmitted jobs.
        #[arg(long)]
        resume: bool,
    },
    /// Tune a controller's parameters over a set of scenarios by particle swarm: tuned.toml, convergence.csv/png, tune.json.
    #[command(
        after_help = "Example:\n  ehservo tune scenarios/league/tune-pid-fig2.toml --out out/tune-pid"
    )]
    Tune {
        /// The tune file (TOML).
        file: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Worker threads, 1 to 1024 (default: every core).
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bar, no summary.
        #[arg(long, short)]
        quiet: bool,
        /// Do not draw the convergence plot.
        #[arg(long)]
        no_plot: bool,
    },
    /// Run a league: every controller of a suite (tuned with the same budget, or with given parameters) on every scenario: league.md/html/csv, runs.csv, figures.
    #[command(
        after_help = "Example:\n  ehservo league scenarios/league/suite.toml --out out/league"
    )]
    League {
        /// The suite file (TOML).
        file: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Worker threads, 1 to 1024 (default: every core).
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bar, no summary.
        #[arg(long, short)]
        quiet: bool,
        /// Do not draw figures.
        #[arg(long)]
        no_plot: bool,
    },
    /// Join the outputs of sharded sweeps into one results.csv.
    #[command(
        after_help = "Example:\n  ehservo merge shards/* --out merged     (ehservo merge --missing shards/*: the shards to rerun)"
    )]
    Merge {
        /// Shard output directories.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Output directory.
        #[arg(long, required_unless_present = "missing")]
        out: Option<PathBuf>,
        /// Write nothing: print the indices K of the shards that are not
        /// among DIRS whole (comma-separated, for `sbatch --array=`; nothing
        /// if none is missing), and on stderr why any folder was set aside.
        #[arg(long, conflicts_with = "out")]
        missing: bool,
    },
    /// Print the default scenario (the paper's Fig. 2 case) as TOML.
    #[command(after_help = "Example:\n  ehservo defaults > my-case.toml")]
    Defaults,
    /// Print the JSON Schema of a file format (or, with --markdown, its reference page, docs/reference/).
    ///
    /// Example: ehservo schema scenario > scenario.schema.json
    Schema {
        /// The format.
        #[arg(value_enum, default_value = "scenario")]
        format: ehservo::schema::Format,
        /// Print the reference page (Markdown) instead.
        #[arg(long)]
        markdown: bool,
    },
    /// Design an identification experiment: excitation.csv for a rig and scenario.toml that simulates it (docs/identification.md).
    #[command(
        after_help = "Example:\n  ehservo excite --signal multisine --duration 20 --out out/experiment"
    )]
    Excite(ExciteArgs),
    /// Identify a servo from logged (t, u, y) data: frequency response, linear and grey-box fits, identified.toml (docs/identification.md).
    #[command(
        after_help = "Example:\n  ehservo identify out/run/trace.csv --pressure none --out out/identified   (out/run: ehservo run out/experiment/scenario.toml --out out/run)"
    )]
    Identify(Box<IdentifyArgs>),
    /// Linearise the loop at an operating point: plant, actuator, delays and a linear controller as state-space models, with poles, zeros, DC gain and damping (JSON; docs/frequency.md).
    #[command(
        after_help = "Example:\n  ehservo linearize scenarios/frequency/pid-nominal.toml --trim"
    )]
    Linearize {
        /// The scenario file (TOML).
        scenario: PathBuf,
        /// At this time along the run (s).
        #[arg(long, conflicts_with = "trim")]
        at: Option<f64>,
        /// At a trim point for the constant reference θ0 (deg; without a value θd(0), the default).
        #[arg(long, value_name = "DEG", num_args = 0..=1)]
        trim: Option<Option<f64>>,
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
    },
    /// Frequency responses of the loop (G, C, L, S, T, θ/θd, θ/d) with margins, computed and measured on the simulator: freq.json, CSVs, Bode and Nyquist plots (docs/frequency.md).
    #[command(
        after_help = "Example:\n  ehservo freq scenarios/frequency/pid-nominal.toml --out out/freq"
    )]
    Freq {
        /// The scenario file (TOML).
        scenario: PathBuf,
        /// Output directory (default: out/<scenario name>-freq).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Linearise at this time along the run (s).
        #[arg(long, conflicts_with = "trim")]
        at: Option<f64>,
        /// Linearise at a trim point for the constant reference θ0 (deg; without a value θd(0), the default); the measurements excite the loop about it.
        #[arg(long, value_name = "DEG", num_args = 0..=1)]
        trim: Option<Option<f64>>,
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
        /// Amplitude of the tracking excitation (deg).
        #[arg(long, default_value_t = 0.5)]
        amplitude_deg: f64,
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
    },
    /// Export the scenario's controller (or, with --closed-loop, its whole loop) as an FMI 3.0 co-simulation FMU.
    #[command(
        after_help = "Example:\n  ehservo fmu scenarios/paper/fig2.toml --closed-loop --out fig2-loop.fmu"
    )]
    Fmu {
        /// The scenario file (TOML).
        scenario: PathBuf,
        /// The FMU to write (e.g. controller.fmu).
        #[arg(long)]
        out: PathBuf,
        /// Export the closed loop (plant, actuator, sensors and controller; no inputs) instead of the controller alone.
        #[arg(long)]
        closed_loop: bool,
        /// The FMU's binary (default: libehservo_ffi.so beside this ehservo; build it with cargo build -p ehservo-ffi).
        #[arg(long)]
        binary: Option<PathBuf>,
        /// Override a key (repeatable).
        #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
        set: Vec<String>,
    },
}

/// `ehservo excite`.
#[derive(clap::Args)]
struct ExciteArgs {
    /// The signal.
    #[arg(long, value_enum, default_value = "multisine")]
    signal: ehservo::identify::excite::Signal,
    /// Open loop (the signal is the valve command, V) or closed loop (the reference, rad, of u = kp·(r − θ)).
    #[arg(long = "loop", value_enum, default_value = "open")]
    loop_kind: ehservo::identify::excite::Loop,
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
    phases: ehservo::identify::excite::Phases,
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
struct IdentifyArgs {
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
    /// The grey-box's free parameters, comma-separated (default beta_e,Kce,Jt,Bm,Kv,G).
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

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // --help and --version go to stdout (and follow its rules),
            // usage errors to stderr (exit 2 whatever becomes of them).
            let printed = e.print().and_then(|()| std::io::stdout().flush());
            return match printed {
                Err(io) if !e.use_stderr() => {
                    if io.kind() != std::io::ErrorKind::BrokenPipe {
                        note!("error: writing to stdout: {io}");
                    }
                    ExitCode::from(1)
                }
                _ => ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2)),
            };
        }
    };
    // Without it a signal still ends the process, but leaves the staging
    // folders; that is all a failure here costs.
    if let Err(e) = ehservo::signals::install() {
        note!("warning: no handler for Ctrl-C and SIGTERM: {e}");
    }
    let stdout = std::io::stdout();
    let mut w = stdout.lock();
    let done = dispatch(cli, &mut w).and_then(|()| Ok(w.flush().map_err(StdoutError)?));
    match done {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if closed_stdout(&e) => ExitCode::from(1),
        Err(e) => {
            note!("error: {e:#}");
            ExitCode::from(ehservo::error::exit_code(&e))
        }
    }
}

/// Whether the error is standard output closed by its reader.
fn closed_stdout(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<StdoutError>()
            .is_some_and(|s| s.0.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// The scenario's name as the folder of its default output, `out/<name>`:
/// one plain name, never a path that leads elsewhere.
/// `--threads`, when given, within 1..=MAX_THREADS.
fn check_threads(threads: Option<usize>) -> Result<()> {
    if let Some(t) = threads {
        if !(1..=MAX_THREADS).contains(&t) {
            ehservo::bad_input!("--threads {t}: must be between 1 and {MAX_THREADS}");
        }
    }
    Ok(())
}

/// A progress bar of `n` steps on a terminal, unless quiet; hidden otherwise.
fn progress_bar(n: u64, quiet: bool) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !quiet && std::io::stderr().is_terminal() {
        indicatif::ProgressBar::new(n)
    } else {
        indicatif::ProgressBar::hidden()
    }
}

fn default_out(name: &str) -> Result<PathBuf> {
    if name.is_empty() || name == "." || name.contains("..") || name.contains(['/', '\\', '\0']) {
        ehservo::bad_input!(
            "`name` = {name:?}: must be a plain name without '/' or '..' to be used as the output folder; pass --out"
        );
    }
    Ok(PathBuf::from("out").join(name))
}

fn load(path: &std::path::Path, set: &[String]) -> Result<Scenario> {
    Ok(Scenario::load(path, set)?)
}

fn dispatch(cli: Cli, w: &mut impl Write) -> Result<()> {
    match cli.command {
        Command::Run {
            scenario,
            out,
            set,
            no_plot,
            quiet,
            float,
        } => {
            let s = load(&scenario, &set)?;
            let dir = match out {
                Some(d) => d,
                None => default_out(&s.name)?,
            };
            let start = Instant::now();
            let rows = s.sim_config().steps / s.output.decimate.max(1) as u64 + 1;
            if rows > 2_000_000 && !quiet {
                note!(
                    "note: trace.csv will have {rows} rows (about {} MB); set output.decimate to thin it",
                    rows * 300 / 1_000_000
                );
            }
            let plot = s.output.plot && !no_plot;
            let (r, files) = if float == "f32" {
                let opts = ehservo::pil::Options::in_process(ehservo_wire_float(&float));
                let (r, files, _) = ehservo::pil::run_to_dir(&dir, &s, plot, opts)?;
                (r, files)
            } else {
                output::run_to_dir(&dir, &s, plot)?
            };
            let elapsed = start.elapsed();
            if !quiet {
                print_summary(w, &s, &r, elapsed.as_secs_f64())?;
                if float == "f32" {
                    out!(
                        w,
                        "  controller in f32 (the PIL board's code, on this host)"
                    );
                }
                let names: Vec<String> = files
                    .iter()
                    .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
                    .collect();
                out!(w, "wrote {}/{{{}}}", dir.display(), names.join(", "));
            }
            Ok(())
        }
        Command::Pil {
            scenario,
            out,
            set,
            qemu,
            port,
            baud,
            connect,
            listen,
            qemu_serial,
            firmware,
            float,
            timeout_ms,
            inject,
            no_plot,
            quiet,
        } => {
            use ehservo::pil::{Options, Target};
            let s = load(&scenario, &set)?;
            let dir = match out {
                Some(d) => d,
                None => default_out(&format!("{}-pil", s.name))?,
            };
            if !(timeout_ms.is_finite() && timeout_ms > 0.0 && timeout_ms <= 60_000.0) {
                ehservo::bad_input!("--timeout-ms {timeout_ms}: must be > 0 and at most 60000");
            }
            let mut plan = Vec::new();
            for i in &inject {
                match ehservo::pil::transport::Inject::parse(i) {
                    Some(p) => plan.push((p.1, p.0)),
                    None => ehservo::bad_input!(
                        "--inject {i}: expected KIND@K, KIND one of corrupt-request, corrupt-reply, drop-request, drop-reply, late-reply, reset-board"
                    ),
                }
            }
            if !qemu && (listen.is_some() || qemu_serial.is_some() || firmware.is_some()) {
                ehservo::bad_input!("--listen, --qemu-serial and --firmware go with --qemu");
            }
            let target = match (qemu, port, connect) {
                (true, None, connect) => Target::Qemu {
                    firmware,
                    serial: qemu_serial,
                    connect,
                    listen,
                },
                (false, Some(path), None) => Target::Port { path, baud },
                (false, None, Some(addr)) => Target::Connect(addr),
                (false, Some(_), Some(_)) => {
                    ehservo::bad_input!("--port and --connect: give one board")
                }
                _ => ehservo::bad_input!(
                    "say where the board is: --qemu, --port /dev/ttyX or --connect HOST:PORT"
                ),
            };
            let opts = Options {
                target,
                float: ehservo_wire_float(&float),
                timeout: std::time::Duration::from_secs_f64(timeout_ms / 1e3),
                handshake_timeout: std::time::Duration::from_secs(20),
                inject: plan,
            };
            let start = Instant::now();
            let (r, files, rep) =
                ehservo::pil::run_to_dir(&dir, &s, s.output.plot && !no_plot, opts)?;
            let elapsed = start.elapsed();
            let o = &rep.offboard;
            if !quiet {
                print_summary(w, &s, &r, elapsed.as_secs_f64())?;
                out!(
                    w,
                    "  PIL over {}: {} ({} samples in {:.2} s: {:.0} samples/s; round trip mean {:.0} µs, max {:.0} µs)",
                    o["transport"].as_str().unwrap_or("?"),
                    o["firmware"].as_str().unwrap_or("?"),
                    o["samples"],
                    o["wall_s"].as_f64().unwrap_or(0.0),
                    o["samples_per_s"].as_f64().unwrap_or(0.0),
                    o["rtt_us"]["mean"].as_f64().unwrap_or(0.0),
                    o["rtt_us"]["max"].as_f64().unwrap_or(0.0),
                );
                out!(
                    w,
                    "  board step ({}): mean {:.0} cycles, max {:.0} cycles",
                    o["float"].as_str().unwrap_or("?"),
                    o["step_cycles"]["mean"].as_f64().unwrap_or(0.0),
                    o["step_cycles"]["max"].as_f64().unwrap_or(0.0),
                );
                let names: Vec<String> = files
                    .iter()
                    .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
                    .collect();
                out!(w, "wrote {}/{{{}}}", dir.display(), names.join(", "));
            }
            if let Some(events) = o["events"].as_array() {
                for e in events.iter().take(20) {
                    note!(
                        "link fault at k = {}: {} ({})",
                        e["k"],
                        e["fault"].as_str().unwrap_or("?"),
                        e["detail"].as_str().unwrap_or("")
                    );
                }
                if events.len() > 20 {
                    note!(
                        "… {} link faults in all: see summary.json",
                        o["link_faults"]
                    );
                }
            }
            if let Some(lost) = o["link_lost"].as_str() {
                anyhow::bail!(
                    "the link to the board was lost ({lost}); the outputs in {} record the run with the fault policy's command from then on",
                    dir.display()
                );
            }
            Ok(())
        }
        Command::Analyze {
            scenario,
            set,
            json,
            run: with_run,
        } => {
            let s = load(&scenario, &set)?;
            let a = ehservo::analysis::analyze(&s);
            let diag = if with_run {
                // Diagnostics over at most MAX_KEPT samples (every one for runs up to that).
                let stride = (s.sim_config().steps + 1).div_ceil(output::MAX_KEPT).max(1);
                let r = run(&s, Keep::Every(stride as u32))?;
                Some((
                    ehservo::analysis::diagnostics(&s, &r.trace),
                    r.outcome.diverged,
                ))
            } else {
                None
            };
            if json {
                let v = serde_json::json!({
                    "scenario": s.name,
                    "analysis": a,
                    "diagnostics": diag.as_ref().and_then(|d| d.0.clone()),
                    "diverged_at_s": diag.as_ref().and_then(|d| d.1.map(|x| x.t)),
                });
                out!(w, "{}", serde_json::to_string_pretty(&v)?);
            } else {
                out!(w, "{} ({})\n", s.name, scenario.display());
                put!(w, "{}", a.to_text());
                match diag {
                    Some((Some(d), div)) => {
                        out!(w);
                        put!(w, "{}", d.to_text());
                        if let Some(dv) = div {
                            out!(w, "  (the run was unbounded at t = {:.4} s)", dv.t);
                        }
                    }
                    Some((None, _)) => out!(w, "\n(--run: condition 4) concerns the NNBVSC only)"),
                    None => {}
                }
            }
            Ok(())
        }
        Command::Check { scenario, set } => {
            let s = load(&scenario, &set)?;
            put!(w, "{}", s.to_toml());
            note!(
                "{}: ok ({} steps)",
                scenario.display(),
                s.sim_config().steps
            );
            Ok(())
        }
        Command::Reproduce {
            out,
            paper_dir,
            quiet,
        } => {
            use std::io::IsTerminal;
            let manifest = paper_dir.join("manifest.toml");
            if !manifest.is_file() {
                ehservo::bad_input!(
                    "{}: not found (run from the repository root, or pass --paper-dir)",
                    manifest.display()
                );
            }
            // Minutes of runs are not spent before finding the output
            // folder refused or unwritable.
            output::probe_destination(&out)?;
            let opts = ehservo::reproduce::Options {
                paper_dir,
                out: out.clone(),
                progress: !quiet && std::io::stderr().is_terminal(),
                skip_boundaries: false,
                skip_figures: false,
                seeds: None,
            };
            let start = Instant::now();
            let rep = ehservo::reproduce::reproduce(&opts)?;
            if !quiet {
                out!(
                    w,
                    "reproduced {} claims under {} readings in {:.1} s; figures use `{}`:",
                    rep.claims.len(),
                    rep.agreements.len(),
                    start.elapsed().as_secs_f64(),
                    rep.primary_reading
                );
                for (r, n) in &rep.agreements {
                    out!(w, "  {r:<18} {n:>2} / {} claims agree", rep.claims.len());
                }
                out!(
                    w,
                    "wrote {}/report.md, report.html, figures/",
                    out.display()
                );
            }
            Ok(())
        }
        Command::Sweep {
            study,
            out,
            shard,
            threads,
            quiet,
            no_plot,
            resume,
        } => {
            use std::io::IsTerminal;
            check_threads(threads)?;
            let plan = ehservo::study::Plan::load(&study)?;
            let shard = match shard {
                Some(s) => Some(
                    ehservo::study::parse_shard(&s)
                        .map_err(|e| ehservo::error::InputError(format!("--shard: {e}")))?,
                ),
                None => None,
            };
            // Hours of runs are not spent before finding the output
            // folder refused or unwritable.
            output::probe_destination(&out)?;
            let opts = ehservo::study::SweepOptions {
                out: out.clone(),
                shard,
                threads,
                progress: !quiet && std::io::stderr().is_terminal(),
                plots: !no_plot,
            };
            if resume {
                use ehservo::study::Resume;
                match ehservo::study::resume_state(&plan, &opts)? {
                    Resume::Complete => {
                        note!(
                            "{}{}: already complete in {} (--resume): skipped",
                            plan.study.name,
                            match shard {
                                Some((k, n)) => format!(" shard {k}/{n}"),
                                None => String::new(),
                            },
                            out.display()
                        );
                        return Ok(());
                    }
                    Resume::Redo(why) => {
                        note!("--resume: running again, replacing what is there: {why}");
                    }
                    Resume::Absent => {}
                }
            }
            let start = Instant::now();
            let rows = ehservo::study::sweep(&plan, &opts)?;
            if !quiet {
                let unbounded = rows
                    .iter()
                    .filter(|r| r.metrics.is_some_and(|m| m.diverged))
                    .count();
                let invalid = rows.iter().filter(|r| r.error.is_some()).count();
                out!(
                    w,
                    "{}: {} runs{} in {:.2} s ({} unbounded{}); wrote {}/results.csv",
                    plan.study.name,
                    rows.len(),
                    match shard {
                        Some((k, n)) => format!(" (shard {k}/{n} of {})", plan.runs),
                        None => String::new(),
                    },
                    start.elapsed().as_secs_f64(),
                    unbounded,
                    if invalid > 0 {
                        format!(", {invalid} invalid draws")
                    } else {
                        String::new()
                    },
                    out.display()
                );
            }
            Ok(())
        }
        Command::Tune {
            file,
            out,
            threads,
            quiet,
            no_plot,
        } => {
            check_threads(threads)?;
            let tune = ehservo::tune::Tune::load(&file)?;
            output::probe_destination(&out)?;
            let pb = progress_bar(tune.file.budget, quiet);
            let start = Instant::now();
            let r = ehservo::tune::tune_to_dir(&tune, &out, threads, &pb, !no_plot)?;
            pb.finish_and_clear();
            if !quiet {
                let params: Vec<String> = r
                    .params
                    .iter()
                    .map(|(k, v)| format!("{k} = {v:.6}"))
                    .collect();
                out!(
                    w,
                    "{}: {} tuned in {} evaluations ({:.2} s): objective {:.5}{}{}\n  {}\nwrote {}/tuned.toml",
                    tune.file.name,
                    tune.kind,
                    r.evaluations,
                    start.elapsed().as_secs_f64(),
                    r.objective,
                    tune.axis.suffix(),
                    if r.kept_defaults {
                        " — no better than the defaults, which are kept".to_string()
                    } else {
                        format!(" (defaults: {:.5}{})", r.defaults, tune.axis.suffix())
                    },
                    params.join(", "),
                    out.display()
                );
            }
            Ok(())
        }
        Command::League {
            file,
            out,
            threads,
            quiet,
            no_plot,
        } => {
            check_threads(threads)?;
            let league = ehservo::league::League::load(&file)?;
            output::probe_destination(&out)?;
            let pb = progress_bar(league.work(), quiet);
            let start = Instant::now();
            let r = ehservo::league::league_to_dir(&league, &out, threads, &pb, !no_plot)?;
            pb.finish_and_clear();
            if !quiet {
                let rows = ehservo::league::report::rows(&league, &r);
                let ranks = ehservo::league::report::ranks(&league, &rows);
                let mut best: Vec<usize> = (0..ranks.len()).collect();
                best.sort_by(|&a, &b| ranks[a].1.total_cmp(&ranks[b].1).then(a.cmp(&b)));
                out!(
                    w,
                    "{}: {} controllers × {} scenarios ({} runs) in {:.1} s; mean rank: {}\nwrote {}/league.md, league.html, league.csv",
                    league.file.name,
                    league.contestants.len(),
                    league.cases.len(),
                    r.cells.len(),
                    start.elapsed().as_secs_f64(),
                    best.iter()
                        .map(|&i| format!("{} {:.2}", r.standings[i].name, ranks[i].1))
                        .collect::<Vec<_>>()
                        .join(", "),
                    out.display()
                );
            }
            Ok(())
        }
        Command::Merge { dirs, out, missing } => {
            let Some(out) = out.filter(|_| !missing) else {
                let m = ehservo::study::missing(&dirs)?;
                for (d, why) in &m.set_aside {
                    note!(
                        "{}: not a whole shard, counted as missing: {why}",
                        d.display()
                    );
                }
                let list = ehservo::study::index_list(&m.missing);
                if !list.is_empty() {
                    out!(w, "{list}");
                }
                note!(
                    "{} of {} shard(s) missing{}",
                    m.missing.len(),
                    m.n,
                    if list.is_empty() {
                        ": ready to merge".to_string()
                    } else {
                        format!(": rerun each with --shard K/{} for K in {list}", m.n)
                    }
                );
                return Ok(());
            };
            let n = ehservo::study::merge(&dirs, &out)?;
            out!(
                w,
                "merged {} shard(s), {n} runs, into {}/results.csv",
                dirs.len(),
                out.display()
            );
            Ok(())
        }
        Command::Fmu {
            scenario,
            out,
            closed_loop,
            binary,
            set,
        } => {
            use ehservo::fmu::{write_fmu, FmuKind};
            let s = load(&scenario, &set)?;
            let kind = if closed_loop {
                FmuKind::ClosedLoop
            } else {
                FmuKind::Controller
            };
            // The destination first (a directory, a missing folder), then
            // the binary: both before any work.
            ehservo::fmu::check_out(&out)?;
            if out.extension().and_then(|e| e.to_str()) != Some("fmu") {
                ehservo::bad_input!("--out {}: an FMU's file name ends in .fmu", out.display());
            }
            let Some(binary) = binary.or_else(ehservo::fmu::default_binary) else {
                ehservo::bad_input!(
                    "the FMU's binary libehservo_ffi.so is not beside this ehservo: build it (cargo build -p ehservo-ffi, same profile) or pass --binary PATH"
                );
            };
            write_fmu(&out, kind, &s, &binary)?;
            note!(
                "{}: the {} FMU of {} (FMI 3.0 co-simulation, step {} s)",
                out.display(),
                kind.as_str(),
                s.name,
                s.simulation.step
            );
            Ok(())
        }
        Command::Excite(a) => {
            use ehservo::identify::excite::{excite_to_dir, Spec};
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
                "{:?} ({} loop{}): {} samples at {} Hz, peak {:.4}, RMS {:.4}, crest factor {:.3}; predicted peak |θ| {:.4} rad on the prior",
                spec.signal,
                if wr.kp.is_some() { "closed" } else { "open" },
                wr.kp.map_or(String::new(), |k| format!(", kp = {k:.4} V/rad")),
                wr.design.values.len(),
                spec.rate,
                wr.design.peak,
                wr.design.rms,
                wr.design.crest_factor,
                wr.predicted_peak_rad
            );
            out!(
                w,
                "wrote {}/{{excitation.csv, scenario.toml, excite.json}}; simulate it with: ehservo run {}/scenario.toml",
                a.out.display(),
                a.out.display()
            );
            Ok(())
        }
        Command::Identify(a) => {
            use ehservo::identify::{data, fit, identify, report, Options};
            let mut fix = Vec::new();
            for f in &a.fix {
                let Some((k, v)) = f.split_once('=') else {
                    ehservo::bad_input!("--fix {f}: expected KEY=VALUE");
                };
                let v: f64 = v.trim().parse().map_err(|_| {
                    ehservo::error::InputError(format!("--fix {f}: `{}` is not a number", v.trim()))
                })?;
                fix.push((k.trim().to_string(), v));
            }
            if !(a.period_tolerance.is_finite()
                && a.period_tolerance > 0.0
                && a.period_tolerance < 0.5)
            {
                ehservo::bad_input!(
                    "--period-tolerance {}: must be in (0, 0.5)",
                    a.period_tolerance
                );
            }
            let window = match (a.from, a.to) {
                (None, None) => None,
                (f, t) => {
                    let (f, t) = (f.unwrap_or(f64::NEG_INFINITY), t.unwrap_or(f64::INFINITY));
                    if f.is_nan() || t.is_nan() || f >= t {
                        ehservo::bad_input!("--from {f} --to {t}: the window must have from < to");
                    }
                    Some([f, t])
                }
            };
            if !(a.ident_threshold.is_finite() && a.ident_threshold > 0.0) {
                ehservo::bad_input!(
                    "--ident-threshold {}: must be finite and > 0",
                    a.ident_threshold
                );
            }
            if !(1..=10_000).contains(&a.lags) {
                ehservo::bad_input!("--lags {}: must be 1 to 10000", a.lags);
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
                    ..Default::default()
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
            Ok(())
        }
        Command::Linearize {
            scenario,
            at,
            trim,
            side,
            discretise,
            out,
            set,
        } => {
            use ehservo::freq::cli;
            let text = cli::linearize_cmd(
                &scenario,
                &set,
                cli::operating_point(at, trim),
                cli::side(side.as_deref()),
                cli::discretisation(&discretise),
                out.as_deref(),
            )?;
            put!(w, "{text}");
            Ok(())
        }
        Command::Freq {
            scenario,
            out,
            at,
            trim,
            side,
            discretise,
            f_min,
            f_max,
            points,
            measure,
            measure_f_min,
            measure_f_max,
            measure_points,
            amplitude_deg,
            disturbance,
            settle,
            cycles,
            periods,
            threads,
            no_plot,
            quiet,
            set,
        } => {
            use ehservo::freq::cli;
            check_threads(threads)?;
            let s = load(&scenario, &set)?;
            let dir = match out {
                Some(d) => d,
                None => default_out(&format!("{}-freq", s.name))?,
            };
            let mut o = ehservo::freq::report::FreqOptions::defaults();
            o.at = cli::operating_point(at, trim);
            o.side = cli::side(side.as_deref());
            o.discretisation = cli::discretisation(&discretise);
            (o.f_min, o.f_max, o.points) = (f_min, f_max, points);
            o.methods = cli::methods(&measure, &scenario.display().to_string())?;
            (o.measure_f_min, o.measure_f_max, o.measure_points) =
                (measure_f_min, measure_f_max, measure_points);
            o.settings.amplitude = amplitude_deg * ehservo::core::math::DR;
            o.settings.disturbance = disturbance;
            o.settings.settle_s = settle;
            o.settings.cycles = cycles;
            o.periods = periods;
            o.plots = !no_plot;
            let start = Instant::now();
            let r = cli::freq_cmd(&s, &scenario, &o, &dir, threads)?;
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
        Command::Schema { format, markdown } => {
            if markdown {
                put!(w, "{}", ehservo::schema::markdown(format));
            } else {
                put!(w, "{}", ehservo::schema::schema_text(format));
            }
            Ok(())
        }
        Command::Defaults => {
            let s = Scenario {
                name: "fig2".into(),
                description: "The paper's Fig. 2 case (every default).".into(),
                ..Scenario::default()
            };
            put!(w, "{}", s.to_toml());
            Ok(())
        }
    }
}

/// `--float`'s value (checked by clap).
fn ehservo_wire_float(s: &str) -> ehservo_wire::msg::FloatType {
    ehservo::pil::parse_float(s).unwrap_or(ehservo_wire::msg::FloatType::F64)
}

fn fmt_opt(v: Option<f64>, digits: usize, unit: &str) -> String {
    match v {
        Some(x) => format!("{x:.digits$}{unit}"),
        None => "—".into(),
    }
}

fn print_summary(
    w: &mut impl Write,
    s: &Scenario,
    r: &ehservo::run::RunResult,
    secs: f64,
) -> Result<()> {
    let m = &r.metrics;
    let unit = m.axis.suffix();
    let sim = &s.simulation;
    out!(
        w,
        "{}: {} on the {} plant, {} (h = {} s{}), horizon {} s",
        s.name,
        s.controller.kind(),
        s.plant.model(),
        sim.mode.as_str(),
        sim.step,
        if sim.mode == ehservo::simulation::Mode::Sampled {
            format!(", {} RK4 substep(s)", sim.substeps)
        } else {
            String::new()
        },
        sim.horizon
    );
    match r.outcome.diverged {
        Some(d) => {
            out!(
                w,
                "  UNBOUNDED at t = {:.4} s: {}",
                d.t,
                d.reason.describe()
            );
            // The hint `ehservo analyze` gives: is the scheme itself unstable?
            if let Some(warning) = ehservo::analysis::analyze(s).closed_loop.warning {
                out!(w, "  hint: {warning}");
            }
        }
        None => out!(w, "  bounded over the horizon"),
    }
    out!(
        w,
        "  e_max   (t ≥ {} s)  {}",
        sim.settle,
        fmt_opt(m.e_max, 4, unit)
    );
    out!(w, "  e_final (last period) {}", fmt_opt(m.e_final, 4, unit));
    out!(
        w,
        "  e_rms   (t ≥ {} s)  {}",
        sim.settle,
        fmt_opt(m.e_rms, 4, unit)
    );
    out!(w, "  u_max                 {}", fmt_opt(m.u_max, 3, " V"));
    out!(
        w,
        "  chattering c[u]       {}",
        fmt_opt(m.chattering, 4, "")
    );
    if m.w_norm_max.is_some() {
        out!(
            w,
            "  ‖W‖ max / final       {} / {}",
            fmt_opt(m.w_norm_max, 3, ""),
            fmt_opt(m.w_norm_final, 3, "")
        );
        out!(
            w,
            "  dead-zone share       {}",
            fmt_opt(m.dead_zone_fraction.map(|f| 100.0 * f), 1, " %")
        );
    }
    out!(
        w,
        "  {} samples simulated in {:.1} ms",
        m.samples,
        secs * 1e3
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::CommandFactory;

    /// Every subcommand's help ends with an example of it (the `ehservo`
    /// line a newcomer can copy).
    #[test]
    fn every_subcommand_has_an_example() {
        let mut cli = Cli::command();
        cli.build();
        let mut n = 0;
        for sub in cli.get_subcommands_mut() {
            let name = sub.get_name().to_string();
            if name == "help" {
                continue;
            }
            let help = sub.render_long_help().to_string();
            let example = help.split_once("Example:").map(|(_, e)| e.trim_start());
            assert!(
                example.is_some_and(|e| e.starts_with(&format!("ehservo {name} "))),
                "`ehservo {name} --help` has no example of itself:\n{help}"
            );
            n += 1;
        }
        assert!(n >= 15, "only {n} subcommands");
    }
}
