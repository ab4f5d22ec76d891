//! The hydraulic supply: a fixed pressure, or a fixed-displacement pump
//! into a line volume with a pressure-relief valve, and the tank. The
//! relief is given by Hopsan's coefficients or by a datasheet
//! ([`crate::relief`]); `kind = "pc-pump"` is a pressure-compensated pump
//! ([`crate::pc_pump`]); either pump's line can carry a gas accumulator
//! ([`crate::accumulator`]). docs/cylinder.md §9.
//!
//! ```text
//! fixed:  Ps = const
//! pump:   (V_s/βe)·Ṗs = Q_pump − Q_P − Q_relief
//!         Q_pump   = D·n/(2π) − C_lp·(Ps − Pt)
//!         ẋr       = (x_s(Ps) − xr)/τ,  0 ≤ xr ≤ x_max  (ẋr = 0 at a limit it pushes against)
//!         x_s(p)   = (p − p_max)/(C_s + C_f·(p − Pt)),  C_s = √p_nom/k_cs,  C_f = 1/(k_cf·√p_nom)
//!         Q_relief = xr·√(Ps − Pt)  (Ps > Pt; a relief valve does not pass flow back)
//!         x_max    = q_nom/√p_nom,  p_nom = 7 MPa
//! ```
//!
//! The opening is a *limited* first-order lag: the limits act on its
//! output, not on its input. Hopsan's relief valve feeds the unlimited
//! static opening `xsh` to its filter (`HydraulicPressureReliefValve.hpp`
//! line 196, `mFilterLP.update(xsh)`), which was initialised with the
//! limits `[0, x0max]` (line 114); the filter clamps its output and stores
//! the clamped value as its state (`HopsanCore/src/ComponentUtilities/
//! FirstOrderTransferFunction.cpp` lines 169–185), so the opening reaches
//! 0 in finite time when the pressure falls below the setting and stays
//! there, with no wind-up. In the ODE that is ẋr = 0 at a limit it pushes
//! against, and the state put back inside the limits after each RK4 step
//! ([`Supply::limit_opening`], called through
//! [`crate::plant::Plant::limit_state`]), as the independent ODE of
//! `tests/data/hopsan/position_servo_ode.py` does (`deriv` and
//! `clamp_state`). Clamping the lag's *input* instead (its target
//! `clamp(x_s, 0, x_max)`) makes the opening decay as e^(−t/τ) and never
//! close.
//!
//! Q_P is what the 4/3 valve draws ([`crate::valve::Flows::p`]). The pump
//! and relief valve are Hopsan's `HydraulicFixedDisplacementPump` (its flow
//! `dp·n/(2π) + Clp·(p1 − p2)` from the inlet p1 to the outlet p2) and
//! `HydraulicPressureReliefValve` (its steady characteristic `b1 = Cs +
//! (p1 − p2)·Cf`, `xs = (p1 − p_max)/b1`, the first-order filter of time
//! constant `tao` limited to `[0, x0max]`, `x0max = q_nom/√p_nom`, `Cs =
//! √p_nom/k_cs`, `Cf = 1/(k_cf·√p_nom)`, `p_nom = 7e6`, the turbulent flow
//! `q = x0·√Δp`), read without their transmission-line terms (Hopsan/hopsan,
//! componentLibraries/defaultLibrary/Hydraulic/Pumps&Motors/
//! HydraulicFixedDisplacementPump.hpp and Valves/PressureControlValves/
//! HydraulicPressureReliefValve.hpp; docs/hopsan/position-servo.md has the
//! lines). Hopsan's relief hysteresis (`p_h`) is not modelled: the key is
//! refused unless 0. The line volume is Hopsan's `HydraulicVolumeMultiPort`
//! read the same way, `(V/βe)·ṗ = Σ q`.

use crate::accumulator::{line_stiffness, Accumulator, AccumulatorCfg};
use crate::error::{non_negative, positive, KeyError};
pub use crate::pc_pump::PcPump;
use crate::relief::ReliefKeys;
pub use crate::relief::RELIEF_P_NOM;
use serde::{Deserialize, Serialize};

