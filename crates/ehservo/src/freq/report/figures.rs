//! The figures of `ehservo freq`: log-frequency panels (the Bode plot of
//! the computed curves, the measured responses against the computed ones)
//! and the Nyquist curve of L, as PNG or SVG.

use super::{db, unwrap, MeasuredSet};
use crate::axis::Axis;
use crate::freq::measure::Measured;
use crate::freq::response::{LoopModel, Responses};
use crate::freq::ss::C64;
use crate::plot::{color, ensure_font, png_file, FAMILY};
use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde_json::Value;
use std::f64::consts::PI;
use std::path::Path;

/// A line of a log-frequency panel.
struct Line {
    label: String,
    x: Vec<f64>,
    y: Vec<Option<f64>>,
    color: usize,
    points: bool,
}

/// A panel with a logarithmic frequency axis.
struct LogPanel {
    title: String,
    y_label: String,
    lines: Vec<Line>,
    marks: Vec<f64>,
}

/// Draws panels on a grid into `path` (PNG or SVG by its extension).
fn draw_log_panels(
    path: &Path,
    title: &str,
    rows: usize,
    cols: usize,
    panels: &[LogPanel],
) -> Result<()> {
    ensure_font();
    let size = (700 * cols as u32, 380 * rows as u32 + 40);
    macro_rules! go {
        ($root:expr) => {{
            let root = $root;
            root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
            let body = root
                .titled(title, (FAMILY, 20).into_font())
                .map_err(|e| anyhow!("{e}"))?;
            for (area, p) in body.split_evenly((rows, cols)).iter().zip(panels) {
                log_panel(area, p)?;
            }
            root.present().map_err(|e| anyhow!("{e}"))?;
        }};
    }
    if path.extension().and_then(|e| e.to_str()) == Some("svg") {
        go!(SVGBackend::new(path, size).into_drawing_area());
        Ok(())
    } else {
        png_file(path, size, |root| {
            go!(root);
            Ok(())
        })
    }
}

fn log_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &LogPanel) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let xs = p
        .lines
        .iter()
        .flat_map(|l| l.x.iter().copied())
        .filter(|x| *x > 0.0 && x.is_finite());
    let (x0, x1) = xs.fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    if !(x0.is_finite() && x1 > x0) {
        return Ok(());
    }
    let ys = p
        .lines
        .iter()
        .flat_map(|l| l.y.iter().flatten().copied())
        .filter(|y| y.is_finite());
    let (mut y0, mut y1) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
        (a.min(y), b.max(y))
    });
    if !(y0.is_finite() && y1.is_finite()) {
        (y0, y1) = (-1.0, 1.0);
    }
    if y1 - y0 < 1e-9 {
        y0 -= 1.0;
        y1 += 1.0;
    }
    let m = 0.05 * (y1 - y0);
    let font = |s: u32| (FAMILY, s).into_font();
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, font(16))
        .margin(8)
        .x_label_area_size(36)
        .y_label_area_size(64)
        .build_cartesian_2d((x0..x1).log_scale(), (y0 - m)..(y1 + m))
        .map_err(|e| anyhow!("building a chart: {e}"))?;
    chart
        .configure_mesh()
        .x_desc("frequency (Hz)")
        .y_desc(&p.y_label)
        .label_style(font(12))
        .axis_desc_style(font(13))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| anyhow!("drawing axes: {e}"))?;
    for l in &p.lines {
        let c = color(l.color);
        let style = ShapeStyle::from(&c).stroke_width(2);
        let mut first = true;
        let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for (x, y) in l.x.iter().zip(&l.y) {
            match y {
                Some(y) if y.is_finite() && *x > 0.0 => {
                    runs.last_mut().expect("one run").push((*x, *y))
                }
                _ => runs.push(Vec::new()),
            }
        }
        for run in runs.iter().filter(|r| !r.is_empty()) {
            let anno = if l.points {
                chart
                    .draw_series(
                        run.iter()
                            .map(|&(x, y)| Circle::new((x, y), 3, style.filled())),
                    )
                    .map_err(|e| anyhow!("drawing points: {e}"))?
            } else {
                chart
                    .draw_series(LineSeries::new(run.iter().copied(), style))
                    .map_err(|e| anyhow!("drawing a line: {e}"))?
            };
            if first && !l.label.is_empty() {
                let pts = l.points;
                anno.label(&l.label).legend(move |(x, y)| {
                    if pts {
                        Circle::new((x + 10, y), 3, c.filled()).into_dyn()
                    } else {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)).into_dyn()
                    }
                });
            }
            first = false;
        }
    }
    for &mx in p.marks.iter().filter(|m| **m >= x0 && **m <= x1) {
        chart
            .draw_series(DashedLineSeries::new(
                [(mx, y0 - m), (mx, y1 + m)],
                6,
                4,
                ShapeStyle::from(&RGBColor(90, 90, 90)).stroke_width(1),
            ))
            .map_err(|e| anyhow!("drawing a mark: {e}"))?;
    }
    chart
        .configure_series_labels()
        .label_font(font(12))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
        .map_err(|e| anyhow!("drawing the legend: {e}"))?;
    Ok(())
}

