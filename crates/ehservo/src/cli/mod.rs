//! The `ehservo` command line's commands: the arguments clap parses (the
//! [`Cli`]), and each command's body, one file per family of commands.
//! `src/main.rs` parses, calls [`dispatch`] and maps errors to exit codes.

use crate::scenario::Loop;
use anyhow::Result;
use clap::{Parser, Subcommand};
use std::io::Write;
use std::path::PathBuf;

/// Most worker threads `--threads` accepts.
const MAX_THREADS: usize = 1024;

/// A failed write to standard output, kept apart from other I/O errors: a
/// closed pipe ends the command quietly.
#[derive(Debug)]
pub struct StdoutError(pub std::io::Error);

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

mod export;
mod freq;
mod identify;
mod run;
mod study;
mod tune;

/// Simulate and control electrohydraulic servo systems (Hwang's NNBVSC).
#[derive(Parser)]
#[command(
    name = "ehservo",
    version = concat!(env!("CARGO_PKG_VERSION"), " (commit ", env!("EHSERVO_COMMIT"), ")"),
    about,
    long_about = None
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run one scenario: print a summary, write trace.csv, summary.json and trace.png.
    #[command(
        after_help = "Example:\n  ehservo run scenarios/paper/fig2.toml --set simulation.horizon=5 --no-plot --out out/fig2"
    )]
    Run(run::RunArgs),
    /// Processor-in-the-loop: the controller on a board (QEMU's Cortex-M4F or a serial port), the rest simulated here in lock-step; writes run's outputs and pil.csv.
    #[command(
        after_help = "Example:\n  ehservo pil scenarios/paper/fig2.toml --set simulation.step=0.001 --qemu   (after: cd examples/firmware-pil && cargo build --release)"
    )]
    Pil(run::PilArgs),
    /// What the theory says about a scenario: poles, K1/K2 and Theorem 2's bound, Remark 6, the σ-loop and the integrator.
    #[command(
        after_help = "Example:\n  ehservo analyze scenarios/paper/fig2.toml --set controller.gamma1=200"
    )]
    Analyze(run::AnalyzeArgs),
    /// Parse and validate a scenario and print it with every default filled in.
    #[command(
        after_help = "Example:\n  ehservo check scenarios/examples/step.toml --set reference.amplitude_deg=2"
    )]
    Check(run::CheckArgs),
    /// Re-run the paper's Section IV: every case, every claim scored, figures and a report.
    #[command(after_help = "Example:\n  ehservo reproduce --out out/reproduce")]
    Reproduce(study::ReproduceArgs),
    /// Run a study (grid sweep and/or Monte Carlo) in parallel: results.csv, study.json, plots.
    #[command(
        after_help = "Example:\n  ehservo sweep scenarios/studies/gamma1-eta.toml --out out/gamma1-eta --shard 0/4"
    )]
    Sweep(study::SweepArgs),
    /// Tune a controller's parameters over a set of scenarios by particle swarm: tuned.toml, convergence.csv/png, tune.json.
    #[command(
        after_help = "Example:\n  ehservo tune scenarios/league/tune-pid-fig2.toml --out out/tune-pid"
    )]
    Tune(tune::TuneArgs),
    /// Run a league: every controller of a suite (tuned with the same budget, or with given parameters) on every scenario: league.md/html/csv, runs.csv, figures.
    #[command(
        after_help = "Example:\n  ehservo league scenarios/league/suite.toml --out out/league"
    )]
    League(tune::LeagueArgs),
    /// Join the outputs of sharded sweeps into one results.csv.
    #[command(
        after_help = "Example:\n  ehservo merge shards/* --out merged     (ehservo merge --missing shards/*: the shards to rerun)"
    )]
    Merge(study::MergeArgs),
    /// Print the default scenario (the paper's Fig. 2 case) as TOML.
    #[command(after_help = "Example:\n  ehservo defaults > my-case.toml")]
    Defaults,
    /// Print the JSON Schema of a file format (or, with --markdown, its reference page, docs/reference/).
    ///
    /// Example: ehservo schema scenario > scenario.schema.json
    Schema(export::SchemaArgs),
    /// Design an identification experiment: excitation.csv for a rig and scenario.toml that simulates it (docs/identification.md).
    #[command(
        after_help = "Example:\n  ehservo excite --signal multisine --duration 20 --out out/experiment"
    )]
    Excite(identify::ExciteArgs),
    /// Identify a servo from logged (t, u, y) data: frequency response, linear and grey-box fits, identified.toml (docs/identification.md).
    #[command(
        after_help = "Example:\n  ehservo identify out/run/trace.csv --pressure none --out out/identified   (out/run: ehservo run out/experiment/scenario.toml --out out/run)"
    )]
    Identify(Box<identify::IdentifyArgs>),
    /// Linearise the loop at an operating point: plant, actuator, delays and a linear controller as state-space models, with poles, zeros, DC gain and damping (JSON; docs/frequency.md).
    #[command(
        after_help = "Example:\n  ehservo linearize scenarios/frequency/pid-nominal.toml --trim"
    )]
    Linearize(freq::LinearizeArgs),
    /// Frequency responses of the loop (G, C, L, S, T, θ/θd, θ/d) with margins, computed and measured on the simulator: freq.json, CSVs, Bode and Nyquist plots (docs/frequency.md).
    #[command(
        after_help = "Example:\n  ehservo freq scenarios/frequency/pid-nominal.toml --out out/freq"
    )]
    Freq(freq::FreqArgs),
    /// Export the scenario's controller (or, with --closed-loop, its whole loop; with --plant, its plant and actuator) as an FMI 3.0 co-simulation FMU.
    #[command(
        after_help = "Example:\n  ehservo fmu scenarios/paper/fig2.toml --closed-loop --out fig2-loop.fmu\n  ehservo fmu scenarios/cylinders/slide.toml --plant --out slide-plant.fmu"
    )]
    Fmu(export::FmuArgs),
}

