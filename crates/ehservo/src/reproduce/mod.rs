//! `ehservo reproduce`: the paper's Section IV, regenerated and scored.
//!
//! 1. Every case of `scenarios/paper/manifest.toml` is run under every
//!    reading of the simulation set-up (in parallel, with a progress bar).
//! 2. Every claim of the paper is scored under every reading; the reading
//!    with the most agreements is chosen for the figures (ties: the first in
//!    the manifest) — the choice is by evidence, and the report shows the
//!    whole matrix.
//! 3. The traditional VSC's breaking point and the NNBVSC's margin are
//!    searched in every reading.
//! 4. Figures (PNG and SVG), `report.md`, `report.html` (figures embedded),
//!    `claims.csv` and `results.json` are written through a staging
//!    directory.

pub mod b_question;
pub mod breaking;
mod cases;
pub mod claims;
pub mod convergence;
pub mod derived;
pub mod doc;
pub mod figures;
pub mod manifest;
mod report;
mod sections;
pub mod stochastic;

pub use cases::load_cases;

use crate::output::{write_atomic, Staging, SOFTWARE};
use crate::run::{run, Keep, RunResult};
use crate::scenario::Loop;
use anyhow::{Context, Result};
use breaking::Boundary;
use cases::{bar, boundaries, measure, sensitivity};
use claims::{Status, Verdict};
use convergence::Estimate;
use derived::CaseMetrics;
use manifest::Manifest;
use rayon::prelude::*;
use report::{claims_csv, report};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Options of a reproduction.
#[derive(Debug, Clone)]
pub struct Options {
    /// Directory holding `manifest.toml` and the case files.
    pub paper_dir: PathBuf,
    /// Output directory.
    pub out: PathBuf,
    /// Show a progress bar (when stderr is a terminal).
    pub progress: bool,
    /// Skip the boundary searches (faster; for tests).
    pub skip_boundaries: bool,
    /// Skip the figures (faster; for tests).
    pub skip_figures: bool,
    /// Seeds of the random cases instead of the manifest's `[stochastic]`.
    pub seeds: Option<u32>,
}

/// One case run under one reading.
#[derive(Debug, Clone, Serialize)]
pub struct CaseRun {
    /// Case id.
    pub case: String,
    /// Reading id.
    pub reading: String,
    /// The converged metrics (the finest level run).
    pub metrics: CaseMetrics,
    /// Every level run, the perturbed run, and whether it converged.
    pub estimate: Estimate,
}

/// A claim scored under every reading.
#[derive(Debug, Clone, Serialize)]
pub struct ClaimRow {
    /// Claim id.
    pub id: String,
    /// The verdict per reading id.
    pub verdicts: BTreeMap<String, Verdict>,
}

/// One case under one sensitivity variation.
#[derive(Debug, Clone, Serialize)]
pub struct SensitivityRow {
    /// Sensitivity id.
    pub id: String,
    /// Case id.
    pub case: String,
    /// The case under the chosen reading.
    pub baseline: CaseMetrics,
    /// The case with the variation (one run), or the run of seed 0.
    pub variant: CaseMetrics,
    /// With seeds: e_max_deg of every seed (None where undefined).
    pub seeds_e_max_deg: Vec<Option<f64>>,
}

/// Everything a reproduction measured.
#[derive(Debug, Clone, Serialize)]
pub struct Reproduction {
    /// Software name and version.
    pub software: crate::output::Software,
    /// The reading chosen for the figures.
    pub primary_reading: String,
    /// Agreements per reading.
    pub agreements: BTreeMap<String, usize>,
    /// Every case under every reading.
    pub runs: Vec<CaseRun>,
    /// Every claim under every reading.
    pub claims: Vec<ClaimRow>,
    /// The traditional VSC's breaking points.
    pub vsc_breaking: Vec<Boundary>,
    /// The NNBVSC's margins.
    pub nn_margin: Vec<Boundary>,
    /// How much each ambiguity moves the results.
    pub sensitivity: Vec<SensitivityRow>,
    /// The claims on random cases, over many seeds.
    pub stochastic: stochastic::Stochastic,
    /// `ehservo analyze` of the Fig. 2 case under every reading.
    pub theory: Vec<(String, crate::analysis::Analysis)>,
    /// Condition 4) and the dead zone along Fig. 2 under the chosen reading.
    pub fig2_diagnostics: Option<crate::analysis::RunDiagnostics>,
}

