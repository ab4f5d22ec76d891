//! IFAC benchmark problem 9007, "hydraulic positioning system" (E. J.
//! Davison, "Benchmark Problems for Control System Design: Report of the
//! IFAC Theory Committee", IFAC, 1990), as a plant: `[plant] model =
//! "ifac9007"`; docs/ifac9007.md has the model, the box and how to run it.
//!
//! Transcribed from JuDO-dev/ControlBenchmarks.jl, commit
//! f11f4a98bd8ab2923771b72e7f0d4c60302207c8, file
//! `src/benchmarks/ifac/prob9007-hydraulicPositioningSystem.jl` (cited
//! below as `jl:N`, N its line). A carriage on a track, state
//! x = (position, velocity, pressure) (`jl:79–100`):
//!
//! ```text
//! ẋ1 = x2
//! ẋ2 = −(R + 4·Rc/π)/m·x2 + A/m·x3 − FL/m                 (jl:80–83, jl:99–100)
//! ẋ3 = −(4B/V)·A·x2 − (4B/V)·(σ + KL)·x3 − (4B/V)·u_b     (jl:82, jl:84, jl:88)
//! ```
//!
//! with the nominal parameters of `jl:30–38`, the box of `jl:49–56`, the
//! input bound |u_b| ≤ 866 (`jl:104`) and the load disturbance FL ∈
//! [0, 800] (`jl:107`). The Coulomb friction Rc enters as its
//! describing-function gain 4·Rc/π (`jl:81`): the model is linear, and so
//! is this plant.
//!
//! **Units.** The source states none. The axis is linear and carries the
//! benchmark's own numbers: its "m" is one benchmark length unit L (its
//! "mm" shown in traces is 10⁻³ L), its time is s; the pressure state and
//! FL are in the benchmark's pressure and force units.
//!
//! **Sign of the input.** The source's input column is negative
//! (`jl:88`: B[3] = −4B/V): a positive u_b lowers the pressure and drives
//! the carriage back. ehservo's controllers are designed for a positive
//! input gain, so the plant's command is u = −u_b; the bound ±866 is
//! symmetric and is the plant's input saturation, applied to u.
//!
//! **Nominal model.** The controller is told the paper's third-order form
//! (8)–(9) of the same dynamics in (y, ẏ, ÿ): with βe = B, Vt = V, Jt = m,
//! Dm = A, Bm = R + 4Rc/π, Kce = σ + KL and G = 0 the paper's coefficients
//! are exactly `a1 = 0`, `a2 = 4B·A²/(V·m) + 4B·(σ+KL)·(R+4Rc/π)/(V·m)`,
//! `a3 = (R+4Rc/π)/m + 4B·(σ+KL)/V`, and `b = 4B·A/(V·m)` when the valve
//! factor Kv·Kg is 1. The paper's valve root √(Ps − sgn(u)·Pl) is made flat
//! by Ps = [`FLAT_SUPPLY`] (with ρ = Cd = Kv = 1, Ag = 1/√Ps): over the
//! pressures the box can reach (|x3| ≤ 866/(σ+KL)_min ≈ 7.9·10⁵) b
//! differs from the linear model's by less than 10⁻⁹ relative. FL is not
//! told: it is the disturbance the loop rejects.
//!
//! **Variation.** `[uncertainty.physical]`: mass scales m, bulk_modulus B,
//! leakage KL, friction R and Rc, load FL, each by `1 + bias + random·r`.
//! The benchmark has no supply pressure; a `supply_pressure` spread is
//! refused. The box's corners and draws inside it are the league's
//! (`[[scenario]] box`, docs/league.md), set on the keys themselves.

use crate::axis::Axis;
use crate::error::{KeyError, Reason};
use crate::plant::{Draw, Plant, PlantConfig, PlantContext, UncertaintySpec};
use crate::uncertainty::{Factors, Spread};
use ehservo_core::math::sgn;
use ehservo_core::servo::{Load, NominalModel, ServoParams};
use serde::{Deserialize, Serialize};

/// The input bound |u| ≤ 866 (`jl:104`).
pub const INPUT_LIMIT: f64 = 866.0;

/// The load disturbance's bound, FL ∈ [0, 800] (`jl:107`).
pub const FL_BOX: (f64, f64) = (0.0, 800.0);

/// The supply pressure that makes the nominal model's valve root flat
/// (module doc).
pub const FLAT_SUPPLY: f64 = 1e15;

