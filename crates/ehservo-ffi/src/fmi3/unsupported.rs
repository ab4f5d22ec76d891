//! What this FMU does not provide (event mode, FMU state, derivatives,
//! model exchange, scheduled execution): each entry point logs why and
//! returns `fmi3Error` (or null for an instantiation).

use super::{log_to, with, LogFn, Status, ERROR};
use std::ffi::{c_char, c_int, c_void};

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
