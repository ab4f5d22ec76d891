//! What `ehservo freq` writes: `freq.json` (the settings, the computed
//! margins and peaks, the measured bandwidth and loop margins, the terminal
//! lines beside it), `linearization.json`, and the CSV tables of the
//! computed and measured curves; the figures are drawn in `figures`.

use super::figures::{bode, measured_plot, nyquist};
use super::measured::{measured_bandwidth, measured_margins};
use super::{db, unwrap, FreqOptions, FreqSummary, MeasuredSet};
use crate::axis::Axis;
use crate::freq::margins::{self, Margins};
use crate::freq::measure::{Measured, Settings};
use crate::freq::response::{curves, LoopModel, Responses};
use crate::freq::ss::{pair, C64};
use crate::freq::{linearisation_json, Linearised};
use crate::output::Staging;
use crate::scenario::{Loop, Scenario};
use anyhow::{Context, Result};
use serde_json::json;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A CSV cell: the number, or empty.
fn cell(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:e}"),
        _ => String::new(),
    }
}

#[allow(clippy::too_many_arguments)]
pub(super) fn write(
    setup: &Loop,
    o: &FreqOptions,
    computed: &std::result::Result<Linearised, String>,
    sets: &[MeasuredSet],
    f_max: f64,
    settings: Settings,
    stage: Staging,
) -> Result<FreqSummary> {
    let s = setup.scenario();
    let axis = setup.axis();
    let mut out = Out {
        dir: stage.path().to_path_buf(),
        files: Vec::new(),
        text: String::new(),
        axis,
    };
    let h = setup.sim().step;
    let freqs: Vec<f64> = (0..o.points)
        .map(|i| o.f_min * (f_max / o.f_min).powf(i as f64 / (o.points - 1) as f64))
        .collect();
    let mut summary = json!({
        "scenario": s.name,
        "ehservo": env!("CARGO_PKG_VERSION"),
        "controller": s.controller.kind(),
        "mode": setup.sim().mode.as_str(),
        "dt_s": h,
        "nyquist_Hz": 0.5 / h,
        "grid": {"f_min_Hz": o.f_min, "f_max_Hz": f_max, "points": o.points},
        "curves": curves(axis).iter().map(|(n, u, d)| json!({"name": n, "unit": u, "what": d, "gain_dB": format!("20·log10 |{n}| re 1 {}", if u.is_empty() { "(dimensionless)" } else { u })})).collect::<Vec<_>>(),
    });
    let mut responses: Vec<Responses> = Vec::new();
    let mut lp_opt = None;
    match computed {
        Ok(l) => {
            lp_opt = Some(&l.lp);
            let (computed_json, rs) = out.computed(s, l, &freqs, f_max, h, axis)?;
            responses = rs;
            summary["computed"] = computed_json;
        }
        Err(why) => {
            summary["computed"] = json!({"not_computed": why});
            let _ = writeln!(out.text, "computed curves: not available ({why})");
        }
    }
    let measured_json = out.measured(sets, lp_opt, axis)?;
    let mut excitation = serde_json::Map::new();
    match axis {
        // The keys and bits the paper's outputs always had.
        Axis::Rotary => {
            excitation.insert(
                "theta0_deg".into(),
                json!(settings.theta0 / ehservo_core::math::DR),
            );
            excitation.insert(
                "amplitude_deg".into(),
                json!(settings.amplitude / ehservo_core::math::DR),
            );
        }
        Axis::Linear | Axis::Force | Axis::Pressure => {
            excitation.insert("x0_m".into(), json!(settings.theta0));
            excitation.insert("x0_mm".into(), json!(axis.display(settings.theta0)));
            excitation.insert("amplitude_m".into(), json!(settings.amplitude));
            excitation.insert(
                "amplitude_mm".into(),
                json!(axis.display(settings.amplitude)),
            );
        }
    }
    let mut settings_json = serde_json::Value::Object(excitation);
    settings_json.as_object_mut().expect("an object").extend(
        json!({
            "disturbance_V": settings.disturbance,
            "settle_s": settings.settle_s,
            "settle_cycles": settings.settle_cycles,
            "cycles": settings.cycles,
            "welch_periods": o.periods,
            "f_min_Hz": o.measure_f_min,
            "points": o.measure_points,
        })
        .as_object()
        .expect("an object")
        .clone(),
    );
    summary["measured"] = json!({
        "settings": settings_json,
        "methods": measured_json,
        "quality": "sinestream: the fundamental fraction, the share of the output's variance at the excited frequency; Welch: the coherence γ²",
    });
    if o.plots {
        out.plots(&s.name, sets, lp_opt, &responses, &freqs, &summary)?;
    }
    let path = out.dir.join("freq.json");
    std::fs::write(&path, serde_json::to_string_pretty(&summary)? + "\n")
        .with_context(|| format!("writing {}", path.display()))?;
    out.files.insert(0, PathBuf::from("freq.json"));
    stage.commit()?;
    Ok(FreqSummary {
        files: out.files,
        text: out.text,
    })
}