/// The eight parameters of the benchmark (`jl:19–26`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ifac9007Params {
    /// Compressibility modulus B.
    pub b: f64,
    /// Mass m.
    pub m: f64,
    /// Friction coefficient R.
    pub r: f64,
    /// Coulomb friction coefficient Rc.
    pub rc: f64,
    /// Bypass oil coefficient KL.
    pub kl: f64,
    /// Hydraulic constant σ.
    pub sigma: f64,
    /// Volume V.
    pub v: f64,
    /// Piston area A.
    pub a: f64,
}

impl Ifac9007Params {
    /// The nominal values (`jl:30–38`).
    pub const NOMINAL: Ifac9007Params = Ifac9007Params {
        b: 14000.0,
        m: 0.1287,
        r: 0.150,
        rc: 0.01,
        kl: 0.002,
        sigma: 0.24,
        v: 874.0,
        a: 10.75,
    };

    /// The published box of each parameter, by its key (`jl:49–56`); V's
    /// is [0, ∞), no box.
    pub const BOX: [(&'static str, f64, f64); 8] = [
        ("B", 9000.0, 16000.0),
        ("m", 0.05, 0.3),
        ("R", 0.05, 5.0),
        ("Rc", 0.0, 0.05),
        ("KL", 0.000103, 0.0035),
        ("sigma", 0.001, 15.0),
        ("V", 0.0, f64::INFINITY),
        ("A", 10.5, 11.10),
    ];

    /// The values in the order of [`Ifac9007Params::BOX`].
    pub fn values(&self) -> [f64; 8] {
        [
            self.b, self.m, self.r, self.rc, self.kl, self.sigma, self.v, self.a,
        ]
    }

    /// The viscous friction of the linear model, R + 4·Rc/π (`jl:81`).
    pub fn damping(&self) -> f64 {
        self.r + 4.0 / std::f64::consts::PI * self.rc
    }

    /// The parameters varied by the physical factors `f` (module doc).
    pub fn varied(&self, f: &Factors) -> Ifac9007Params {
        Ifac9007Params {
            b: self.b * f.bulk_modulus,
            m: self.m * f.mass,
            r: self.r * f.friction,
            rc: self.rc * f.friction,
            kl: self.kl * f.leakage,
            ..*self
        }
    }

    /// The paper's physical parameters whose third-order model is this
    /// plant's (module doc).
    pub fn servo_params(&self) -> ServoParams {
        ServoParams {
            ps: FLAT_SUPPLY,
            beta_e: self.b,
            vt: self.v,
            kce: self.sigma + self.kl,
            dm: self.a,
            jt: self.m,
            bm: self.damping(),
            kv: 1.0,
            g: 0.0,
            rho: 1.0,
            cd: 1.0,
            ag: 1.0 / FLAT_SUPPLY.sqrt(),
        }
    }
}

/// `[plant]` of `model = "ifac9007"`: the eight parameters (nominal by
/// default), the constant load disturbance FL, and whether a value outside
/// the published box is allowed.
///
/// ```
/// use ehservo_sim::ifac9007::Ifac9007Cfg;
/// # use ehservo_sim::plant::{PlantConfig, PlantContext, UncertaintySpec};
/// # let ctx = PlantContext { load: None, load_given: false, uncertainty: UncertaintySpec::NONE,
/// #     x0: [0.0; 3], base_dir: None, reference_range: None, quantity: Default::default() };
/// // m = 0.4 is outside the box [0.05, 0.3] (jl:50): refused by its key…
/// let cfg: Ifac9007Cfg = toml::from_str("m = 0.4").unwrap();
/// assert_eq!(cfg.build(&ctx).unwrap_err().key, "plant.m");
/// // …unless the box is widened.
/// let cfg: Ifac9007Cfg = toml::from_str("m = 0.4\nwiden_box = true").unwrap();
/// assert!(cfg.build(&ctx).is_ok());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Ifac9007Cfg {
    /// Compressibility modulus B (default 14000, `jl:31`).
    #[serde(rename = "B")]
    pub b: f64,
    /// Mass m (default 0.1287, `jl:32`).
    pub m: f64,
    /// Friction coefficient R (default 0.150, `jl:33`).
    #[serde(rename = "R")]
    pub r: f64,
    /// Coulomb friction coefficient Rc (default 0.01, `jl:34`).
    #[serde(rename = "Rc")]
    pub rc: f64,
    /// Bypass oil coefficient KL (default 0.002, `jl:35`).
    #[serde(rename = "KL")]
    pub kl: f64,
    /// Hydraulic constant σ (default 0.24, `jl:36`).
    pub sigma: f64,
    /// Volume V (default 874, `jl:37`).
    #[serde(rename = "V")]
    pub v: f64,
    /// Piston area A (default 10.75, `jl:38`).
    #[serde(rename = "A")]
    pub a: f64,
    /// The constant load disturbance FL (the benchmark's force unit; box
    /// [0, 800], `jl:107`; default 0).
    #[serde(rename = "FL")]
    pub fl: f64,
    /// Allow parameters and FL outside the published box (default false).
    pub widen_box: bool,
}

