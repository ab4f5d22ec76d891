//! A gas accumulator on the supply line: `[plant.supply.accumulator]`.
//!
//! Hopsan's `HydraulicAckumulator` (Hopsan/hopsan, componentLibraries/
//! defaultLibrary/Hydraulic/Volumes&Lines/HydraulicAckumulator.hpp) holds
//! the state of charge x = V_oil/V0 and the gas law
//!
//! ```text
//! p_a = p0·V0^κ/(V0·(1 − x))^κ           (line 250, 1 − x limited to [0.1, 1])
//! ẋ   = K_ca·(p1 − p_a)/V0,  0 ≤ x ≤ 1   (lines 244–248: q1 = −V0·ẋ, line 249)
//! ```
//!
//! ehservo takes the inlet as lossless (K_ca → ∞, so p_a = p, the line's
//! pressure): the accumulator then carries no state of its own, and its oil
//! volume is a function of the line pressure,
//!
//! ```text
//! V_oil(p) = V0·(1 − (p0/p)^(1/n))   for p > p0, else 0
//! C_a(p)   = dV_oil/dp = (V0/(n·p))·(p0/p)^(1/n)   for p > p0, else 0
//! ```
//!
//! which adds to the line's own compliance V_s/βe:
//! `(V_s/βe + C_a(p))·ṗ = Σq`. The cylinder's six states (y, v, p_A, p_B,
//! p_s, x_r) are all in use, so no seventh is spent on x; the price is that
//! the inlet's loss (a time constant C_a/K_ca, 0.44 ms for Hopsan's default
//! K_ca = 1e-8 at 10 L and 100 bar over 50 bar precharge) is not modelled.
//! Hopsan's limit 1 − x ≥ 0.1 (p ≤ p0·10^κ) is not modelled either: the
//! key check keeps the working pressures below it in practice (a precharge
//! below the supply's setting, the setting below p0·10^n is not enforced).

use crate::error::{positive, KeyError};
use serde::{Deserialize, Serialize};

/// The largest polytropic exponent accepted: 5/3, the adiabatic exponent
/// of a monatomic ideal gas, above every real charging gas's (nitrogen
/// 1.4 as an ideal diatomic gas, somewhat more at high pressure).
pub const MAX_EXPONENT: f64 = 5.0 / 3.0;

/// `[plant.supply.accumulator]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AccumulatorCfg {
    /// Gas precharge pressure p0 (Pa).
    pub precharge: f64,
    /// Total (gas) volume V0 (m³).
    pub volume: f64,
    /// Polytropic exponent n: 1 isothermal (slow cycles), 1.4 adiabatic
    /// (fast cycles); in [1, 5/3].
    pub exponent: f64,
}

/// The validated accumulator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Accumulator {
    /// p0 (Pa).
    pub p0: f64,
    /// V0 (m³).
    pub v0: f64,
    /// 1/n.
    pub inv_n: f64,
}

impl AccumulatorCfg {
    /// Checks the keys against the supply's pressure setting `setting`
    /// (the relief's cracking pressure, or the compensator's setting): a
    /// precharge at or above it would never take oil in.
    pub fn validate(&self, setting: f64) -> Result<Accumulator, KeyError> {
        let p0 = positive("accumulator.precharge", self.precharge)?;
        let v0 = positive("accumulator.volume", self.volume)?;
        let n = self.exponent;
        if !(1.0..=MAX_EXPONENT).contains(&n) {
            return Err(KeyError::new(
                "accumulator.exponent",
                format!("must lie in [1, 5/3] (1 isothermal, 1.4 adiabatic nitrogen; got {n:?})"),
            ));
        }
        if p0 >= setting {
            return Err(KeyError::new(
                "accumulator.precharge",
                format!(
                    "must be below the supply's pressure setting {setting:e} Pa, or the accumulator never takes oil in (got {p0:e})"
                ),
            ));
        }
        Ok(Accumulator {
            p0,
            v0,
            inv_n: 1.0 / n,
        })
    }
}

