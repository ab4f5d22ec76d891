//! A valve-controlled double-rod (symmetric) hydraulic cylinder driving its
//! load through a rack and pinion, and the paper's rotary-servo parameters
//! that its linearisation at mid-stroke is equal to (docs/cylinder.md).
//!
//! ```text
//! θ = y/r                                              rack and pinion
//! M·ÿ = A·(P1 − P2) − B·ẏ − K·y − Ff(ẏ) − Tl(θ, θ̇)/r     force balance
//! (V0 + A·y)/βe·Ṗ1 =  Q1 − A·ẏ − Cl·(P1 − P2)            chamber 1
//! (V0 − A·y)/βe·Ṗ2 = −Q2 + A·ẏ + Cl·(P1 − P2)            chamber 2
//! x_v = Kv·u
//! x_v ≥ 0: Q1 = Cd·w·x_v·√(2/ρ·(Ps − P1)),  Q2 = Cd·w·x_v·√(2/ρ·(P2 − Pt))
//! x_v < 0: Q1 = Cd·w·x_v·√(2/ρ·(P1 − Pt)),  Q2 = Cd·w·x_v·√(2/ρ·(Ps − P2))
//! ```
//!
//! `Q1` flows into chamber 1, `Q2` out of chamber 2; the tank is at
//! `Pt = 0`. A negative pressure drop across an open orifice (a chamber
//! above supply, or below tank, which only compressibility transients can
//! produce) would make the root imaginary: its argument is clamped at 0
//! (no flow through that edge, never NaN) and the clamp is reported, as
//! [`ServoParams::flow_gain`] does.
//!
//! With `P1 + P2 = Ps` (the symmetric valve's steady state) and
//! `P_L = P1 − P2`, both flows are the load flow
//! `Q_L = Cd·w·x_v·√((Ps − sgn(x_v)·P_L)/ρ)`: the paper's valve law (2)
//! with `Ag = w`. Linearised at the centre the cylinder is the paper's
//! (1)–(6) under the mapping of [`CylinderParams::nominal_servo_params`].

use crate::error::{non_negative, positive, ParamError};
use crate::math::{exp, sqrt};
use crate::servo::{Friction, ServoParams};

/// Parameters of the cylinder, its valve and its rack, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
pub struct CylinderParams {
    /// Supply pressure Ps (Pa); the tank is at 0.
    #[cfg_attr(feature = "serde", serde(rename = "Ps"))]
    pub ps: f64,
    /// Effective bulk modulus βe (Pa).
    pub beta_e: f64,
    /// Fluid mass density ρ (kg/m³).
    pub rho: f64,
    /// Discharge coefficient Cd (–).
    #[cfg_attr(feature = "serde", serde(rename = "Cd"))]
    pub cd: f64,
    /// Area gradient of each metering edge w (m): orifice area w·|x_v|.
    pub w: f64,
    /// Spool opening per volt Kv (m/V): x_v = Kv·u.
    #[cfg_attr(feature = "serde", serde(rename = "Kv"))]
    pub kv: f64,
    /// Piston (annulus) area A (m²), the same on both sides.
    #[cfg_attr(feature = "serde", serde(rename = "A"))]
    pub area: f64,
    /// Volume of each chamber at mid-stroke, lines included, V0 (m³).
    #[cfg_attr(feature = "serde", serde(rename = "V0"))]
    pub v0: f64,
    /// Full stroke (m): the piston travels y ∈ [−stroke/2, stroke/2].
    pub stroke: f64,
    /// Moving mass M (kg): piston, rods, rack and the load referred to y.
    #[cfg_attr(feature = "serde", serde(rename = "M"))]
    pub mass: f64,
    /// Viscous friction B (N·s/m).
    #[cfg_attr(feature = "serde", serde(rename = "B"))]
    pub damping: f64,
    /// Load spring K (N/m).
    #[cfg_attr(feature = "serde", serde(rename = "K"))]
    pub spring: f64,
    /// Internal (cross-piston) leakage Cl (m³/(s·Pa)).
    #[cfg_attr(feature = "serde", serde(rename = "Cl"))]
    pub leakage: f64,
    /// Pinion radius r (m): θ = y/r.
    pub r: f64,
    /// Seal friction as a force (N, m/s, N·s/m): the core's Coulomb–
    /// Stribeck–viscous law read in linear units. Not in the nominal model.
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub friction: Option<Friction>,
}

