//! `[plant.hose]`: the hoses from the valve to the cylinder's ports, as a
//! hose datasheet gives them (inner diameter, the wall's volumetric
//! expansion under pressure) and as the machine is plumbed (each hose's
//! length).
//!
//! **The model.** A hose of inner diameter d and length L holds
//! V_h = π·d²/4·L of oil. Under a pressure rise dp its oil is compressed
//! by V_h·dp/βe and its wall swells by V_h·dp/β_w, where β_w is the wall's
//! compliance written as a bulk modulus (β_w = V_h·Δp/ΔV_wall, what a
//! datasheet's volumetric expansion ΔV/L at a pressure Δp gives:
//! β_w = (π·d²/4)·Δp/(ΔV/L)). Both store oil at the chamber's pressure,
//! so the hose adds to the chamber it feeds the equivalent oil volume
//!
//! ```text
//! V_eq = V_h·(1 + βe/β_w)
//! ```
//!
//! (its capacitance dV/dp = V_h/βe + V_h/β_w = V_eq/βe), and the chamber's
//! pressure obeys the cylinder's equation (V/βe)·ṗ = Σq with V = V_0 +
//! V_eq + A·y. Merritt, *Hydraulic Control Systems* (Wiley, 1967), §2.3,
//! composes an effective bulk modulus from the oil's and the container's
//! the same way (1/βe_eff = 1/β_oil + 1/β_container, per unit volume);
//! here only the hose's share of the volume is compliant, the steel
//! cylinder is taken rigid.
//!
//! **Left out:** the hose's flow resistance and the oil's inertia in it
//! (the hose is one pressure with the chamber: a lumped capacitance, not a
//! line). [`drop`] states the resistance at a flow (laminar f = 64/Re
//! below Re = 2300, Blasius f = 0.3164·Re^(−1/4) above: White, *Fluid
//! Mechanics*, 7th ed., eqs. 6.12 and 6.55), and `ehservo check` warns when
//! it is more than 5 % of the supply at the valve's full flow, where
//! folding the hose into the chamber stops being a fair model.

use crate::error::{positive, KeyError};
use serde::{Deserialize, Serialize};

/// `[plant.hose]`.
///
/// ```
/// use ehservo_sim::hose::HoseCfg;
///
/// // 2 m of DN10 hose to each port, swelling by 0.5 cm³ per metre at 100
/// // bar (a datasheet's volumetric expansion).
/// let h: HoseCfg = toml::from_str(r#"
/// inner_diameter = 0.010
/// length_a = 2.0
/// length_b = 2.0
/// volumetric_expansion = 5e-7
/// expansion_pressure = 1e7
/// "#).unwrap();
/// // V_h = π/4·0.01²·2 = 1.5708e-4 m³; β_w = (π/4·0.01²)·1e7/5e-7
/// // = 1.5708e9 Pa; with βe = 1.4e9, V_eq = V_h·(1 + 1.4/1.5708).
/// let [va, vb] = h.equivalent_volumes(1.4e9).unwrap();
/// let vh = std::f64::consts::FRAC_PI_4 * 1e-4 * 2.0;
/// let want = vh * (1.0 + 1.4e9 / (std::f64::consts::FRAC_PI_4 * 1e-4 * 1e7 / 5e-7));
/// assert!((va - want).abs() < 1e-12 * want && va == vb);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct HoseCfg {
    /// Inner diameter d (m), the datasheet's I.D.
    pub inner_diameter: f64,
    /// Length of the hose from the valve's port A to the cylinder's A (m).
    pub length_a: f64,
    /// Length of the hose to the cylinder's B (m).
    pub length_b: f64,
    /// The wall's compliance as a bulk modulus β_w = V_h·Δp/ΔV (Pa); or
    /// give `volumetric_expansion` and `expansion_pressure`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_bulk_modulus: Option<f64>,
    /// The datasheet's volumetric expansion ΔV/L (m³ per metre of hose)
    /// at `expansion_pressure`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub volumetric_expansion: Option<f64>,
    /// The pressure of `volumetric_expansion` (Pa).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub expansion_pressure: Option<f64>,
}

impl HoseCfg {
    /// The bore's cross-section π·d²/4 (m²), checked.
    fn section(&self) -> Result<f64, KeyError> {
        let d = positive("inner_diameter", self.inner_diameter)?;
        Ok(std::f64::consts::FRAC_PI_4 * d * d)
    }

