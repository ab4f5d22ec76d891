//! The hydraulic supply: a fixed pressure, or a fixed-displacement pump
//! into a line volume with a pressure-relief valve, and the tank.
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

use crate::error::{non_negative, positive, KeyError};
use serde::{Deserialize, Serialize};

/// The rated pressure of Hopsan's relief characteristic, `mPnom = 7e6f`
/// (HydraulicPressureReliefValve.hpp, `initialize`).
pub const RELIEF_P_NOM: f64 = 7e6;

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
        /// Relief cracking pressure p_max (Pa).
        relief_pressure: f64,
        /// Relief spool time constant τ (s).
        relief_time_constant: f64,
        /// Relief characteristic due to the spring, k_cs ((m³/s)/Pa).
        relief_k_cs: f64,
        /// Relief characteristic due to flow forces, k_cf ((m³/s)/Pa).
        relief_k_cf: f64,
        /// Relief flow at full opening and 7 MPa, q_nom (m³/s).
        relief_q_nom: f64,
        /// Tank pressure Pt (Pa). Default 0.
        #[serde(default)]
        tank_pressure: f64,
        /// Ps(0) (Pa); default the tank pressure.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        initial_pressure: Option<f64>,
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
                        format!("must be below the supply pressure {ps} Pa (got {pt})"),
                    ));
                }
                Ok((Supply::Fixed { ps }, pt))
            }
            SupplyCfg::Pump {
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
                tank_pressure,
                initial_pressure,
            } => {
                let d = positive("displacement", displacement)?;
                let n = positive("speed", speed)?;
                let cl = non_negative("leakage", leakage)?;
                let v = positive("volume", volume)?;
                let b = positive("bulk_modulus", bulk_modulus.unwrap_or(beta))?;
                let p_max = positive("relief_pressure", relief_pressure)?;
                let tau = positive("relief_time_constant", relief_time_constant)?;
                let kcs = positive("relief_k_cs", relief_k_cs)?;
                let kcf = positive("relief_k_cf", relief_k_cf)?;
                let qn = positive("relief_q_nom", relief_q_nom)?;
                let pt = non_negative("tank_pressure", tank_pressure)?;
                if pt >= p_max {
                    return Err(KeyError::new(
                        "tank_pressure",
                        format!("must be below the relief pressure {p_max} Pa (got {pt})"),
                    ));
                }
                let p0 = match initial_pressure {
                    None => pt,
                    Some(p) => non_negative("initial_pressure", p)?,
                };
                let sq = RELIEF_P_NOM.sqrt();
                Ok((
                    Supply::Pump(Pump {
                        q_ideal: d * n / (2.0 * core::f64::consts::PI),
                        leakage: cl,
                        stiffness: b / v,
                        beta: b,
                        volume: v,
                        p_max,
                        rate: 1.0 / tau,
                        cs: sq / kcs,
                        cf: 1.0 / (kcf * sq),
                        x_max: qn / sq,
                        p0,
                    }),
                    pt,
                ))
            }
        }
    }

    /// The pressure the relief valve holds with the pump's whole flow
    /// through it (Pa): the steady Ps with the 4/3 valve closed, found by
    /// bisection; the fixed pressure for a fixed supply.
    pub fn holding_pressure(&self, pt: f64) -> f64 {
        match self {
            Supply::Fixed { ps } => *ps,
            Supply::Pump(_) => self.holding_pressure_at(pt, 1.0),
        }
    }

    /// [`Supply::holding_pressure`] with the relief setting (or a fixed
    /// supply's pressure) scaled by `pressure_factor`, as
    /// [`Supply::deriv`] scales it: the supply's steady pressure when the
    /// 4/3 valve draws nothing.
    pub fn holding_pressure_at(&self, pt: f64, pressure_factor: f64) -> f64 {
        match self {
            Supply::Fixed { ps } => ps * pressure_factor,
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
            Supply::Pump(_) => ps_state.max(0.0),
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
            Supply::Pump(p) => {
                let p_max = p.p_max * pressure_factor;
                let relief = Pump { p_max, ..*p };
                let xs = relief.static_opening(ps, pt);
                let qr = relief.q_relief(xr, ps, pt);
                let dxr = (xs - xr) * p.rate;
                let held = (xr <= 0.0 && dxr < 0.0) || (xr >= p.x_max && dxr > 0.0);
                [
                    p.stiffness * bulk_factor * (p.q_pump(ps, pt) - qr - q_p),
                    if held { 0.0 } else { dxr },
                ]
            }
        }
    }

    /// The relief's opening `xr` put back inside [0, x_max] (the state
    /// after an RK4 step that crossed a limit); unchanged for a fixed
    /// supply.
    #[inline]
    pub fn limit_opening(&self, xr: f64) -> f64 {
        match self {
            Supply::Fixed { .. } => xr,
            Supply::Pump(p) => xr.clamp(0.0, p.x_max),
        }
    }
}

impl Pump {
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
                relief_time_constant: 1e-3,
                relief_k_cs: 1e-8,
                relief_k_cf: 1e-8,
                relief_q_nom: 0.01,
                tank_pressure: 1e5,
                initial_pressure: None,
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
                x[0] = s.limit_opening(x[0]);
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
            "must be below the supply pressure 10000000 Pa (got 20000000)"
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
