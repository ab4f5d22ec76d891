//! Where the controllers stop working.
//!
//! - **The traditional VSC's breaking point** in the bias fraction x, under
//!   both readings of "x % bias" (SPEC §2): R1 keeps the controller's bounds
//!   of Fig. 2 (α_i = |ā_i|, β = 0.5|b̄|) with the true Δa_i = x·|ā_i|,
//!   Δb = x·0.5·b̄; R2 tells the controller the true size (α_i = x·|ā_i|,
//!   β = x·0.5·b̄). (With `b_reference = 1`, 0.5·b̄ becomes b̄ throughout.)
//!   The paper: "bounded at 40 %, unbounded above 45 %".
//! - **The NNBVSC's margin** in the a_i bias (b bias kept at Fig. 2's 0.5).
//!
//! Every point of a scan has one of three statuses: *tracking* (bounded and
//! e_max after the transient below [`TRACKING_FRACTION`] of the reference
//! amplitude: 0.5° for the paper's 5°), *bounded* only, or *diverged*
//! (|θ| > 1 rad or a non-finite state within the horizon). Two thresholds
//! are read from them, each with its own pass criterion:
//!
//! - **bounded**: the point did not diverge;
//! - **tracking**: bounded, and e_max < [`TRACKING_FRACTION`]·amplitude.
//!
//! "Bounded" is not "tracking": in the sampled reading R1 the VSC is bounded
//! up to x ≈ 0.33–0.37 but its e_max there is 10–34° against a 5° reference.
//!
//! The boundary need not be monotone (the sampled VSC is unbounded at x and
//! bounded again at a slightly larger x), so a scan on a fine uniform grid
//! comes first, and **every** interval where a criterion changes is then
//! bisected, until its bracket is at most [`Scan::tol`] wide. The tolerance
//! is tied to the scan step (a fifth of it): the status can change again
//! between two grid points, so a finer bisection would claim a precision the
//! boundary does not have, and an island narrower than the step can be
//! missed altogether. For each criterion the search reports the first
//! failure, the last pass and the list of transitions; a criterion is
//! non-monotone when it passes again after failing.

use super::doc::Block;
use crate::run::{run, Keep};
use crate::scenario::{parse_value, Loop};
use anyhow::Result;
use rayon::prelude::*;
use serde::Serialize;

/// The tracking criterion: e_max after the transient below this fraction of
/// the reference amplitude (10 %: 0.5° for the paper's 5°).
pub const TRACKING_FRACTION: f64 = 0.1;

/// How the bias is told to the traditional VSC.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum BiasReading {
    /// Bounds of Fig. 2, true variation x.
    R1,
    /// Bounds equal to the true variation x.
    R2,
}

/// What a run at one x did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PointStatus {
    /// Bounded, e_max below the tracking limit.
    Tracking,
    /// Bounded, e_max at or above the tracking limit (or undefined).
    Bounded,
    /// Diverged within the horizon.
    Diverged,
}

/// One of the two pass criteria of a scan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Criterion {
    /// Not diverged.
    Bounded,
    /// Not diverged and e_max below the tracking limit.
    Tracking,
}

impl Criterion {
    /// Whether a point of status `s` passes.
    pub fn passes(self, s: PointStatus) -> bool {
        match self {
            Criterion::Bounded => s != PointStatus::Diverged,
            Criterion::Tracking => s == PointStatus::Tracking,
        }
    }
}

/// One point of a scan.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ScanPoint {
    /// The swept value.
    pub x: f64,
    /// e_max_deg (None if diverged or undefined).
    pub e_max_deg: Option<f64>,
    /// When the run diverged.
    pub diverged_at_s: Option<f64>,
}

impl ScanPoint {
    /// The point's status against the tracking limit `e_limit_deg`.
    pub fn status(&self, e_limit_deg: f64) -> PointStatus {
        if self.diverged_at_s.is_some() {
            PointStatus::Diverged
        } else if self.e_max_deg.is_some_and(|e| e < e_limit_deg) {
            PointStatus::Tracking
        } else {
            PointStatus::Bounded
        }
    }
}

