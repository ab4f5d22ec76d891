//! Operating points: a trim point for a constant reference (the plant at
//! rest at θ0, found by Newton's method on its equations), or the state of
//! a scenario's run at a time along it.
//!
//! **Trim.** For the plant `ẋ = f(x, p)`, `θ = g(x)`, the unknowns are the
//! state `x` and the plant's input `p`; the equations `f(x, p) = 0` and
//! `g(x) = θ0` (n + 1 of each). Newton's method from `(θ0, 0, …, 0; 0)`
//! with the analytic Jacobian `[[A, B], [C, D]]` in the states' scaled
//! units, halving a step until the scaled residual falls (at most
//! [`TRIM_MAX_ITERATIONS`] iterations of at most [`TRIM_MAX_HALVINGS`]
//! halvings). A residual `F_i` has vanished when
//! `|F_i| ≤ 1e-10·Σ_j |J_ij|·s_j` (the sizes of the terms it is made of,
//! `s_j` the unknowns' scales); otherwise the trim does not exist and the
//! error names the residual. The actuator is then inverted in closed form
//! ([`ActuatorStage::invert`]): the spool at rest where the dead band and
//! null bias give `p`, within the saturation. The parameter variation at a
//! trim point is its bias (the random part at its mean, zero).
//!
//! **Along a run** (`--at T`): the scenario's own simulation to the sample
//! nearest `T` (`Simulation::log_states` on), the plant's state read from
//! that sample ([`PlantState`]), the spool's from a replay of the applied
//! commands ([`ActuatorStage::replay`]; exact in sampled mode, where the
//! commands are held), the command applied over the next period, and the
//! variation the simulator draws for that period. Such a point is no
//! equilibrium: its `drift` ẋ is reported.

use super::linearize::{ActuatorStage, CylinderLin, Linearize, PlantState, Point, Side};
use crate::axis::Axis;
use crate::plant::{PhysicalPlant, Plant, ThirdOrderPlant, UncertaintySignal, Variation};
use crate::scenario::{self, ControllerConfig, KeyError, Loop, LoopPlant, LoopVisit, Typed};
use crate::simulation::{Mode, Simulation, Stop};
use crate::third_order::varied;
use crate::uncertainty::{Draw, Factors};
use ehservo_core::math::DR;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Newton iterations a trim may take.
pub const TRIM_MAX_ITERATIONS: usize = 100;

/// Step halvings per Newton iteration.
pub const TRIM_MAX_HALVINGS: usize = 40;

/// Where to linearise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum At {
    /// A trim point for the constant reference at this position (the
    /// axis's SI unit: rad or m), at rest.
    Trim(f64),
    /// A trim point in steady motion: the position and the speed (the
    /// axis's SI units); the cylinder's only.
    Moving(f64, f64),
    /// The run's state at time t (s).
    Time(f64),
}

/// A plant of the scenario that can be linearised, with its true
/// parameters at the operating point (a physical bias or draw folded in:
/// the physical factors vary the parameters, the paper's Δa_i/δb stay in
/// [`Point::v`]).
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)]
pub enum LinPlant {
    /// `plant.model = "third-order"`.
    Third(ThirdOrderPlant),
    /// `plant.model = "physical"`.
    Physical(PhysicalPlant),
    /// `plant.model = "cylinder"`.
    Cylinder(Box<CylinderLin>),
    /// `plant.model = "ifac9007"`.
    Ifac9007(ehservo_sim::ifac9007::Ifac9007Plant),
}

impl LinPlant {
    /// The scenario's plant at its variation's bias; an error (key,
    /// reason) for a plant without a [`Linearize`] implementation.
    pub fn of(setup: &Loop) -> Result<Self, KeyError> {
        Self::with_factors(setup, &bias(setup).1)
    }