impl Default for Ifac9007Cfg {
    fn default() -> Self {
        Self::of(Ifac9007Params::NOMINAL, 0.0)
    }
}

impl Ifac9007Cfg {
    /// The configuration of the parameters `p` and the load `fl`.
    pub fn of(p: Ifac9007Params, fl: f64) -> Self {
        Self {
            b: p.b,
            m: p.m,
            r: p.r,
            rc: p.rc,
            kl: p.kl,
            sigma: p.sigma,
            v: p.v,
            a: p.a,
            fl,
            widen_box: false,
        }
    }

    /// The eight parameters.
    pub fn params(&self) -> Ifac9007Params {
        Ifac9007Params {
            b: self.b,
            m: self.m,
            r: self.r,
            rc: self.rc,
            kl: self.kl,
            sigma: self.sigma,
            v: self.v,
            a: self.a,
        }
    }
}

/// A value outside its box, by its key.
fn check_box(key: &str, v: f64, low: f64, high: f64, widen: bool) -> Result<(), KeyError> {
    let key = format!("plant.{key}");
    crate::error::finite(&key, v)?;
    if !widen && !(low..=high).contains(&v) {
        return Err(KeyError::new(
            key,
            Reason::OutsideBox {
                value: v,
                low,
                high,
            },
        ));
    }
    Ok(())
}

impl Ifac9007Cfg {
    /// Checks every key: finite, m, V, A > 0 always, each parameter and FL
    /// inside the published box unless `widen_box`.
    pub fn validate(&self, ctx: &PlantContext) -> Result<(), KeyError> {
        let params = self.params();
        let vals = params.values();
        for ((key, low, high), v) in Ifac9007Params::BOX.iter().zip(vals) {
            check_box(key, v, *low, *high, self.widen_box)?;
            if matches!(*key, "m" | "V" | "A") {
                crate::error::positive(&format!("plant.{key}"), v)?;
            } else {
                crate::error::non_negative(&format!("plant.{key}"), v)?;
            }
        }
        check_box("FL", self.fl, FL_BOX.0, FL_BOX.1, self.widen_box)?;
        params
            .servo_params()
            .validate()
            .map_err(|e| KeyError::new("plant", Reason::Param(e)))?;
        let phys = &ctx.uncertainty.physical;
        phys.validate()
            .map_err(|e| e.under("uncertainty.physical"))?;
        if phys.supply_pressure != Spread::NONE {
            return Err(KeyError::new(
                "uncertainty.physical.supply_pressure",
                "the IFAC 9007 plant has no supply pressure: vary B, m, KL, the friction or FL",
            ));
        }
        Ok(())
    }
}

impl PlantConfig for Ifac9007Cfg {
    const MODEL: &'static str = "ifac9007";
    const DOC: &'static str =
        "IFAC benchmark 9007, the hydraulic positioning system (Davison 1990), linear, in (y, ẏ, p)";
    const PAPER_UNCERTAINTY: bool = false;
    const USES_LOAD: bool = false;
    type Plant = Ifac9007Plant;

    fn axis(&self) -> Axis {
        Axis::Linear
    }

    fn build(&self, ctx: &PlantContext) -> Result<Ifac9007Plant, KeyError> {
        self.validate(ctx)?;
        Ok(Ifac9007Plant::new(self.params(), self.fl))
    }
}

/// The benchmark's plant: the parameters, FL, and the nominal model told
/// to the controller.
#[derive(Debug, Clone, PartialEq)]
pub struct Ifac9007Plant {
    /// The parameters.
    pub params: Ifac9007Params,
    /// The load disturbance FL.
    pub fl: f64,
    model: NominalModel,
}

/// The variation of one hold interval: the physical factors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ifac9007Variation {
    /// The factors (module doc).
    pub f: Factors,
}

impl Ifac9007Plant {
    /// The plant with the parameters `params` and the load `fl` (assumed
    /// checked: [`Ifac9007Cfg::build`] checks them).
    pub fn new(params: Ifac9007Params, fl: f64) -> Self {
        let load = Load {
            amplitude: 0.0,
            wavenumber: 0.0,
            friction: None,
        };
        Self {
            params,
            fl,
            model: NominalModel::new(params.servo_params(), load),
        }
    }