/// `[plant.supply]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SupplyCfg {
    /// A constant supply pressure.
    Fixed {
        /// Ps (Pa).
        pressure: f64,
        /// Tank pressure Pt (Pa). Default 0.
        #[serde(default)]
        tank_pressure: f64,
    },
    /// A fixed-displacement pump, a line volume and a relief valve.
    Pump {
        /// Displacement D (m³/rev).
        displacement: f64,
        /// Shaft speed n (rad/s).
        speed: f64,
        /// Leakage coefficient C_lp (m³/(s·Pa)). Default 0.
        #[serde(default)]
        leakage: f64,
        /// Line volume V_s (m³).
        volume: f64,
        /// The line's bulk modulus (Pa); default the fluid's.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        bulk_modulus: Option<f64>,
        /// Relief cracking pressure p_max (Pa): the flow starts there.
        relief_pressure: f64,
        /// Relief spool time constant τ (s) (Hopsan's form).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        relief_time_constant: Option<f64>,
        /// Relief characteristic due to the spring, k_cs ((m³/s)/Pa) (Hopsan's form).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        relief_k_cs: Option<f64>,
        /// Relief characteristic due to flow forces, k_cf ((m³/s)/Pa) (Hopsan's form).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        relief_k_cf: Option<f64>,
        /// Relief flow at full opening and 7 MPa, q_nom (m³/s) (Hopsan's form).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        relief_q_nom: Option<f64>,
        /// The relief's pressure at its rated flow (Pa) (datasheet form:
        /// the p–Q curve's cracking pressure plus its override).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        relief_full_flow_pressure: Option<f64>,
        /// The relief's rated flow (m³/s), passed fully open at
        /// `relief_full_flow_pressure` (datasheet form).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        relief_rated_flow: Option<f64>,
        /// The relief's response time (s): 90 % of a step, τ = t/ln 10
        /// (datasheet form).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        relief_response_time: Option<f64>,
        /// Tank pressure Pt (Pa). Default 0.
        #[serde(default)]
        tank_pressure: f64,
        /// Ps(0) (Pa); default the tank pressure.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        initial_pressure: Option<f64>,
        /// A gas accumulator on the line.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        accumulator: Option<AccumulatorCfg>,
    },
    /// A pressure-compensated variable pump (Hopsan's
    /// HydraulicPressureControlledPump) into a line volume.
    PcPump {
        /// Maximum displacement D (m³/rev).
        displacement: f64,
        /// Shaft speed n (rad/s).
        speed: f64,
        /// Leakage coefficient C_lp (m³/(s·Pa)). Default 0.
        #[serde(default)]
        leakage: f64,
        /// Line volume V_s (m³).
        volume: f64,
        /// The line's bulk modulus (Pa); default the fluid's.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        bulk_modulus: Option<f64>,
        /// The compensator's setting p_dif (Pa): the pressure at zero
        /// displacement (dead head).
        compensator_pressure: f64,
        /// The compensator's band (Pa): the pressure rise from full to zero
        /// displacement, r_p·q_max.
        compensator_band: f64,
        /// Regulator inductance l_p at 7 MPa (Pa·s²/m³). Default Hopsan's 7e7.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        compensator_inductance: Option<f64>,
        /// Lead frequency of the regulator ω_p1 (rad/s). Default Hopsan's 200.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        compensator_lead: Option<f64>,
        /// Time constant of the control valve τ_v (s). Default Hopsan's 1e-3.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        compensator_valve_time_constant: Option<f64>,
        /// Hopsan's t_p, "time from min to full displacement" (s). Default 0.15.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        on_stroke_time: Option<f64>,
        /// Hopsan's t_m, "time from full to min displacement" (s). Default 0.12.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        de_stroke_time: Option<f64>,
        /// Tank pressure Pt (Pa). Default 0.
        #[serde(default)]
        tank_pressure: f64,
        /// Ps(0) (Pa); default the tank pressure.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        initial_pressure: Option<f64>,
        /// A gas accumulator on the line.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        accumulator: Option<AccumulatorCfg>,
    },
}

