//! The linear loop about an operating point and its frequency responses.
//!
//! ```text
//!                 d (at the controller's output, held)
//!  θd ──▶ C_r ──▶(+)──▶ z^{−n_c} ──▶ G_d ──▶ θ ──▶ z^{−n_s} ──▶ θm
//!           └──────────(−)── C ◀──────────────────────────────┘
//! ```
//!
//! - **G**: the plant with its actuator, linearised ([`super::linearize`]),
//!   continuous, from the command u (V) to θ (rad);
//! - **G_d**: G discretised at the sample period: exactly under a
//!   zero-order hold (`e^{A·h}`, the default), or the map of the
//!   simulator's own RK4 sub-steps (`--discretise rk4`);
//! - **C**: the feedback path of a linear controller, `−∂u/∂θm`
//!   (negative-feedback convention), and **C_r** its reference path:
//!   `Σ_i D_i(z)·(jω)^i` over the reference's derivatives
//!   `z = (θd, θ̇d, θ̈d, θ⃛d)` the law reads (known exactly, not filtered);
//! - `z^{−n_s}` the sensor's delay of `sensor.delay` samples and `z^{−n_c}`
//!   the one-sample `simulation.computation_delay`;
//! - **L** `= C·z^{−n_s}·G_d·z^{−n_c}`, **S** `= 1/(1 + L)`,
//!   **T** `= L/(1 + L)`, the **tracking** response
//!   `θ/θd = z^{−n_c}·G_d·C_r/(1 + L)` and the response to a **disturbance**
//!   d added to the command, `θ/d = z^{−n_c}·G_d/(1 + L)`.
//!
//! Discrete responses are evaluated on the unit circle, `z = e^{jωh}`. In
//! the continuous mode (the law inside every RK4 stage, no delays) the loop
//! is `C(s)·G(s)` at `s = jω`, the controller's law itself.

use super::controllers::{controller_model, observer_model, ControllerModel};

#[path = "response_parts.rs"]
mod parts;
use super::linearize::{ActuatorStage, Chain, Delay, Kink, Linearize, Point, Side};
use super::oppoint::{LinPlant, OperatingPoint};
use super::ss::{Quantity, StateSpace, C64};
use crate::axis::Axis;
use crate::scenario::{KeyError, Loop};
use crate::simulation::Mode;
use ehservo_sim::estimator::AnyEstimator;
use parts::{compensated_gain, discretise, measured_path, open_loop, Delays};

/// How the plant is discretised in the sampled loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Discretisation {
    /// Exactly, under a zero-order hold (the matrix exponential).
    Zoh,
    /// The map of the simulator's RK4 sub-steps over one sample.
    Rk4,
}

impl Discretisation {
    /// The command-line spelling.
    pub fn as_str(&self) -> &'static str {
        match self {
            Discretisation::Zoh => "zoh",
            Discretisation::Rk4 => "rk4",
        }
    }
}

/// The loop's linear models at an operating point.
#[derive(Debug, Clone)]
pub struct LoopModel {
    /// The loop's mode.
    pub mode: Mode,
    /// The sample period (s).
    pub h: f64,
    /// How G was discretised.
    pub discretisation: Discretisation,
    /// The plant alone, continuous, from its input u_plant to θ.
    pub plant: StateSpace,
    /// The actuator alone, continuous, from u to u_plant.
    pub actuator: StateSpace,
    /// G: actuator and plant, continuous, from u to θ.
    pub g: StateSpace,
    /// G_d: G discretised (sampled mode).
    pub g_d: Option<StateSpace>,
    /// Samples of the sensor's delay.
    pub sensor_delay: usize,
    /// Samples of the computation delay (0 or 1).
    pub computation_delay: usize,
    /// The linear controller's models, if the kind is linear.
    pub controller: Option<ControllerModel>,
    /// Its model in the loop's time base (inputs θm, z; output u).
    pub controller_loop: Option<StateSpace>,
    /// C = −u/θm in the loop's time base; a law that reads the measured
    /// (θm, θ̇m, θ̈m) has the row `−∂u/∂(θm, θ̇m, θ̈m)` (the state feedback).
    pub feedback: Option<StateSpace>,
    /// The measured channels' path when the law reads (θm, θ̇m, θ̈m): G
    /// with the outputs (θ, θ̇, θ̈), in the loop's time base (G_d's with
    /// them, sampled). None for a law that reads θm alone.
    pub measured: Option<StateSpace>,
    /// L as one model (SISO: θm's error in, θm out): C ∘ z^{−n_s} ∘ G_d ∘ z^{−n_c}.
    pub loop_l: Option<StateSpace>,
    /// The observer of `[estimator]`, when it is linear (Luenberger, Kalman).
    pub observer: Option<StateSpace>,
    /// Where the point is not differentiable (then the model is one-sided).
    pub kinks: Vec<Kink>,
    /// Regimes with a zero gain at the point.
    pub notes: Vec<String>,
}

