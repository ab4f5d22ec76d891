//! A 4/3 spool valve as a datasheet describes it: four metering edges
//! (P→A, P→B, A→T, B→T), each with its own lap, a spool travel limit, and
//! sharp-edged orifices that are turbulent at a working pressure drop and
//! laminar near ΔP = 0.
//!
//! ```text
//! x_v   = clamp(Kv·u, ±x_max)                          spool position (m); u from the actuator stage
//! A_PA  = w_PA·max(x_v − lap_PA, 0)    A_AT = w_AT·max(−x_v − lap_AT, 0)
//! A_PB  = w_PB·max(−x_v − lap_PB, 0)   A_BT = w_BT·max(x_v − lap_BT, 0)
//! q(A, Δp) = Cd·A·√(2/ρ)·Δp / (Δp² + p_cr(A)²)^¼       every edge, either sign of Δp
//! p_cr(A) = (ρ/2)·(Re_cr·ν/(Cd·D_H))²,  D_H = √(4A/π)
//! Q_A = q(A_PA, Ps − P1) − q(A_AT, P1 − Pt)            into chamber A
//! Q_B = q(A_PB, Ps − P2) − q(A_BT, P2 − Pt)            into chamber B
//! ```
//!
//! The edge layout and lap convention are Hopsan's `Hydraulic43Valve`
//! (Hopsan/hopsan, componentLibraries/defaultLibrary/Hydraulic/Valves/
//! FlowControlValves/Hydraulic43Valve.hpp: `xpanom = max(xv − x_pa, 0)`,
//! `xpbnom = max(−xv − x_pb, 0)`, `xatnom = max(−xv − x_at, 0)`,
//! `xbtnom = max(xv − x_bt, 0)`, the area `f·π·d·x`): a positive lap is an
//! overlap (a dead band), a negative one an underlap (the edge is open at
//! null), zero is critically centred. The orifice law is the one of
//! Simscape Fluids' hydraulic orifices (MathWorks, "Fixed Orifice",
//! Hydraulics (Isothermal) library: `q = CD·A·√(2/ρ)·p/(p² + p_cr²)^(1/4)`,
//! laminar transition "by Reynolds number" `p_cr = (ρ/2)·(Re_cr·ν/(CD·D_H))²`,
//! D_H = √(4A/π)): the flow is turbulent, `Cd·A·√(2|Δp|/ρ)`, for
//! |Δp| ≫ p_cr, and linear in Δp near 0, so there is no √ singularity and no
//! clamp: a reversed drop gives a reversed flow. Written with
//! D_H² = 4A/π, `q = Cd·√(2/ρ)·Δp·A^{3/2}/((A·Δp)² + k²)^¼`,
//! k = ρπ·(Re_cr·ν)²/(8·Cd²), which is 0 at A = 0 without a division.
//! With Hopsan's turbulent-only orifice the difference is confined to
//! drops below p_cr, a few pascals at working openings (docs/cylinder.md).
//!
//! The spool's dynamics are the actuator stage's (`[actuator]`, e.g.
//! `natural_frequency` and `damping`); the valve takes its output in volts
//! and its gain Kv (m/V), or `rated_signal` (the signal that gives
//! x_max). Either the edge's area gradient `w` (m, area per metre of
//! spool travel: π·d for a full-circumference edge) with `Cd` is given, or
//! the datasheet's rated flow Q_nom at the rated valve drop Δp_nom and the
//! rated signal: a land then passes Q_nom at Δp_nom/2 and full opening,
//! `Cd·w = Q_nom/(x_max·√(Δp_nom/ρ))` (two lands in series share Δp_nom).

use crate::error::{positive, KeyError};
use ehservo_core::math::sgn;
use serde::{Deserialize, Serialize};

