//! Claims on cases with a random variation, judged over many seeds.
//!
//! A case is random when its scenario (under the chosen reading) has
//! `uncertainty.a_random` or `uncertainty.b_random` non-zero — today Fig. 8,
//! "half random, half bias". One seed says little about such a claim, so
//! the case is run for seeds 0..N−1 (`[stochastic] seeds = N` in the
//! manifest; 400 for the paper), in parallel and collected in seed order, so
//! the result does not depend on the number of threads.
//!
//! Each claim whose case (or other case) is random is turned into a
//! per-seed quantity q and a band that q must fall in:
//!
//! | kind | q | band |
//! |---|---|---|
//! | approx | m | value·(1 ± tol) |
//! | at_least / at_most | m | [value, ∞) / (−∞, value] |
//! | ratio | m/m_other | value·(1 ± tol) |
//! | similar | m/m_other | [1 − tol, 1 + tol] |
//! | less / greater | m − m_other | (−∞, 0) / (0, ∞) |
//! | bounded / unbounded | 1 if bounded, else 0 | {1} / {0} |
//!
//! A seed whose q is undefined (a diverged run, an undefined metric) counts
//! in `n_undefined` and outside the band. The distribution gives the median
//! and the 5 % and 95 % quantiles of the defined values (linear
//! interpolation between order statistics, NumPy's default: the p-quantile
//! of sorted v_0..v_{n−1} is v_⌊h⌋ + (h − ⌊h⌋)(v_⌊h⌋+1 − v_⌊h⌋), h = (n−1)p),
//! and the share of all seeds inside the band. The claim **agrees** when the
//! median is inside the band; it is undecided when half the seeds or more
//! are undefined (no median is then reported).

use super::cases::measure;
use super::derived::{format_metric, CaseMetrics};
use super::doc::Block;
use super::manifest::{Claim, ClaimKind, Manifest};
use crate::plot::{HistPanel, Histogram};
use crate::scenario::Loop;
use anyhow::Result;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Seeds when the manifest has no `[stochastic]` table but a case is random.
pub const DEFAULT_SEEDS: u32 = 400;

/// Whether a scenario's variation has a random part.
pub fn is_random(s: &Loop) -> bool {
    s.stages().uncertainty.paper_is_random()
}

/// The p-quantile (0 ≤ p ≤ 1) of an ascending sample, by linear
/// interpolation between order statistics; None for an empty sample.
pub fn quantile(sorted: &[f64], p: f64) -> Option<f64> {
    let n = sorted.len();
    if n == 0 {
        return None;
    }
    let h = (n - 1) as f64 * p.clamp(0.0, 1.0);
    let i = h.floor() as usize;
    let f = h - i as f64;
    let a = sorted[i];
    Some(match sorted.get(i + 1) {
        Some(b) if f > 0.0 => a + f * (b - a),
        _ => a,
    })
}

/// The interval a claim's per-seed quantity must fall in (an infinite end
/// is written as null in results.json).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Band {
    /// Lower end (may be −∞).
    pub lo: f64,
    /// Upper end (may be +∞).
    pub hi: f64,
    /// Ends excluded (less / greater: a strict comparison).
    pub strict: bool,
}

impl Band {
    /// Whether `q` is inside.
    pub fn contains(&self, q: f64) -> bool {
        if self.strict {
            q > self.lo && q < self.hi
        } else {
            q >= self.lo && q <= self.hi
        }
    }
}

/// A distribution over seeds, judged against a band.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Distribution {
    /// Seeds.
    pub n: usize,
    /// Seeds with q undefined (diverged, or the metric undefined).
    pub n_undefined: usize,
    /// Seeds whose run diverged.
    pub n_diverged: usize,
    /// Median of the defined values (None: half the seeds or more undefined).
    pub median: Option<f64>,
    /// 5 % quantile of the defined values.
    pub p05: Option<f64>,
    /// 95 % quantile of the defined values.
    pub p95: Option<f64>,
    /// Share of all n seeds with q inside the band.
    pub share_in_band: f64,
}