    /// The scenario's plant with the physical factors `f`.
    pub fn with_factors(setup: &Loop, f: &Factors) -> Result<Self, KeyError> {
        let (p, l) = if *f == Factors::ONE {
            (setup.model().params, setup.model().load)
        } else {
            varied(&setup.model().params, &setup.model().load, f)
        };
        match &setup.plant() {
            scenario::AnyPlant::ThirdOrder(_) => Ok(LinPlant::Third(ThirdOrderPlant::new(p, l))),
            scenario::AnyPlant::Physical(_) => Ok(LinPlant::Physical(PhysicalPlant::new(p, l))),
            // The cylinder's factors vary it as the simulator does; its
            // force signal at t = 0 (a trim's; `at_time` moves it).
            scenario::AnyPlant::Cylinder(c)
                if matches!(c.cylinder().supply, ehservo_sim::supply::Supply::PcPump(_)) =>
            {
                Err(KeyError::new(
                    "plant.supply.kind",
                    "a pressure-compensated pump (\"pc-pump\") is not linearised yet: its regulator's Jacobian is not written; linearise on kind = \"pump\" or \"fixed\"",
                ))
            }
            scenario::AnyPlant::Cylinder(c) => Ok(LinPlant::Cylinder(Box::new(CylinderLin::new(
                c.clone(),
                *f,
                0.0,
            )))),
            // Linear: its factors vary its parameters.
            scenario::AnyPlant::Ifac9007(p) => Ok(LinPlant::Ifac9007(p.with_factors(f))),
            // Any plant registered later (a new one need not be named here
            // to build: its computed responses are refused until it is).
            #[allow(unreachable_patterns)]
            other => Err(KeyError::new(
                "plant.model",
                format!(
                    "\"{}\" is not linearised yet (no ehservo::freq::Linearize for it): the measured responses (--measure) work on it, the computed ones do not",
                    other.model()
                ),
            )),
        }
    }

    /// As a linearisable stage.
    pub fn lin(&self) -> &dyn Linearize {
        match self {
            LinPlant::Third(p) => p,
            LinPlant::Physical(p) => p,
            LinPlant::Cylinder(p) => p.as_ref(),
            LinPlant::Ifac9007(p) => p,
        }
    }

    /// Its state at a logged sample.
    pub fn state_of(&self, s: &crate::simulation::Sample) -> Vec<f64> {
        match self {
            LinPlant::Third(p) => p.state_of(s),
            LinPlant::Physical(p) => p.state_of(s),
            LinPlant::Cylinder(p) => p.state_of(s),
            LinPlant::Ifac9007(p) => p.state_of(s),
        }
    }

    /// The same plant with its time-dependent parts (the cylinder's force
    /// signal) taken at `t`.
    fn at_time(self, t: f64) -> Self {
        match self {
            LinPlant::Cylinder(p) => LinPlant::Cylinder(Box::new(p.at_time(t))),
            other => other,
        }
    }
}

/// An operating point of the whole loop.
#[derive(Debug, Clone, Serialize)]
pub struct OperatingPoint {
    /// `"trim"` or `"time"`.
    pub kind: &'static str,
    /// The time along the run (s), for `"time"`.
    pub t_s: Option<f64>,
    /// θ there (deg), on a rotary axis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub theta_deg: Option<f64>,
    /// The position there (m), on a linear axis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub x_m: Option<f64>,
    /// The same in mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub x_mm: Option<f64>,
    /// The trim's speed (m/s) on a linear axis.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub v_m_s: Option<f64>,
    /// The same in mm/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub v_mm_s: Option<f64>,
    /// The trim's speed (deg/s) on a rotary axis, when it moves.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub theta_dot_deg_s: Option<f64>,
    /// The axis.
    #[serde(skip)]
    pub axis: Axis,
    /// The plant's state, in the order of its model's states.
    pub plant_state: Vec<f64>,
    /// The actuator's state (spool; its rate for a second-order spool).
    pub actuator_state: Vec<f64>,
    /// The command applied to the actuator over the next period (V).
    #[serde(rename = "u_V")]
    pub u: f64,
    /// What the plant receives (V).
    #[serde(rename = "u_plant_V")]
    pub u_plant: f64,
    /// Δa1, Δa2, Δa3 of the true plant there (s⁻³, s⁻², s⁻¹).
    pub da: [f64; 3],
    /// δb there (true b = (1 + δb)·b̄).
    pub db_rel: f64,
    /// The physical factors there (mass, bulk modulus, leakage, supply
    /// pressure, friction, load; all 1 without `[uncertainty.physical]`).
    pub factors: Factors,
    /// ẋ of the plant's states at the point (zero at a trim point, up to the
    /// tolerance).
    pub drift: Vec<f64>,
    /// Newton iterations (trim).
    pub iterations: Option<usize>,
}

