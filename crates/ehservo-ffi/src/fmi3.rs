//! The FMI 3.0 co-simulation entry points of the FMUs `ehservo fmu`
//! writes (the model description, the variables and the token are in
//! `ehservo::fmu`).
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
//!
//! A communication step must be a whole number of sample periods h (the
//! model description's `fixedInternalStepSize`). Calls out of order, unknown
//! value references, non-finite inputs and anything this FMU does not
//! provide (model exchange, scheduled execution, FMU state, event mode,
//! other types than Float64) return `fmi3Error` with a message through the
//! logger; a panic is caught and returns `fmi3Fatal`.

use ehservo::fmu::{check_token, vr, FmuKind};
use ehservo::scenario::Scenario;
use ehservo::simulation::{Sample, Stop};
use ehservo::stepper::{ControllerStepper, LawOutput, LoopStepper};
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
}

struct Instance {
    name: String,
    env: *mut c_void,
    log: LogFn,
    logging_on: bool,
    kind: FmuKind,
    scenario: Scenario,
    phase: Phase,
    t0: f64,
    h: f64,
    k: u64,
    body: Body,
}

fn build(kind: FmuKind, s: &Scenario) -> Result<(Body, f64), String> {
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
            let mut sim = LoopStepper::new(s).map_err(|e| e.to_string())?;
            let h = sim.period();
            // The sample at t = 0 depends on nothing the importer sets.
            let last = sim
                .step()
                .ok_or_else(|| "the loop stopped before its first sample".to_string())?;
            Ok((Body::Loop { sim, last }, h))
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
            Body::Loop { .. } => None,
        }
    }

    fn get(&mut self, r: u32) -> Result<f64, String> {
        let t = self.time();
        if r == vr::TIME {
            return Ok(t);
        }
        match self.kind {
            FmuKind::Controller => {
                if let Body::Controller { x, ctl, .. } = &self.body {
                    match r {
                        vr::THETA | vr::THETA_DOT | vr::THETA_DDOT => {
                            return Ok(x[(r - vr::THETA) as usize])
                        }
                        vr::THETA_D => return Ok(ctl.reference(t)[0]),
                        _ => {}
                    }
                }
                if r == vr::U {
                    return Ok(self.law_output().map_or(f64::NAN, |o| o.u));
                }
            }
            FmuKind::ClosedLoop => {
                if let Body::Loop { sim, last } = &self.body {
                    return match r {
                        vr::THETA => Ok(last.x[0]),
                        vr::THETA_DOT => Ok(last.x[1]),
                        vr::THETA_DDOT => Ok(last.x[2]),
                        vr::U => Ok(last.u),
                        vr::U_PLANT => Ok(last.u_plant),
                        vr::THETA_D => Ok(last.z[0]),
                        vr::E => Ok(last.e),
                        vr::E_DEG => Ok(sim.axis().display(last.e)),
                        vr::E_MAX_DEG => Ok(sim.metrics().e_max.unwrap_or(0.0)),
                        _ => Err(format!("no Float64 variable has value reference {r}")),
                    };
                }
            }
        }
        Err(format!("no Float64 variable has value reference {r}"))
    }

    fn set(&mut self, r: u32, v: f64) -> Result<(), String> {
        if self.phase == Phase::Terminated {
            return Err("fmi3SetFloat64 after fmi3Terminate".into());
        }
        match &mut self.body {
            Body::Controller { x, out, .. }
                if matches!(r, vr::THETA | vr::THETA_DOT | vr::THETA_DDOT) =>
            {
                let name = ["theta", "theta_dot", "theta_ddot"][(r - vr::THETA) as usize];
                if !v.is_finite() {
                    return Err(format!(
                        "input `{name}` (value reference {r}) must be finite (got {v:?})"
                    ));
                }
                x[(r - vr::THETA) as usize] = v;
                *out = None;
                Ok(())
            }
            _ => Err(format!(
                "value reference {r} is not an input of this {} FMU",
                self.kind.as_str()
            )),
        }
    }

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

/// The FMI version (static).
#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

