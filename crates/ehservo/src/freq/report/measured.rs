//! The measured points read as numbers: the tracking −3 dB bandwidth and
//! the margins of the measured loop, by interpolation between neighbouring
//! frequencies.

use super::unwrap;
use crate::freq::measure::Measured;
use crate::freq::ss::C64;
use serde_json::{json, Value};
use std::f64::consts::PI;

/// The measured −3 dB bandwidth: the first frequency where |H|, log-log
/// interpolated between the measured points, falls 3 dB below the lowest
/// point's. Points are read in order up to the first that is missing (an
/// unbounded run) or of quality below 0.9: past it the bandwidth is only
/// known to be above the last point read.
pub(super) fn measured_bandwidth(pts: &[Measured]) -> Value {
    let mut good: Vec<(f64, C64)> = Vec::new();
    let mut stop = None;
    for m in pts {
        match m.theta_c() {
            Some(z) if m.quality >= 0.9 => good.push((m.f_hz, z)),
            _ => {
                stop = Some(m);
                break;
            }
        }
    }
    let Some(first) = good.first() else {
        return json!({"bandwidth_Hz": null, "why": "no measured point"});
    };
    let level = first.1.norm() * 10f64.powf(-3.0 / 20.0);
    for w in good.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b.1.norm() < level {
            let (la, lb) = (a.1.norm().ln(), b.1.norm().ln());
            let r = if (lb - la).abs() > 0.0 {
                (level.ln() - la) / (lb - la)
            } else {
                0.0
            };
            return json!({"bandwidth_Hz": (a.0.ln() + r * (b.0.ln() - a.0.ln())).exp()});
        }
    }
    let last = good.last().map(|g| g.0);
    let why = match stop {
        Some(m) if m.diverged_at_s.is_some() => format!(
            "the gain never fell 3 dB up to {:.4} Hz; the run at {:.4} Hz was unbounded",
            last.unwrap_or(0.0),
            m.f_hz
        ),
        Some(m) => format!(
            "the gain never fell 3 dB up to {:.4} Hz; at {:.4} Hz the response is distorted (quality {:.3} < 0.9)",
            last.unwrap_or(0.0),
            m.f_hz,
            m.quality
        ),
        None => format!(
            "the gain never fell 3 dB within the measured band (to {:.4} Hz)",
            last.unwrap_or(0.0)
        ),
    };
    json!({"bandwidth_Hz": null, "above_Hz": last, "why": why})
}

/// Margins of a measured loop L at the points (f, L), by interpolation
/// between neighbours (log |L| against log f, the unwrapped phase linear
/// in log f).
pub(super) fn measured_margins(pts: &[(f64, Option<C64>, f64)]) -> Value {
    let z: Vec<Option<C64>> = pts.iter().map(|p| p.1).collect();
    let ph = unwrap(&z);
    let mut gains = Vec::new();
    let mut phases = Vec::new();
    for i in 0..pts.len().saturating_sub(1) {
        // Neighbours only: no crossing is read across a missing point.
        let (Some(za), Some(zb), Some(pa), Some(pb)) = (z[i], z[i + 1], ph[i], ph[i + 1]) else {
            continue;
        };
        let (fa, fb) = (pts[i].0, pts[i + 1].0);
        let quality = pts[i].2.min(pts[i + 1].2);
        let (ga, gb) = (za.norm().ln(), zb.norm().ln());
        let at = |r: f64| (fa.ln() + r * (fb.ln() - fa.ln())).exp();
        if ga * gb <= 0.0 && (gb - ga).abs() > 0.0 {
            let r = -ga / (gb - ga);
            let f = at(r);
            let p = pa + r * (pb - pa);
            let pm = (p + 180.0).rem_euclid(360.0);
            let pm = if pm > 180.0 { pm - 360.0 } else { pm };
            let w = 2.0 * PI * f;
            gains.push(json!({
                "f_Hz": f,
                "phase_margin_deg": pm,
                "delay_margin_s": (pm >= 0.0).then(|| pm.to_radians() / w),
                "quality": quality,
            }));
        }
        // Crossings of −180° (mod 360°).
        let k = ((pa.min(pb) + 180.0) / 360.0).ceil();
        let target = -180.0 + 360.0 * k;
        if target <= pa.max(pb) && (pb - pa).abs() > 0.0 && target >= pa.min(pb) {
            let r = (target - pa) / (pb - pa);
            let f = at(r);
            let g = (ga + r * (gb - ga)).exp();
            phases.push(json!({"f_Hz": f, "gain_margin": 1.0 / g, "gain_margin_dB": -20.0 * g.log10(), "quality": quality}));
        }
    }
    let least = |v: &Vec<Value>, key: &str| -> Value {
        v.iter()
            .filter(|x| x[key].is_number())
            .min_by(|a, b| {
                a[key]
                    .as_f64()
                    .unwrap_or(f64::INFINITY)
                    .abs()
                    .total_cmp(&b[key].as_f64().unwrap_or(f64::INFINITY).abs())
            })
            .cloned()
            .unwrap_or(Value::Null)
    };
    let gm = phases
        .iter()
        .min_by(|a, b| {
            let la = a["gain_margin"]
                .as_f64()
                .unwrap_or(f64::INFINITY)
                .ln()
                .abs();
            let lb = b["gain_margin"]
                .as_f64()
                .unwrap_or(f64::INFINITY)
                .ln()
                .abs();
            la.total_cmp(&lb)
        })
        .cloned()
        .unwrap_or(Value::Null);
    json!({
        "gain_margin": gm,
        "phase_margin": least(&gains, "phase_margin_deg"),
        "delay_margin": least(&gains, "delay_margin_s"),
        "gain_crossovers": gains,
        "phase_crossovers": phases,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Measured margins of L = 1/(s(s + 1)²) sampled at 200 log-spaced
    /// points: the interpolated crossovers land within a grid cell of the
    /// exact ones (PM 21.386° at 0.682 rad/s, GM 2 at 1 rad/s).
    #[test]
    fn measured_margins_interpolate() {
        let pts: Vec<(f64, Option<C64>, f64)> = (0..200)
            .map(|i| {
                let f = 0.01 * 10f64.powf(3.0 * i as f64 / 199.0);
                let s = C64::new(0.0, 2.0 * PI * f);
                (f, Some(1.0 / (s * (s + 1.0) * (s + 1.0))), 1.0)
            })
            .collect();
        let m = measured_margins(&pts);
        let pm = m["phase_margin"]["phase_margin_deg"].as_f64().unwrap();
        assert!((pm - 21.386).abs() < 0.1, "{pm}");
        let gm = m["gain_margin"]["gain_margin"].as_f64().unwrap();
        assert!((gm - 2.0).abs() < 0.02, "{gm}");
    }
}
