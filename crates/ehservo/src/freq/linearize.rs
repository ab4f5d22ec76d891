//! Analytic Jacobians of the loop's stages about an operating point: the
//! plants (third-order (8)–(9) and physical (1)–(6)), the actuator stage
//! (saturation, first- or second-order spool, rate limit, dead band, null
//! bias) and a delay of whole samples (the sensor's, the computation's).
//!
//! Each stage implements [`Linearize`]: its nonlinear right-hand side and
//! output, **evaluated by the simulator's own code** (`Plant::deriv`,
//! `Actuator::deriv`, `Actuator::output`), beside hand-derived Jacobians
//! `A = ∂f/∂x`, `B = ∂f/∂u`, `C = ∂y/∂x`, `D = ∂y/∂u`; the tests hold the
//! second to central differences of the first. A stage also names the
//! points where it is **not differentiable** ([`Kink`]) — the valve's
//! `sgn(xv)` at `xv = 0` when the two directions' flow gains differ, the
//! orifice at a zero pressure drop `Ps − sgn(xv)·P_L = 0` (the root's slope
//! is infinite), a saturation, rate limit or dead-band edge — and gives
//! the one-sided Jacobians there ([`Side`]); and the regimes where it is
//! differentiable with a zero gain (saturated, inside the dead band, the
//! valve root clamped), as notes.
//!
//! A new plant (the lead's cylinder) implements [`Linearize`] and
//! [`PlantState`]; nothing else here knows a plant.

use super::ss::{Quantity, StateSpace};
use crate::actuator::{second_order_bandwidth_ratio, Actuator, ActuatorConfig};
use crate::physical::PhysicalVariation;
use crate::plant::{PhysicalPlant, Plant, ThirdOrderPlant, Variation};
use crate::simulation::Sample;
use ehservo_core::error::ParamError;
use ehservo_core::servo::{Friction, Load, NominalModel};
use ehservo_sim::uncertainty::Factors;
use nalgebra::DMatrix;

/// Which one-sided derivative to take at a kink: the kinked quantity
/// approached from below (`Minus`) or from above (`Plus`). Away from a
/// kink both give the derivative.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// From below.
    Minus,
    /// From above.
    Plus,
}

impl Side {
    /// The scenario spelling (`--side minus|plus`).
    pub fn as_str(&self) -> &'static str {
        match self {
            Side::Minus => "minus",
            Side::Plus => "plus",
        }
    }

    /// The sign a kinked quantity at exactly its kink takes on this side.
    fn sign(&self) -> f64 {
        match self {
            Side::Minus => -1.0,
            Side::Plus => 1.0,
        }
    }
}

/// Where a stage is not differentiable.
#[derive(Debug, Clone, PartialEq)]
pub struct Kink {
    /// What, for people (with the values there).
    pub what: String,
    /// The quantity at its kink (`u_plant`, `u`, `p_load`, `spool`).
    pub quantity: String,
}

/// The linearisation of one stage at a point.
#[derive(Debug, Clone, PartialEq)]
pub struct Jacobian {
    /// ∂f/∂x (n × n).
    pub a: DMatrix<f64>,
    /// ∂f/∂u (n × 1).
    pub b: DMatrix<f64>,
    /// ∂y/∂x (1 × n).
    pub c: DMatrix<f64>,
    /// ∂y/∂u (1 × 1).
    pub d: DMatrix<f64>,
}

impl Jacobian {
    fn zeros(n: usize) -> Self {
        Self {
            a: DMatrix::zeros(n, n),
            b: DMatrix::zeros(n, 1),
            c: DMatrix::zeros(1, n),
            d: DMatrix::zeros(1, 1),
        }
    }

    /// Every entry finite (an orifice at ΔP = 0 has an infinite slope on
    /// its open side).
    pub fn is_finite(&self) -> bool {
        [&self.a, &self.b, &self.c, &self.d]
            .iter()
            .all(|m| m.iter().all(|v| v.is_finite()))
    }
}

/// An operating point: a stage's state, its input and the plant's
/// parameter variation there.
#[derive(Debug, Clone, Copy)]
pub struct Point<'a> {
    /// The state, in the order of [`Linearize::states`].
    pub x: &'a [f64],
    /// The input.
    pub u: f64,
    /// The plant's variation (ignored by the other stages).
    pub v: Variation,
}

/// A stage of the loop with one input and one output, linearised
/// analytically.
pub trait Linearize {
    /// None for a continuous-time stage; the sample period of a discrete one.
    fn dt(&self) -> Option<f64> {
        None
    }
    /// The states, with units.
    fn states(&self) -> Vec<Quantity>;
    /// The input, with its unit.
    fn input(&self) -> Quantity;
    /// The output, with its unit.
    fn output(&self) -> Quantity;
    /// A typical size of each state (finite-difference steps, Newton's
    /// scaling), in its unit.
    fn scales(&self) -> Vec<f64>;
    /// The nonlinear right-hand side `dx = f(x, u)` (the next state, for a
    /// discrete stage) and the output `y = g(x, u)`, as the simulator
    /// computes them.
    fn eval(&self, p: &Point, dx: &mut [f64]) -> f64;
    /// The Jacobians at `p`; at a kink, the one-sided ones of `side`.
    fn jacobian(&self, p: &Point, side: Side) -> Jacobian;
    /// Where `p` is a point at which `eval` is not differentiable.
    fn kinks(&self, p: &Point) -> Vec<Kink>;
    /// Regimes at `p` that are differentiable but cut the loop (a zero
    /// gain): saturated, inside the dead band, the valve root clamped.
    fn notes(&self, _p: &Point) -> Vec<String> {
        Vec::new()
    }

    /// The linear model at `p` on `side`.
    fn model(&self, p: &Point, side: Side) -> StateSpace {
        let j = self.jacobian(p, side);
        StateSpace::new(
            j.a,
            j.b,
            j.c,
            j.d,
            self.dt(),
            (self.states(), vec![self.input()], vec![self.output()]),
        )
    }
}

/// A plant whose state can be read off the simulator's logged samples
/// (with `Simulation::log_states(true)`), in [`Linearize::states`]' order.
pub trait PlantState: Linearize {
    /// The plant's state at a logged sample.
    fn state_of(&self, s: &Sample) -> Vec<f64>;
}

/// Tolerance on "exactly at a kink": a quantity within this fraction of its
/// scale of a kink is taken to be at it (a trim point found by Newton
/// lands within round-off of an exact 0, never on it).
const AT_KINK: f64 = 1e-9;