/// `[plant.valve]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ValveCfg {
    /// Spool travel limit x_max (m).
    pub spool_limit: f64,
    /// Spool position per volt of command Kv (m/V); or give `rated_signal`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gain: Option<f64>,
    /// The command (V) that puts the spool at `spool_limit`: Kv = x_max/u_rated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rated_signal: Option<f64>,
    /// Discharge coefficient Cd (–).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub discharge_coefficient: Option<f64>,
    /// Spool diameter d (m): each edge's area gradient is f·π·d.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spool_diameter: Option<f64>,
    /// Fraction f of the circumference each edge opens: one value for all,
    /// or [P→A, P→B, A→T, B→T]. Default 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub circumference_fraction: Option<Edges>,
    /// Area gradient w of each edge (m), instead of `spool_diameter`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub area_gradient: Option<Edges>,
    /// Rated flow Q_nom (m³/s) at `rated_drop` and full opening, instead
    /// of `discharge_coefficient` with a geometry.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rated_flow: Option<f64>,
    /// The valve drop Δp_nom (Pa) of `rated_flow` (over two lands).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rated_drop: Option<f64>,
    /// Laps (m): one value for all edges, or [P→A, P→B, A→T, B→T]; > 0
    /// overlap, < 0 underlap. Default 0 (critically centred).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lap: Option<Edges>,
    /// Critical Reynolds number of the laminar transition. Default 12
    /// (Simscape Fluids' orifice default).
    pub critical_reynolds: f64,
}

impl Default for ValveCfg {
    fn default() -> Self {
        Self {
            spool_limit: 1e-3,
            gain: None,
            rated_signal: None,
            discharge_coefficient: None,
            spool_diameter: None,
            circumference_fraction: None,
            area_gradient: None,
            rated_flow: None,
            rated_drop: None,
            lap: None,
            critical_reynolds: 12.0,
        }
    }
}

/// One value for the four edges, or one each (P→A, P→B, A→T, B→T).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum Edges {
    /// The same for every edge.
    All(f64),
    /// [P→A, P→B, A→T, B→T].
    Each([f64; 4]),
}

impl Edges {
    /// The four values.
    pub fn values(&self) -> [f64; 4] {
        match *self {
            Edges::All(v) => [v; 4],
            Edges::Each(v) => v,
        }
    }
}

/// Edge indices.
const PA: usize = 0;
const PB: usize = 1;
const AT: usize = 2;
const BT: usize = 3;

/// The validated valve.
///
/// ```
/// use ehservo_sim::valve::{SpoolValve, ValveCfg};
///
/// // Rated as a datasheet gives it: 4e-4 m³/s at a 70-bar valve drop and
/// // 10 V (full spool travel, 1 mm), as `[plant.valve]`.
/// let cfg: ValveCfg = toml::from_str(
///     "spool_limit = 1e-3\nrated_signal = 10.0\nrated_flow = 4e-4\nrated_drop = 7e6",
/// )
/// .unwrap();
/// let valve = SpoolValve::try_new(&cfg, 850.0, 46e-6).unwrap();
/// assert_eq!(valve.spool(10.0), 1e-3);
/// // Fully open with 35 bar across each land (70 bar over the two in
/// // series, Ps = 100 bar, Pt = 0): the rated flow in at A and out at B.
/// let q = valve.flows(valve.spool(10.0), 1e7, 0.0, 6.5e6, 3.5e6);
/// assert!((q.a - 4e-4).abs() < 1e-9 && (q.b + 4e-4).abs() < 1e-9);
/// // Half the command, half the opening, half the flow.
/// let half = valve.flows(valve.spool(5.0), 1e7, 0.0, 6.5e6, 3.5e6);
/// assert!((half.a - 2e-4).abs() < 1e-9);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpoolValve {
    /// x_max (m).
    pub x_max: f64,
    /// Kv (m/V).
    pub kv: f64,
    /// Cd·w of each edge (m).
    pub cdw: [f64; 4],
    /// Cd (for the laminar transition).
    pub cd: f64,
    /// Laps (m).
    pub lap: [f64; 4],
    /// `Cd·√(2/ρ)`.
    k_turb: f64,
    /// k = ρπ(Re_cr·ν)²/(8·Cd²) (Pa·m²).
    k_lam: f64,
}

/// Flows through the valve (m³/s).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Flows {
    /// Into chamber A.
    pub a: f64,
    /// Into chamber B.
    pub b: f64,
    /// From the supply.
    pub p: f64,
    /// To the tank.
    pub t: f64,
}

