//! The paper's physical model (1)–(6) as a plant, in (θ, θ̇, Pl):
//!
//! ```text
//! (Vt/4βe)·Ṗl = (1 + δb)·Kg(Pl, sgn u)·Kv·u − Dm·θ̇ − Kce·Pl − (Jt/Dm)·Σ Δa_i·x_i
//! Jt·θ̈ = Pl·Dm − Bm·θ̇ − G·θ − Tl(θ, θ̇)
//! ```
//!
//! **Variation.** The paper's form is carried exactly: the valve flow
//! scaled by `1 + δb`, and the `Δa_i` as an unmodelled flow term
//! `−(Jt/Dm)·Σ Δa_i·x_i` in `Ṗl`. Differentiating (4) once shows that this
//! term adds exactly `−Σ Δa_i·x_i` to `θ⃛`, so this plant and the
//! third-order one are the same system under any such variation (a test
//! checks it). The physical form (`[uncertainty.physical]`, bias and
//! random) is carried exactly too: over each hold interval the equations
//! above are evaluated with Jt·mass, βe·bulk_modulus, Kce·leakage,
//! Ps·supply_pressure, the load's amplitude·load and its friction
//! forces·friction. The lumped uncertainty (19) is then the true model's
//! third-order form against the nominal one:
//! `Σ (a_i,true + Δa_i − ā_i)·x_i − (b_true − b̄)·u_eq + d_true`.

use crate::axis::Axis;
use crate::error::KeyError;
use crate::plant::MAX_STATES;
use crate::plant::{lumped, Draw, Plant, PlantConfig, PlantContext, UncertaintySpec, Variation};
use crate::third_order::{paper_family, varied, LOAD_PRESSURE};
use crate::uncertainty::Factors;
use ehservo_core::control::Signal;
use ehservo_core::math::sgn;
use ehservo_core::servo::{Load, NominalModel, ServoParams};
use serde::{Deserialize, Serialize};

/// One hold interval's variation of the physical plant: the paper's form
/// and the physical parameters it has then.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhysicalVariation {
    /// Δa_i and δb.
    pub paper: Variation,
    /// The physical factors.
    pub factors: Factors,
}

/// The physical model (1)–(6) in (θ, θ̇, Pl).
///
/// ```
/// use ehservo_sim::core::servo::{Load, ServoParams};
/// use ehservo_sim::physical::PhysicalVariation;
/// use ehservo_sim::plant::{Factors, PhysicalPlant, Plant, Variation};
///
/// let p = ServoParams::paper();
/// let plant = PhysicalPlant::new(p, Load::none());
/// let v = PhysicalVariation { paper: Variation::NONE, factors: Factors::ONE };
/// // At rest under u = 1 V, (5): (Vt/4βe)·Ṗl = Kg·Kv·u with Kg = Cd·Ag·√(Ps/ρ) (2).
/// let mut ds = [0.0; 3];
/// plant.deriv(0.0, &[0.0; 3], 1.0, &v, &mut ds);
/// let kg = p.cd * p.ag * (p.ps / p.rho).sqrt();
/// let pl_rate = 4.0 * p.beta_e / p.vt * kg * p.kv;
/// assert_eq!(ds[..2], [0.0, 0.0]);
/// assert!((ds[2] - pl_rate).abs() <= 1e-12 * pl_rate);
/// // (4) differentiated: Jt·θ⃛ = Dm·Ṗl, the third-order model's b·u at rest.
/// let b0 = plant.nominal().b_at_rest();
/// assert!((p.dm / p.jt * ds[2] - b0).abs() <= 1e-12 * b0);
/// ```
#[derive(Debug, Clone, Copy)]
pub struct PhysicalPlant {
    model: NominalModel,
}

impl PhysicalPlant {
    /// From validated physical parameters and load.
    pub fn new(params: ServoParams, load: Load) -> Self {
        Self {
            model: NominalModel::new(params, load),
        }
    }

