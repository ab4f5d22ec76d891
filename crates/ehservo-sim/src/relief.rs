//! The pump's relief valve, from Hopsan's coefficients or from a datasheet.
//!
//! Hopsan's `HydraulicPressureReliefValve` (Hopsan/hopsan,
//! componentLibraries/defaultLibrary/Hydraulic/Valves/PressureControlValves/
//! HydraulicPressureReliefValve.hpp) opens by
//!
//! ```text
//! x_s(p) = (p − p_max)/b1,   b1 = C_s + C_f·(p − P_t)         (lines 140–144, 185)
//! x     : first-order lag of x_s, time constant τ, in [0, x_max] (lines 111–114, 192–196)
//! Q     = x·√(p − P_t)                                        (lines 199–200)
//! C_s = √p_nom/k_cs,  C_f = 1/(k_cf·√p_nom),  x_max = q_nom/√p_nom,  p_nom = 7 MPa (lines 100–106)
//! ```
//!
//! A datasheet gives none of k_cs, k_cf, q_nom: it gives the p–Q curve of
//! the valve (the cracking pressure p_c where flow starts, and the pressure
//! p_r it reaches at the rated flow Q_r, the "pressure override" p_r − p_c)
//! and, sometimes, a response time t_r. The datasheet keys map onto the same
//! model with
//!
//! ```text
//! p_max = p_c                          (x_s = 0 at the cracking pressure)
//! C_f   = 0                            (k_cf → ∞: no flow-force term; the two
//!                                       points fix two coefficients, not three)
//! x_max = Q_r/√(p_r − P_t)             (the rated flow passes fully open at p_r)
//! C_s   = (p_r − p_c)/x_max            (x_s(p_r) = x_max)
//!       = (p_r − p_c)·√(p_r − P_t)/Q_r
//! τ     = t_r/ln 10                    (t_r: the time the opening takes to
//!                                       cover 90 % of a step, e^(−t_r/τ) = 0.1)
//! ```
//!
//! so the steady curve passes through (p_c, 0) and (p_r, Q_r):
//! Q(p) = (p − p_c)·√(p − P_t)/C_s between them, and the fully open orifice
//! x_max·√(p − P_t) above p_r. In Hopsan's own keys that is
//! `k_cs = √p_nom/C_s`, `q_nom = x_max·√p_nom` and `k_cf` large (C_f → 0).

use crate::error::{positive, KeyError};

/// The rated pressure of Hopsan's relief characteristic, `mPnom = 7e6f`
/// (HydraulicPressureReliefValve.hpp line 100).
pub const RELIEF_P_NOM: f64 = 7e6;

/// The relief's constants in Hopsan's form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relief {
    /// p_max: the cracking pressure (Pa).
    pub p_max: f64,
    /// 1/τ (1/s).
    pub rate: f64,
    /// C_s (Pa·s/m³·√Pa).
    pub cs: f64,
    /// C_f.
    pub cf: f64,
    /// x_max (m³/(s·√Pa)).
    pub x_max: f64,
}

/// The relief's keys as `[plant.supply]` gives them: Hopsan's four, or a
/// datasheet's three, each beside the cracking pressure `relief_pressure`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ReliefKeys {
    /// `relief_time_constant`, τ (s).
    pub time_constant: Option<f64>,
    /// `relief_k_cs`.
    pub k_cs: Option<f64>,
    /// `relief_k_cf`.
    pub k_cf: Option<f64>,
    /// `relief_q_nom` (m³/s).
    pub q_nom: Option<f64>,
    /// `relief_full_flow_pressure`, p_r (Pa).
    pub full_flow_pressure: Option<f64>,
    /// `relief_rated_flow`, Q_r (m³/s).
    pub rated_flow: Option<f64>,
    /// `relief_response_time`, t_r (s).
    pub response_time: Option<f64>,
}