/// The grid of a scan and the bisection tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Scan {
    /// First x.
    pub start: f64,
    /// Grid step.
    pub step: f64,
    /// Number of grid points.
    pub points: usize,
    /// Width of a bisected bracket, at most.
    pub tol: f64,
}

impl Scan {
    /// `start, start + step, …, end` (end included when on the grid), with
    /// brackets bisected to a fifth of the step.
    pub fn new(start: f64, end: f64, step: f64) -> Self {
        let points = ((end - start) / step + 1e-9).floor() as usize + 1;
        Scan {
            start,
            step,
            points,
            tol: step / 5.0,
        }
    }

    /// The grid, x_k = start + k·step.
    pub fn grid(&self) -> Vec<f64> {
        (0..self.points)
            .map(|k| self.start + k as f64 * self.step)
            .collect()
    }
}

/// An interval where a criterion changes, bisected.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Transition {
    /// The bracket's left end (status of the left grid point).
    pub lo: f64,
    /// The bracket's right end (status of the right grid point).
    pub hi: f64,
    /// true: passes at `lo`, fails at `hi`; false: fails at `lo`, passes at `hi`.
    pub fails: bool,
}

/// One criterion's threshold over a scan.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Threshold {
    /// The smallest x found failing: the first grid point, or the right end
    /// of the first failing transition. None: it passes over the whole scan.
    pub first_fail: Option<f64>,
    /// The largest x found passing: the last grid point, or the left end of
    /// the last failing transition. None: it fails over the whole scan.
    pub last_pass: Option<f64>,
    /// Every change of the criterion along the scan, in x order.
    pub transitions: Vec<Transition>,
    /// It passes again after failing.
    pub non_monotone: bool,
}

/// The result of a boundary search.
#[derive(Debug, Clone, Serialize)]
pub struct Search {
    /// The grid and the tolerance.
    pub grid: Scan,
    /// The tracking limit on e_max (deg).
    pub e_limit_deg: f64,
    /// The scan.
    pub scan: Vec<ScanPoint>,
    /// Bounded (not diverged).
    pub bounded: Threshold,
    /// Bounded and tracking.
    pub tracking: Threshold,
}

/// One boundary search, labelled.
#[derive(Debug, Clone, Serialize)]
pub struct Boundary {
    /// The reading of the simulation (manifest id).
    pub reading: String,
    /// R1 / R2 for the VSC; None for the NNBVSC margin.
    pub bias_reading: Option<BiasReading>,
    /// The reading's `uncertainty.b_reference` (0.5: Δb fractions of β; 1: of b̄).
    pub b_reference: f64,
    /// What the search found.
    #[serde(flatten)]
    pub found: Search,
}

fn point(base: &Loop, set: &[String], x: f64) -> Result<ScanPoint> {
    let values: Vec<(String, toml::Value)> = set
        .iter()
        .filter_map(|s| s.split_once('='))
        .map(|(k, v)| (k.trim().to_string(), parse_value(v)))
        .collect();
    let s = base.with_values(&values).map_err(anyhow::Error::from)?;
    let m = run(&s, Keep::Nothing).metrics;
    Ok(ScanPoint {
        x,
        e_max_deg: m.e_max,
        diverged_at_s: m.diverged_at_s,
    })
}

/// Bisects a bracket whose ends differ under `pass` until it is at most
/// `tol` wide.
fn bisect(
    eval: &(dyn Fn(f64) -> Result<PointStatus> + Sync),
    pass: impl Fn(PointStatus) -> bool,
    lo: f64,
    hi: f64,
    tol: f64,
) -> Result<(f64, f64)> {
    let left = pass(eval(lo)?);
    // Bounded whatever `tol` is ([`crate::bisection`]).
    let (lo, hi, _) = crate::bisection::bisect(lo, hi, tol, |mid| {
        Ok::<_, anyhow::Error>(pass(eval(mid)?) == left)
    })?;
    Ok((lo, hi))
}

