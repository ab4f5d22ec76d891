//! Line figures: [`Figure`], a grid of [`Panel`]s of [`Series`] (lines,
//! bands, points) with legends and [`Mark`]s, drawn to PNG or SVG.

use crate::axes::{linear_ticks, log_tick, pad, range, typeset, Bounds, Runs};
use crate::backend::{ensure_font, png_file, FAMILY};
use crate::style::{color, cycle, Dash};
use anyhow::{anyhow, Context, Result};
use plotters::coord::ranged1d::{BoldPoints, Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// One line, or (with `lower`) a shaded band.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text (empty: no legend entry).
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates (the upper edge of a band).
    pub y: Vec<f64>,
    /// Colour index into the palette.
    pub color: usize,
    /// Line style.
    pub dash: Dash,
    /// When set, the series is a band shaded between `lower` and `y` (an
    /// envelope), drawn light under every line.
    pub lower: Option<Vec<f64>>,
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
            lower: None,
        }
    }

    /// A band between `lower` and `upper`, shaded in palette colour `color`.
    pub fn band(
        label: impl Into<String>,
        x: Vec<f64>,
        lower: Vec<f64>,
        upper: Vec<f64>,
        color: usize,
    ) -> Self {
        Self {
            lower: Some(lower),
            ..Self::new(label, x, upper, color)
        }
    }

    /// The same series with another line style.
    pub fn dash(mut self, dash: Dash) -> Self {
        self.dash = dash;
        self
    }

    /// The same series in the `i`-th style of [`cycle`] (colour and dash).
    pub fn cycled(mut self, i: usize) -> Self {
        (self.color, self.dash) = cycle(i);
        self
    }
}

/// A vertical marker line with a note (e.g. "unbounded at t = 1.23 s").
#[derive(Debug, Clone)]
pub struct Mark {
    /// Where, on the x axis.
    pub x: f64,
    /// The note written beside the line.
    pub text: String,
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
    /// Fixed x range (a zoom); default: the data's.
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range; default: the data's inside the x range (padded).
    /// Lines are clipped to the plotting area either way.
    pub y_range: Option<(f64, f64)>,
    /// Vertical marker lines.
    pub marks: Vec<Mark>,
}

/// A figure: a title, a grid of panels and a footer.
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
    /// Small print across the bottom, one line per `\n` (e.g. the reading
    /// the runs were made under); empty: none.
    pub footer: String,
}

impl Default for Figure {
    fn default() -> Self {
        Self {
            title: String::new(),
            rows: 1,
            cols: 1,
            panels: Vec::new(),
            size: (1200, 600),
            footer: String::new(),
        }
    }
}

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

/// A legend swatch at `at`: the line in its dash pattern (up to five
/// pieces), a shaded box for a band, or a dot for points.
fn swatch<'b, DB: DrawingBackend + 'b>(
    c: RGBColor,
    dash: Dash,
    band: bool,
    at: (i32, i32),
) -> impl IntoDynElement<'b, DB, (i32, i32)> {
    let pieces = swatch_pieces(dash);
    let line = ShapeStyle::from(&c).stroke_width(2);
    let hidden = ShapeStyle::from(&TRANSPARENT);
    let piece = |k: usize| {
        let (a, b, st) = match pieces.get(k) {
            Some(&(a, b)) if !band => (a, b, line),
            _ => (0, 1, hidden),
        };
        PathElement::new(vec![(a, 0), (b, 0)], st)
    };
    EmptyElement::at(at)
        + piece(0)
        + piece(1)
        + piece(2)
        + piece(3)
        + piece(4)
        + Rectangle::new(
            [(0, -5), (24, 5)],
            if band { c.mix(0.3).filled() } else { hidden },
        )
        + Circle::new(
            (12, 0),
            4,
            if dash == Dash::Points && !band {
                line.filled()
            } else {
                hidden
            },
        )
}