/// The distribution of `q` (None: undefined) against `band`; `n_diverged`
/// is carried through.
pub fn distribution(q: &[Option<f64>], band: Band, n_diverged: usize) -> Distribution {
    let mut v: Vec<f64> = q
        .iter()
        .flatten()
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    v.sort_by(f64::total_cmp);
    let n = q.len();
    let n_undefined = n - v.len();
    let inside = v.iter().filter(|&&x| band.contains(x)).count();
    Distribution {
        n,
        n_undefined,
        n_diverged,
        median: if 2 * n_undefined >= n.max(1) {
            None
        } else {
            quantile(&v, 0.5)
        },
        p05: quantile(&v, 0.05),
        p95: quantile(&v, 0.95),
        share_in_band: if n == 0 {
            0.0
        } else {
            inside as f64 / n as f64
        },
    }
}

/// One claim judged over the seeds.
#[derive(Debug, Clone, Serialize)]
pub struct ClaimDistribution {
    /// Claim id.
    pub claim: String,
    /// What q is, in words.
    pub quantity: String,
    /// The band.
    pub band: Band,
    /// The paper's value, where the claim has one.
    pub paper: Option<f64>,
    /// The distribution.
    #[serde(flatten)]
    pub dist: Distribution,
    /// The median is inside the band.
    pub agree: bool,
    /// q of every seed, in seed order.
    pub per_seed: Vec<Option<f64>>,
}

/// A random case over its seeds.
#[derive(Debug, Clone, Serialize)]
pub struct SeededCase {
    /// Case id.
    pub case: String,
    /// e_max_deg of seeds 0..n−1.
    pub e_max_deg: Vec<Option<f64>>,
    /// The metrics of every seed (not written to results.json).
    #[serde(skip)]
    pub metrics: Vec<CaseMetrics>,
}

/// Everything the stochastic judgement measured.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Stochastic {
    /// The reading the seeds were run under.
    pub reading: String,
    /// The random cases.
    pub cases: Vec<SeededCase>,
    /// The claims on them.
    pub claims: Vec<ClaimDistribution>,
}

/// The per-seed quantity of `claim` and its band; `m(case, k)` gives the
/// metrics of a case at seed k (the same for every k when it is not random).
pub fn judge(
    claim: &Claim,
    n: usize,
    m: &dyn Fn(&str, usize) -> Option<CaseMetrics>,
) -> ClaimDistribution {
    let metric = claim.metric.as_deref().unwrap_or("");
    let other = claim.other.as_deref().unwrap_or("");
    let get = |case: &str, k: usize| m(case, k).and_then(|c| c.get(metric));
    let (quantity, band, paper) = quantity_and_band(claim);
    let per_seed: Vec<Option<f64>> = (0..n)
        .map(|k| match claim.kind {
            ClaimKind::Approx | ClaimKind::AtLeast | ClaimKind::AtMost => get(&claim.case, k),
            ClaimKind::Ratio | ClaimKind::Similar => match (get(&claim.case, k), get(other, k)) {
                (Some(a), Some(b)) if b != 0.0 => Some(a / b),
                _ => None,
            },
            ClaimKind::Less | ClaimKind::Greater => Some(get(&claim.case, k)? - get(other, k)?),
            ClaimKind::Bounded | ClaimKind::Unbounded => {
                m(&claim.case, k).map(|c| if c.base.diverged { 0.0 } else { 1.0 })
            }
        })
        .collect();
    let diverged = (0..n)
        .filter(|&k| {
            [Some(claim.case.as_str()), claim.other.as_deref()]
                .into_iter()
                .flatten()
                .any(|c| m(c, k).is_some_and(|c| c.base.diverged))
        })
        .count();
    let dist = distribution(&per_seed, band, diverged);
    ClaimDistribution {
        claim: claim.id.clone(),
        quantity,
        band,
        paper,
        agree: dist.median.is_some_and(|q| band.contains(q)),
        dist,
        per_seed,
    }
}

