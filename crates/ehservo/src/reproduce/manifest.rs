//! `scenarios/paper/manifest.toml`: readings, cases and claims as data.

use anyhow::{Context, Result};
use serde::Deserialize;
use std::collections::HashSet;
use std::path::Path;

/// One reading of the paper's simulation set-up: overrides applied to every case.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reading {
    /// Short id.
    pub id: String,
    /// Human label.
    pub label: String,
    /// `key.path=value` overrides: the model of the simulation.
    pub set: Vec<String>,
    /// The discretisation parameter and its ladder (see `convergence`).
    pub refine: Refine,
}

/// `[reading.refine]`: the discretisation parameter of a reading and the
/// values it is refined through, the paper's printed set-up first.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Refine {
    /// The scenario key (`simulation.substeps` or `simulation.step`).
    pub key: String,
    /// Its values, coarsest first.
    pub levels: Vec<f64>,
}

/// One case: a scenario file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// Short id.
    pub id: String,
    /// Loop file, relative to the manifest.
    pub file: String,
}

/// How a claim is scored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClaimKind {
    /// |m − value| ≤ tol·|value|.
    Approx,
    /// The run stays bounded.
    Bounded,
    /// The run diverges.
    Unbounded,
    /// m(case) < m(other).
    Less,
    /// m(case) > m(other).
    Greater,
    /// |m(case)/m(other) − value| ≤ tol·value.
    Ratio,
    /// |m(case)/m(other) − 1| ≤ tol.
    Similar,
    /// m ≥ value.
    AtLeast,
    /// m ≤ value.
    AtMost,
}

/// A claim of the paper about one case (or a pair).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Claim {
    /// Short id.
    pub id: String,
    /// Where in the paper.
    pub source: String,
    /// The claim in words.
    pub text: String,
    /// How it is scored.
    pub kind: ClaimKind,
    /// The case.
    pub case: String,
    /// The other case, for comparisons.
    #[serde(default)]
    pub other: Option<String>,
    /// The metric.
    #[serde(default)]
    pub metric: Option<String>,
    /// Target value.
    #[serde(default)]
    pub value: Option<f64>,
    /// Relative tolerance.
    #[serde(default)]
    pub tol: Option<f64>,
    /// Explanation for the report.
    #[serde(default)]
    pub note: String,
}

/// A variation applied to some cases to measure how much an ambiguity matters.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sensitivity {
    /// Short id.
    pub id: String,
    /// The question, in words.
    pub question: String,
    /// Overrides on top of the chosen reading.
    pub set: Vec<String>,
    /// Cases it applies to.
    pub cases: Vec<String>,
    /// Run seeds 0..n−1 and report the spread.
    #[serde(default)]
    pub seeds: Option<u32>,
}

/// How the claims on cases with a random variation are judged.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StochasticCfg {
    /// Seeds 0..seeds−1 of every case whose scenario has a random part.
    pub seeds: u32,
}

/// The whole manifest.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Readings, in order.
    pub reading: Vec<Reading>,
    /// Cases, in order.
    pub case: Vec<Case>,
    /// Claims, in order.
    pub claim: Vec<Claim>,
    /// Sensitivity studies, in order.
    #[serde(default)]
    pub sensitivity: Vec<Sensitivity>,
    /// When successive discretisations agree.
    #[serde(default)]
    pub convergence: super::convergence::Tolerance,
    /// Claims on random cases judged over many seeds (none: not done).
    #[serde(default)]
    pub stochastic: Option<StochasticCfg>,
}

/// Most seeds one sensitivity study may ask for.
pub const MAX_SEEDS: u32 = 1000;