const HOPSAN: [&str; 4] = [
    "relief_time_constant",
    "relief_k_cs",
    "relief_k_cf",
    "relief_q_nom",
];
const DATASHEET: [&str; 3] = [
    "relief_full_flow_pressure",
    "relief_rated_flow",
    "relief_response_time",
];

impl ReliefKeys {
    /// The relief valve cracking at `p_max` over the tank at `pt`, from
    /// whichever form was given. Giving keys of both forms, or an
    /// incomplete one, is refused (the error names the first key at
    /// fault); so is a full-flow pressure at or below the cracking one.
    pub fn resolve(&self, p_max: f64, pt: f64) -> Result<Relief, KeyError> {
        let hopsan = [self.time_constant, self.k_cs, self.k_cf, self.q_nom];
        let sheet = [self.full_flow_pressure, self.rated_flow, self.response_time];
        let given = |v: &[Option<f64>], names: &[&'static str]| {
            names
                .iter()
                .zip(v)
                .filter(|(_, x)| x.is_some())
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
        };
        let (h, d) = (given(&hopsan, &HOPSAN), given(&sheet, &DATASHEET));
        if !h.is_empty() && !d.is_empty() {
            return Err(KeyError::new(
                d[0],
                format!(
                    "give one form of the relief, its datasheet's keys or Hopsan's coefficients, not both (`{}` of Hopsan's given too)",
                    h[0]
                ),
            ));
        }
        let missing = |v: &[Option<f64>], names: &[&'static str], form: &str| {
            let i = v.iter().position(Option::is_none).unwrap_or(0);
            KeyError::new(
                names[i],
                format!(
                    "missing: the relief by its {form} needs {}",
                    names.join(", ")
                ),
            )
        };
        if !d.is_empty() {
            let [Some(pr), Some(qr), Some(tr)] = sheet else {
                return Err(missing(&sheet, &DATASHEET, "datasheet"));
            };
            return from_datasheet(p_max, pt, pr, qr, tr);
        }
        let [Some(tau), Some(kcs), Some(kcf), Some(qn)] = hopsan else {
            return Err(missing(&hopsan, &HOPSAN, "Hopsan coefficients"));
        };
        let tau = positive("relief_time_constant", tau)?;
        let kcs = positive("relief_k_cs", kcs)?;
        let kcf = positive("relief_k_cf", kcf)?;
        let qn = positive("relief_q_nom", qn)?;
        let sq = RELIEF_P_NOM.sqrt();
        Ok(Relief {
            p_max,
            rate: 1.0 / tau,
            cs: sq / kcs,
            cf: 1.0 / (kcf * sq),
            x_max: qn / sq,
        })
    }
}

/// The module's datasheet mapping: cracking at `pc`, the rated flow `qr` at
/// `pr`, 90 % of a step in `tr`, over the tank at `pt`.
fn from_datasheet(pc: f64, pt: f64, pr: f64, qr: f64, tr: f64) -> Result<Relief, KeyError> {
    let pr = positive("relief_full_flow_pressure", pr)?;
    let qr = positive("relief_rated_flow", qr)?;
    let tr = positive("relief_response_time", tr)?;
    if pr <= pc {
        return Err(KeyError::new(
            "relief_full_flow_pressure",
            format!(
                "must be above the cracking pressure relief_pressure = {pc:e} Pa: the p–Q curve rises with the flow (got {pr:e})"
            ),
        ));
    }
    let x_max = qr / (pr - pt).sqrt();
    Ok(Relief {
        p_max: pc,
        rate: core::f64::consts::LN_10 / tr,
        cs: (pr - pc) / x_max,
        cf: 0.0,
        x_max,
    })
}

