//! A pressure-compensated variable pump into the supply line:
//! `[plant.supply] kind = "pc-pump"`.
//!
//! Hopsan's `HydraulicPressureControlledPump` (Hopsan/hopsan,
//! componentLibraries/defaultLibrary/Hydraulic/Pumps&Motors/
//! HydraulicPressureControlledPump.hpp) regulates its geometric flow
//! q_p = y/d through the filter `fltppu` (lines 227–279), the bilinear
//! transform of
//!
//! ```text
//! Y(s)/U(s) = (1 + s/ω_p1)/(g1·s² + s + g2),  u = p_dif − p2 + p_ref         (lines 196, 243–252)
//! d  = l_pe + r_p·τ_v,  l_pe = l_p·√(p_nom/p2)·(125/(n + 0.001))            (lines 186, 193)
//! g1 = l_pe·τ_v/d,  g2 = r_p/d                                               (lines 194–195)
//! 0 ≤ y ≤ q_max·d,  ẏ ∈ [−q_max·d·√(|p2 − 1e5|/(p_nom·t_m)), q_max·d·√(|p2 − 1e5|/(p_nom·t_p))]  (lines 197–200, 253–273)
//! q2 = y/d − C_lp·(p2 − p1)                                                  (lines 201, 209–210)
//! ```
//!
//! with p_nom = 7 MPa (line 68), q_max the flow at full displacement at the
//! shaft speed n (D·n/2π here; Hopsan states it at 125 rad/s and scales it
//! by n/125, line 182) and the characteristic impedances (TLM terms) 0.
//! The compensator's reference port PREF is its spring chamber, drained to
//! the tank: p_ref = P_t, so the setting is a pressure over the tank.
//! At steady state y = u/g2, so q_p = (p_dif + P_t − p)/r_p: the pump
//! delivers its full flow at P_t + p_dif − r_p·q_max and none at
//! P_t + p_dif. The datasheet keys are that setting
//! (`compensator_pressure` = p_dif over the tank, the dead-head pressure)
//! and its band (`compensator_band` = r_p·q_max, the pressure
//! rise from full flow to none), and Hopsan's stroke times t_p, t_m (as
//! Hopsan uses them, line 199: the stroke rate's bound at p is
//! q_max·√(|p − 1e5|/(p_nom·t)), so the full stroke at 70 bar takes √t
//! seconds with t in s, not t).
//!
//! One state: the cylinder's slot 5 (the relief opening x_r of a
//! fixed-displacement pump) holds y; a pressure-compensated supply has no
//! relief valve of its own (the compensator holds the pressure). The fast
//! pole of the control valve, g1 = l_pe·τ_v/d (about 1/τ_v = 1000 rad/s
//! with Hopsan's defaults, beside the slow pole near g2 = 14 rad/s), is
//! dropped (g1 → 0, τ_v kept in d): ẏ = u + u̇/ω_p1 − g2·y with u̇ = −ṗ,
//! limited as above. The comparison against Hopsan in docs/cylinder.md
//! measures what that costs.

use crate::accumulator::{line_stiffness, Accumulator};

/// Hopsan's nominal pressure of the regulator, `pnom = 7e6` (line 68).
pub const P_NOM: f64 = 7e6;
/// Hopsan's nominal speed, `movementnom = 125` rad/s (line 69).
pub const N_NOM: f64 = 125.0;

/// The validated pressure-compensated pump and its line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PcPump {
    /// q_max = D·n/(2π) (m³/s).
    pub q_max: f64,
    /// n (rad/s).
    pub speed: f64,
    /// C_lp (m³/(s·Pa)).
    pub leakage: f64,
    /// V_s (m³).
    pub volume: f64,
    /// βe of the line (Pa).
    pub beta: f64,
    /// p_dif, the compensator's setting (Pa).
    pub p_set: f64,
    /// r_p = band/q_max (Pa·s/m³).
    pub r_p: f64,
    /// l_p (Pa·s²/m³).
    pub l_p: f64,
    /// ω_p1 (rad/s).
    pub lead: f64,
    /// τ_v (s).
    pub tau_v: f64,
    /// t_p, min to full displacement (s).
    pub t_on: f64,
    /// t_m, full to min displacement (s).
    pub t_off: f64,
    /// Ps(0) (Pa).
    pub p0: f64,
    /// The accumulator on the line.
    pub acc: Option<Accumulator>,
}

