//! An instance's life: the version, instantiation from the scenario in the
//! FMU's resources, the initialization and step modes, terminate, reset and
//! free.

use super::{build, log_to, text, with, Body, Instance, LogFn, Phase, Status, ERROR, FATAL, OK};
use ehservo_scenario::fmi::check_token;
use ehservo_scenario::scenario::Loop;
use std::ffi::{c_char, c_void};
use std::panic::{catch_unwind, AssertUnwindSafe};

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
        let toml_text = ehservo_scenario::input::read_text(&path)
            .map_err(|e| fail(format!("reading {}: {e}", path.display())))?;
        let kind = check_token(&token, &toml_text).map_err(|e| fail(e.to_string()))?;
        let scenario = Loop::load(&path, &[]).map_err(|e| fail(e.to_string()))?;
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
        if matches!(i.body, Body::Plant { .. }) && start_time.abs() > 0.0 {
            return i.fail(&format!(
                "startTime = {start_time:?}: the plant starts at t = 0 (its load and variation are functions of the scenario's time)"
            ));
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
