//! Histograms: [`Histogram`], a column of [`HistPanel`]s, each counts in
//! equal bins with a shaded band and vertical marks.

use crate::axes::{pad, range};
use crate::backend::{ensure_font, png_file, FAMILY};
use crate::style::color;
use anyhow::{anyhow, Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// One histogram panel: counts of `values` in equal bins, a shaded band
/// (e.g. a claim's tolerance) and vertical marks (e.g. the paper's value).
#[derive(Debug, Clone, Default)]
pub struct HistPanel {
    /// Caption above the panel.
    pub title: String,
    /// x axis label (with unit).
    pub x_label: String,
    /// The sample (non-finite values are left out).
    pub values: Vec<f64>,
    /// Number of bins.
    pub bins: usize,
    /// Shaded interval [lo, hi] with its legend text (infinite ends are
    /// clipped to the axis).
    pub band: Option<(f64, f64, String)>,
    /// Vertical lines: legend text, x, palette colour.
    pub marks: Vec<(String, f64, usize)>,
}

/// A grid of histogram panels (one column).
#[derive(Debug, Clone)]
pub struct Histogram {
    /// Title across the top.
    pub title: String,
    /// Panels, top to bottom.
    pub panels: Vec<HistPanel>,
    /// Size in pixels.
    pub size: (u32, u32),
}

fn draw_hist_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &HistPanel) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let v: Vec<f64> = p.values.iter().copied().filter(|x| x.is_finite()).collect();
    let finite_marks = p.marks.iter().map(|m| m.1).filter(|x| x.is_finite());
    let band_ends = p
        .band
        .iter()
        .flat_map(|b| [b.0, b.1])
        .filter(|x| x.is_finite());
    let (lo, hi) =
        range(v.iter().copied().chain(finite_marks).chain(band_ends)).unwrap_or((0.0, 1.0));
    let (x0, x1) = pad(lo, hi);
    let bins = p.bins.max(1);
    let (v0, v1) = range(v.iter().copied()).unwrap_or((lo, hi));
    let width = if v1 > v0 {
        (v1 - v0) / bins as f64
    } else {
        1.0
    };
    let mut counts = vec![0usize; bins];
    for x in &v {
        let k = (((x - v0) / width).floor() as usize).min(bins - 1);
        counts[k] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(1).max(1) as f64 * 1.15;
    let font = |s: u32| (FAMILY, s).into_font();
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, font(18))
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, 0.0..top)
        .map_err(|e| anyhow!("building a chart: {e}"))?;
    chart
        .configure_mesh()
        .x_desc(&p.x_label)
        .y_desc("seeds")
        .label_style(font(13))
        .axis_desc_style(font(14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| anyhow!("drawing axes: {e}"))?;
    if let Some((a, b, label)) = &p.band {
        let (a, b) = (a.max(x0), b.min(x1));
        if b > a {
            let c = color(2);
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(a, 0.0), (b, top)],
                    c.mix(0.18).filled(),
                )))
                .map_err(|e| anyhow!("drawing the band: {e}"))?
                .label(label.clone())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 20, y + 5)], c.mix(0.3).filled())
                });
        }
    }
    let bar = color(0);
    chart
        .draw_series(
            counts
                .iter()
                .enumerate()
                .filter(|(_, &n)| n > 0)
                .map(|(k, &n)| {
                    let a = v0 + k as f64 * width;
                    Rectangle::new([(a, 0.0), (a + width, n as f64)], bar.mix(0.75).filled())
                }),
        )
        .map_err(|e| anyhow!("drawing the bars: {e}"))?;
    for (label, x, ci) in &p.marks {
        if !x.is_finite() {
            continue;
        }
        let c = color(*ci);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(*x, 0.0), (*x, top)],
                8,
                5,
                ShapeStyle::from(&c).stroke_width(2),
            ))
            .map_err(|e| anyhow!("drawing a mark: {e}"))?
            .label(label.clone())
            .legend(move |(x, y)| {
                PathElement::new(
                    vec![(x, y), (x + 20, y)],
                    ShapeStyle::from(&c).stroke_width(2),
                )
            });
    }
    chart
        .configure_series_labels()
        .label_font(font(13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| anyhow!("drawing the legend: {e}"))?;
    Ok(())
}

fn draw_histogram<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, h: &Histogram) -> Result<()>
where
    DB::ErrorType: 'static,
{
    ensure_font();
    root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
    let body = root
        .titled(&h.title, (FAMILY, 22).into_font())
        .map_err(|e| anyhow!("{e}"))?;
    let areas = body.split_evenly((h.panels.len().max(1), 1));
    for (area, panel) in areas.iter().zip(h.panels.iter()) {
        draw_hist_panel(area, panel)?;
    }
    root.present().map_err(|e| anyhow!("{e}"))?;
    Ok(())
}

impl Histogram {
    /// Renders to a PNG file.
    pub fn png(&self, path: &Path) -> Result<()> {
        png_file(path, self.size, |root| draw_histogram(root, self))
            .with_context(|| format!("rendering {}", path.display()))
    }

    /// Renders to an SVG file.
    pub fn svg(&self, path: &Path) -> Result<()> {
        let root = SVGBackend::new(path, self.size).into_drawing_area();
        draw_histogram(root, self).with_context(|| format!("rendering {}", path.display()))
    }
}