impl OperatingPoint {
    /// The position and speed fields of an axis: θ in degrees on a rotary
    /// axis (the bits the paper's outputs always had), x and v in m and mm
    /// on a linear one.
    #[allow(clippy::type_complexity)]
    fn position_fields(
        axis: Axis,
        x: f64,
        v: f64,
    ) -> (
        Option<f64>,
        Option<f64>,
        Option<f64>,
        Option<f64>,
        Option<f64>,
        Option<f64>,
    ) {
        // A force or pressure loop is refused before (`freq::position_loop`).
        match axis {
            Axis::Rotary => (
                Some(x / DR),
                None,
                None,
                None,
                None,
                (v != 0.0).then(|| v / DR),
            ),
            Axis::Linear | Axis::Force | Axis::Pressure => (
                None,
                Some(x),
                Some(axis.display(x)),
                Some(v),
                Some(axis.display(v)),
                None,
            ),
        }
    }

    /// The position there in the axis's SI unit (rad or m).
    pub fn position(&self) -> f64 {
        match (self.theta_deg, self.x_m) {
            (Some(d), _) => d * DR,
            (None, Some(x)) => x,
            (None, None) => 0.0,
        }
    }

    /// The position for people: `θ = 1.2345°` (from `theta_deg` itself, as
    /// the paper's outputs always printed it) or `y = 142.0000 mm`.
    pub fn describe(&self) -> String {
        let a = self.axis;
        let shown = match self.theta_deg {
            Some(d) => d,
            None => a.display(self.position()),
        };
        format!("{} = {shown:.4}{}", a.letter(), a.suffix())
    }

    /// The variation there.
    pub fn variation(&self) -> Variation {
        Variation {
            da: self.da,
            db_rel: self.db_rel,
        }
    }

    /// The point of the plant + actuator chain: the state `(x_plant,
    /// x_actuator)` (the caller keeps the vector alive).
    pub fn chain_state(&self) -> Vec<f64> {
        let mut x = self.plant_state.clone();
        x.extend_from_slice(&self.actuator_state);
        x
    }
}

/// The scenario's variation for the draw `r`: the paper's part on the
/// nominal coefficients and the physical factors, as the plants make them
/// (`Plant::variation`).
fn variation_of(setup: &Loop, r: &Draw) -> (Variation, Factors) {
    let spec = &setup.stages().uncertainty;
    (
        Variation::of(spec, &setup.model().coeffs.as_array(), r),
        spec.physical.factors(&r.physical),
    )
}

/// The bias part of the scenario's variation (every r = 0).
fn bias(setup: &Loop) -> (Variation, Factors) {
    variation_of(setup, &Draw::default())
}