impl SpoolValve {
    /// Validates `[plant.valve]` against the fluid (ρ, ν). The error is
    /// the key inside `[plant.valve]` and the reason.
    pub fn try_new(c: &ValveCfg, rho: f64, nu: f64) -> Result<SpoolValve, KeyError> {
        let err = |k: &str, r: String| Err(KeyError::new(k, r));
        let x_max = positive("spool_limit", c.spool_limit)?;
        let kv =
            match (c.gain, c.rated_signal) {
                (Some(_), Some(_)) => {
                    return err("gain", "give either gain or rated_signal, not both".into())
                }
                (Some(g), None) => positive("gain", g)?,
                (None, Some(u)) => x_max / positive("rated_signal", u)?,
                (None, None) => return err(
                    "gain",
                    "required: the spool travel per volt (m/V), or rated_signal (V at spool_limit)"
                        .into(),
                ),
            };
        let lap = c.lap.map_or([0.0; 4], |l| l.values());
        for (i, l) in lap.iter().enumerate() {
            if !l.is_finite() {
                return err("lap", format!("edge {}: must be finite (got {l:?})", i + 1));
            }
            if *l <= -x_max {
                return err(
                    "lap",
                    format!(
                        "edge {} underlaps by {} m, as much as the spool travel ({x_max} m): the edge never closes",
                        i + 1,
                        -l
                    ),
                );
            }
            if *l >= x_max {
                return err(
                    "lap",
                    format!(
                        "edge {} overlaps by {l} m, as much as the spool travel ({x_max} m): it never opens",
                        i + 1
                    ),
                );
            }
        }
        let re = positive("critical_reynolds", c.critical_reynolds)?;
        let geometry = c.spool_diameter.is_some() || c.area_gradient.is_some();
        let (cd, cdw) = match (c.rated_flow, geometry) {
            (Some(_), true) => {
                return err(
                    "rated_flow",
                    "give either rated_flow (with rated_drop) or a geometry (spool_diameter or area_gradient, with discharge_coefficient), not both".into(),
                )
            }
            (Some(q), false) => {
                let q = positive("rated_flow", q)?;
                let dp = positive(
                    "rated_drop",
                    c.rated_drop.ok_or_else(|| {
                        KeyError::new(
                            "rated_drop",
                            "required with rated_flow: the valve drop (Pa) at which it is rated",
                        )
                    })?,
                )?;
                if c.circumference_fraction.is_some() {
                    return err(
                        "circumference_fraction",
                        "is a geometry key: not used with rated_flow".into(),
                    );
                }
                // A land at full opening passes Q_nom at Δp_nom/2:
                // Cd·w·x_max·√(2·(Δp_nom/2)/ρ) = Q_nom.
                let cdw = q / (x_max * (dp / rho).sqrt());
                let cd = c.discharge_coefficient.unwrap_or(0.61);
                (positive("discharge_coefficient", cd)?, [cdw; 4])
            }
            (None, _) => {
                if c.rated_drop.is_some() {
                    return err("rated_drop", "needs rated_flow".into());
                }
                let cd = positive(
                    "discharge_coefficient",
                    c.discharge_coefficient.ok_or_else(|| {
                        KeyError::new(
                            "discharge_coefficient",
                            "required with a geometry (or give rated_flow and rated_drop)",
                        )
                    })?,
                )?;
                let w = match (c.spool_diameter, c.area_gradient) {
                    (Some(_), Some(_)) => {
                        return err(
                            "area_gradient",
                            "give either spool_diameter or area_gradient, not both".into(),
                        )
                    }
                    (Some(d), None) => {
                        let d = positive("spool_diameter", d)?;
                        let f = c.circumference_fraction.map_or([1.0; 4], |f| f.values());
                        let mut w = [0.0; 4];
                        for i in 0..4 {
                            if !(f[i].is_finite() && f[i] > 0.0 && f[i] <= 1.0) {
                                return err(
                                    "circumference_fraction",
                                    format!("edge {}: must be in (0, 1] (got {:?})", i + 1, f[i]),
                                );
                            }
                            w[i] = f[i] * core::f64::consts::PI * d;
                        }
                        w
                    }
                    (None, Some(w)) => {
                        if c.circumference_fraction.is_some() {
                            return err(
                                "circumference_fraction",
                                "goes with spool_diameter, not area_gradient".into(),
                            );
                        }
                        let w = w.values();
                        for (i, v) in w.iter().enumerate() {
                            if !(v.is_finite() && *v > 0.0) {
                                return err(
                                    "area_gradient",
                                    format!("edge {}: must be finite and > 0 (got {v:?})", i + 1),
                                );
                            }
                        }
                        w
                    }
                    (None, None) => {
                        return err(
                            "spool_diameter",
                            "required: the valve's geometry (spool_diameter or area_gradient), or its rated_flow and rated_drop".into(),
                        )
                    }
                };
                (cd, w.map(|w| cd * w))
            }
        };
        let k_turb = (2.0 / rho).sqrt();
        let k_lam = rho * core::f64::consts::PI * (re * nu) * (re * nu) / (8.0 * cd * cd);
        Ok(SpoolValve {
            x_max,
            kv,
            cdw,
            cd,
            lap,
            k_turb,
            k_lam,
        })
    }

