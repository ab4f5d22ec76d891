//! Where the controllers stop working.
//!
//! - **The traditional VSC's breaking point**: the smallest bias fraction x at
//!   which Theorem 1's controller becomes unbounded, under both readings of
//!   "x % bias" (SPEC §2): R1 keeps the controller's bounds of Fig. 2
//!   (α_i = |ā_i|, β = 0.5|b̄|) with the true Δa_i = x·|ā_i|, Δb = x·0.5·b̄;
//!   R2 tells the controller the true size (α_i = x·|ā_i|, β = x·0.5·b̄).
//!   (With `b_reference = 1`, 0.5·b̄ becomes b̄ throughout.)
//!   The paper: "bounded at 40 %, unbounded above 45 %".
//! - **The NNBVSC's margin**: the largest a_i bias (b bias kept at Fig. 2's
//!   0.5) at which it still tracks: bounded with e_max_deg < 0.5°.
//!
//! Both scan a grid first (the boundary need not be monotone: a loop can be
//! unbounded at x and bounded again at a larger x), then bisect the first
//! transition of the scan.

use crate::run::{run, Keep};
use crate::scenario::{parse_value, Scenario};
use anyhow::Result;
use serde::Serialize;

/// How the bias is told to the traditional VSC.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum BiasReading {
    /// Bounds of Fig. 2, true variation x.
    R1,
    /// Bounds equal to the true variation x.
    R2,
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
    /// Whether the point passes the criterion of its study.
    fn ok(&self, e_limit: Option<f64>) -> bool {
        self.diverged_at_s.is_none()
            && e_limit.is_none_or(|lim| self.e_max_deg.is_some_and(|e| e < lim))
    }
}

/// One boundary search, labelled.
#[derive(Debug, Clone, Serialize)]
pub struct Boundary {
    /// The reading of the simulation (manifest id).
    pub reading: String,
    /// R1 / R2 for the VSC; None for the NNBVSC margin.
    pub bias_reading: Option<BiasReading>,
    /// What the search found.
    #[serde(flatten)]
    pub found: Search,
}

/// The result of a boundary search.
#[derive(Debug, Clone, Serialize)]
pub struct Search {
    /// The scan.
    pub scan: Vec<ScanPoint>,
    /// Last passing value before the first failure (bisected).
    pub last_ok: Option<f64>,
    /// First failing value (bisected).
    pub first_fail: Option<f64>,
    /// The scan passes again after failing.
    pub non_monotone: bool,
}

fn point(base: &Scenario, set: &[String], x: f64) -> Result<ScanPoint> {
    let values: Vec<(String, toml::Value)> = set
        .iter()
        .filter_map(|s| s.split_once('='))
        .map(|(k, v)| (k.trim().to_string(), parse_value(v)))
        .collect();
    let s = base.with_values(&values).map_err(anyhow::Error::from)?;
    let m = run(&s, Keep::Nothing)?.metrics;
    Ok(ScanPoint {
        x,
        e_max_deg: m.e_max_deg,
        diverged_at_s: m.diverged_at_s,
    })
}

/// A boundary search over `grid`, with `sets(x)` giving the overrides at x
/// and `e_limit` the tracking criterion (None: bounded is enough).
pub fn search(
    base: &Scenario,
    grid: &[f64],
    sets: &(dyn Fn(f64) -> Vec<String> + Sync),
    e_limit: Option<f64>,
    bisections: usize,
) -> Result<Search> {
    use rayon::prelude::*;
    let scan: Vec<ScanPoint> = grid
        .par_iter()
        .map(|&x| point(base, &sets(x), x))
        .collect::<Result<_>>()?;
    let first_bad = scan.iter().position(|p| !p.ok(e_limit));
    let Some(i) = first_bad else {
        return Ok(Search {
            scan,
            last_ok: grid.last().copied(),
            first_fail: None,
            non_monotone: false,
        });
    };
    let non_monotone = scan[i..].iter().any(|p| p.ok(e_limit));
    if i == 0 {
        return Ok(Search {
            scan,
            last_ok: None,
            first_fail: Some(grid[0]),
            non_monotone,
        });
    }
    let (mut lo, mut hi) = (grid[i - 1], grid[i]);
    for _ in 0..bisections {
        let mid = 0.5 * (lo + hi);
        if point(base, &sets(mid), mid)?.ok(e_limit) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(Search {
        scan,
        last_ok: Some(lo),
        first_fail: Some(hi),
        non_monotone,
    })
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