fn threshold(
    statuses: &[PointStatus],
    grid: &[f64],
    c: Criterion,
    t: Vec<Transition>,
) -> Threshold {
    let pass: Vec<bool> = statuses.iter().map(|&s| c.passes(s)).collect();
    let first_fail = if pass.first() == Some(&false) {
        grid.first().copied()
    } else {
        t.iter().find(|t| t.fails).map(|t| t.hi)
    };
    let last_pass = if pass.last() == Some(&true) {
        grid.last().copied()
    } else {
        t.iter().rev().find(|t| t.fails).map(|t| t.lo)
    };
    let first_bad = pass.iter().position(|p| !p);
    Threshold {
        first_fail,
        last_pass,
        non_monotone: first_bad.is_some_and(|i| pass[i..].iter().any(|&p| p)),
        transitions: t,
    }
}

/// A boundary search with `eval(x)` giving the run at x: the whole grid in
/// parallel, then every transition of either criterion bisected (in
/// parallel too). `e_limit_deg` is the tracking limit. The result does not
/// depend on the number of threads.
pub fn search_with(
    grid: Scan,
    eval: &(dyn Fn(f64) -> Result<ScanPoint> + Sync),
    e_limit_deg: f64,
) -> Result<Search> {
    let xs = grid.grid();
    let scan: Vec<ScanPoint> = xs.par_iter().map(|&x| eval(x)).collect::<Result<_>>()?;
    let statuses: Vec<PointStatus> = scan.iter().map(|p| p.status(e_limit_deg)).collect();
    // (criterion, grid index k: the change is between k and k + 1)
    let changes: Vec<(Criterion, usize)> = [Criterion::Bounded, Criterion::Tracking]
        .into_iter()
        .flat_map(|c| {
            statuses
                .windows(2)
                .enumerate()
                .filter(move |(_, w)| c.passes(w[0]) != c.passes(w[1]))
                .map(move |(k, _)| (c, k))
        })
        .collect();
    let status_at = |x: f64| eval(x).map(|p| p.status(e_limit_deg));
    let bisected: Vec<(Criterion, Transition)> = changes
        .par_iter()
        .map(|&(c, k)| {
            let (lo, hi) = bisect(&status_at, |s| c.passes(s), xs[k], xs[k + 1], grid.tol)?;
            Ok((
                c,
                Transition {
                    lo,
                    hi,
                    fails: c.passes(statuses[k]),
                },
            ))
        })
        .collect::<Result<_>>()?;
    let of = |c: Criterion| -> Vec<Transition> {
        bisected
            .iter()
            .filter(|(cc, _)| *cc == c)
            .map(|(_, t)| *t)
            .collect()
    };
    Ok(Search {
        grid,
        e_limit_deg,
        bounded: threshold(&statuses, &xs, Criterion::Bounded, of(Criterion::Bounded)),
        tracking: threshold(&statuses, &xs, Criterion::Tracking, of(Criterion::Tracking)),
        scan,
    })
}

/// A boundary search on `base` with `sets(x)` giving the overrides at x; the
/// tracking limit is [`TRACKING_FRACTION`] of the base's reference amplitude.
pub fn search(
    base: &Loop,
    grid: Scan,
    sets: &(dyn Fn(f64) -> Vec<String> + Sync),
) -> Result<Search> {
    let e_limit = TRACKING_FRACTION
        * base
            .scenario()
            .reference
            .amplitude_deg
            .unwrap_or(crate::scenario::DEFAULT_AMPLITUDE_DEG)
            .abs();
    search_with(grid, &|x| point(base, &sets(x), x), e_limit)
}

