//! The plants' analytic Jacobians: the third-order model (8)–(9) and the
//! physical model (1)–(6), with the load's and the friction's slopes and
//! the valve's kinks (the sign of `xv`, the orifice at a zero pressure
//! drop) and notes (the root clamped).

use super::{direction, Jacobian, Kink, Linearize, PlantState, Point, Side, AT_KINK, SAME_SLOPE};
use crate::freq::ss::Quantity;
use crate::physical::PhysicalVariation;
use crate::plant::{PhysicalPlant, Plant, ThirdOrderPlant, Variation};
use crate::simulation::Sample;
use ehservo_core::servo::{Friction, Load, NominalModel};
use ehservo_sim::uncertainty::Factors;

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
pub(super) fn physical(v: Variation) -> PhysicalVariation {
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
