//! The FMI 3.0 co-simulation entry points of the FMUs `ehservo fmu`
//! writes (the model description, the variables and the token are in
//! `ehservo_scenario::fmu`).
//!
//! Two kinds of FMU, told apart by the instantiation token:
//!
//! - **controller**: inputs θ, θ̇, θ̈ (rad, rad/s, rad/s²), outputs u (V)
//!   and θd (rad). The controller samples at t_k = t_start + k·h. `u` is
//!   the law at the current sample with the inputs as set now (direct
//!   feedthrough: setting an input again before `fmi3DoStep` recomputes it
//!   from the state at the start of the sample); `fmi3DoStep` commits that
//!   sample and, for a step of n periods, runs the n − 1 further samples
//!   with the inputs held.
//! - **closed-loop**: no inputs; after `fmi3DoStep` to t_k the outputs are
//!   the loop's sample at t_k, as `ehservo run` logs it; `e_max_deg` is its
//!   `summary.json` metric over the samples so far.
//! - **plant**: the plant with its actuator; inputs u (V) and, on a plant
//!   that takes one, the external load `f_load`; outputs x and the
//!   pressures at the current time. `fmi3DoStep` over n periods integrates
//!   n sample periods, each by the scenario's RK4 sub-steps, with the
//!   inputs held (`ehservo_scenario::stepper::PlantStepper`).
//!
//! A communication step must be a whole number of sample periods h (the
//! model description's `fixedInternalStepSize`). Calls out of order, unknown
//! value references, non-finite inputs and anything this FMU does not
//! provide (model exchange, scheduled execution, FMU state, event mode,
//! other types than Float64) return `fmi3Error` with a message through the
//! logger; a panic is caught and returns `fmi3Fatal`.
//!
//! The rooms: this file holds the instance (its phase, its body, the
//! controller's output at the current sample) and the boundary's helpers
//! (the logger, the panic guard); `lifecycle.rs` instantiation, the modes
//! and reset; `variables.rs` the Get and Set of variables; `step.rs`
//! `fmi3DoStep`; `unsupported.rs` what this FMU does not provide.

mod lifecycle;
mod step;
mod unsupported;
mod variables;

pub use lifecycle::*;
pub use step::*;
pub use unsupported::*;
pub use variables::*;

use ehservo_scenario::fmi::FmuKind;
use ehservo_scenario::scenario::Loop;
use ehservo_scenario::simulation::PlantOutput;
use ehservo_scenario::simulation::Sample;
use ehservo_scenario::stepper::{ControllerStepper, LawOutput, LoopStepper, PlantStepper};
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

type Status = c_int;
const OK: Status = 0;
const WARNING: Status = 1;
const ERROR: Status = 3;
const FATAL: Status = 4;

/// `fmi3LogMessageCallback`.
type LogFn = Option<unsafe extern "C" fn(*mut c_void, Status, *const c_char, *const c_char)>;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Instantiated,
    Initialization,
    Step,
    Terminated,
}

enum Body {
    Controller {
        /// The controller, possibly advanced by the current sample.
        ctl: ControllerStepper,
        /// The controller at the start of the current sample.
        snapshot: ControllerStepper,
        /// The inputs.
        x: [f64; 3],
        /// The current sample's output, once computed from `snapshot`.
        out: Option<LawOutput>,
    },
    Loop {
        sim: LoopStepper,
        /// The sample at the current time.
        last: Sample,
    },
    Plant {
        plant: PlantStepper,
        /// The command u (V), held over a step.
        u: f64,
        /// The external load (N or N·m), when the plant takes one.
        f_load: f64,
        /// The outputs at the current time under `u`.
        out: PlantOutput,
    },
}

struct Instance {
    name: String,
    env: *mut c_void,
    log: LogFn,
    logging_on: bool,
    kind: FmuKind,
    scenario: Loop,
    phase: Phase,
    t0: f64,
    h: f64,
    k: u64,
    body: Body,
}