impl Accumulator {
    /// The oil volume it holds at the pressure `p` (m³).
    pub fn oil_volume(&self, p: f64) -> f64 {
        if p > self.p0 {
            self.v0 * (1.0 - (self.p0 / p).powf(self.inv_n))
        } else {
            0.0
        }
    }

    /// Its compliance dV_oil/dp at `p` (m³/Pa).
    pub fn compliance(&self, p: f64) -> f64 {
        if p > self.p0 {
            self.v0 * self.inv_n / p * (self.p0 / p).powf(self.inv_n)
        } else {
            0.0
        }
    }
}

/// The stiffness of a line of volume `volume` and bulk modulus `beta`
/// with an optional accumulator, at the pressure `p`: 1/(V/βe + C_a(p))
/// (Pa/m³).
pub fn line_stiffness(volume: f64, beta: f64, acc: Option<&Accumulator>, p: f64) -> f64 {
    let c = volume / beta + acc.map_or(0.0, |a| a.compliance(p));
    1.0 / c
}

#[cfg(test)]
mod tests {
    use super::*;

    fn acc(n: f64) -> Accumulator {
        AccumulatorCfg {
            precharge: 5e6,
            volume: 1e-2,
            exponent: n,
        }
        .validate(2e7)
        .unwrap()
    }

    /// The stored oil volume against the closed form, by hand: 10 L
    /// precharged to 50 bar, at 100 bar. Isothermal (n = 1): the gas halves,
    /// V_oil = 10·(1 − 0.5) = 5 L. Adiabatic (n = 1.4): 0.5^(1/1.4) =
    /// e^(−0.693147/1.4) = e^(−0.495105) = 0.609507, V_oil = 3.90493 L.
    /// At or below the precharge it holds nothing.
    #[test]
    #[allow(clippy::float_cmp)] // the zeros below and above the precharge are exact
    fn the_stored_volume_is_the_gas_law() {
        assert!((acc(1.0).oil_volume(1e7) - 5e-3).abs() < 1e-15);
        assert!((acc(1.4).oil_volume(1e7) - 3.90493e-3).abs() < 1e-8);
        assert_eq!(acc(1.4).oil_volume(5e6), 0.0);
        assert_eq!(acc(1.4).oil_volume(1e6), 0.0);
        // The compliance is the volume's slope: a central difference.
        for n in [1.0, 1.4] {
            let a = acc(n);
            let h = 1e3;
            let fd = (a.oil_volume(1e7 + h) - a.oil_volume(1e7 - h)) / (2.0 * h);
            assert!((a.compliance(1e7) - fd).abs() < 1e-6 * fd, "{n}");
        }
        // Isothermal at 100 bar: C_a = V0·p0/p² = 1e-2·5e6/1e14 = 5e-10 m³/Pa,
        // beside a 1 L line at 1 GPa (1e-12 m³/Pa): the line is 501 times softer.
        let k = line_stiffness(1e-3, 1e9, Some(&acc(1.0)), 1e7);
        assert!((k - 1.0 / (1e-12 + 5e-10)).abs() < 1e-9 * k);
        assert_eq!(line_stiffness(1e-3, 1e9, None, 1e7), 1e12);
    }

    #[test]
    fn bad_keys_are_named() {
        let cfg = |p0: f64, n: f64| AccumulatorCfg {
            precharge: p0,
            volume: 1e-3,
            exponent: n,
        };
        let e = cfg(2.5e7, 1.4).validate(2e7).unwrap_err();
        assert_eq!(e.key, "accumulator.precharge");
        assert!(
            e.reason.contains("below the supply's pressure setting"),
            "{e}"
        );
        for n in [0.9, 1.8, f64::NAN] {
            let e = cfg(5e6, n).validate(2e7).unwrap_err();
            assert_eq!(e.key, "accumulator.exponent");
        }
        let e = cfg(0.0, 1.4).validate(2e7).unwrap_err();
        assert_eq!(e.key, "accumulator.precharge");
    }
}