/// The output folder being written: its (staging) path, the files written
/// in it so far, and the lines for the terminal.
struct Out {
    dir: PathBuf,
    files: Vec<PathBuf>,
    text: String,
    /// The axis the outputs speak (units and names).
    axis: Axis,
}

impl Out {
    /// The computed curves: linearization.json and response.csv written,
    /// the margins, peaks and bandwidths of the loop, its terminal lines.
    /// The summary's `computed` and the responses on the grid `freqs`.
    fn computed(
        &mut self,
        s: &Scenario,
        l: &Linearised,
        freqs: &[f64],
        f_max: f64,
        h: f64,
        axis: Axis,
    ) -> Result<(serde_json::Value, Vec<Responses>)> {
        let lp = &l.lp;
        let lj = linearisation_json(l);
        let path = self.dir.join("linearization.json");
        std::fs::write(&path, serde_json::to_string_pretty(&lj)? + "\n")
            .with_context(|| format!("writing {}", path.display()))?;
        self.files.push(PathBuf::from("linearization.json"));
        let responses: Vec<Responses> = freqs.iter().map(|&f| lp.at(2.0 * PI * f)).collect();
        let hi = if lp.sampled() {
            lp.nyquist() * (1.0 - 1e-9)
        } else {
            2.0 * PI * f_max
        };
        let (lo, features) = lp.search_band();
        let c = |sel: fn(&Responses) -> Option<C64>| move |w: f64| sel(&lp.at(w));
        let m: Option<Margins> = lp.loop_l.as_ref().map(|_| {
            margins::margins_on(
                &c(|r| r.l),
                lo,
                hi,
                lp.sampled().then_some(h),
                margins::POINTS_PER_DECADE,
                true,
                &features,
            )
        });
        let peak = |sel: fn(&Responses) -> Option<C64>| {
            margins::peak(&c(sel), lo, hi)
                .map(|(w, v)| json!({"value": v, "dB": 20.0 * v.log10(), "f_Hz": w / (2.0 * PI)}))
        };
        let bw = |sel: fn(&Responses) -> Option<C64>| {
            let dc = sel(&lp.at(lo)).map(|z| z.norm())?;
            margins::bandwidth(&c(sel), dc, lo, hi).map(|w| w / (2.0 * PI))
        };
        let computed_json = json!({
            "operating_point": l.point,
            "one_sided": l.side.map(|s| s.as_str()),
            "kinks": lp.kinks.iter().map(|k| k.what.clone()).collect::<Vec<_>>(),
            "notes": lp.notes,
            "discretisation": lp.discretisation.as_str(),
            "linear_controller": lp.controller.is_some(),
            "closed_loop_stable": lp.closed_loop_stable(),
            "hidden_modes": lp.hidden_modes().map(|v| v.iter().map(|z| pair(*z)).collect::<Vec<_>>()),
            "margins": m,
            "Ms": lp.loop_l.as_ref().and_then(|_| peak(|r| r.s)),
            "Mt": lp.loop_l.as_ref().and_then(|_| peak(|r| r.t)),
            "tracking_peak": lp.loop_l.as_ref().and_then(|_| peak(|r| r.track)),
            "bandwidth_Hz": {
                "T": lp.loop_l.as_ref().and_then(|_| bw(|r| r.t)),
                "tracking": lp.loop_l.as_ref().and_then(|_| bw(|r| r.track)),
                "G": bw(|r| r.g),
            },
            "dc_gain": {
                axis.si_name("G_rad_V"): lp.g.dc_gain(),
                axis.si_name("C_V_rad"): lp.feedback.as_ref().and_then(|f| f.dc_gain()),
            },
        });
        computed_text(&mut self.text, s, l, m.as_ref(), &computed_json);
        write_response_csv(&self.dir.join("response.csv"), &responses, freqs, axis)?;
        self.files.push(PathBuf::from("response.csv"));
        Ok((computed_json, responses))
    }

