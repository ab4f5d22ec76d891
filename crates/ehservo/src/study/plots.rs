//! Plots of a study, chosen from its shape:
//!
//! - one numeric axis (with or without categorical ones such as
//!   `controller.kind`): e_max against that axis, one line per category, log
//!   scale when the values span more than a decade, unbounded runs marked
//!   with points above the curves (`emax_vs_<axis>.png/.svg`);
//! - two or more numeric axes: a heat map of e_max over the first two, one
//!   per combination of the other axes' values (up to six; `emax_map*.png`);
//! - Monte Carlo: a histogram of e_max over the runs, one per category
//!   (`emax_hist.png/.svg`), with unbounded runs counted in the title.

use super::{as_f64, Plan, RunRow};
use crate::plot::{Dash, Figure, HeatMap, Panel, Series};
use anyhow::Result;
use std::collections::BTreeMap;
use std::path::Path;

fn label(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

fn save(f: &Figure, dir: &Path, stem: &str) -> Result<()> {
    f.png(&dir.join(format!("{stem}.png")))?;
    f.svg(&dir.join(format!("{stem}.svg")))
}

fn file_safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Writes the plots that fit the study's shape into `dir`.
pub fn study_plots(plan: &Plan, rows: &[RunRow], dir: &Path) -> Result<()> {
    let numeric: Vec<usize> = plan
        .axes
        .iter()
        .enumerate()
        .filter(|(_, (_, vals))| vals.len() > 1 && vals.iter().all(|v| as_f64(v).is_some()))
        .map(|(i, _)| i)
        .collect();
    let others: Vec<usize> = (0..plan.axes.len())
        .filter(|i| !numeric.contains(i))
        .collect();
    let shape = Shape {
        plan,
        numeric,
        others,
        // The errors' unit: the base scenario's axis (deg or mm).
        unit: plan.axis().unit(),
    };
    if plan.study.monte_carlo.is_some() {
        histogram(&shape, rows, dir)?;
    }
    if shape.numeric.len() == 1 {
        emax_vs_axis(&shape, rows, dir)?;
    }
    if shape.numeric.len() >= 2 {
        heat_maps(&shape, rows, dir)?;
    }
    Ok(())
}

/// A study as its plots see it: its numeric axes (more than one value, all
/// numbers), the others, and the errors' unit.
struct Shape<'a> {
    plan: &'a Plan,
    numeric: Vec<usize>,
    others: Vec<usize>,
    unit: &'static str,
}

impl Shape<'_> {
    /// A run's category: `column = value` of each axis that varies among
    /// the non-numeric ones and the numeric ones in `skip`.
    fn category(&self, r: &RunRow, skip: &[usize]) -> String {
        let plan = self.plan;
        self.others
            .iter()
            .chain(self.numeric.iter().filter(|i| skip.contains(i)))
            .filter(|i| plan.axes[**i].1.len() > 1)
            .map(|i| format!("{} = {}", plan.axes[*i].0.column(), label(&r.values[*i])))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The runs grouped by their category (`skip` as in
    /// [`Shape::category`]), in the categories' order.
    fn groups<'r>(&self, rows: &'r [RunRow], skip: &[usize]) -> BTreeMap<String, Vec<&'r RunRow>> {
        let mut groups: BTreeMap<String, Vec<&RunRow>> = BTreeMap::new();
        for r in rows {
            groups.entry(self.category(r, skip)).or_default().push(r);
        }
        groups
    }
}

/// A run's e_max; None when it diverged or has no metrics.
fn e(r: &RunRow) -> Option<f64> {
    r.metrics
        .and_then(|m| if m.diverged { None } else { m.e_max })
}

/// Whether a run diverged.
fn unbounded(r: &RunRow) -> bool {
    r.metrics.is_some_and(|m| m.diverged)
}