/// The overrides of the traditional VSC at bias x under reading `r`;
/// `b_ref` is the scenario's `uncertainty.b_reference` (β = b_ref·b̄).
pub fn vsc_sets(r: BiasReading, b_ref: f64, x: f64) -> Vec<String> {
    let mut v = vec![
        format!("uncertainty.a_bias={x}"),
        format!("uncertainty.b_bias={x}"),
        "uncertainty.a_random=0".into(),
        "uncertainty.b_random=0".into(),
        "controller.kind=vsc".into(),
    ];
    match r {
        BiasReading::R1 => {
            // The bounds printed in Section IV: α_i = |ā_i|, β = 0.5|b̄|.
            v.push("controller.bound_a=1".into());
            v.push("controller.bound_b=0.5".into());
        }
        BiasReading::R2 => {
            v.push(format!("controller.bound_a={x}"));
            v.push(format!("controller.bound_b={}", b_ref * x));
        }
    }
    v
}

/// The overrides of the NNBVSC margin at a_i bias x.
pub fn nn_sets(x: f64) -> Vec<String> {
    vec![format!("uncertainty.a_bias={x}")]
}

/// Decimals that resolve a bracket of width `tol` (one more than its
/// leading digit): 4 for 0.001, 3 for 0.02.
fn decimals(tol: f64) -> usize {
    if tol > 0.0 && tol.is_finite() {
        (-tol.log10()).ceil().max(0.0) as usize + 1
    } else {
        3
    }
}

/// The first failure in words: the grid's start fails when the first
/// transition is a recovery (or there is none).
fn fmt_first_fail(t: &Threshold, n: usize) -> String {
    let fmt_x = |x: f64| format!("{x:.n$}");
    match (t.first_fail, t.transitions.first()) {
        (None, _) => "none over the scan".into(),
        (Some(x), None) => format!("already at {}", fmt_x(x)),
        (Some(x), Some(tr)) if !tr.fails => format!("already at {}", fmt_x(x)),
        (Some(x), Some(tr)) => format!("{} (passes at {})", fmt_x(x), fmt_x(tr.lo)),
    }
}

fn fmt_last_pass(t: &Threshold, s: &Search, n: usize) -> String {
    let fmt_x = |x: f64| format!("{x:.n$}");
    let end = s.grid.start + (s.grid.points.saturating_sub(1)) as f64 * s.grid.step;
    match t.last_pass {
        None => "none".into(),
        Some(x) if t.first_fail.is_none() || (x - end).abs() < 1e-12 => {
            format!("{} (scan end)", fmt_x(x))
        }
        Some(x) => fmt_x(x),
    }
}

fn fmt_transitions(t: &Threshold, n: usize) -> String {
    let fmt_x = |x: f64| format!("{x:.n$}");
    if t.transitions.is_empty() {
        return "—".into();
    }
    let all: Vec<String> = t
        .transitions
        .iter()
        .map(|tr| {
            format!(
                "{}{}–{}",
                if tr.fails { "↓" } else { "↑" },
                fmt_x(tr.lo),
                fmt_x(tr.hi)
            )
        })
        .collect();
    const SHOWN: usize = 8;
    if all.len() > SHOWN {
        format!("{} … ({} in all)", all[..SHOWN].join(", "), all.len())
    } else {
        all.join(", ")
    }
}

fn threshold_rows(bs: &[Boundary], vsc: bool) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for b in bs {
        for (name, t) in [
            ("bounded", &b.found.bounded),
            ("tracking", &b.found.tracking),
        ] {
            let mut row = vec![format!("`{}`", b.reading)];
            if vsc {
                row.push(format!("{:?}", b.bias_reading.unwrap_or(BiasReading::R1)));
            }
            let n = decimals(b.found.grid.tol);
            row.extend([
                name.to_string(),
                fmt_first_fail(t, n),
                fmt_last_pass(t, &b.found, n),
                if t.non_monotone { "yes" } else { "no" }.into(),
                fmt_transitions(t, n),
            ]);
            if vsc && name == "bounded" {
                row.push(paper_vsc_check(&b.found).into());
            } else if vsc {
                row.push("".into());
            }
            rows.push(row);
        }
    }
    rows
}