    /// β_w (Pa), from `wall_bulk_modulus` or the volumetric expansion.
    pub fn wall_bulk_modulus(&self) -> Result<f64, KeyError> {
        match (
            self.wall_bulk_modulus,
            self.volumetric_expansion,
            self.expansion_pressure,
        ) {
            (Some(b), None, None) => positive("wall_bulk_modulus", b),
            (None, Some(dv), Some(p)) => {
                let dv = positive("volumetric_expansion", dv)?;
                let p = positive("expansion_pressure", p)?;
                Ok(self.section()? * p / dv)
            }
            (None, Some(_), None) => Err(KeyError::new(
                "expansion_pressure",
                "required with volumetric_expansion: the pressure (Pa) at which the datasheet states it",
            )),
            (None, None, Some(_)) => Err(KeyError::new(
                "volumetric_expansion",
                "required with expansion_pressure",
            )),
            (None, None, None) => Err(KeyError::new(
                "wall_bulk_modulus",
                "the hose's compliance is required: wall_bulk_modulus (Pa), or volumetric_expansion (m³/m) with expansion_pressure (Pa)",
            )),
            _ => Err(KeyError::new(
                "wall_bulk_modulus",
                "give either wall_bulk_modulus or volumetric_expansion with expansion_pressure, not both",
            )),
        }
    }

    /// The equivalent oil volumes V_h·(1 + βe/β_w) the hoses add to
    /// chambers A and B (m³), under the oil's βe; the error is the key
    /// inside `[plant.hose]`.
    pub fn equivalent_volumes(&self, beta: f64) -> Result<[f64; 2], KeyError> {
        let s = self.section()?;
        let bw = self.wall_bulk_modulus()?;
        let la = positive("length_a", self.length_a)?;
        let lb = positive("length_b", self.length_b)?;
        let k = 1.0 + beta / bw;
        Ok([s * la * k, s * lb * k])
    }

    /// The longer hose's pressure drop (Pa) at the flow `q` (m³/s) of an
    /// oil of density `rho` (kg/m³) and kinematic viscosity `nu` (m²/s).
    pub fn drop(&self, q: f64, rho: f64, nu: f64) -> f64 {
        let d = self.inner_diameter;
        drop(d, self.length_a.max(self.length_b), q, rho, nu)
    }
}