/// The dash pattern of a legend swatch 24 px long: up to five pieces
/// (from, to) in pixels.
fn swatch_pieces(dash: Dash) -> Vec<(i32, i32)> {
    match dash {
        Dash::Solid => vec![(0, 24)],
        Dash::Dashed => vec![(0, 6), (9, 15), (18, 24)],
        Dash::DashDot => vec![(0, 8), (11, 13), (16, 24)],
        Dash::Dotted => vec![(0, 2), (5, 7), (10, 12), (15, 17), (20, 22)],
        Dash::Points => Vec::new(),
    }
}

/// Draws a panel. `segments`: draw solid lines segment by segment (the
/// bitmap backend joins a wide polyline with unbounded miters, which throw
/// spikes across the figure where a line turns back on itself).
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    segments: bool,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let runs: Vec<(usize, Runs)> = p
        .series
        .iter()
        .enumerate()
        .map(|(i, s)| (i, finite_runs(&s.x, &s.y, p.log_y)))
        .collect();
    let ((x0, x1), (y0, y1)) = data_ranges(p, &runs);
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(typeset(&p.title), font(18))
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(80);
    if p.log_y {
        let (y0, y1) = (y0.max(1e-300), y1.max(1e-300));
        let (y0, y1) = if y1 > y0 {
            (y0, y1)
        } else {
            (y0 / 10.0, y1 * 10.0)
        };
        let bounds = Bounds {
            x0,
            x1,
            y0: y0.log10(),
            y1: y1.log10(),
            log_y: true,
        };
        let chart = builder
            .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
            .map_err(|e| anyhow!("building a chart: {e}"))?;
        draw_chart(chart, p, &runs, &bounds, &log_tick, segments)?;
    } else {
        let (y0, y1) = if p.y_range.is_some() && y1 > y0 {
            (y0, y1)
        } else {
            pad(y0, y1)
        };
        let bounds = Bounds {
            x0,
            x1,
            y0,
            y1,
            log_y: false,
        };
        let chart = builder
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| anyhow!("building a chart: {e}"))?;
        let yfmt = linear_ticks(chart.as_coord_spec().y_spec().key_points(BoldPoints(8)));
        draw_chart(chart, p, &runs, &bounds, &yfmt, segments)?;
    }
    Ok(())
}

/// The text of a panel in `size` points.
fn font(size: u32) -> FontDesc<'static> {
    (FAMILY, size).into_font()
}

/// A panel's x range, given or the data's and the marks' (a point range
/// widened), and its y range, given or the data's inside the x range (not
/// yet padded); the data are the lines' finite `runs` and the bands'
/// lower edges.
fn data_ranges(p: &Panel, runs: &[(usize, Runs)]) -> ((f64, f64), (f64, f64)) {
    let lowers: Vec<(usize, Runs)> = p
        .series
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.lower.as_ref().map(|l| (i, finite_runs(&s.x, l, p.log_y))))
        .collect();
    let pts = || {
        runs.iter()
            .chain(lowers.iter())
            .flat_map(|(_, r)| r.iter().flatten())
    };
    let (x0, x1) = p
        .x_range
        .or_else(|| range(pts().map(|p| p.0).chain(p.marks.iter().map(|m| m.x))))
        .unwrap_or((0.0, 1.0));
    let (x0, x1) = if x1 > x0 { (x0, x1) } else { pad(x0, x1) };
    let in_x = |q: &&(f64, f64)| q.0 >= x0 && q.0 <= x1;
    let (y0, y1) = p
        .y_range
        .or_else(|| range(pts().filter(in_x).map(|p| p.1)))
        .unwrap_or((0.0, 1.0));
    ((x0, x1), (y0, y1))
}

