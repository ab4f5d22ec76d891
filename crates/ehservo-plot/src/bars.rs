//! Bar charts: [`Bars`], grouped bars on a logarithmic axis, a cross where
//! a value is missing.

use crate::axes::range;
use crate::backend::{ensure_font, png_file, FAMILY};
use crate::style::color;
use anyhow::{anyhow, Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Grouped bars on a logarithmic axis: a group per category (e.g. a
/// scenario), a bar per series (e.g. a controller) in each; a missing or
/// non-positive value is a cross at the top.
#[derive(Debug, Clone)]
pub struct Bars {
    /// Title across the top.
    pub title: String,
    /// y axis label (with unit).
    pub y_label: String,
    /// The groups, left to right.
    pub groups: Vec<String>,
    /// (legend text, a value per group; None: missing, e.g. unbounded).
    pub series: Vec<(String, Vec<Option<f64>>)>,
    /// Size in pixels.
    pub size: (u32, u32),
}

fn draw_bars<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, b: &Bars) -> Result<()>
where
    DB::ErrorType: 'static,
{
    ensure_font();
    root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
    let body = root
        .titled(&b.title, (FAMILY, 22).into_font())
        .map_err(|e| anyhow!("{e}"))?;
    let font = |s: u32| (FAMILY, s).into_font();
    let ok = |v: f64| v.is_finite() && v > 0.0;
    let values = b
        .series
        .iter()
        .flat_map(|s| s.1.iter().flatten().copied())
        .filter(|&v| ok(v));
    let (lo, hi) = range(values).unwrap_or((0.1, 1.0));
    // Room above the tallest bar for the legend.
    let (y0, y1) = (lo / 2.0, hi * 600.0);
    let ng = b.groups.len().max(1);
    let ns = b.series.len().max(1);
    let width = 0.8 / ns as f64;
    let mut chart = ChartBuilder::on(&body)
        .margin(12)
        .x_label_area_size(10)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..ng as f64, (y0..y1).log_scale())
        .map_err(|e| anyhow!("building a chart: {e}"))?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_x_axis()
        .y_desc(&b.y_label)
        .label_style(font(13))
        .axis_desc_style(font(14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| anyhow!("drawing axes: {e}"))?;
    for (k, (label, vals)) in b.series.iter().enumerate() {
        let c = color(k);
        let x = |g: usize| g as f64 + 0.1 + k as f64 * width;
        chart
            .draw_series(vals.iter().enumerate().filter_map(|(g, v)| {
                v.filter(|&v| ok(v)).map(|v| {
                    Rectangle::new([(x(g), y0), (x(g) + width * 0.9, v)], c.mix(0.85).filled())
                })
            }))
            .map_err(|e| anyhow!("drawing bars: {e}"))?
            .label(label.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 16, y + 5)], c.filled()));
        chart
            .draw_series(
                vals.iter()
                    .enumerate()
                    .filter(|(_, v)| v.filter(|&v| ok(v)).is_none())
                    .map(|(g, _)| {
                        Cross::new(
                            (x(g) + width * 0.45, hi * 1.5),
                            6,
                            ShapeStyle::from(&c).stroke_width(3),
                        )
                    }),
            )
            .map_err(|e| anyhow!("drawing the unbounded marks: {e}"))?;
    }
    let style = TextStyle::from(font(15)).pos(Pos::new(HPos::Center, VPos::Bottom));
    chart
        .draw_series(
            b.groups.iter().enumerate().map(|(g, name)| {
                Text::new(name.clone(), (g as f64 + 0.5, y0 * 1.15), style.clone())
            }),
        )
        .map_err(|e| anyhow!("drawing the group names: {e}"))?;
    chart
        .configure_series_labels()
        .label_font(font(13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| anyhow!("drawing the legend: {e}"))?;
    root.present().map_err(|e| anyhow!("{e}"))?;
    Ok(())
}

impl Bars {
    /// Renders to a PNG file.
    pub fn png(&self, path: &Path) -> Result<()> {
        png_file(path, self.size, |root| draw_bars(root, self))
            .with_context(|| format!("rendering {}", path.display()))
    }

    /// Renders to an SVG file.
    pub fn svg(&self, path: &Path) -> Result<()> {
        let root = SVGBackend::new(path, self.size).into_drawing_area();
        draw_bars(root, self).with_context(|| format!("rendering {}", path.display()))
    }
}