/// The documented typical set (docs/cylinder.md): the paper's fluid,
/// supply and discharge coefficient, a 32 mm bore with 20 mm rods, 100 mm
/// stroke, 20 kg, on a 0.1 m pinion.
impl Default for CylinderParams {
    fn default() -> Self {
        Self::typical()
    }
}

impl CylinderParams {
    /// The documented typical set (see [`Default`]).
    pub const fn typical() -> Self {
        Self {
            ps: 13.795e6,
            beta_e: 344.875e6,
            rho: 850.0,
            cd: 0.67,
            w: 2.0e-3,
            kv: 5.0e-5,
            // π/4·(0.032² − 0.020²)
            area: 4.900_884_539_600_077e-4,
            // A·stroke/2 + 1e-5 m³ of lines and ports.
            v0: 3.450_442_269_800_039e-5,
            stroke: 0.1,
            mass: 20.0,
            damping: 1000.0,
            spring: 0.0,
            leakage: 1.0e-12,
            r: 0.1,
            friction: None,
        }
    }

    /// Checks every parameter; the names are the scenario keys.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("Ps", self.ps)?;
        positive("beta_e", self.beta_e)?;
        positive("rho", self.rho)?;
        positive("Cd", self.cd)?;
        positive("w", self.w)?;
        positive("Kv", self.kv)?;
        positive("A", self.area)?;
        positive("V0", self.v0)?;
        positive("stroke", self.stroke)?;
        positive("M", self.mass)?;
        non_negative("B", self.damping)?;
        non_negative("K", self.spring)?;
        non_negative("Cl", self.leakage)?;
        positive("r", self.r)?;
        if self.v0 <= self.area * self.half_stroke() {
            return Err(ParamError::new(
                "V0",
                "must exceed A·stroke/2: a chamber would have no volume at the end of the stroke",
                self.v0,
            ));
        }
        if let Some(f) = &self.friction {
            f.validate()?;
        }
        Ok(())
    }

    /// Half the stroke: |y| ≤ stroke/2.
    pub fn half_stroke(&self) -> f64 {
        0.5 * self.stroke
    }

    /// The angle the end of the stroke maps to, stroke/(2r) (rad).
    pub fn stroke_angle(&self) -> f64 {
        self.half_stroke() / self.r
    }

    /// Chamber volumes (V1, V2) at `y`, floored at their end-of-stroke
    /// values (beyond the stroke the run is stopped as diverged; the floor
    /// only keeps a last RK4 stage finite).
    #[inline]
    pub fn volumes(&self, y: f64) -> (f64, f64) {
        let vmin = self.v0 - self.area * self.half_stroke();
        let ay = self.area * y;
        ((self.v0 + ay).max(vmin), (self.v0 - ay).max(vmin))
    }

    /// Valve flows `(Q1 into chamber 1, Q2 out of chamber 2, clamped)` at
    /// spool opening `xv` and chamber pressures `p1`, `p2`; `clamped` when
    /// a root's argument was negative and set to 0.
    #[inline]
    pub fn valve_flows(&self, xv: f64, p1: f64, p2: f64) -> (f64, f64, bool) {
        let (d1, d2) = if xv >= 0.0 {
            (self.ps - p1, p2)
        } else {
            (p1, self.ps - p2)
        };
        let k = self.cd * self.w * xv;
        let two_rho = 2.0 / self.rho;
        let q1 = k * sqrt(two_rho * d1.max(0.0));
        let q2 = k * sqrt(two_rho * d2.max(0.0));
        (q1, q2, xv != 0.0 && (d1 < 0.0 || d2 < 0.0))
    }

    /// Seal friction force at rod speed `v` (0 without friction).
    #[inline]
    pub fn friction_force(&self, v: f64) -> f64 {
        self.friction.map_or(0.0, |f| f.torque(v))
    }

    /// The valve's flow gain at the centre, Kq = ∂Q_L/∂x_v = Cd·w·√(Ps/ρ)
    /// (m²/s).
    pub fn flow_gain_at_centre(&self) -> f64 {
        self.cd * self.w * sqrt(self.ps / self.rho)
    }

    /// The paper's rotary-servo parameters whose model (1)–(6) is this
    /// cylinder linearised at mid-stroke (docs/cylinder.md):
    ///
    /// | paper | cylinder |
    /// |---|---|
    /// | Dm | A·r |
    /// | Jt | M·r² |
    /// | Bm | B·r² |
    /// | G | K·r² |
    /// | Vt | 2·V0 |
    /// | Kce | Cl (a critically centred ideal valve has Kc = 0 at null) |
    /// | Ag, Kv, Cd, ρ, Ps, βe | w, Kv, Cd, ρ, Ps, βe |
    ///
    /// The seal friction is not part of it.
    pub fn nominal_servo_params(&self) -> ServoParams {
        ServoParams {
            ps: self.ps,
            beta_e: self.beta_e,
            vt: 2.0 * self.v0,
            kce: self.leakage,
            dm: self.area * self.r,
            jt: self.mass * self.r * self.r,
            bm: self.damping * self.r * self.r,
            kv: self.kv,
            g: self.spring * self.r * self.r,
            rho: self.rho,
            cd: self.cd,
            ag: self.w,
        }
    }

    /// Hydraulic potential of a volume of fluid entering at pressure `p`
    /// in this constant-βe model: π(p) = βe·(e^{p/βe} − 1) = p + O(p²/βe).
    /// The port power of a flow Q at pressure p is π(p)·Q.
    #[inline]
    pub fn port_potential(&self, p: f64) -> f64 {
        self.beta_e * (exp(p / self.beta_e) - 1.0)
    }

    /// Stored energy per unit chamber volume at pressure `p`:
    /// g(p) = βe·(e^{p/βe} − 1) − p ≥ 0 (≈ p²/(2βe)), the storage whose
    /// rate is exactly port power minus piston work (docs/cylinder.md).
    #[inline]
    pub fn compression_energy_density(&self, p: f64) -> f64 {
        self.port_potential(p) - p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typical_set_is_valid_and_consistent() {
        let c = CylinderParams::typical();
        c.validate().unwrap();
        let a = core::f64::consts::FRAC_PI_4 * (0.032 * 0.032 - 0.020 * 0.020);
        assert!((c.area - a).abs() < 1e-18);
        assert!((c.v0 - (a * 0.05 + 1e-5)).abs() < 1e-18);
        // The stroke maps to well beyond the paper's 5° reference.
        assert!(c.stroke_angle().to_degrees() > 20.0);
    }

    #[test]
    fn validation_names_the_key() {
        let bad = |f: fn(&mut CylinderParams)| {
            let mut c = CylinderParams::typical();
            f(&mut c);
            c.validate().unwrap_err().name
        };
        assert_eq!(bad(|c| c.area = -1e-4), "A");
        assert_eq!(bad(|c| c.v0 = c.area * c.stroke / 2.0), "V0");
        assert_eq!(bad(|c| c.r = 0.0), "r");
        assert_eq!(bad(|c| c.damping = f64::NAN), "B");
        assert_eq!(
            bad(|c| {
                c.friction = Some(Friction {
                    smoothing: 0.0,
                    ..Friction::default()
                })
            }),
            "smoothing"
        );
    }

    /// With P1 + P2 = Ps both edges carry Merritt's load flow
    /// Cd·w·x_v·√((Ps − sgn(x_v)·P_L)/ρ), which is the paper's Kg·x_v with
    /// Ag = w.
    #[test]
    fn symmetric_valve_is_the_papers_valve_law() {
        let c = CylinderParams::typical();
        let sp = c.nominal_servo_params();
        for &pl in &[-9e6, -1e6, 0.0, 2.5e6, 1.3e7] {
            let (p1, p2) = ((c.ps + pl) / 2.0, (c.ps - pl) / 2.0);
            for &u in &[-3.0, -0.1, 0.2, 4.0] {
                let xv = c.kv * u;
                let (q1, q2, clamped) = c.valve_flows(xv, p1, p2);
                assert!(!clamped);
                let ql = c.cd * c.w * xv * ((c.ps - xv.signum() * pl) / c.rho).sqrt();
                let (kg, _) = sp.flow_gain(pl, u.signum());
                for q in [q1, q2, kg * sp.kv * u] {
                    assert!((q - ql).abs() <= 1e-12 * ql.abs(), "{q} vs {ql}");
                }
            }
        }
    }

    #[test]
    fn reverse_drop_is_clamped_not_nan() {
        let c = CylinderParams::typical();
        let (q1, q2, clamped) = c.valve_flows(1e-4, c.ps + 1e5, -2e5);
        assert!(q1 == 0.0 && q2 == 0.0 && clamped);
        let (_, _, clamped) = c.valve_flows(0.0, c.ps + 1e5, -2e5);
        assert!(!clamped, "a closed valve has no flow to clamp");
    }
}