    /// The spool position for the command `u` (V): `clamp(Kv·u, ±x_max)`.
    #[inline]
    pub fn spool(&self, u: f64) -> f64 {
        (self.kv * u).clamp(-self.x_max, self.x_max)
    }

    /// The four edges' openings (m) at spool position `xv`.
    #[inline]
    pub fn openings(&self, xv: f64) -> [f64; 4] {
        [
            (xv - self.lap[PA]).max(0.0),
            (-xv - self.lap[PB]).max(0.0),
            (-xv - self.lap[AT]).max(0.0),
            (xv - self.lap[BT]).max(0.0),
        ]
    }

    /// The orifice law through an edge of discharge-area `cda = Cd·A` (m²)
    /// at the drop `dp` (Pa): `Cd·A·√(2/ρ)·Δp/(Δp² + p_cr²)^¼` with
    /// `p_cr = k/A` (module doc), in the form that is 0 at A = 0.
    #[inline]
    pub fn orifice(&self, cda: f64, dp: f64) -> f64 {
        if cda <= 0.0 {
            return 0.0;
        }
        // A = cda/Cd; q = Cd·√(2/ρ)·Δp·A^{3/2}/((A·Δp)² + k²)^¼.
        let a = cda / self.cd;
        let ad = a * dp;
        self.k_turb * self.cd * dp * a * (a / (ad * ad + self.k_lam * self.k_lam).sqrt()).sqrt()
    }

    /// d q/d Δp of [`SpoolValve::orifice`] at discharge area `cda` and the
    /// drop `dp` (m³/(s·Pa)): finite at Δp = 0 (the laminar region).
    #[inline]
    pub fn orifice_slope(&self, cda: f64, dp: f64) -> f64 {
        if cda <= 0.0 {
            return 0.0;
        }
        // q = c·Δp·A^{3/2}·D^{-1/4}, D = (AΔp)² + k², c = Cd·√(2/ρ):
        // dq/dΔp = c·A^{3/2}·D^{-5/4}·((AΔp)²/2 + k²).
        let a = cda / self.cd;
        let ad = a * dp;
        let k2 = self.k_lam * self.k_lam;
        let d = ad * ad + k2;
        self.k_turb * self.cd * a * a.sqrt() * (0.5 * ad * ad + k2) / (d * d.sqrt().sqrt())
    }

    /// ∂q/∂(Cd·A) of [`SpoolValve::orifice`] at discharge area `cda` and
    /// the drop `dp` (m/s per m² of Cd·A): with D = (AΔp)² + k²,
    /// `dq/dA = Cd·√(2/ρ)·Δp·A^{1/2}·D^{−5/4}·((AΔp)² + 3k²/2)`, divided by
    /// Cd. Its turbulent limit (k → 0) is `√(2/ρ)·sgn(Δp)·√|Δp|`
    /// ([`SpoolValve::turbulent_area_slope`]); at A = 0 it is 0 (the
    /// laminar region: q ∝ A^{3/2} there), and 0 for a closed edge.
    #[inline]
    pub fn orifice_area_slope(&self, cda: f64, dp: f64) -> f64 {
        if cda <= 0.0 {
            return 0.0;
        }
        let a = cda / self.cd;
        let ad = a * dp;
        let k2 = self.k_lam * self.k_lam;
        let d = ad * ad + k2;
        self.k_turb * dp * a.sqrt() * (ad * ad + 1.5 * k2) / (d * d.sqrt().sqrt())
    }

    /// The turbulent orifice's ∂q/∂(Cd·A) at the drop `dp`,
    /// `√(2/ρ)·sgn(Δp)·√|Δp|`: what [`SpoolValve::orifice_area_slope`]
    /// tends to once the opening is past its laminar region (a few
    /// nanometres of spool at working drops), the flow gain of an edge that
    /// just opens (Merritt's K_q at null).
    #[inline]
    pub fn turbulent_area_slope(&self, dp: f64) -> f64 {
        self.k_turb * sgn(dp) * dp.abs().sqrt()
    }