/// Two one-sided slopes that differ by less than this fraction are one.
const SAME_SLOPE: f64 = 1e-9;

/// `sgn` with a side at 0.
fn sign_at(u: f64, side: Side) -> f64 {
    if u > 0.0 {
        1.0
    } else if u < 0.0 {
        -1.0
    } else {
        side.sign()
    }
}

/// The valve direction the plant's input `u` (V) selects: its sign, or
/// the side's when `u` is within [`AT_KINK`] of 0.
fn direction(u: f64, side: Side) -> f64 {
    if u.abs() <= AT_KINK {
        side.sign()
    } else {
        sign_at(u, side)
    }
}

/// `d²Tf/dv²` of the friction torque (for `∂Ṫl/∂θ̇ = … + Tf''(θ̇)·θ̈`):
/// with `th = tanh(v/v0)`, `g = Tc + (Ts − Tc)·e^{−r²}`, `r = v/vs`,
/// `g' = (Ts − Tc)·e^{−r²}·(−2r/vs)`, `g'' = (Ts − Tc)·e^{−r²}·(4r² − 2)/vs²`:
/// `Tf'' = −2·th·(1 − th²)·g/v0² + 2·(1 − th²)·g'/v0 + th·g''`.
pub fn friction_curvature(f: &Friction, v: f64) -> f64 {
    let th = (v / f.smoothing).tanh();
    let r = v / f.stribeck_velocity;
    let e = (-r * r).exp();
    let dts = f.stiction - f.coulomb;
    let g = f.coulomb + dts * e;
    let dg = dts * e * (-2.0 * r / f.stribeck_velocity);
    let ddg = dts * e * (4.0 * r * r - 2.0) / (f.stribeck_velocity * f.stribeck_velocity);
    let v0 = f.smoothing;
    -2.0 * th * (1.0 - th * th) * g / (v0 * v0) + 2.0 * (1.0 - th * th) * dg / v0 + th * ddg
}

/// The load's partial derivatives at x = (θ, θ̇, θ̈): `Tl_θ`, `Tl_θ̇`, and
/// of `Ṫl = A·k·cos(kθ)·θ̇ + Tf'(θ̇)·θ̈` its three.
struct LoadSlopes {
    tl_theta: f64,
    tl_v: f64,
    rate: [f64; 3],
}

fn load_slopes(l: &Load, x: &[f64]) -> LoadSlopes {
    let (s, c) = (l.wavenumber * x[0]).sin_cos();
    let ak = l.amplitude * l.wavenumber;
    let mut out = LoadSlopes {
        tl_theta: ak * c,
        tl_v: 0.0,
        rate: [-ak * l.wavenumber * s * x[1], ak * c, 0.0],
    };
    if let Some(f) = &l.friction {
        let slope = f.slope(x[1]);
        out.tl_v = slope;
        out.rate[1] += friction_curvature(f, x[1]) * x[2];
        out.rate[2] = slope;
    }
    out
}

/// The valve's flow gain `Kg` of (2) for direction `s` at load pressure
/// `pl`, and `∂Kg/∂P_L = −s·Kg/(2·(Ps − s·P_L))` (0 where the root is
/// clamped; infinite at a zero pressure drop).
fn flow_gain_slope(m: &NominalModel, pl: f64, s: f64) -> (f64, f64) {
    let p = &m.params;
    let arg = p.ps - s * pl;
    if arg > 0.0 {
        let kg = p.cd * p.ag * (arg / p.rho).sqrt();
        (kg, -s * kg / (2.0 * arg))
    } else if arg == 0.0 {
        (0.0, -s * f64::INFINITY)
    } else {
        (0.0, 0.0)
    }
}

/// The kinks and notes of the valve of `m` at load pressure `pl` under the
/// plant input `u`: the two directions' flow gains where `u` is 0, and the
/// orifice's pressure drop.
fn valve_kinks(m: &NominalModel, pl: f64, u: f64) -> Vec<Kink> {
    let p = &m.params;
    let mut out = Vec::new();
    let dirs: &[f64] = if u.abs() <= AT_KINK {
        &[-1.0, 1.0]
    } else if u > 0.0 {
        &[1.0]
    } else {
        &[-1.0]
    };
    if u.abs() <= AT_KINK {
        let (kp, _) = flow_gain_slope(m, pl, 1.0);
        let (km, _) = flow_gain_slope(m, pl, -1.0);
        if (kp - km).abs() > SAME_SLOPE * kp.abs().max(km.abs()) {
            out.push(Kink {
                what: format!(
                    "the valve's sgn(xv) at xv = 0 (u_plant = {u:.3e} V, P_L = {pl:.6e} Pa): its flow gain Kg is {kp:.6e} m²/s for xv > 0 and {km:.6e} m²/s for xv < 0",
                ),
                quantity: "u_plant".into(),
            });
        }
    }
    for &s in dirs {
        let arg = p.ps - s * pl;
        if arg.abs() <= AT_KINK * p.ps {
            out.push(Kink {
                what: format!(
                    "the orifice at a zero pressure drop Ps − sgn(xv)·P_L = {arg:.3e} Pa (P_L = {pl:.6e} Pa, Ps = {:.6e} Pa): the flow gain's slope is infinite on the open side",
                    p.ps
                ),
                quantity: "p_load".into(),
            });
        }
    }
    out
}

fn valve_notes(m: &NominalModel, pl: f64, u: f64) -> Vec<String> {
    let p = &m.params;
    let s = if u > AT_KINK {
        1.0
    } else if u < -AT_KINK {
        -1.0
    } else {
        return Vec::new();
    };
    if p.ps - s * pl < -AT_KINK * p.ps {
        vec![format!(
            "the valve root is clamped (Ps − sgn(xv)·P_L = {:.4e} Pa < 0): no flow in this direction, the plant's input gain is 0",
            p.ps - s * pl
        )]
    } else {
        Vec::new()
    }
}

fn names3(third: &str) -> Vec<Quantity> {
    vec![
        Quantity::new("theta", "rad"),
        Quantity::new("theta_dot", "rad/s"),
        match third {
            "p_load" => Quantity::new("p_load", "Pa"),
            _ => Quantity::new("theta_ddot", "rad/s²"),
        },
    ]
}

