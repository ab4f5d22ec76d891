//! The pieces `LoopModel::new` composes the loop from: G discretised, the
//! measured channels a law reads, the compensating law's gain at the
//! point, the delays and L itself.

use super::*;

/// The gain a compensating law divides by at `op`: the nominal model's
/// `b(x, s)` (floored as the law floors it) at the point's position and
/// speed, at rest in acceleration, in the valve direction `s` of `side`.
pub(super) fn compensated_gain(setup: &Loop, op: &OperatingPoint, side: Side) -> f64 {
    let speed = match (op.v_m_s, op.theta_dot_deg_s) {
        (Some(v), _) => v,
        (None, Some(d)) => d * ehservo_core::math::DR,
        (None, None) => 0.0,
    };
    let x = [op.position(), speed, 0.0];
    let model = &setup.design().model;
    let b0 = model.b_at_rest();
    model.gain_for(&x, side.sign(), 1e-3 * b0).0
}

/// G discretised as `discretisation` says, at the loop's period.
pub(super) fn discretise(
    g: &StateSpace,
    discretisation: Discretisation,
    setup: &Loop,
) -> Result<StateSpace, KeyError> {
    let h = setup.sim().step;
    match discretisation {
        Discretisation::Zoh => g.zoh(h),
        Discretisation::Rk4 => g.rk4_map(h, setup.sim().substeps),
    }
    .map_err(|e| KeyError::new("plant", e.to_string()))
}

/// G with the outputs (θ, θ̇, θ̈), continuous, when the law reads the
/// three (the state feedback) from the sensors; None for a law that reads
/// θm alone, or (with a note) when the law's channels are not G's
/// derivatives: an estimator supplies some, or G's input reaches θ sooner
/// than its third integral.
pub(super) fn measured_path(
    setup: &Loop,
    g: &StateSpace,
    controller: Option<&ControllerModel>,
    notes: &mut Vec<String>,
) -> Option<StateSpace> {
    if controller.is_none_or(|c| c.measured == 1) {
        return None;
    }
    if !setup.stages().sensor.measured().is_all() {
        notes.push(
            "controller: the law reads the estimator's x̂ for the channels the sensors do not measure; the estimator in the loop is not modelled, so the loop is not computed"
                .into(),
        );
        return None;
    }
    let names = vec![
        Quantity::new("theta", "rad"),
        Quantity::new("theta_dot", "rad/s"),
        Quantity::new("theta_ddot", "rad/s²"),
    ];
    let g3 = g.with_derivatives(names);
    if g3.is_none() {
        notes.push(
            "controller: the plant's command reaches θ sooner than its third integral, so θ̇m and θ̈m are not G's derivatives; the loop is not computed"
                .into(),
        );
    }
    g3
}

/// The loop's delays: the sample period and the samples of the sensor's
/// and the computation's delays.
pub(super) struct Delays {
    pub(super) h: f64,
    pub(super) sensor: usize,
    pub(super) computation: usize,
}

/// L as one model, when the law is linear: C ∘ z^{−n_s} ∘ G_d ∘ z^{−n_c}
/// in sampled mode, C ∘ G in continuous time.
pub(super) fn open_loop(
    g: &StateSpace,
    g_d: Option<&StateSpace>,
    feedback: Option<&StateSpace>,
    delays: &Delays,
) -> Result<Option<StateSpace>, KeyError> {
    let h = delays.h;
    if let (Some(c), true) = (feedback, g.outputs.len() > 1) {
        // Several measured channels, each delayed alike: the delays
        // commute with G, so both sit on the command, z^{−(n_s + n_c)}.
        let u = Quantity::new("u", "V");
        let m = match g_d {
            Some(gd) => StateSpace::delay(delays.computation + delays.sensor, h, &u).series(gd),
            None => Ok(g.clone()),
        };
        return m
            .and_then(|m| m.series(c))
            .map(Some)
            .map_err(|e| KeyError::new("loop", e.0));
    }
    Ok(match (feedback, g_d) {
        (Some(c), Some(gd)) => {
            let theta = Quantity::new("theta", "rad");
            let u = Quantity::new("u", "V");
            let comp = Delay {
                n: delays.computation,
                h,
                signal: u.clone(),
            };
            let sens = Delay {
                n: delays.sensor,
                h,
                signal: theta.clone(),
            };
            let comp_m = StateSpace::delay(comp.n, h, &u);
            let sens_m = StateSpace::delay(sens.n, h, &theta);
            Some(
                comp_m
                    .series(gd)
                    .and_then(|m| m.series(&sens_m))
                    .and_then(|m| m.series(c))
                    .map_err(|e| KeyError::new("loop", e.0))?,
            )
        }
        (Some(c), None) => Some(g.series(c).map_err(|e| KeyError::new("loop", e.0))?),
        _ => None,
    })
}