/// Instantiates a co-simulation FMU from `resourcePath/scenario.toml`.
///
/// # Safety
/// FMI 3.0's contract for `fmi3InstantiateCoSimulation`.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instance_name: *const c_char,
    instantiation_token: *const c_char,
    resource_path: *const c_char,
    _visible: bool,
    logging_on: bool,
    _event_mode_used: bool,
    _early_return_allowed: bool,
    _required_intermediate_variables: *const u32,
    _n_required_intermediate_variables: usize,
    instance_environment: *mut c_void,
    log_message: LogFn,
    _intermediate_update: *const c_void,
) -> *mut c_void {
    let made = catch_unwind(AssertUnwindSafe(|| -> Result<Box<Instance>, String> {
        // SAFETY: FMI's contract: null or NUL-terminated.
        let name = unsafe { text(instance_name) }.unwrap_or_else(|| "ehservo".into());
        let fail = |m: String| format!("{name}: fmi3InstantiateCoSimulation: {m}");
        // SAFETY: as above.
        let token = unsafe { text(instantiation_token) }
            .ok_or_else(|| fail("instantiationToken is null".into()))?;
        // SAFETY: as above.
        let res = unsafe { text(resource_path) }.ok_or_else(|| {
            fail("resourcePath is null (the FMU needs resources/scenario.toml)".into())
        })?;
        let path = std::path::Path::new(&res).join("scenario.toml");
        // Bounded as every input file is (a regular file, ≤ 1 MiB).
        let toml_text = ehservo::input::read_text(&path)
            .map_err(|e| fail(format!("reading {}: {e}", path.display())))?;
        let kind = check_token(&token, &toml_text).map_err(fail)?;
        let scenario = Scenario::load(&path, &[]).map_err(|e| fail(e.to_string()))?;
        let (body, h) = build(kind, &scenario).map_err(fail)?;
        Ok(Box::new(Instance {
            name,
            env: instance_environment,
            log: log_message,
            logging_on,
            kind,
            scenario,
            phase: Phase::Instantiated,
            t0: 0.0,
            h,
            k: 0,
            body,
        }))
    }));
    match made {
        Ok(Ok(i)) => Box::into_raw(i).cast(),
        Ok(Err(msg)) => {
            log_to(log_message, instance_environment, ERROR, &msg);
            std::ptr::null_mut()
        }
        Err(_) => {
            log_to(
                log_message,
                instance_environment,
                FATAL,
                "fmi3InstantiateCoSimulation: internal error (a panic)",
            );
            std::ptr::null_mut()
        }
    }
}

/// Frees an instance (null is ignored).
///
/// # Safety
/// `instance` is null or from `fmi3InstantiateCoSimulation`, freed once.
#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(instance: *mut c_void) {
    if !instance.is_null() {
        // SAFETY: made by Box::into_raw above, freed once.
        drop(unsafe { Box::from_raw(instance.cast::<Instance>()) });
    }
}

/// # Safety
/// FMI 3.0's contract.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: *mut c_void,
    logging_on: bool,
    _n_categories: usize,
    _categories: *const *const c_char,
) -> Status {
    with(instance, "fmi3SetDebugLogging", |i| {
        i.logging_on = logging_on;
        OK
    })
}

/// # Safety
/// FMI 3.0's contract.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: *mut c_void,
    _tolerance_defined: bool,
    _tolerance: f64,
    start_time: f64,
    stop_time_defined: bool,
    stop_time: f64,
) -> Status {
    with(instance, "fmi3EnterInitializationMode", |i| {
        if i.phase != Phase::Instantiated {
            return i.fail(&format!(
                "fmi3EnterInitializationMode called in {:?} mode (only after instantiation or fmi3Reset)",
                i.phase
            ));
        }
        if !start_time.is_finite() {
            return i.fail(&format!("startTime must be finite (got {start_time:?})"));
        }
        if let Body::Loop { sim, .. } = &i.body {
            if start_time.abs() > 0.0 {
                return i.fail(&format!(
                    "startTime = {start_time:?}: the closed loop starts at t = 0"
                ));
            }
            let horizon = sim.steps() as f64 * sim.period();
            if stop_time_defined && stop_time > horizon * (1.0 + 1e-12) {
                return i.fail(&format!(
                    "stopTime = {stop_time:?} s is beyond the scenario's horizon {horizon:?} s (simulation.horizon)"
                ));
            }
        }
        i.t0 = start_time;
        i.phase = Phase::Initialization;
        OK
    })
}

