//! `ehservo reproduce`, `sweep` and `merge`: the paper's Section IV re-run, and
//! studies run in parallel, sharded and joined.

use super::{check_threads, StdoutError};
use crate::output;
use anyhow::Result;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// `ehservo reproduce`.
#[derive(clap::Args)]
pub(super) struct ReproduceArgs {
    /// Output directory.
    #[arg(long, default_value = "out/reproduce")]
    out: PathBuf,
    /// Directory with manifest.toml and the case files.
    #[arg(long, default_value = "scenarios/paper")]
    paper_dir: PathBuf,
    /// No progress bar, no summary.
    #[arg(long, short)]
    quiet: bool,
}

/// `ehservo sweep`.
#[derive(clap::Args)]
pub(super) struct SweepArgs {
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
}

/// `ehservo merge`.
#[derive(clap::Args)]
pub(super) struct MergeArgs {
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
}

/// `ehservo reproduce`.
pub(super) fn reproduce(a: ReproduceArgs, w: &mut impl Write) -> Result<()> {
    let ReproduceArgs {
        out,
        paper_dir,
        quiet,
    } = a;
    use std::io::IsTerminal;
    let manifest = paper_dir.join("manifest.toml");
    if !manifest.is_file() {
        crate::bad_input!(
            "{}: not found (run from the repository root, or pass --paper-dir)",
            manifest.display()
        );
    }
    // Minutes of runs are not spent before finding the output
    // folder refused or unwritable.
    output::probe_destination(&out)?;
    let opts = crate::reproduce::Options {
        paper_dir,
        out: out.clone(),
        progress: !quiet && std::io::stderr().is_terminal(),
        skip_boundaries: false,
        skip_figures: false,
        seeds: None,
    };
    let start = Instant::now();
    let rep = crate::reproduce::reproduce(&opts)?;
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

/// `ehservo sweep`.
pub(super) fn sweep(a: SweepArgs, w: &mut impl Write) -> Result<()> {
    let SweepArgs {
        study,
        out,
        shard,
        threads,
        quiet,
        no_plot,
        resume,
    } = a;
    use std::io::IsTerminal;
    check_threads(threads)?;
    let plan = crate::study::Plan::load(&study)?;
    let shard = match shard {
        Some(s) => Some(
            crate::study::parse_shard(&s)
                .map_err(|e| crate::error::InputError::Request(format!("--shard: {e}")))?,
        ),
        None => None,
    };
    // Hours of runs are not spent before finding the output
    // folder refused or unwritable.
    output::probe_destination(&out)?;
    let opts = crate::study::SweepOptions {
        out: out.clone(),
        shard,
        threads,
        progress: !quiet && std::io::stderr().is_terminal(),
        plots: !no_plot,
    };
    if resume {
        use crate::study::Resume;
        match crate::study::resume_state(&plan, &opts)? {
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
    let rows = crate::study::sweep(&plan, &opts)?;
    if !quiet {
        let findings: Vec<Vec<crate::behaviour::Finding>> = rows
            .iter()
            .filter_map(|r| r.metrics.map(|m| m.behaviour.findings(m.diverged)))
            .collect();
        let tally = crate::behaviour::tally(findings.iter().map(Vec::as_slice));
        let invalid = rows.iter().filter(|r| r.error.is_some()).count();
        out!(
            w,
            "{}: {} runs{} in {:.2} s ({}{}); wrote {}/results.csv",
            plan.study.name,
            rows.len(),
            match shard {
                Some((k, n)) => format!(" (shard {k}/{n} of {})", plan.runs),
                None => String::new(),
            },
            start.elapsed().as_secs_f64(),
            crate::behaviour::tally_text(&tally),
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

/// `ehservo merge`.
pub(super) fn merge(a: MergeArgs, w: &mut impl Write) -> Result<()> {
    let MergeArgs { dirs, out, missing } = a;
    let Some(out) = out.filter(|_| !missing) else {
        let m = crate::study::missing(&dirs)?;
        for (d, why) in &m.set_aside {
            note!(
                "{}: not a whole shard, counted as missing: {why}",
                d.display()
            );
        }
        let list = crate::study::index_list(&m.missing);
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
    let n = crate::study::merge(&dirs, &out)?;
    out!(
        w,
        "merged {} shard(s), {n} runs, into {}/results.csv",
        dirs.len(),
        out.display()
    );
    Ok(())
}