impl Default for SupplyCfg {
    fn default() -> Self {
        SupplyCfg::Fixed {
            pressure: 0.0,
            tank_pressure: 0.0,
        }
    }
}

/// The validated supply.
///
/// ```
/// use ehservo_sim::supply::{Supply, SupplyCfg};
///
/// // A fixed supply holds its pressure: no state moves.
/// let fixed = SupplyCfg::Fixed { pressure: 2e7, tank_pressure: 1e5 };
/// let (s, pt) = Supply::try_new(&fixed, 1.4e9).unwrap();
/// assert_eq!((s.holding_pressure(pt), pt), (2e7, 1e5));
/// assert_eq!(s.deriv(2e7, 0.0, pt, 1e-4, 1.0, 1.0), [0.0, 0.0]);
/// // A pump of 10 cm³/rev at 25 rev/s into a 1-litre line, relief at 200 bar,
/// // as `[plant.supply]`.
/// let pump: SupplyCfg = toml::from_str(r#"
/// kind = "pump"
/// displacement = 1e-5
/// speed = 157.07963267948966  # 25 rev/s, in rad/s
/// volume = 1e-3
/// relief_pressure = 2e7
/// relief_time_constant = 0.01
/// relief_k_cs = 1e-8
/// relief_k_cf = 1e-8
/// relief_q_nom = 1e-3
/// "#).unwrap();
/// let (s, pt) = Supply::try_new(&pump, 1.4e9).unwrap();
/// // Below the relief setting, with the valve drawing 1e-4 m³/s:
/// // Ṗs = (βe/V)·(D·n/2π − Q_P) = 1.4e12·(2.5e-4 − 1e-4) = 2.1e8 Pa/s.
/// let [dps, dxr] = s.deriv(1e7, 0.0, pt, 1e-4, 1.0, 1.0);
/// assert!((dps - 2.1e8).abs() < 1e-3 * 2.1e8 && dxr == 0.0);
/// // With the whole flow through the relief, Ps settles above its setting.
/// assert!(s.holding_pressure(pt) > 2e7);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Supply {
    /// Ps constant.
    Fixed {
        /// Ps (Pa).
        ps: f64,
    },
    /// The pump, line and relief valve.
    Pump(Pump),
    /// The pressure-compensated pump and its line.
    PcPump(PcPump),
}

/// A pump supply's constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pump {
    /// D·n/(2π) (m³/s).
    pub q_ideal: f64,
    /// C_lp.
    pub leakage: f64,
    /// βe/V_s (Pa/m³).
    pub stiffness: f64,
    /// βe of the line (Pa).
    pub beta: f64,
    /// V_s (m³).
    pub volume: f64,
    /// p_max.
    pub p_max: f64,
    /// 1/τ.
    pub rate: f64,
    /// C_s.
    pub cs: f64,
    /// C_f.
    pub cf: f64,
    /// x_max of the relief.
    pub x_max: f64,
    /// Ps(0).
    pub p0: f64,
    /// The accumulator on the line.
    pub acc: Option<Accumulator>,
}

impl Supply {
    /// Validates `[plant.supply]` (the fluid's bulk modulus as the line's
    /// default). Returns the supply and the tank pressure; the error is the
    /// key inside `[plant.supply]` and the reason.
    pub fn try_new(c: &SupplyCfg, beta: f64) -> Result<(Supply, f64), KeyError> {
        match *c {
            SupplyCfg::Fixed {
                pressure,
                tank_pressure,
            } => {
                let ps = positive("pressure", pressure)?;
                let pt = non_negative("tank_pressure", tank_pressure)?;
                if pt >= ps {
                    return Err(KeyError::new(
                        "tank_pressure",
                        format!("must be below the supply pressure {ps:?} Pa (got {pt:?})"),
                    ));
                }
                Ok((Supply::Fixed { ps }, pt))
            }
            SupplyCfg::Pump { .. } => Self::pump(c, beta),
            SupplyCfg::PcPump { .. } => Self::pc_pump(c, beta),
        }
    }