/// Whether the error is standard output closed by its reader.
pub fn closed_stdout(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<StdoutError>()
            .is_some_and(|s| s.0.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// `--threads`, when given, within 1..=MAX_THREADS.
fn check_threads(threads: Option<usize>) -> Result<()> {
    if let Some(t) = threads {
        if !(1..=MAX_THREADS).contains(&t) {
            crate::bad_input!("--threads {t}: must be between 1 and {MAX_THREADS}");
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

/// The scenario's name as the folder of its default output, `out/<name>`:
/// one plain name, never a path that leads elsewhere.
fn default_out(name: &str) -> Result<PathBuf> {
    if name.is_empty() || name == "." || name.contains("..") || name.contains(['/', '\\', '\0']) {
        crate::bad_input!(
            "`name` = {name:?}: must be a plain name without '/' or '..' to be used as the output folder; pass --out"
        );
    }
    Ok(PathBuf::from("out").join(name))
}

/// A scenario file, read with its `--set` overrides and built.
fn load(path: &std::path::Path, set: &[String]) -> Result<Loop> {
    Ok(crate::formats::load(path, set)?)
}

/// Runs the parsed command, writing its output to `w`.
pub fn dispatch(cli: Cli, w: &mut impl Write) -> Result<()> {
    match cli.command {
        Command::Run(a) => run::run(a, w),
        Command::Pil(a) => run::pil(a, w),
        Command::Analyze(a) => run::analyze(a, w),
        Command::Check(a) => run::check(a, w),
        Command::Reproduce(a) => study::reproduce(a, w),
        Command::Sweep(a) => study::sweep(a, w),
        Command::Tune(a) => tune::tune(a, w),
        Command::League(a) => tune::league(a, w),
        Command::Merge(a) => study::merge(a, w),
        Command::Defaults => export::defaults(w),
        Command::Schema(a) => export::schema(a, w),
        Command::Excite(a) => identify::excite(a, w),
        Command::Identify(a) => identify::identify(*a, w),
        Command::Linearize(a) => freq::linearize(a, w),
        Command::Freq(a) => freq::freq(a, w),
        Command::Fmu(a) => export::fmu(a),
    }
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