/// The values of every curve at one frequency.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Responses {
    /// Frequency (rad/s).
    pub omega: f64,
    /// G (continuous plant with actuator), rad/V.
    pub g: Option<C64>,
    /// G_d with the delays z^{−n_s − n_c}, rad/V (sampled mode).
    pub g_d: Option<C64>,
    /// C, V/rad.
    pub c: Option<C64>,
    /// L.
    pub l: Option<C64>,
    /// S.
    pub s: Option<C64>,
    /// T.
    pub t: Option<C64>,
    /// θ/θd.
    pub track: Option<C64>,
    /// θ/d, rad/V.
    pub dist: Option<C64>,
}

/// The names of the curves, their units and what they are (for the CSV
/// and the docs), on a rotary axis.
pub const CURVES: [(&str, &str, &str); 8] = [
    ("G", "rad/V", "plant with actuator, continuous"),
    (
        "Gd",
        "rad/V",
        "plant discretised, with the delays z^-(ns+nc)",
    ),
    ("C", "V/rad", "controller's feedback path −u/θm"),
    ("L", "", "loop C·Gd"),
    ("S", "", "sensitivity 1/(1 + L)"),
    ("T", "", "complementary sensitivity L/(1 + L)"),
    ("track", "", "tracking response θ/θd"),
    (
        "dist",
        "rad/V",
        "response θ/d to a disturbance d on the command",
    ),
];

/// [`CURVES`] on `axis`: on a linear one the position is y in m (`m/V`,
/// `V/m`, y/yd, y/d); a rotary axis's are [`CURVES`] as they are.
pub fn curves(axis: Axis) -> Vec<(&'static str, String, String)> {
    CURVES
        .iter()
        .map(|(n, u, d)| match axis {
            Axis::Rotary => (*n, u.to_string(), d.to_string()),
            _ => (*n, axis.si_name(u), d.replace('θ', axis.letter())),
        })
        .collect()
}

impl Responses {
    /// The curves in the order of [`CURVES`].
    pub fn all(&self) -> [Option<C64>; 8] {
        [
            self.g, self.g_d, self.c, self.l, self.s, self.t, self.track, self.dist,
        ]
    }
}

/// Notes on the stages the linear model leaves out or takes as the
/// identity: a quantising sensor, sensor noise, Levant's differentiator.
fn unmodelled_notes(setup: &Loop) -> Vec<String> {
    let mut notes = Vec::new();
    let sc = setup.stages().sensor.config();
    if sc.resolution.iter().any(|&r| r > 0.0) {
        notes.push(
            "sensor.resolution: the quantiser is taken as the identity (its slope is 0 between steps and undefined at them; 1 on average)"
                .into(),
        );
    }
    if sc.noise.iter().any(|&v| v > 0.0) {
        notes.push("sensor.noise: left out of the linear model".into());
    }
    if matches!(setup.stages().estimator, Some(AnyEstimator::Levant(_))) {
        notes.push(
            "estimator: Levant's differentiator is nonlinear and not linearised; PID and ADRC read θ only, so it is outside their loop"
                .into(),
        );
    }
    notes
}

/// The linear controller's models, as [`LoopModel`] holds them (each None for a
/// nonlinear kind).
struct ControllerModels {
    controller: Option<ControllerModel>,
    controller_loop: Option<StateSpace>,
    feedback: Option<StateSpace>,
}