/// What `claim` judges per seed (its name), the band it must lie in and
/// the paper's value, where the claim has one.
fn quantity_and_band(claim: &Claim) -> (String, Band, Option<f64>) {
    let metric = claim.metric.as_deref().unwrap_or("");
    let value = claim.value.unwrap_or(f64::NAN);
    let tol = claim.tol.unwrap_or(0.0);
    let other = claim.other.as_deref().unwrap_or("");
    let inf = f64::INFINITY;
    match claim.kind {
        ClaimKind::Approx => (
            metric.into(),
            Band {
                lo: value - tol * value.abs(),
                hi: value + tol * value.abs(),
                strict: false,
            },
            Some(value),
        ),
        ClaimKind::AtLeast => (
            metric.into(),
            Band {
                lo: value,
                hi: inf,
                strict: false,
            },
            Some(value),
        ),
        ClaimKind::AtMost => (
            metric.into(),
            Band {
                lo: -inf,
                hi: value,
                strict: false,
            },
            Some(value),
        ),
        ClaimKind::Ratio => (
            format!("{metric}: {} / {other}", claim.case),
            Band {
                lo: value - tol * value.abs(),
                hi: value + tol * value.abs(),
                strict: false,
            },
            Some(value),
        ),
        ClaimKind::Similar => (
            format!("{metric}: {} / {other}", claim.case),
            Band {
                lo: 1.0 - tol,
                hi: 1.0 + tol,
                strict: false,
            },
            Some(1.0),
        ),
        ClaimKind::Less => (
            format!("{metric}: {} − {other}", claim.case),
            Band {
                lo: -inf,
                hi: 0.0,
                strict: true,
            },
            None,
        ),
        ClaimKind::Greater => (
            format!("{metric}: {} − {other}", claim.case),
            Band {
                lo: 0.0,
                hi: inf,
                strict: true,
            },
            None,
        ),
        ClaimKind::Bounded | ClaimKind::Unbounded => {
            let want = if claim.kind == ClaimKind::Bounded {
                1.0
            } else {
                0.0
            };
            (
                "bounded (1) or not (0)".into(),
                Band {
                    lo: want,
                    hi: want,
                    strict: false,
                },
                None,
            )
        }
    }
}