pub(super) fn bode(
    path: &Path,
    lp: &LoopModel,
    rs: &[Responses],
    f: &[f64],
    summary: &Value,
    axis: Axis,
) -> Result<()> {
    let pick = [(0usize, 0usize), (3, 1), (4, 2), (5, 3), (6, 4), (7, 5)];
    let curves: Vec<(usize, Vec<Option<C64>>)> = pick
        .iter()
        .map(|&(i, c)| (c, rs.iter().map(|r| r.all()[i]).collect::<Vec<_>>()))
        .filter(|(_, v)| v.iter().any(|z| z.is_some()))
        .collect();
    let a = axis.letter();
    let si = axis.si_unit();
    let labels = [
        format!("G ({si}/V)"),
        "L".to_string(),
        "S".to_string(),
        "T".to_string(),
        format!("{a}/{a}d"),
        format!("{a}/d ({si}/V)"),
    ];
    let mut gains = Vec::new();
    let mut phases = Vec::new();
    for (c, v) in &curves {
        gains.push(Line {
            label: labels[*c].clone(),
            x: f.to_vec(),
            y: v.iter().map(|z| z.map(db)).collect(),
            color: *c,
            points: false,
        });
        phases.push(Line {
            label: labels[*c].clone(),
            x: f.to_vec(),
            y: unwrap(v),
            color: *c,
            points: false,
        });
    }
    let m = &summary["computed"]["margins"];
    let mut marks = Vec::new();
    for k in ["gain_margin", "phase_margin"] {
        if let Some(x) = m[k]["f_Hz"].as_f64() {
            marks.push(x);
        }
    }
    let fmt = |v: Option<f64>, u: &str| v.map(|x| format!("{x:.2}{u}")).unwrap_or("—".into());
    let op = &summary["computed"]["operating_point"];
    let title = format!(
        "{}: {} loop about {} = {:.3}{} — GM {}, PM {}, DM {}",
        summary["scenario"].as_str().unwrap_or(""),
        summary["controller"].as_str().unwrap_or(""),
        a,
        op[match axis {
            Axis::Rotary => "theta_deg",
            Axis::Linear | Axis::Force | Axis::Pressure => "x_mm",
        }]
        .as_f64()
        .unwrap_or(0.0),
        axis.suffix(),
        fmt(m["gain_margin"]["gain_margin_dB"].as_f64(), " dB"),
        fmt(m["phase_margin"]["phase_margin_deg"].as_f64(), "°"),
        fmt(
            m["delay_margin"]["delay_margin_s"]
                .as_f64()
                .map(|d| d * 1e3),
            " ms"
        ),
    );
    let _ = lp;
    draw_log_panels(
        path,
        &title,
        2,
        1,
        &[
            LogPanel {
                title: "gain".into(),
                y_label: "gain (dB)".into(),
                lines: gains,
                marks: marks.clone(),
            },
            LogPanel {
                title: "phase".into(),
                y_label: "phase (deg)".into(),
                lines: phases,
                marks,
            },
        ],
    )
}