/// The third-order model (8)–(9), `x = (θ, θ̇, θ̈)`, input the valve
/// command the plant receives (V), output θ.
///
/// ```text
/// f3 = −Σ(a_i + Δa_i)·x_i + (1 + δb)·b(x, sgn u)·u − d(x)
/// ∂f3/∂x_i = −(a_i + Δa_i) + (1 + δb)·u·∂b/∂P_L·∂P_L/∂x_i − ∂d/∂x_i
/// ∂f3/∂u   = (1 + δb)·b(x, sgn u)
/// ∂b/∂P_L = −s·b/(2·(Ps − s·P_L)),  ∂P_L/∂x = ((G + Tl_θ), (Bm + Tl_θ̇), Jt)/Dm
/// ∂d/∂x   = 4βe·Kce/(Vt·Jt)·(Tl_θ, Tl_θ̇, 0) + ∂Ṫl/∂x / Jt
/// ```
impl Linearize for ThirdOrderPlant {
    fn states(&self) -> Vec<Quantity> {
        names3("theta_ddot")
    }
    fn input(&self) -> Quantity {
        Quantity::new("u_plant", "V")
    }
    fn output(&self) -> Quantity {
        Quantity::new("theta", "rad")
    }
    fn scales(&self) -> Vec<f64> {
        vec![0.1, 1.0, 100.0]
    }
    fn eval(&self, p: &Point, dx: &mut [f64]) -> f64 {
        let x = [p.x[0], p.x[1], p.x[2]];
        let mut d = [0.0; 3];
        self.deriv(0.0, &x, p.u, &p.v, &mut d);
        dx.copy_from_slice(&d);
        x[0]
    }
    fn jacobian(&self, p: &Point, side: Side) -> Jacobian {
        let m = self.nominal();
        let (par, a) = (&m.params, &m.coeffs);
        let x = [p.x[0], p.x[1], p.x[2]];
        let ls = load_slopes(&m.load, &x);
        let pl = m.load_pressure(&x);
        let s = direction(p.u, side);
        let (kg, dkg) = flow_gain_slope(m, pl, s);
        let bpk = par.b_per_kg();
        let bt = 1.0 + p.v.db_rel;
        let b = bpk * kg;
        let db_dpl = bpk * dkg;
        let dpl = [
            (par.g + ls.tl_theta) / par.dm,
            (par.bm + ls.tl_v) / par.dm,
            par.jt / par.dm,
        ];
        let dpt = par.d_per_torque();
        let dd = [
            dpt * ls.tl_theta + ls.rate[0] / par.jt,
            dpt * ls.tl_v + ls.rate[1] / par.jt,
            ls.rate[2] / par.jt,
        ];
        let ai = [a.a1 + p.v.da[0], a.a2 + p.v.da[1], a.a3 + p.v.da[2]];
        let mut j = Jacobian::zeros(3);
        j.a[(0, 1)] = 1.0;
        j.a[(1, 2)] = 1.0;
        for i in 0..3 {
            // u·∂b is 0 at u = 0 whatever the side (even beside an
            // infinite ∂b at ΔP = 0, which the kink reports).
            let flow = if p.u == 0.0 {
                0.0
            } else {
                bt * p.u * db_dpl * dpl[i]
            };
            j.a[(2, i)] = -ai[i] + flow - dd[i];
        }
        j.b[(2, 0)] = bt * b;
        j.c[(0, 0)] = 1.0;
        j
    }
    fn kinks(&self, p: &Point) -> Vec<Kink> {
        let m = self.nominal();
        valve_kinks(m, m.load_pressure(&[p.x[0], p.x[1], p.x[2]]), p.u)
    }
    fn notes(&self, p: &Point) -> Vec<String> {
        let m = self.nominal();
        valve_notes(m, m.load_pressure(&[p.x[0], p.x[1], p.x[2]]), p.u)
    }
}

impl PlantState for ThirdOrderPlant {
    fn state_of(&self, s: &Sample) -> Vec<f64> {
        s.x.to_vec()
    }
}

/// The physical model (1)–(6), state `(θ, θ̇, P_L)`, input the valve
/// command (V), output θ.
///
/// ```text
/// θ̈  = (P_L·Dm − Bm·θ̇ − G·θ − Tl)/Jt
/// f3 = 4βe/Vt·((1 + δb)·Kg(P_L, sgn u)·Kv·u − Dm·θ̇ − Kce·P_L) − Jt/Dm·(Δa1·θ + Δa2·θ̇ + Δa3·θ̈)
/// ∂θ̈/∂x  = (−(G + Tl_θ), −(Bm + Tl_θ̇), Dm)/Jt
/// ∂f3/∂θ  = −Jt/Dm·(Δa1 + Δa3·∂θ̈/∂θ)
/// ∂f3/∂θ̇  = −4βe·Dm/Vt − Jt/Dm·(Δa2 + Δa3·∂θ̈/∂θ̇)
/// ∂f3/∂P_L = 4βe/Vt·((1 + δb)·Kv·u·∂Kg/∂P_L − Kce) − Δa3
/// ∂f3/∂u  = 4βe/Vt·(1 + δb)·Kg·Kv
/// ```
/// The physical plant's variation with the paper's part `v` alone: a
/// physical bias or draw is in the plant's parameters instead (the
/// operating point builds the plant with its true parameters, which is the
/// same derivative: `PhysicalPlant` varies them by the factors).
fn physical(v: Variation) -> PhysicalVariation {
    PhysicalVariation {
        paper: v,
        factors: Factors::ONE,
    }
}