fn build(kind: FmuKind, s: &Loop) -> Result<(Body, f64), String> {
    match kind {
        FmuKind::Controller => {
            let ctl = ControllerStepper::new(s).map_err(|e| e.to_string())?;
            let h = ctl.period();
            Ok((
                Body::Controller {
                    snapshot: ctl.clone(),
                    ctl,
                    x: [0.0; 3],
                    out: None,
                },
                h,
            ))
        }
        FmuKind::ClosedLoop => {
            let mut sim = LoopStepper::new(s);
            let h = sim.period();
            // The sample at t = 0 depends on nothing the importer sets.
            let last = sim
                .step()
                .ok_or_else(|| "the loop stopped before its first sample".to_string())?;
            Ok((Body::Loop { sim, last }, h))
        }
        FmuKind::Plant => {
            let mut plant = PlantStepper::new(s);
            let h = plant.period();
            let out = plant.output(0.0);
            Ok((
                Body::Plant {
                    plant,
                    u: 0.0,
                    f_load: 0.0,
                    out,
                },
                h,
            ))
        }
    }
}

impl Instance {
    fn log(&self, status: Status, msg: &str) {
        if status < ERROR && !self.logging_on {
            return;
        }
        log_to(self.log, self.env, status, &format!("{}: {msg}", self.name));
    }

    fn fail(&self, msg: &str) -> Status {
        self.log(ERROR, msg);
        ERROR
    }

    fn time(&self) -> f64 {
        self.t0 + self.k as f64 * self.h
    }

    /// The controller's output at the current sample, computed from the
    /// state at the start of the sample and the inputs as set now.
    fn law_output(&mut self) -> Option<LawOutput> {
        let t = self.time();
        match &mut self.body {
            Body::Controller {
                ctl,
                snapshot,
                x,
                out,
            } => {
                if out.is_none() {
                    *ctl = snapshot.clone();
                    let z = ctl.reference(t);
                    *out = Some(ctl.step(t, *x, z));
                }
                *out
            }
            Body::Loop { .. } | Body::Plant { .. } => None,
        }
    }
}

fn log_to(log: LogFn, env: *mut c_void, status: Status, msg: &str) {
    if let Some(f) = log {
        let category = if status >= ERROR {
            c"logStatusError"
        } else {
            c"logStatusWarning"
        };
        let m = CString::new(msg.replace('\0', "\\0")).unwrap_or_default();
        // SAFETY: the importer's callback, with NUL-terminated strings
        // that live through the call.
        unsafe { f(env, status, category.as_ptr(), m.as_ptr()) };
    }
}

/// The instance behind a pointer, or null.
///
/// # Safety
/// `p` is null or an instance from `fmi3InstantiateCoSimulation` not yet
/// freed.
unsafe fn inst<'a>(p: *mut c_void) -> Option<&'a mut Instance> {
    // SAFETY: the caller's contract.
    unsafe { p.cast::<Instance>().as_mut() }
}

/// Runs `body` on the instance, catching a panic.
fn with(p: *mut c_void, func: &str, body: impl FnOnce(&mut Instance) -> Status) -> Status {
    // SAFETY: FMI's contract on the instance pointer.
    let Some(i) = (unsafe { inst(p) }) else {
        return ERROR;
    };
    let (log, env, name) = (i.log, i.env, i.name.clone());
    match catch_unwind(AssertUnwindSafe(|| body(i))) {
        Ok(s) => s,
        Err(_) => {
            log_to(
                log,
                env,
                FATAL,
                &format!("{name}: {func}: internal error (a panic)"),
            );
            FATAL
        }
    }
}

/// # Safety
/// `p` is null or NUL-terminated.
unsafe fn text(p: *const c_char) -> Option<String> {
    if p.is_null() {
        return None;
    }
    // SAFETY: non-null, NUL-terminated by FMI's contract.
    Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
}
#[cfg(test)]
mod tests;
