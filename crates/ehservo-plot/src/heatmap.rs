//! Heat maps: [`HeatMap`], a value over two categorical axes as coloured
//! cells with a colour bar.

use crate::axes::range;
use crate::backend::{ensure_font, png_file, FAMILY};
use anyhow::{anyhow, Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// A map of a value over two axes, drawn as coloured cells (categorical
/// axes: one cell per value, labelled with the value). `None` cells
/// (diverged runs) are drawn black.
#[derive(Debug, Clone)]
pub struct HeatMap {
    /// Title.
    pub title: String,
    /// x axis label.
    pub x_label: String,
    /// y axis label.
    pub y_label: String,
    /// Values along x.
    pub xs: Vec<f64>,
    /// Values along y.
    pub ys: Vec<f64>,
    /// `z[iy][ix]`.
    pub z: Vec<Vec<Option<f64>>>,
    /// Colour by log10(z).
    pub log_z: bool,
    /// What z is (for the colour bar).
    pub z_label: String,
    /// Size in pixels.
    pub size: (u32, u32),
}

/// A perceptually ordered ramp (viridis, sampled at 5 points), t in [0, 1].
fn ramp(t: f64) -> RGBColor {
    const P: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let t = t.clamp(0.0, 1.0) * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f64;
    let lerp = |a: f64, b: f64| (a + f * (b - a)).round() as u8;
    RGBColor(
        lerp(P[i].0, P[i + 1].0),
        lerp(P[i].1, P[i + 1].1),
        lerp(P[i].2, P[i + 1].2),
    )
}

fn short(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-2 || v.abs() >= 1e4) {
        format!("{v:.2e}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

fn draw_heatmap<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, h: &HeatMap) -> Result<()>
where
    DB::ErrorType: 'static,
{
    ensure_font();
    root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
    let (main, bar) = root.split_horizontally(h.size.0.saturating_sub(130));
    let vals: Vec<f64> =
        h.z.iter()
            .flatten()
            .flatten()
            .copied()
            .filter(|v| v.is_finite() && (!h.log_z || *v > 0.0))
            .map(|v| if h.log_z { v.log10() } else { v })
            .collect();
    let (lo, hi) = range(vals.iter().copied()).unwrap_or((0.0, 1.0));
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else {
        (lo - 0.5, hi + 0.5)
    };
    let (nx, ny) = (h.xs.len(), h.ys.len());
    let font = |s: u32| (FAMILY, s).into_font();
    let mut chart = ChartBuilder::on(&main)
        .caption(&h.title, font(18))
        .margin(10)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(-0.5..nx as f64 - 0.5, -0.5..ny as f64 - 0.5)
        .map_err(|e| anyhow!("{e}"))?;
    let xs = h.xs.clone();
    let ys = h.ys.clone();
    // Cells are centred on whole numbers; only those ticks get a label.
    let at = |vals: &[f64], v: f64| -> String {
        let i = v.round();
        if (v - i).abs() < 1e-6 && i >= 0.0 {
            vals.get(i as usize).map(|x| short(*x)).unwrap_or_default()
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(&h.x_label)
        .y_desc(&h.y_label)
        .x_labels(2 * nx.min(16) + 1)
        .y_labels(2 * ny.min(16) + 1)
        .x_label_formatter(&|v| at(&xs, *v))
        .y_label_formatter(&|v| at(&ys, *v))
        .label_style(font(12))
        .axis_desc_style(font(14))
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    for (iy, row) in h.z.iter().enumerate() {
        for (ix, v) in row.iter().enumerate() {
            let color = match v {
                Some(z) if z.is_finite() && (!h.log_z || *z > 0.0) => {
                    let z = if h.log_z { z.log10() } else { *z };
                    ramp((z - lo) / (hi - lo))
                }
                _ => BLACK,
            };
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [
                        (ix as f64 - 0.5, iy as f64 - 0.5),
                        (ix as f64 + 0.5, iy as f64 + 0.5),
                    ],
                    color.filled(),
                )))
                .map_err(|e| anyhow!("{e}"))?;
        }
    }
    // Colour bar.
    let mut cb = ChartBuilder::on(&bar)
        .margin_top(40)
        .margin_bottom(60)
        .margin_right(10)
        .y_label_area_size(60)
        .caption(
            if h.log_z {
                format!("{} (log10)", h.z_label)
            } else {
                h.z_label.clone()
            },
            font(12),
        )
        .build_cartesian_2d(0.0..1.0, lo..hi)
        .map_err(|e| anyhow!("{e}"))?;
    cb.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .label_style(font(12))
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    let steps = 64;
    for k in 0..steps {
        let a = lo + (hi - lo) * k as f64 / steps as f64;
        let b = lo + (hi - lo) * (k + 1) as f64 / steps as f64;
        cb.draw_series(std::iter::once(Rectangle::new(
            [(0.0, a), (1.0, b)],
            ramp(k as f64 / (steps - 1) as f64).filled(),
        )))
        .map_err(|e| anyhow!("{e}"))?;
    }
    root.draw(&Text::new(
        "black: unbounded",
        (10, h.size.1 as i32 - 18),
        font(12),
    ))
    .map_err(|e| anyhow!("{e}"))?;
    root.present().map_err(|e| anyhow!("{e}"))?;
    Ok(())
}

impl HeatMap {
    /// Renders to a PNG file.
    pub fn png(&self, path: &Path) -> Result<()> {
        png_file(path, self.size, |root| draw_heatmap(root, self))
            .with_context(|| format!("rendering {}", path.display()))
    }

    /// Renders to an SVG file.
    pub fn svg(&self, path: &Path) -> Result<()> {
        let root = SVGBackend::new(path, self.size).into_drawing_area();
        draw_heatmap(root, self).with_context(|| format!("rendering {}", path.display()))
    }
}
