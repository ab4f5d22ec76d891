//! Step-response metrics of a sampled trace: rise times, peak, overshoot,
//! settling and any sustained oscillation after each step of the
//! reference. The definitions are those of
//! `tests/data/hopsan/step_metrics.py` (its docstring), so that a run and
//! Hopsan's trace are measured alike; this is a second, separate
//! implementation of them.
//!
//! - A **step** is a sample i ≥ 1 where |r_i − r_{i−1}| > 1e-9·max(1, max|r|);
//!   its window runs to the sample before the next step. Its time t0 is
//!   t_i, or the given true time. The start can be analysed as a step from
//!   y_0 to r_0 at t_0.
//! - y0 is y at t0 (interpolated), the target r after the step, δ = target − y0,
//!   s(t) = (y − y0)/δ.
//! - **t10, t50, t90**: the first times after t0 that s reaches 0.1, 0.5,
//!   0.9 (interpolated), minus t0.
//! - **Peak**: the window's largest s (the first if tied), its value and
//!   time; overshoot = max(0, s_peak − 1)·100 %.
//! - **Settling (2 %)**: the last entry into target ± 0.02·|δ| after which y
//!   stays in the band to the window's end; none when y leaves the band in
//!   the window's second half.
//! - **Sustained oscillation**, on the window's second half: m its mean,
//!   e = y − m; upward zero crossings of e (interpolated) cut it into
//!   cycles with a length and a peak-to-peak value. Sustained when there
//!   are ≥ 2 cycles, the last peak-to-peak is at least half the first, and
//!   half the mean peak-to-peak exceeds max(1e-12, 1e-4·|δ|): then the
//!   period (mean cycle length), the amplitude (half the mean peak-to-peak)
//!   and the offset m − target.

use crate::scenario::CsvError;
use serde::Serialize;

/// The metrics of one step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepMetrics {
    /// The step's time t0.
    pub t0: f64,
    /// The output at t0.
    pub y0: f64,
    /// The reference after the step.
    pub target: f64,
    /// The 10, 50 and 90 % rise times after t0 (None when not reached).
    pub rise: [Option<f64>; 3],
    /// The peak's value.
    pub peak: f64,
    /// The peak's time after t0.
    pub peak_time: f64,
    /// Overshoot (%).
    pub overshoot_pct: f64,
    /// The 2 % settling time after t0 (None when not settled).
    pub settling: Option<f64>,
    /// A sustained oscillation's period and amplitude.
    pub oscillation: Option<(f64, f64)>,
    /// The tail's mean minus the target.
    pub offset: f64,
}

/// Linear interpolation of y at t (t within the samples).
fn at(t: &[f64], y: &[f64], tq: f64) -> f64 {
    let j = t.partition_point(|&v| v < tq);
    if j == 0 {
        return y[0];
    }
    if j >= t.len() {
        return y[t.len() - 1];
    }
    let w = (tq - t[j - 1]) / (t[j] - t[j - 1]);
    y[j - 1] + w * (y[j] - y[j - 1])
}

/// The metrics of every step of `r` in (t, y); `step_times` the true times
/// of the steps in order (or empty: the first sample at the new value),
/// `initial` whether the start is analysed as a step too.
pub fn step_metrics(
    t: &[f64],
    y: &[f64],
    r: &[f64],
    step_times: &[f64],
    initial: bool,
) -> Vec<StepMetrics> {
    let n = t.len().min(y.len()).min(r.len());
    if n < 3 {
        return Vec::new();
    }
    let starts = step_starts(&t[..n], &y[..n], r, step_times, initial);
    let mut out = Vec::new();
    for (s, &(i0, t0, y0)) in starts.iter().enumerate() {
        let end = starts.get(s + 1).map_or(n, |n1| n1.0);
        let w = Window {
            t,
            y,
            i0,
            end,
            t0,
            y0,
            target: r[i0],
        };
        let delta = w.target - y0;
        if delta == 0.0 || end <= i0 + 2 {
            continue;
        }
        let (ip, sp) = w.peak();
        let (m, oscillation) = w.tail();
        out.push(StepMetrics {
            t0,
            y0,
            target: w.target,
            rise: w.rise(),
            peak: y[ip],
            peak_time: t[ip] - t0,
            overshoot_pct: (sp - 1.0).max(0.0) * 100.0,
            settling: w.settling(),
            oscillation,
            offset: m - w.target,
        });
    }
    out
}

/// Where each step starts: (first index, t0, y0 = y at t0). A step is a
/// change of r (by more than 10⁻⁹ of its largest value); t0 its true time
/// from `step_times` (in order) or its first sample; with `initial`, the
/// start of the run too. `t` and `y` are cut to the samples analysed.
fn step_starts(
    t: &[f64],
    y: &[f64],
    r: &[f64],
    step_times: &[f64],
    initial: bool,
) -> Vec<(usize, f64, f64)> {
    let scale = r.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    let mut starts: Vec<(usize, f64, f64)> = Vec::new();
    if initial {
        starts.push((0, t[0], y[0]));
    }
    let mut k = 0;
    for i in 1..t.len() {
        if (r[i] - r[i - 1]).abs() > 1e-9 * scale {
            let t0 = step_times.get(k).copied().unwrap_or(t[i]);
            k += 1;
            starts.push((i, t0, at(t, y, t0)));
        }
    }
    starts
}

