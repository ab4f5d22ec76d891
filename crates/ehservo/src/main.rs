//! The `ehservo` command line.

use anyhow::Result;
use clap::{Parser, Subcommand};
use ehservo::output;
use ehservo::run::{run, Keep};
use ehservo::scenario::Scenario;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// Simulate and control electrohydraulic servo systems (Hwang's NNBVSC).
#[derive(Parser)]
#[command(name = "ehservo", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run one scenario: print a summary, write trace.csv, summary.json and trace.png.
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
    },
    /// Parse and validate a scenario and print it with every default filled in.
    Check {
        /// The scenario file (TOML).
        scenario: PathBuf,
        /// Override a key (repeatable).
        #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
        set: Vec<String>,
    },
    /// Re-run the paper's Section IV: every case, every claim scored, figures and a report.
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
    /// Print the default scenario (the paper's Fig. 2 case) as TOML.
    Defaults,
}

/// Bad input: exit code 2.
struct BadInput(String);

fn main() -> ExitCode {
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::BadInput(BadInput(msg))) => {
            eprintln!("error: {msg}");
            ExitCode::from(2)
        }
        Err(Failure::Other(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

enum Failure {
    BadInput(BadInput),
    Other(anyhow::Error),
}

impl From<anyhow::Error> for Failure {
    fn from(e: anyhow::Error) -> Self {
        Failure::Other(e)
    }
}

fn load(path: &std::path::Path, set: &[String]) -> Result<Scenario, Failure> {
    Scenario::load(path, set).map_err(|e| Failure::BadInput(BadInput(e.to_string())))
}

fn dispatch(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        Command::Run {
            scenario,
            out,
            set,
            no_plot,
            quiet,
        } => {
            let s = load(&scenario, &set)?;
            let dir = out.unwrap_or_else(|| PathBuf::from("out").join(&s.name));
            let start = Instant::now();
            let r = run(&s, Keep::Every(s.output.decimate))?;
            let elapsed = start.elapsed();
            let files = output::write_run(&dir, &s, &r, s.output.plot && !no_plot)?;
            if !quiet {
                print_summary(&s, &r, elapsed.as_secs_f64());
                let names: Vec<String> = files
                    .iter()
                    .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
                    .collect();
                println!("wrote {}/{{{}}}", dir.display(), names.join(", "));
            }
            Ok(())
        }
        Command::Check { scenario, set } => {
            let s = load(&scenario, &set)?;
            print!("{}", s.to_toml());
            eprintln!(
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
                return Err(Failure::BadInput(BadInput(format!(
                    "{}: not found (run from the repository root, or pass --paper-dir)",
                    manifest.display()
                ))));
            }
            let opts = ehservo::reproduce::Options {
                paper_dir,
                out: out.clone(),
                progress: !quiet && std::io::stderr().is_terminal(),
                skip_boundaries: false,
                skip_figures: false,
            };
            let start = Instant::now();
            let rep = ehservo::reproduce::reproduce(&opts)?;
            if !quiet {
                println!(
                    "reproduced {} claims under {} readings in {:.1} s; figures use `{}`:",
                    rep.claims.len(),
                    rep.agreements.len(),
                    start.elapsed().as_secs_f64(),
                    rep.primary_reading
                );
                for (r, n) in &rep.agreements {
                    println!("  {r:<18} {n:>2} / {} claims agree", rep.claims.len());
                }
                println!("wrote {}/report.md, report.html, figures/", out.display());
            }
            Ok(())
        }
        Command::Defaults => {
            let s = Scenario {
                name: "fig2".into(),
                description: "The paper's Fig. 2 case (every default).".into(),
                ..Scenario::default()
            };
            print!("{}", s.to_toml());
            Ok(())
        }
    }
}

fn fmt_opt(v: Option<f64>, digits: usize, unit: &str) -> String {
    match v {
        Some(x) => format!("{x:.digits$}{unit}"),
        None => "—".into(),
    }
}

fn print_summary(s: &Scenario, r: &ehservo::run::RunResult, secs: f64) {
    let m = &r.metrics;
    let sim = &s.simulation;
    println!(
        "{}: {} on the {} plant, {} (h = {} s{}), horizon {} s",
        s.name,
        s.controller.kind.as_str(),
        match s.plant.model {
            ehservo::scenario::PlantModel::ThirdOrder => "third-order",
            ehservo::scenario::PlantModel::Physical => "physical",
        },
        sim.mode.as_str(),
        sim.step,
        if sim.mode == ehservo::sim::Mode::Sampled {
            format!(", {} RK4 substep(s)", sim.substeps)
        } else {
            String::new()
        },
        sim.horizon
    );
    match r.outcome.diverged {
        Some(d) => println!("  UNBOUNDED at t = {:.4} s: {}", d.t, d.reason.describe()),
        None => println!("  bounded over the horizon"),
    }
    println!(
        "  e_max   (t ≥ {} s)  {}",
        sim.settle,
        fmt_opt(m.e_max_deg, 4, "°")
    );
    println!("  e_final (last period) {}", fmt_opt(m.e_final_deg, 4, "°"));
    println!(
        "  e_rms   (t ≥ {} s)  {}",
        sim.settle,
        fmt_opt(m.e_rms_deg, 4, "°")
    );
    println!("  u_max                 {}", fmt_opt(m.u_max, 3, " V"));
    println!("  chattering c[u]       {}", fmt_opt(m.chattering, 4, ""));
    if m.w_norm_max.is_some() {
        println!(
            "  ‖W‖ max / final       {} / {}",
            fmt_opt(m.w_norm_max, 3, ""),
            fmt_opt(m.w_norm_final, 3, "")
        );
        println!(
            "  dead-zone share       {}",
            fmt_opt(m.dead_zone_fraction.map(|f| 100.0 * f), 1, " %")
        );
    }
    println!("  {} samples simulated in {:.1} ms", m.samples, secs * 1e3);
}