impl Linearize for PhysicalPlant {
    fn states(&self) -> Vec<Quantity> {
        names3("p_load")
    }
    fn input(&self) -> Quantity {
        Quantity::new("u_plant", "V")
    }
    fn output(&self) -> Quantity {
        Quantity::new("theta", "rad")
    }
    fn scales(&self) -> Vec<f64> {
        vec![0.1, 1.0, 1e6]
    }
    fn eval(&self, p: &Point, dx: &mut [f64]) -> f64 {
        let s = [p.x[0], p.x[1], p.x[2]];
        let mut d = [0.0; 3];
        self.deriv(0.0, &s, p.u, &physical(p.v), &mut d);
        dx.copy_from_slice(&d);
        s[0]
    }
    fn jacobian(&self, p: &Point, side: Side) -> Jacobian {
        let m = self.nominal();
        let par = &m.params;
        let s = [p.x[0], p.x[1], p.x[2]];
        let x = self.measure(0.0, &s, &physical(p.v));
        let ls = load_slopes(&m.load, &x);
        let dacc = [
            -(par.g + ls.tl_theta) / par.jt,
            -(par.bm + ls.tl_v) / par.jt,
            par.dm / par.jt,
        ];
        let dir = direction(p.u, side);
        let (kg, dkg) = flow_gain_slope(m, s[2], dir);
        let bt = 1.0 + p.v.db_rel;
        let k = 4.0 * par.beta_e / par.vt;
        let r = par.jt / par.dm;
        let da = p.v.da;
        let mut j = Jacobian::zeros(3);
        j.a[(0, 1)] = 1.0;
        for (i, d) in dacc.iter().enumerate() {
            j.a[(1, i)] = *d;
        }
        j.a[(2, 0)] = -r * (da[0] + da[2] * dacc[0]);
        j.a[(2, 1)] = -k * par.dm - r * (da[1] + da[2] * dacc[1]);
        let flow = if p.u == 0.0 {
            0.0
        } else {
            bt * par.kv * p.u * dkg
        };
        j.a[(2, 2)] = k * (flow - par.kce) - r * da[2] * dacc[2];
        j.b[(2, 0)] = k * bt * kg * par.kv;
        j.c[(0, 0)] = 1.0;
        j
    }
    fn kinks(&self, p: &Point) -> Vec<Kink> {
        valve_kinks(self.nominal(), p.x[2], p.u)
    }
    fn notes(&self, p: &Point) -> Vec<String> {
        valve_notes(self.nominal(), p.x[2], p.u)
    }
}

impl PlantState for PhysicalPlant {
    /// `(θ, θ̇, P_L)`: P_L is the sample's logged load pressure.
    fn state_of(&self, s: &Sample) -> Vec<f64> {
        vec![s.x[0], s.x[1], s.states[0]]
    }
}

/// The spool's dynamics, as `Actuator::try_new` derives them from
/// `[actuator]` (the same formulas; the tests hold this stage's
/// derivatives to the `Actuator`'s own).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Spool {
    None,
    First { tau: f64 },
    Second { wn2: f64, two_zeta_wn: f64 },
}

/// The actuator stage: command (V) → saturation → spool → dead band and
/// null bias → the plant's input (V). Its states are the spool's: none,
/// `v` (first order) or `(v, v̇)` (second order).
///
/// ```text
/// sat'(u) = 1 for |u| < limit, 0 beyond (kink at |u| = limit)
/// first:  v̇ = (sat(u) − v)/τ          A = −1/τ, B = sat'/τ   (|v̇| < rate_limit; 0 beyond)
/// second: v̇ = w, ẇ = ωn²(sat(u) − v) − 2ζωn·w
///         A = [[0, 1], [−ωn², −2ζωn]], B = (0, ωn²·sat')     (|w| < rate_limit)
/// output: db(v + null_bias), slope 1 outside the dead band, 0 inside (kink at its edge)
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActuatorStage {
    act: Actuator,
    limit: f64,
    rate: f64,
    spool: Spool,
    dead_band: f64,
    null_bias: f64,
}

impl ActuatorStage {
    /// The stage of `[actuator]` (validated as `Actuator::try_new` does).
    pub fn new(c: &ActuatorConfig) -> Result<Self, ParamError> {
        let act = Actuator::try_new(c)?;
        let spool = match (c.time_constant, c.bandwidth_hz) {
            (Some(tau), _) => Spool::First { tau },
            (None, Some(f)) => {
                let wb = 2.0 * std::f64::consts::PI * f;
                if c.order.unwrap_or(1) == 1 {
                    Spool::First { tau: 1.0 / wb }
                } else {
                    let zeta = c.damping.unwrap_or(0.7);
                    let wn = wb / second_order_bandwidth_ratio(zeta);
                    Spool::Second {
                        wn2: wn * wn,
                        two_zeta_wn: 2.0 * zeta * wn,
                    }
                }
            }
            (None, None) => Spool::None,
        };
        Ok(Self {
            act,
            limit: c.limit.unwrap_or(f64::INFINITY),
            rate: c.rate_limit.unwrap_or(f64::INFINITY),
            spool,
            dead_band: c.dead_band.unwrap_or(0.0),
            null_bias: c.null_bias.unwrap_or(0.0),
        })
    }

    /// The simulator's stage.
    pub fn actuator(&self) -> &Actuator {
        &self.act
    }

    /// The spool state `(v, w)` of the simulator from this stage's states.
    fn full(&self, x: &[f64]) -> [f64; 2] {
        [
            x.first().copied().unwrap_or(0.0),
            x.get(1).copied().unwrap_or(0.0),
        ]
    }

    /// The number of states.
    pub fn n(&self) -> usize {
        match self.spool {
            Spool::None => 0,
            Spool::First { .. } => 1,
            Spool::Second { .. } => 2,
        }
    }

    /// The stage's state at a logged sample: the spool position, and for a
    /// second-order spool its rate, which a sample does not carry (`w`
    /// comes from [`ActuatorStage::replay`]).
    pub fn state_from(&self, spool: f64, rate: f64) -> Vec<f64> {
        match self.spool {
            Spool::None => Vec::new(),
            Spool::First { .. } => vec![spool],
            Spool::Second { .. } => vec![spool, rate],
        }
    }

    /// The spool's state after the held commands `u` (one per sample of
    /// `h`, integrated by `substeps` RK4 steps each, from rest): the
    /// simulator integrates the spool with the plant in one RK4 state, but
    /// the spool's derivative does not depend on the plant, so its
    /// components of that step are this stage's RK4 step alone.
    pub fn replay(&self, u: &[f64], h: f64, substeps: u32) -> [f64; 2] {
        let mut s = self.act.initial_state();
        if self.spool == Spool::None {
            return s;
        }
        let m = substeps.max(1);
        let hs = h / f64::from(m);
        let act = &self.act;
        for &uk in u {
            for _ in 0..m {
                ehservo_core::rk4::rk4_step(
                    |_t, y: &[f64; 2], dy: &mut [f64; 2]| act.deriv(y, uk, dy),
                    0.0,
                    &mut s,
                    hs,
                );
            }
        }
        s
    }