/// Draws a panel on its built chart (linear or logarithmic y): the axes,
/// the bands under the lines, the lines, the marks and the legend.
fn draw_chart<'a, DB, Y>(
    mut chart: ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    p: &Panel,
    runs: &[(usize, Runs)],
    bounds: &Bounds,
    yfmt: &dyn Fn(&f64) -> String,
    segments: bool,
) -> Result<()>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let xfmt = linear_ticks(chart.as_coord_spec().x_spec().key_points(BoldPoints(10)));
    chart
        .configure_mesh()
        .x_labels(10)
        .y_labels(8)
        .x_label_formatter(&xfmt)
        .y_label_formatter(yfmt)
        .x_desc(typeset(&p.x_label))
        .y_desc(typeset(&p.y_label))
        .label_style(font(13))
        .axis_desc_style(font(14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| anyhow!("drawing axes: {e}"))?;
    let banded = draw_bands(&mut chart, p, bounds)?;
    let lined = draw_lines(&mut chart, p, runs, bounds, segments)?;
    draw_marks(&mut chart, p, bounds)?;
    if banded || lined {
        chart
            .configure_series_labels()
            .label_font(font(13))
            .legend_area_size(30)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| anyhow!("drawing the legend: {e}"))?;
    }
    Ok(())
}

/// Draws the bands, shaded and clamped to the plotting area, each piece
/// where both edges are finite inside the x range; true when one has a
/// legend entry.
fn draw_bands<'a, DB, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    p: &Panel,
    bounds: &Bounds,
) -> Result<bool>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64>,
{
    let (x0, x1) = (bounds.x0, bounds.x1);
    let mut any_label = false;
    for s in p.series.iter() {
        let Some(lower) = &s.lower else { continue };
        let clamp = |y: f64| {
            let (lo, hi) = (
                bounds.data_coords((0.0, bounds.y0)).1,
                bounds.data_coords((0.0, bounds.y1)).1,
            );
            y.clamp(lo, hi)
        };
        let c = color(s.color);
        let mut drawn = false;
        let keep = |i: &usize| {
            let (x, a, b) = (s.x[*i], lower[*i], s.y[*i]);
            x >= x0
                && x <= x1
                && a.is_finite()
                && b.is_finite()
                && (!p.log_y || (a > 0.0 && b > 0.0))
        };
        let idx: Vec<usize> = (0..s.x.len().min(lower.len()).min(s.y.len())).collect();
        for piece in idx.split(|i| !keep(i)).filter(|r| r.len() > 1) {
            let mut poly: Vec<(f64, f64)> =
                piece.iter().map(|&i| (s.x[i], clamp(s.y[i]))).collect();
            poly.extend(piece.iter().rev().map(|&i| (s.x[i], clamp(lower[i]))));
            let anno = chart
                .draw_series(std::iter::once(Polygon::new(poly, c.mix(0.25).filled())))
                .map_err(|e| anyhow!("drawing a band: {e}"))?;
            let s_dash = s.dash;
            if !drawn && !s.label.is_empty() {
                any_label = true;
                anno.label(typeset(&s.label))
                    .legend(move |at| swatch(c, s_dash, true, at));
            }
            drawn = true;
        }
    }
    Ok(any_label)
}

/// Draws the lines (and points), each clipped to the plotting area, in its
/// dash; true when one has a legend entry.
fn draw_lines<'a, DB, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    p: &Panel,
    runs: &[(usize, Runs)],
    bounds: &Bounds,
    segments: bool,
) -> Result<bool>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64>,
{
    let mut any_label = false;
    for (i, r) in runs {
        let s = &p.series[*i];
        if s.lower.is_some() {
            continue;
        }
        let c = color(s.color);
        let style = ShapeStyle::from(&c).stroke_width(2);
        let mut first = true;
        let pieces: Runs = if s.dash == Dash::Points {
            r.iter()
                .map(|run| run.iter().copied().filter(|q| bounds.inside(*q)).collect())
                .collect()
        } else {
            r.iter().flat_map(|run| bounds.clip(run)).collect()
        };
        for run in pieces.iter().filter(|r| !r.is_empty()) {
            let dashed = |a: u32, b: u32| DashedLineSeries::new(run.iter().copied(), a, b, style);
            let anno = match s.dash {
                Dash::Solid if segments => chart
                    .draw_series(
                        run.windows(2)
                            .map(|w| PathElement::new(vec![w[0], w[1]], style)),
                    )
                    .map_err(|e| anyhow!("drawing a line: {e}"))?,
                Dash::Solid => chart
                    .draw_series(LineSeries::new(run.iter().copied(), style))
                    .map_err(|e| anyhow!("drawing a line: {e}"))?,
                Dash::Dashed => chart
                    .draw_series(dashed(10, 6))
                    .map_err(|e| anyhow!("drawing a line: {e}"))?,
                Dash::Dotted => chart
                    .draw_series(dashed(2, 4))
                    .map_err(|e| anyhow!("drawing a line: {e}"))?,
                Dash::DashDot => chart
                    .draw_series(dashed(12, 4))
                    .map_err(|e| anyhow!("drawing a line: {e}"))?,
                Dash::Points => chart
                    .draw_series(
                        run.iter()
                            .map(|&(x, y)| Circle::new((x, y), 4, style.filled())),
                    )
                    .map_err(|e| anyhow!("drawing points: {e}"))?,
            };
            let s_dash = s.dash;
            if first && !s.label.is_empty() {
                any_label = true;
                anno.label(typeset(&s.label))
                    .legend(move |at| swatch(c, s_dash, false, at));
            }
            first = false;
        }
    }
    Ok(any_label)
}

