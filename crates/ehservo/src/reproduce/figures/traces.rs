//! The traces as drawn: long series reduced to at most `MAX_POINTS` (every
//! peak kept), envelopes per window, head and tail windows, and the u and σ
//! panels and status notes the figures share.

use crate::output::{clip_diverged, panel};
use crate::plot::{Dash, Panel, Series};
use crate::run::RunResult;
use crate::simulation::Sample;

/// Longest series drawn; longer ones are reduced by min/max per bucket, which
/// keeps every peak (an SVG with 60 000 points per line helps nobody).
const MAX_POINTS: usize = 4000;

pub(super) fn series(
    label: &str,
    trace: &[Sample],
    f: impl Fn(&Sample) -> f64,
    color: usize,
    dash: Dash,
) -> Series {
    let (x, y) = decimate(trace, &f);
    Series::new(label, x, y, color).dash(dash)
}

fn decimate(trace: &[Sample], f: &dyn Fn(&Sample) -> f64) -> (Vec<f64>, Vec<f64>) {
    if trace.len() <= MAX_POINTS {
        return (
            trace.iter().map(|s| s.t).collect(),
            trace.iter().map(f).collect(),
        );
    }
    let buckets = MAX_POINTS / 2;
    let per = trace.len().div_ceil(buckets);
    let (mut x, mut y) = (
        Vec::with_capacity(MAX_POINTS),
        Vec::with_capacity(MAX_POINTS),
    );
    for chunk in trace.chunks(per) {
        let (mut imin, mut imax) = (0, 0);
        for (i, s) in chunk.iter().enumerate() {
            if f(s) < f(&chunk[imin]) {
                imin = i;
            }
            if f(s) > f(&chunk[imax]) {
                imax = i;
            }
        }
        let (a, b) = if imin <= imax {
            (imin, imax)
        } else {
            (imax, imin)
        };
        x.push(chunk[a].t);
        y.push(f(&chunk[a]));
        if b != a {
            x.push(chunk[b].t);
            y.push(f(&chunk[b]));
        }
    }
    (x, y)
}

/// Min, max and mean of `f` over consecutive windows of `window` seconds,
/// at each window's centre.
struct Envelope {
    n: Vec<usize>,
    t: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    mean: Vec<f64>,
}

fn envelope(trace: &[Sample], f: &dyn Fn(&Sample) -> f64, window: f64) -> Envelope {
    let mut e = Envelope {
        n: Vec::new(),
        t: Vec::new(),
        lo: Vec::new(),
        hi: Vec::new(),
        mean: Vec::new(),
    };
    let Some(t0) = trace.first().map(|s| s.t) else {
        return e;
    };
    // Window index of a sample; the tolerance puts t = k·window (rounded)
    // at the start of window k.
    let index = |t: f64| ((t - t0) / window + 1e-9).floor() as i64;
    let mut i = 0;
    while i < trace.len() {
        let k = index(trace[i].t);
        let j = i + trace[i..]
            .iter()
            .position(|s| index(s.t) != k)
            .unwrap_or(trace.len() - i);
        let vals: Vec<f64> = trace[i..j]
            .iter()
            .map(f)
            .filter(|v| v.is_finite())
            .collect();
        // A window cut short by the end of the run (the lone sample at
        // t = T) would draw a spurious step: windows of fewer than half the
        // first one's samples are left out.
        let full = e.n.first().copied().unwrap_or(vals.len());
        if !vals.is_empty() && 2 * vals.len() >= full {
            e.n.push(vals.len());
            e.t.push(t0 + (k as f64 + 0.5) * window);
            e.lo.push(vals.iter().copied().fold(f64::INFINITY, f64::min));
            e.hi.push(vals.iter().copied().fold(f64::NEG_INFINITY, f64::max));
            e.mean.push(vals.iter().sum::<f64>() / vals.len() as f64);
        }
        i = j;
    }
    e
}

/// The envelope of `f` over one case, as a shaded band and its mean line.
pub(super) fn envelope_series(
    label: &str,
    trace: &[Sample],
    f: &dyn Fn(&Sample) -> f64,
    window: f64,
    color: usize,
    dash: Dash,
) -> [Series; 2] {
    let e = envelope(trace, f, window);
    [
        Series::band("", e.t.clone(), e.lo, e.hi, color),
        Series::new(label, e.t, e.mean, color).dash(dash),
    ]
}

/// The samples of the last `span` seconds.
pub(super) fn tail(trace: &[Sample], span: f64) -> &[Sample] {
    let end = trace.last().map_or(0.0, |s| s.t);
    let from = trace.partition_point(|s| s.t < end - span - 1e-9);
    &trace[from..]
}

/// The samples with t ≤ `span`.
pub(super) fn head(trace: &[Sample], span: f64) -> &[Sample] {
    &trace[..trace.partition_point(|s| s.t <= span + 1e-9)]
}

/// A panel of u(t) (V).
pub(super) fn u_panel(title: &str, r: &RunResult) -> Panel {
    let mut p = panel(
        title,
        "u (V)",
        vec![series("", &r.trace, |s| s.u, 0, Dash::Solid)],
    );
    clip_diverged(&mut p, r);
    p
}

/// A panel of σ(t) (rad/s²).
pub(super) fn sigma_panel(title: &str, r: &RunResult) -> Panel {
    let f = |s: &Sample| s.part("sigma");
    let mut p = panel(
        title,
        "σ (rad/s²)",
        vec![series("", &r.trace, f, 0, Dash::Solid)],
    );
    clip_diverged(&mut p, r);
    p
}

pub(super) fn status(r: &RunResult) -> String {
    match r.outcome.diverged {
        Some(d) => format!(" — unbounded at t = {:.2} s", d.t),
        None => String::new(),
    }
}

pub(super) fn e_deg(s: &Sample) -> f64 {
    s.e_deg()
}
