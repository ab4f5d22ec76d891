//! The frequency domain (issue #36): `ehservo linearize` and `ehservo freq`.
//!
//! | module | what |
//! |---|---|
//! | [`ss`] | state-space models with named, unit-carrying signals; responses, poles, zeros, DC gain, damping; ZOH (matrix exponential), RK4 and Euler maps |
//! | [`linearize`] | the [`linearize::Linearize`] trait: analytic Jacobians of the plants, the actuator stage and the delays, with their kinks and one-sided Jacobians |
//! | [`oppoint`] | operating points: a trim (Newton) or a time along the run |
//! | [`controllers`] | the linear controllers (PID, ADRC: observer and law) and the Luenberger/Kalman observers as state-space models |
//! | [`response`] | the loop: G, G_d, C, L, S, T, θ/θd, θ/d |
//! | [`margins`] | gain, phase, delay and stability margins with every crossover; bandwidth, peaks |
//! | [`measure`] | measured responses on the simulator: sinestream, Welch's H1 with coherence (multisine, chirp) |
//! | [`report`] | the outputs: JSON, CSV, Bode and Nyquist plots |
//!
//! The frequency grid and the measurement are set by flags (`--f-min`,
//! `--f-max`, `--points`, `--measure …`), not by scenario keys.

pub mod cli;
pub mod controllers;
pub mod linearize;
pub mod margins;
pub mod measure;
pub mod oppoint;
pub mod report;
pub mod response;
pub mod ss;
pub mod stability;

use crate::scenario::{Loop, Reason, ScenarioError};
use ehservo_core::math::DR;
use ehservo_core::reference::Reference;
use linearize::{ActuatorStage, Chain, Linearize, Point, Side};
use oppoint::{At, LinPlant, OperatingPoint};
use response::{Discretisation, LoopModel};
use serde_json::{json, Value};
use ss::{pair, StateSpace};

/// The frequency domain's refusal of a force or pressure loop (issue #49
/// item 7, open): its responses are not written for a loop whose x₀ is
/// not a position.
pub fn position_loop(setup: &Loop, file: &str) -> Result<(), ScenarioError> {
    let axis = setup.axis();
    if axis.is_position() {
        Ok(())
    } else {
        Err(bad(
            file,
            "reference.quantity",
            format!(
                "a {} loop has no frequency responses in this version (issue #49 item 7): use a position loop",
                axis.name()
            ),
        ))
    }
}

/// A bad request about a scenario: its file, the key (or flag) and why.
pub fn bad(file: &str, key: &str, reason: impl Into<String>) -> ScenarioError {
    ScenarioError {
        file: file.to_string(),
        key: key.to_string(),
        line_col: None,
        reason: Reason::Other(reason.into()),
    }
}

