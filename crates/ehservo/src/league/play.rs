//! Playing a league: the tunes, every controller on every scenario × draw,
//! the margins, and the outputs written (the report itself is in
//! [`report`](super::report)).

use super::{report, Case, League, MarginResult, Source};
use crate::metrics::Metrics;
use crate::output::{write_atomic, Staging};
use crate::scenario::Loop;
use crate::tune::TuneResult;
use anyhow::{Context, Result};
use rayon::prelude::*;
use serde::Serialize;
use std::path::Path;

/// The scenario of case `c` with `[controller]` = `table`, at draw seed
/// `seed`.
pub(super) fn build_with(
    c: &Case,
    table: &toml::Table,
    run: usize,
) -> Result<Loop, crate::scenario::ScenarioError> {
    let mut tab = c.table.clone();
    tab.insert("controller".into(), toml::Value::Table(table.clone()));
    let (seed, point) = c.run(run);
    let sets: Vec<(String, toml::Value)> = seed
        .map(|s| {
            (
                "uncertainty.seed".to_string(),
                toml::Value::Integer(s as i64),
            )
        })
        .into_iter()
        .chain(
            point
                .iter()
                .map(|(k, v)| (k.clone(), toml::Value::Float(*v))),
        )
        .collect();
    c.scenario.with_values_on(tab, &sets)
}

/// One run of the league.
#[derive(Debug, Clone, Serialize)]
pub struct Cell {
    /// Controller index.
    pub controller: usize,
    /// Scenario index.
    pub scenario: usize,
    /// Draw index.
    pub draw: usize,
    /// `uncertainty.seed` of the run.
    pub seed: u64,
    /// Its metrics (None: the scenario refused the controller's
    /// parameters).
    pub metrics: Option<Metrics>,
    /// Why it was refused.
    pub refused: Option<String>,
    /// Control energy ∫u² dt over [settle, horizon] (V²·s), from u_rms.
    pub energy: Option<f64>,
}

impl Cell {
    /// Bounded, with an e_max.
    pub fn bounded(&self) -> bool {
        self.metrics
            .as_ref()
            .is_some_and(|m| !m.diverged && m.e_max.is_some())
    }
}

/// A controller's result.
#[derive(Debug, Clone, Serialize)]
pub struct Standing {
    /// Label.
    pub name: String,
    /// Kind.
    pub kind: &'static str,
    /// "tuned", "tuned (defaults kept)" or "given".
    pub parameters: String,
    /// The `[controller]` table it ran with.
    pub table: toml::Table,
    /// The tune, when tuned.
    pub tune: Option<TuneResult>,
    /// The margin, when the suite asks for one.
    pub margin: Option<MarginResult>,
}

/// What a league found.
#[derive(Debug, Clone, Serialize)]
pub struct LeagueResult {
    /// Per controller.
    pub standings: Vec<Standing>,
    /// Per run, in [`League::cells`] order.
    pub cells: Vec<Cell>,
}

/// Tunes the tuned controllers, runs every controller on every scenario
/// and bisects the margins (on `threads` threads, default every core).
/// With `tuned_dir`, each tune's outputs are written into
/// `tuned_dir/<controller>/`.
pub fn play(
    l: &League,
    threads: Option<usize>,
    progress: &indicatif::ProgressBar,
    tuned_dir: Option<&Path>,
    plot: bool,
) -> Result<LeagueResult> {
    let pool = match threads {
        Some(k) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(k.max(1))
                .build()
                .context("building the thread pool")?,
        ),
        None => None,
    };
    let install = |f: &(dyn Fn() -> Result<LeagueResult> + Sync)| match &pool {
        Some(p) => p.install(f),
        None => f(),
    };
    install(&|| {
        // Tunes, one after another (each is parallel inside).
        let mut standings = Vec::new();
        for c in &l.contestants {
            let mut table = c.table.clone();
            let (parameters, tune) = match &c.source {
                Source::Given => ("given".to_string(), None),
                Source::Tuned(t) => {
                    let r = match tuned_dir {
                        Some(d) => {
                            crate::tune::tune_to_dir(t, &d.join(&c.name), None, progress, plot)?
                        }
                        None => crate::tune::search(t, None, progress)?,
                    };
                    if !r.kept_defaults {
                        for (k, v) in &r.params {
                            table.insert(k.clone(), toml::Value::Float(*v));
                        }
                    }
                    let p = if !r.objective.is_finite() {
                        "tuned (no candidate passed: defaults kept)"
                    } else if !r.accepted() {
                        "tuned (failed its verification)"
                    } else if r.kept_defaults {
                        "tuned (defaults kept)"
                    } else {
                        "tuned"
                    };
                    (p.to_string(), Some(r))
                }
            };
            standings.push(Standing {
                name: c.name.clone(),
                kind: c.kind,
                parameters,
                table,
                tune,
                margin: None,
            });
        }
        // Every run, in parallel, collected in order.
        if crate::cancel::requested() {
            return Err(crate::cancel::Cancelled.into());
        }
        let cells: Vec<Cell> = l
            .cells()
            .par_iter()
            .map(|&(ci, si, d)| {
                let case = &l.cases[si];
                let r = build_with(case, &standings[ci].table, d);
                progress.inc(1);
                match r {
                    Err(reason) => Cell {
                        controller: ci,
                        scenario: si,
                        draw: d,
                        seed: case
                            .run(d)
                            .0
                            .unwrap_or(case.scenario.scenario().uncertainty.seed),
                        metrics: None,
                        refused: Some(reason.to_string()),
                        energy: None,
                    },
                    Ok(lp) => {
                        let m = crate::run::run_metrics(&lp, &mut |_| {}).1;
                        let s = lp.scenario();
                        let span = s.simulation.horizon - s.simulation.settle;
                        let energy = match (m.diverged, m.u_rms) {
                            (false, Some(u)) if span > 0.0 => Some(u * u * span),
                            _ => None,
                        };
                        Cell {
                            controller: ci,
                            scenario: si,
                            draw: d,
                            seed: s.uncertainty.seed,
                            metrics: Some(m),
                            refused: None,
                            energy,
                        }
                    }
                }
            })
            .collect();
        // Margins, one controller per task.
        if let Some(m) = &l.margin {
            let margins: Vec<MarginResult> = standings
                .par_iter()
                .map(|s| m.bisect(&s.table, progress))
                .collect();
            for (s, r) in standings.iter_mut().zip(margins) {
                s.margin = Some(r);
            }
        }
        // Runs cut short by an interruption are no result.
        if crate::cancel::requested() {
            return Err(crate::cancel::Cancelled.into());
        }
        Ok(LeagueResult { standings, cells })
    })
}

