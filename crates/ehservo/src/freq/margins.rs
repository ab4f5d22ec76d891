//! Stability margins of a loop transfer function `L(ω)`, found on a dense
//! logarithmic grid and refined by regula falsi (crossings, Illinois) and golden-section
//! search (the smallest distance to −1), every search bounded.
//!
//! The conventions are python-control's `stability_margins` (its
//! `margins.py`), so the two can be compared number for number:
//!
//! - a **phase crossover** is a frequency where `Im L = 0` and `Re L ≤ 0`;
//!   its gain margin is `1/|L|`; the reported gain margin is the one of all
//!   the crossovers closest to 1 on a log scale (`min |ln GM|`);
//! - a **gain crossover** is where `|L| = 1`; its phase margin is
//!   `mod(∠L, 360°) − 180°`; the reported phase margin is the one of least
//!   magnitude;
//! - the **stability margin** is `min |1 + L| = 1/Ms`.
//!
//! To those the **delay margin** of each gain crossover: the extra delay
//! `τ = PM/ω_c` (PM in radians) that rotates `L(jω_c)` onto −1; the loop's
//! delay margin is the least over its crossovers (of non-negative phase
//! margin), in seconds and in samples of the loop's period. Every crossover
//! is reported, and the worst of each kind.
//!
//! In discrete time the grid ends just below the Nyquist frequency π/h
//! (python-control does not count z = −1 either).

use super::ss::C64;
use serde::Serialize;
use std::f64::consts::PI;

/// Grid points per decade of the crossing search.
pub const POINTS_PER_DECADE: usize = 400;

/// Bisection steps refining a crossing (from a grid cell of 1/400 decade,
/// 60 halvings reach the float's resolution).
pub const BISECTIONS: usize = 60;

/// A phase crossover.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PhaseCrossover {
    /// Frequency (Hz).
    #[serde(rename = "f_Hz")]
    pub f_hz: f64,
    /// Frequency (rad/s).
    pub omega_rad_s: f64,
    /// The gain margin 1/|L| there.
    pub gain_margin: f64,
    /// The same in dB.
    #[serde(rename = "gain_margin_dB")]
    pub gain_margin_db: f64,
}

/// A gain crossover.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GainCrossover {
    /// Frequency (Hz).
    #[serde(rename = "f_Hz")]
    pub f_hz: f64,
    /// Frequency (rad/s).
    pub omega_rad_s: f64,
    /// The phase margin there (deg).
    pub phase_margin_deg: f64,
    /// The extra delay that brings L there onto −1 (s); None for a
    /// negative phase margin.
    pub delay_margin_s: Option<f64>,
    /// The same in samples of the loop's period (discrete loops).
    pub delay_margin_samples: Option<f64>,
}

/// The smallest distance of the Nyquist curve to −1.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StabilityMargin {
    /// Frequency (Hz).
    #[serde(rename = "f_Hz")]
    pub f_hz: f64,
    /// Frequency (rad/s).
    pub omega_rad_s: f64,
    /// min |1 + L| (= 1/Ms).
    pub distance: f64,
}

/// Every margin of a loop.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Margins {
    /// The reported (worst) gain margin: python-control's choice.
    pub gain_margin: Option<PhaseCrossover>,
    /// The reported (worst) phase margin.
    pub phase_margin: Option<GainCrossover>,
    /// The least delay margin over the gain crossovers (s, samples).
    pub delay_margin: Option<GainCrossover>,
    /// min |1 + L|.
    pub stability_margin: Option<StabilityMargin>,
    /// Every phase crossover, by frequency.
    pub phase_crossovers: Vec<PhaseCrossover>,
    /// Every gain crossover, by frequency.
    pub gain_crossovers: Vec<GainCrossover>,
    /// The searched band (rad/s).
    pub searched_rad_s: [f64; 2],
}

/// A frequency grid, log-spaced over `[lo, hi]` (rad/s).
pub fn log_grid(lo: f64, hi: f64, per_decade: usize) -> Vec<f64> {
    let decades = (hi / lo).log10().max(0.0);
    let n = ((decades * per_decade as f64).ceil() as usize).max(2);
    (0..=n)
        .map(|i| lo * (hi / lo).powf(i as f64 / n as f64))
        .collect()
}

