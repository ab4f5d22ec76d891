//! `ehservo tune` and `league`: a controller tuned by particle swarm, and every
//! controller of a suite tuned alike and run on every scenario.

use super::{check_threads, progress_bar, StdoutError};
use crate::output;
use anyhow::Result;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// `ehservo tune`.
#[derive(clap::Args)]
pub(super) struct TuneArgs {
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
}

/// `ehservo league`.
#[derive(clap::Args)]
pub(super) struct LeagueArgs {
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
}

/// `ehservo tune`.
pub(super) fn tune(a: TuneArgs, w: &mut impl Write) -> Result<()> {
    let TuneArgs {
        file,
        out,
        threads,
        quiet,
        no_plot,
    } = a;
    check_threads(threads)?;
    let tune = crate::tune::Tune::load(&file)?;
    output::probe_destination(&out)?;
    let pb = progress_bar(tune.file.budget, quiet);
    let start = Instant::now();
    let r = crate::tune::tune_to_dir(&tune, &out, threads, &pb, !no_plot)?;
    pb.finish_and_clear();
    if let Some(why) = r.failure(&tune) {
        // Not a silent "best": the outputs (tune.json, convergence.csv)
        // say what was tried, and no tuned.toml is written.
        anyhow::bail!(
            "{}: {} not tuned: {why} (wrote {}/tune.json)",
            tune.file.name,
            tune.kind,
            out.display()
        );
    }
    if !quiet {
        let params: Vec<String> = r
            .params
            .iter()
            .map(|(k, v)| format!("{k} = {v:.6}"))
            .collect();
        let swarm = r
            .swarm_best
            .as_ref()
            .map(|b| {
                let p: Vec<String> = b
                    .params
                    .iter()
                    .map(|(k, v)| format!("{k} = {v:.6}"))
                    .collect();
                if b.objective.is_finite() {
                    format!(
                        "\n  (the swarm's best, {}, scored {:.5}{}: not better)",
                        p.join(", "),
                        b.objective,
                        tune.axis.suffix()
                    )
                } else {
                    format!("\n  (the swarm's best, {}, was rejected)", p.join(", "))
                }
            })
            .unwrap_or_default();
        out!(
            w,
            "{}: {} tuned in {} evaluations ({:.2} s): objective {:.5}{}{}\n  {}{}{}\n  {}\nwrote {}/tuned.toml",
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
            if r.kept_defaults && params.is_empty() {
                "the kind's defaults".to_string()
            } else {
                params.join(", ")
            },
            if r.kept_defaults && !params.is_empty() {
                " (the kind's defaults)"
            } else {
                ""
            },
            swarm,
            r.verification
                .as_ref()
                .map(|v| v.summary(tune.axis.suffix()))
                .unwrap_or_default(),
            out.display()
        );
    }
    Ok(())
}

/// `ehservo league`.
pub(super) fn league(a: LeagueArgs, w: &mut impl Write) -> Result<()> {
    let LeagueArgs {
        file,
        out,
        threads,
        quiet,
        no_plot,
    } = a;
    check_threads(threads)?;
    let league = crate::league::League::load(&file)?;
    output::probe_destination(&out)?;
    let pb = progress_bar(league.work(), quiet);
    let start = Instant::now();
    let r = crate::league::league_to_dir(&league, &out, threads, &pb, !no_plot)?;
    pb.finish_and_clear();
    if !quiet {
        let findings: Vec<Vec<crate::behaviour::Finding>> = r
            .cells
            .iter()
            .filter_map(|c| c.metrics.map(|m| m.behaviour.findings(m.diverged)))
            .collect();
        let rows = crate::league::report::rows(&league, &r);
        let ranks = crate::league::report::ranks(&league, &rows);
        let mut best: Vec<usize> = (0..ranks.len()).collect();
        best.sort_by(|&a, &b| ranks[a].1.total_cmp(&ranks[b].1).then(a.cmp(&b)));
        out!(
            w,
            "{}: {} controllers × {} scenarios ({} runs: {}) in {:.1} s; mean rank: {}\nwrote {}/league.md, league.html, league.csv",
            league.file.name,
            league.contestants.len(),
            league.cases.len(),
            r.cells.len(),
            crate::behaviour::tally_text(&crate::behaviour::tally(
                findings.iter().map(Vec::as_slice)
            )),
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