impl PcPump {
    /// Hopsan's d at the line pressure `p` (lines 185–186, 193).
    pub fn denom(&self, p: f64) -> f64 {
        let l_pe = self.l_p * (P_NOM / p.max(1.0)).sqrt() * (N_NOM / (self.speed + 0.001));
        l_pe + self.r_p * self.tau_v
    }

    /// The regulator's upper limit on y at `p`, q_max·d.
    pub fn y_max(&self, p: f64) -> f64 {
        self.q_max * self.denom(p)
    }

    /// The geometric flow y/d at `p` (m³/s), y limited to [0, y_max].
    pub fn q_geometric(&self, y: f64, p: f64) -> f64 {
        let d = self.denom(p);
        (y / d).clamp(0.0, self.q_max)
    }

    /// The pump's delivery into the line (m³/s): geometric flow less
    /// leakage C_lp·(p − P_t).
    pub fn q_out(&self, y: f64, p: f64, pt: f64) -> f64 {
        self.q_geometric(y, p) - self.leakage * (p - pt)
    }

    /// The derivatives (ṗ_s, ẏ) when the valve draws `q_p` from the line
    /// at `p`, the setting scaled by `pressure_factor` and βe by
    /// `bulk_factor`.
    pub fn deriv(
        &self,
        p: f64,
        y: f64,
        pt: f64,
        q_p: f64,
        pressure_factor: f64,
        bulk_factor: f64,
    ) -> [f64; 2] {
        let k = line_stiffness(self.volume, self.beta * bulk_factor, self.acc.as_ref(), p);
        let dp = k * (self.q_out(y, p, pt) - q_p);
        let d = self.denom(p);
        let g2 = self.r_p / d;
        let u = self.p_set * pressure_factor + pt - p;
        let mut dy = u - dp / self.lead - g2 * y;
        // The stroke rate's limits (lines 199–200, 253–263).
        let s = ((p - 1e5).abs() / P_NOM).sqrt();
        dy = dy.clamp(
            -self.q_max * d * s / self.t_off.sqrt(),
            self.q_max * d * s / self.t_on.sqrt(),
        );
        // The stroke's limits (lines 264–273): ẏ = 0 at a limit it pushes against.
        let ymax = self.y_max(p);
        if (y <= 0.0 && dy < 0.0) || (y >= ymax && dy > 0.0) {
            dy = 0.0;
        }
        [dp, dy]
    }

    /// y put back inside [0, y_max(p)] after a step.
    pub fn limit(&self, p: f64, y: f64) -> f64 {
        y.clamp(0.0, self.y_max(p))
    }