/// # Safety
/// FMI 3.0's contract.
#[no_mangle]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: *mut c_void) -> Status {
    with(instance, "fmi3ExitInitializationMode", |i| {
        if i.phase != Phase::Initialization {
            return i.fail(&format!(
                "fmi3ExitInitializationMode called in {:?} mode (call fmi3EnterInitializationMode first)",
                i.phase
            ));
        }
        i.phase = Phase::Step;
        OK
    })
}

/// # Safety
/// FMI 3.0's contract.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterStepMode(instance: *mut c_void) -> Status {
    with(instance, "fmi3EnterStepMode", |i| {
        if i.phase == Phase::Step {
            OK
        } else {
            i.fail("fmi3EnterStepMode: this FMU has no event mode")
        }
    })
}

/// # Safety
/// FMI 3.0's contract.
#[no_mangle]
pub unsafe extern "C" fn fmi3Terminate(instance: *mut c_void) -> Status {
    with(instance, "fmi3Terminate", |i| {
        i.phase = Phase::Terminated;
        OK
    })
}

/// Back to the state after instantiation.
///
/// # Safety
/// FMI 3.0's contract.
#[no_mangle]
pub unsafe extern "C" fn fmi3Reset(instance: *mut c_void) -> Status {
    with(instance, "fmi3Reset", |i| {
        match build(i.kind, &i.scenario) {
            Ok((body, h)) => {
                i.body = body;
                i.h = h;
                i.k = 0;
                i.t0 = 0.0;
                i.phase = Phase::Instantiated;
                OK
            }
            Err(e) => i.fail(&e),
        }
    })
}

/// # Safety
/// FMI 3.0's contract: `vrs` holds `nvr` references, `values` `n_values`
/// doubles.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: *mut c_void,
    vrs: *const u32,
    nvr: usize,
    values: *mut f64,
    n_values: usize,
) -> Status {
    with(instance, "fmi3GetFloat64", |i| {
        if nvr == 0 {
            return OK;
        }
        if vrs.is_null() || values.is_null() || n_values != nvr {
            return i.fail(&format!(
                "fmi3GetFloat64: null arrays or nValues = {n_values} != nValueReferences = {nvr} (every variable is a scalar)"
            ));
        }
        // SAFETY: FMI's contract on the array lengths.
        let (vrs, values) = unsafe {
            (
                std::slice::from_raw_parts(vrs, nvr),
                std::slice::from_raw_parts_mut(values, nvr),
            )
        };
        for (r, v) in vrs.iter().zip(values.iter_mut()) {
            match i.get(*r) {
                Ok(x) => *v = x,
                Err(e) => return i.fail(&format!("fmi3GetFloat64: {e}")),
            }
        }
        OK
    })
}