    /// The same plant with its parameters and FL varied by `f` (the
    /// operating point of `ehservo linearize` folds a bias in so).
    pub fn with_factors(&self, f: &Factors) -> Self {
        Self::new(self.params.varied(f), self.fl * f.load)
    }

    /// ẋ2 of `jl:81–83` with the load term of `jl:100`.
    #[inline]
    fn accel(p: &Ifac9007Params, fl: f64, s: &[f64; 3]) -> f64 {
        (-p.damping() * s[1] + p.a * s[2] - fl) / p.m
    }

    /// The derivative of the linear model with varied parameters `p`, load
    /// `fl`, under the command `u` (saturated at ±[`INPUT_LIMIT`]).
    #[inline]
    pub fn rhs(p: &Ifac9007Params, fl: f64, s: &[f64; 3], u: f64, ds: &mut [f64; 3]) {
        let u = u.clamp(-INPUT_LIMIT, INPUT_LIMIT);
        let k = 4.0 * p.b / p.v;
        ds[0] = s[1];
        ds[1] = Self::accel(p, fl, s);
        // u_b = −u (module doc): −(4B/V)·u_b = +(4B/V)·u.
        ds[2] = -k * p.a * s[1] - k * (p.sigma + p.kl) * s[2] + k * u;
    }
}

impl Plant for Ifac9007Plant {
    type State = [f64; 3];
    type Variation = Ifac9007Variation;
    type Prepared = ();

    fn axis(&self) -> Axis {
        Axis::Linear
    }

    /// The pressure that holds the acceleration x0[2] at the speed x0[1]:
    /// x3 = (m·ÿ + (R + 4Rc/π)·ẏ + FL)/A.
    fn initial_state(&self, x0: [f64; 3], v: &Ifac9007Variation) -> [f64; 3] {
        let p = self.params.varied(&v.f);
        let fl = self.fl * v.f.load;
        [x0[0], x0[1], (p.m * x0[2] + p.damping() * x0[1] + fl) / p.a]
    }

    #[inline]
    fn measure(&self, _t: f64, s: &[f64; 3], v: &Ifac9007Variation) -> [f64; 3] {
        let p = self.params.varied(&v.f);
        [s[0], s[1], Self::accel(&p, self.fl * v.f.load, s)]
    }

    /// max(a3, √a2) of the varied model, the largest |λ| of s·(s² + a3·s +
    /// a2) (real roots: both ≤ a3; complex ones: |λ| = √a2).
    #[inline]
    fn stiffness(&self, _t: f64, _s: &[f64; 3], _u: f64, v: &Ifac9007Variation) -> f64 {
        let c = self.params.varied(&v.f).servo_params().coefficients();
        c.a3.max(c.a2.max(0.0).sqrt())
    }

    #[inline]
    fn deriv(&self, _t: f64, s: &[f64; 3], u: f64, v: &Ifac9007Variation, ds: &mut [f64; 3]) {
        Self::rhs(&self.params.varied(&v.f), self.fl * v.f.load, s, u, ds);
    }

    fn nominal(&self) -> &NominalModel {
        &self.model
    }

    fn variation(&self, spec: &UncertaintySpec, r: &Draw) -> Ifac9007Variation {
        Ifac9007Variation {
            f: spec.physical.factors(&r.physical),
        }
    }

    /// (19) at the applied command, as the cylinder's:
    /// `x⃛_model(u) − x⃛_true + d̄(x)`, with the true jerk
    /// `(A·ẋ3 − (R + 4Rc/π)·ẍ2)/m` (FL constant).
    fn lumped_uncertainty(
        &self,
        s: &[f64; 3],
        x: &[f64; 3],
        u: f64,
        _u_eq: f64,
        _b_bar: f64,
        v: &Ifac9007Variation,
    ) -> f64 {
        let p = self.params.varied(&v.f);
        let mut ds = [0.0; 3];
        Self::rhs(&p, self.fl * v.f.load, s, u, &mut ds);
        let jerk = (p.a * ds[2] - p.damping() * ds[1]) / p.m;
        let m = &self.model;
        let a = m.coeffs.as_array();
        let (b, d) = m.b_and_d(x, sgn(u));
        let model = -a[0] * x[0] - a[1] * x[1] - a[2] * x[2] + b * u - d;
        model - jerk + d
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values (a saturated run, a box's end, a1 = 0) are the point
#[path = "ifac9007_tests.rs"]
mod tests;