    /// The steady state that delivers the plant input `p`: the spool at
    /// rest where the dead band and null bias give `p`, the command that
    /// holds it there. An error names the key that makes it impossible.
    pub fn invert(&self, p: f64) -> Result<(Vec<f64>, f64), (String, String)> {
        let v = if p == 0.0 {
            0.0 - self.null_bias
        } else {
            p + self.dead_band * p.signum() - self.null_bias
        };
        if v.abs() > self.limit {
            return Err((
                "actuator.limit".into(),
                format!(
                    "the trim needs a spool at {v:.6} V (the plant's input {p:.6} V), beyond the saturation ±{} V",
                    self.limit
                ),
            ));
        }
        Ok((self.state_from(v, 0.0), v))
    }

    /// The saturation's slope on `side` at `u`.
    fn sat_slope(&self, u: f64, side: Side) -> f64 {
        let over = u.abs() - self.limit;
        if self.limit.is_infinite() || over < -AT_KINK * self.limit {
            1.0
        } else if over > AT_KINK * self.limit {
            0.0
        } else {
            // At the limit: inside from below at +limit, from above at −limit.
            let inside = (u > 0.0) == (side == Side::Minus);
            if inside {
                1.0
            } else {
                0.0
            }
        }
    }

    /// The dead band's slope on `side` at spool `v`.
    fn db_slope(&self, v: f64, side: Side) -> f64 {
        if self.dead_band == 0.0 {
            return 1.0;
        }
        let q = v + self.null_bias;
        let over = q.abs() - self.dead_band;
        if over > AT_KINK * self.dead_band {
            1.0
        } else if over < -AT_KINK * self.dead_band {
            0.0
        } else {
            // At the edge: outside from above at +db, from below at −db.
            let outside = (q > 0.0) == (side == Side::Plus);
            if outside {
                1.0
            } else {
                0.0
            }
        }
    }

    /// Whether a slew `r` is below the rate limit, on `side` at the limit.
    fn under_rate(&self, r: f64, side: Side) -> bool {
        if self.rate.is_infinite() {
            return true;
        }
        let over = r.abs() - self.rate;
        if over < -AT_KINK * self.rate {
            true
        } else if over > AT_KINK * self.rate {
            false
        } else {
            (r > 0.0) == (side == Side::Minus)
        }
    }
}

impl Linearize for ActuatorStage {
    fn states(&self) -> Vec<Quantity> {
        match self.spool {
            Spool::None => Vec::new(),
            Spool::First { .. } => vec![Quantity::new("spool", "V")],
            Spool::Second { .. } => vec![
                Quantity::new("spool", "V"),
                Quantity::new("spool_rate", "V/s"),
            ],
        }
    }
    fn input(&self) -> Quantity {
        Quantity::new("u", "V")
    }
    fn output(&self) -> Quantity {
        Quantity::new("u_plant", "V")
    }
    fn scales(&self) -> Vec<f64> {
        match self.spool {
            Spool::None => Vec::new(),
            Spool::First { tau } => vec![1.0 / tau.max(1e-300) * 0.0 + 1.0],
            Spool::Second { wn2, .. } => vec![1.0, wn2.sqrt()],
        }
    }
    fn eval(&self, p: &Point, dx: &mut [f64]) -> f64 {
        let s = self.full(p.x);
        let mut d = [0.0; 2];
        self.act.deriv(&s, p.u, &mut d);
        let n = self.n();
        dx[..n].copy_from_slice(&d[..n]);
        self.act.output(&s, p.u)
    }
    fn jacobian(&self, p: &Point, side: Side) -> Jacobian {
        let n = self.n();
        let mut j = Jacobian::zeros(n);
        let sat = self.sat_slope(p.u, side);
        let uc = self.act.saturate(p.u);
        let s = self.full(p.x);
        match self.spool {
            Spool::None => {
                j.d[(0, 0)] = self.db_slope(uc, side) * sat;
            }
            Spool::First { tau } => {
                let r = (uc - s[0]) / tau;
                if self.under_rate(r, side) {
                    j.a[(0, 0)] = -1.0 / tau;
                    j.b[(0, 0)] = sat / tau;
                }
                j.c[(0, 0)] = self.db_slope(s[0], side);
            }
            Spool::Second { wn2, two_zeta_wn } => {
                let w = s[1];
                let acc = wn2 * (uc - s[0]) - two_zeta_wn * w;
                if self.under_rate(w, side) {
                    j.a[(0, 1)] = 1.0;
                    j.a[(1, 0)] = -wn2;
                    j.a[(1, 1)] = -two_zeta_wn;
                    j.b[(1, 0)] = wn2 * sat;
                } else if acc * w <= 0.0 {
                    // Held at the rate limit, accelerating back inward.
                    j.a[(1, 0)] = -wn2;
                    j.a[(1, 1)] = -two_zeta_wn;
                    j.b[(1, 0)] = wn2 * sat;
                }
                j.c[(0, 0)] = self.db_slope(s[0], side);
            }
        }
        j
    }
    fn kinks(&self, p: &Point) -> Vec<Kink> {
        let mut out = Vec::new();
        if self.limit.is_finite() && (p.u.abs() - self.limit).abs() <= AT_KINK * self.limit {
            out.push(Kink {
                what: format!(
                    "the saturation at its limit (u = {} V, actuator.limit = {} V): slope 1 inside, 0 beyond",
                    p.u, self.limit
                ),
                quantity: "u".into(),
            });
        }
        let s = self.full(p.x);
        let uc = self.act.saturate(p.u);
        let slew = match self.spool {
            Spool::None => None,
            Spool::First { tau } => Some((uc - s[0]) / tau),
            Spool::Second { .. } => Some(s[1]),
        };
        if let Some(r) = slew {
            if self.rate.is_finite() && (r.abs() - self.rate).abs() <= AT_KINK * self.rate {
                out.push(Kink {
                    what: format!(
                        "the spool at its rate limit (slew {r} V/s, actuator.rate_limit = {} V/s)",
                        self.rate
                    ),
                    quantity: "spool".into(),
                });
            }
        }
        if self.dead_band > 0.0 {
            let v = if self.spool == Spool::None { uc } else { s[0] };
            let q = v + self.null_bias;
            if (q.abs() - self.dead_band).abs() <= AT_KINK * self.dead_band {
                out.push(Kink {
                    what: format!(
                        "the dead band's edge (spool + null bias = {q} V, actuator.dead_band = {} V): slope 0 inside, 1 outside",
                        self.dead_band
                    ),
                    quantity: "spool".into(),
                });
            }
        }
        out
    }
    fn notes(&self, p: &Point) -> Vec<String> {
        let mut out = Vec::new();
        if p.u.abs() > self.limit * (1.0 + AT_KINK) {
            out.push(format!(
                "the command {} V is saturated at ±{} V (actuator.limit): the stage's gain is 0",
                p.u, self.limit
            ));
        }
        let s = self.full(p.x);
        let v = if self.spool == Spool::None {
            self.act.saturate(p.u)
        } else {
            s[0]
        };
        if self.dead_band > 0.0 && (v + self.null_bias).abs() < self.dead_band * (1.0 - AT_KINK) {
            out.push(format!(
                "the spool + null bias ({} V) is inside the dead band ±{} V (actuator.dead_band): the stage's gain is 0",
                v + self.null_bias,
                self.dead_band
            ));
        }
        out
    }
}