/// Draws the marks inside the x range: a dashed vertical line across the
/// plotting area, its note at its foot.
fn draw_marks<'a, DB, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    p: &Panel,
    bounds: &Bounds,
) -> Result<()>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64>,
{
    let (ylo, yhi) = (
        bounds.data_coords((0.0, bounds.y0)).1,
        bounds.data_coords((0.0, bounds.y1)).1,
    );
    for m in p
        .marks
        .iter()
        .filter(|m| m.x >= bounds.x0 && m.x <= bounds.x1)
    {
        let st = ShapeStyle::from(&RGBColor(90, 90, 90)).stroke_width(1);
        chart
            .draw_series(DashedLineSeries::new([(m.x, ylo), (m.x, yhi)], 6, 4, st))
            .map_err(|e| anyhow!("drawing a mark: {e}"))?;
        chart
            .draw_series(std::iter::once(
                EmptyElement::at((m.x, ylo))
                    + Text::new(
                        typeset(&m.text),
                        (-6, -4),
                        TextStyle::from(font(13)).pos(Pos::new(HPos::Right, VPos::Bottom)),
                    ),
            ))
            .map_err(|e| anyhow!("drawing a mark: {e}"))?;
    }
    Ok(())
}

fn draw_figure<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    f: &Figure,
    segments: bool,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    ensure_font();
    root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
    let body = if f.title.is_empty() {
        root.clone()
    } else {
        root.titled(&typeset(&f.title), (FAMILY, 22).into_font())
            .map_err(|e| anyhow!("{e}"))?
    };
    let body = if f.footer.is_empty() {
        body
    } else {
        let lines: Vec<&str> = f.footer.lines().collect();
        let (_, h) = body.dim_in_pixel();
        let (main, foot) = body.split_vertically(h.saturating_sub(6 + 20 * lines.len() as u32));
        for (i, line) in lines.iter().enumerate() {
            foot.draw(&Text::new(
                typeset(line),
                (12, 4 + 20 * i as i32),
                (FAMILY, 14).into_font().color(&RGBColor(60, 60, 60)),
            ))
            .map_err(|e| anyhow!("{e}"))?;
        }
        main
    };
    let areas = body.split_evenly((f.rows.max(1), f.cols.max(1)));
    for (area, panel) in areas.iter().zip(f.panels.iter()) {
        draw_panel(area, panel, segments)?;
    }
    root.present().map_err(|e| anyhow!("{e}"))?;
    Ok(())
}

impl Figure {
    /// Renders to a PNG file.
    pub fn png(&self, path: &Path) -> Result<()> {
        png_file(path, self.size, |root| draw_figure(root, self, true))
            .with_context(|| format!("rendering {}", path.display()))
    }

    /// Renders to an SVG file.
    pub fn svg(&self, path: &Path) -> Result<()> {
        let root = SVGBackend::new(path, self.size).into_drawing_area();
        draw_figure(root, self, false).with_context(|| format!("rendering {}", path.display()))
    }
}
