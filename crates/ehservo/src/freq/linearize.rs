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
//! A new plant implements [`Linearize`] and [`PlantState`] (the cylinder
//! does, in `cylinder`); nothing else here knows a plant.
//!
//! Here: the trait, its points, kinks and sides, the delay, the chain of
//! two stages and the finite-difference check; the paper's plants in
//! `plants`, the cylinder in `cylinder`, the actuator stage in
//! `actuator_stage`.

mod actuator_stage;
mod cylinder;
mod ifac9007;
mod plants;

pub use actuator_stage::ActuatorStage;
pub use cylinder::CylinderLin;
pub use plants::friction_curvature;

use super::ss::{Quantity, StateSpace};
use crate::plant::Variation;
use crate::simulation::Sample;
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
    pub(crate) fn sign(&self) -> f64 {
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
    use super::plants::physical;
    use super::*;
    use crate::actuator::ActuatorConfig;
    use crate::plant::{PhysicalPlant, Plant, ThirdOrderPlant};
    use ehservo_core::servo::{Friction, Load, ServoParams};
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
            let st = ActuatorStage::of_config(&cfg).unwrap();
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
        let st = ActuatorStage::of_config(&ActuatorConfig {
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
        let st = ActuatorStage::of_config(&stages()[2].0).unwrap();
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
        let st = ActuatorStage::of_config(&ActuatorConfig {
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
        let st = ActuatorStage::of_config(&ActuatorConfig {
            limit: Some(0.2),
            dead_band: Some(0.05),
            null_bias: Some(0.01),
            ..Default::default()
        })
        .unwrap();
        let (_, u) = st.invert(0.1).unwrap();
        assert!((u - 0.14).abs() < 1e-15);
        assert_eq!(st.invert(0.2).unwrap_err().key, "actuator.limit");
    }
}