/// One step's window of the trace: samples i0..end, from (t0, y0) towards
/// `target`.
struct Window<'a> {
    t: &'a [f64],
    y: &'a [f64],
    i0: usize,
    end: usize,
    t0: f64,
    y0: f64,
    target: f64,
}

impl Window<'_> {
    /// A value as a fraction of the step (0 at y0, 1 at the target).
    fn norm(&self, v: f64) -> f64 {
        (v - self.y0) / (self.target - self.y0)
    }

    /// The rise times to 10, 50 and 90 % of the step: the first crossing
    /// of each level after t0.
    fn rise(&self) -> [Option<f64>; 3] {
        let (t, y, t0) = (self.t, self.y, self.t0);
        let mut rise = [None; 3];
        for (li, level) in [0.1, 0.5, 0.9].iter().enumerate() {
            let mut prev = (t0, self.norm(self.y0));
            for i in self.i0..self.end {
                if t[i] < t0 {
                    continue;
                }
                let cur = (t[i], self.norm(y[i]));
                if cur.1 >= *level {
                    // The bracket's level difference: > 0 unless s jumped
                    // onto the level exactly (then the sample's time).
                    let tc = if cur.1 <= prev.1 {
                        cur.0
                    } else {
                        prev.0 + (level - prev.1) / (cur.1 - prev.1) * (cur.0 - prev.0)
                    };
                    rise[li] = Some(tc - t0);
                    break;
                }
                prev = cur;
            }
        }
        rise
    }

    /// The peak: its index and its value as a fraction of the step.
    fn peak(&self) -> (usize, f64) {
        let (mut ip, mut sp) = (self.i0, f64::NEG_INFINITY);
        for (i, &v) in self.y.iter().enumerate().take(self.end).skip(self.i0) {
            if self.norm(v) > sp {
                sp = self.norm(v);
                ip = i;
            }
        }
        (ip, sp)
    }

    /// The time after t0 of the last entry into the ±2 % band (None: it
    /// leaves the band in the window's second half).
    fn settling(&self) -> Option<f64> {
        let (t, y, t0, target) = (self.t, self.y, self.t0, self.target);
        let (i0, end) = (self.i0, self.end);
        let band = 0.02 * (target - self.y0).abs();
        let half = t0 + 0.5 * (t[end - 1] - t0);
        let inside = |i: usize| (y[i] - target).abs() <= band;
        if (i0..end).any(|i| t[i] >= half && !inside(i)) {
            return None;
        }
        // The last entry: after the last sample outside the band.
        match (i0..end).rev().find(|&i| !inside(i)) {
            None => Some(0.0),
            Some(j) => {
                let (a, b) = ((y[j] - target).abs(), (y[j + 1] - target).abs());
                // a > band ≥ b: the entry is inside the interval.
                let w = if a <= b { 1.0 } else { (a - band) / (a - b) };
                Some(t[j] + w * (t[j + 1] - t[j]) - t0)
            }
        }
    }

    /// The tail (the window's second half): its mean, and a sustained
    /// oscillation about it (period, amplitude) when there is one.
    fn tail(&self) -> (f64, Option<(f64, f64)>) {
        let (t, y, t0) = (self.t, self.y, self.t0);
        let delta = self.target - self.y0;
        let half = t0 + 0.5 * (t[self.end - 1] - t0);
        let tail: Vec<usize> = (self.i0..self.end).filter(|&i| t[i] >= half).collect();
        let m = tail.iter().map(|&i| y[i]).sum::<f64>() / tail.len().max(1) as f64;
        let mut cross = Vec::new();
        for w in tail.windows(2) {
            let (a, b) = (y[w[0]] - m, y[w[1]] - m);
            if a < 0.0 && b >= 0.0 {
                cross.push((w[0], t[w[0]] + (-a) / (b - a) * (t[w[1]] - t[w[0]])));
            }
        }
        let mut cycles = Vec::new();
        for c in cross.windows(2) {
            let (lo, hi) = tail
                .iter()
                .filter(|&&i| i > c[0].0 && i <= c[1].0)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &i| {
                    (lo.min(y[i]), hi.max(y[i]))
                });
            cycles.push((c[1].1 - c[0].1, hi - lo));
        }
        let oscillation = if cycles.len() >= 2 {
            let pp = cycles.iter().map(|c| c.1).sum::<f64>() / cycles.len() as f64;
            let sustained = cycles[cycles.len() - 1].1 >= 0.5 * cycles[0].1
                && 0.5 * pp > (1e-4 * delta.abs()).max(1e-12);
            sustained.then(|| {
                let period = cycles.iter().map(|c| c.0).sum::<f64>() / cycles.len() as f64;
                (period, 0.5 * pp)
            })
        } else {
            None
        };
        (m, oscillation)
    }
}