/// Monte Carlo: a histogram of e_max over the runs, one per category, the
/// unbounded runs counted in the title (`emax_hist`).
fn histogram(shape: &Shape, rows: &[RunRow], dir: &Path) -> Result<()> {
    let (plan, unit) = (shape.plan, shape.unit);
    let groups = shape.groups(rows, &shape.numeric);
    let all: Vec<f64> = rows.iter().filter_map(e).collect();
    let (Some(lo), Some(hi)) = (
        all.iter().copied().reduce(f64::min),
        all.iter().copied().reduce(f64::max),
    ) else {
        return Ok(());
    };
    let bins = 40usize;
    let width = if hi > lo {
        (hi - lo) / bins as f64
    } else {
        1.0
    };
    let mut series = Vec::new();
    let mut n_unb = 0;
    for (ci, (cat, rs)) in groups.iter().enumerate() {
        let mut counts = vec![0u64; bins];
        for v in rs.iter().filter_map(|r| e(r)) {
            let k = (((v - lo) / width) as usize).min(bins - 1);
            counts[k] += 1;
        }
        n_unb += rs.iter().filter(|r| unbounded(r)).count();
        let (mut x, mut y) = (vec![lo], vec![0.0]);
        for (k, c) in counts.iter().enumerate() {
            let (a, b) = (lo + k as f64 * width, lo + (k + 1) as f64 * width);
            x.extend([a, b]);
            y.extend([*c as f64, *c as f64]);
        }
        x.push(lo + bins as f64 * width);
        y.push(0.0);
        let name = if cat.is_empty() {
            format!("{} runs", rs.len())
        } else {
            cat.clone()
        };
        series.push(Series::new(name, x, y, ci));
    }
    let f = Figure {
        title: format!(
            "{}: max |e| after the transient over {} runs{}",
            plan.study.name,
            rows.len(),
            if n_unb > 0 {
                format!(" ({n_unb} unbounded, not shown)")
            } else {
                String::new()
            }
        ),
        rows: 1,
        cols: 1,
        size: (1100, 650),
        panels: vec![Panel {
            title: "histogram".into(),
            x_label: format!("max |e| after t_s ({unit})"),
            y_label: "runs".into(),
            series,
            log_y: false,
            ..Default::default()
        }],
        ..Default::default()
    };
    save(&f, dir, "emax_hist")
}

/// One numeric axis: e_max against it, one line per category (log scale
/// when the values span more than a decade), the unbounded runs as points
/// above the curves (`emax_vs_<axis>`).
fn emax_vs_axis(shape: &Shape, rows: &[RunRow], dir: &Path) -> Result<()> {
    let (plan, unit) = (shape.plan, shape.unit);
    let ax = shape.numeric[0];
    let (axis, _) = &plan.axes[ax];
    let groups = shape.groups(rows, &[]);
    let finite: Vec<f64> = rows.iter().filter_map(e).filter(|v| *v > 0.0).collect();
    let (lo, hi) = (
        finite.iter().copied().fold(f64::INFINITY, f64::min),
        finite.iter().copied().fold(0.0, f64::max),
    );
    let log_y = hi > 10.0 * lo && lo > 0.0;
    let top = if log_y { hi * 2.0 } else { hi * 1.1 };
    let mut series = Vec::new();
    for (ci, (cat, rs)) in groups.iter().enumerate() {
        let pts = medians(rs, ax);
        let name = if cat.is_empty() {
            "e_max".to_string()
        } else {
            cat.clone()
        };
        series.push(Series::new(
            name.clone(),
            pts.iter().map(|p| p.0).collect(),
            pts.iter().map(|p| p.1).collect(),
            ci,
        ));
        let unb: Vec<&(f64, f64, usize)> = pts.iter().filter(|p| p.2 > 0).collect();
        if !unb.is_empty() {
            series.push(
                Series::new(
                    format!("{name}: unbounded"),
                    unb.iter().map(|p| p.0).collect(),
                    unb.iter()
                        .map(|_| {
                            if log_y {
                                top * 1.25f64.powi(ci as i32)
                            } else {
                                top * (1.0 + 0.04 * ci as f64)
                            }
                        })
                        .collect(),
                    ci,
                )
                .dash(Dash::Points),
            );
        }
    }
    let f = Figure {
        title: format!(
            "{}: max |e| after the transient against {}",
            plan.study.name,
            axis.column()
        ),
        rows: 1,
        cols: 1,
        size: (1100, 650),
        panels: vec![Panel {
            title: "points on the top line: unbounded runs".into(),
            x_label: axis.column(),
            y_label: if log_y {
                format!("max |e| after t_s ({unit}, log)")
            } else {
                format!("max |e| after t_s ({unit})")
            },
            series,
            log_y,
            ..Default::default()
        }],
        ..Default::default()
    };
    save(&f, dir, &format!("emax_vs_{}", file_safe(&axis.column())))
}

