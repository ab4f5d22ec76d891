//! Figures: a grid of panels of line series, rendered to PNG or SVG with
//! plotters and an embedded font (DejaVu Sans), so that a fresh machine needs
//! no system fonts.
//!
//! Non-finite points are never drawn: a series is split where its values stop
//! being finite.
//!
//! The rooms: the back end (the font, [`png_file`], [`Stroked`]); axes and
//! ticks (ranges, clipping, tick labels); colours and line styles
//! ([`color`], [`cycle`], [`Dash`]); line figures ([`Figure`] of [`Panel`]s
//! of [`Series`]); and the other kinds of figure, [`HeatMap`],
//! [`Histogram`] and [`Bars`]. ehservo re-exports this crate as
//! `ehservo::plot`.

mod axes;
mod backend;
mod bars;
mod heatmap;
mod histogram;
mod lines;
mod style;

pub use backend::{ensure_font, png_file, Stroked, FAMILY};
pub use bars::Bars;
pub use heatmap::HeatMap;
pub use histogram::{HistPanel, Histogram};
pub use lines::{Figure, Mark, Panel, Series};
pub use style::{color, cycle, Dash};