/// The Darcy–Weisbach drop Δp = f·(L/d)·ρ·v²/2 (Pa) over a pipe of
/// diameter `d` and length `l` (m) at the flow `q` (m³/s): f = 64/Re
/// (laminar, Re < 2300) or 0.3164·Re^(−1/4) (Blasius, smooth and turbulent).
/// 0 for a degenerate pipe or no flow.
pub fn drop(d: f64, l: f64, q: f64, rho: f64, nu: f64) -> f64 {
    if !(d > 0.0 && l > 0.0 && nu > 0.0 && q.is_finite()) || q == 0.0 {
        return 0.0;
    }
    let v = q.abs() / (std::f64::consts::FRAC_PI_4 * d * d);
    let re = v * d / nu;
    let f = if re < 2300.0 {
        64.0 / re
    } else {
        0.3164 * re.powf(-0.25)
    };
    f * (l / d) * rho * v * v / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Laminar: Hagen–Poiseuille Δp = 128·μ·L·Q/(π·d⁴), μ = ρ·ν. 1 L/min
    /// through 2 m of 10 mm hose of ISO VG 46 (ν = 46e-6, ρ = 870):
    /// v = 1.6667e-5/7.854e-5 = 0.2122 m/s, Re = 0.2122·0.01/46e-6 = 46.1.
    #[test]
    fn a_laminar_drop_is_hagen_poiseuille() {
        let (d, l, q, rho, nu): (f64, f64, f64, f64, f64) = (0.01, 2.0, 1e-3 / 60.0, 870.0, 46e-6);
        let hp = 128.0 * rho * nu * l * q / (std::f64::consts::PI * d.powi(4));
        let got = drop(d, l, q, rho, nu);
        assert!((got - hp).abs() < 1e-9 * hp, "{got} vs {hp}");
    }

    /// Turbulent: 100 L/min through 2 m of 10 mm hose at ν = 10e-6 (a thin
    /// oil): v = 1.6667e-3/7.854e-5 = 21.22 m/s, Re = 21221 (turbulent),
    /// f = 0.3164·21221^(−1/4) = 0.02622, Δp = 0.02622·200·870·21.22²/2
    /// = 1.027e6 Pa.
    #[test]
    fn a_turbulent_drop_is_blasius() {
        let got = drop(0.01, 2.0, 100e-3 / 60.0, 870.0, 10e-6);
        assert!((got / 1.027e6 - 1.0).abs() < 1e-3, "{got}");
    }

    /// With the valve closed, a small velocity rings at the oil column's
    /// ω_h = √(βe·(A_A²/V_A + A_B²/V_B)/M), the hoses' oil and swelling in
    /// V_A and V_B: 63/36 mm, M = 250 kg, dead volumes 2e-4 m³, βe =
    /// 1.4e9; 2 m of 10 mm hose to A and 1 m to B with β_w = 5e8, so
    /// V_eq = π/4·0.01²·L·(1 + 1.4e9/5e8) = 5.9690e-4 (A), 2.9845e-4 (B).
    #[test]
    fn the_rod_rings_at_the_frequency_of_the_hoses_volumes() {
        use crate::cylinder::CylinderCfg;
        use crate::plant::{Factors, Plant, PlantConfig, PlantContext, UncertaintySpec};
        let cfg: CylinderCfg = toml::from_str(
            r#"
            [cylinder]
            bore = 0.063
            rod_diameter = 0.036
            stroke = 0.5
            dead_volume_a = 2e-4
            dead_volume_b = 2e-4
            [fluid]
            density = 870.0
            bulk_modulus = 1.4e9
            [valve]
            spool_limit = 5e-4
            gain = 5e-5
            discharge_coefficient = 0.65
            area_gradient = 0.02
            [supply]
            kind = "fixed"
            pressure = 2e7
            [load]
            mass = 250.0
            [hose]
            inner_diameter = 0.01
            length_a = 2.0
            length_b = 1.0
            wall_bulk_modulus = 5e8
            "#,
        )
        .unwrap();
        let ctx = PlantContext {
            load: None,
            load_given: false,
            uncertainty: UncertaintySpec::NONE,
            x0: [0.0; 3],
            base_dir: None,
            reference_range: None,
            quantity: Default::default(),
        };
        let p = cfg.build(&ctx).unwrap();
        let q = std::f64::consts::FRAC_PI_4;
        let (aa, ab) = (q * 0.063 * 0.063, q * (0.063 * 0.063 - 0.036 * 0.036));
        let y0 = 0.15;
        let va = 2e-4 + q * 1e-4 * 2.0 * 3.8 + aa * y0;
        let vb = 2e-4 + q * 1e-4 * 1.0 * 3.8 + ab * (0.5 - y0);
        let wh = (1.4e9 * (aa * aa / va + ab * ab / vb) / 250.0).sqrt();
        // Pressures balanced (no force), a 1 mm/s kick.
        let (pb, f) = (1e7, crate::cylinder::CylinderVariation { f: Factors::ONE });
        let mut s = [y0, 1e-3, ab * pb / aa, pb, 2e7, 0.0];
        let h = 1e-6;
        let (mut crossings, mut prev) = (Vec::new(), s[1]);
        for k in 0..200_000 {
            ehservo_core::rk4::rk4_step(
                |t, x: &[f64; 6], d: &mut [f64; 6]| p.deriv(t, x, 0.0, &f, d),
                k as f64 * h,
                &mut s,
                h,
            );
            if prev > 0.0 && s[1] <= 0.0 {
                crossings.push((k as f64 + prev / (prev - s[1])) * h);
            }
            prev = s[1];
        }
        let n = crossings.len() - 1;
        assert!(n >= 4, "{n}");
        let period = (crossings[n] - crossings[0]) / n as f64;
        let want = 2.0 * std::f64::consts::PI / wh;
        assert!((period / want - 1.0).abs() < 2e-4, "{period} vs {want}");
    }

    #[test]
    fn bad_hoses_name_their_key() {
        let ok = HoseCfg {
            inner_diameter: 0.01,
            length_a: 1.0,
            length_b: 1.0,
            wall_bulk_modulus: Some(5e8),
            ..Default::default()
        };
        assert!(ok.equivalent_volumes(1.4e9).is_ok());
        for (h, key) in [
            (
                HoseCfg {
                    inner_diameter: 0.0,
                    ..ok
                },
                "inner_diameter",
            ),
            (
                HoseCfg {
                    length_b: -1.0,
                    ..ok
                },
                "length_b",
            ),
            (
                HoseCfg {
                    wall_bulk_modulus: None,
                    ..ok
                },
                "wall_bulk_modulus",
            ),
            (
                HoseCfg {
                    volumetric_expansion: Some(1e-7),
                    ..ok
                },
                "wall_bulk_modulus",
            ),
            (
                HoseCfg {
                    wall_bulk_modulus: None,
                    volumetric_expansion: Some(1e-7),
                    ..ok
                },
                "expansion_pressure",
            ),
        ] {
            assert_eq!(h.equivalent_volumes(1.4e9).unwrap_err().key, key, "{h:?}");
        }
    }
}