/// The linear controller's models: as built, in the loop's time base, and
/// as the feedback C = −u/θm.
fn controller_models(
    setup: &Loop,
    sampled: bool,
    at: (&OperatingPoint, Side),
    notes: &mut Vec<String>,
) -> Result<ControllerModels, KeyError> {
    let h = setup.sim().step;
    let controller = match controller_model(setup.controller(), setup.design()) {
        None => None,
        Some(r) => Some(r.map_err(|e| {
            KeyError::new(
                format!("controller.{}", e.name),
                format!("{} (got {:?})", e.reason, e.value),
            )
        })?),
    };
    let controller = controller.map(|c| match c.compensated_b0 {
        Some(b0) => {
            let b = compensated_gain(setup, at.0, at.1);
            notes.push(format!(
                "controller.compensate: the law divides by the valve's gain at the measured state, b(x, sgn v); linearised at the point on the {} side, by b = {b:.6e} (b̄0 = {b0:.6e} at rest)",
                at.1.as_str()
            ));
            c.divided_by(b)
        }
        None => c,
    });
    let controller_loop = controller
        .as_ref()
        .map(|c| c.for_mode(sampled.then_some(h)));
    let feedback = controller
        .as_ref()
        .zip(controller_loop.as_ref())
        .map(|(m, c)| {
            c.inputs_from(0, m.measured)
                .scaled_output(-1.0, vec![Quantity::new("minus_u", "V")])
        });
    Ok(ControllerModels {
        controller,
        controller_loop,
        feedback,
    })
}

impl LoopModel {
    /// The loop of `setup` at the operating point `op`, on `side` at a kink.
    pub fn new(
        setup: &Loop,
        plant: &LinPlant,
        actuator: &ActuatorStage,
        op: &OperatingPoint,
        side: Side,
        discretisation: Discretisation,
    ) -> Result<LoopModel, KeyError> {
        let h = setup.sim().step;
        let v = op.variation();
        let chain = Chain {
            first: actuator,
            then: plant.lin(),
        };
        let x = op.chain_state();
        let p = Point { x: &x, u: op.u, v };
        let kinks = chain.kinks(&p);
        let mut notes = chain.notes(&p);
        notes.extend(unmodelled_notes(setup));
        let g = chain.model(&p, side);
        let pp = Point {
            x: &op.plant_state,
            u: op.u_plant,
            v,
        };
        let plant_m = plant.lin().model(&pp, side);
        let act_m = actuator.model(
            &Point {
                x: &op.actuator_state,
                u: op.u,
                v,
            },
            side,
        );
        if !g.is_finite() {
            return Err(KeyError::new(
                "--side",
                format!(
                    "the {} one-sided model is not finite there ({})",
                    side.as_str(),
                    kinks
                        .iter()
                        .map(|k| k.what.clone())
                        .collect::<Vec<_>>()
                        .join("; ")
                ),
            ));
        }
        let sampled = setup.sim().mode == Mode::Sampled;
        let g_d = if sampled {
            Some(discretise(&g, discretisation, setup)?)
        } else {
            None
        };
        let sensor_delay = if sampled {
            setup.stages().sensor.config().delay as usize
        } else {
            0
        };
        let computation_delay = usize::from(sampled && setup.sim().computation_delay);
        let ControllerModels {
            controller,
            controller_loop,
            feedback,
        } = controller_models(setup, sampled, (op, side), &mut notes)?;
        let delays = Delays {
            h,
            sensor: sensor_delay,
            computation: computation_delay,
        };
        let measured = measured_path(setup, &g, controller.as_ref(), &mut notes);
        // A law that reads three channels with no model of them has no loop
        // (the note says why): drop it before L is composed.
        let (controller, controller_loop, feedback) =
            if measured.is_none() && controller.as_ref().is_some_and(|c| c.measured > 1) {
                (None, None, None)
            } else {
                (controller, controller_loop, feedback)
            };
        let measured_d = match (&measured, sampled) {
            (Some(g3), true) => Some(discretise(g3, discretisation, setup)?),
            _ => None,
        };
        let loop_l = match &measured {
            Some(g3) => open_loop(g3, measured_d.as_ref(), feedback.as_ref(), &delays)?,
            None => open_loop(&g, g_d.as_ref(), feedback.as_ref(), &delays)?,
        };
        let measured = if sampled { measured_d } else { measured };
        let observer = match &setup.stages().estimator {
            Some(AnyEstimator::Linear(o)) if sampled => Some(observer_model(o, h)),
            _ => None,
        };
        let mut lm = LoopModel {
            mode: setup.sim().mode,
            h,
            discretisation,
            plant: plant_m,
            actuator: act_m,
            g,
            g_d,
            sensor_delay,
            computation_delay,
            controller,
            controller_loop,
            feedback,
            measured,
            loop_l,
            observer,
            kinks,
            notes,
        };
        lm.name_for_axis(setup.axis());
        Ok(lm)
    }