pub(super) fn nyquist(path: &Path, rs: &[Responses], summary: &Value) -> Result<()> {
    ensure_font();
    let l: Vec<(f64, f64)> = rs
        .iter()
        .filter_map(|r| r.l)
        .filter(|z| z.re.is_finite() && z.im.is_finite())
        .map(|z| (z.re, z.im))
        .collect();
    let size = (800u32, 800u32);
    let (lo, hi) = (-3.0, 1.5);
    let title = format!(
        "{}: Nyquist curve of L (ω > 0 solid, its mirror dashed), −1 marked",
        summary["scenario"].as_str().unwrap_or("")
    );
    macro_rules! go {
        ($root:expr) => {{
            let root = $root;
            root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
            let font = |s: u32| (FAMILY, s).into_font();
            let mut chart = ChartBuilder::on(&root)
                .caption(&title, font(16))
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(50)
                .build_cartesian_2d(lo..hi, -2.25..2.25)
                .map_err(|e| anyhow!("building a chart: {e}"))?;
            chart
                .configure_mesh()
                .x_desc("Re L")
                .y_desc("Im L")
                .label_style(font(12))
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(|e| anyhow!("drawing axes: {e}"))?;
            let circle: Vec<(f64, f64)> = (0..=360)
                .map(|i| {
                    let a = i as f64 * PI / 180.0;
                    (a.cos(), a.sin())
                })
                .collect();
            chart
                .draw_series(DashedLineSeries::new(
                    circle,
                    4,
                    4,
                    ShapeStyle::from(&RGBColor(150, 150, 150)),
                ))
                .map_err(|e| anyhow!("{e}"))?;
            // Clip the curve to the box: split where it leaves.
            let inside = |p: &(f64, f64)| p.0 >= lo && p.0 <= hi && p.1.abs() <= 2.25;
            let style = ShapeStyle::from(&color(1)).stroke_width(2);
            for pts in l.split(|p| !inside(p)).filter(|r| r.len() > 1) {
                chart
                    .draw_series(LineSeries::new(pts.iter().copied(), style))
                    .map_err(|e| anyhow!("{e}"))?;
                chart
                    .draw_series(DashedLineSeries::new(
                        pts.iter().map(|p| (p.0, -p.1)),
                        6,
                        4,
                        ShapeStyle::from(&color(1)),
                    ))
                    .map_err(|e| anyhow!("{e}"))?;
            }
            chart
                .draw_series(std::iter::once(Cross::new(
                    (-1.0, 0.0),
                    8,
                    ShapeStyle::from(&BLACK).stroke_width(2),
                )))
                .map_err(|e| anyhow!("{e}"))?;
            root.present().map_err(|e| anyhow!("{e}"))?;
        }};
    }
    if path.extension().and_then(|e| e.to_str()) == Some("svg") {
        go!(SVGBackend::new(path, size).into_drawing_area());
        Ok(())
    } else {
        png_file(path, size, |root| {
            go!(root);
            Ok(())
        })
    }
}

pub(super) fn measured_plot(
    path: &Path,
    sets: &[MeasuredSet],
    lp: Option<&LoopModel>,
    name: &str,
    axis: Axis,
) -> Result<()> {
    let mut panels = Vec::new();
    let a = axis.letter();
    let track_title = format!("{a}/{a}d (tracking)");
    let dist_title = format!("{a}/d (disturbance on the command)");
    let dist_unit = format!("{}/V", axis.si_unit());
    type Sel = fn(&Measured) -> Option<C64>;
    let th: Sel = |m| m.theta_c();
    let sv: Sel = |m| m.s_c();
    type Spec<'a> = (&'a str, &'a str, bool, Sel, fn(&Responses) -> Option<C64>);
    let specs: [Spec<'_>; 3] = [
        (&track_title, "", true, th, |r| r.track),
        (&dist_title, &dist_unit, false, th, |r| r.dist),
        ("S = u/d", "", false, sv, |r| r.s),
    ];
    for (title, unit, tracking, sel, csel) in specs {
        let mut g = Vec::new();
        let mut p = Vec::new();
        for (i, set) in sets.iter().enumerate() {
            let pts = if tracking {
                &set.tracking
            } else {
                &set.disturbance
            };
            let x: Vec<f64> = pts.iter().map(|m| m.f_hz).collect();
            let z: Vec<Option<C64>> = pts.iter().map(sel).collect();
            g.push(Line {
                label: format!("measured ({})", set.method.as_str()),
                x: x.clone(),
                y: z.iter().map(|v| v.map(db)).collect(),
                color: 1 + i,
                points: true,
            });
            p.push(Line {
                label: format!("measured ({})", set.method.as_str()),
                x,
                y: unwrap(&z),
                color: 1 + i,
                points: true,
            });
        }
        if let Some(lp) = lp {
            let f: Vec<f64> = sets[0].tracking.iter().map(|m| m.f_hz).collect();
            let lo = f.first().copied().unwrap_or(0.1);
            let hi = f.last().copied().unwrap_or(1.0);
            let fine: Vec<f64> = (0..300)
                .map(|i| lo * (hi / lo).powf(i as f64 / 299.0))
                .collect();
            let z: Vec<Option<C64>> = fine.iter().map(|&f| csel(&lp.at(2.0 * PI * f))).collect();
            if z.iter().any(|v| v.is_some()) {
                g.push(Line {
                    label: "computed".into(),
                    x: fine.clone(),
                    y: z.iter().map(|v| v.map(db)).collect(),
                    color: 0,
                    points: false,
                });
                p.push(Line {
                    label: "computed".into(),
                    x: fine,
                    y: unwrap(&z),
                    color: 0,
                    points: false,
                });
            }
        }
        let u = if unit.is_empty() {
            String::new()
        } else {
            format!(" re 1 {unit}")
        };
        panels.push(LogPanel {
            title: format!("{title}: gain"),
            y_label: format!("gain (dB{u})"),
            lines: g,
            marks: Vec::new(),
        });
        panels.push(LogPanel {
            title: format!("{title}: phase"),
            y_label: "phase (deg)".into(),
            lines: p,
            marks: Vec::new(),
        });
    }
    draw_log_panels(
        path,
        &format!("{name}: measured frequency responses"),
        3,
        2,
        &panels,
    )
}