/// The root of `g` between `a` and `b` (a sign change) on log ω, by the
/// Illinois variant of regula falsi (Dowell & Jarratt, BIT 11:168–174,
/// 1971): superlinear (order ≈ 1.44), the bracket kept, so a dozen
/// evaluations do what [`BISECTIONS`] halvings do. A step that leaves the
/// bracket or a value that is not finite falls back to halving; at most
/// [`BISECTIONS`] evaluations.
fn bisect(g: &dyn Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let (mut xa, mut xb) = (a.ln(), b.ln());
    let (mut fa, mut fb) = (g(a), g(b));
    if !(fa.is_finite() && fb.is_finite()) || fa * fb > 0.0 {
        return halve(g, a, b);
    }
    // The last two steps' sides: Illinois halves the retained end's value
    // when the same end is kept twice running.
    let mut kept_a = false;
    for _ in 0..BISECTIONS {
        if fa == 0.0 {
            return xa.exp();
        }
        if fb == 0.0 || (xb - xa).abs() <= 4.0 * f64::EPSILON * xa.abs().max(xb.abs()).max(1.0) {
            return xb.exp();
        }
        let mut x = (xa * fb - xb * fa) / (fb - fa);
        if !(x > xa.min(xb) && x < xa.max(xb)) {
            x = 0.5 * (xa + xb);
        }
        let mut fx = g(x.exp());
        if !fx.is_finite() {
            x = 0.5 * (xa + xb);
            fx = g(x.exp());
            if !fx.is_finite() {
                return halve(g, xa.min(xb).exp(), xa.max(xb).exp());
            }
        }
        if fx == 0.0 || (x - xb).abs() <= 4.0 * f64::EPSILON * x.abs().max(1.0) {
            return x.exp();
        }
        if (fx > 0.0) == (fb > 0.0) {
            // The new point replaces b; a is kept.
            if kept_a {
                fa *= 0.5;
            }
            kept_a = true;
        } else {
            // The sign changed: b moves to a.
            xa = xb;
            fa = fb;
            kept_a = false;
        }
        xb = x;
        fb = fx;
    }
    xb.exp()
}

/// Bisection of `g` on log ω ([`BISECTIONS`] halvings): where the
/// Illinois step cannot start (a value that is not finite at an end).
fn halve(g: &dyn Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    let mut ga = g(a);
    for _ in 0..BISECTIONS {
        let m = (a * b).sqrt();
        if m <= a || m >= b {
            break;
        }
        let gm = g(m);
        if gm == 0.0 {
            return m;
        }
        if (gm > 0.0) == (ga > 0.0) {
            a = m;
            ga = gm;
        } else {
            b = m;
        }
    }
    (a * b).sqrt()
}

/// Golden-section search for the minimum of `g` on `[a, b]` (log ω).
fn golden(g: &dyn Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let (mut lo, mut hi) = (a.ln(), b.ln());
    let mut x1 = hi - r * (hi - lo);
    let mut x2 = lo + r * (hi - lo);
    let (mut f1, mut f2) = (g(x1.exp()), g(x2.exp()));
    for _ in 0..200 {
        if hi - lo <= 1e-15 * hi.abs().max(1.0) {
            break;
        }
        if f1 < f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - r * (hi - lo);
            f1 = g(x1.exp());
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + r * (hi - lo);
            f2 = g(x2.exp());
        }
    }
    ((lo + hi) / 2.0).exp()
}

/// python-control's phase margin of a value of L: `mod(∠L, 360) − 180`.
pub fn phase_margin_of(l: C64) -> f64 {
    l.arg().to_degrees().rem_euclid(360.0) - 180.0
}

/// The margins of `l` over `[lo, hi]` rad/s; `h` the loop's period (for
/// delays in samples), None in continuous time.
pub fn margins(l: &dyn Fn(f64) -> Option<C64>, lo: f64, hi: f64, h: Option<f64>) -> Margins {
    margins_on(l, lo, hi, h, POINTS_PER_DECADE, true, &[])
}

/// Where a lightly damped pole or zero of L makes its curve turn faster
/// than a logarithmic grid can follow: for each with natural frequency
/// ω_n and damping |ζ| < 0.5 (s, or s = ln(z)/h of a discrete one), the
/// frequencies ω_n·(1 + k·|ζ|), k ∈ ±{0, ¼, ½, 1, 1.5, 2, 3, 6}. Across
/// ±|ζ|·ω_n its phase swings through most of its 180° and its gain peaks
/// by 1/(2|ζ|): at ζ = 0.01 that band is 2 % of ω_n wide, a fifth of a
/// 25-point-per-decade grid's cell, and a pair of crossings inside one
/// cell is missed (the slide of issue #45: a PID accepted with 0.9 dB of
/// gain margin at its 13 Hz resonance). Merged into the grid, these put
/// points on both sides of every such swing.
pub fn resonance_points(roots: &[C64], dt: Option<f64>) -> Vec<f64> {
    const K: [f64; 15] = [
        -6.0, -3.0, -2.0, -1.5, -1.0, -0.5, -0.25, 0.0, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 6.0,
    ];
    let mut out = Vec::new();
    for &r in roots {
        let s = match dt {
            Some(h) if r.norm() > 0.0 && h > 0.0 => r.ln() / h,
            Some(_) => continue,
            None => r,
        };
        let wn = s.norm();
        if !(wn.is_finite() && wn > 0.0) {
            continue;
        }
        let zeta = (-s.re / wn).abs().max(1e-9);
        if zeta >= 0.5 {
            continue;
        }
        out.extend(K.iter().map(|k| wn * (1.0 + k * zeta)).filter(|w| *w > 0.0));
    }
    out
}