    /// On a linear axis every signal named for the angle is the rod's
    /// position: `theta…` becomes `y…` and `rad` becomes `m` in names and
    /// units (the laws are the same equations in m); nothing changes on a
    /// rotary axis.
    fn name_for_axis(&mut self, axis: Axis) {
        if axis == Axis::Rotary {
            return;
        }
        let models = [
            Some(&mut self.plant),
            Some(&mut self.actuator),
            Some(&mut self.g),
            self.g_d.as_mut(),
            self.controller_loop.as_mut(),
            self.feedback.as_mut(),
            self.measured.as_mut(),
            self.loop_l.as_mut(),
            self.observer.as_mut(),
        ];
        for m in models.into_iter().flatten() {
            rename_for_axis(m, axis);
        }
        if let Some(c) = self.controller.as_mut() {
            rename_for_axis(&mut c.law, axis);
            for (_, m) in c.parts.iter_mut() {
                rename_for_axis(m, axis);
            }
        }
    }

    /// Whether the loop is discrete.
    pub fn sampled(&self) -> bool {
        self.mode == Mode::Sampled
    }

    /// The highest frequency the loop's responses are defined to (rad/s):
    /// just below Nyquist, π/h, in sampled mode; π/h too in the continuous
    /// mode (the simulator's RK4 step resolves nothing faster).
    pub fn nyquist(&self) -> f64 {
        std::f64::consts::PI / self.h
    }

    /// The plant's path at ω (rad/s) — G_d after the computation's delay
    /// in sampled mode, G in continuous time — and the sensor's delay.
    fn plant_path(&self, w: f64) -> (Option<C64>, C64) {
        let zd = |n: usize| C64::from_polar(1.0, -(n as f64) * w * self.h);
        match &self.g_d {
            Some(gd) => (
                gd.response(w).map(|v| v * zd(self.computation_delay)),
                zd(self.sensor_delay),
            ),
            None => (self.g.response(w), C64::new(1.0, 0.0)),
        }
    }

    /// L at ω (rad/s) alone, as [`at`](Self::at) gives it (None without a
    /// linear controller): what the margins need, without the other curves.
    pub fn loop_at(&self, w: f64) -> Option<C64> {
        let f = self.feedback.as_ref()?;
        let Some(g3) = &self.measured else {
            let (p, delay) = self.plant_path(w);
            return Some(f.response(w)? * p? * delay);
        };
        // The row −∂u/∂(θm, θ̇m, θ̈m) times the column of the measured
        // channels, delayed alike by z^{−(n_s + n_c)}.
        let n = self.sensor_delay + self.computation_delay;
        let z = C64::from_polar(1.0, -(n as f64) * w * self.h);
        let l = (f.at(f.point(w))? * g3.at(g3.point(w))?)[(0, 0)];
        Some(if self.sampled() { l * z } else { l })
    }

    /// Every curve at ω (rad/s).
    pub fn at(&self, w: f64) -> Responses {
        let g = self.g.response(w);
        let (plant_path, loop_delay) = self.plant_path(w);
        let g_d = self.g_d.as_ref().and(plant_path.map(|p| p * loop_delay));
        let (c, l) = match &self.measured {
            None => {
                let c = self.feedback.as_ref().and_then(|f| f.response(w));
                let l = match (c, plant_path) {
                    (Some(c), Some(p)) => Some(c * p * loop_delay),
                    _ => None,
                };
                (c, l)
            }
            // A law that reads θ̇m and θ̈m too: C is the equivalent
            // feedback on θm alone, L over the position's path.
            Some(_) => {
                let l = self.loop_at(w);
                let c = l.zip(plant_path).map(|(l, p)| l / (p * loop_delay));
                (c, l)
            }
        };
        let s = l.map(|l| 1.0 / (1.0 + l));
        let t = l.map(|l| l / (1.0 + l));
        let first_z = self.controller.as_ref().map_or(1, |c| c.measured);
        let cr = self.controller_loop.as_ref().and_then(|k| {
            let jw = C64::new(0.0, w);
            let mut sum = C64::new(0.0, 0.0);
            let mut pow = C64::new(1.0, 0.0);
            for i in 0..4 {
                sum += k.siso(0, first_z + i).response(w)? * pow;
                pow *= jw;
            }
            Some(sum)
        });
        let track = match (cr, plant_path, s) {
            (Some(cr), Some(p), Some(s)) => Some(p * cr * s),
            _ => None,
        };
        let dist = match (plant_path, s) {
            (Some(p), Some(s)) => Some(p * s),
            _ => None,
        };
        Responses {
            omega: w,
            g,
            g_d,
            c,
            l,
            s,
            t,
            track,
            dist,
        }
    }