    /// The line's common keys: (V_s, βe, P_t, Ps(0)), the tank pressure
    /// checked below the supply's `setting` named `setting_key`.
    fn line(
        volume: f64,
        bulk_modulus: Option<f64>,
        beta: f64,
        tank_pressure: f64,
        initial_pressure: Option<f64>,
        (setting_key, setting): (&str, f64),
    ) -> Result<[f64; 4], KeyError> {
        let v = positive("volume", volume)?;
        let b = positive("bulk_modulus", bulk_modulus.unwrap_or(beta))?;
        let pt = non_negative("tank_pressure", tank_pressure)?;
        if pt >= setting {
            return Err(KeyError::new(
                "tank_pressure",
                format!("must be below {setting_key} {setting:?} Pa (got {pt:?})"),
            ));
        }
        let p0 = match initial_pressure {
            None => pt,
            Some(p) => non_negative("initial_pressure", p)?,
        };
        Ok([v, b, pt, p0])
    }

    /// `kind = "pump"`.
    fn pump(c: &SupplyCfg, beta: f64) -> Result<(Supply, f64), KeyError> {
        let SupplyCfg::Pump {
            displacement,
            speed,
            leakage,
            volume,
            bulk_modulus,
            relief_pressure,
            relief_time_constant,
            relief_k_cs,
            relief_k_cf,
            relief_q_nom,
            relief_full_flow_pressure,
            relief_rated_flow,
            relief_response_time,
            tank_pressure,
            initial_pressure,
            accumulator,
        } = *c
        else {
            unreachable!("called for a pump")
        };
        let d = positive("displacement", displacement)?;
        let n = positive("speed", speed)?;
        let cl = non_negative("leakage", leakage)?;
        let p_max = positive("relief_pressure", relief_pressure)?;
        let [v, b, pt, p0] = Self::line(
            volume,
            bulk_modulus,
            beta,
            tank_pressure,
            initial_pressure,
            ("the relief pressure", p_max),
        )?;
        let r = ReliefKeys {
            time_constant: relief_time_constant,
            k_cs: relief_k_cs,
            k_cf: relief_k_cf,
            q_nom: relief_q_nom,
            full_flow_pressure: relief_full_flow_pressure,
            rated_flow: relief_rated_flow,
            response_time: relief_response_time,
        }
        .resolve(p_max, pt)?;
        let acc = accumulator.map(|a| a.validate(p_max)).transpose()?;
        Ok((
            Supply::Pump(Pump {
                q_ideal: d * n / (2.0 * core::f64::consts::PI),
                leakage: cl,
                stiffness: b / v,
                beta: b,
                volume: v,
                p_max,
                rate: r.rate,
                cs: r.cs,
                cf: r.cf,
                x_max: r.x_max,
                p0,
                acc,
            }),
            pt,
        ))
    }

    /// `kind = "pc-pump"`.
    fn pc_pump(c: &SupplyCfg, beta: f64) -> Result<(Supply, f64), KeyError> {
        let SupplyCfg::PcPump {
            displacement,
            speed,
            leakage,
            volume,
            bulk_modulus,
            compensator_pressure,
            compensator_band,
            compensator_inductance,
            compensator_lead,
            compensator_valve_time_constant,
            on_stroke_time,
            de_stroke_time,
            tank_pressure,
            initial_pressure,
            accumulator,
        } = *c
        else {
            unreachable!("called for a pressure-compensated pump")
        };
        let d = positive("displacement", displacement)?;
        let n = positive("speed", speed)?;
        let cl = non_negative("leakage", leakage)?;
        let p_set = positive("compensator_pressure", compensator_pressure)?;
        let band = positive("compensator_band", compensator_band)?;
        let [v, b, pt, p0] = Self::line(
            volume,
            bulk_modulus,
            beta,
            tank_pressure,
            initial_pressure,
            ("the compensator pressure", p_set),
        )?;
        if band >= p_set {
            return Err(KeyError::new(
                "compensator_band",
                format!(
                    "must be below compensator_pressure = {p_set:e} Pa: the pump would not reach full stroke above the tank (got {band:e})"
                ),
            ));
        }
        let opt = |key: &str, v: Option<f64>, default: f64| positive(key, v.unwrap_or(default));
        let q_max = d * n / (2.0 * core::f64::consts::PI);
        let acc = accumulator.map(|a| a.validate(p_set + pt)).transpose()?;
        Ok((
            Supply::PcPump(PcPump {
                q_max,
                speed: n,
                leakage: cl,
                volume: v,
                beta: b,
                p_set,
                r_p: band / q_max,
                l_p: opt("compensator_inductance", compensator_inductance, 7e7)?,
                lead: opt("compensator_lead", compensator_lead, 200.0)?,
                tau_v: opt(
                    "compensator_valve_time_constant",
                    compensator_valve_time_constant,
                    1e-3,
                )?,
                t_on: opt("on_stroke_time", on_stroke_time, 0.15)?,
                t_off: opt("de_stroke_time", de_stroke_time, 0.12)?,
                p0,
                acc,
            }),
            pt,
        ))
    }