/// The runs' points along axis `ax`, in increasing x: each x's median
/// e_max over its replicates (NaN when none is bounded) and its count of
/// unbounded runs.
fn medians(rs: &[&RunRow], ax: usize) -> Vec<(f64, f64, usize)> {
    let mut by_x: BTreeMap<u64, (f64, Vec<f64>, usize)> = BTreeMap::new();
    for r in rs {
        let x = as_f64(&r.values[ax]).unwrap_or(f64::NAN);
        let entry = by_x.entry(x.to_bits()).or_insert((x, Vec::new(), 0));
        match e(r) {
            Some(v) => entry.1.push(v),
            None if unbounded(r) => entry.2 += 1,
            None => {}
        }
    }
    let mut pts: Vec<(f64, f64, usize)> = by_x
        .values()
        .map(|(x, v, u)| {
            let mut v = v.clone();
            v.sort_by(f64::total_cmp);
            (
                *x,
                if v.is_empty() {
                    f64::NAN
                } else {
                    v[v.len() / 2]
                },
                *u,
            )
        })
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    pts
}

/// Two or more numeric axes: a heat map of e_max over the first two, one
/// per combination of the other axes' values, up to six (`emax_map*`).
fn heat_maps(shape: &Shape, rows: &[RunRow], dir: &Path) -> Result<()> {
    let (plan, unit, numeric) = (shape.plan, shape.unit, &shape.numeric);
    let (ix, iy) = (numeric[0], numeric[1]);
    let xs: Vec<f64> = plan.axes[ix].1.iter().filter_map(as_f64).collect();
    let ys: Vec<f64> = plan.axes[iy].1.iter().filter_map(as_f64).collect();
    let groups = shape.groups(rows, &numeric[2..]);
    for (gi, (cat, rs)) in groups.iter().enumerate().take(6) {
        let mut cells: Vec<Vec<Vec<Option<f64>>>> = vec![vec![Vec::new(); xs.len()]; ys.len()];
        for r in rs {
            let (x, y) = (as_f64(&r.values[ix]), as_f64(&r.values[iy]));
            let (Some(x), Some(y)) = (x, y) else { continue };
            let cx = xs.iter().position(|v| v.to_bits() == x.to_bits());
            let cy = ys.iter().position(|v| v.to_bits() == y.to_bits());
            if let (Some(cx), Some(cy)) = (cx, cy) {
                cells[cy][cx].push(e(r));
            }
        }
        // Median over replicates; a cell with any unbounded run is None.
        let z: Vec<Vec<Option<f64>>> = cells
            .into_iter()
            .map(|row| {
                row.into_iter()
                    .map(|c| {
                        if c.is_empty() || c.iter().any(|v| v.is_none()) {
                            None
                        } else {
                            let mut v: Vec<f64> = c.into_iter().flatten().collect();
                            v.sort_by(f64::total_cmp);
                            Some(v[v.len() / 2])
                        }
                    })
                    .collect()
            })
            .collect();
        let h = HeatMap {
            title: format!(
                "{}: max |e| after the transient{}",
                plan.study.name,
                if cat.is_empty() {
                    String::new()
                } else {
                    format!(" ({cat})")
                }
            ),
            x_label: plan.axes[ix].0.column(),
            y_label: plan.axes[iy].0.column(),
            xs: xs.clone(),
            ys: ys.clone(),
            z,
            log_z: true,
            z_label: format!("max |e| after t_s ({unit})"),
            size: (1100, 750),
        };
        let stem = if gi == 0 {
            "emax_map".to_string()
        } else {
            format!("emax_map_{gi}")
        };
        h.png(&dir.join(format!("{stem}.png")))?;
        h.svg(&dir.join(format!("{stem}.svg")))?;
    }
    Ok(())
}