/// A figure for a one-line message: as written (`50`, `0.1`) within
/// 10⁻⁴ ≤ |v| < 10¹⁵, in scientific notation beyond (`1e-300`, never three
/// hundred digits).
///
/// ```
/// use ehservo::freq::fig;
/// assert_eq!(fig(50.0), "50");
/// assert_eq!(fig(0.1), "0.1");
/// assert_eq!(fig(1e-300), "1e-300");
/// assert_eq!(fig(1e300), "1e300");
/// assert_eq!(fig(0.0), "0");
/// ```
pub fn fig(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && a.is_finite() && !(1e-4..1e15).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// What `ehservo linearize` builds.
#[derive(Debug, Clone)]
pub struct Linearised {
    /// The scenario built.
    pub setup: Loop,
    /// The operating point.
    pub point: OperatingPoint,
    /// The loop's models.
    pub lp: LoopModel,
    /// The side of a one-sided model (None: differentiable there).
    pub side: Option<Side>,
}

/// The default operating point: a trim at the reference's θd(0).
pub fn default_at(setup: &Loop) -> At {
    At::Trim(setup.reference().z(0.0)[0])
}

/// Linearises the scenario's loop at `at`. At a kink without `side`, the
/// error names the kink and gives the one-sided derivatives; with `side`
/// the one-sided model is built.
pub fn linearise(
    setup: &Loop,
    file: &str,
    at: Option<At>,
    side: Option<Side>,
    discretisation: Discretisation,
) -> Result<Linearised, ScenarioError> {
    let key = match at {
        Some(At::Time(_)) => "--at",
        _ => "--trim",
    };
    position_loop(setup, file)?;
    let plant = LinPlant::of(setup).map_err(|e| bad(file, &e.key, e.reason.to_string()))?;
    let act = ActuatorStage::new(&setup.stages().actuator);
    let at = at.unwrap_or_else(|| default_at(setup));
    let point = match at {
        At::Trim(x0) => oppoint::trim(setup, &plant, &act, x0, 0.0, side.unwrap_or(Side::Plus)),
        At::Moving(x0, v0) => {
            oppoint::trim(setup, &plant, &act, x0, v0, side.unwrap_or(Side::Plus))
        }
        At::Time(t) => oppoint::at_time(setup, &plant, &act, t),
    }
    .map_err(|e| bad(file, &e.key, e.reason.to_string()))?;
    let lp = LoopModel::new(
        setup,
        &plant,
        &act,
        &point,
        side.unwrap_or(Side::Plus),
        discretisation,
    )
    .map_err(|e| bad(file, &e.key, e.reason.to_string()))?;
    if !lp.kinks.is_empty() && side.is_none() {
        let chain = Chain {
            first: &act,
            then: plant.lin(),
        };
        let x = point.chain_state();
        let p = Point {
            x: &x,
            u: point.u,
            v: point.variation(),
        };
        return Err(bad(file, key, kink_message(&chain, &p, &lp)));
    }
    let lp_kinks_empty = lp.kinks.is_empty();
    // The controller's own output limit at the point.
    if let Some(c) = &lp.controller {
        if point.u.abs() >= c.u_limit {
            return Err(bad(file,
                key,
                format!(
                    "the controller's command {:.6} V is at its output limit controller.u_limit = {} V there: its linear model (slope 1 inside, 0 beyond) does not hold",
                    point.u, c.u_limit
                ),
            ));
        }
    }
    Ok(Linearised {
        setup: setup.clone(),
        point,
        lp,
        // A side only means something at a kink.
        side: side.filter(|_| !lp_kinks_empty),
    })
}

/// The one line naming the kinks and the one-sided derivatives that differ
/// most.
fn kink_message(chain: &Chain, p: &Point, lp: &LoopModel) -> String {
    let jm = chain.jacobian(p, Side::Minus);
    let jp = chain.jacobian(p, Side::Plus);
    let names = chain.states();
    let n = names.len();
    let mut best = (0.0f64, String::new());
    for i in 0..n {
        for j in 0..=n {
            let (a, b) = if j < n {
                (jm.a[(i, j)], jp.a[(i, j)])
            } else {
                (jm.b[(i, 0)], jp.b[(i, 0)])
            };
            let diff = if a.is_finite() && b.is_finite() {
                (a - b).abs()
            } else if a.to_bits() != b.to_bits() {
                f64::INFINITY
            } else {
                0.0
            };
            if diff > best.0 {
                let wrt = if j < n {
                    names[j].name.clone()
                } else {
                    "u".to_string()
                };
                best = (
                    diff,
                    format!(
                        "∂(d{}/dt)/∂{wrt} = {a:.6e} (from below) and {b:.6e} (from above)",
                        names[i].name
                    ),
                );
            }
        }
    }
    let what: Vec<String> = lp.kinks.iter().map(|k| k.what.clone()).collect();
    format!(
        "not differentiable there: {}; one-sided: {}; pass --side minus or --side plus for a one-sided model",
        what.join("; "),
        best.1
    )
}

/// A model with its poles, zeros, DC gain and damping, as JSON.
pub fn model_json(m: &StateSpace) -> Value {
    let siso = m.inputs.len() == 1 && m.outputs.len() == 1;
    let roots = |v: Option<Vec<ss::C64>>| -> Value {
        match v {
            Some(v) => json!(v.iter().map(|z| pair(*z)).collect::<Vec<_>>()),
            None => Value::Null,
        }
    };
    json!({
        "ss": m.to_json(),
        "poles": roots(m.poles()),
        "damping": m.damping(),
        "zeros": if siso { roots(m.zeros()) } else { Value::Null },
        "dc_gain": if siso { json!(m.dc_gain()) } else { Value::Null },
    })
}

/// The linearisation as JSON (what `ehservo linearize` writes).
pub fn linearisation_json(l: &Linearised) -> Value {
    let s = l.setup.scenario();
    let lp = &l.lp;
    let ctrl = lp.controller.as_ref().map(|c| {
        json!({
            "kind": c.kind,
            "u_limit_V": c.u_limit.is_finite().then_some(c.u_limit),
            "law": model_json(&c.law),
            "in_loop": lp.controller_loop.as_ref().map(model_json),
            "parts": c.parts_for_mode(lp.sampled().then_some(lp.h)).iter().map(|(n, m)| (n.to_string(), model_json(m))).collect::<serde_json::Map<_, _>>(),
            "feedback": lp.feedback.as_ref().map(model_json),
        })
    });
    let loop_json = lp.loop_l.as_ref().map(|m| {
        json!({
            "model": model_json(m),
            "closed_loop_poles": lp.closed_loop_poles().map(|v| v.iter().map(|z| pair(*z)).collect::<Vec<_>>()),
            "closed_loop_stable": lp.closed_loop_stable(),
            "hidden_modes": lp.hidden_modes().map(|v| v.iter().map(|z| pair(*z)).collect::<Vec<_>>()),
        })
    });
    let axis = l.setup.axis();
    let theta = response::quantity_for_axis(&ss::Quantity::new("theta", "rad"), axis);
    let u = ss::Quantity::new("u", "V");
    let feedback = match axis {
        crate::axis::Axis::Rotary => {
            "C = −u/θm: negative feedback, L = C·z^−ns·Gd·z^−nc".to_string()
        }
        _ => "C = −u/ym: negative feedback, L = C·z^−ns·Gd·z^−nc".to_string(),
    };
    json!({
        "scenario": s.name,
        "ehservo": env!("CARGO_PKG_VERSION"),
        "mode": lp.mode.as_str(),
        "dt_s": lp.h,
        "discretisation": lp.discretisation.as_str(),
        "operating_point": l.point,
        "one_sided": l.side.map(|s| s.as_str()),
        "kinks": lp.kinks.iter().map(|k| json!({"what": k.what, "quantity": k.quantity})).collect::<Vec<_>>(),
        "notes": lp.notes,
        "plant": model_json(&lp.plant),
        "actuator": model_json(&lp.actuator),
        "plant_with_actuator": model_json(&lp.g),
        "plant_discrete": lp.g_d.as_ref().map(model_json),
        "sensor_delay": {
            "samples": lp.sensor_delay,
            "model": lp.sampled().then(|| StateSpace::delay(lp.sensor_delay, lp.h, &theta).to_json()),
        },
        "computation_delay": {
            "samples": lp.computation_delay,
            "model": lp.sampled().then(|| StateSpace::delay(lp.computation_delay, lp.h, &u).to_json()),
        },
        "controller": ctrl,
        "loop": loop_json,
        "estimator": lp.observer.as_ref().map(model_json),
        "conventions": {
            "feedback": feedback,
            "phase_margin": "mod(∠L, 360°) − 180° (python-control's)",
            "discrete": "x⁺ = A·x + B·u at the period dt_s; responses at z = e^{jωh}",
        },
    })
}

/// Every model of a linearisation is finite (nothing non-finite is written).
pub fn all_finite(l: &Linearised) -> bool {
    let lp = &l.lp;
    let mut ok = lp.g.is_finite() && lp.plant.is_finite() && lp.actuator.is_finite();
    for m in [
        &lp.g_d,
        &lp.controller_loop,
        &lp.feedback,
        &lp.loop_l,
        &lp.observer,
    ]
    .into_iter()
    .flatten()
    {
        ok &= m.is_finite();
    }
    ok
}

/// θ0 of a trim in degrees for messages.
pub fn deg(rad: f64) -> f64 {
    rad / DR
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With zero leakage (Kce = 0) the motor holds a load with the valve
    /// closed: at a trim under load, u = 0 while P_L ≠ 0, and the two valve
    /// directions' gains differ — a kink, refused with the one-sided values
    /// and built on request.
    #[test]
    fn a_kink_is_refused_with_its_one_sided_values() {
        let toml = "[plant.params]\nKce = 0.0\n[uncertainty]\na_bias = 0.0\nb_bias = 0.0\n[controller]\nkind = \"pid\"\n";
        let s = Loop::parse(toml).unwrap();
        let e =
            linearise(&s, "k.toml", Some(At::Trim(0.2)), None, Discretisation::Zoh).unwrap_err();
        assert_eq!(e.key, "--trim");
        assert!(e.reason.contains("sgn(xv)"), "{}", e.reason);
        assert!(e.reason.contains("from below"), "{}", e.reason);
        assert!(!e.reason.contains("\n"));
        for side in [Side::Minus, Side::Plus] {
            let l = linearise(
                &s,
                "k.toml",
                Some(At::Trim(0.2)),
                Some(side),
                Discretisation::Zoh,
            )
            .unwrap();
            assert_eq!(l.lp.kinks.len(), 1);
        }
        let m = linearise(
            &s,
            "k",
            Some(At::Trim(0.2)),
            Some(Side::Minus),
            Discretisation::Zoh,
        )
        .unwrap();
        let p = linearise(
            &s,
            "k",
            Some(At::Trim(0.2)),
            Some(Side::Plus),
            Discretisation::Zoh,
        )
        .unwrap();
        // P_L > 0 at θ = 0.2 (the load 2·sin 0.8 > 0): the negative
        // direction has the larger flow gain.
        assert!(m.lp.g.b[(2, 0)] > p.lp.g.b[(2, 0)]);
    }
}
