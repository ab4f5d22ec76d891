//! Figures: a grid of panels of line series, rendered to PNG or SVG with
//! plotters and an embedded font (DejaVu Sans), so that a fresh machine needs
//! no system fonts.
//!
//! Non-finite points are never drawn: a series is split where its values stop
//! being finite.

use anyhow::{anyhow, Context, Result};
use plotters::coord::ranged1d::{BoldPoints, Ranged};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
#[cfg(not(target_arch = "wasm32"))]
use plotters::style::FontStyle;
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingErrorKind,
};
use std::path::Path;
use std::sync::Once;

#[cfg(not(target_arch = "wasm32"))]
const FONT: &[u8] = include_bytes!("../../../assets/DejaVuSans.ttf");
/// The embedded font's family name (also for `freq::report`'s figures).
pub(crate) const FAMILY: &str = "sans-serif";

/// Registers the embedded font once.
pub(crate) fn ensure_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is part of the source tree: failure here is a build defect.
        // (plotters registers fonts only off wasm32, where nothing is drawn.)
        #[cfg(not(target_arch = "wasm32"))]
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT);
    });
}

/// A pixel backend whose opaque 2-pixel lines are drawn as three 1-pixel
/// lines a pixel apart across the line's major axis, where plotters'
/// default fills a polygon per path (±1 pixel about the line, so also
/// three pixels across, with ragged joins between segments). It is
/// the same weight of line, drawn cleanly and much more cheaply. The polygon fill had been
/// 45 M of the 153 M instructions of a whole `ehservo run` of Fig. 2
/// (callgrind). Every other drawing call, and lines of other widths or
/// with transparency, go to the wrapped backend unchanged.
pub struct Stroked<B>(B);

impl<B: DrawingBackend> DrawingBackend for Stroked<B> {
    type ErrorType = B::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.0.get_size()
    }
    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.ensure_prepared()
    }
    fn present(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.present()
    }
    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_pixel(point, color)
    }
    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_line(from, to, style)
    }
    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_rect(upper_left, bottom_right, style, fill)
    }
    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        if style.stroke_width() != 2 || style.color().alpha < 1.0 {
            return self.0.draw_path(path, style);
        }
        let thin = ShapeStyle {
            color: RGBAColor(
                style.color().rgb.0,
                style.color().rgb.1,
                style.color().rgb.2,
                1.0,
            ),
            filled: false,
            stroke_width: 1,
        };
        let mut from: Option<BackendCoord> = None;
        for to in path {
            if let Some(a) = from {
                // Across the major axis: shallow lines vertically, steep
                // ones horizontally.
                let (dx, dy) = if (to.0 - a.0).abs() >= (to.1 - a.1).abs() {
                    (0, 1)
                } else {
                    (1, 0)
                };
                for k in -1..=1 {
                    let (ox, oy) = (k * dx, k * dy);
                    self.0
                        .draw_line((a.0 + ox, a.1 + oy), (to.0 + ox, to.1 + oy), &thin)?;
                }
            }
            from = Some(to);
        }
        Ok(())
    }
    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_circle(center, radius, style, fill)
    }
    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.fill_polygon(vert, style)
    }
    fn draw_text<TStyle: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &TStyle,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_text(text, style, pos)
    }
    fn estimate_text_size<TStyle: BackendTextStyle>(
        &self,
        text: &str,
        style: &TStyle,
    ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        self.0.estimate_text_size(text, style)
    }
    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.blit_bitmap(pos, size, src)
    }
}