/// The scenario file of controller `ci` on case `si` (its first draw).
fn cell_scenario(l: &League, r: &LeagueResult, ci: usize, si: usize) -> Result<String> {
    let case = &l.cases[si];
    let mut s = build_with(case, &r.standings[ci].table, 0)
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .scenario()
        .clone();
    s.name = format!("{}--{}", r.standings[ci].name, case.name);
    s.description = format!(
        "league `{}`: controller `{}` ({}, {}) on scenario `{}`",
        l.file.name,
        r.standings[ci].name,
        r.standings[ci].kind,
        r.standings[ci].parameters,
        case.name
    );
    let mut text = format!(
        "# Written by `ehservo league` ({} {}): re-run with `ehservo run` (this is draw 0;\n# draw d is `--set uncertainty.seed=S` with S in league.csv's runs).\n",
        crate::output::SOFTWARE.name,
        crate::output::SOFTWARE.version
    );
    text.push_str(&toml::to_string(&s).context("writing a scenario")?);
    Ok(text)
}

/// Runs a league and writes its outputs into `out`: `league.md`,
/// `league.html`, `league.csv` (a row per controller × scenario),
/// `runs.csv` (a row per run), `league.json`, `pareto.png/svg`,
/// `bars.png/svg`, `scenarios/<controller>/<scenario>.toml` and
/// `tuned/<controller>/` (each tune's outputs).
pub fn league_to_dir(
    l: &League,
    out: &Path,
    threads: Option<usize>,
    progress: &indicatif::ProgressBar,
    plot: bool,
) -> Result<LeagueResult> {
    let stage = Staging::new(out)?;
    let tuned = stage.path().join("tuned");
    std::fs::create_dir_all(&tuned).with_context(|| format!("creating {}", tuned.display()))?;
    let r = play(l, threads, progress, Some(&tuned), plot)?;
    for (ci, s) in r.standings.iter().enumerate() {
        let d = stage.path().join("scenarios").join(&s.name);
        std::fs::create_dir_all(&d).with_context(|| format!("creating {}", d.display()))?;
        for (si, c) in l.cases.iter().enumerate() {
            write_atomic(
                &d.join(format!("{}.toml", c.name)),
                cell_scenario(l, &r, ci, si)?.as_bytes(),
            )?;
        }
    }
    let rows = report::rows(l, &r);
    write_atomic(
        &stage.path().join("league.csv"),
        report::league_csv(l, &rows).as_bytes(),
    )?;
    write_atomic(
        &stage.path().join("runs.csv"),
        report::runs_csv(l, &r).as_bytes(),
    )?;
    let json = serde_json::json!({
        "software": crate::output::SOFTWARE,
        "suite": l.file,
        "standings": r.standings,
        "rows": rows,
    });
    write_atomic(
        &stage.path().join("league.json"),
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    let figures = if plot {
        let p = report::pareto(l, &rows);
        p.png(&stage.path().join("pareto.png"))?;
        p.svg(&stage.path().join("pareto.svg"))?;
        let b = report::bars(l, &rows);
        b.png(&stage.path().join("bars.png"))?;
        b.svg(&stage.path().join("bars.svg"))?;
        true
    } else {
        false
    };
    write_atomic(
        &stage.path().join("league.md"),
        report::markdown(l, &r, &rows, figures).as_bytes(),
    )?;
    let svgs = if figures {
        let read = |f: &str| std::fs::read_to_string(stage.path().join(f)).unwrap_or_default();
        Some((read("pareto.svg"), read("bars.svg")))
    } else {
        None
    };
    write_atomic(
        &stage.path().join("league.html"),
        report::html(l, &r, &rows, svgs).as_bytes(),
    )?;
    stage.commit()?;
    Ok(r)
}
