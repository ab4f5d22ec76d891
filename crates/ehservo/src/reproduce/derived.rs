//! Metrics the paper's qualitative claims need, beyond SPEC §9.
//!
//! All use samples with t ≥ t_s (the transient end) unless said otherwise:
//!
//! | name | definition |
//! |---|---|
//! | `sigma_rms` | RMS of σ (rad/s²) — "the operating point is near the surface" |
//! | `capture_corr` | Pearson correlation of WᵀΦ with the lumped uncertainty of (19) — "WᵀΦ captures the dominant feature" |
//! | `capture_gain` | RMS(WᵀΦ)/RMS(uncertainty) |
//! | `w_drift` | (‖W‖(T) − ‖W‖(T/2))/‖W‖(T/2): growth of the weights over the second half of the whole run |
//! | `w128_pp` | peak-to-peak of w_128 over the last 5 s — "more oscillatory weight" |
//! | `e_hf_share` | share of the energy of e above 1.5× the reference frequency, over a whole number of reference periods ending at T — "higher frequencies" |
//! | `chattering_10ms` | c[u] = sqrt(Σ Δu_n²)/sqrt(Σ u_n²) over the samples on the common grid t_n = n·0.01 s (the paper's sample interval) with t_n ≥ t_s, Δu_n = u_n − u_{n−1} — "u is smooth / chatters" |
//!
//! SPEC §9's `chattering` sums over every sample, so it depends on the step:
//! for the same smooth u, Δu per sample shrinks with h and c[u] with it
//! (0.0063 at 1 ms against 0.063 at 10 ms for a 1 Hz sine). Readings with
//! different steps are compared on `chattering_10ms`, which every reading's
//! step (a divisor of 0.01 s) samples identically.
//!
//! Each is `None` when it is undefined (diverged run, no network, zero
//! variance), never NaN.

use crate::metrics::Metrics;
use crate::simulation::Sample;
use serde::Serialize;

/// SPEC §9 metrics plus the derived ones.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CaseMetrics {
    /// SPEC §9.
    pub base: Metrics,
    /// RMS of σ after t_s.
    pub sigma_rms: Option<f64>,
    /// corr(WᵀΦ, uncertainty) after t_s.
    pub capture_corr: Option<f64>,
    /// RMS(WᵀΦ)/RMS(uncertainty) after t_s.
    pub capture_gain: Option<f64>,
    /// Relative growth of ‖W‖ over the second half of the run.
    pub w_drift: Option<f64>,
    /// Peak-to-peak of w_128 over the last 5 s.
    pub w128_pp: Option<f64>,
    /// Share of e's energy above 1.5·f_ref.
    pub e_hf_share: Option<f64>,
    /// c[u] on the common 10 ms grid after t_s.
    pub chattering_10ms: Option<f64>,
}

/// The derived metrics' names (the base ones are [`Metrics::NAMES`]).
const DERIVED: [&str; 7] = [
    "sigma_rms",
    "capture_corr",
    "capture_gain",
    "w_drift",
    "w128_pp",
    "e_hf_share",
    "chattering_10ms",
];

/// The common grid of `chattering_10ms`: the paper's sample interval (s).
pub const CHATTER_GRID: f64 = 0.01;

/// Whether `name` is a metric [`CaseMetrics::get`] knows.
pub fn is_metric(name: &str) -> bool {
    Metrics::NAMES.contains(&name) || DERIVED.contains(&name)
}

/// Units and digits for display.
pub fn format_metric(name: &str, v: f64) -> String {
    match name {
        "e_max_deg" | "e_final_deg" | "e_rms_deg" => format!("{v:.4}°"),
        "u_max" | "u_rms" => format!("{v:.3} V"),
        "diverged_at_s" => format!("{v:.2} s"),
        "dead_zone_fraction" | "e_hf_share" => format!("{:.1} %", 100.0 * v),
        "w_drift" => format!("{:+.2} %", 100.0 * v),
        _ => {
            if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e4) {
                format!("{v:.3e}")
            } else {
                format!("{v:.4}")
            }
        }
    }
}

impl From<Metrics> for CaseMetrics {
    /// The SPEC §9 metrics alone, every derived one undefined (None).
    fn from(base: Metrics) -> Self {
        Self {
            base,
            sigma_rms: None,
            capture_corr: None,
            capture_gain: None,
            w_drift: None,
            w128_pp: None,
            e_hf_share: None,
            chattering_10ms: None,
        }
    }
}

impl CaseMetrics {
    /// A metric by name.
    pub fn get(&self, name: &str) -> Option<f64> {
        match name {
            "sigma_rms" => self.sigma_rms,
            "capture_corr" => self.capture_corr,
            "capture_gain" => self.capture_gain,
            "w_drift" => self.w_drift,
            "w128_pp" => self.w128_pp,
            "e_hf_share" => self.e_hf_share,
            "chattering_10ms" => self.chattering_10ms,
            _ => self.base.get(name),
        }
    }