/// Draws into an RGB buffer and writes it to `path` as a PNG.
///
/// One fixed filter (Paeth) rather than plotters' default encoding (the
/// `image` crate's adaptive choice among the five filters, row by row):
/// the same pixels, a file of about the same size (575 kB against 557 kB
/// for Fig. 2's 1400×1500 trace.png), and 17 % fewer instructions for the
/// whole `ehservo run` (154 M against 185 M, callgrind).
#[cfg(not(target_arch = "wasm32"))]
pub(crate) fn png_file<F>(path: &Path, size: (u32, u32), draw: F) -> Result<()>
where
    F: FnOnce(DrawingArea<Stroked<BitMapBackend<'_>>, Shift>) -> Result<()>,
{
    let (w, h) = size;
    let mut buf = vec![0u8; w as usize * h as usize * 3];
    draw(Stroked(BitMapBackend::with_buffer(&mut buf, size)).into_drawing_area())?;
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let encode = || {
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        enc.set_filter(png::FilterType::Paeth);
        let mut out = enc.write_header()?;
        out.write_image_data(&buf)?;
        out.finish()
    };
    encode().with_context(|| format!("writing {}", path.display()))
}

/// PNG files are not written on wasm32 (the browser playground,
/// crates/ehservo-web, draws with uPlot instead).
#[cfg(target_arch = "wasm32")]
pub(crate) fn png_file<F>(path: &Path, _size: (u32, u32), _draw: F) -> Result<()>
where
    F: FnOnce(DrawingArea<Stroked<BitMapBackend<'_>>, Shift>) -> Result<()>,
{
    Err(anyhow!(
        "{}: PNG files are not written on wasm32",
        path.display()
    ))
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

/// Ten colours distinct on screen and in print (Tableau 10, its grey
/// replaced by black).
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(0, 0, 0),
];

/// Line styles [`cycle`] goes through, one per round of the palette.
const DASHES: [Dash; 4] = [Dash::Solid, Dash::Dashed, Dash::DashDot, Dash::Dotted];

/// Palette colour `i` (wraps).
pub fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// The `i`-th of 40 distinguishable styles, (palette colour, dash): the ten
/// colours solid, then the ten dashed, dash-dotted and dotted.
pub fn cycle(i: usize) -> (usize, Dash) {
    let n = PALETTE.len();
    (i % n, DASHES[(i / n) % DASHES.len()])
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

/// The plotting area in data coordinates; y in log10 when `log_y`.
#[derive(Debug, Clone, Copy)]
struct Bounds {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    log_y: bool,
}

impl Bounds {
    fn plot_coords(&self, p: (f64, f64)) -> (f64, f64) {
        (p.0, if self.log_y { p.1.log10() } else { p.1 })
    }

    fn data_coords(&self, p: (f64, f64)) -> (f64, f64) {
        (p.0, if self.log_y { 10f64.powf(p.1) } else { p.1 })
    }

    fn inside(&self, p: (f64, f64)) -> bool {
        let q = self.plot_coords(p);
        q.0 >= self.x0 && q.0 <= self.x1 && q.1 >= self.y0 && q.1 <= self.y1
    }

    /// Liang–Barsky: the part of the segment a→b inside the box, as
    /// parameters 0 ≤ t0 ≤ t1 ≤ 1 (None: wholly outside).
    fn clip_segment(&self, a: (f64, f64), b: (f64, f64)) -> Option<(f64, f64)> {
        let (d0, d1) = (b.0 - a.0, b.1 - a.1);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (p, q) in [
            (-d0, a.0 - self.x0),
            (d0, self.x1 - a.0),
            (-d1, a.1 - self.y0),
            (d1, self.y1 - a.1),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return None;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }

    /// The visible pieces of a polyline: a piece ends where the line leaves
    /// the box and a new one starts where it comes back.
    fn clip(&self, run: &[(f64, f64)]) -> Runs {
        let mut out: Runs = Vec::new();
        if run.len() == 1 {
            if self.inside(run[0]) {
                out.push(run.to_vec());
            }
            return out;
        }
        let mut cur: Vec<(f64, f64)> = Vec::new();
        for w in run.windows(2) {
            let (a, b) = (self.plot_coords(w[0]), self.plot_coords(w[1]));
            let lerp = |t: f64| (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
            match self.clip_segment(a, b) {
                Some((t0, t1)) => {
                    if cur.is_empty() || t0 > 0.0 {
                        if !cur.is_empty() {
                            out.push(std::mem::take(&mut cur));
                        }
                        cur.push(self.data_coords(lerp(t0)));
                    }
                    cur.push(self.data_coords(lerp(t1)));
                    if t1 < 1.0 {
                        out.push(std::mem::take(&mut cur));
                    }
                }
                None => {
                    if !cur.is_empty() {
                        out.push(std::mem::take(&mut cur));
                    }
                }
            }
        }
        if !cur.is_empty() {
            out.push(cur);
        }
        out
    }
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

/// Text as drawn: plotters places no combining marks, so "b̄" (b and a
/// combining macron) is spelt out; Markdown code quotes are dropped.
fn typeset(s: &str) -> String {
    s.replace("b\u{304}", "nominal b").replace('`', "")
}

/// Decimals enough to tell the ticks `at` apart (and no more).
fn tick_decimals(at: &[f64]) -> usize {
    (0..=9)
        .find(|&d| {
            let s = 10f64.powi(d as i32);
            at.iter()
                .all(|v| (v * s - (v * s).round()).abs() < 1e-6 * s.max(1.0))
        })
        .unwrap_or(9)
}

/// A tick label: `decimals` after the point, scientific notation for very
/// large or very small steps, and never "−0".
fn tick_label(v: f64, decimals: usize, sci: bool) -> String {
    let s = if sci && v == 0.0 {
        "0".to_string()
    } else if sci {
        format!("{v:.1e}")
    } else {
        format!("{v:.decimals$}")
    };
    match s.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| matches!(c, '0' | '.' | 'e')) => rest.to_string(),
        _ => s,
    }
}

/// A tick formatter for the linear axis whose ticks are `at`.
fn linear_ticks(at: Vec<f64>) -> impl Fn(&f64) -> String {
    let big = at.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let d = tick_decimals(&at);
    let sci = big >= 1e5 || d > 5;
    // A tick computed as 0 ± rounding prints as 0.
    move |v| {
        let v = if v.abs() <= 1e-9 * big { 0.0 } else { *v };
        tick_label(v, d, sci)
    }
}

/// A tick formatter for a logarithmic axis.
fn log_tick(v: &f64) -> String {
    let e = v.log10();
    if (e - e.round()).abs() < 1e-9 && !(-3.0..=4.0).contains(&e.round()) {
        format!("1e{}", e.round() as i32)
    } else if *v >= 1e-3 && *v < 1e5 {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.1e}")
    }
}

/// The dash pattern of a legend swatch 24 px long: up to five pieces
/// (from, to) in pixels.
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
    let font = |s: u32| (FAMILY, s).into_font();
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(typeset(&p.title), font(18))
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(80);
    macro_rules! finish {
        ($chart:expr, $bounds:expr, $yfmt:expr) => {{
            let mut chart = $chart;
            let bounds: Bounds = $bounds;
            let xfmt = linear_ticks(chart.as_coord_spec().x_spec().key_points(BoldPoints(10)));
            chart
                .configure_mesh()
                .x_labels(10)
                .y_labels(8)
                .x_label_formatter(&xfmt)
                .y_label_formatter(&$yfmt)
                .x_desc(typeset(&p.x_label))
                .y_desc(typeset(&p.y_label))
                .label_style(font(13))
                .axis_desc_style(font(14))
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(|e| anyhow!("drawing axes: {e}"))?;
            let mut any_label = false;
            // Bands first, under the lines; clamped to the area.
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
            for (i, r) in &runs {
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
                    let dashed =
                        |a: u32, b: u32| DashedLineSeries::new(run.iter().copied(), a, b, style);
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
            let (ylo, yhi) = (
                bounds.data_coords((0.0, bounds.y0)).1,
                bounds.data_coords((0.0, bounds.y1)).1,
            );
            for m in p.marks.iter().filter(|m| m.x >= x0 && m.x <= x1) {
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
            if any_label {
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
        }};
    }
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
        finish!(
            builder
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(|e| anyhow!("building a chart: {e}"))?,
            bounds,
            log_tick
        );
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
        finish!(chart, bounds, yfmt);
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
        png_file(path, self.size, |root| draw_heatmap(root, self))
            .with_context(|| format!("rendering {}", path.display()))
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
        png_file(path, self.size, |root| draw_histogram(root, self))
            .with_context(|| format!("rendering {}", path.display()))
    }

    /// Renders to an SVG file.
    pub fn svg(&self, path: &Path) -> Result<()> {
        let root = SVGBackend::new(path, self.size).into_drawing_area();
        draw_histogram(root, self).with_context(|| format!("rendering {}", path.display()))
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;

    /// The pixels a path leaves set in a 32×32 black buffer drawn through
    /// `Stroked` (or plain plotters), as (x, y), row by row.
    #[cfg(not(target_arch = "wasm32"))]
    fn stroke(path: &[(i32, i32)], style: ShapeStyle, stroked: bool) -> Vec<(i32, i32)> {
        let mut buf = vec![0u8; 32 * 32 * 3];
        {
            let b = BitMapBackend::with_buffer(&mut buf, (32, 32));
            if stroked {
                Stroked(b).draw_path(path.iter().copied(), &style).unwrap();
            } else {
                let mut b = b;
                b.draw_path(path.iter().copied(), &style).unwrap();
            }
        }
        (0..32 * 32)
            .filter(|i| buf[3 * i..3 * i + 3] != [0, 0, 0])
            .map(|i| ((i % 32) as i32, (i / 32) as i32))
            .collect()
    }

    /// A 2-pixel line through `Stroked` is three pixels across its major
    /// axis, as plotters' ±1 pixel polygon is: exactly so when it is
    /// horizontal or vertical; a slanted one is three of plotters'
    /// anti-aliased 1-pixel lines (two pixels a step, blended), so three
    /// or four pixels a step, none farther than 2 from the line. Other
    /// widths and translucent lines are plotters' own.
    #[cfg(not(target_arch = "wasm32"))]
    #[test]
    fn stroked_lines_are_three_pixels_across() {
        let red = ShapeStyle::from(&RED).stroke_width(2);
        // Horizontal, x 2..=12 at y = 5: rows 4, 5 and 6.
        let want: Vec<(i32, i32)> = (4..=6)
            .flat_map(|y| (2..=12).map(move |x| (x, y)))
            .collect();
        assert_eq!(stroke(&[(2, 5), (12, 5)], red, true), want);
        // Vertical, y 3..=15 at x = 9: columns 8, 9 and 10.
        let want: Vec<(i32, i32)> = (3..=15)
            .flat_map(|y| (8..=10).map(move |x| (x, y)))
            .collect();
        assert_eq!(stroke(&[(9, 3), (9, 15)], red, true), want);
        // A bent path, shallow from (1, 2) to (13, 6), then steep to (15, 18).
        let got = stroke(&[(1, 2), (13, 6), (15, 18)], red, true);
        let near_shallow = |x: i32, y: i32| {
            (1..=14).contains(&x) && (f64::from(y) - (2.0 + f64::from(x - 1) / 3.0)).abs() <= 2.0
        };
        let near_steep = |x: i32, y: i32| {
            (5..=19).contains(&y) && (f64::from(x) - (13.0 + f64::from(y - 6) / 6.0)).abs() <= 2.0
        };
        assert!(
            got.iter()
                .all(|&(x, y)| near_shallow(x, y) || near_steep(x, y)),
            "{got:?}"
        );
        for x in 2..=10 {
            let n = got.iter().filter(|p| p.0 == x).count();
            assert!((3..=4).contains(&n), "column {x}: {n} pixels in {got:?}");
        }
        for y in 9..=17 {
            let n = got.iter().filter(|p| p.1 == y).count();
            assert!((3..=4).contains(&n), "row {y}: {n} pixels in {got:?}");
        }
        // Width 3 and a translucent 2-pixel line: plotters' own pixels.
        let path = [(1, 2), (13, 6), (15, 18)];
        for style in [
            ShapeStyle::from(&RED).stroke_width(3),
            ShapeStyle::from(&RED.mix(0.5)).stroke_width(2),
        ] {
            assert_eq!(stroke(&path, style, true), stroke(&path, style, false));
        }
    }

    #[test]
    fn ticks_never_read_negative_zero() {
        // Ticks −0.1, −0.05, 0, 0.05: two decimals; 0 computed as −1e-17.
        let f = linear_ticks(vec![-0.1, -0.05, -1e-17, 0.05]);
        assert_eq!(f(&-1e-17), "0.00");
        assert_eq!(f(&-0.05), "-0.05");
        let f = linear_ticks(vec![-2.0, 0.0, 2.0]);
        assert_eq!(f(&-0.0), "0");
        assert_eq!(f(&2.0), "2");
        // Ticks 0, 0.25, 0.5: two decimals, not one ("0.3").
        assert_eq!(linear_ticks(vec![0.0, 0.25, 0.5])(&0.25), "0.25");
        // Scientific notation for large ticks, but a plain 0.
        let f = linear_ticks(vec![-2e5, -1e-11, 2e5]);
        assert_eq!(f(&-1e-11), "0");
        assert_eq!(f(&2e5), "2.0e5");
    }

    #[test]
    fn lines_are_clipped_to_the_box() {
        let b = Bounds {
            x0: 0.0,
            x1: 10.0,
            y0: -1.0,
            y1: 1.0,
            log_y: false,
        };
        // Up through y = 1 at x = 1, out to y = 3, back in at x = 3.
        let runs = b.clip(&[(0.0, 0.0), (2.0, 2.0), (4.0, 0.0)]);
        assert_eq!(runs.len(), 2);
        assert_eq!(runs[0], vec![(0.0, 0.0), (1.0, 1.0)]);
        assert_eq!(runs[1], vec![(3.0, 1.0), (4.0, 0.0)]);
        assert!(b.clip(&[(0.0, 5.0), (10.0, 5.0)]).is_empty());
    }

    #[test]
    fn forty_distinct_styles() {
        let styles: Vec<(usize, Dash)> = (0..40).map(cycle).collect();
        for (i, a) in styles.iter().enumerate() {
            assert!(styles[..i].iter().all(|b| b != a), "style {i} repeats");
        }
        assert_eq!(cycle(0), (0, Dash::Solid));
        assert_eq!(cycle(10), (0, Dash::Dashed));
    }
}