    /// The true parameters and load under `v` (the nominal ones, the same
    /// values, when no physical factor is set).
    #[inline]
    fn truth(&self, v: &PhysicalVariation) -> (ServoParams, Load) {
        if v.factors == Factors::ONE {
            (self.model.params, self.model.load)
        } else {
            varied(&self.model.params, &self.model.load, &v.factors)
        }
    }
}

impl Plant for PhysicalPlant {
    type State = [f64; 3];
    type Variation = PhysicalVariation;
    type Prepared = ();
    const STATES: &'static [Signal] = &LOAD_PRESSURE;

    fn states(&self, _t: f64, s: &[f64; 3], _x: &[f64; 3], out: &mut [f64; MAX_STATES]) {
        out[0] = s[2];
    }

    /// Pl(0) from the torque balance (4) with θ̈(0) = `x0[2]`.
    fn initial_state(&self, x0: [f64; 3], v: &PhysicalVariation) -> [f64; 3] {
        let (p, l) = self.truth(v);
        [x0[0], x0[1], NominalModel::new(p, l).load_pressure(&x0)]
    }

    /// θ̈ from (4): `(Pl·Dm − Bm·θ̇ − G·θ − Tl)/Jt`.
    #[inline]
    fn measure(&self, _t: f64, s: &[f64; 3], v: &PhysicalVariation) -> [f64; 3] {
        let (p, l) = self.truth(v);
        let tl = l.torque(s[0], s[1]);
        [
            s[0],
            s[1],
            (s[2] * p.dm - p.bm * s[1] - p.g * s[0] - tl) / p.jt,
        ]
    }

    #[inline]
    fn deriv(&self, _t: f64, s: &[f64; 3], u: f64, v: &PhysicalVariation, ds: &mut [f64; 3]) {
        let (p, _) = self.truth(v);
        let x = self.measure(0.0, s, v);
        let (kg, _) = p.flow_gain(s[2], sgn(u));
        let da = &v.paper.da;
        let flow = (1.0 + v.paper.db_rel) * kg * p.kv * u;
        ds[0] = s[1];
        ds[1] = x[2];
        ds[2] = 4.0 * p.beta_e / p.vt * (flow - p.dm * s[1] - p.kce * s[2])
            - p.jt / p.dm * (da[0] * x[0] + da[1] * x[1] + da[2] * x[2]);
    }

    fn nominal(&self) -> &NominalModel {
        &self.model
    }

    fn variation(&self, spec: &UncertaintySpec, r: &Draw) -> PhysicalVariation {
        PhysicalVariation {
            paper: Variation::of(spec, &self.model.coeffs.as_array(), r),
            factors: spec.physical.factors(&r.physical),
        }
    }

    fn lumped_uncertainty(
        &self,
        _s: &[f64; 3],
        x: &[f64; 3],
        u: f64,
        u_eq: f64,
        b_bar: f64,
        v: &PhysicalVariation,
    ) -> f64 {
        if v.factors == Factors::ONE {
            let (b, d) = self.model.b_and_d(x, sgn(u));
            return lumped(x, u_eq, b_bar, &v.paper, b, d);
        }
        let (p, l) = self.truth(v);
        let t = NominalModel::new(p, l);
        let (b, d) = t.b_and_d(x, sgn(u));
        let (at, an) = (t.coeffs.as_array(), self.model.coeffs.as_array());
        let da = core::array::from_fn(|i| at[i] + v.paper.da[i] - an[i]);
        lumped(x, u_eq, b_bar, &Variation { da, ..v.paper }, b, d)
    }
}