impl Relief {
    /// Hopsan's keys `(k_cs, q_nom)` of this relief (for a Hopsan model of
    /// it; `k_cf` is then any value large enough that C_f·Δp ≪ C_s).
    pub fn hopsan_keys(&self) -> (f64, f64) {
        let sq = RELIEF_P_NOM.sqrt();
        (sq / self.cs, self.x_max * sq)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sheet(pr: f64, qr: f64, tr: f64) -> ReliefKeys {
        ReliefKeys {
            full_flow_pressure: Some(pr),
            rated_flow: Some(qr),
            response_time: Some(tr),
            ..ReliefKeys::default()
        }
    }

    /// The datasheet's two points, by hand: cracking at 230 bar, 250 bar at
    /// 100 L/min (1/600 m³/s), over a tank at 1 bar, 90 % in 10 ms.
    /// x_max = (1/600)/√(249e5) = 3.3400e-7; C_s = 20e5/x_max = 5.9880e12;
    /// τ = 0.01/ln 10 = 4.3429e-3 s. The steady flow at p is
    /// x_s(p)·√(p − P_t) with x_s = (p − 230e5)/C_s: 0 at 230 bar,
    /// 1/600 m³/s at 250 bar, and at 240 bar half the override,
    /// (10e5/C_s)·√(239e5) = 8.1643e-4 m³/s.
    #[test]
    #[allow(clippy::float_cmp)] // C_f = 0 and the closed valve are exact
    fn the_datasheet_points_are_on_the_steady_curve() {
        let r = sheet(250e5, 1.0 / 600.0, 0.01).resolve(230e5, 1e5).unwrap();
        let x_max = (1.0 / 600.0) / 249e5_f64.sqrt();
        assert!((r.x_max - x_max).abs() <= 1e-12 * x_max);
        assert!((r.x_max - 3.3400e-7).abs() < 1e-10, "{}", r.x_max);
        assert!((r.cs - 5.9880e12).abs() < 1e9, "{}", r.cs);
        assert!((1.0 / r.rate - 4.3429e-3).abs() < 1e-7);
        assert_eq!(r.cf, 0.0);
        let q = |p: f64| {
            ((p - r.p_max) / (r.cs + r.cf * (p - 1e5))).clamp(0.0, r.x_max) * (p - 1e5).sqrt()
        };
        assert_eq!(q(230e5), 0.0);
        assert!((q(250e5) - 1.0 / 600.0).abs() <= 1e-12, "{}", q(250e5));
        assert!((q(240e5) - 8.1643e-4).abs() < 1e-8, "{}", q(240e5));
        // Above the full-flow pressure the valve is a fixed orifice.
        assert!((q(300e5) - x_max * 299e5_f64.sqrt()).abs() < 1e-12);
        // Hopsan's keys of the same valve: k_cs = √7e6/C_s, q_nom = x_max·√7e6.
        let (kcs, qn) = r.hopsan_keys();
        assert!((kcs - 7e6_f64.sqrt() / 5.9880e12).abs() < 1e-3 * kcs);
        assert!((qn - x_max * 7e6_f64.sqrt()).abs() < 1e-12 * qn);
    }

    #[test]
    fn the_forms_are_not_mixed_and_the_curve_rises() {
        let mut both = sheet(250e5, 1e-3, 0.01);
        both.k_cs = Some(1e-8);
        let e = both.resolve(230e5, 0.0).unwrap_err();
        assert_eq!(e.key, "relief_full_flow_pressure");
        assert!(e.reason.contains("not both (`relief_k_cs` of"), "{e}");
        let e = ReliefKeys {
            rated_flow: Some(1e-3),
            ..ReliefKeys::default()
        }
        .resolve(230e5, 0.0)
        .unwrap_err();
        assert_eq!(e.key, "relief_full_flow_pressure");
        assert!(e.reason.contains("missing"), "{e}");
        let e = ReliefKeys::default().resolve(230e5, 0.0).unwrap_err();
        assert_eq!(e.key, "relief_time_constant");
        let e = sheet(220e5, 1e-3, 0.01).resolve(230e5, 0.0).unwrap_err();
        assert_eq!(e.key, "relief_full_flow_pressure");
        assert!(e.reason.contains("above the cracking pressure"), "{e}");
        let e = sheet(250e5, 0.0, 0.01).resolve(230e5, 0.0).unwrap_err();
        assert_eq!(e.key, "relief_rated_flow");
    }
}