    /// The closed loop's poles, from L's model under unity negative
    /// feedback: `A − B·C/(1 + D)`.
    pub fn closed_loop_poles(&self) -> Option<Vec<C64>> {
        super::ss::eigenvalues(&self.closed_loop_a()?)
    }

    /// The closed loop's A, `A − B·C/(1 + D)` of L's model (None without
    /// a linear controller, or with 1 + D = 0).
    fn closed_loop_a(&self) -> Option<nalgebra::DMatrix<f64>> {
        let l = self.loop_l.as_ref()?;
        let d = 1.0 + l.d[(0, 0)];
        if d == 0.0 {
            return None;
        }
        Some(&l.a - &l.b * &l.c / d)
    }

    /// Whether the closed loop is stable as a map from its inputs to its
    /// outputs: every pole inside the unit circle (or in the open left
    /// half-plane), except a pole on the boundary that the loop neither
    /// excites nor sees ([`hidden_modes`](Self::hidden_modes)), which
    /// only holds a constant. Such modes are the rule on a cylinder at rest:
    /// the chamber pressures' common mode (any pair that holds the load is
    /// an equilibrium) and a PID's unused integrator (ki = 0) are poles at
    /// z = 1 that the command cannot move or the position cannot see.
    pub fn closed_loop_stable(&self) -> Option<bool> {
        let p = self.closed_loop_poles()?;
        let hidden = self.hidden_modes()?;
        Some(p.iter().all(|&z| self.inside(z) || hidden.contains(&z)))
    }

    /// Whether `z` is strictly inside the stability region.
    fn inside(&self, z: C64) -> bool {
        if self.sampled() {
            z.norm() < 1.0
        } else {
            z.re < 0.0
        }
    }

    /// The closed loop's poles on the stability boundary (|z| = 1, or
    /// re s = 0, to 1e-9) that are uncontrollable from L's input or
    /// unobservable from its output, by the Popov–Belevitch–Hautus test:
    /// rank [λI − A; C] < n or rank [λI − A, B] < n, judged by the least
    /// singular value against 1e-9·(1 + ‖A‖). Feedback A − B·C/(1 + D)
    /// changes neither rank. A pole outside the boundary is never hidden
    /// here: it is reported unstable whatever it couples to.
    pub fn hidden_modes(&self) -> Option<Vec<C64>> {
        let l = self.loop_l.as_ref()?;
        let a = self.closed_loop_a()?;
        let n = a.nrows();
        let scale = 1.0 + a.norm();
        let tol = 1e-9 * scale;
        let on_boundary = |z: C64| {
            if self.sampled() {
                (z.norm() - 1.0).abs() <= 1e-9
            } else {
                z.re.abs() <= tol
            }
        };
        let cx = |m: &nalgebra::DMatrix<f64>| m.map(|v| C64::new(v, 0.0));
        let least_sv = |m: nalgebra::DMatrix<C64>| {
            m.svd(false, false)
                .singular_values
                .iter()
                .fold(f64::INFINITY, |acc, &v| acc.min(v))
        };
        let mut hidden = Vec::new();
        for z in self.closed_loop_poles()? {
            if !on_boundary(z) {
                continue;
            }
            let shifted = nalgebra::DMatrix::<C64>::identity(n, n) * z - cx(&a);
            // [λI − A; C] (n + p) × n, and [λI − A, B] n × (n + m): the
            // transpose of the latter has the same singular values.
            let obs = concat_rows(&shifted, &cx(&l.c));
            let ctr = concat_rows(&shifted.transpose(), &cx(&l.b).transpose());
            if least_sv(obs) <= tol || least_sv(ctr) <= tol {
                hidden.push(z);
            }
        }
        Some(hidden)
    }