/// `[plant] model = "physical"`: the same `[plant.params]` as the
/// third-order model; the load is the scenario's `[load]`.
///
/// ```
/// use ehservo_sim::physical::PhysicalCfg;
/// use ehservo_sim::plant::{Plant, PlantConfig, PlantContext, UncertaintySpec};
/// use ehservo_sim::third_order::ThirdOrderCfg;
///
/// let ctx = PlantContext {
///     load: None,
///     load_given: false,
///     uncertainty: UncertaintySpec::NONE,
///     x0: [0.0; 3],
///     base_dir: None,
///     reference_range: None,
///     quantity: Default::default(),
/// };
/// // The same servo as `"third-order"`, in (θ, θ̇, Pl): the controller is
/// // told the same nominal model.
/// assert_eq!(PhysicalCfg::MODEL, "physical");
/// let phys = PhysicalCfg::default().build(&ctx).unwrap();
/// let third = ThirdOrderCfg::default().build(&ctx).unwrap();
/// assert_eq!(phys.nominal(), third.nominal());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct PhysicalCfg {
    /// `[plant.params]`.
    pub params: ServoParams,
}

impl PlantConfig for PhysicalCfg {
    const MODEL: &'static str = "physical";
    const DOC: &'static str = "the paper's physical model (1)–(6) in (θ, θ̇, Pl)";
    const PAPER_UNCERTAINTY: bool = true;
    const USES_LOAD: bool = true;
    type Plant = PhysicalPlant;

    fn axis(&self) -> Axis {
        Axis::Rotary
    }

    fn build(&self, ctx: &PlantContext) -> Result<PhysicalPlant, KeyError> {
        let load = paper_family(&self.params, ctx, true)?;
        Ok(PhysicalPlant::new(self.params, load))
    }

    fn paper_params(&self) -> Option<ServoParams> {
        Some(self.params)
    }

    fn with_paper_params(&self, params: ServoParams) -> Option<Self> {
        Some(Self { params })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::third_order::ThirdOrderPlant;
    use crate::uncertainty::{PhysicalSpec, Spread};

    /// The physical model's measured θ̈ and the third-order model's x3 have
    /// the same derivative at a state (the two models are one system),
    /// under the paper's variation and under a physical bias.
    #[test]
    fn models_have_the_same_jerk() {
        let p = ServoParams::paper();
        let x = [0.03, -0.2, 1.5];
        let v = Variation {
            da: [0.4, 13000.0, 170.0],
            db_rel: 0.25,
        };
        let bias = PhysicalSpec {
            mass: Spread {
                bias: 0.4,
                random: 0.0,
            },
            leakage: Spread {
                bias: 2.0,
                random: 0.0,
            },
            supply_pressure: Spread {
                bias: -0.2,
                random: 0.0,
            },
            load: Spread {
                bias: -0.5,
                random: 0.0,
            },
            ..Default::default()
        }
        .factors(&[0.0; 6]);
        for f in [Factors::ONE, bias] {
            let third = ThirdOrderPlant::with_bias(p, Load::paper(), &f);
            let phys = PhysicalPlant::new(p, Load::paper());
            let pv = PhysicalVariation {
                paper: v,
                factors: f,
            };
            let (tp, tl) = varied(&p, &Load::paper(), &f);
            for &u in &[0.3, -0.2] {
                let mut d3 = [0.0; 3];
                third.deriv(0.0, &x, u, &v, &mut d3);
                // d/dt of the physical θ̈ = (Ṗl·Dm − Bm·θ̈ − G·θ̇ − Ṫl)/Jt.
                let s = phys.initial_state(x, &pv);
                assert!((phys.measure(0.0, &s, &pv)[2] - x[2]).abs() < 1e-9);
                let mut ds = [0.0; 3];
                phys.deriv(0.0, &s, u, &pv, &mut ds);
                let jerk =
                    (ds[2] * tp.dm - tp.bm * x[2] - tp.g * x[1] - tl.torque_rate(x[0], x[1], x[2]))
                        / tp.jt;
                assert!(
                    (jerk - d3[2]).abs() < 1e-6 * d3[2].abs().max(1.0),
                    "{jerk} vs {}",
                    d3[2]
                );
            }
        }
    }
}