    /// Computes the derived metrics from a full trace (every sample).
    pub fn from_trace(
        base: Metrics,
        trace: &[Sample],
        settle: f64,
        horizon: f64,
        f_ref: f64,
        network: bool,
    ) -> Self {
        let finite = |v: f64| if v.is_finite() { Some(v) } else { None };
        let tol = 1e-9 * horizon.max(1.0);
        let after: Vec<&Sample> = trace.iter().filter(|s| s.t >= settle - tol).collect();
        let ok = !base.diverged && !after.is_empty();

        let sigma_rms = if ok {
            finite(
                (after
                    .iter()
                    .map(|s| s.part("sigma") * s.part("sigma"))
                    .sum::<f64>()
                    / after.len() as f64)
                    .sqrt(),
            )
        } else {
            None
        };

        let (capture_corr, capture_gain) = if ok && network {
            let n = after.len() as f64;
            let mx = after.iter().map(|s| s.part("wphi")).sum::<f64>() / n;
            let my = after.iter().map(|s| s.part("uncertainty")).sum::<f64>() / n;
            let (mut sxy, mut sxx, mut syy, mut qx, mut qy) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for s in &after {
                let (x, y) = (s.part("wphi") - mx, s.part("uncertainty") - my);
                sxy += x * y;
                sxx += x * x;
                syy += y * y;
                qx += s.part("wphi") * s.part("wphi");
                qy += s.part("uncertainty") * s.part("uncertainty");
            }
            let corr = if sxx > 0.0 && syy > 0.0 {
                finite(sxy / (sxx * syy).sqrt())
            } else {
                None
            };
            let gain = if qy > 0.0 {
                finite((qx / qy).sqrt())
            } else {
                None
            };
            (corr, gain)
        } else {
            (None, None)
        };

        let w_drift = if !base.diverged && network && trace.len() > 2 {
            let last = trace[trace.len() - 1];
            let mid_t = 0.5 * last.t;
            let mid = trace
                .iter()
                .find(|s| s.t >= mid_t - tol)
                .copied()
                .unwrap_or(last);
            let mid_w = mid.part("w_norm");
            if mid_w > 0.0 {
                finite((last.part("w_norm") - mid_w) / mid_w)
            } else {
                None
            }
        } else {
            None
        };

        let w128_pp = if !base.diverged && network && !trace.is_empty() {
            let t_end = trace[trace.len() - 1].t;
            let tail = trace.iter().filter(|s| s.t >= t_end - 5.0 - tol);
            let (lo, hi) = tail.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
                (lo.min(s.part("w_128")), hi.max(s.part("w_128")))
            });
            finite(hi - lo)
        } else {
            None
        };

        let e_hf_share = if ok {
            hf_share(&after, f_ref, horizon)
        } else {
            None
        };

        let chattering_10ms = chattering_on_grid(trace, settle, CHATTER_GRID);

        Self {
            base,
            sigma_rms,
            capture_corr,
            capture_gain,
            w_drift,
            w128_pp,
            e_hf_share,
            chattering_10ms,
        }
    }
}

/// c[u] over the samples on the grid t_n = n·`grid` with t_n ≥ `settle`;
/// Δu_n needs the sample at n − 1 (the first one after t_s uses the one
/// before it, as SPEC §9). A sample is on the grid when t is within 1e-6
/// of a grid step of n·grid (t_k = k·h is rounded, never exactly n·grid).
fn chattering_on_grid(trace: &[Sample], settle: f64, grid: f64) -> Option<f64> {
    let tol = 1e-6 * grid;
    let (mut u_sq, mut du_sq, mut pairs) = (0.0, 0.0, 0usize);
    let mut prev: Option<(i64, f64)> = None;
    for s in trace {
        let n = (s.t / grid).round();
        if (s.t - n * grid).abs() > tol {
            continue;
        }
        let n = n as i64;
        if s.t >= settle - tol {
            u_sq += s.u * s.u;
            if let Some((m, pu)) = prev {
                if m == n - 1 {
                    du_sq += (s.u - pu) * (s.u - pu);
                    pairs += 1;
                }
            }
        }
        prev = Some((n, s.u));
    }
    (u_sq > 0.0 && pairs > 0)
        .then(|| (du_sq / u_sq).sqrt())
        .filter(|c| c.is_finite())
}