/// Runs every random case for seeds 0..n−1 under the chosen reading
/// (`jobs` holds every case under every reading, as [`super::load_cases`]
/// gives them) and judges every claim on them. `base` holds the chosen
/// reading's single-run metrics of every case.
pub(super) fn run(
    m: &Manifest,
    jobs: &[(usize, usize, Loop)],
    reading: usize,
    base: &BTreeMap<String, CaseMetrics>,
    seeds_override: Option<u32>,
    progress: bool,
) -> Result<Stochastic> {
    let random: Vec<(String, &Loop)> = jobs
        .iter()
        .filter(|(ri, _, s)| *ri == reading && is_random(s))
        .map(|(_, ci, s)| (m.case[*ci].id.clone(), s))
        .collect();
    let mut out = Stochastic {
        reading: m.reading[reading].id.clone(),
        ..Stochastic::default()
    };
    if random.is_empty() {
        return Ok(out);
    }
    let n = seeds_override
        .or(m.stochastic.as_ref().map(|s| s.seeds))
        .unwrap_or(DEFAULT_SEEDS)
        .max(1) as usize;
    let runs: Vec<(usize, u64)> = (0..random.len())
        .flat_map(|c| (0..n as u64).map(move |k| (c, k)))
        .collect();
    let pb = super::cases::bar(progress, runs.len() as u64, "seeds");
    let measured: Vec<CaseMetrics> = runs
        .par_iter()
        .map(|&(c, k)| {
            let s = random[c]
                .1
                .with_values(&[("uncertainty.seed".into(), toml::Value::Integer(k as i64))])
                .map_err(anyhow::Error::from)?;
            let r = measure(&s, false).map(|x| x.0);
            pb.inc(1);
            r
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();
    for (c, (id, _)) in random.iter().enumerate() {
        let metrics: Vec<CaseMetrics> = measured[c * n..(c + 1) * n].to_vec();
        out.cases.push(SeededCase {
            case: id.clone(),
            e_max_deg: metrics.iter().map(|x| x.base.e_max).collect(),
            metrics,
        });
    }
    let cases = &out.cases;
    let lookup = |case: &str, k: usize| -> Option<CaseMetrics> {
        match cases.iter().find(|c| c.case == case) {
            Some(c) => c.metrics.get(k).copied(),
            None => base.get(case).copied(),
        }
    };
    out.claims = m
        .claim
        .iter()
        .filter(|c| {
            [Some(c.case.as_str()), c.other.as_deref()]
                .into_iter()
                .flatten()
                .any(|id| cases.iter().any(|s| s.case == id))
        })
        .map(|c| judge(c, n, &lookup))
        .collect();
    Ok(out)
}

/// A claim's verdict from its distribution over the seeds: agree when the
/// median is in the band, undecided without a median (half the seeds or
/// more undefined), differ otherwise.
pub fn verdict(c: &Claim, d: &ClaimDistribution) -> super::claims::Verdict {
    use super::claims::{Status, Verdict};
    let metric = c.metric.as_deref().unwrap_or("");
    let ratio = is_ratio(c);
    let f = |v: Option<f64>| fmt_q(metric, ratio, v);
    Verdict {
        status: match d.dist.median {
            None => Status::Undecided,
            Some(_) if d.agree => Status::Agree,
            Some(_) => Status::Differ,
        },
        measured: format!(
            "median {} (5–95 %: {} – {})",
            f(d.dist.median),
            f(d.dist.p05),
            f(d.dist.p95)
        ),
        detail: format!(
            "over {} seeds: {:.0} % inside the claim's band {}",
            d.dist.n,
            100.0 * d.dist.share_in_band,
            band_text(&d.band, metric, ratio)
        ),
    }
}

fn fmt_q(metric: &str, ratio: bool, v: Option<f64>) -> String {
    match v {
        None => "—".into(),
        Some(v) if ratio => format!("{v:.3}"),
        Some(v) => format_metric(metric, v),
    }
}

fn band_text(b: &Band, metric: &str, ratio: bool) -> String {
    let f = |v: f64| fmt_q(metric, ratio, Some(v));
    let (l, r) = if b.strict { ("(", ")") } else { ("[", "]") };
    match (b.lo.is_finite(), b.hi.is_finite()) {
        (true, true) if (b.hi - b.lo).abs() < 1e-300 => format!("= {}", f(b.lo)),
        (true, true) => format!("{l}{}, {}{r}", f(b.lo), f(b.hi)),
        (true, false) => format!("{} {}", if b.strict { ">" } else { "≥" }, f(b.lo)),
        (false, true) => format!("{} {}", if b.strict { "<" } else { "≤" }, f(b.hi)),
        _ => "any".into(),
    }
}

fn is_ratio(c: &Claim) -> bool {
    matches!(
        c.kind,
        ClaimKind::Ratio | ClaimKind::Similar | ClaimKind::Bounded | ClaimKind::Unbounded
    )
}

/// The report's section: one row per claim on a random case.
pub fn report_blocks(m: &Manifest, st: &Stochastic) -> Vec<Block> {
    let Some(n) = st.cases.first().map(|c| c.e_max_deg.len()) else {
        return Vec::new();
    };
    let mut d = vec![
        Block::Heading(2, "Claims on random cases, over many seeds".into()),
        Block::Para(format!(
            "Cases with a random variation ({}) run for seeds 0–{} under the reading `{}`. Each claim is judged on the \
distribution of its quantity over the seeds: it **agrees** when the median is inside the claim's band. The 5–95 % \
range is of the defined values; the share in the band counts every seed (a diverged seed is outside). The claims \
tables score these claims the same way under every reading (each at its converged level).",
            st.cases.iter().map(|c| format!("`{}`", c.case)).collect::<Vec<_>>().join(", "),
            n - 1,
            st.reading
        )),
    ];
    let rows = st
        .claims
        .iter()
        .map(|cd| {
            let c = m.claim.iter().find(|c| c.id == cd.claim);
            let metric = c.and_then(|c| c.metric.as_deref()).unwrap_or("");
            let ratio = c.is_some_and(is_ratio);
            let q = |v| fmt_q(metric, ratio, v);
            vec![
                format!("`{}`", cd.claim),
                c.map(|c| c.text.clone()).unwrap_or_default(),
                cd.quantity.clone(),
                band_text(&cd.band, metric, ratio),
                q(cd.dist.median),
                format!("{} … {}", q(cd.dist.p05), q(cd.dist.p95)),
                format!("{:.0} %", 100.0 * cd.dist.share_in_band),
                format!("{} / {}", cd.dist.n_diverged, cd.dist.n),
                if cd.dist.median.is_none() {
                    "undecided"
                } else if cd.agree {
                    "agree"
                } else {
                    "differ"
                }
                .into(),
            ]
        })
        .collect();
    d.push(Block::Table(
        [
            "claim",
            "the paper's claim",
            "quantity",
            "band",
            "median",
            "5–95 %",
            "seeds in band",
            "diverged",
            "verdict (median)",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect(),
        rows,
    ));
    d
}

/// One histogram figure per random case: a panel per claim on it (not the
/// bounded ones), the band shaded, the paper's value marked.
pub fn figures(m: &Manifest, st: &Stochastic) -> Vec<(String, String, Histogram)> {
    let mut out = Vec::new();
    for case in &st.cases {
        let mut panels = Vec::new();
        for cd in &st.claims {
            let Some(c) = m.claim.iter().find(|c| c.id == cd.claim) else {
                continue;
            };
            if c.case != case.case || matches!(c.kind, ClaimKind::Bounded | ClaimKind::Unbounded) {
                continue;
            }
            let mut marks = Vec::new();
            if let Some(p) = cd.paper {
                marks.push((format!("paper: {p}"), p, 1));
            }
            if let Some(med) = cd.dist.median {
                marks.push((format!("median {med:.4}"), med, 3));
            }
            panels.push(HistPanel {
                title: format!(
                    "{} — {} seeds, {:.0} % in the band, {} undefined",
                    c.id,
                    cd.dist.n,
                    100.0 * cd.dist.share_in_band,
                    cd.dist.n_undefined
                ),
                x_label: cd.quantity.clone(),
                values: cd.per_seed.iter().flatten().copied().collect(),
                bins: 40,
                band: Some((cd.band.lo, cd.band.hi, "the claim's band".into())),
                marks,
            });
        }
        if panels.is_empty() {
            continue;
        }
        let rows = panels.len() as u32;
        out.push((
            format!("{}-seeds", case.case),
            format!(
                "`{}` over {} seeds (reading `{}`): histogram of each claim's quantity, the claim's band shaded, the \
paper's value and the median marked",
                case.case,
                case.e_max_deg.len(),
                st.reading
            ),
            Histogram {
                title: format!("{}: the claims over {} seeds", case.case, case.e_max_deg.len()),
                panels,
                size: (1200, 80 + 380 * rows),
            },
        ));
    }
    out
}

/// Writes the histogram figures (PNG and SVG) into `dir/figures` and
/// returns their (relative PNG path, caption) for the report.
pub fn write_figures(m: &Manifest, st: &Stochastic, dir: &Path) -> Result<Vec<(String, String)>> {
    let mut v = Vec::new();
    for (stem, caption, h) in figures(m, st) {
        h.png(&dir.join("figures").join(format!("{stem}.png")))?;
        h.svg(&dir.join("figures").join(format!("{stem}.svg")))?;
        v.push((format!("figures/{stem}.png"), caption));
    }
    Ok(v)
}