/// The RMS and the largest |a − b| of two traces at b's times (a
/// interpolated linearly, b's times inside a's span).
pub fn difference(ta: &[f64], ya: &[f64], tb: &[f64], yb: &[f64]) -> (f64, f64) {
    let (mut sq, mut max, mut n) = (0.0, 0.0f64, 0usize);
    for (&t, &y) in tb.iter().zip(yb) {
        if t < ta[0] || t > ta[ta.len() - 1] {
            continue;
        }
        let d = at(ta, ya, t) - y;
        sq += d * d;
        max = max.max(d.abs());
        n += 1;
    }
    ((sq / n.max(1) as f64).sqrt(), max)
}

/// Named columns of a CSV file with one header row, as numbers (a bounded
/// read; the error names the file, the line and the column).
pub fn read_columns(path: &std::path::Path, names: &[&str]) -> Result<Vec<Vec<f64>>, CsvError> {
    let file = path.display().to_string();
    let text =
        crate::input::read_text_at_most(path, crate::input::MAX_DATA_BYTES).map_err(|source| {
            CsvError::Read {
                file: file.clone(),
                source,
            }
        })?;
    let fail = |line: Option<usize>, reason: String| CsvError::Content {
        file: file.clone(),
        line,
        row: None,
        reason,
    };
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .ok_or_else(|| fail(None, "empty".into()))?
        .split(',')
        .map(str::trim)
        .collect();
    let idx: Vec<usize> = names
        .iter()
        .map(|n| {
            header
                .iter()
                .position(|h| h == n)
                .ok_or_else(|| fail(None, format!("no column `{n}`")))
        })
        .collect::<Result<_, _>>()?;
    let mut out = vec![Vec::new(); names.len()];
    for (i, line) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        for (c, &j) in idx.iter().enumerate() {
            let v: f64 = f
                .get(j)
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| fail(Some(i + 2), format!("column {}: not a number", names[c])))?;
            out[c].push(v);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A first-order step y = 1 − e^{−t/τ}: t10 = τ·ln(10/9), t50 = τ·ln 2,
    /// t90 = τ·ln 10; no overshoot; settles (2 %) at τ·ln 50.
    #[test]
    fn first_order_closed_forms() {
        let tau = 0.1;
        let t: Vec<f64> = (0..=20_000).map(|k| k as f64 * 1e-4).collect();
        let r: Vec<f64> = t
            .iter()
            .map(|&v| if v >= 0.5 { 1.0 } else { 0.0 })
            .collect();
        let y: Vec<f64> = t
            .iter()
            .map(|&v| {
                if v < 0.5 {
                    0.0
                } else {
                    1.0 - (-(v - 0.5) / tau).exp()
                }
            })
            .collect();
        let m = step_metrics(&t, &y, &r, &[0.5], false);
        assert_eq!(m.len(), 1);
        let m = m[0];
        let close = |a: Option<f64>, b: f64| (a.unwrap() - b).abs() < 2e-5;
        assert!(close(m.rise[0], tau * (10.0f64 / 9.0).ln()), "{:?}", m.rise);
        assert!(close(m.rise[1], tau * 2f64.ln()));
        assert!(close(m.rise[2], tau * 10f64.ln()));
        assert!(close(m.settling, tau * 50f64.ln()), "{:?}", m.settling);
        assert!(m.overshoot_pct == 0.0 && m.oscillation.is_none());
    }

    /// A sine around the target after the step: sustained, with its period
    /// and amplitude.
    #[test]
    fn a_limit_cycle_is_measured() {
        let t: Vec<f64> = (0..=30_000).map(|k| k as f64 * 1e-4).collect();
        let r: Vec<f64> = t
            .iter()
            .map(|&v| if v >= 0.1 { 2.0 } else { 0.0 })
            .collect();
        let y: Vec<f64> = t
            .iter()
            .map(|&v| {
                if v < 0.1 {
                    0.0
                } else {
                    // A fast rise (τ = 10 ms) into a sine about the target.
                    let d = v - 0.1;
                    2.0 * (1.0 - (-d / 0.01).exp())
                        + 0.05 * (2.0 * core::f64::consts::PI * d / 0.04).sin()
                }
            })
            .collect();
        let m = step_metrics(&t, &y, &r, &[0.1], false)[0];
        let (p, a) = m.oscillation.expect("sustained");
        assert!((p - 0.04).abs() < 1e-5, "period {p}");
        assert!((a - 0.05).abs() < 1e-3, "amplitude {a}");
        assert!(m.settling.is_none());
    }
}
