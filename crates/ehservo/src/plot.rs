//! Figures: a grid of panels of line series, rendered to PNG or SVG with
//! plotters and an embedded font (DejaVu Sans), so that a fresh machine needs
//! no system fonts.
//!
//! Non-finite points are never drawn: a series is split where its values stop
//! being finite.

use anyhow::{anyhow, Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
use std::path::Path;
use std::sync::Once;

const FONT: &[u8] = include_bytes!("../../../assets/DejaVuSans.ttf");
const FAMILY: &str = "sans-serif";

fn ensure_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is part of the source tree: failure here is a build defect.
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT);
    });
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dash {
    /// Solid line (the paper's "—").
    Solid,
    /// Dashed ("---").
    Dashed,
    /// Dotted ("···").
    Dotted,
    /// Dash-dot ("-·-").
    DashDot,
    /// Markers only (circles), no line.
    Points,
}

/// One line.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text (empty: no legend entry).
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
    /// Colour index into the palette.
    pub color: usize,
    /// Line style.
    pub dash: Dash,
}

impl Series {
    /// A solid series in palette colour `color`.
    pub fn new(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, color: usize) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            color,
            dash: Dash::Solid,
        }
    }

    /// The same series with another line style.
    pub fn dash(mut self, dash: Dash) -> Self {
        self.dash = dash;
        self
    }
}

/// One panel: axes, labels and series.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// Caption above the panel.
    pub title: String,
    /// x axis label (with unit).
    pub x_label: String,
    /// y axis label (with unit).
    pub y_label: String,
    /// The lines.
    pub series: Vec<Series>,
    /// Logarithmic y axis.
    pub log_y: bool,
}

/// A figure: a title and a grid of panels.
#[derive(Debug, Clone)]
pub struct Figure {
    /// Title across the top.
    pub title: String,
    /// Grid rows.
    pub rows: usize,
    /// Grid columns.
    pub cols: usize,
    /// Panels, row-major.
    pub panels: Vec<Panel>,
    /// Size in pixels.
    pub size: (u32, u32),
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// Palette colour `i` (wraps).
pub fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// Contiguous runs of finite points.
type Runs = Vec<Vec<(f64, f64)>>;

fn finite_runs(x: &[f64], y: &[f64], log_y: bool) -> Runs {
    let mut runs = Vec::new();
    let mut cur = Vec::new();
    for (&a, &b) in x.iter().zip(y.iter()) {
        let ok = a.is_finite() && b.is_finite() && (!log_y || b > 0.0);
        if ok {
            cur.push((a, b));
        } else if !cur.is_empty() {
            runs.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        runs.push(cur);
    }
    runs
}

fn range(vals: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in vals {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo.is_finite() && hi.is_finite() {
        Some((lo, hi))
    } else {
        None
    }
}

fn pad(lo: f64, hi: f64) -> (f64, f64) {
    if hi > lo {
        let m = 0.05 * (hi - lo);
        (lo - m, hi + m)
    } else {
        let m = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - m, hi + m)
    }
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let runs: Vec<(usize, Runs)> = p
        .series
        .iter()
        .enumerate()
        .map(|(i, s)| (i, finite_runs(&s.x, &s.y, p.log_y)))
        .collect();
    let pts = || runs.iter().flat_map(|(_, r)| r.iter().flatten());
    let (x0, x1) = range(pts().map(|p| p.0)).unwrap_or((0.0, 1.0));
    let (y0, y1) = range(pts().map(|p| p.1)).unwrap_or((0.0, 1.0));
    let (x0, x1) = if x1 > x0 { (x0, x1) } else { pad(x0, x1) };
    let font = |s: u32| (FAMILY, s).into_font();
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(&p.title, font(18))
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(70);
    macro_rules! finish {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(&p.x_label)
                .y_desc(&p.y_label)
                .label_style(font(13))
                .axis_desc_style(font(14))
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(|e| anyhow!("drawing axes: {e}"))?;
            let mut any_label = false;
            for (i, r) in &runs {
                let s = &p.series[*i];
                let c = color(s.color);
                let style =
                    ShapeStyle::from(&c).stroke_width(if s.dash == Dash::Solid { 2 } else { 2 });
                let mut first = true;
                for run in r {
                    let anno = match s.dash {
                        Dash::Solid => chart
                            .draw_series(LineSeries::new(run.iter().copied(), style))
                            .map_err(|e| anyhow!("drawing a line: {e}"))?,
                        Dash::Dashed => chart
                            .draw_series(DashedLineSeries::new(run.iter().copied(), 10, 6, style))
                            .map_err(|e| anyhow!("drawing a line: {e}"))?,
                        Dash::Dotted => chart
                            .draw_series(DashedLineSeries::new(run.iter().copied(), 2, 4, style))
                            .map_err(|e| anyhow!("drawing a line: {e}"))?,
                        Dash::DashDot => chart
                            .draw_series(DashedLineSeries::new(run.iter().copied(), 12, 4, style))
                            .map_err(|e| anyhow!("drawing a line: {e}"))?,
                        Dash::Points => chart
                            .draw_series(
                                run.iter()
                                    .map(|&(x, y)| Circle::new((x, y), 4, style.filled())),
                            )
                            .map_err(|e| anyhow!("drawing points: {e}"))?,
                    };
                    if first && !s.label.is_empty() {
                        any_label = true;
                        anno.label(s.label.clone()).legend(move |(x, y)| {
                            PathElement::new(
                                vec![(x, y), (x + 20, y)],
                                ShapeStyle::from(&c).stroke_width(2),
                            )
                        });
                    }
                    first = false;
                }
            }
            if any_label {
                chart
                    .configure_series_labels()
                    .label_font(font(13))
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .position(SeriesLabelPosition::UpperRight)
                    .draw()
                    .map_err(|e| anyhow!("drawing the legend: {e}"))?;
            }
        }};
    }
    if p.log_y {
        let (y0, y1) = (y0.max(1e-300), y1.max(1e-300));
        let (y0, y1) = if y1 > y0 {
            (y0, y1)
        } else {
            (y0 / 10.0, y1 * 10.0)
        };
        finish!(builder
            .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
            .map_err(|e| anyhow!("building a chart: {e}"))?);
    } else {
        let (y0, y1) = pad(y0, y1);
        finish!(builder
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| anyhow!("building a chart: {e}"))?);
    }
    Ok(())
}