    /// Each measured set: its CSV table written, its tracking bandwidth and
    /// loop margins, its terminal line. The summary's `methods`.
    fn measured(
        &mut self,
        sets: &[MeasuredSet],
        lp_opt: Option<&LoopModel>,
        axis: Axis,
    ) -> Result<serde_json::Map<String, serde_json::Value>> {
        let mut measured_json = serde_json::Map::new();
        for set in sets {
            let name = format!("measured_{}.csv", set.method.as_str());
            write_measured_csv(&self.dir.join(&name), set, lp_opt, axis)?;
            self.files.push(PathBuf::from(&name));
            let loop_pts: Vec<(f64, Option<C64>, f64)> = set
                .disturbance
                .iter()
                .map(|m| {
                    let l = m.s_c().filter(|s| s.norm() > 0.0).map(|s| 1.0 / s - 1.0);
                    (m.f_hz, l, m.quality.min(m.quality_s.unwrap_or(1.0)))
                })
                .collect();
            let diverged = set
                .tracking
                .iter()
                .chain(&set.disturbance)
                .filter(|m| m.diverged_at_s.is_some())
                .count();
            let q_min = |v: &[Measured]| v.iter().map(|m| m.quality).fold(f64::INFINITY, f64::min);
            let bw = measured_bandwidth(&set.tracking);
            let mm = measured_margins(&loop_pts);
            // Why a margin is absent: |L| did not cross 1 between the
            // measured frequencies (or too few of them were measured).
            let measured_l: Vec<f64> = loop_pts
                .iter()
                .filter(|p| p.1.is_some())
                .map(|p| p.0)
                .collect();
            let no_crossover = match (measured_l.first(), measured_l.last()) {
                (Some(a), Some(b)) if measured_l.len() > 1 => format!(
                    "none (|L| does not cross 1 between {a:.3} and {b:.3} Hz, where L was measured)"
                ),
                _ => "none (L measured at fewer than two frequencies)".into(),
            };
            let _ = writeln!(
                self.text,
                "measured ({}, {} frequencies): tracking −3 dB bandwidth {}; loop at the plant's input: phase margin {}, delay margin {}{}",
                set.method.as_str(),
                set.tracking.len(),
                bw["bandwidth_Hz"]
                    .as_f64()
                    .map(|b| format!("{b:.3} Hz"))
                    .unwrap_or_else(|| format!("not found ({})", bw["why"].as_str().unwrap_or(""))),
                mm["phase_margin"]["phase_margin_deg"]
                    .as_f64()
                    .map(|p| format!("{p:.2}°"))
                    .unwrap_or_else(|| no_crossover.clone()),
                mm["delay_margin"]["delay_margin_s"]
                    .as_f64()
                    .map(|d| format!("{:.2} ms", d * 1e3))
                    .unwrap_or_else(|| if mm["phase_margin"].is_null() {
                        "none".into()
                    } else {
                        "none (no crossover of non-negative phase margin)".into()
                    }),
                if diverged > 0 {
                    format!("; {diverged} runs unbounded")
                } else {
                    String::new()
                }
            );
            measured_json.insert(
                set.method.as_str().into(),
                json!({
                    "file": name,
                    "tracking_bandwidth": bw,
                    "loop_margins": mm,
                    "unbounded_runs": diverged,
                    "least_quality": {"tracking": q_min(&set.tracking), "disturbance": q_min(&set.disturbance)},
                    "plan": set.plan,
                }),
            );
        }
        Ok(measured_json)
    }

    /// The figures, PNG and SVG: the Bode and (with a loop) Nyquist plots
    /// of the computed curves, and the measured points.
    fn plots(
        &mut self,
        name: &str,
        sets: &[MeasuredSet],
        lp_opt: Option<&LoopModel>,
        responses: &[Responses],
        freqs: &[f64],
        summary: &serde_json::Value,
    ) -> Result<()> {
        let axis = self.axis;
        if let Some(lp) = lp_opt {
            for ext in ["png", "svg"] {
                let p = self.dir.join(format!("bode.{ext}"));
                bode(&p, lp, responses, freqs, summary, axis)?;
                self.files.push(PathBuf::from(format!("bode.{ext}")));
                if lp.loop_l.is_some() {
                    let p = self.dir.join(format!("nyquist.{ext}"));
                    nyquist(&p, responses, summary)?;
                    self.files.push(PathBuf::from(format!("nyquist.{ext}")));
                }
            }
        }
        if !sets.is_empty() {
            for ext in ["png", "svg"] {
                let p = self.dir.join(format!("measured.{ext}"));
                measured_plot(&p, sets, lp_opt, name, axis)?;
                self.files.push(PathBuf::from(format!("measured.{ext}")));
            }
        }
        Ok(())
    }
}

