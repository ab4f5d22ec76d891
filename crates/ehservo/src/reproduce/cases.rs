//! Running the cases: progress bars, loading every case under every
//! reading, measuring a run, the sensitivity runs and the boundary searches.

use super::breaking::{self, BiasReading, Boundary};
use super::derived::CaseMetrics;
use super::manifest::Manifest;
use super::SensitivityRow;
use crate::run::{run, Keep, RunResult};
use crate::scenario::Loop;
use anyhow::Result;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

pub(super) fn bar(progress: bool, len: u64, msg: &str) -> ProgressBar {
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
pub fn load_cases(m: &Manifest, dir: &Path) -> Result<Vec<(usize, usize, Loop)>> {
    let mut v = Vec::new();
    for (ri, r) in m.reading.iter().enumerate() {
        for (ci, c) in m.case.iter().enumerate() {
            let s = Loop::load(&dir.join(&c.file), &r.set).map_err(anyhow::Error::from)?;
            v.push((ri, ci, s));
        }
    }
    Ok(v)
}

pub(super) fn measure(s: &Loop, keep_trace: bool) -> Result<(CaseMetrics, Option<RunResult>)> {
    // At most MAX_KEPT samples in memory (every one for the shipped cases,
    // which are at most 60 001 samples; a legal 2·10⁷-step case is thinned).
    let stride = (s.sim().steps + 1).div_ceil(crate::output::MAX_KEPT).max(1);
    let r = run(s, Keep::Every(stride as u32));
    let network = r.metrics.w_norm_max.is_some();
    let cm = CaseMetrics::from_trace(
        r.metrics,
        &r.trace,
        s.settle(),
        s.horizon(),
        s.scenario().reference.base_frequency_hz(s.horizon()),
        network,
    );
    Ok((cm, if keep_trace { Some(r) } else { None }))
}

/// Runs every sensitivity variation on top of each case's converged set-up
/// under the chosen reading (`base`: case → (its metrics, its overrides)).
pub(super) fn sensitivity(
    m: &Manifest,
    dir: &Path,
    base: &BTreeMap<String, (CaseMetrics, Vec<String>)>,
    progress: bool,
) -> Result<Vec<SensitivityRow>> {
    // (sensitivity, case, seed) jobs, each a scenario loaded up front.
    let mut jobs: Vec<(usize, usize, Option<u32>, Loop)> = Vec::new();
    for (si, sv) in m.sensitivity.iter().enumerate() {
        for (ci, case) in sv.cases.iter().enumerate() {
            let file = &m.case.iter().find(|c| &c.id == case).expect("checked").file;
            let seeds: Vec<Option<u32>> = match sv.seeds {
                Some(n) => (0..n.max(1)).map(Some).collect(),
                None => vec![None],
            };
            for seed in seeds {
                let mut set = base[case].1.clone();
                set.extend(sv.set.iter().cloned());
                if let Some(k) = seed {
                    set.push(format!("uncertainty.seed={k}"));
                }
                let s = Loop::load(&dir.join(file), &set).map_err(anyhow::Error::from)?;
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
            Some(row) => row.seeds_e_max_deg.push(cm.base.e_max),
            None => rows.push(SensitivityRow {
                id: sv.id.clone(),
                case: case.clone(),
                baseline: base[case].0,
                variant: cm,
                seeds_e_max_deg: if seed.is_some() {
                    vec![cm.base.e_max]
                } else {
                    Vec::new()
                },
            }),
        }
    }
    Ok(rows)
}

/// The VSC's scan over the bias fraction and the NNBVSC's over the a_i bias
/// (brackets bisected to a fifth of the step, [`breaking::Scan::new`]).
pub(super) const VSC_SCAN: (f64, f64, f64) = (0.0, 1.5, 0.005);
pub(super) const NN_SCAN: (f64, f64, f64) = (0.0, 10.0, 0.1);

/// The boundary searches under every reading (`sets`: reading id, the
/// converged overrides of the Fig. 3 case and of the Fig. 2 case).
pub(super) fn boundaries(
    sets: &[(String, Vec<String>, Vec<String>)],
    dir: &Path,
    progress: bool,
) -> Result<(Vec<Boundary>, Vec<Boundary>)> {
    let load =
        |file: &str, set: &[String]| Loop::load(&dir.join(file), set).map_err(anyhow::Error::from);
    // (reading id, bias reading, base scenario with the reading applied)
    let mut tasks: Vec<(String, Option<BiasReading>, Loop)> = Vec::new();
    for (id, fig3_set, fig2_set) in sets {
        let vsc_base = load("fig3.toml", fig3_set)?;
        for br in [BiasReading::R1, BiasReading::R2] {
            tasks.push((id.clone(), Some(br), vsc_base.clone()));
        }
        tasks.push((id.clone(), None, load("fig2.toml", fig2_set)?));
    }
    let pb = bar(progress, tasks.len() as u64, "boundaries");
    let results: Vec<Boundary> = tasks
        .par_iter()
        .map(|(rid, br, base)| {
            let b_ref = base.stages().uncertainty.b_reference;
            let found = match br {
                Some(b) => {
                    let (start, mut end, step) = VSC_SCAN;
                    if *b == BiasReading::R2 {
                        // R2 tells the controller β = b_ref·x·b̄, which must stay < b̄.
                        end = end.min(1.0 / b_ref - 1e-6);
                    }
                    let grid = breaking::Scan::new(start, end, step);
                    breaking::search(base, grid, &|x| breaking::vsc_sets(*b, b_ref, x))?
                }
                None => {
                    let (start, end, step) = NN_SCAN;
                    breaking::search(
                        base,
                        breaking::Scan::new(start, end, step),
                        &breaking::nn_sets,
                    )?
                }
            };
            pb.inc(1);
            Ok(Boundary {
                reading: rid.clone(),
                bias_reading: *br,
                b_reference: b_ref,
                found,
            })
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    let (vsc, nn): (Vec<Boundary>, Vec<Boundary>) =
        results.into_iter().partition(|b| b.bias_reading.is_some());
    Ok((vsc, nn))
}