fn draw_figure<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, f: &Figure) -> Result<()>
where
    DB::ErrorType: 'static,
{
    ensure_font();
    root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
    let body = if f.title.is_empty() {
        root.clone()
    } else {
        root.titled(&f.title, (FAMILY, 22).into_font())
            .map_err(|e| anyhow!("{e}"))?
    };
    let areas = body.split_evenly((f.rows.max(1), f.cols.max(1)));
    for (area, panel) in areas.iter().zip(f.panels.iter()) {
        draw_panel(area, panel)?;
    }
    root.present().map_err(|e| anyhow!("{e}"))?;
    Ok(())
}

impl Figure {
    /// Renders to a PNG file.
    pub fn png(&self, path: &Path) -> Result<()> {
        let root = BitMapBackend::new(path, self.size).into_drawing_area();
        draw_figure(root, self).with_context(|| format!("rendering {}", path.display()))
    }

    /// Renders to an SVG file.
    pub fn svg(&self, path: &Path) -> Result<()> {
        let root = SVGBackend::new(path, self.size).into_drawing_area();
        draw_figure(root, self).with_context(|| format!("rendering {}", path.display()))
    }
}

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
    /// z[iy][ix].
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
        let root = BitMapBackend::new(path, self.size).into_drawing_area();
        draw_heatmap(root, self).with_context(|| format!("rendering {}", path.display()))
    }

    /// Renders to an SVG file.
    pub fn svg(&self, path: &Path) -> Result<()> {
        let root = SVGBackend::new(path, self.size).into_drawing_area();
        draw_heatmap(root, self).with_context(|| format!("rendering {}", path.display()))
    }
}

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
        let root = BitMapBackend::new(path, self.size).into_drawing_area();
        draw_histogram(root, self).with_context(|| format!("rendering {}", path.display()))
    }

    /// Renders to an SVG file.
    pub fn svg(&self, path: &Path) -> Result<()> {
        let root = SVGBackend::new(path, self.size).into_drawing_area();
        draw_histogram(root, self).with_context(|| format!("rendering {}", path.display()))
    }
}