/// The terminal lines of the computed curves: the operating point, and the
/// loop's margins, Ms, Mt and bandwidths (or why there is no loop).
fn computed_text(
    text: &mut String,
    s: &Scenario,
    l: &Linearised,
    m: Option<&Margins>,
    computed_json: &serde_json::Value,
) {
    let lp = &l.lp;
    let _ = writeln!(
        text,
        "computed about the {} point {}{}:",
        l.point.kind,
        l.point.describe(),
        l.point
            .t_s
            .map(|t| format!(" (t = {t} s)"))
            .unwrap_or_default()
    );
    let Some(m) = m else {
        let _ = writeln!(
            text,
            "  `{}` is not a linear law: the computed curves are the plant's alone",
            s.controller.kind()
        );
        return;
    };
    let _ = writeln!(
        text,
        "  L: gain margin {}, phase margin {}, delay margin {}; closed loop {}",
        m.gain_margin
            .map(|g| format!("{:.3} dB at {:.3} Hz", g.gain_margin_db, g.f_hz))
            .unwrap_or("none (no phase crossover)".into()),
        m.phase_margin
            .map(|g| format!("{:.3}° at {:.3} Hz", g.phase_margin_deg, g.f_hz))
            .unwrap_or("none (no gain crossover)".into()),
        m.delay_margin
            .and_then(|g| g.delay_margin_s)
            .map(|d| format!("{:.3} ms", d * 1e3))
            .unwrap_or(if m.phase_margin.is_none() {
                "none (no gain crossover)".into()
            } else {
                "none (no crossover of non-negative phase margin)".into()
            }),
        match (lp.closed_loop_stable(), lp.hidden_modes().map(|h| h.len())) {
            (Some(true), Some(n)) if n > 0 => format!(
                "stable ({n} mode(s) on the stability boundary that the loop neither moves nor sees: they hold a constant)"
            ),
            (Some(true), _) => "stable".into(),
            (Some(false), _) => "UNSTABLE".into(),
            (None, _) => "?".into(),
        }
    );
    let bt = computed_json["bandwidth_Hz"]["tracking"].as_f64();
    let _ = writeln!(
        text,
        "  Ms {:.3}, Mt {:.3}; −3 dB bandwidth of T {}, of {} {}",
        computed_json["Ms"]["value"].as_f64().unwrap_or(f64::NAN),
        computed_json["Mt"]["value"].as_f64().unwrap_or(f64::NAN),
        computed_json["bandwidth_Hz"]["T"]
            .as_f64()
            .map(|b| format!("{b:.3} Hz"))
            .unwrap_or("beyond the band".into()),
        tracking_name(l.setup.axis()),
        bt.map(|b| format!("{b:.3} Hz"))
            .unwrap_or("beyond the band".into()),
    );
}

/// The tracking response's name: θ/θd, or y/yd on a linear axis.
pub(super) fn tracking_name(axis: Axis) -> String {
    let a = axis.letter();
    format!("{a}/{a}d")
}

fn write_response_csv(path: &Path, rs: &[Responses], freqs: &[f64], axis: Axis) -> Result<()> {
    let mut head = vec!["f_Hz".to_string(), "omega_rad_s".to_string()];
    let curves = curves(axis);
    for (n, u, _) in &curves {
        let u = u.replace('/', "_");
        let suf = if u.is_empty() {
            String::new()
        } else {
            format!("_{u}")
        };
        head.push(format!("{n}_gain_dB"));
        head.push(format!("{n}_phase_deg"));
        head.push(format!("{n}_re{suf}"));
        head.push(format!("{n}_im{suf}"));
    }
    let cols: Vec<Vec<Option<C64>>> = (0..curves.len())
        .map(|i| rs.iter().map(|r| r.all()[i]).collect())
        .collect();
    let phases: Vec<Vec<Option<f64>>> = cols.iter().map(|c| unwrap(c)).collect();
    let mut out = head.join(",") + "\n";
    for (k, f) in freqs.iter().enumerate() {
        let mut row = vec![cell(Some(*f)), cell(Some(2.0 * PI * f))];
        for i in 0..curves.len() {
            let z = cols[i][k];
            row.push(cell(z.map(db)));
            row.push(cell(phases[i][k]));
            row.push(cell(z.map(|z| z.re)));
            row.push(cell(z.map(|z| z.im)));
        }
        out += &(row.join(",") + "\n");
    }
    std::fs::write(path, out).with_context(|| format!("writing {}", path.display()))
}