    /// The pressure the relief valve holds with the pump's whole flow
    /// through it (Pa): the steady Ps with the 4/3 valve closed, found by
    /// bisection; the fixed pressure for a fixed supply; a
    /// pressure-compensated pump's steady pressure with no draw (its
    /// setting, less what its leakage costs).
    pub fn holding_pressure(&self, pt: f64) -> f64 {
        match self {
            Supply::Fixed { ps } => *ps,
            Supply::Pump(_) | Supply::PcPump(_) => self.holding_pressure_at(pt, 1.0),
        }
    }

    /// [`Supply::holding_pressure`] with the relief setting (or a fixed
    /// supply's pressure) scaled by `pressure_factor`, as
    /// [`Supply::deriv`] scales it: the supply's steady pressure when the
    /// 4/3 valve draws nothing.
    pub fn holding_pressure_at(&self, pt: f64, pressure_factor: f64) -> f64 {
        match self {
            Supply::Fixed { ps } => ps * pressure_factor,
            Supply::PcPump(p) => p.steady_pressure(pt, 0.0, pressure_factor),
            Supply::Pump(p) => {
                let p = &Pump {
                    p_max: p.p_max * pressure_factor,
                    ..*p
                };
                // Q_pump(Ps) = Q_relief(Ps) at the steady opening, both
                // monotone in Ps: bisection over [p_max, p_max + 1e9 Pa],
                // 200 halvings at most (far below the ulp of the bracket).
                let f = |ps: f64| {
                    let x = p.steady_opening(ps, pt);
                    p.q_pump(ps, pt) - x * (ps - pt).max(0.0).sqrt()
                };
                let (mut lo, mut hi) = (p.p_max, p.p_max + 1e9);
                if f(lo) <= 0.0 {
                    return lo;
                }
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    if f(mid) > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                0.5 * (lo + hi)
            }
        }
    }
}

impl Supply {
    /// The pressure the supply delivers (Pa) at its state `ps_state`: a
    /// fixed supply's Ps scaled by `pressure_factor` (the variation's), a
    /// pump's line pressure, floored at 0.
    #[inline]
    pub fn pressure(&self, ps_state: f64, pressure_factor: f64) -> f64 {
        match self {
            Supply::Fixed { ps } => ps * pressure_factor,
            Supply::Pump(_) | Supply::PcPump(_) => ps_state.max(0.0),
        }
    }

    /// The derivatives of the supply's own two states, the line pressure
    /// Ps (Pa/s) and the relief valve's opening xr (1/s; 0 at a limit of
    /// [0, x_max] that the lag pushes against), when the valve
    /// draws `q_p` (m³/s) from the line at the pressure `ps` (Pa, from
    /// [`Supply::pressure`]), over the tank at `pt`: the module's
    /// equations, with the relief setting scaled by `pressure_factor` and
    /// βe by `bulk_factor`. Both are 0 for a fixed supply. A plant that has
    /// a supply holds one and integrates these two states with its own
    /// (the cylinder: its slots 4 and 5).
    #[inline]
    pub fn deriv(
        &self,
        ps: f64,
        xr: f64,
        pt: f64,
        q_p: f64,
        pressure_factor: f64,
        bulk_factor: f64,
    ) -> [f64; 2] {
        match self {
            Supply::Fixed { .. } => [0.0, 0.0],
            Supply::PcPump(p) => p.deriv(ps, xr, pt, q_p, pressure_factor, bulk_factor),
            Supply::Pump(p) => {
                let p_max = p.p_max * pressure_factor;
                let relief = Pump { p_max, ..*p };
                let xs = relief.static_opening(ps, pt);
                let qr = relief.q_relief(xr, ps, pt);
                let dxr = (xs - xr) * p.rate;
                let held = (xr <= 0.0 && dxr < 0.0) || (xr >= p.x_max && dxr > 0.0);
                [
                    p.line_stiffness(ps, bulk_factor) * (p.q_pump(ps, pt) - qr - q_p),
                    if held { 0.0 } else { dxr },
                ]
            }
        }
    }

