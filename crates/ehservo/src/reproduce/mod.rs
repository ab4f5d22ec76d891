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

pub mod breaking;
pub mod claims;
pub mod derived;
pub mod doc;
pub mod figures;
pub mod manifest;

use crate::output::{write_atomic, Staging, SOFTWARE};
use crate::run::{run, Keep, RunResult};
use crate::scenario::Scenario;
use anyhow::{Context, Result};
use breaking::{BiasReading, Boundary};
use claims::{Status, Verdict};
use derived::{format_metric, CaseMetrics};
use doc::{Block, Doc};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use manifest::Manifest;
use rayon::prelude::*;
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
}

/// One case run under one reading.
#[derive(Debug, Clone, Serialize)]
pub struct CaseRun {
    /// Case id.
    pub case: String,
    /// Reading id.
    pub reading: String,
    /// Metrics.
    pub metrics: CaseMetrics,
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
    /// `ehservo analyze` of the Fig. 2 case under every reading.
    pub theory: Vec<(String, crate::analysis::Analysis)>,
    /// Condition 4) and the dead zone along Fig. 2 under the chosen reading.
    pub fig2_diagnostics: Option<crate::analysis::RunDiagnostics>,
}

fn bar(progress: bool, len: u64, msg: &str) -> ProgressBar {
    let pb = ProgressBar::with_draw_target(
        Some(len),
        if progress {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        },
    );
    pb.set_style(
        ProgressStyle::with_template("{msg:>14} [{bar:40}] {pos}/{len} ({eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_message(msg.to_string());
    pb
}

/// Loads every case under every reading (bad input is reported before any
/// run starts).
pub fn load_cases(m: &Manifest, dir: &Path) -> Result<Vec<(usize, usize, Scenario)>> {
    let mut v = Vec::new();
    for (ri, r) in m.reading.iter().enumerate() {
        for (ci, c) in m.case.iter().enumerate() {
            let s =
                Scenario::load(&dir.join(&c.file), &r.set).map_err(|e| anyhow::anyhow!("{e}"))?;
            v.push((ri, ci, s));
        }
    }
    Ok(v)
}

fn measure(s: &Scenario, keep_trace: bool) -> Result<(CaseMetrics, Option<RunResult>)> {
    let r = run(s, Keep::Every(1))?;
    let network = r.metrics.w_norm_max.is_some();
    let cm = CaseMetrics::from_trace(
        r.metrics,
        &r.trace,
        s.simulation.settle,
        s.simulation.horizon,
        s.reference.frequency_hz,
        network,
    );
    Ok((cm, if keep_trace { Some(r) } else { None }))
}

/// Runs the whole reproduction and writes its outputs.
pub fn reproduce(opts: &Options) -> Result<Reproduction> {
    let manifest = Manifest::load(&opts.paper_dir.join("manifest.toml"))?;
    let jobs = load_cases(&manifest, &opts.paper_dir)?;

    // 1. Every case under every reading.
    let pb = bar(opts.progress, jobs.len() as u64, "cases");
    let measured: Vec<CaseMetrics> = jobs
        .par_iter()
        .map(|(_, _, s)| {
            let r = measure(s, false).map(|x| x.0);
            pb.inc(1);
            r
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    let mut by_reading: BTreeMap<String, BTreeMap<String, CaseMetrics>> = BTreeMap::new();
    let mut runs = Vec::new();
    for ((ri, ci, _), cm) in jobs.iter().zip(measured) {
        let (r, c) = (&manifest.reading[*ri].id, &manifest.case[*ci].id);
        by_reading
            .entry(r.clone())
            .or_default()
            .insert(c.clone(), cm);
        runs.push(CaseRun {
            case: c.clone(),
            reading: r.clone(),
            metrics: cm,
        });
    }

    // 2. Claims, and the reading with the most agreements.
    let mut claims = Vec::new();
    for c in &manifest.claim {
        let verdicts = manifest
            .reading
            .iter()
            .map(|r| (r.id.clone(), claims::evaluate(c, &by_reading[&r.id])))
            .collect();
        claims.push(ClaimRow {
            id: c.id.clone(),
            verdicts,
        });
    }
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

    // 3. Sensitivity of the results to the remaining ambiguities.
    let primary_idx = manifest
        .reading
        .iter()
        .position(|r| r.id == primary)
        .unwrap_or(0);
    let sensitivity = sensitivity(
        &manifest,
        &opts.paper_dir,
        primary_idx,
        &by_reading[&primary],
        opts.progress,
    )?;

    // 4. Boundaries.
    let (vsc_breaking, nn_margin) = if opts.skip_boundaries {
        (Vec::new(), Vec::new())
    } else {
        boundaries(&manifest, &opts.paper_dir, opts.progress)?
    };

    // 5. What the theory says of the Fig. 2 case, reading by reading.
    let theory: Vec<(String, crate::analysis::Analysis)> = jobs
        .iter()
        .filter(|(_, ci, _)| manifest.case[*ci].id == "fig2")
        .map(|(ri, _, s)| {
            (
                manifest.reading[*ri].id.clone(),
                crate::analysis::analyze(s),
            )
        })
        .collect();
    let fig2_diagnostics = jobs
        .iter()
        .find(|(ri, ci, _)| *ri == primary_idx && manifest.case[*ci].id == "fig2")
        .map(|(_, _, s)| -> Result<_> {
            let r = run(s, Keep::Every(1))?;
            Ok(crate::analysis::diagnostics(s, &r.trace))
        })
        .transpose()?
        .flatten();

    let rep = Reproduction {
        software: SOFTWARE,
        primary_reading: primary.clone(),
        agreements,
        runs,
        claims,
        vsc_breaking,
        nn_margin,
        sensitivity,
        theory,
        fig2_diagnostics,
    };

    // 5. Outputs.
    let stage = Staging::new(&opts.out)?;
    let dir = stage.path().to_path_buf();
    let mut figs: Vec<(String, String)> = Vec::new();
    if !opts.skip_figures {
        let primary_idx = manifest
            .reading
            .iter()
            .position(|r| r.id == primary)
            .unwrap_or(0);
        let label = manifest.reading[primary_idx].label.clone();
        let pjobs: Vec<&(usize, usize, Scenario)> =
            jobs.iter().filter(|j| j.0 == primary_idx).collect();
        let pb = bar(opts.progress, pjobs.len() as u64, "figure runs");
        let traces: Vec<(String, RunResult)> = pjobs
            .par_iter()
            .map(|(_, ci, s)| {
                let r = measure(s, true)
                    .map(|(_, r)| (manifest.case[*ci].id.clone(), r.expect("kept")));
                pb.inc(1);
                r
            })
            .collect::<Result<_>>()?;
        pb.finish_and_clear();
        let traces: BTreeMap<String, RunResult> = traces.into_iter().collect();
        let mut all = figures::paper_figures(&traces, &label);
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
        let pb = bar(opts.progress, all.len() as u64, "figures");
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
    }

    let doc = report(&manifest, &rep, &figs);
    write_atomic(&dir.join("report.md"), doc.to_markdown().as_bytes())?;
    write_atomic(
        &dir.join("report.html"),
        doc.to_html("ehservo — reproduction of Hwang's NNBVSC, Section IV", &dir)
            .as_bytes(),
    )?;
    write_atomic(
        &dir.join("results.json"),
        serde_json::to_string_pretty(&rep)?.as_bytes(),
    )?;
    write_atomic(
        &dir.join("claims.csv"),
        claims_csv(&manifest, &rep)?.as_bytes(),
    )?;
    stage
        .commit()
        .context("moving the reproduction into place")?;
    Ok(rep)
}

fn sensitivity(
    m: &Manifest,
    dir: &Path,
    reading: usize,
    base: &BTreeMap<String, CaseMetrics>,
    progress: bool,
) -> Result<Vec<SensitivityRow>> {
    // (sensitivity, case, seed) jobs, each a scenario loaded up front.
    let mut jobs: Vec<(usize, usize, Option<u32>, Scenario)> = Vec::new();
    for (si, sv) in m.sensitivity.iter().enumerate() {
        for (ci, case) in sv.cases.iter().enumerate() {
            let file = &m.case.iter().find(|c| &c.id == case).expect("checked").file;
            let seeds: Vec<Option<u32>> = match sv.seeds {
                Some(n) => (0..n.max(1)).map(Some).collect(),
                None => vec![None],
            };
            for seed in seeds {
                let mut set = m.reading[reading].set.clone();
                set.extend(sv.set.iter().cloned());
                if let Some(k) = seed {
                    set.push(format!("uncertainty.seed={k}"));
                }
                let s =
                    Scenario::load(&dir.join(file), &set).map_err(|e| anyhow::anyhow!("{e}"))?;
                jobs.push((si, ci, seed, s));
            }
        }
    }
    let pb = bar(progress, jobs.len() as u64, "sensitivity");
    let results: Vec<CaseMetrics> = jobs
        .par_iter()
        .map(|(_, _, _, s)| {
            let r = measure(s, false).map(|x| x.0);
            pb.inc(1);
            r
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    let mut rows: Vec<SensitivityRow> = Vec::new();
    for ((si, ci, seed, _), cm) in jobs.iter().zip(results) {
        let sv = &m.sensitivity[*si];
        let case = &sv.cases[*ci];
        match rows.iter_mut().find(|r| r.id == sv.id && &r.case == case) {
            Some(row) => row.seeds_e_max_deg.push(cm.base.e_max_deg),
            None => rows.push(SensitivityRow {
                id: sv.id.clone(),
                case: case.clone(),
                baseline: base[case],
                variant: cm,
                seeds_e_max_deg: if seed.is_some() {
                    vec![cm.base.e_max_deg]
                } else {
                    Vec::new()
                },
            }),
        }
    }
    Ok(rows)
}

fn boundaries(m: &Manifest, dir: &Path, progress: bool) -> Result<(Vec<Boundary>, Vec<Boundary>)> {
    let load = |file: &str, set: &[String]| {
        Scenario::load(&dir.join(file), set).map_err(|e| anyhow::anyhow!("{e}"))
    };
    let vsc_grid: Vec<f64> = (0..=30).map(|i| i as f64 * 0.05).collect();
    let nn_grid: Vec<f64> = (0..=40).map(|i| i as f64 * 0.25).collect();
    // (reading id, bias reading, base scenario with the reading applied)
    let mut tasks: Vec<(String, Option<BiasReading>, Scenario)> = Vec::new();
    for r in &m.reading {
        let vsc_base = load("fig3.toml", &r.set)?;
        for br in [BiasReading::R1, BiasReading::R2] {
            tasks.push((r.id.clone(), Some(br), vsc_base.clone()));
        }
        tasks.push((r.id.clone(), None, load("fig2.toml", &r.set)?));
    }
    let pb = bar(progress, tasks.len() as u64, "boundaries");
    let results: Vec<Boundary> = tasks
        .par_iter()
        .map(|(rid, br, base)| {
            let found = match br {
                Some(b) => {
                    let (b, b_ref) = (*b, base.uncertainty.b_reference);
                    // R2 tells the controller β = b_ref·x·b̄, which must stay < b̄.
                    let grid: Vec<f64> = vsc_grid
                        .iter()
                        .copied()
                        .filter(|&x| b == BiasReading::R1 || b_ref * x < 1.0)
                        .collect();
                    breaking::search(base, &grid, &|x| breaking::vsc_sets(b, b_ref, x), None, 10)?
                }
                None => breaking::search(base, &nn_grid, &breaking::nn_sets, Some(0.5), 10)?,
            };
            pb.inc(1);
            Ok(Boundary {
                reading: rid.clone(),
                bias_reading: *br,
                found,
            })
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    let (vsc, nn): (Vec<Boundary>, Vec<Boundary>) =
        results.into_iter().partition(|b| b.bias_reading.is_some());
    Ok((vsc, nn))
}

fn claims_csv(m: &Manifest, rep: &Reproduction) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "claim", "reading", "status", "measured", "detail", "source", "text",
    ])?;
    for (c, row) in m.claim.iter().zip(&rep.claims) {
        for r in &m.reading {
            let v = &row.verdicts[&r.id];
            w.write_record([
                &c.id,
                &r.id,
                v.status.word(),
                &v.measured,
                &v.detail,
                &c.source,
                &c.text,
            ])?;
        }
    }
    Ok(String::from_utf8(
        w.into_inner().map_err(|e| anyhow::anyhow!("{e}"))?,
    )?)
}

fn fmt_boundary(b: &Boundary) -> String {
    match (b.found.last_ok, b.found.first_fail) {
        (_, None) => "never over the scan".into(),
        (None, Some(x)) => format!("already at {x:.3}"),
        (Some(lo), Some(hi)) => format!(
            "{:.3} (bounded at {lo:.4}, fails at {hi:.4})",
            0.5 * (lo + hi)
        ),
    }
}

fn report(m: &Manifest, rep: &Reproduction, figs: &[(String, String)]) -> Doc {
    let mut d = Doc::default();
    let primary = &rep.primary_reading;
    let label = |id: &str| {
        m.reading
            .iter()
            .find(|r| r.id == id)
            .map(|r| r.label.clone())
            .unwrap_or_default()
    };
    d.push(Block::Heading(
        1,
        "Reproduction of Hwang's NNBVSC — Section IV".into(),
    ));
    d.push(Block::Para(format!(
        "Generated by `ehservo reproduce` ({} {}). Every case of `scenarios/paper/` was run under {} readings of the \
paper's \"fourth-order Runge–Kutta with a 0.01-s interval\" and every claim of the paper scored under each. The \
figures use the reading with the most agreements: **{}** ({} of {} claims). Readings, ambiguities and their \
measured effect: `docs/paper-notes.md`.",
        rep.software.name,
        rep.software.version,
        m.reading.len(),
        label(primary),
        rep.agreements[primary],
        m.claim.len()
    )));

    findings(&mut d, m, rep);

    d.push(Block::Heading(
        2,
        "Readings of the simulation set-up".into(),
    ));
    d.push(Block::Table(
        vec![
            "reading".into(),
            "what it means".into(),
            "claims agreeing".into(),
        ],
        m.reading
            .iter()
            .map(|r| {
                vec![
                    format!(
                        "`{}`{}",
                        r.id,
                        if &r.id == primary { " (chosen)" } else { "" }
                    ),
                    r.label.clone(),
                    format!("{} / {}", rep.agreements[&r.id], m.claim.len()),
                ]
            })
            .collect(),
    ));

    d.push(Block::Heading(
        2,
        format!("The paper's claims, measured (reading `{primary}`)"),
    ));
    let rows = m
        .claim
        .iter()
        .zip(&rep.claims)
        .map(|(c, row)| {
            let v = &row.verdicts[primary];
            let mut why = c.note.clone();
            if !v.detail.is_empty() {
                why = format!("{} — {}", v.detail, why);
            }
            vec![
                format!("`{}` ({})", c.case, c.source),
                c.text.clone(),
                v.measured.clone(),
                v.status.word().to_string(),
                why,
            ]
        })
        .collect();
    d.push(Block::Table(
        vec![
            "case".into(),
            "the paper's claim".into(),
            "measured".into(),
            "verdict".into(),
            "why".into(),
        ],
        rows,
    ));

    d.push(Block::Heading(2, "Every claim under every reading".into()));
    let mut head = vec!["claim".to_string()];
    head.extend(m.reading.iter().map(|r| format!("`{}`", r.id)));
    let rows = m
        .claim
        .iter()
        .zip(&rep.claims)
        .map(|(c, row)| {
            let mut r = vec![format!("`{}`", c.id)];
            r.extend(m.reading.iter().map(|rd| {
                let v = &row.verdicts[&rd.id];
                format!("{}: {}", v.status.word(), v.measured)
            }));
            r
        })
        .collect();
    d.push(Block::Table(head, rows));

    d.push(Block::Heading(2, "Key metrics of every case".into()));
    let keys = [
        "e_max_deg",
        "u_max",
        "chattering",
        "w_norm_final",
        "diverged_at_s",
    ];
    let mut head = vec!["case".to_string(), "reading".to_string()];
    head.extend(keys.iter().map(|k| format!("`{k}`")));
    let rows = rep
        .runs
        .iter()
        .filter(|r| &r.reading == primary || r.case == "fig2")
        .map(|r| {
            let mut row = vec![format!("`{}`", r.case), format!("`{}`", r.reading)];
            row.extend(keys.iter().map(|k| {
                r.metrics
                    .get(k)
                    .map(|v| format_metric(k, v))
                    .unwrap_or("—".into())
            }));
            row
        })
        .collect();
    d.push(Block::Table(head, rows));

    sensitivity_section(&mut d, m, rep);
    theory_section(&mut d, rep);

    if !rep.vsc_breaking.is_empty() {
        d.push(Block::Heading(
            2,
            "The traditional VSC's breaking point".into(),
        ));
        d.push(Block::Para(
            "The paper: bounded at 40 % bias, unbounded above 45 %. The bias fraction x at which Theorem 1's \
controller first becomes unbounded (10 s horizon), scanned over x = 0, 0.05, …, 1.5 and bisected to 1e-4. R1: the \
controller keeps the bounds of Fig. 2 while the true variation is x; R2: the controller is told the true size x."
                .into(),
        ));
        let rows = rep
            .vsc_breaking
            .iter()
            .map(|b| {
                vec![
                    format!("`{}`", b.reading),
                    format!("{:?}", b.bias_reading.unwrap_or(BiasReading::R1)),
                    fmt_boundary(b),
                    if b.found.non_monotone {
                        "yes: bounded again further up"
                    } else {
                        "no"
                    }
                    .into(),
                    if b.found
                        .first_fail
                        .is_some_and(|x| x > 0.40 && x <= 0.45 + 1e-9)
                    {
                        "agree"
                    } else {
                        "differ"
                    }
                    .into(),
                ]
            })
            .collect();
        d.push(Block::Table(
            vec![
                "reading".into(),
                "bias reading".into(),
                "first unbounded x".into(),
                "non-monotone".into(),
                "paper's 40–45 %".into(),
            ],
            rows,
        ));
    }
    if !rep.nn_margin.is_empty() {
        d.push(Block::Heading(2, "The NNBVSC's margin".into()));
        d.push(Block::Para(
            "The largest a_i bias fraction (Δb kept at 0.5β) at which the NNBVSC still tracks, i.e. stays bounded \
with max |e| after 2 s below 0.5°; scanned over 0, 0.25, …, 10 and bisected."
                .into(),
        ));
        let rows = rep
            .nn_margin
            .iter()
            .map(|b| {
                vec![
                    format!("`{}`", b.reading),
                    match b.found.last_ok {
                        Some(x) if b.found.first_fail.is_none() => {
                            format!("≥ {x:.2} (the whole scan)")
                        }
                        Some(x) => format!("{x:.3}"),
                        None => "none".into(),
                    },
                    if b.found.non_monotone { "yes" } else { "no" }.into(),
                ]
            })
            .collect();
        d.push(Block::Table(
            vec![
                "reading".into(),
                "largest a_i bias still tracking".into(),
                "non-monotone".into(),
            ],
            rows,
        ));
    }

    if !figs.is_empty() {
        d.push(Block::Heading(2, format!("Figures (reading `{primary}`)")));
        for (path, caption) in figs {
            d.push(Block::Figure(path.clone(), caption.clone()));
        }
    }
    d
}

fn e_max_text(c: &CaseMetrics) -> String {
    match (c.base.e_max_deg, c.base.diverged_at_s) {
        (_, Some(t)) => format!("unbounded at {t:.2} s"),
        (Some(e), None) => format!("{e:.4}°"),
        (None, None) => "—".into(),
    }
}

fn sensitivity_section(d: &mut Doc, m: &Manifest, rep: &Reproduction) {
    if rep.sensitivity.is_empty() {
        return;
    }
    d.push(Block::Heading(
        2,
        "How much each ambiguity moves the results".into(),
    ));
    d.push(Block::Para(format!(
        "Each variation is applied on top of the chosen reading (`{}`); e_max is max |e| after the transient \
window. The discussion is in `docs/paper-notes.md`.",
        rep.primary_reading
    )));
    let rel = |a: Option<f64>, b: f64| match a {
        Some(a) if a > 0.0 => format!("{:+.1} %", 100.0 * (b / a - 1.0)),
        _ => "—".into(),
    };
    let rows = rep
        .sensitivity
        .iter()
        .map(|r| {
            let q = m
                .sensitivity
                .iter()
                .find(|s| s.id == r.id)
                .map(|s| s.question.clone())
                .unwrap_or_default();
            let base = r.baseline.base.e_max_deg;
            let (variant, change) = if r.seeds_e_max_deg.is_empty() {
                let change = match r.variant.base.e_max_deg {
                    Some(b) if !r.variant.base.diverged => rel(base, b),
                    _ => "—".into(),
                };
                (e_max_text(&r.variant), change)
            } else {
                let mut v: Vec<f64> = r.seeds_e_max_deg.iter().flatten().copied().collect();
                v.sort_by(f64::total_cmp);
                let unbounded = r.seeds_e_max_deg.len() - v.len();
                if v.is_empty() {
                    ("all unbounded".into(), "—".into())
                } else {
                    let (lo, hi) = (v[0], v[v.len() - 1]);
                    let med = v[v.len() / 2];
                    let extra = if unbounded > 0 {
                        format!(", {unbounded} unbounded")
                    } else {
                        String::new()
                    };
                    (
                        format!(
                            "{} seeds: min {lo:.4}°, median {med:.4}°, max {hi:.4}°{extra}",
                            r.seeds_e_max_deg.len()
                        ),
                        format!("{} … {}", rel(base, lo), rel(base, hi)),
                    )
                }
            };
            vec![
                format!("`{}`: {q}", r.id),
                format!("`{}`", r.case),
                e_max_text(&r.baseline),
                variant,
                change,
            ]
        })
        .collect();
    d.push(Block::Table(
        vec![
            "variation".into(),
            "case".into(),
            "baseline e_max".into(),
            "with the variation".into(),
            "change".into(),
        ],
        rows,
    ));
}

/// Which claims hold in which readings, in a few lines. Readings in which
/// the NNBVSC of Fig. 2 itself diverges ("unstable") are set apart.
fn findings(d: &mut Doc, m: &Manifest, rep: &Reproduction) {
    let stable: Vec<&str> = m
        .reading
        .iter()
        .filter(|r| {
            !rep.runs
                .iter()
                .any(|c| c.reading == r.id && c.case == "fig2" && c.metrics.base.diverged)
        })
        .map(|r| r.id.as_str())
        .collect();
    let unstable: Vec<String> = m
        .reading
        .iter()
        .filter(|r| !stable.contains(&r.id.as_str()))
        .map(|r| format!("`{}`", r.id))
        .collect();
    let (mut all, mut none, mut some) = (Vec::new(), Vec::new(), Vec::new());
    for (c, row) in m.claim.iter().zip(&rep.claims) {
        let agreeing: Vec<&str> = stable
            .iter()
            .copied()
            .filter(|r| row.verdicts[*r].status == Status::Agree)
            .collect();
        let line = format!("`{}` — {}", c.id, c.text);
        if agreeing.is_empty() {
            none.push(line);
        } else if agreeing.len() == stable.len() {
            all.push(line);
        } else {
            some.push(format!("{line} (agrees under: {})", agreeing.join(", ")));
        }
    }
    d.push(Block::Heading(2, "Findings".into()));
    let primary = &rep.primary_reading;
    let differ: Vec<String> = m
        .claim
        .iter()
        .zip(&rep.claims)
        .filter(|(_, row)| row.verdicts[primary].status != Status::Agree)
        .map(|(c, row)| format!("`{}` ({})", c.id, row.verdicts[primary].status.word()))
        .collect();
    d.push(Block::Para(format!(
        "Under the chosen reading `{primary}`, {} of {} claims agree; the others are {}.",
        rep.agreements[primary],
        m.claim.len(),
        if differ.is_empty() {
            "none".into()
        } else {
            differ.join(", ")
        }
    )));
    if !unstable.is_empty() {
        d.push(Block::Para(format!(
            "The NNBVSC of Fig. 2 diverges under {}: {} left out of the lists below.",
            unstable.join(", "),
            if unstable.len() == 1 {
                "that reading is"
            } else {
                "those readings are"
            }
        )));
    }
    for (title, list) in [
        ("Claims reproduced under **every** stable reading:", all),
        ("Claims that depend on the reading:", some),
        ("Claims that **no** reading reproduces:", none),
    ] {
        if !list.is_empty() {
            d.push(Block::Para(title.into()));
            d.push(Block::List(list));
        }
    }
}

fn theory_section(d: &mut Doc, rep: &Reproduction) {
    let Some((_, a)) = rep.theory.first() else {
        return;
    };
    d.push(Block::Heading(
        2,
        "What the theory says of the Fig. 2 case (`ehservo analyze`)".into(),
    ));
    let s = &a.surface;
    let mut items = vec![
        format!(
            "Plant: ā = ({:.5}, {:.4}, {:.5}), b̄ = {:.2} s⁻³V⁻¹ at Pl = 0; open-loop poles {:.4e}, {:.4} ± j{:.4}.",
            a.a_nominal[0],
            a.a_nominal[1],
            a.a_nominal[2],
            a.b_at_rest,
            a.open_loop_poles[0].re,
            a.open_loop_poles[1].re,
            a.open_loop_poles[1].im.abs()
        ),
        format!(
            "Theorem 2: K2 = {:.4}, K1 = {} (checked on an independent grid: {}), bound K2/K1 = {:.4e}. {}",
            s.k2,
            s.k1.value.map(|v| format!("{v:.4}")).unwrap_or("∞".into()),
            if s.k1.verified { "verified" } else { "not verified" },
            s.alpha_bound,
            s.verdict
        ),
    ];
    if let Some(w) = &a.weights {
        items.push(format!("Remark 6: {}", w.note));
    }
    if let Some(dg) = &rep.fig2_diagnostics {
        items.push(format!(
            "Along the Fig. 2 run (reading `{}`): condition 4) of Theorem 3 holds at {:.1} % of the samples (left half {:.1} %, right half α‖E‖ < c/γ1 + ᾱ‖E‖ {:.1} %: it needs ‖E‖ ≈ 1e-4); {:.1} % of the samples are in the dead zone. The paper's runs illustrate the controller, not the theorem's guarantee.",
            rep.primary_reading,
            100.0 * dg.condition4,
            100.0 * dg.condition4_left,
            100.0 * dg.condition4_right,
            100.0 * dg.dead_zone
        ));
    }
    d.push(Block::List(items));
    d.push(Block::Para(
        "The linearised closed loop (W = 0, σΔ = σ) under each reading: the fast σ eigenvalue and whether the \
simulation scheme is stable on it (continuous: RK4's |R(hλ)| < 1; sampled: the one-sample map's spectral radius < 1)."
            .into(),
    ));
    let rows = rep
        .theory
        .iter()
        .map(|(r, a)| {
            let l = &a.closed_loop;
            vec![
                format!("`{r}`"),
                l.sigma_gain
                    .map(|g| format!("{g:.1}"))
                    .unwrap_or("—".into()),
                l.fast.map(|f| format!("{f:.1} s⁻¹")).unwrap_or("—".into()),
                l.growth.map(|g| format!("{g:.4}")).unwrap_or("—".into()),
                match l.stable {
                    Some(true) => "stable".into(),
                    Some(false) => "UNSTABLE".into(),
                    None => "—".into(),
                },
            ]
        })
        .collect();
    d.push(Block::Table(
        vec![
            "reading".into(),
            "σ-loop gain b/(b̄ − β)·γ1".into(),
            "fast eigenvalue".into(),
            "growth per step".into(),
            "scheme".into(),
        ],
        rows,
    ));
}