/// # Safety
/// FMI 3.0's contract: `vrs` holds `nvr` references, `values` `n_values`
/// doubles.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: *mut c_void,
    vrs: *const u32,
    nvr: usize,
    values: *const f64,
    n_values: usize,
) -> Status {
    with(instance, "fmi3SetFloat64", |i| {
        if nvr == 0 {
            return OK;
        }
        if vrs.is_null() || values.is_null() || n_values != nvr {
            return i.fail(&format!(
                "fmi3SetFloat64: null arrays or nValues = {n_values} != nValueReferences = {nvr} (every variable is a scalar)"
            ));
        }
        // SAFETY: FMI's contract on the array lengths.
        let (vrs, values) = unsafe {
            (
                std::slice::from_raw_parts(vrs, nvr),
                std::slice::from_raw_parts(values, nvr),
            )
        };
        for (r, v) in vrs.iter().zip(values) {
            if let Err(e) = i.set(*r, *v) {
                return i.fail(&format!("fmi3SetFloat64: {e}"));
            }
        }
        OK
    })
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

/// The functions of FMI 3.0 this FMU does not provide: each logs why and
/// returns `fmi3Error` (a Get or Set of no variables is a no-op, as FMI
/// allows).
macro_rules! unsupported {
    ($($name:ident($($arg:ident: $ty:ty),*) $why:literal;)*) => {$(
        /// Not provided by this FMU: returns `fmi3Error`.
        ///
        /// # Safety
        /// FMI 3.0's contract.
        #[no_mangle]
        #[allow(clippy::too_many_arguments)]
        pub unsafe extern "C" fn $name(instance: *mut c_void, $($arg: $ty),*) -> Status {
            $(let _ = $arg;)*
            with(instance, stringify!($name), |i| {
                i.fail(concat!(stringify!($name), ": ", $why))
            })
        }
    )*};
}

/// Get/Set of a type this FMU has no variables of: nothing to do for an
/// empty list, an error otherwise.
macro_rules! no_variables_of_type {
    ($($name:ident($($arg:ident: $ty:ty),*);)*) => {$(
        /// This FMU has no variables of this type: an empty request is
        /// fine, any other is `fmi3Error`.
        ///
        /// # Safety
        /// FMI 3.0's contract.
        #[no_mangle]
        pub unsafe extern "C" fn $name(instance: *mut c_void, vrs: *const u32, nvr: usize, $($arg: $ty),*) -> Status {
            $(let _ = $arg;)*
            let _ = vrs;
            with(instance, stringify!($name), |i| {
                if nvr == 0 {
                    OK
                } else {
                    i.fail(concat!(stringify!($name), ": this FMU has only Float64 variables"))
                }
            })
        }
    )*};
}

no_variables_of_type! {
    fmi3GetFloat32(v: *mut f32, n: usize);
    fmi3GetInt8(v: *mut i8, n: usize);
    fmi3GetUInt8(v: *mut u8, n: usize);
    fmi3GetInt16(v: *mut i16, n: usize);
    fmi3GetUInt16(v: *mut u16, n: usize);
    fmi3GetInt32(v: *mut i32, n: usize);
    fmi3GetUInt32(v: *mut u32, n: usize);
    fmi3GetInt64(v: *mut i64, n: usize);
    fmi3GetUInt64(v: *mut u64, n: usize);
    fmi3GetBoolean(v: *mut bool, n: usize);
    fmi3GetString(v: *mut *const c_char, n: usize);
    fmi3GetBinary(sizes: *mut usize, v: *mut *const u8, n: usize);
    fmi3GetClock(v: *mut bool);
    fmi3SetFloat32(v: *const f32, n: usize);
    fmi3SetInt8(v: *const i8, n: usize);
    fmi3SetUInt8(v: *const u8, n: usize);
    fmi3SetInt16(v: *const i16, n: usize);
    fmi3SetUInt16(v: *const u16, n: usize);
    fmi3SetInt32(v: *const i32, n: usize);
    fmi3SetUInt32(v: *const u32, n: usize);
    fmi3SetInt64(v: *const i64, n: usize);
    fmi3SetUInt64(v: *const u64, n: usize);
    fmi3SetBoolean(v: *const bool, n: usize);
    fmi3SetString(v: *const *const c_char, n: usize);
    fmi3SetBinary(sizes: *const usize, v: *const *const u8, n: usize);
    fmi3SetClock(v: *const bool);
    fmi3GetIntervalDecimal(intervals: *mut f64, qualifiers: *mut c_int);
    fmi3GetIntervalFraction(counters: *mut u64, resolutions: *mut u64, qualifiers: *mut c_int);
    fmi3GetShiftDecimal(shifts: *mut f64);
    fmi3GetShiftFraction(counters: *mut u64, resolutions: *mut u64);
    fmi3SetIntervalDecimal(intervals: *const f64);
    fmi3SetIntervalFraction(counters: *const u64, resolutions: *const u64);
    fmi3SetShiftDecimal(shifts: *const f64);
    fmi3SetShiftFraction(counters: *const u64, resolutions: *const u64);
}

unsupported! {
    fmi3EnterEventMode() "this FMU has no event mode (hasEventMode = false)";
    fmi3EnterConfigurationMode() "this FMU has no structural parameters";
    fmi3ExitConfigurationMode() "this FMU has no structural parameters";
    fmi3EvaluateDiscreteStates() "this FMU has no event mode";
    fmi3UpdateDiscreteStates(a: *mut bool, b: *mut bool, c: *mut bool, d: *mut bool, e: *mut bool, f: *mut f64) "this FMU has no event mode";
    fmi3GetNumberOfVariableDependencies(r: u32, n: *mut usize) "the dependencies are in modelDescription.xml";
    fmi3GetVariableDependencies(r: u32, a: *mut usize, b: *mut u32, c: *mut usize, d: *mut c_int, n: usize) "the dependencies are in modelDescription.xml";
    fmi3GetFMUState(s: *mut *mut c_void) "canGetAndSetFMUState = false";
    fmi3SetFMUState(s: *mut c_void) "canGetAndSetFMUState = false";
    fmi3FreeFMUState(s: *mut *mut c_void) "canGetAndSetFMUState = false";
    fmi3SerializedFMUStateSize(s: *mut c_void, n: *mut usize) "canSerializeFMUState = false";
    fmi3SerializeFMUState(s: *mut c_void, b: *mut u8, n: usize) "canSerializeFMUState = false";
    fmi3DeserializeFMUState(b: *const u8, n: usize, s: *mut *mut c_void) "canSerializeFMUState = false";
    fmi3GetDirectionalDerivative(a: *const u32, b: usize, c: *const u32, d: usize, e: *const f64, f: usize, g: *mut f64, h: usize) "providesDirectionalDerivatives = false";
    fmi3GetAdjointDerivative(a: *const u32, b: usize, c: *const u32, d: usize, e: *const f64, f: usize, g: *mut f64, h: usize) "providesAdjointDerivatives = false";
    fmi3GetOutputDerivatives(a: *const u32, b: usize, c: *const i32, d: *mut f64, e: usize) "maxOutputDerivativeOrder = 0";
    fmi3EnterContinuousTimeMode() "a co-simulation FMU (no model exchange)";
    fmi3CompletedIntegratorStep(a: bool, b: *mut bool, c: *mut bool) "a co-simulation FMU (no model exchange)";
    fmi3SetTime(t: f64) "a co-simulation FMU (no model exchange)";
    fmi3SetContinuousStates(x: *const f64, n: usize) "a co-simulation FMU (no model exchange)";
    fmi3GetContinuousStateDerivatives(x: *mut f64, n: usize) "a co-simulation FMU (no model exchange)";
    fmi3GetEventIndicators(x: *mut f64, n: usize) "a co-simulation FMU (no model exchange)";
    fmi3GetContinuousStates(x: *mut f64, n: usize) "a co-simulation FMU (no model exchange)";
    fmi3GetNominalsOfContinuousStates(x: *mut f64, n: usize) "a co-simulation FMU (no model exchange)";
    fmi3GetNumberOfEventIndicators(n: *mut usize) "a co-simulation FMU (no model exchange)";
    fmi3GetNumberOfContinuousStates(n: *mut usize) "a co-simulation FMU (no model exchange)";
    fmi3ActivateModelPartition(clock: u32, t: f64) "a co-simulation FMU (no scheduled execution)";
}

/// Not provided: a co-simulation FMU. Logs and returns null.
///
/// # Safety
/// FMI 3.0's contract.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    _instance_name: *const c_char,
    _instantiation_token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    instance_environment: *mut c_void,
    log_message: LogFn,
) -> *mut c_void {
    log_to(
        log_message,
        instance_environment,
        ERROR,
        "fmi3InstantiateModelExchange: this is a co-simulation FMU",
    );
    std::ptr::null_mut()
}

/// Not provided: a co-simulation FMU. Logs and returns null.
///
/// # Safety
/// FMI 3.0's contract.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _instance_name: *const c_char,
    _instantiation_token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    instance_environment: *mut c_void,
    log_message: LogFn,
    _clock_update: *const c_void,
    _lock_preemption: *const c_void,
    _unlock_preemption: *const c_void,
) -> *mut c_void {
    log_to(
        log_message,
        instance_environment,
        ERROR,
        "fmi3InstantiateScheduledExecution: this is a co-simulation FMU",
    );
    std::ptr::null_mut()
}