    /// The supply's second state put back inside its limits at the line
    /// pressure `ps` (the state after an RK4 step that crossed one): the
    /// relief's opening `xr` in [0, x_max], a pressure-compensated pump's
    /// regulator in [0, y_max(ps)]; unchanged for a fixed supply.
    #[inline]
    pub fn limit_opening(&self, ps: f64, xr: f64) -> f64 {
        match self {
            Supply::Fixed { .. } => xr,
            Supply::Pump(p) => xr.clamp(0.0, p.x_max),
            Supply::PcPump(p) => p.limit(ps, xr),
        }
    }

    /// The supply's pressure setting (Pa, absolute) over the tank at `pt`:
    /// a fixed supply's pressure, a relief's cracking pressure, a
    /// compensator's dead-head pressure (its setting over the tank, + P_t).
    pub fn setting(&self, pt: f64) -> f64 {
        match self {
            Supply::Fixed { ps } => *ps,
            Supply::Pump(p) => p.p_max,
            Supply::PcPump(p) => p.p_set + pt,
        }
    }
}

impl Pump {
    /// The line's stiffness at Ps with βe scaled by `bulk_factor`:
    /// 1/(V_s/βe + C_a(Ps)) with the accumulator's compliance C_a
    /// ([`crate::accumulator`]), βe/V_s without one.
    #[inline]
    pub fn line_stiffness(&self, ps: f64, bulk_factor: f64) -> f64 {
        match &self.acc {
            None => self.stiffness * bulk_factor,
            acc => line_stiffness(self.volume, self.beta * bulk_factor, acc.as_ref(), ps),
        }
    }

    /// The pump's delivery at Ps (m³/s).
    #[inline]
    pub fn q_pump(&self, ps: f64, pt: f64) -> f64 {
        self.q_ideal - self.leakage * (ps - pt)
    }

    /// The relief's static opening x_s at Ps, not limited: the input of
    /// its first-order lag (Hopsan's `xs`, HydraulicPressureReliefValve.hpp
    /// lines 140–144 and 185 without the TLM terms), negative below the
    /// setting.
    #[inline]
    pub fn static_opening(&self, ps: f64, pt: f64) -> f64 {
        let dp = ps - pt;
        let b1 = if dp * self.cf < 0.0 {
            self.cs
        } else {
            self.cs + dp * self.cf
        };
        (ps - self.p_max) / b1
    }

    /// The opening the relief settles to at a constant Ps: the static
    /// opening limited to [0, x_max].
    #[inline]
    pub fn steady_opening(&self, ps: f64, pt: f64) -> f64 {
        self.static_opening(ps, pt).clamp(0.0, self.x_max)
    }

