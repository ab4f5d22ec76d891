//! The boundary searches' figures: e_max against the swept fraction, one
//! panel per bias reading and b reading, diverged runs marked in strips
//! (the traditional VSC's breaking point, the NNBVSC's margin).

use super::PaperFigure;
use crate::plot::{Dash, Figure, Panel, Series};
use crate::reproduce::breaking::{BiasReading, Boundary};

/// Line styles of the boundary figures, one per simulation reading of a panel.
const STYLES: [Dash; 4] = [Dash::Solid, Dash::Dashed, Dash::DashDot, Dash::Dotted];

fn bias_title(br: Option<BiasReading>) -> &'static str {
    match br {
        Some(BiasReading::R1) => "R1 (controller keeps Fig. 2's bounds)",
        Some(BiasReading::R2) => "R2 (controller told the true size x)",
        None => "NNBVSC",
    }
}

/// A boundary search's legend entry: where it first diverges and how far
/// it tracks.
fn legend(b: &Boundary) -> String {
    let (bd, tr) = (&b.found.bounded, &b.found.tracking);
    let start = b.found.grid.start;
    let unbounded = match bd.first_fail {
        None => "bounded throughout".to_string(),
        Some(x) if (x - start).abs() < 1e-12 => "unbounded throughout".to_string(),
        Some(x) => format!("unbounded from {x:.3}"),
    };
    let tracking = match (tr.first_fail, tr.last_pass) {
        (None, _) => "tracks throughout".to_string(),
        (Some(_), None) => "never tracks".to_string(),
        (Some(x), Some(_)) => format!("tracks below {x:.3}"),
    };
    let nm = if bd.non_monotone || tr.non_monotone {
        " (non-monotone)"
    } else {
        ""
    };
    format!("{}: {unbounded}, {tracking}{nm}", b.reading)
}

/// e_max (log) against the swept fraction: one panel per bias reading (rows:
/// R1, R2) and b reading (columns: Δb fractions of β = 0.5·b̄, or of b̄),
/// at most four simulation readings a panel, each its colour and dash (the
/// same reading keeps them across panels). A run that diverged leaves a gap
/// in its line and a marker in a strip above the curves, in the line's
/// colour; the horizontal dotted line is the tracking limit.
pub fn boundary_figure(stem: &str, title: &str, x_label: &str, bs: &[Boundary]) -> PaperFigure {
    let mut rows: Vec<Option<BiasReading>> = Vec::new();
    let mut cols: Vec<f64> = Vec::new();
    for b in bs {
        if !rows.contains(&b.bias_reading) {
            rows.push(b.bias_reading);
        }
        if !cols.iter().any(|c| (c - b.b_reference).abs() < 1e-12) {
            cols.push(b.b_reference);
        }
    }
    cols.sort_by(f64::total_cmp);
    let mut panels = Vec::new();
    for br in &rows {
        for &bref in &cols {
            let here: Vec<&Boundary> = bs
                .iter()
                .filter(|b| b.bias_reading == *br && (b.b_reference - bref).abs() < 1e-12)
                .collect();
            // The divergence strips sit below the lowest curve (the legend
            // takes the upper right).
            let low = here
                .iter()
                .flat_map(|b| b.found.scan.iter().filter_map(|p| p.e_max_deg))
                .chain(here.iter().map(|b| b.found.e_limit_deg))
                .filter(|e| e.is_finite() && *e > 0.0)
                .fold(f64::INFINITY, f64::min);
            let bottom = if low.is_finite() { 0.5 * low } else { 0.1 };
            let mut series = Vec::new();
            for (i, b) in here.iter().enumerate() {
                let x: Vec<f64> = b.found.scan.iter().map(|p| p.x).collect();
                let e: Vec<f64> = b
                    .found
                    .scan
                    .iter()
                    .map(|p| match p.diverged_at_s {
                        Some(_) => f64::NAN,
                        None => p.e_max_deg.unwrap_or(f64::NAN),
                    })
                    .collect();
                let label = legend(b);
                // A reading with no bounded run has no line: its strip takes
                // the legend entry.
                let no_line = e.iter().all(|v| !v.is_finite());
                let (line_label, strip_label) = if no_line {
                    (String::new(), label)
                } else {
                    (label, String::new())
                };
                series
                    .push(Series::new(line_label, x.clone(), e, i).dash(STYLES[i % STYLES.len()]));
                // The divergence strip: one row per reading below the curves.
                let strip = bottom / 1.5f64.powi(i as i32);
                let d: Vec<f64> = b
                    .found
                    .scan
                    .iter()
                    .map(|p| {
                        if p.diverged_at_s.is_some() {
                            strip
                        } else {
                            f64::NAN
                        }
                    })
                    .collect();
                series.push(Series::new(strip_label, x, d, i).dash(Dash::Points));
            }
            if let Some(b) = here.first() {
                let (x0, x1) = (
                    b.found.grid.start,
                    b.found.grid.start
                        + (b.found.grid.points.saturating_sub(1)) as f64 * b.found.grid.step,
                );
                series.push(
                    Series::new(
                        format!("tracking limit {}°", b.found.e_limit_deg),
                        vec![x0, x1],
                        vec![b.found.e_limit_deg; 2],
                        4,
                    )
                    .dash(Dash::Dotted),
                );
            }
            panels.push(Panel {
                title: format!(
                    "{}; Δb fractions of {} — bottom strips: diverged runs",
                    bias_title(*br),
                    if bref < 0.75 {
                        "β = 0.5·b̄ (text)"
                    } else {
                        "b̄ (hypothesis Δb = β)"
                    }
                ),
                x_label: x_label.into(),
                y_label: "max |e| after 2 s (deg, log)".into(),
                series,
                log_y: true,
                ..Default::default()
            });
        }
    }
    let (nr, nc) = (rows.len().max(1), cols.len().max(1));
    PaperFigure {
        stem: stem.into(),
        caption: format!(
            "{title}: one panel per bias reading and b reading; a gap in a line and a marker in the bottom strips is a \
diverged run; dotted: the tracking limit"
        ),
        figure: Figure {
            title: title.into(),
            rows: nr,
            cols: nc,
            size: (900 * nc as u32, 120 + 480 * nr as u32),
            panels,
            ..Default::default()
        },
    }
}