/// A delay of `n` whole samples of period `h` on one signal (the sensor's
/// `sensor.delay`, the one-sample `simulation.computation_delay`): linear
/// everywhere, `z⁻ⁿ`.
#[derive(Debug, Clone, PartialEq)]
pub struct Delay {
    /// Samples.
    pub n: usize,
    /// The sample period (s).
    pub h: f64,
    /// The signal delayed.
    pub signal: Quantity,
}

impl Linearize for Delay {
    fn dt(&self) -> Option<f64> {
        Some(self.h)
    }
    fn states(&self) -> Vec<Quantity> {
        StateSpace::delay(self.n, self.h, &self.signal).states
    }
    fn input(&self) -> Quantity {
        self.signal.clone()
    }
    fn output(&self) -> Quantity {
        self.signal.clone()
    }
    fn scales(&self) -> Vec<f64> {
        vec![1.0; self.n]
    }
    /// The next state of the shift register and the delayed output.
    fn eval(&self, p: &Point, dx: &mut [f64]) -> f64 {
        if self.n == 0 {
            return p.u;
        }
        for i in (1..self.n).rev() {
            dx[i] = p.x[i - 1];
        }
        dx[0] = p.u;
        p.x[self.n - 1]
    }
    fn jacobian(&self, _p: &Point, _side: Side) -> Jacobian {
        let s = StateSpace::delay(self.n, self.h, &self.signal);
        Jacobian {
            a: s.a,
            b: s.b,
            c: s.c,
            d: s.d,
        }
    }
    fn kinks(&self, _p: &Point) -> Vec<Kink> {
        Vec::new()
    }
}

/// Two continuous stages in series: `first`'s output is `then`'s input;
/// the state is `(x_then, x_first)` (the simulator's order: plant, then
/// actuator).
pub struct Chain<'a> {
    /// The first stage (the actuator).
    pub first: &'a dyn Linearize,
    /// The second (the plant).
    pub then: &'a dyn Linearize,
}

impl Chain<'_> {
    fn split<'x>(&self, x: &'x [f64]) -> (&'x [f64], &'x [f64]) {
        x.split_at(self.then.states().len())
    }

    /// The first stage's output at `p` (the second stage's input).
    fn middle(&self, p: &Point) -> f64 {
        let (_, x1) = self.split(p.x);
        let mut scratch = vec![0.0; x1.len()];
        self.first.eval(
            &Point {
                x: x1,
                u: p.u,
                v: p.v,
            },
            &mut scratch,
        )
    }
}

impl Linearize for Chain<'_> {
    fn states(&self) -> Vec<Quantity> {
        let mut s = self.then.states();
        s.extend(self.first.states());
        s
    }
    fn input(&self) -> Quantity {
        self.first.input()
    }
    fn output(&self) -> Quantity {
        self.then.output()
    }
    fn scales(&self) -> Vec<f64> {
        let mut s = self.then.scales();
        s.extend(self.first.scales());
        s
    }
    fn eval(&self, p: &Point, dx: &mut [f64]) -> f64 {
        let n2 = self.then.states().len();
        let (x2, x1) = self.split(p.x);
        let (d2, d1) = dx.split_at_mut(n2);
        let mid = self.first.eval(
            &Point {
                x: x1,
                u: p.u,
                v: p.v,
            },
            d1,
        );
        self.then.eval(
            &Point {
                x: x2,
                u: mid,
                v: p.v,
            },
            d2,
        )
    }
    fn jacobian(&self, p: &Point, side: Side) -> Jacobian {
        let (x2, x1) = self.split(p.x);
        let mid = self.middle(p);
        let j1 = self.first.jacobian(
            &Point {
                x: x1,
                u: p.u,
                v: p.v,
            },
            side,
        );
        let j2 = self.then.jacobian(
            &Point {
                x: x2,
                u: mid,
                v: p.v,
            },
            side,
        );
        let (n1, n2) = (x1.len(), x2.len());
        let mut j = Jacobian::zeros(n1 + n2);
        j.a.view_mut((0, 0), (n2, n2)).copy_from(&j2.a);
        j.a.view_mut((0, n2), (n2, n1)).copy_from(&(&j2.b * &j1.c));
        j.a.view_mut((n2, n2), (n1, n1)).copy_from(&j1.a);
        j.b.view_mut((0, 0), (n2, 1)).copy_from(&(&j2.b * &j1.d));
        j.b.view_mut((n2, 0), (n1, 1)).copy_from(&j1.b);
        j.c.view_mut((0, 0), (1, n2)).copy_from(&j2.c);
        j.c.view_mut((0, n2), (1, n1)).copy_from(&(&j2.d * &j1.c));
        j.d = &j2.d * &j1.d;
        j
    }
    fn kinks(&self, p: &Point) -> Vec<Kink> {
        let (x2, x1) = self.split(p.x);
        let mid = self.middle(p);
        let mut k = self.first.kinks(&Point {
            x: x1,
            u: p.u,
            v: p.v,
        });
        k.extend(self.then.kinks(&Point {
            x: x2,
            u: mid,
            v: p.v,
        }));
        k
    }
    fn notes(&self, p: &Point) -> Vec<String> {
        let (x2, x1) = self.split(p.x);
        let mid = self.middle(p);
        let mut k = self.first.notes(&Point {
            x: x1,
            u: p.u,
            v: p.v,
        });
        k.extend(self.then.notes(&Point {
            x: x2,
            u: mid,
            v: p.v,
        }));
        k
    }
}