    /// The lowest frequency worth searching for crossings (rad/s): a
    /// hundredth of the slowest nonzero pole or zero of L (or of G), at
    /// least 1e-9.
    pub fn lowest(&self) -> f64 {
        self.search_band().0
    }

    /// [`lowest`](Self::lowest) and the [`super::margins::resonance_points`] of
    /// L's (or G's) poles and zeros: where the margins' grid must be dense.
    pub fn search_band(&self) -> (f64, Vec<f64>) {
        let m = self.loop_l.as_ref().unwrap_or(&self.g);
        let to_s = |z: C64| match m.dt {
            Some(h) if z.norm() > 0.0 => (z.ln() / h).norm(),
            Some(_) => f64::INFINITY,
            None => z.norm(),
        };
        let mut all = m.poles().unwrap_or_default();
        all.extend(m.zeros().unwrap_or_default());
        let slow = all
            .iter()
            .map(|&z| to_s(z))
            .filter(|w| *w > 1e-12 && w.is_finite())
            .fold(f64::INFINITY, f64::min);
        let lo = if slow.is_finite() {
            (slow / 100.0).max(1e-9)
        } else {
            1e-3
        };
        (lo, super::margins::resonance_points(&all, m.dt))
    }
}

/// `top` over `bottom` (same column count).
fn concat_rows(
    top: &nalgebra::DMatrix<C64>,
    bottom: &nalgebra::DMatrix<C64>,
) -> nalgebra::DMatrix<C64> {
    let (r1, c) = top.shape();
    let r2 = bottom.nrows();
    let mut m = nalgebra::DMatrix::<C64>::zeros(r1 + r2, c);
    m.view_mut((0, 0), (r1, c)).copy_from(top);
    m.view_mut((r1, 0), (r2, c)).copy_from(bottom);
    m
}

/// A quantity of the angle renamed for `axis` ([`LoopModel`]'s
/// `name_for_axis`): `theta_m` in rad is `y_m` in m on a linear axis.
pub fn quantity_for_axis(q: &Quantity, axis: Axis) -> Quantity {
    if axis == Axis::Rotary {
        return q.clone();
    }
    let name = match q.name.strip_prefix("theta") {
        Some(rest) => format!("{}{rest}", axis.symbol()),
        None => q.name.clone(),
    };
    Quantity {
        name: axis.si_name(&name),
        unit: axis.si_name(&q.unit),
    }
}

