//! The back end: the embedded font, [`Stroked`] (a pixel backend that draws
//! 2-pixel lines as three 1-pixel ones) and [`png_file`], which draws into an
//! RGB buffer and writes it as a PNG. SVG files are plotters' own backend.

#[cfg(target_arch = "wasm32")]
use anyhow::anyhow;
#[cfg(not(target_arch = "wasm32"))]
use anyhow::Context;
use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
#[cfg(not(target_arch = "wasm32"))]
use plotters::style::FontStyle;
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingErrorKind,
};
use std::path::Path;
use std::sync::Once;

#[cfg(not(target_arch = "wasm32"))]
const FONT: &[u8] = include_bytes!("../../../assets/DejaVuSans.ttf");
/// The embedded font's family name (also for ehservo's `freq::report` figures).
pub const FAMILY: &str = "sans-serif";

/// Registers the embedded font once.
pub fn ensure_font() {
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
pub fn png_file<F>(path: &Path, size: (u32, u32), draw: F) -> Result<()>
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
pub fn png_file<F>(path: &Path, _size: (u32, u32), _draw: F) -> Result<()>
where
    F: FnOnce(DrawingArea<Stroked<BitMapBackend<'_>>, Shift>) -> Result<()>,
{
    Err(anyhow!(
        "{}: PNG files are not written on wasm32",
        path.display()
    ))
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
}