fn write_measured_csv(
    path: &Path,
    set: &MeasuredSet,
    lp: Option<&LoopModel>,
    axis: Axis,
) -> Result<()> {
    let (dist_re, dist_im) = (axis.si_name("dist_re_rad_V"), axis.si_name("dist_im_rad_V"));
    let head = [
        "f_Hz",
        "track_gain_dB",
        "track_phase_deg",
        "track_re",
        "track_im",
        "track_quality",
        "dist_gain_dB",
        "dist_phase_deg",
        dist_re.as_str(),
        dist_im.as_str(),
        "S_gain_dB",
        "S_phase_deg",
        "S_re",
        "S_im",
        "L_gain_dB",
        "L_phase_deg",
        "dist_quality",
        "S_quality",
        "track_computed_gain_dB",
        "track_computed_phase_deg",
        "dist_computed_gain_dB",
        "dist_computed_phase_deg",
        "S_computed_gain_dB",
        "S_computed_phase_deg",
        "track_unbounded_at_s",
        "dist_unbounded_at_s",
    ];
    let tr: Vec<Option<C64>> = set.tracking.iter().map(|m| m.theta_c()).collect();
    let di: Vec<Option<C64>> = set.disturbance.iter().map(|m| m.theta_c()).collect();
    let sv: Vec<Option<C64>> = set.disturbance.iter().map(|m| m.s_c()).collect();
    let lv: Vec<Option<C64>> = sv
        .iter()
        .map(|s| s.filter(|s| s.norm() > 0.0).map(|s| 1.0 / s - 1.0))
        .collect();
    let comp: Vec<Option<Responses>> = set
        .tracking
        .iter()
        .map(|m| lp.map(|l| l.at(2.0 * PI * m.f_hz)))
        .collect();
    let ctr: Vec<Option<C64>> = comp.iter().map(|r| r.and_then(|r| r.track)).collect();
    let cdi: Vec<Option<C64>> = comp.iter().map(|r| r.and_then(|r| r.dist)).collect();
    let csv_: Vec<Option<C64>> = comp.iter().map(|r| r.and_then(|r| r.s)).collect();
    let (ptr, pdi, psv, plv, pctr, pcdi, pcs) = (
        unwrap(&tr),
        unwrap(&di),
        unwrap(&sv),
        unwrap(&lv),
        unwrap(&ctr),
        unwrap(&cdi),
        unwrap(&csv_),
    );
    let mut out = head.join(",") + "\n";
    for k in 0..set.tracking.len() {
        let (t, d) = (&set.tracking[k], &set.disturbance[k]);
        let row = [
            cell(Some(t.f_hz)),
            cell(tr[k].map(db)),
            cell(ptr[k]),
            cell(tr[k].map(|z| z.re)),
            cell(tr[k].map(|z| z.im)),
            cell(tr[k].map(|_| t.quality)),
            cell(di[k].map(db)),
            cell(pdi[k]),
            cell(di[k].map(|z| z.re)),
            cell(di[k].map(|z| z.im)),
            cell(sv[k].map(db)),
            cell(psv[k]),
            cell(sv[k].map(|z| z.re)),
            cell(sv[k].map(|z| z.im)),
            cell(lv[k].map(db)),
            cell(plv[k]),
            cell(di[k].map(|_| d.quality)),
            cell(d.quality_s),
            cell(ctr[k].map(db)),
            cell(pctr[k]),
            cell(cdi[k].map(db)),
            cell(pcdi[k]),
            cell(csv_[k].map(db)),
            cell(pcs[k]),
            cell(t.diverged_at_s),
            cell(d.diverged_at_s),
        ];
        out += &(row.join(",") + "\n");
    }
    std::fs::write(path, out).with_context(|| format!("writing {}", path.display()))
}