/// [`margins`] on a grid of `per_decade` points per decade with the
/// `features` ([`resonance_points`]) merged in (crossings are refined
/// whatever the grid; a coarser grid can only miss a pair of crossings
/// closer than its cell), with the stability margin min |1 + L| searched
/// or not (None).
pub fn margins_on(
    l: &dyn Fn(f64) -> Option<C64>,
    lo: f64,
    hi: f64,
    h: Option<f64>,
    per_decade: usize,
    with_stability_margin: bool,
    features: &[f64],
) -> Margins {
    let mut grid = log_grid(lo, hi, per_decade);
    grid.extend(features.iter().copied().filter(|w| *w > lo && *w < hi));
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    let c = crossings(l, &grid);
    let hz = |w: f64| w / (2.0 * PI);
    let gain_crossovers: Vec<GainCrossover> = c
        .gains
        .iter()
        .filter_map(|&w| {
            let pm = phase_margin_of(l(w)?);
            let dm = (pm >= 0.0).then(|| pm.to_radians() / w);
            Some(GainCrossover {
                f_hz: hz(w),
                omega_rad_s: w,
                phase_margin_deg: pm,
                delay_margin_s: dm,
                delay_margin_samples: dm.and_then(|d| h.map(|h| d / h)),
            })
        })
        .collect();
    let phase_crossovers: Vec<PhaseCrossover> = c
        .phases
        .iter()
        .filter_map(|&w| {
            let z = l(w)?;
            let gm = 1.0 / z.norm();
            gm.is_finite().then(|| PhaseCrossover {
                f_hz: hz(w),
                omega_rad_s: w,
                gain_margin: gm,
                gain_margin_db: 20.0 * gm.log10(),
            })
        })
        .collect();
    let stability_margin = with_stability_margin
        .then(|| stability_margin(l, &c.minima, &grid))
        .flatten();
    let gain_margin = phase_crossovers.iter().copied().min_by(|a, b| {
        a.gain_margin
            .ln()
            .abs()
            .total_cmp(&b.gain_margin.ln().abs())
    });
    let phase_margin = gain_crossovers.iter().copied().min_by(|a, b| {
        a.phase_margin_deg
            .abs()
            .total_cmp(&b.phase_margin_deg.abs())
    });
    let delay_margin = gain_crossovers
        .iter()
        .copied()
        .filter(|g| g.delay_margin_s.is_some())
        .min_by(|a, b| {
            a.delay_margin_s
                .unwrap_or(f64::INFINITY)
                .total_cmp(&b.delay_margin_s.unwrap_or(f64::INFINITY))
        });
    Margins {
        gain_margin,
        phase_margin,
        delay_margin,
        stability_margin,
        phase_crossovers,
        gain_crossovers,
        searched_rad_s: [lo, hi],
    }
}

/// Where L crosses what the margins read, found on a grid and refined.
struct Crossings {
    /// Gain crossovers, |L| = 1 (rad/s).
    gains: Vec<f64>,
    /// Phase crossovers, Im L = 0 with Re L ≤ 0 (rad/s).
    phases: Vec<f64>,
    /// Brackets (rad/s) of the local minima of |1 + L| inside the grid.
    minima: Vec<(f64, f64)>,
}