    /// The valve's flows at spool position `xv` with supply `ps`, tank
    /// `pt` and chamber pressures `p1`, `p2` (Pa).
    #[inline]
    pub fn flows(&self, xv: f64, ps: f64, pt: f64, p1: f64, p2: f64) -> Flows {
        let o = self.openings(xv);
        let q_pa = self.orifice(self.cdw[PA] * o[PA], ps - p1);
        let q_pb = self.orifice(self.cdw[PB] * o[PB], ps - p2);
        let q_at = self.orifice(self.cdw[AT] * o[AT], p1 - pt);
        let q_bt = self.orifice(self.cdw[BT] * o[BT], p2 - pt);
        Flows {
            a: q_pa - q_at,
            b: q_pb - q_bt,
            p: q_pa + q_pb,
            t: q_at + q_bt,
        }
    }

    /// The power the four edges dissipate (W): Σ q·Δp over the edges,
    /// which the orifice law makes ≥ 0 (q has the sign of Δp).
    pub fn loss(&self, xv: f64, ps: f64, pt: f64, p1: f64, p2: f64) -> f64 {
        let o = self.openings(xv);
        let drops = [ps - p1, ps - p2, p1 - pt, p2 - pt];
        (0..4)
            .map(|i| self.orifice(self.cdw[i] * o[i], drops[i]) * drops[i])
            .sum()
    }

    /// The turbulent flow gain of one fully-developed land at the drop
    /// `dp` (m²/s): `Cd·w·√(2·dp/ρ)` for the P→A edge.
    pub fn land_gain(&self, dp: f64) -> f64 {
        self.cdw[PA] * self.k_turb * dp.max(0.0).sqrt()
    }