    /// The steady line pressure when the valve draws `q_draw`, with the
    /// setting scaled by `pressure_factor`: ẏ = 0 gives
    /// q_p = (p_set + P_t − p)/r_p, and q_p − C_lp·(p − P_t) = q_draw, so
    /// p = (p_set + P_t + r_p·(C_lp·P_t − q_draw))/(1 + r_p·C_lp), while
    /// q_p ≤ q_max (beyond, the pump is at full stroke, and with no
    /// leakage the line holds no pressure: −∞ is returned, which the
    /// supply never asks for with no draw).
    pub fn steady_pressure(&self, pt: f64, q_draw: f64, pressure_factor: f64) -> f64 {
        let p_set = self.p_set * pressure_factor + pt;
        let p = (p_set + self.r_p * (self.leakage * pt - q_draw)) / (1.0 + self.r_p * self.leakage);
        let qp = (p_set - p) / self.r_p;
        if qp > self.q_max {
            // Full stroke: q_max − C_lp·(p − P_t) = q_draw; with no leakage
            // the line cannot hold any pressure.
            if self.leakage > 0.0 {
                pt + (self.q_max - q_draw) / self.leakage
            } else {
                f64::NEG_INFINITY
            }
        } else {
            p
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 28 cm³/rev at 1500 rpm (157.08 rad/s): q_max = 28e-6·25 = 7e-4 m³/s
    /// (42 L/min); set at 210 bar with a 10 bar band: r_p = 1e6/7e-4
    /// = 1.428571e9 Pa·s/m³; Hopsan's default dynamics.
    pub(crate) fn pump(acc: Option<Accumulator>) -> PcPump {
        let q_max = 28e-6 * 25.0;
        PcPump {
            q_max,
            speed: 25.0 * 2.0 * core::f64::consts::PI,
            leakage: 1e-12,
            volume: 1e-3,
            beta: 1e9,
            p_set: 210e5,
            r_p: 10e5 / q_max,
            l_p: 7e7,
            lead: 200.0,
            tau_v: 1e-3,
            t_on: 0.15,
            t_off: 0.12,
            p0: 1e5,
            acc,
        }
    }

    /// Steady state under a valve's draw of 3e-4 m³/s (18 L/min, below
    /// q_max), by hand: p = (210e5 + 1e5 + r_p·(1e-12·1e5 − 3e-4))/(1 +
    /// r_p·1e-12) with r_p = 1.428571e9: r_p·1e-12 = 1.428571e-3,
    /// r_p·(1e-7 − 3e-4) = −428428.6 Pa, p = 20671571.4/1.001428571 =
    /// 20642083 Pa (206.4 bar, inside the 201–211 bar band over the 1 bar
    /// tank). The draw is an orifice k_o·√(p − P_t) sized to pass 3e-4 at
    /// that pressure (a constant-flow sink is not held by this regulator,
    /// in Hopsan either: docs/cylinder.md). Stepped by RK4 from the dead
    /// head (211 bar, zero stroke) as the orifice opens, the line settles
    /// there, and the pump's delivery equals the draw plus the leakage
    /// (flow conservation).
    #[test]
    fn the_line_settles_in_the_band_at_the_closed_form() {
        let p = pump(None);
        let (pt, q_d) = (1e5, 3e-4);
        let want = 20642083.0;
        assert!((p.steady_pressure(pt, q_d, 1.0) - want).abs() < 1.0);
        let k_o = q_d / (want - pt).sqrt();
        let draw = |ps: f64| k_o * (ps - pt).max(0.0).sqrt();
        let mut s = [211e5, 0.0];
        let h = 1e-5;
        for k in 0..300_000 {
            ehservo_core::rk4::rk4_step(
                |_, y: &[f64; 2], dy: &mut [f64; 2]| {
                    *dy = p.deriv(y[0], y[1], pt, draw(y[0]), 1.0, 1.0);
                },
                k as f64 * h,
                &mut s,
                h,
            );
            s[1] = p.limit(s[0], s[1]);
        }
        assert!((s[0] - want).abs() < 10.0, "{} vs {want}", s[0]);
        assert!(s[0] > 201e5 && s[0] < 211e5);
        let qp = p.q_geometric(s[1], s[0]);
        let leak = 1e-12 * (s[0] - pt);
        assert!((qp - (q_d + leak)).abs() < 1e-9, "{qp} vs {}", q_d + leak);
        // The regulator's steady law q_p = (p_set + P_t − p)/r_p.
        assert!((qp - (211e5 - s[0]) / p.r_p).abs() < 1e-9);
    }

    /// The stroke rate's limit, Hopsan's expression as written (line 199):
    /// from zero stroke at 71 bar, far below the setting, y rises at
    /// q_max·d·√((p − 1e5)/(p_nom·t_p)) = q_max·d/√t_p.
    #[test]
    #[allow(clippy::float_cmp)] // a held stroke is exactly 0
    fn the_stroke_rate_is_limited() {
        let p = pump(None);
        let ps = P_NOM + 1e5;
        let [_, dy] = p.deriv(ps, 0.0, 1e5, 0.0, 1.0, 1.0);
        let want = p.q_max * p.denom(ps) / 0.15_f64.sqrt();
        assert!((dy - want).abs() < 1e-9 * want, "{dy} vs {want}");
        // At full stroke, pushing further: held.
        let [_, dy] = p.deriv(ps, p.y_max(ps), 1e5, 0.0, 1.0, 1.0);
        assert_eq!(dy, 0.0);
    }
}