/// The paper's "bounded at 40 %, unbounded above 45 %" against a scan:
/// agree when the grid point x = 0.40 is bounded and every grid point above
/// 0.45 diverged.
pub fn paper_vsc_check(s: &Search) -> &'static str {
    let bounded_at_40 = s
        .scan
        .iter()
        .find(|p| (p.x - 0.40).abs() < 1e-9)
        .map(|p| p.diverged_at_s.is_none());
    let above: Vec<bool> = s
        .scan
        .iter()
        .filter(|p| p.x > 0.45 + 1e-9)
        .map(|p| p.diverged_at_s.is_some())
        .collect();
    match bounded_at_40 {
        None => "not scanned",
        Some(b) if b && !above.is_empty() && above.iter().all(|&d| d) => "agree",
        Some(_) => "differ",
    }
}

fn scan_text(s: &Search) -> String {
    let end = s.grid.start + (s.grid.points.saturating_sub(1)) as f64 * s.grid.step;
    format!(
        "scanned over x = {}, {}, …, {} (step {}, {} runs), every transition bisected to a bracket ≤ {} wide \
(a fifth of the step: the status can change again between grid points, so a finer bisection would be spurious \
precision, and an island narrower than the step can be missed)",
        s.grid.start,
        s.grid.start + s.grid.step,
        end,
        s.grid.step,
        s.grid.points,
        s.grid.tol
    )
}

const COLUMNS: [&str; 5] = [
    "criterion",
    "first failure",
    "last pass",
    "non-monotone",
    "transitions (↓ pass→fail, ↑ fail→pass; bracket)",
];

/// The report's sections on the VSC's breaking point and the NNBVSC's
/// margin (as document blocks: report.md and report.html both render them).
pub fn report_blocks(vsc: &[Boundary], nn: &[Boundary]) -> Vec<Block> {
    let mut d = Vec::new();
    let criteria = |e: f64| {
        format!(
            "Two criteria: **bounded** — |θ| < 1 rad and finite over the 10 s horizon; **tracking** — bounded and \
max |e| after 2 s below {e}° ({:.0} % of the reference amplitude). Bounded is not tracking: a run can stay bounded \
with an error several times the reference.",
            100.0 * TRACKING_FRACTION
        )
    };
    if let Some(first) = vsc.first() {
        d.push(Block::Heading(
            2,
            "The traditional VSC's breaking point".into(),
        ));
        d.push(Block::Para(format!(
            "The paper: bounded at 40 % bias, unbounded above 45 %. R1: the controller keeps the bounds of Fig. 2 \
while the true variation is x; R2: the controller is told the true size x (the R2 scan stops where β would reach \
b̄). Each reading {}. {} \"First failure\" is the smallest failing x found, \"last pass\" the largest passing one; \
they differ when the boundary is not monotone.",
            scan_text(&first.found),
            criteria(first.found.e_limit_deg)
        )));
        let mut head = vec!["reading".to_string(), "bias reading".to_string()];
        head.extend(COLUMNS.iter().map(|s| s.to_string()));
        head.push("paper: bounded at 0.40, unbounded above 0.45".into());
        d.push(Block::Table(head, threshold_rows(vsc, true)));
    }
    if let Some(first) = nn.first() {
        d.push(Block::Heading(2, "The NNBVSC's margin".into()));
        d.push(Block::Para(format!(
            "The a_i bias fraction x (Δb kept at Fig. 2's 0.5) up to which the NNBVSC stays bounded and tracks; \
{}. {}",
            scan_text(&first.found),
            criteria(first.found.e_limit_deg)
        )));
        let mut head = vec!["reading".to_string()];
        head.extend(COLUMNS.iter().map(|s| s.to_string()));
        d.push(Block::Table(head, threshold_rows(nn, false)));
    }
    d
}