/// The crossings of `l` between neighbours of `grid`: the gain and phase
/// crossovers refined by bisection, the minima of |1 + L| bracketed.
fn crossings(l: &dyn Fn(f64) -> Option<C64>, grid: &[f64]) -> Crossings {
    let vals: Vec<Option<C64>> = grid.iter().map(|&w| l(w)).collect();
    let mag = |w: f64| l(w).map_or(f64::NAN, |z| z.norm() - 1.0);
    let imag = |w: f64| l(w).map_or(f64::NAN, |z| z.im);
    let mut gains = Vec::new();
    let mut phases = Vec::new();
    let mut minima = Vec::new();
    for i in 0..grid.len() - 1 {
        let (Some(a), Some(b)) = (vals[i], vals[i + 1]) else {
            continue;
        };
        let (w0, w1) = (grid[i], grid[i + 1]);
        // Gain crossovers.
        let (ma, mb) = (a.norm() - 1.0, b.norm() - 1.0);
        if ma == 0.0 {
            gains.push(w0);
        } else if ma * mb < 0.0 {
            gains.push(bisect(&mag, w0, w1));
        }
        // Phase crossovers (Im L = 0 with Re L ≤ 0).
        if a.im == 0.0 {
            if a.re <= 0.0 {
                phases.push(w0);
            }
        } else if a.im * b.im < 0.0 && (a.re <= 0.0 || b.re <= 0.0) {
            let w = bisect(&imag, w0, w1);
            if let Some(z) = l(w) {
                // A sign change through infinity (a pole near the unit
                // circle) is no crossing: the value found must be small.
                if z.re <= 0.0 && z.im.abs() <= 1e-6 * z.norm() {
                    phases.push(w);
                }
            }
        }
        // Local minima of |1 + L| (interior of the grid).
        if i > 0 {
            if let Some(p) = vals[i - 1] {
                let (dp, d0, d1) = ((p + 1.0).norm(), (a + 1.0).norm(), (b + 1.0).norm());
                if d0 <= dp && d0 < d1 {
                    minima.push((grid[i - 1], w1));
                }
            }
        }
    }
    Crossings {
        gains,
        phases,
        minima,
    }
}

/// The least distance of L from −1: over the bracketed minima (refined by
/// golden section) and the ends of the band.
fn stability_margin(
    l: &dyn Fn(f64) -> Option<C64>,
    minima: &[(f64, f64)],
    grid: &[f64],
) -> Option<StabilityMargin> {
    let hz = |w: f64| w / (2.0 * PI);
    let dist = |w: f64| l(w).map_or(f64::INFINITY, |z| (z + 1.0).norm());
    minima
        .iter()
        .map(|&(a, b)| {
            let w = golden(&dist, a, b);
            StabilityMargin {
                f_hz: hz(w),
                omega_rad_s: w,
                distance: dist(w),
            }
        })
        .chain(
            // The ends of the band, when the least distance is there.
            [grid[0], grid[grid.len() - 1]]
                .iter()
                .map(|&w| StabilityMargin {
                    f_hz: hz(w),
                    omega_rad_s: w,
                    distance: dist(w),
                }),
        )
        .filter(|s| s.distance.is_finite())
        .min_by(|a, b| a.distance.total_cmp(&b.distance))
}

/// The first frequency in `[lo, hi]` (rad/s) where `|H|` falls below `dc`
/// by 3 dB (`|dc|·10^{−3/20}`), refined by bisection; None when it never
/// does in the band.
pub fn bandwidth(h: &dyn Fn(f64) -> Option<C64>, dc: f64, lo: f64, hi: f64) -> Option<f64> {
    let level = dc.abs() * 10f64.powf(-3.0 / 20.0);
    let g = |w: f64| h(w).map_or(f64::NAN, |z| z.norm() - level);
    let grid = log_grid(lo, hi, POINTS_PER_DECADE);
    let mut prev = grid[0];
    if g(prev) < 0.0 {
        return Some(prev);
    }
    for &w in &grid[1..] {
        if g(w) < 0.0 {
            return Some(bisect(&g, prev, w));
        }
        prev = w;
    }
    None
}