impl Manifest {
    /// Reads and checks a manifest.
    pub fn load(path: &Path) -> Result<Manifest> {
        use crate::error::InputError;
        let file = path.display().to_string();
        let text = crate::input::read_text(path)
            .map_err(|r| InputError::file(&file, format!("the manifest {r}")))?;
        // One line: where, the key, and toml's message without its snippet.
        let at = |span: Option<std::ops::Range<usize>>| {
            span.map(|s| crate::scenario::line_col(&text, s.start))
        };
        let first = |m: &str| m.lines().next().unwrap_or("").trim().to_string();
        let de = toml::Deserializer::parse(&text).map_err(|e| InputError::File {
            file: file.clone(),
            line_col: at(e.span()),
            reason: first(e.message()).into(),
        })?;
        let m: Manifest = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = e.path().to_string();
            let inner = e.into_inner();
            let (line_col, reason) = (at(inner.span()), first(inner.message()).into());
            if key == "." || key == "?" {
                InputError::File {
                    file: file.clone(),
                    line_col,
                    reason,
                }
            } else {
                InputError::Key {
                    file: file.clone(),
                    line_col,
                    key,
                    reason,
                }
            }
        })?;
        m.check()
            .with_context(|| format!("checking {}", path.display()))?;
        Ok(m)
    }

    fn check(&self) -> Result<()> {
        let cases: HashSet<&str> = self.case.iter().map(|c| c.id.as_str()).collect();
        if cases.len() != self.case.len() {
            crate::bad_input!("duplicate case id");
        }
        if self.reading.is_empty() {
            crate::bad_input!("no [[reading]]");
        }
        for r in &self.reading {
            const KEYS: [&str; 2] = ["simulation.substeps", "simulation.step"];
            if !KEYS.contains(&r.refine.key.as_str()) {
                crate::bad_input!(
                    "reading `{}`: refine.key `{}` is not one of {KEYS:?}",
                    r.id,
                    r.refine.key
                );
            }
            if let Some(v) = r
                .refine
                .levels
                .iter()
                .find(|v| !(v.is_finite() && **v > 0.0))
            {
                crate::bad_input!(
                    "reading `{}`: refine.levels: {v} is not finite and > 0",
                    r.id
                );
            }
            let substeps = r.refine.key.ends_with("substeps");
            let finer = |a: f64, b: f64| if substeps { b > a } else { b < a };
            if r.refine.levels.windows(2).any(|w| !finer(w[0], w[1])) {
                crate::bad_input!(
                    "reading `{}`: refine.levels must get finer at every level ({})",
                    r.id,
                    if substeps {
                        "more sub-steps"
                    } else {
                        "smaller steps"
                    }
                );
            }
            if substeps && r.refine.levels.iter().any(|v| v.fract() != 0.0) {
                crate::bad_input!(
                    "reading `{}`: refine.levels: sub-steps must be whole numbers",
                    r.id
                );
            }
            self.convergence.check(r.refine.levels.len(), &r.id)?;
        }
        for c in &self.claim {
            if !cases.contains(c.case.as_str()) {
                crate::bad_input!("claim `{}`: unknown case `{}`", c.id, c.case);
            }
            if let Some(o) = &c.other {
                if !cases.contains(o.as_str()) {
                    crate::bad_input!("claim `{}`: unknown other case `{o}`", c.id);
                }
            }
            let needs_metric = !matches!(c.kind, ClaimKind::Bounded | ClaimKind::Unbounded);
            if needs_metric && c.metric.is_none() {
                crate::bad_input!("claim `{}`: kind needs `metric`", c.id);
            }
            if let Some(m) = &c.metric {
                if !super::derived::is_metric(m) {
                    crate::bad_input!("claim `{}`: unknown metric `{m}`", c.id);
                }
            }
            let needs_other = matches!(
                c.kind,
                ClaimKind::Less | ClaimKind::Greater | ClaimKind::Ratio | ClaimKind::Similar
            );
            if needs_other && c.other.is_none() {
                crate::bad_input!("claim `{}`: kind needs `other`", c.id);
            }
            let needs_value = matches!(
                c.kind,
                ClaimKind::Approx | ClaimKind::Ratio | ClaimKind::AtLeast | ClaimKind::AtMost
            );
            if needs_value && c.value.is_none() {
                crate::bad_input!("claim `{}`: kind needs `value`", c.id);
            }
            if matches!(
                c.kind,
                ClaimKind::Approx | ClaimKind::Ratio | ClaimKind::Similar
            ) && c.tol.is_none()
            {
                crate::bad_input!("claim `{}`: kind needs `tol`", c.id);
            }
        }
        if let Some(st) = &self.stochastic {
            if st.seeds == 0 || st.seeds > MAX_SEEDS {
                crate::bad_input!(
                    "[stochastic] seeds = {} is outside 1..={MAX_SEEDS}",
                    st.seeds
                );
            }
        }
        for s in &self.sensitivity {
            if s.seeds.is_some_and(|n| n > MAX_SEEDS) {
                crate::bad_input!(
                    "sensitivity `{}`: seeds = {} is more than the limit of {MAX_SEEDS}",
                    s.id,
                    s.seeds.unwrap_or(0)
                );
            }
            for c in &s.cases {
                if !cases.contains(c.as_str()) {
                    crate::bad_input!("sensitivity `{}`: unknown case `{c}`", s.id);
                }
            }
        }
        Ok(())
    }
}
