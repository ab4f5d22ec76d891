//! `fmi3DoStep`: a communication step of whole sample periods, for the
//! controller (commit the current sample, run the rest with the inputs
//! held) and for the closed loop (run to the step's end, or its stop).

use super::{with, Body, Instance, Phase, Status, FATAL, OK, WARNING};
use ehservo_scenario::fmi::FmuKind;
use ehservo_scenario::simulation::Stop;
use std::ffi::c_void;

impl Instance {
    fn do_step(&mut self, t: f64, step: f64, terminate: &mut bool, last_ok: &mut f64) -> Status {
        if self.phase != Phase::Step {
            return self.fail(&format!(
                "fmi3DoStep called in {:?} mode: call fmi3EnterInitializationMode and fmi3ExitInitializationMode first",
                self.phase
            ));
        }
        let h = self.h;
        let now = self.time();
        if !t.is_finite() || (t - now).abs() > 1e-6 * h {
            return self.fail(&format!(
                "currentCommunicationPoint = {t:?} is not the FMU's time {now:?}"
            ));
        }
        let end = t + step;
        let n_f = ((end - self.t0) / h).round();
        if step.is_nan()
            || step <= 0.0
            || !end.is_finite()
            || n_f <= self.k as f64
            || (self.t0 + n_f * h - end).abs() > 1e-6 * h
        {
            return self.fail(&format!(
                "communicationStepSize = {step:?} is not a positive whole number of sample periods h = {h:?} s"
            ));
        }
        let n = n_f as u64;
        if self.kind == FmuKind::Controller {
            let _ = self.law_output(); // commits sample k
            let t0 = self.t0;
            if let Body::Controller {
                ctl,
                snapshot,
                x,
                out,
                ..
            } = &mut self.body
            {
                for j in self.k + 1..n {
                    let tj = t0 + j as f64 * h;
                    let z = ctl.reference(tj);
                    ctl.step(tj, *x, z);
                }
                *snapshot = ctl.clone();
                *out = None;
            }
            self.k = n;
            *last_ok = self.time();
            return OK;
        }
        if self.kind == FmuKind::Plant {
            return self.plant_step(n, terminate, last_ok);
        }
        let Body::Loop { sim, last } = &mut self.body else {
            return FATAL;
        };
        if n > sim.steps() {
            let (steps, hh) = (sim.steps(), sim.period());
            return self.fail(&format!(
                "fmi3DoStep to t = {end:?} s goes beyond the scenario's horizon {:?} s",
                steps as f64 * hh
            ));
        }
        while last.k < n {
            match sim.step() {
                Some(s) => *last = s,
                None => break,
            }
        }
        self.k = last.k;
        *last_ok = self.t0 + self.k as f64 * h;
        if last.k < n {
            *terminate = true;
            let why = match sim.stopped() {
                Some(Stop::Diverged(d)) => {
                    format!("the run diverged at t = {} s: {}", d.t, d.reason.describe())
                }
                _ => "the run stopped".into(),
            };
            self.log(WARNING, &why);
            return WARNING;
        }
        OK
    }
}

impl Instance {
    /// The plant to sample `n` with the inputs held: each period by the
    /// scenario's RK4 sub-steps; a divergence ends the simulation there.
    fn plant_step(&mut self, n: u64, terminate: &mut bool, last_ok: &mut f64) -> Status {
        let Body::Plant { plant, u, out, .. } = &mut self.body else {
            return FATAL;
        };
        let mut diverged = None;
        while self.k < n {
            if let Err(d) = plant.hold(*u) {
                diverged = Some(d);
                break;
            }
            self.k += 1;
        }
        *out = plant.output(*u);
        *last_ok = self.time();
        if let Some(d) = diverged {
            *terminate = true;
            self.log(
                WARNING,
                &format!(
                    "the plant diverged at t = {} s: {}",
                    d.t,
                    d.reason.describe()
                ),
            );
            return WARNING;
        }
        OK
    }
}

/// # Safety
/// FMI 3.0's contract; the output pointers may be null.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn fmi3DoStep(
    instance: *mut c_void,
    current_communication_point: f64,
    communication_step_size: f64,
    _no_set_fmu_state_prior_to_current_point: bool,
    event_handling_needed: *mut bool,
    terminate_simulation: *mut bool,
    early_return: *mut bool,
    last_successful_time: *mut f64,
) -> Status {
    with(instance, "fmi3DoStep", |i| {
        let mut terminate = false;
        let mut last = i.time();
        let s = i.do_step(
            current_communication_point,
            communication_step_size,
            &mut terminate,
            &mut last,
        );
        // SAFETY: each is null or writable by FMI's contract.
        unsafe {
            if !event_handling_needed.is_null() {
                event_handling_needed.write(false);
            }
            if !terminate_simulation.is_null() {
                terminate_simulation.write(terminate);
            }
            if !early_return.is_null() {
                early_return.write(false);
            }
            if !last_successful_time.is_null() {
                last_successful_time.write(last);
            }
        }
        s
    })
}