/// The peak of `|H|` over `[lo, hi]`: (frequency rad/s, |H|), the grid's
/// largest refined by golden-section search.
pub fn peak(h: &dyn Fn(f64) -> Option<C64>, lo: f64, hi: f64) -> Option<(f64, f64)> {
    let grid = log_grid(lo, hi, POINTS_PER_DECADE);
    let mag = |w: f64| h(w).map_or(f64::NAN, |z| z.norm());
    let (i, m) = grid
        .iter()
        .map(|&w| mag(w))
        .enumerate()
        .filter(|(_, m)| m.is_finite())
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    let (a, b) = (grid[i.saturating_sub(1)], grid[(i + 1).min(grid.len() - 1)]);
    let w = golden(&|w| -mag(w), a, b);
    let mw = mag(w);
    Some(if mw >= m { (w, mw) } else { (grid[i], m) })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Illinois refinement of a crossing: |L| − 1 of the double lag
    /// above, 1/(ω·(1 + ω²)) − 1, crosses at the real root of
    /// ω³ + ω − 1 = 0, ω = 0.682327803828019 (Cardano:
    /// ∛(1/2 + √(31/108)) + ∛(1/2 − √(31/108))), found from a grid cell
    /// [0.5, 1] to 1e-14 in at most 16 evaluations (halving needs 60).
    #[test]
    fn a_crossing_is_refined_superlinearly() {
        let n = std::cell::Cell::new(0usize);
        let g = |w: f64| {
            n.set(n.get() + 1);
            1.0 / (w * (1.0 + w * w)) - 1.0
        };
        let r = (31.0f64 / 108.0).sqrt();
        let want = (0.5 + r).cbrt() + (0.5 - r).cbrt();
        let got = bisect(&g, 0.5, 1.0);
        assert!((got - want).abs() < 1e-14 * want, "{got} vs {want}");
        assert!(n.get() <= 16, "{} evaluations", n.get());
    }

    /// L(s) = K/(s(s + 1)²) with K = 1, by hand: the phase crosses −180°
    /// where 2·atan(ω) = 90°, ω = 1, |L(j)| = 1/(1·2) = 0.5: GM = 2
    /// (6.02 dB). |L| = 1 where ω(1 + ω²) = 1: ω = 0.6823278 (the real
    /// root of ω³ + ω − 1); PM = 180° − 90° − 2·atan(ω) = 90° − 2·34.30681°
    /// = 21.38639°; delay margin PM/ω = 0.373262 rad / 0.682328 rad/s
    /// = 0.547043 s.
    #[test]
    fn margins_of_an_integrator_and_a_double_lag_by_hand() {
        let l = |w: f64| {
            let s = C64::new(0.0, w);
            Some(1.0 / (s * (s + 1.0) * (s + 1.0)))
        };
        let m = margins(&l, 1e-3, 1e3, None);
        let gm = m.gain_margin.unwrap();
        assert!((gm.omega_rad_s - 1.0).abs() < 1e-12, "{gm:?}");
        assert!((gm.gain_margin - 2.0).abs() < 1e-12);
        let pm = m.phase_margin.unwrap();
        let wc = 0.682_327_803_828_019_3;
        assert!((pm.omega_rad_s - wc).abs() < 1e-12, "{pm:?}");
        let want = 90.0 - 2.0 * wc.atan().to_degrees();
        assert!((pm.phase_margin_deg - want).abs() < 1e-10, "{pm:?}");
        assert!((pm.phase_margin_deg - 21.38639).abs() < 1e-5);
        let dm = m.delay_margin.unwrap().delay_margin_s.unwrap();
        assert!((dm - want.to_radians() / wc).abs() < 1e-12);
        assert!((dm - 0.547043).abs() < 1e-6, "{dm}");
        assert_eq!(m.gain_crossovers.len(), 1);
        assert_eq!(m.phase_crossovers.len(), 1);
    }

    /// A pure delay around a gain k < 1 never crosses |L| = 1; with
    /// L = 2·e^{−jω} the phase crosses −180° at ω = π, 3π, 5π, … each with
    /// GM = 1/2, and |L| never equals 1.
    #[test]
    fn every_crossover_is_found() {
        let l = |w: f64| Some(C64::from_polar(2.0, -w));
        let m = margins(&l, 0.1, 20.0, None);
        let ws: Vec<f64> = m.phase_crossovers.iter().map(|p| p.omega_rad_s).collect();
        assert_eq!(ws.len(), 3, "{ws:?}");
        for (w, k) in ws.iter().zip([1.0, 3.0, 5.0]) {
            assert!((w - k * PI).abs() < 1e-10, "{w}");
        }
        assert!(m.gain_crossovers.is_empty());
        // min |1 + L| = 1 at every phase crossover.
        assert!((m.stability_margin.unwrap().distance - 1.0).abs() < 1e-9);
    }

    /// −3 dB of 1/(s/10 + 1) is at ω = 10 rad/s.
    #[test]
    fn bandwidth_of_a_lag() {
        let h = |w: f64| Some(1.0 / (C64::new(0.0, w / 10.0) + 1.0));
        let b = bandwidth(&h, 1.0, 1e-2, 1e3).unwrap();
        // |H| = 10^{−3/20} exactly at ω = 10·sqrt(10^{0.3} − 1) = 9.9763.
        let want = 10.0 * (10f64.powf(0.3) - 1.0).sqrt();
        assert!((b - want).abs() < 1e-10, "{b} vs {want}");
    }
}
