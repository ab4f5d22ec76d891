//! Terminal text of [`super::Analysis`] and [`super::RunDiagnostics`]
//! (a child module of `analysis`, kept apart to keep the numbers readable).

use super::{
    Analysis, LoopAnalysis, Pole, RunDiagnostics, SurfaceAnalysis, WeightAnalysis, K1,
    RK4_REAL_LIMIT,
};
use std::fmt::Write;

/// `x` with `n` significant digits: fixed notation for 1e-2 ≤ |x| < 1e6
/// (trailing zeros trimmed), otherwise `1.23e-5`; ∞ and NaN spelled out.
pub(super) fn sig(x: f64, n: usize) -> String {
    if x.is_nan() {
        return "NaN".into();
    }
    if x.is_infinite() {
        return if x > 0.0 {
            "∞".into()
        } else {
            "−∞".into()
        };
    }
    if x == 0.0 {
        return "0".into();
    }
    let n = n.max(1);
    let e = x.abs().log10().floor() as i32;
    if !(-2..6).contains(&e) {
        let s = format!("{:.*e}", n - 1, x);
        return match s.split_once('e') {
            Some((m, ex)) if m.contains('.') => {
                format!("{}e{ex}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        };
    }
    let d = (n as i32 - 1 - e).max(0) as usize;
    let s = format!("{x:.d$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Display width: combining marks (U+0300–U+036F, U+20D0–U+20FF) take no
/// column.
fn width(s: &str) -> usize {
    s.chars()
        .filter(|c| !matches!(*c as u32, 0x300..=0x36F | 0x20D0..=0x20FF))
        .count()
}

fn pad(s: &str, w: usize) -> String {
    let mut out = s.to_string();
    for _ in width(s)..w {
        out.push(' ');
    }
    out
}

const LABEL: usize = 30;

fn row(t: &mut String, label: &str, value: &str) {
    let _ = writeln!(t, "  {}{}", pad(label, LABEL), value);
}

fn heading(t: &mut String, h: &str) {
    if !t.is_empty() {
        t.push('\n');
    }
    let _ = writeln!(t, "{h}");
    let _ = writeln!(t, "{}", "─".repeat(width(h)));
}

fn pole_table(t: &mut String, label: &str, poles: &[Pole]) {
    let _ = writeln!(
        t,
        "  {}{:>14}{:>14}{:>14}{:>10}",
        pad(label, LABEL),
        "Re (1/s)",
        "Im (rad/s)",
        "ωn (rad/s)",
        "ζ"
    );
    for q in poles {
        let _ = writeln!(
            t,
            "  {}{:>14}{:>14}{:>14}{:>10.4}",
            pad("", LABEL),
            sig(q.re, 6),
            sig(q.im, 6),
            sig(q.wn, 6),
            q.zeta
        );
    }
}

impl Analysis {
    /// A multi-section report for the terminal: plant, surface and
    /// Theorem 2, weights (Remark 6), the σ-loop and the integrator.
    /// Verdicts are on their own lines; warnings start with `warning:`.
    pub fn to_text(&self) -> String {
        let mut t = String::new();
        self.plant_text(&mut t);
        surface_text(&mut t, &self.surface);
        if let Some(w) = &self.weights {
            weights_text(&mut t, w);
        }
        loop_text(&mut t, &self.closed_loop);
        t
    }

    /// The plant's section: the nominal coefficients, b̄, d(t), the
    /// open-loop poles.
    fn plant_text(&self, t: &mut String) {
        heading(t, "Plant (nominal model (9), Pl = 0)");
        row(
            t,
            "ā1, ā2, ā3",
            &format!(
                "{} s⁻³   {} s⁻²   {} s⁻¹",
                sig(self.a_nominal[0], 6),
                sig(self.a_nominal[1], 9),
                sig(self.a_nominal[2], 8)
            ),
        );
        let linear = self.axis == "linear";
        row(
            t,
            "b̄ at Pl = 0",
            &format!(
                "{} {}s⁻³V⁻¹",
                sig(self.b_at_rest, 8),
                if linear { "m·" } else { "" }
            ),
        );
        let (d0, d1) = (
            sig(self.d_coefficients[0], 7),
            sig(self.d_coefficients[1], 7),
        );
        row(
            t,
            "d(t)",
            &if linear {
                format!("{d0}·F + {d1}·Ḟ   (4βe·Kce/(Vt·M), 1/M; F the load force, N)")
            } else {
                format!("{d0}·Tl + {d1}·Ṫl   (4βe·Kce/(Vt·Jt), 1/Jt)")
            },
        );
        pole_table(t, "open-loop poles", &self.open_loop_poles);
    }
}

/// The switching surface's section and Theorem 2's verdict.
fn surface_text(t: &mut String, s: &SurfaceAnalysis) {
    heading(t, "Switching surface (10) and Theorem 2");
    row(
        t,
        "p1, p2, p3",
        &format!("{}, {}, {}", sig(s.p[0], 8), sig(s.p[1], 8), sig(s.p[2], 8)),
    );
    pole_table(t, "sliding poles (eig P)", &s.poles);
    for (i, r) in s.p_matrix.iter().enumerate() {
        let cells: Vec<String> = r.iter().map(|v| format!("{:>10}", sig(*v, 6))).collect();
        row(
            t,
            if i == 0 { "P of (16)" } else { "" },
            &format!("[{} ]", cells.join("")),
        );
    }
    row(t, "K2 = −max Re λ(P)", &sig(s.k2, 8));
    k1_rows(t, &s.k1);
    row(t, "Theorem 2 bound K2/K1", &sig(s.alpha_bound, 5));
    if let Some(a) = s.alpha {
        row(t, "α of the scenario", &sig(a, 6));
    }
    let _ = writeln!(t, "  verdict: {}", s.verdict);
}

/// K1's rows: its value and where, the search, the asymptote and the
/// proof-of-bound check; or ∞.
fn k1_rows(t: &mut String, k: &K1) {
    match k.value {
        Some(v) => {
            row(
                t,
                "K1 = sup ‖e^(Pt)‖·e^(K2 t)",
                &format!(
                    "{}  ({})",
                    sig(v, 8),
                    match k.at_t {
                        Some(tt) => format!("reached at t = {} s", sig(tt, 6)),
                        None => "approached as t → ∞".into(),
                    }
                ),
            );
            row(
                t,
                "  search",
                &format!(
                    "nalgebra exp on {} points (linear + geometric) over {} s, refined by golden section",
                    k.grid_points,
                    sig(k.span, 4)
                ),
            );
            if let (Some(l), Some(b)) = (k.limit, k.tail_bound) {
                row(
                    t,
                    "  asymptote (Sylvester)",
                    &format!(
                        "lim sup = {}, and g(t) ≤ {} for t ≥ {} s",
                        sig(l, 10),
                        sig(b, 10),
                        sig(k.span, 4)
                    ),
                );
            }
            row(
                t,
                "  proof-of-bound check",
                &format!(
                    "{}: {} independent points over {} s, max g/K1 = {:.12} (tolerance {})",
                    if k.verified {
                        "verified"
                    } else {
                        "NOT verified"
                    },
                    k.check_points,
                    sig(2.0 * k.span, 4),
                    k.check_max_ratio,
                    sig(k.tolerance, 1)
                ),
            );
        }
        None => row(
            t,
            "K1",
            "∞ (repeated dominant pole: ‖e^(Pt)‖·e^(K2 t) grows like t)",
        ),
    }
}

/// The weights' section: the invariant set of Remark 6.
fn weights_text(t: &mut String, w: &WeightAnalysis) {
    heading(t, "Weights: the invariant set of Remark 6");
    row(
        t,
        "η, Wmax, ε0, ε1",
        &format!(
            "{}, {}, {}, {}",
            sig(w.eta, 6),
            sig(w.w_max, 6),
            sig(w.eps0, 6),
            sig(w.eps1, 6)
        ),
    );
    row(
        t,
        "largest ‖Φ‖",
        &format!(
            "{} along the reference (‖z‖ ≤ {}), {} over Ω",
            sig(w.phi_norm_reference, 5),
            sig(w.z_norm_reference, 5),
            sig(w.phi_norm_omega, 5)
        ),
    );
    let rad = |r: Option<f64>| r.map(|v| sig(v, 6)).unwrap_or("unbounded (η = 0)".into());
    row(t, "radius at ‖Φ‖ = 1", &rad(w.radius_min));
    row(t, "radius along the reference", &rad(w.radius_reference));
    row(
        t,
        "radius at the largest ‖Φ‖",
        &format!("{}  (from {})", rad(w.radius_max), w.phi_norm_max_from),
    );
    row(
        t,
        "ball kept by (26): ‖Φ‖/η",
        &w.law_ball
            .map(|v| sig(v, 5))
            .unwrap_or("unbounded (η = 0)".into()),
    );
    let _ = writeln!(t, "  note: {}", w.note);
}

/// The σ-loop's section: its linearisation, the integrator's stability and
/// the verdict.
fn loop_text(t: &mut String, l: &LoopAnalysis) {
    heading(t, "The σ-loop, linearised, and the integrator");
    row(
        t,
        "controller, mode",
        &format!(
            "{}, {} (h = {} s{})",
            l.controller,
            l.mode,
            sig(l.step, 4),
            if l.mode == "sampled" {
                format!(", {} RK4 sub-step(s)", l.substeps)
            } else {
                String::new()
            }
        ),
    );
    row(
        t,
        "b/b̄ (bias; worst case)",
        &format!(
            "{}; {} (b_bias + |b_random|)",
            sig(l.b_ratio, 6),
            sig(l.b_ratio_worst, 6)
        ),
    );
    if let Some([lo, hi]) = l.vsc_sat_kb {
        row(
            t,
            "kb = b̄·k along the reference",
            &format!(
                "{} … {} s⁻³ (the check uses the largest)",
                sig(lo, 5),
                sig(hi, 5)
            ),
        );
    }
    if let (Some(g), Some(gw)) = (l.sigma_gain, l.sigma_gain_worst) {
        row(
            t,
            if l.vsc_sat_kb.is_some() {
                "σ-loop gain b·kb/(b̄·μ)"
            } else {
                "σ-loop gain b/(b̄ − β)·γ1"
            },
            &format!("{} s⁻¹ (worst case {})", sig(g, 6), sig(gw, 6)),
        );
    }
    if !l.eigenvalues.is_empty() {
        pole_table(t, "closed-loop eigenvalues", &l.eigenvalues);
    }
    if let (Some(f), Some(e), Some(fw)) = (l.fast, l.fast_estimate, l.fast_worst) {
        row(
            t,
            "fast (σ) eigenvalue",
            &format!(
                "{} s⁻¹ (one-dimensional estimate {}; worst case {})",
                sig(f, 5),
                sig(e, 5),
                sig(fw, 5)
            ),
        );
    }
    if let Some(hl) = l.h_lambda {
        row(
            t,
            "h·λ_fast (worst case)",
            &format!(
                "{}  (RK4's real-axis limit {:.3})",
                sig(hl, 4),
                RK4_REAL_LIMIT
            ),
        );
    }
    if let Some(g) = l.growth {
        row(
            t,
            if l.mode == "sampled" {
                "spectral radius of the map"
            } else {
                "max |R(hλ)|"
            },
            &sig(g, 6),
        );
    }
    let _ = writeln!(t, "  check: {}", l.check);
    let _ = writeln!(t, "  verdict: {}", l.verdict);
    if let Some(w) = &l.warning {
        let _ = writeln!(t, "warning: {w}");
    }
}

impl RunDiagnostics {
    /// Terminal text: the shares over all samples and over t ≥ settle.
    pub fn to_text(&self) -> String {
        let pc = |v: f64| format!("{:.1} %", 100.0 * v);
        let mut t = String::new();
        heading(
            &mut t,
            "Along the run: condition 4) of Theorem 3 and the dead zone",
        );
        let _ = writeln!(
            t,
            "  {}{:>12}{:>14}",
            pad("share of samples", 36),
            "all",
            "t ≥ settle"
        );
        let _ = writeln!(
            t,
            "  {}{:>12}{:>14}",
            pad("", 36),
            format!("({})", self.samples),
            format!("({})", self.samples_after_settle)
        );
        for (label, a, b) in [
            ("condition 4) holds", self.condition4, self.after_settle[0]),
            (
                "  left:  f + ᾱ‖E‖ < α‖E‖",
                self.condition4_left,
                self.after_settle[1],
            ),
            (
                "  right: α‖E‖ < c/γ1 + ᾱ‖E‖",
                self.condition4_right,
                self.after_settle[2],
            ),
            (
                "in the dead zone (σΔ = 0)",
                self.dead_zone,
                self.after_settle[3],
            ),
        ] {
            let _ = writeln!(t, "  {}{:>12}{:>14}", pad(label, 36), pc(a), pc(b));
        }
        let _ = writeln!(
            t,
            "  note: the right half needs ‖E‖ < c/(γ1(α − ᾱ)) ≈ {} (median); the median ‖E‖ of the run is {}",
            sig(self.right_half_limit_median, 3),
            sig(self.norm_e_median, 3)
        );
        heading(&mut t, "Along the run: assumption A5 and Remark 6");
        let w = &self.weights;
        for (label, v) in [
            ("max |uncertainty of (19)|", sig(w.uncertainty_max, 4)),
            ("max ‖Φ‖", sig(w.phi_norm_max, 4)),
            ("least ‖W̄‖ meeting (19), (22)", sig(w.w_bar_required, 4)),
            (
                "A5 with Wmax",
                format!(
                    "{} (Wmax = {})",
                    if w.a5_holds { "holds" } else { "FAILS" },
                    sig(w.w_max, 3)
                ),
            ),
            ("max ‖W‖ of the run", sig(w.w_norm_max, 4)),
            (
                "Remark 6's set",
                match w.remark6_left_at_s {
                    Some(t0) => format!(
                        "LEFT at t = {} s ({} of the samples outside)",
                        sig(t0, 4),
                        pc(w.remark6_outside_share)
                    ),
                    None => "not left".into(),
                },
            ),
        ] {
            let _ = writeln!(t, "  {}{v}", pad(label, 36));
        }
        let _ = writeln!(t, "  note: {}", w.note);
        t
    }
}
