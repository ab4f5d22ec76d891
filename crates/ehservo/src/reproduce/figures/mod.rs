//! The paper's figures, rebuilt from the runs of the chosen reading: the
//! same panels, signals, units (degrees where the paper uses them) and line
//! styles as the paper's captions describe.
//!
//! Every figure states, in its footer, the reading its runs were made under
//! and the size of the b variation of its cases, both taken from the loaded
//! scenarios (never from the paper's captions). Long oscillating signals
//! (the 60 s weights of Figs. 6–7) are drawn as an envelope per reference
//! period (min–max shaded, mean as a line) beside a zoom on the last
//! periods; a diverging run is clipped to its bounded part and marked.
//!
//! The rooms: `traces` (decimation, envelopes and the panels every figure
//! shares), `paper` (one function per figure of the paper, Figs. 2–8) and
//! `boundary` (the breaking-point and margin figures of the boundary
//! searches).

use crate::output::{a_variation, b_convention, b_size};
use crate::plot::Figure;
use crate::scenario::Loop;
use ehservo_sim::plant::UncertaintySpec;
use std::collections::BTreeMap;

use super::manifest::Reading;

mod boundary;
mod paper;
mod traces;

pub use boundary::boundary_figure;
pub use paper::paper_figures;

/// What the figures' runs were made under.
pub struct FigureContext<'a> {
    /// The reading (manifest entry).
    pub reading: &'a Reading,
    /// The scenario of every case, under that reading.
    pub scenarios: BTreeMap<String, &'a Loop>,
}

impl FigureContext<'_> {
    /// The footer of a figure made from `cases`: the reading, then the b
    /// variation (per case where the cases differ) and its convention.
    fn footer(&self, cases: &[&str]) -> String {
        let found: Vec<(&str, &Loop)> = cases
            .iter()
            .filter_map(|c| self.scenarios.get(*c).map(|s| (*c, *s)))
            .collect();
        // The converged level each case was run at.
        let level = per_case(&found, |s| {
            let sim = &s.scenario().simulation;
            match sim.mode {
                ehservo_sim::simulation::Mode::Sampled => format!(
                    "sampled every {} s, {} RK4 sub-step{}",
                    sim.step,
                    sim.substeps,
                    if sim.substeps == 1 { "" } else { "s" }
                ),
                ehservo_sim::simulation::Mode::Continuous => {
                    format!("continuous, RK4 step {:e} s", sim.step)
                }
            }
        });
        let b = per_case(&found, |s| b_size(&s.stages().uncertainty));
        let mut conventions: Vec<String> = Vec::new();
        for (_, s) in &found {
            let conv = b_convention(&s.stages().uncertainty);
            if !conventions.contains(&conv) {
                conventions.push(conv);
            }
        }
        format!(
            "Reading {}: {}\nConverged level: {level}\nTrue b variation: {b} ({})",
            self.reading.id,
            self.reading.label,
            conventions.join("; ")
        )
    }

    fn uncertainty(&self, case: &str) -> Option<UncertaintySpec> {
        self.scenarios.get(case).map(|s| s.stages().uncertainty)
    }

    /// The size of a case's b variation, as captions state it (empty if
    /// the case is unknown).
    fn b_of(&self, case: &str) -> String {
        self.uncertainty(case)
            .as_ref()
            .map(b_size)
            .unwrap_or_default()
    }

    /// A case's aᵢ variation, as captions state it (empty if the case is
    /// unknown).
    fn a_of(&self, case: &str) -> String {
        self.uncertainty(case)
            .as_ref()
            .map(a_variation)
            .unwrap_or_default()
    }

    /// One reference period (s) of a case (1 s if unknown).
    fn period(&self, case: &str) -> f64 {
        self.scenarios
            .get(case)
            .map(|s| s.scenario().reference.base_frequency_hz(s.horizon()))
            .filter(|f| *f > 0.0)
            .map_or(1.0, |f| 1.0 / f)
    }
}

/// `text` of every case: the one text when all cases share it, else
/// "a, b: text; c: other text".
fn per_case(cases: &[(&str, &Loop)], text: impl Fn(&Loop) -> String) -> String {
    let mut groups: Vec<(String, Vec<&str>)> = Vec::new();
    for (c, s) in cases {
        let t = text(s);
        match groups.iter_mut().find(|(g, _)| *g == t) {
            Some((_, cs)) => cs.push(c),
            None => groups.push((t, vec![c])),
        }
    }
    match groups.as_slice() {
        [] => String::new(),
        [(t, _)] => t.clone(),
        _ => groups
            .iter()
            .map(|(t, cs)| format!("{}: {t}", cs.join(", ")))
            .collect::<Vec<_>>()
            .join("; "),
    }
}

/// A figure with its file stem and caption.
pub struct PaperFigure {
    /// File stem (`fig2` → fig2.png, fig2.svg).
    pub stem: String,
    /// Caption for the report.
    pub caption: String,
    /// The figure.
    pub figure: Figure,
}
