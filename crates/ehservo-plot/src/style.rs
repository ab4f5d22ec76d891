//! Colours and line styles: the palette, the dashes and [`cycle`], the 40
//! distinguishable (colour, dash) pairs every figure kind draws with.

use plotters::style::RGBColor;

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

#[cfg(test)]
mod tests {
    use super::*;

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