/// The trim point of `plant` at θ0 (rad) under the variation `v`: `(x, p,
/// iterations)`, or the residual that does not vanish (key, reason).
pub fn trim_plant(
    plant: &dyn Linearize,
    theta0: f64,
    v: Variation,
    key: &str,
) -> Result<(Vec<f64>, f64, usize), KeyError> {
    let names = plant.states();
    let n = names.len();
    let mut scale = plant.scales();
    scale.push(1.0); // the input, V
    scale[0] = scale[0].max(theta0.abs());
    let mut z = vec![0.0; n + 1];
    z[0] = theta0;
    let residual = |z: &[f64], out: &mut Vec<f64>| {
        let mut dx = vec![0.0; n];
        let y = plant.eval(
            &Point {
                x: &z[..n],
                u: z[n],
                v,
            },
            &mut dx,
        );
        out.clear();
        out.extend_from_slice(&dx);
        out.push(y - theta0);
    };
    let jac = |z: &[f64]| {
        let j = plant.jacobian(
            &Point {
                x: &z[..n],
                u: z[n],
                v,
            },
            Side::Plus,
        );
        let mut m = DMatrix::zeros(n + 1, n + 1);
        m.view_mut((0, 0), (n, n)).copy_from(&j.a);
        m.view_mut((0, n), (n, 1)).copy_from(&j.b);
        m.view_mut((n, 0), (1, n)).copy_from(&j.c);
        m[(n, n)] = j.d[(0, 0)];
        m
    };
    // The tolerance of each residual: the sizes of its terms.
    let tolerances = |m: &DMatrix<f64>| -> Vec<f64> {
        (0..=n)
            .map(|i| {
                let s: f64 = (0..=n).map(|j| m[(i, j)].abs() * scale[j]).sum();
                1e-10 * s + 1e-300
            })
            .collect()
    };
    let worst = |f: &[f64], tol: &[f64]| -> (usize, f64) {
        f.iter()
            .zip(tol)
            .map(|(a, t)| a.abs() / t)
            .enumerate()
            .fold((0, 0.0), |acc, (i, r)| if r > acc.1 { (i, r) } else { acc })
    };
    let mut f = Vec::new();
    residual(&z, &mut f);
    let fail = |z: &[f64], f: &[f64], tol: &[f64], why: &str| {
        let (i, _) = worst(f, tol);
        let what = if i < n {
            format!("d({})/dt = {:.6e} {}/s", names[i].name, f[i], names[i].unit)
        } else {
            format!("θ − θ0 = {:.6e} rad", f[i])
        };
        let notes = plant.notes(&Point {
            x: &z[..n],
            u: z[n],
            v,
        });
        KeyError::new(
            key,
            format!(
                "no trim point at θ = {:.6}°: the residual {what} does not vanish ({why}; the plant's input there {:.6} V){}",
                theta0 / DR,
                z[n],
                if notes.is_empty() {
                    String::new()
                } else {
                    format!(": {}", notes.join("; "))
                }
            ),
        )
    };
    for it in 0..=TRIM_MAX_ITERATIONS {
        let m = jac(&z);
        let tol = tolerances(&m);
        if !f.iter().all(|v| v.is_finite()) {
            return Err(fail(&z, &f, &tol, "the equations are not finite there"));
        }
        let (_, r) = worst(&f, &tol);
        if r <= 1.0 {
            return Ok((z[..n].to_vec(), z[n], it));
        }
        if it == TRIM_MAX_ITERATIONS {
            return Err(fail(
                &z,
                &f,
                &tol,
                &format!("{TRIM_MAX_ITERATIONS} Newton iterations"),
            ));
        }
        // Newton's step in scaled unknowns.
        let ms = DMatrix::from_fn(n + 1, n + 1, |i, j| m[(i, j)] * scale[j] / tol[i]);
        let rhs = DVector::from_fn(n + 1, |i, _| -f[i] / tol[i]);
        let Some(step) = ms
            .lu()
            .solve(&rhs)
            .filter(|s| s.iter().all(|v| v.is_finite()))
        else {
            return Err(fail(&z, &f, &tol, "its Jacobian is singular there"));
        };
        let norm = |f: &[f64]| {
            f.iter()
                .zip(&tol)
                .map(|(a, t)| (a / t) * (a / t))
                .sum::<f64>()
        };
        let f0 = norm(&f);
        let mut lambda = 1.0;
        let mut next = z.clone();
        let mut fnext = Vec::new();
        let mut improved = false;
        for _ in 0..TRIM_MAX_HALVINGS {
            for j in 0..=n {
                next[j] = z[j] + lambda * step[j] * scale[j];
            }
            residual(&next, &mut fnext);
            let fn_ = norm(&fnext);
            if fn_.is_finite() && fn_ < f0 {
                improved = true;
                break;
            }
            lambda /= 2.0;
        }
        if !improved {
            return Err(fail(&z, &f, &tol, "Newton's method stalls there"));
        }
        z = next;
        f = fnext;
    }
    unreachable!("the loop returns")
}