/// Every case's estimate under every reading: by reading id, then case id.
type ByReading = BTreeMap<String, BTreeMap<String, Estimate>>;

/// A case under a reading: (reading index, case index, its scenario).
type Job = (usize, usize, Loop);

/// Runs the whole reproduction and writes its outputs.
pub fn reproduce(opts: &Options) -> Result<Reproduction> {
    let manifest = Manifest::load(&opts.paper_dir.join("manifest.toml"))?;
    let jobs = load_cases(&manifest, &opts.paper_dir)?;

    // 1. Every case under every reading, refined until converged.
    let (runs, by_reading) = estimate_all(&manifest, &jobs, opts)?;
    let converged_jobs: Vec<Job> = jobs
        .iter()
        .map(|(ri, ci, _)| {
            let set = converged_set(&manifest, &by_reading, *ri, &manifest.case[*ci].id);
            let s = Loop::load(&opts.paper_dir.join(&manifest.case[*ci].file), &set)?;
            Ok((*ri, *ci, s))
        })
        .collect::<Result<_>>()?;
    // Claims on random cases are judged over many seeds, under every
    // reading (each case at its converged level).
    let seeded: Vec<stochastic::Stochastic> = (0..manifest.reading.len())
        .map(|ri| {
            let base: BTreeMap<String, CaseMetrics> = by_reading[&manifest.reading[ri].id]
                .iter()
                .map(|(k, e)| (k.clone(), *e.best()))
                .collect();
            stochastic::run(
                &manifest,
                &converged_jobs,
                ri,
                &base,
                opts.seeds,
                opts.progress,
            )
        })
        .collect::<Result<_>>()?;

    // 2. Claims (on the converged results), and the reading with the most
    // agreements.
    let claims = score_claims(&manifest, &by_reading, &seeded);
    let (agreements, primary) = choose_reading(&manifest, &claims);

    // 3. Sensitivity of the results to the remaining ambiguities.
    let primary_idx = manifest
        .reading
        .iter()
        .position(|r| r.id == primary)
        .unwrap_or(0);
    let baseline: BTreeMap<String, (CaseMetrics, Vec<String>)> = manifest
        .case
        .iter()
        .map(|c| {
            let e = &by_reading[&primary][&c.id];
            let set = converged_set(&manifest, &by_reading, primary_idx, &c.id);
            (c.id.clone(), (*e.best(), set))
        })
        .collect();
    let sensitivity = sensitivity(&manifest, &opts.paper_dir, &baseline, opts.progress)?;

    // 4. Boundaries.
    let (vsc_breaking, nn_margin) = if opts.skip_boundaries {
        (Vec::new(), Vec::new())
    } else {
        boundary_scans(&manifest, &by_reading, opts)?
    };

    // 5. What the theory says of the Fig. 2 case, reading by reading.
    let theory = fig2_theory(&manifest, &converged_jobs);
    let fig2_diagnostics = fig2_diagnostics(&manifest, &converged_jobs, primary_idx)?;

    let rep = Reproduction {
        software: SOFTWARE,
        primary_reading: primary.clone(),
        agreements,
        runs,
        claims,
        vsc_breaking,
        nn_margin,
        sensitivity,
        stochastic: seeded[primary_idx].clone(),
        theory,
        fig2_diagnostics,
    };

    // 5. Outputs.
    let stage = Staging::new(&opts.out)?;
    let dir = stage.path().to_path_buf();
    let figs = if opts.skip_figures {
        Vec::new()
    } else {
        write_figures(&manifest, &converged_jobs, &rep, &dir, opts.progress)?
    };
    write_reports(&manifest, &rep, &figs, &dir)?;
    stage
        .commit()
        .context("moving the reproduction into place")?;
    Ok(rep)
}