    /// The sign of the spool's effect: +1 when x_v > 0 opens P→A.
    pub fn direction(xv: f64) -> f64 {
        sgn(xv)
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact zeros and symmetry are the point
mod tests {
    use super::*;

    fn hopsan_like() -> SpoolValve {
        SpoolValve::try_new(
            &ValveCfg {
                spool_limit: 0.01,
                gain: Some(1e-3),
                discharge_coefficient: Some(0.67),
                spool_diameter: Some(0.01),
                lap: Some(Edges::All(1e-4)),
                ..Default::default()
            },
            890.0,
            46e-6,
        )
        .unwrap()
    }

    /// Far from ΔP = 0 the orifice is the turbulent law Cd·A·√(2Δp/ρ), by
    /// hand; near 0 it is linear with the slope Cd·A·√(2/ρ)/√p_cr; it is
    /// odd in Δp (reverse drop, reverse flow) and 0 when closed.
    #[test]
    fn orifice_is_turbulent_far_and_laminar_near_zero() {
        let v = hopsan_like();
        let a = 1e-5; // m²
        let cda = 0.67 * a;
        let dp = 5e6;
        let turb = 0.67 * a * (2.0 * dp / 890.0_f64).sqrt();
        let q = v.orifice(cda, dp);
        assert!((q - turb).abs() <= 1e-6 * turb, "{q} vs {turb}");
        assert_eq!(v.orifice(cda, -dp), -q);
        // p_cr = (ρ/2)·(Re·ν/(Cd·D_H))², D_H = √(4A/π).
        let dh = (4.0 * a / core::f64::consts::PI).sqrt();
        let pcr = 890.0 / 2.0 * (12.0 * 46e-6 / (0.67 * dh)).powi(2);
        let small = pcr * 1e-6;
        let lin = 0.67 * a * (2.0 / 890.0_f64).sqrt() * small / pcr.sqrt();
        let ql = v.orifice(cda, small);
        assert!((ql - lin).abs() <= 1e-6 * lin, "{ql} vs {lin}");
        assert_eq!(v.orifice(0.0, dp), 0.0);
        assert_eq!(v.orifice(cda, 0.0), 0.0);
    }

    /// Hopsan's edge layout: with a 0.1 mm overlap nothing flows at
    /// |x_v| ≤ 0.1 mm; beyond, P→A and B→T open for x_v > 0, P→B and A→T
    /// for x_v < 0, with area π·d·(|x_v| − lap).
    #[test]
    fn laps_and_edges() {
        let v = hopsan_like();
        assert_eq!(v.openings(0.5e-4), [0.0; 4]);
        assert_eq!(v.openings(-0.5e-4), [0.0; 4]);
        let o = v.openings(3e-4);
        assert!((o[0] - 2e-4).abs() < 1e-18 && o[1] == 0.0 && o[2] == 0.0);
        assert!((o[3] - 2e-4).abs() < 1e-18);
        let f = v.flows(0.0, 2e7, 1e5, 1e7, 1e7);
        assert_eq!(f, Flows::default());
        let f = v.flows(3e-4, 2e7, 1e5, 1e7, 1e6);
        assert!(f.a > 0.0 && f.b < 0.0 && f.p > 0.0 && f.t > 0.0);
        // Conservation: what the supply gives and the tank takes balances
        // what the chambers take.
        assert!((f.p - f.t - (f.a + f.b)).abs() <= 1e-15 * f.p);
        assert!(v.loss(3e-4, 2e7, 1e5, 1e7, 1e6) > 0.0);
    }

    /// ∂q/∂(Cd·A) against a central difference of the orifice law, in the
    /// laminar, transitional and turbulent regions and for both signs of
    /// Δp; far from the laminar region it is the turbulent √(2Δp/ρ).
    #[test]
    fn orifice_area_slope_is_the_laws_derivative() {
        let v = hopsan_like();
        for a in [1e-12, 1e-10, 1e-8, 1e-6] {
            for dp in [-5e6, -1e3, -1.0, 1.0, 1e3, 5e6] {
                let cda = 0.67 * a;
                let h = 1e-6 * cda;
                let fd = (v.orifice(cda + h, dp) - v.orifice(cda - h, dp)) / (2.0 * h);
                let an = v.orifice_area_slope(cda, dp);
                assert!(
                    (an - fd).abs() <= 1e-6 * fd.abs() + 1e-300,
                    "A = {a}, Δp = {dp}: {an} vs {fd}"
                );
            }
        }
        // Turbulent: A·Δp ≫ k, so the slope is √(2/ρ)·√Δp to O((k/AΔp)²).
        let dp = 5e6;
        let turb = (2.0 * dp / 890.0f64).sqrt();
        assert_eq!(v.turbulent_area_slope(dp), turb);
        assert_eq!(v.turbulent_area_slope(-dp), -turb);
        let an = v.orifice_area_slope(0.67 * 1e-6, dp);
        assert!((an - turb).abs() <= 1e-6 * turb, "{an} vs {turb}");
        assert_eq!(v.orifice_area_slope(0.0, dp), 0.0);
    }

    #[test]
    fn rated_flow_gives_the_lands_gain_and_bad_keys_are_named() {
        // Q_nom = 40 L/min at Δp_nom = 70 bar, x_max = 0.5 mm.
        let q = 40e-3 / 60.0;
        let v = SpoolValve::try_new(
            &ValveCfg {
                spool_limit: 5e-4,
                rated_signal: Some(10.0),
                rated_flow: Some(q),
                rated_drop: Some(70e5),
                ..Default::default()
            },
            850.0,
            46e-6,
        )
        .unwrap();
        assert!((v.kv - 5e-5).abs() < 1e-20);
        // Through P→A then B→T at full opening, 35 bar each: Q_nom.
        let qa = v.orifice(v.cdw[0] * 5e-4, 35e5);
        assert!((qa - q).abs() <= 1e-4 * q, "{qa} vs {q}");
        let bad = |c: ValveCfg| SpoolValve::try_new(&c, 850.0, 46e-6).unwrap_err().key;
        let ok = ValveCfg {
            spool_limit: 1e-3,
            gain: Some(1e-4),
            discharge_coefficient: Some(0.6),
            spool_diameter: Some(0.008),
            ..Default::default()
        };
        assert!(SpoolValve::try_new(&ok, 850.0, 46e-6).is_ok());
        assert_eq!(
            bad(ValveCfg {
                lap: Some(Edges::All(2e-3)),
                ..ok
            }),
            "lap"
        );
        assert_eq!(bad(ValveCfg { gain: None, ..ok }), "gain");
        let e = SpoolValve::try_new(
            &ValveCfg {
                lap: Some(Edges::All(2e-3)),
                ..ok
            },
            850.0,
            46e-6,
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "`lap`: edge 1 overlaps by 0.002 m, as much as the spool travel (0.001 m): it never opens"
        );
        assert_eq!(
            bad(ValveCfg {
                rated_flow: Some(1e-3),
                ..ok
            }),
            "rated_flow"
        );
        assert_eq!(
            bad(ValveCfg {
                spool_diameter: None,
                ..ok
            }),
            "spool_diameter"
        );
    }
}