    /// The relief's flow at Ps with the opening `x` (limited to [0, x_max]).
    #[inline]
    pub fn q_relief(&self, x: f64, ps: f64, pt: f64) -> f64 {
        x.clamp(0.0, self.x_max) * (ps - pt).max(0.0).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hopsan_pump() -> (Supply, f64) {
        // The values of Hopsan's Position Servo (docs/hopsan/position-servo.md).
        Supply::try_new(
            &SupplyCfg::Pump {
                displacement: 25e-5,
                speed: 200.0,
                leakage: 1e-12,
                volume: 1e-3,
                bulk_modulus: Some(1e9),
                relief_pressure: 2e7,
                relief_time_constant: Some(1e-3),
                relief_k_cs: Some(1e-8),
                relief_k_cf: Some(1e-8),
                relief_q_nom: Some(0.01),
                relief_full_flow_pressure: None,
                relief_rated_flow: None,
                relief_response_time: None,
                tank_pressure: 1e5,
                initial_pressure: None,
                accumulator: None,
            },
            1e9,
        )
        .unwrap()
    }

    /// The line's pressure integrates the flow balance, by hand: at
    /// Ps = 10 MPa (below the 20 MPa relief, so closed and staying so) the
    /// pump delivers D·n/(2π) − C_lp·(Ps − Pt) = 25e-5·200/(2π) − 1e-12·9.9e6
    /// m³/s; drawing half of that, Ṗs = (βe/V)·(the other half) with
    /// βe/V = 1e9/1e-3. With the relief open by x above its setting its flow
    /// x·√(Ps − Pt) leaves the line too, and x relaxes towards the steady
    /// opening at 1/τ (at 20.5 MPa, 2.5 % over its setting, the steady
    /// opening is within x_max). A fixed supply has no dynamics.
    #[test]
    #[allow(clippy::float_cmp)] // 0 and 7e6·0.5 are exact
    fn the_line_integrates_the_flow_balance() {
        let (s, pt) = hopsan_pump();
        let q_pump = 25e-5 * 200.0 / (2.0 * std::f64::consts::PI) - 1e-12 * (1e7 - 1e5);
        let [dps, dxr] = s.deriv(1e7, 0.0, pt, 0.5 * q_pump, 1.0, 1.0);
        let want = 1e9 / 1e-3 * 0.5 * q_pump;
        assert!((dps - want).abs() <= 1e-12 * want, "{dps} vs {want}");
        assert_eq!(dxr, 0.0);
        let Supply::Pump(p) = s else { unreachable!() };
        let (ps, x) = (2.05e7, 0.5 * p.x_max);
        let q_pump = 25e-5 * 200.0 / (2.0 * std::f64::consts::PI) - 1e-12 * (ps - 1e5);
        let [dps, dxr] = s.deriv(ps, x, pt, 0.0, 1.0, 1.0);
        let want = 1e9 / 1e-3 * (q_pump - x * (ps - 1e5_f64).sqrt());
        assert!((dps - want).abs() <= 1e-9 * want.abs(), "{dps} vs {want}");
        let xs = p.steady_opening(ps, pt);
        assert!(xs > 0.0 && xs < p.x_max, "{xs}");
        assert!((dxr - (xs - x) / 1e-3).abs() <= 1e-9 * dxr.abs(), "{dxr}");
        // A 10 % lower relief setting opens it further.
        let [_, dxr_low] = s.deriv(ps, x, pt, 0.0, 0.9, 1.0);
        assert!(dxr_low > dxr);
        let fixed = Supply::Fixed { ps: 7e6 };
        assert_eq!(fixed.deriv(7e6, 0.0, pt, 1e-3, 1.0, 1.0), [0.0, 0.0]);
        assert_eq!(fixed.pressure(123.0, 0.5), 3.5e6);
    }

    /// The holding pressure balances the pump's flow against the relief's
    /// steady flow, checked here by hand at the returned pressure.
    #[test]
    fn holding_pressure_balances_pump_and_relief() {
        let (s, pt) = hopsan_pump();
        let Supply::Pump(p) = s else { unreachable!() };
        let ps = s.holding_pressure(pt);
        assert!(ps > p.p_max);
        // Q_pump = 25e-5·200/(2π) − 1e-12·(Ps − Pt).
        let q = 25e-5 * 200.0 / (2.0 * core::f64::consts::PI) - 1e-12 * (ps - pt);
        let sq = 7e6_f64.sqrt();
        let b1 = sq / 1e-8 + (ps - pt) / (1e-8 * sq);
        let x = ((ps - 2e7) / b1).min(0.01 / sq);
        let qr = x * (ps - pt).sqrt();
        assert!((q - qr).abs() <= 1e-9 * q, "{q} vs {qr}");
    }

    /// The relief's opening under a constant Ps, stepped as the simulator
    /// steps it (RK4 on the supply's ẋr, then [`Supply::limit_opening`]):
    /// the lag's closed form x_s + (x(0) − x_s)·e^(−t/τ) between the limits,
    /// and a limit reached in finite time, at t* = τ·ln((x(0) − x_s)/(L −
    /// x_s)) for the limit L, where it then stays exactly. The old rule
    /// (the limits on the lag's input) instead decayed towards 0 as
    /// e^(−t/τ) and never reached it.
    #[test]
    #[allow(clippy::float_cmp)] // the limits are held exactly
    fn the_relief_opening_is_a_limited_lag() {
        let (s, pt) = hopsan_pump();
        let Supply::Pump(p) = s else { unreachable!() };
        let tau = 1e-3;
        let h = 1e-5;
        // (Ps, x(0), the limit it runs into): below the 20 MPa setting the
        // static opening is negative and the valve closes from half open;
        // far above it the static opening is beyond x_max and it opens
        // fully from closed.
        for (ps, x_start, limit) in [(1.9e7, 0.5 * p.x_max, 0.0), (3e7, 0.0, p.x_max)] {
            let xs = p.static_opening(ps, pt);
            assert!(xs < 0.0 || xs > p.x_max, "{xs}");
            let t_star = tau * ((x_start - xs) / (limit - xs)).ln();
            assert!(t_star > 10.0 * h, "{t_star}");
            let exact = |t: f64| xs + (x_start - xs) * (-t / tau).exp();
            let mut x = [x_start];
            let mut held = 0;
            for k in 1..=((5.0 * t_star / h) as usize) {
                ehservo_core::rk4::rk4_step(
                    |_, y: &[f64; 1], dy: &mut [f64; 1]| {
                        dy[0] = s.deriv(ps, y[0], pt, 0.0, 1.0, 1.0)[1];
                    },
                    (k - 1) as f64 * h,
                    &mut x,
                    h,
                );
                x[0] = s.limit_opening(ps, x[0]);
                let t = k as f64 * h;
                if t <= t_star - h {
                    let want = exact(t);
                    assert!(
                        (x[0] - want).abs() <= 1e-9 * p.x_max,
                        "t = {t}: {} vs {want}",
                        x[0]
                    );
                } else if t >= t_star + h {
                    assert_eq!(x[0], limit, "t = {t} (t* = {t_star})");
                    held += 1;
                }
            }
            assert!(held > 0);
        }
        // At a limit with the lag pushing against it the derivative is 0;
        // pulling away from it, the lag's.
        assert_eq!(s.deriv(1.9e7, 0.0, pt, 0.0, 1.0, 1.0)[1], 0.0);
        assert_eq!(s.deriv(3e7, p.x_max, pt, 0.0, 1.0, 1.0)[1], 0.0);
        let xs = p.static_opening(2.05e7, pt);
        assert_eq!(s.deriv(2.05e7, 0.0, pt, 0.0, 1.0, 1.0)[1], xs * p.rate);
        // The relief's flow sees the limited opening.
        let sq = (2.05e7 - pt).sqrt();
        assert_eq!(p.q_relief(-1e-6, 2.05e7, pt), 0.0);
        assert_eq!(p.q_relief(2.0 * p.x_max, 2.05e7, pt), p.x_max * sq);
    }

    #[test]
    fn bad_keys_are_named() {
        let e = Supply::try_new(
            &SupplyCfg::Fixed {
                pressure: 1e7,
                tank_pressure: 2e7,
            },
            1e9,
        )
        .unwrap_err();
        assert_eq!(e.key, "tank_pressure");
        assert_eq!(
            e.reason.to_string(),
            "must be below the supply pressure 10000000.0 Pa (got 20000000.0)"
        );
        let e = Supply::try_new(
            &SupplyCfg::Fixed {
                pressure: -1.0,
                tank_pressure: 0.0,
            },
            1e9,
        )
        .unwrap_err();
        assert_eq!(e.key, "pressure");
        assert_eq!(e.reason, crate::error::Reason::NotPositive(-1.0));
    }
}