/// The trim point of the scenario's loop at the position `theta0` (the
/// axis's SI unit) moving at `speed` (the cylinder's only; 0 otherwise);
/// `side` picks the direction a cylinder at rest on a closed-centre valve
/// last moved in.
pub fn trim(
    setup: &Loop,
    plant: &LinPlant,
    actuator: &ActuatorStage,
    theta0: f64,
    speed: f64,
    side: Side,
) -> Result<OperatingPoint, KeyError> {
    let (v, factors) = bias(setup);
    let (x, p, it) = match plant {
        LinPlant::Cylinder(c) => c.trim(theta0, speed, side)?,
        _ if speed != 0.0 => {
            return Err(KeyError::new(
                "--velocity",
                format!(
                    "a trim in steady motion is the cylinder's (plant.model = \"cylinder\"), not plant.model = \"{}\"'s",
                    setup.plant().model()
                ),
            ))
        }
        _ => trim_plant(plant.lin(), theta0, v, "--trim")?,
    };
    let (xa, u) = actuator
        .invert(p)
        .map_err(|e| KeyError::new("--trim", format!("{} ({})", e.reason, e.key)))?;
    let mut drift = vec![0.0; x.len()];
    plant.lin().eval(&Point { x: &x, u: p, v }, &mut drift);
    let axis = setup.axis();
    let (theta_deg, x_m, x_mm, v_m_s, v_mm_s, theta_dot_deg_s) =
        OperatingPoint::position_fields(axis, theta0, speed);
    Ok(OperatingPoint {
        kind: "trim",
        t_s: None,
        theta_deg,
        x_m,
        x_mm,
        v_m_s,
        v_mm_s,
        theta_dot_deg_s,
        axis,
        plant_state: x,
        actuator_state: xa,
        u,
        u_plant: p,
        da: v.da,
        db_rel: v.db_rel,
        factors,
        drift,
        iterations: Some(it),
    })
}

/// The run's state at the sample nearest `t`.
pub fn at_time(
    setup: &Loop,
    plant: &LinPlant,
    actuator: &ActuatorStage,
    t: f64,
) -> Result<OperatingPoint, KeyError> {
    let h = setup.sim().step;
    if !(t.is_finite() && t >= 0.0 && t <= setup.horizon() * (1.0 + 1e-12)) {
        return Err(KeyError::new(
            "--at",
            format!(
                "{t}: must be a time within the run, 0 to simulation.horizon = {} s",
                setup.horizon()
            ),
        ));
    }
    let k = (t / h).round() as u64;
    let rec = setup.simulate(RunTo { k })?;
    let tk = k as f64 * h;
    let x = plant.state_of(&rec.sample);
    // The command the plant gets over [t_k, t_k + h).
    let delay = setup.sim().computation_delay && setup.sim().mode == Mode::Sampled;
    let applied: Vec<f64> = if delay {
        std::iter::once(0.0)
            .chain(rec.commands.iter().copied())
            .collect()
    } else {
        rec.commands.clone()
    };
    let u = applied[k as usize];
    let spool = actuator.replay(&applied[..k as usize], h, setup.sim().substeps);
    let xa = actuator.state_from(rec.sample.spool, spool[1]);
    let (v, factors) = if setup.stages().uncertainty.is_random() {
        let mut unc = UncertaintySignal::new(setup.stages().uncertainty);
        let r = *unc.draw_at(unc.interval_at(tk));
        variation_of(setup, &r)
    } else {
        bias(setup)
    };
    let plant = LinPlant::with_factors(setup, &factors)?.at_time(tk);
    let mut dx = vec![0.0; x.len()];
    plant.lin().eval(
        &Point {
            x: &x,
            u: rec.sample.u_plant,
            v,
        },
        &mut dx,
    );
    let axis = setup.axis();
    let (theta_deg, x_m, x_mm, _, _, _) =
        OperatingPoint::position_fields(axis, rec.sample.x[0], 0.0);
    Ok(OperatingPoint {
        kind: "time",
        t_s: Some(tk),
        theta_deg,
        x_m,
        x_mm,
        v_m_s: None,
        v_mm_s: None,
        theta_dot_deg_s: None,
        axis,
        plant_state: x,
        actuator_state: xa,
        u,
        u_plant: rec.sample.u_plant,
        da: v.da,
        db_rel: v.db_rel,
        factors,
        drift: dx,
        iterations: None,
    })
}

/// What a run to sample k leaves: that sample and the commands of the
/// samples 0..=k.
struct Recorded {
    sample: crate::simulation::Sample,
    commands: Vec<f64>,
}

/// Runs the scenario's own plant and controller, typed, to sample `k`.
struct RunTo {
    k: u64,
}

impl LoopVisit for RunTo {
    type Out = Result<Recorded, KeyError>;
    fn visit<P: LoopPlant, K: ControllerConfig>(self, t: Typed<'_, P, K>) -> Self::Out {
        let s = t.lp;
        record(t.simulation(), s, self.k)
    }
}