fn rename_for_axis(m: &mut StateSpace, axis: Axis) {
    for q in m
        .states
        .iter_mut()
        .chain(m.inputs.iter_mut())
        .chain(m.outputs.iter_mut())
    {
        *q = quantity_for_axis(q, axis);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::freq::oppoint;
    fn setup(toml: &str) -> Loop {
        Loop::parse(toml).unwrap()
    }

    fn loop_of(toml: &str, d: Discretisation) -> LoopModel {
        let s = setup(toml);
        let plant = LinPlant::of(&s).unwrap();
        let act = ActuatorStage::new(&s.stages().actuator);
        let op = oppoint::trim(&s, &plant, &act, 0.0, 0.0, Side::Plus).unwrap();
        LoopModel::new(&s, &plant, &act, &op, Side::Plus, d).unwrap()
    }

    /// PID on the nominal third-order plant at rest, by hand: G(s) =
    /// b0/(s³ + a3's² + a2's + a1') with b0 = b̄ at rest (no variation, no
    /// load pressure at θ = 0) and the load 2·sin 4θ linearised into the
    /// coefficients: Tl ≈ A·k·θ adds 4βe·Kce/(Vt·Jt)·A·k to a1 (through d)
    /// and A·k/Jt to a2 (through Ṫl/Jt). L at s = jω in the continuous mode
    /// is C(jω)·G(jω) with C = kp + ki/s + kd·s/(1 + Tf·s).
    #[test]
    fn continuous_loop_by_hand() {
        let toml = "[simulation]\nmode = \"continuous\"\nstep = 0.001\n[controller]\nkind = \"pid\"\n[uncertainty]\na_bias = 0.0\nb_bias = 0.0\n";
        let lp = loop_of(toml, Discretisation::Zoh);
        let s = setup(toml);
        let m = &s.design().model;
        let a = m.coeffs;
        let ak = 2.0 * 4.0;
        let (a1, a2, a3) = (
            a.a1 + m.params.d_per_torque() * ak,
            a.a2 + ak / m.params.jt,
            a.a3,
        );
        let b0 = m.b_at_rest();
        let pid = s
            .controller()
            .get::<ehservo_core::control::pid::PidConfig>()
            .unwrap();
        let built = ehservo_core::control::Config::build(pid, s.design()).unwrap();
        let (kp, ki, kd) = built.gains();
        let (tf, _) = built.times();
        for w in [0.3, 5.0, 60.0, 800.0] {
            let sj = C64::new(0.0, w);
            let gg = b0 / (sj * sj * sj + a3 * sj * sj + a2 * sj + a1);
            let c = kp + ki / sj + kd * sj / (1.0 + tf * sj);
            let r = lp.at(w);
            assert!((r.g.unwrap() - gg).norm() < 1e-9 * gg.norm(), "G at {w}");
            assert!(
                (r.l.unwrap() - c * gg).norm() < 1e-9 * (c * gg).norm(),
                "L at {w}"
            );
            let t = c * gg / (1.0 + c * gg);
            assert!((r.t.unwrap() - t).norm() < 1e-9 * t.norm().max(1e-3));
        }
        // The designed closed loop is stable.
        assert_eq!(lp.closed_loop_stable(), Some(true));
    }

    /// The PBH test keeps an unstable verdict unstable and hides only what
    /// L cannot touch. A P law (ki = kd = 0) of kp = 1000 V/rad on the
    /// paper's servo at 1 ms: Routh on s³ + ā3s² + ā2s + ā1 + b̄0·kp gives
    /// the limit kp < (ā3ā2 − ā1)/b̄0 = (169.98·13000.27 − 0.4)/17911.75
    /// = 123.4 V/rad, so the loop is unstable; the PID's integrator, unused
    /// at ki = 0, is a pole at z = 1 that the output does not see: hidden,
    /// and the one mode that is.
    #[test]
    fn an_unstable_loop_stays_unstable_and_an_unused_integrator_is_hidden() {
        let toml = "[simulation]\nstep = 0.001\n[controller]\nkind = \"pid\"\nkp = 1000.0\nki = 0.0\nkd = 0.0\n";
        let lp = loop_of(toml, Discretisation::Zoh);
        assert_eq!(lp.closed_loop_stable(), Some(false));
        let hidden = lp.hidden_modes().unwrap();
        assert_eq!(hidden.len(), 1, "{hidden:?}");
        assert!((hidden[0] - C64::new(1.0, 0.0)).norm() < 1e-9);
        // The same law at kp = 10 (below the limit) is stable, the
        // integrator again hidden.
        let lp = loop_of(&toml.replace("1000.0", "10.0"), Discretisation::Zoh);
        assert_eq!(lp.closed_loop_stable(), Some(true));
        assert_eq!(lp.hidden_modes().unwrap().len(), 1);
    }

    /// The discrete loop with delays: L = C(z)·G_d(z)·z^{−(n_s + n_c)}, the
    /// product of the separately computed pieces, and L's one model gives
    /// the same values.
    #[test]
    fn sampled_loop_with_delays() {
        let toml = "[simulation]\nstep = 0.001\ncomputation_delay = true\n[sensor]\ndelay = 3\n[controller]\nkind = \"pid\"\n[actuator]\nbandwidth_hz = 150.0\norder = 2\n";
        let lp = loop_of(toml, Discretisation::Zoh);
        assert_eq!((lp.sensor_delay, lp.computation_delay), (3, 1));
        for w in [1.0, 30.0, 700.0, 3000.0] {
            let r = lp.at(w);
            let gd = lp.g_d.as_ref().unwrap().response(w).unwrap();
            let c = lp.feedback.as_ref().unwrap().response(w).unwrap();
            let want = c * gd * C64::from_polar(1.0, -4.0 * w * 0.001);
            let l = r.l.unwrap();
            assert!(
                (l - want).norm() < 1e-12 * want.norm(),
                "{w}: {l} vs {want}"
            );
            let one = lp.loop_l.as_ref().unwrap().response(w).unwrap();
            // One 9-state solve beside the product of three small ones:
            // near Nyquist the larger system loses a few more digits.
            assert!(
                (one - want).norm() < 1e-7 * want.norm(),
                "{w}: {one} vs {want}"
            );
        }
    }
}