/// The Jacobians of `lin` at `p` by central differences of its `eval`,
/// steps `1e-6·max(|x_j|, scale_j)` (and `1e-6·max(|u|, 1)` for u): the
/// independent check the tests hold the analytic Jacobians to.
pub fn finite_difference(lin: &dyn Linearize, p: &Point) -> Jacobian {
    let n = p.x.len();
    let scales = lin.scales();
    let mut j = Jacobian::zeros(n);
    let mut plus = vec![0.0; n];
    let mut minus = vec![0.0; n];
    let mut x = p.x.to_vec();
    for k in 0..n {
        let h = 1e-6 * x[k].abs().max(scales[k]);
        let x0 = x[k];
        x[k] = x0 + h;
        let yp = lin.eval(&Point { x: &x, ..*p }, &mut plus);
        x[k] = x0 - h;
        let ym = lin.eval(&Point { x: &x, ..*p }, &mut minus);
        x[k] = x0;
        for i in 0..n {
            j.a[(i, k)] = (plus[i] - minus[i]) / (2.0 * h);
        }
        j.c[(0, k)] = (yp - ym) / (2.0 * h);
    }
    let h = 1e-6 * p.u.abs().max(1.0);
    let yp = lin.eval(&Point { u: p.u + h, ..*p }, &mut plus);
    let ym = lin.eval(&Point { u: p.u - h, ..*p }, &mut minus);
    for i in 0..n {
        j.b[(i, 0)] = (plus[i] - minus[i]) / (2.0 * h);
    }
    j.d[(0, 0)] = (yp - ym) / (2.0 * h);
    j
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact slopes (0, 1) are the point of the kink checks
mod tests {
    use super::*;
    use ehservo_core::servo::ServoParams;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Entry by entry, `|analytic − fd| ≤ tol·(|fd| + the row's largest
    /// magnitude·1e-3)`: central differences are accurate to about 1e-8
    /// relative at these steps; the row term absorbs an entry that is a
    /// difference of large terms.
    fn close(an: &DMatrix<f64>, fd: &DMatrix<f64>, what: &str) {
        for i in 0..an.nrows() {
            let row = (0..an.ncols()).fold(0.0f64, |m, j| m.max(fd[(i, j)].abs()));
            for j in 0..an.ncols() {
                let (a, f) = (an[(i, j)], fd[(i, j)]);
                assert!(
                    (a - f).abs() <= 1e-5 * (f.abs() + 1e-3 * row) + 1e-9,
                    "{what}[{i},{j}]: analytic {a:e} vs finite difference {f:e}"
                );
            }
        }
    }

    fn check(lin: &dyn Linearize, p: &Point, what: &str) {
        assert!(lin.kinks(p).is_empty(), "{what}: a kink at {:?}", p.x);
        let an = lin.jacobian(p, Side::Plus);
        let fd = finite_difference(lin, p);
        close(&an.a, &fd.a, &format!("{what} A"));
        close(&an.b, &fd.b, &format!("{what} B"));
        close(&an.c, &fd.c, &format!("{what} C"));
        close(&an.d, &fd.d, &format!("{what} D"));
    }

    fn loads() -> Vec<Load> {
        vec![
            Load::paper(),
            Load::none(),
            Load {
                friction: Some(Friction {
                    coulomb: 0.3,
                    stiction: 0.5,
                    stribeck_velocity: 0.1,
                    viscous: 0.05,
                    smoothing: 0.05,
                }),
                ..Load::paper()
            },
        ]
    }

    /// The friction's curvature against a central difference of its slope.
    #[test]
    fn friction_curvature_is_the_slopes_derivative() {
        let f = Friction {
            coulomb: 0.3,
            stiction: 0.5,
            stribeck_velocity: 0.1,
            viscous: 0.05,
            smoothing: 0.01,
        };
        for v in [-0.3, -0.05, -0.004, 0.0, 0.003, 0.07, 0.4] {
            let h = 1e-7;
            let fd = (f.slope(v + h) - f.slope(v - h)) / (2.0 * h);
            let an = friction_curvature(&f, v);
            assert!(
                (fd - an).abs() < 1e-5 * (1.0 + an.abs()),
                "v = {v}: {fd} vs {an}"
            );
        }
    }

    /// Both plants' analytic Jacobians against central differences of the
    /// simulator's `Plant::deriv`, at random states and commands of both
    /// signs, under a variation, for three loads.
    #[test]
    fn plant_jacobians_match_finite_differences() {
        let mut rng = ChaCha8Rng::seed_from_u64(36);
        let v = Variation {
            da: [0.4, 13000.0, 170.0],
            db_rel: 0.25,
        };
        for load in loads() {
            let third = ThirdOrderPlant::new(ServoParams::paper(), load);
            let phys = PhysicalPlant::new(ServoParams::paper(), load);
            for _ in 0..40 {
                let x = [
                    rng.random_range(-0.5..0.5),
                    rng.random_range(-2.0..2.0),
                    rng.random_range(-50.0..50.0),
                ];
                let u: f64 = rng.random_range(-2.0..2.0);
                let u = if u.abs() < 0.01 { 0.5 } else { u };
                check(&third, &Point { x: &x, u, v }, "third-order");
                let s = phys.initial_state(x, &physical(Variation::NONE));
                check(&phys, &Point { x: &s, u, v }, "physical");
            }
        }
    }

    /// At u = 0 with P_L = 0 the valve's two directions agree: no kink, and
    /// the derivative in u is b at rest (17 911.8·1.25 with δb = 0.25).
    /// With P_L ≠ 0 at u = 0 (θ̈ ≠ 0) the directions differ: a kink, whose
    /// one-sided ∂f3/∂u are (1 + δb)·b(x, ∓1), each the one-sided
    /// difference quotient of `deriv`.
    #[test]
    fn the_valve_sign_is_a_kink_only_under_load_pressure() {
        let v = Variation {
            da: [0.0; 3],
            db_rel: 0.25,
        };
        let p = ThirdOrderPlant::new(ServoParams::paper(), Load::none());
        let x0 = [0.0; 3];
        let at_rest = Point { x: &x0, u: 0.0, v };
        assert!(p.kinks(&at_rest).is_empty());
        let b = p.jacobian(&at_rest, Side::Plus).b[(2, 0)];
        assert!((b - 1.25 * 17911.8).abs() < 0.2, "{b}");
        let x = [0.0, 0.0, 500.0];
        let at = Point { x: &x, u: 0.0, v };
        let k = p.kinks(&at);
        assert_eq!(k.len(), 1, "{k:?}");
        assert_eq!(k[0].quantity, "u_plant");
        let h = 1e-6;
        let mut d0 = [0.0; 3];
        let mut d1 = [0.0; 3];
        p.eval(&at, &mut d0);
        p.eval(&Point { u: h, ..at }, &mut d1);
        let right = (d1[2] - d0[2]) / h;
        p.eval(&Point { u: -h, ..at }, &mut d1);
        let left = (d0[2] - d1[2]) / h;
        let jp = p.jacobian(&at, Side::Plus).b[(2, 0)];
        let jm = p.jacobian(&at, Side::Minus).b[(2, 0)];
        assert!((jp - right).abs() < 1e-6 * right.abs(), "{jp} vs {right}");
        assert!((jm - left).abs() < 1e-6 * left.abs(), "{jm} vs {left}");
        assert!(jm > jp, "P_L > 0 helps the negative direction");
    }

    /// The orifice at ΔP = 0: P_L = Ps exactly, u > 0 — a kink.
    #[test]
    fn the_orifice_at_zero_pressure_drop_is_a_kink() {
        let par = ServoParams::paper();
        let p = PhysicalPlant::new(par, Load::none());
        let s = [0.0, 0.0, par.ps];
        let at = Point {
            x: &s,
            u: 0.3,
            v: Variation::NONE,
        };
        let k = p.kinks(&at);
        assert!(k.iter().any(|k| k.quantity == "p_load"), "{k:?}");
        assert!(!p.jacobian(&at, Side::Plus).is_finite());
    }

    fn stages() -> Vec<(ActuatorConfig, &'static str)> {
        vec![
            (ActuatorConfig::default(), "identity"),
            (
                ActuatorConfig {
                    limit: Some(2.0),
                    time_constant: Some(0.005),
                    ..Default::default()
                },
                "first order",
            ),
            (
                ActuatorConfig {
                    limit: Some(2.0),
                    bandwidth_hz: Some(150.0),
                    order: Some(2),
                    damping: Some(0.7),
                    ..Default::default()
                },
                "second order",
            ),
            (
                ActuatorConfig {
                    limit: Some(2.0),
                    dead_band: Some(0.05),
                    null_bias: Some(0.01),
                    bandwidth_hz: Some(40.0),
                    ..Default::default()
                },
                "first order, dead band",
            ),
            (
                ActuatorConfig {
                    dead_band: Some(0.05),
                    null_bias: Some(-0.02),
                    ..Default::default()
                },
                "static dead band",
            ),
        ]
    }

    /// The actuator stage's Jacobians against central differences of
    /// `Actuator::deriv` and `Actuator::output` (so this stage's spool
    /// parameters are the simulator's), in the linear regime.
    #[test]
    fn actuator_jacobians_match_finite_differences() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for (cfg, what) in stages() {
            let st = ActuatorStage::new(&cfg).unwrap();
            for _ in 0..30 {
                let u = rng.random_range(-1.5..1.5);
                let x: Vec<f64> = match st.n() {
                    0 => vec![],
                    1 => vec![rng.random_range(-1.5..1.5)],
                    _ => vec![rng.random_range(-1.5..1.5), rng.random_range(-50.0..50.0)],
                };
                let p = Point {
                    x: &x,
                    u,
                    v: Variation::NONE,
                };
                if !st.kinks(&p).is_empty() || !st.notes(&p).is_empty() {
                    continue;
                }
                check(&st, &p, what);
            }
        }
    }

    /// Saturated: slope 0 beyond the limit; at the limit a kink whose
    /// one-sided slopes are 1 (inside) and 0 (beyond).
    #[test]
    fn saturation_kink_and_one_sided_slopes() {
        let st = ActuatorStage::new(&ActuatorConfig {
            limit: Some(2.0),
            ..Default::default()
        })
        .unwrap();
        let x: [f64; 0] = [];
        let at = |u| Point {
            x: &x,
            u,
            v: Variation::NONE,
        };
        assert_eq!(st.jacobian(&at(3.0), Side::Plus).d[(0, 0)], 0.0);
        assert!(!st.notes(&at(3.0)).is_empty());
        assert_eq!(st.kinks(&at(2.0)).len(), 1);
        assert_eq!(st.jacobian(&at(2.0), Side::Minus).d[(0, 0)], 1.0);
        assert_eq!(st.jacobian(&at(2.0), Side::Plus).d[(0, 0)], 0.0);
        assert_eq!(st.jacobian(&at(-2.0), Side::Minus).d[(0, 0)], 0.0);
        assert_eq!(st.jacobian(&at(-2.0), Side::Plus).d[(0, 0)], 1.0);
    }

    /// The chain of a second-order valve and the third-order plant against
    /// central differences of the two `eval`s in series.
    #[test]
    fn chain_jacobian_matches_finite_differences() {
        let st = ActuatorStage::new(&stages()[2].0).unwrap();
        let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
        let chain = Chain {
            first: &st,
            then: &plant,
        };
        let x = [0.05, -0.3, 4.0, 0.4, 12.0];
        let v = Variation {
            da: [0.4, 13000.0, 170.0],
            db_rel: 0.25,
        };
        check(&chain, &Point { x: &x, u: 0.7, v }, "chain");
        assert_eq!(chain.states().len(), 5);
        assert_eq!(chain.states()[3].name, "spool");
    }

    /// The spool's replay is the simulator's spool: a step of 1 V through
    /// τ = 5 ms for 0.01 s is 1 − e^{−2} = 0.8646647 (RK4, 10 sub-steps of
    /// 1 ms, is that to about 1e-6).
    #[test]
    fn spool_replay_by_hand() {
        let st = ActuatorStage::new(&ActuatorConfig {
            time_constant: Some(0.005),
            ..Default::default()
        })
        .unwrap();
        let s = st.replay(&[1.0], 0.01, 10);
        assert!((s[0] - (1.0 - (-2.0f64).exp())).abs() < 1e-5, "{}", s[0]);
    }

    /// Trim inversion through a dead band 0.05 V and null bias 0.01 V: the
    /// plant input 0.1 V needs the spool at 0.1 + 0.05 − 0.01 = 0.14 V; 0.2 V
    /// needs 0.24 V, beyond the 0.2 V saturation.
    #[test]
    fn actuator_inversion_by_hand() {
        let st = ActuatorStage::new(&ActuatorConfig {
            limit: Some(0.2),
            dead_band: Some(0.05),
            null_bias: Some(0.01),
            ..Default::default()
        })
        .unwrap();
        let (_, u) = st.invert(0.1).unwrap();
        assert!((u - 0.14).abs() < 1e-15);
        assert_eq!(st.invert(0.2).unwrap_err().0, "actuator.limit");
    }
}