/// Share of the energy of e above 1.5·f_ref over the largest whole number of
/// reference periods that ends at the last sample. Energy below the cut is
/// summed from DFT bins at multiples of 1/T_w (Parseval: total energy is
/// Σ e², two-sided bins counted twice except DC).
fn hf_share(after: &[&Sample], f_ref: f64, horizon: f64) -> Option<f64> {
    if after.len() < 8 {
        return None;
    }
    let t_end = after[after.len() - 1].t;
    let span = t_end - after[0].t;
    let periods = (span * f_ref + 1e-9).floor();
    if periods < 1.0 {
        return None;
    }
    let t_w = periods / f_ref;
    let tol = 1e-9 * horizon.max(1.0);
    // Samples in (t_end − t_w, t_end]: exactly N = t_w/h of them.
    let win: Vec<f64> = after
        .iter()
        .filter(|s| s.t > t_end - t_w + tol)
        .map(|s| s.e)
        .collect();
    let n = win.len();
    if n < 8 {
        return None;
    }
    let total: f64 = win.iter().map(|e| e * e).sum();
    if total <= 0.0 {
        return None;
    }
    // Bins m = 0..M with f_m = m/t_w ≤ 1.5 f_ref, M = floor(1.5·periods).
    let m_max = (1.5 * periods).floor() as usize;
    let mut low = 0.0;
    for m in 0..=m_max.min(n / 2) {
        let w = 2.0 * std::f64::consts::PI * m as f64 / n as f64;
        let (mut re, mut im) = (0.0, 0.0);
        for (k, e) in win.iter().enumerate() {
            let a = w * k as f64;
            re += e * a.cos();
            im -= e * a.sin();
        }
        let p = (re * re + im * im) / n as f64;
        low += if m == 0 || 2 * m == n { p } else { 2.0 * p };
    }
    let share = 1.0 - low / total;
    Some(share.clamp(0.0, 1.0))
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    fn samples(h: f64, n: usize, e: impl Fn(f64) -> f64) -> Vec<Sample> {
        (0..n)
            .map(|k| {
                let t = k as f64 * h;
                Sample {
                    k: k as u64,
                    t,
                    e: e(t),
                    ..Default::default()
                }
            })
            .collect()
    }

    /// A pure 1 Hz sine has no energy above 1.5 Hz; adding a 3 Hz sine of
    /// amplitude 0.5 puts 0.25/(1 + 0.25) = 20 % of the energy above the cut
    /// (mean squares 1/2 and 1/8).
    #[test]
    fn hf_share_of_known_signals() {
        let pi2 = 2.0 * std::f64::consts::PI;
        let s = samples(0.01, 1001, |t| (pi2 * t).sin());
        let refs: Vec<&Sample> = s.iter().filter(|x| x.t >= 2.0 - 1e-9).collect();
        assert!(hf_share(&refs, 1.0, 10.0).unwrap() < 1e-9);
        let s = samples(0.01, 1001, |t| {
            (pi2 * t).sin() + 0.5 * (3.0 * pi2 * t).sin()
        });
        let refs: Vec<&Sample> = s.iter().filter(|x| x.t >= 2.0 - 1e-9).collect();
        assert!((hf_share(&refs, 1.0, 10.0).unwrap() - 0.2).abs() < 1e-9);
    }

    /// The same smooth u = sin 2πt sampled at 1 ms and at 10 ms: SPEC §9's
    /// per-sample index differs tenfold, the 10 ms-grid one not at all.
    /// On the grid Δu_n ≈ 2π·0.01·cos 2πt_n, so c[u] ≈ 2π·0.01 = 0.0628
    /// (mean squares of sin and cos equal over whole periods).
    #[test]
    fn chattering_on_the_common_grid_ignores_the_step() {
        let pi2 = 2.0 * std::f64::consts::PI;
        let trace = |h: f64, n: usize| -> Vec<Sample> {
            (0..n)
                .map(|k| {
                    let t = k as f64 * h;
                    Sample {
                        k: k as u64,
                        t,
                        u: (pi2 * t).sin(),
                        ..Default::default()
                    }
                })
                .collect()
        };
        let fine = chattering_on_grid(&trace(0.001, 10_001), 2.0, 0.01).unwrap();
        let coarse = chattering_on_grid(&trace(0.01, 1001), 2.0, 0.01).unwrap();
        assert!((fine - coarse).abs() < 1e-12, "{fine} vs {coarse}");
        assert!((coarse - 0.0628).abs() < 2e-3, "{coarse}");
        // A trace thinned to every 20 ms has no neighbours on the grid.
        let mut even = trace(0.01, 1001);
        even.retain(|s| s.k % 2 == 0);
        assert_eq!(chattering_on_grid(&even, 2.0, 0.01), None);
    }

    #[test]
    fn names_are_known() {
        for n in Metrics::NAMES.iter().chain(DERIVED.iter()) {
            assert!(is_metric(n));
        }
        assert!(!is_metric("e_max"));
    }
}