fn record<P: Plant, C: ehservo_core::control::Controller>(
    mut sim: Simulation<P, C, scenario::AnyReference>,
    s: &Loop,
    k: u64,
) -> Result<Recorded, KeyError> {
    sim.log_states(true);
    let mut commands = Vec::with_capacity(k as usize + 1);
    loop {
        match sim.step() {
            Some(smp) => {
                commands.push(smp.u);
                if smp.k == k {
                    return Ok(Recorded {
                        sample: smp,
                        commands,
                    });
                }
            }
            None => {
                let when = match sim.stopped() {
                    Some(Stop::Diverged(d)) => format!("the run was unbounded at t = {} s", d.t),
                    _ => "the run ended".into(),
                };
                return Err(KeyError::new(
                    "--at",
                    format!("{when}, before t = {} s", k as f64 * s.sim().step),
                ));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ehservo_core::servo::{Load, ServoParams};

    /// The third-order plant's trim at θ0, by hand: θ̇ = θ̈ = 0 and
    /// −(a1 + Δa1)·θ0 + (1 + δb)·b(θ0, sgn u)·u − d(θ0) = 0, with
    /// P_L = (G·θ0 + Tl(θ0))/Dm and d = 4βe·Kce·Tl/(Vt·Jt) (Ṫl = 0 at rest).
    /// At θ0 = 0.1 rad with the paper's load: Tl = 2·sin 0.4 = 0.7788 N·m.
    #[test]
    fn third_order_trim_by_hand() {
        let par = ServoParams::paper();
        let plant = ThirdOrderPlant::new(par, Load::paper());
        let v = Variation {
            da: [0.39982, 13000.0, 170.0],
            db_rel: 0.25,
        };
        let (x, u, _) = trim_plant(&plant, 0.1, v, "--trim").unwrap();
        assert!((x[0] - 0.1).abs() < 1e-12);
        assert!(x[1].abs() < 1e-9 && x[2].abs() < 1e-7, "{x:?}");
        let m = plant.nominal();
        let tl = 2.0 * 0.4f64.sin();
        let pl = (par.g * 0.1 + tl) / par.dm;
        let d = par.d_per_torque() * tl;
        let kg = par.cd * par.ag * ((par.ps - pl) / par.rho).sqrt();
        let b = par.b_per_kg() * kg;
        let want = ((m.coeffs.a1 + 0.39982) * 0.1 + d) / (1.25 * b);
        assert!((u - want).abs() < 1e-9 * want.abs(), "{u} vs {want}");
    }

    /// The physical plant's trim is the third-order plant's (the same
    /// system): the same command, and P_L from the torque balance.
    #[test]
    fn physical_trim_is_the_third_order_trim() {
        let par = ServoParams::paper();
        let v = Variation {
            da: [0.39982, 13000.0, 170.0],
            db_rel: 0.25,
        };
        let (_, u3, _) =
            trim_plant(&ThirdOrderPlant::new(par, Load::paper()), -0.3, v, "--trim").unwrap();
        let (s, up, _) =
            trim_plant(&PhysicalPlant::new(par, Load::paper()), -0.3, v, "--trim").unwrap();
        assert!((u3 - up).abs() < 1e-8 * u3.abs(), "{u3} vs {up}");
        let pl = (par.g * -0.3 + 2.0 * (-1.2f64).sin()) / par.dm;
        assert!((s[2] - pl).abs() < 1e-6 * pl.abs(), "{} vs {pl}", s[2]);
    }

    /// A load the supply cannot hold: A·sin(kθ) with A = 500 N·m needs
    /// P_L = 500/Dm = 6.1e7 Pa > Ps = 1.38e7 Pa: no trim, and the error
    /// names the residual of θ⃛ and the clamped valve root.
    #[test]
    fn no_trim_names_the_residual() {
        let load = Load {
            amplitude: 500.0,
            wavenumber: 1.0,
            friction: None,
        };
        let plant = ThirdOrderPlant::new(ServoParams::paper(), load);
        let e = trim_plant(&plant, 1.0, Variation::NONE, "--trim").unwrap_err();
        let (k, r) = (e.key, e.reason.to_string());
        assert_eq!(k, "--trim");
        assert!(r.contains("d(theta_ddot)/dt"), "{r}");
    }
}