/// Every case under every reading, refined until converged (in parallel,
/// with a progress bar): each one's run, and the estimates by reading.
fn estimate_all(
    manifest: &Manifest,
    jobs: &[Job],
    opts: &Options,
) -> Result<(Vec<CaseRun>, ByReading)> {
    let pb = bar(opts.progress, jobs.len() as u64, "cases");
    let estimates: Vec<Estimate> = jobs
        .par_iter()
        .map(|(ri, ci, _)| {
            let (r, c) = (&manifest.reading[*ri], &manifest.case[*ci]);
            let e = convergence::estimate(
                &opts.paper_dir,
                &c.file,
                r,
                &manifest.convergence,
                convergence::checked_metrics(manifest, &c.id),
                &|s| measure(s, false).map(|x| x.0),
            );
            pb.inc(1);
            e
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    let mut by_reading: ByReading = BTreeMap::new();
    let mut runs = Vec::new();
    for ((ri, ci, _), est) in jobs.iter().zip(estimates) {
        let (r, c) = (&manifest.reading[*ri].id, &manifest.case[*ci].id);
        runs.push(CaseRun {
            case: c.clone(),
            reading: r.clone(),
            metrics: *est.best(),
            estimate: est.clone(),
        });
        by_reading
            .entry(r.clone())
            .or_default()
            .insert(c.clone(), est);
    }
    Ok((runs, by_reading))
}

/// The overrides that give a case's converged result under reading `ri`.
fn converged_set(
    manifest: &Manifest,
    by_reading: &ByReading,
    ri: usize,
    case: &str,
) -> Vec<String> {
    let r = &manifest.reading[ri];
    convergence::set_at(r, by_reading[&r.id][case].best_value())
}

/// Every claim scored under every reading. A random case's claim is
/// judged on its seeds — unless a case it reads did not converge on its
/// metric (then the single-run scoring says undecided, and why).
fn score_claims(
    manifest: &Manifest,
    by_reading: &ByReading,
    seeded: &[stochastic::Stochastic],
) -> Vec<ClaimRow> {
    let mut claims = Vec::new();
    for c in &manifest.claim {
        let verdicts = manifest
            .reading
            .iter()
            .zip(seeded)
            .map(|(r, st)| {
                let results = &by_reading[&r.id];
                let v = match (
                    claims::unconverged(c, results),
                    st.claims.iter().find(|d| d.claim == c.id),
                ) {
                    (Some(u), _) => u,
                    (None, Some(d)) => stochastic::verdict(c, d),
                    (None, None) => claims::evaluate(c, results),
                };
                (r.id.clone(), v)
            })
            .collect();
        claims.push(ClaimRow {
            id: c.id.clone(),
            verdicts,
        });
    }
    claims
}

/// The agreements of each reading, and the reading with the most (ties:
/// the first in the manifest).
fn choose_reading(manifest: &Manifest, claims: &[ClaimRow]) -> (BTreeMap<String, usize>, String) {
    let mut agreements = BTreeMap::new();
    for r in &manifest.reading {
        let n = claims
            .iter()
            .filter(|c| c.verdicts[&r.id].status == Status::Agree)
            .count();
        agreements.insert(r.id.clone(), n);
    }
    let primary = manifest
        .reading
        .iter()
        .max_by(|a, b| {
            agreements[&a.id]
                .cmp(&agreements[&b.id])
                .then(std::cmp::Ordering::Greater)
        })
        .map(|r| r.id.clone())
        .unwrap_or_default();
    (agreements, primary)
}

/// The traditional VSC's breaking points and the NNBVSC's margins, in
/// every reading.
fn boundary_scans(
    manifest: &Manifest,
    by_reading: &ByReading,
    opts: &Options,
) -> Result<(Vec<Boundary>, Vec<Boundary>)> {
    let sets: Vec<(String, Vec<String>, Vec<String>)> = (0..manifest.reading.len())
        // Both scans run at the level where the Fig. 2 NNBVSC converged.
        // Not at Fig. 3's: in continuous time the sgn law's error tends
        // to 0 with the step and its ladder runs to the finest level
        // (10 µs: 300 runs of 10⁶ steps). Its bounded status is settled
        // from the third level on, and a finer step only lowers its
        // error, so its tracking threshold there is conservative.
        .map(|ri| {
            let at = converged_set(manifest, by_reading, ri, "fig2");
            (manifest.reading[ri].id.clone(), at.clone(), at)
        })
        .collect();
    boundaries(&sets, &opts.paper_dir, opts.progress)
}

/// `ehservo analyze` of the Fig. 2 case's file under every reading.
fn fig2_theory(
    manifest: &Manifest,
    converged_jobs: &[Job],
) -> Vec<(String, crate::analysis::Analysis)> {
    let fig2_file = manifest
        .case
        .iter()
        .find(|c| c.id == "fig2")
        .map(|c| &c.file);
    converged_jobs
        .iter()
        .filter(|(_, ci, _)| Some(&manifest.case[*ci].file) == fig2_file)
        .map(|(ri, _, s)| {
            (
                manifest.reading[*ri].id.clone(),
                crate::analysis::analyze(s),
            )
        })
        .collect()
}

/// Condition 4) and the dead zone along the Fig. 2 case's run under the
/// chosen reading.
fn fig2_diagnostics(
    manifest: &Manifest,
    converged_jobs: &[Job],
    primary_idx: usize,
) -> Result<Option<crate::analysis::RunDiagnostics>> {
    Ok(converged_jobs
        .iter()
        .find(|(ri, ci, _)| *ri == primary_idx && manifest.case[*ci].id == "fig2")
        .map(|(_, _, s)| -> Result<_> {
            let stride = (s.sim().steps + 1).div_ceil(crate::output::MAX_KEPT).max(1);
            let r = run(s, Keep::Every(stride as u32));
            Ok(crate::analysis::diagnostics(s.scenario(), &r.trace))
        })
        .transpose()?
        .flatten())
}

/// The figures (PNG and SVG) into `dir/figures`: the paper's, from the
/// cases run again under the chosen reading with their traces kept, the
/// boundary scans', and the random cases'. Each one's file and caption.
fn write_figures(
    manifest: &Manifest,
    converged_jobs: &[Job],
    rep: &Reproduction,
    dir: &Path,
    progress: bool,
) -> Result<Vec<(String, String)>> {
    let mut figs: Vec<(String, String)> = Vec::new();
    let primary_idx = manifest
        .reading
        .iter()
        .position(|r| r.id == rep.primary_reading)
        .unwrap_or(0);
    let pjobs: Vec<&Job> = converged_jobs
        .iter()
        .filter(|j| j.0 == primary_idx)
        .collect();
    let pb = bar(progress, pjobs.len() as u64, "figure runs");
    let traces: Vec<(String, RunResult)> = pjobs
        .par_iter()
        .map(|(_, ci, s)| {
            let r =
                measure(s, true).map(|(_, r)| (manifest.case[*ci].id.clone(), r.expect("kept")));
            pb.inc(1);
            r
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    let traces: BTreeMap<String, RunResult> = traces.into_iter().collect();
    let ctx = figures::FigureContext {
        reading: &manifest.reading[primary_idx],
        scenarios: pjobs
            .iter()
            .map(|j| (manifest.case[j.1].id.clone(), &j.2))
            .collect(),
    };
    let mut all = figures::paper_figures(&traces, &ctx);
    if !rep.vsc_breaking.is_empty() {
        all.push(figures::boundary_figure(
            "vsc-breaking",
            "Traditional VSC: max |e| against the bias fraction x (R1: bounds of Fig. 2; R2: bounds = x)",
            "bias fraction x",
            &rep.vsc_breaking,
        ));
    }
    if !rep.nn_margin.is_empty() {
        all.push(figures::boundary_figure(
            "nnvsc-margin",
            "NNBVSC: max |e| against the a_i bias fraction (b bias 0.5)",
            "a_i bias fraction",
            &rep.nn_margin,
        ));
    }
    std::fs::create_dir_all(dir.join("figures"))?;
    let pb = bar(progress, all.len() as u64, "figures");
    let rendered: Vec<Result<(String, String)>> = all
        .par_iter()
        .map(|f| {
            let png = dir.join("figures").join(format!("{}.png", f.stem));
            let svg = dir.join("figures").join(format!("{}.svg", f.stem));
            f.figure.png(&png)?;
            f.figure.svg(&svg)?;
            pb.inc(1);
            Ok((format!("figures/{}.png", f.stem), f.caption.clone()))
        })
        .collect();
    pb.finish_and_clear();
    for r in rendered {
        figs.push(r?);
    }
    figs.extend(stochastic::write_figures(manifest, &rep.stochastic, dir)?);
    Ok(figs)
}

/// `report.md`, `report.html` (figures embedded), `results.json` and
/// `claims.csv` into `dir`.
fn write_reports(
    manifest: &Manifest,
    rep: &Reproduction,
    figs: &[(String, String)],
    dir: &Path,
) -> Result<()> {
    let doc = report(manifest, rep, figs);
    write_atomic(&dir.join("report.md"), doc.to_markdown().as_bytes())?;
    write_atomic(
        &dir.join("report.html"),
        doc.to_html("ehservo — reproduction of Hwang's NNBVSC, Section IV", dir)
            .as_bytes(),
    )?;
    write_atomic(
        &dir.join("results.json"),
        serde_json::to_string_pretty(rep)?.as_bytes(),
    )?;
    write_atomic(
        &dir.join("claims.csv"),
        claims_csv(manifest, rep)?.as_bytes(),
    )?;
    Ok(())
}
