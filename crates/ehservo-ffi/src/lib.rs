//! # ehservo-ffi: a C ABI for ehservo
//!
//! Two opaque handles, each made from a scenario file, stepped by the
//! caller and freed explicitly:
//!
//! - [`EhservoSim`]: the scenario's whole closed loop (plant, actuator,
//!   sensors, controller), the simulation `ehservo run` runs. Each
//!   [`ehservo_sim_step`] produces the sample at t_k and advances to
//!   t_{k+1}; stepped to the horizon, [`ehservo_sim_metric`] gives
//!   `ehservo run`'s `summary.json` metrics to the bit.
//! - [`EhservoController`]: the scenario's controller alone in the sampled
//!   loop, for a plant that is the caller's (hardware, another simulator):
//!   [`ehservo_controller_step`] takes (t, x, z) and returns u.
//!
//! Every function returns an [`EhservoStatus`]: 0 is success, positive
//! values are results that are not errors (the run has stopped, a
//! measurement fault answered by the `[fault]` policy), negative values are
//! errors. After anything but [`EhservoStatus::Ok`] the reason is a
//! sentence in [`ehservo_last_error`] (per thread); a scenario that does
//! not load gives the message `ehservo run` prints after `error: `. Null
//! pointers, non-finite arguments and non-UTF-8 text are errors, never
//! undefined behaviour on this side, and a panic is caught at the boundary
//! ([`EhservoStatus::Panic`]).
//!
//! The header `include/ehservo.h` is generated from this file by cbindgen
//! and committed; `tests/header.rs` fails when it is out of date. The
//! FMI 3.0 entry points of `ehservo fmu` are in [`fmi3`].

// The C boundary: raw pointers from C and `#[no_mangle]` exports are what
// this crate is for; every dereference is checked for null first.
#![allow(unsafe_code)]

/// The FMI 3.0 entry points (declared by the standard's own headers, not
/// by ehservo.h).
///
/// cbindgen:ignore
pub mod fmi3;

use ehservo_scenario::scenario::Loop;
use ehservo_scenario::simulation::Stop;
use ehservo_scenario::stepper::{ControllerStepper, LoopStepper};
use std::cell::RefCell;
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

/// What a call did. Negative values are errors.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EhservoStatus {
    /// Done.
    Ok = 0,
    /// `ehservo_sim_step`: the run has stopped (its horizon's sample was
    /// produced, or it diverged: `ehservo_last_error` says which); no
    /// sample was written.
    Stopped = 1,
    /// `ehservo_controller_step`: the measurement x was non-finite or
    /// beyond `fault.measurement_limit`; u is the `[fault]` policy's safe
    /// command and the controller's state was left as it was.
    MeasurementFault = 2,
    /// `ehservo_controller_step`: the law returned a non-finite command or
    /// state; u is the safe command and the state was left as it was.
    ControlFault = 3,
    /// `ehservo_sim_metric`: the metric is not defined (yet): e.g.
    /// `e_max_deg` before the settling time. The value written is NaN.
    Unavailable = 4,
    /// A pointer argument that must not be null was null (a handle whose
    /// `_new` failed or was never called, an output pointer).
    NullPointer = -1,
    /// An argument is not acceptable: a non-finite number, text that is
    /// not UTF-8, an unknown metric name.
    InvalidArgument = -2,
    /// The scenario does not load or does not validate; the message is the
    /// one `ehservo run` prints.
    Scenario = -3,
    /// A bug: the library panicked. The handle involved should be freed.
    Panic = -4,
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_error(msg: &str) {
    // An interior NUL cannot be represented in C; it would cut the text.
    let c = CString::new(msg.replace('\0', "\\0")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = c);
}

fn clear_error() {
    LAST_ERROR.with(|e| *e.borrow_mut() = CString::default());
}

/// The message of the last call on this thread that did not return
/// `EHSERVO_STATUS_OK` (empty after a success). The text is UTF-8, owned
/// by the library and valid until the next call on this thread.
#[no_mangle]
pub extern "C" fn ehservo_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// The library's version (static, NUL-terminated).
#[no_mangle]
pub extern "C" fn ehservo_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// An error status with its message.
struct Fail(EhservoStatus, String);

type Outcome = Result<EhservoStatus, Fail>;

fn null(func: &str, arg: &str) -> Fail {
    Fail(
        EhservoStatus::NullPointer,
        format!("{func}: `{arg}` is null"),
    )
}

fn invalid(func: &str, msg: String) -> Fail {
    Fail(EhservoStatus::InvalidArgument, format!("{func}: {msg}"))
}

/// Runs `body`, catching a panic; records the message of anything but Ok.
fn guard(func: &str, body: impl FnOnce() -> Outcome) -> EhservoStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(EhservoStatus::Ok)) => {
            clear_error();
            EhservoStatus::Ok
        }
        Ok(Ok(status)) => status,
        Ok(Err(Fail(status, msg))) => {
            set_error(&msg);
            status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "(no message)".into());
            set_error(&format!("{func}: internal error (a panic): {what}"));
            EhservoStatus::Panic
        }
    }
}

/// A path from C: any bytes on Unix (paths need not be UTF-8).
///
/// # Safety
/// `p` is null or a NUL-terminated string.
unsafe fn path_arg(func: &str, name: &str, p: *const c_char) -> Result<PathBuf, Fail> {
    if p.is_null() {
        return Err(null(func, name));
    }
    // SAFETY: non-null, NUL-terminated by the caller's contract.
    let bytes = unsafe { CStr::from_ptr(p) }.to_bytes();
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        Ok(PathBuf::from(std::ffi::OsStr::from_bytes(bytes)))
    }
    #[cfg(not(unix))]
    {
        std::str::from_utf8(bytes)
            .map(PathBuf::from)
            .map_err(|_| invalid(func, format!("`{name}` is not UTF-8")))
    }
}

/// Text from C that must be UTF-8.
///
/// # Safety
/// `p` is null or a NUL-terminated string.
unsafe fn str_arg<'a>(func: &str, name: &str, p: *const c_char) -> Result<&'a str, Fail> {
    if p.is_null() {
        return Err(null(func, name));
    }
    // SAFETY: non-null, NUL-terminated by the caller's contract.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| invalid(func, format!("`{name}` is not UTF-8")))
}

fn finite(func: &str, name: &str, v: f64) -> Result<f64, Fail> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(invalid(
            func,
            format!("`{name}` must be finite (got {v:?})"),
        ))
    }
}

/// Loads and validates a scenario file as `ehservo run` does.
pub(crate) fn load_scenario(path: &std::path::Path) -> Result<Loop, Fail> {
    Loop::load(path, &[]).map_err(|e| Fail(EhservoStatus::Scenario, e.to_string()))
}

/// Writes `value` through `out`, checked for null.
///
/// # Safety
/// `out` is null or valid for a write of `T`.
unsafe fn put<T>(func: &str, name: &str, out: *mut T, value: T) -> Result<(), Fail> {
    if out.is_null() {
        return Err(null(func, name));
    }
    // SAFETY: non-null and writable by the caller's contract.
    unsafe { out.write(value) };
    Ok(())
}

// ---------------------------------------------------------------- the loop

/// A scenario's closed loop (opaque). Made by [`ehservo_sim_new`], freed by
/// [`ehservo_sim_free`]. Not to be used from two threads at once.
pub struct EhservoSim {
    inner: LoopStepper,
    name: String,
}

/// One sample of the loop at t_k (SI units: rad, V).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EhservoSample {
    /// The sample index k.
    pub k: u64,
    /// t_k = k·h (s).
    pub t: f64,
    /// The reference θd (rad).
    pub theta_d: f64,
    /// The true θ (rad).
    pub theta: f64,
    /// The true θ̇ (rad/s).
    pub theta_dot: f64,
    /// The true θ̈ (rad/s²).
    pub theta_ddot: f64,
    /// The tracking error e = θd − θ (rad).
    pub e: f64,
    /// The controller's command u (V).
    pub u: f64,
    /// What the plant receives after the actuator (V).
    pub u_plant: f64,
    /// The law's flags: a bitwise OR of the `EHSERVO_FLAG_*` constants
    /// (each documented where it is defined; docs/flags.md lists them).
    pub flags: u32,
}

/// Flag of [`EhservoSample::flags`]: the valve root of (2) had a negative
/// argument and was clamped at 0 (bit 0).
pub const EHSERVO_FLAG_VALVE_ROOT_CLAMPED: u32 = 1;
/// Flag of [`EhservoSample::flags`]: ‖E‖ = 0, so σΔ, μ and ξ were set to 0
/// (bit 1).
pub const EHSERVO_FLAG_ZERO_ERROR_NORM: u32 = 2;
/// Flag of [`EhservoSample::flags`]: a measurement was non-finite or beyond
/// `fault.measurement_limit`; the safe command was returned (bit 2).
pub const EHSERVO_FLAG_MEASUREMENT_FAULT: u32 = 4;
/// Flag of [`EhservoSample::flags`]: the law produced a non-finite u; the
/// safe command was returned (bit 3).
pub const EHSERVO_FLAG_NON_FINITE_CONTROL: u32 = 8;
/// Flag of [`EhservoSample::flags`]: u was clamped to the valve range (or
/// the controller's own output limit) (bit 4).
pub const EHSERVO_FLAG_SATURATED: u32 = 16;
/// Flag of [`EhservoSample::flags`]: the state update was non-finite; the
/// safe command was returned (bit 5).
pub const EHSERVO_FLAG_NON_FINITE_STATE: u32 = 32;
/// Flag of [`EhservoSample::flags`]: an off-board controller's command did
/// not arrive usable (processor-in-the-loop: a corrupted, dropped or late
/// frame, a board reset); the safe command was applied (bit 6).
pub const EHSERVO_FLAG_LINK_FAULT: u32 = 64;

/// The C constants in the order of `ehservo_scenario::core::control::flags::ALL`
/// (the header's literals, checked against the law's values at compile
/// time and by `tests/header.rs`).
///
/// cbindgen:ignore
pub const FLAGS: [(&str, u32); 7] = [
    (
        "EHSERVO_FLAG_VALVE_ROOT_CLAMPED",
        EHSERVO_FLAG_VALVE_ROOT_CLAMPED,
    ),
    ("EHSERVO_FLAG_ZERO_ERROR_NORM", EHSERVO_FLAG_ZERO_ERROR_NORM),
    (
        "EHSERVO_FLAG_MEASUREMENT_FAULT",
        EHSERVO_FLAG_MEASUREMENT_FAULT,
    ),
    (
        "EHSERVO_FLAG_NON_FINITE_CONTROL",
        EHSERVO_FLAG_NON_FINITE_CONTROL,
    ),
    ("EHSERVO_FLAG_SATURATED", EHSERVO_FLAG_SATURATED),
    (
        "EHSERVO_FLAG_NON_FINITE_STATE",
        EHSERVO_FLAG_NON_FINITE_STATE,
    ),
    ("EHSERVO_FLAG_LINK_FAULT", EHSERVO_FLAG_LINK_FAULT),
];

/// The literals above are the law's flags, or this crate does not build.
///
/// cbindgen:ignore
const _: () = {
    use ehservo_scenario::core::control::flags::ALL;
    let mut i = 0;
    while i < ALL.len() {
        assert!(FLAGS[i].1 == ALL[i].1 as u32);
        i += 1;
    }
};

/// Makes the closed loop of the scenario file `path` (TOML, as `ehservo
/// run` reads it), at t = 0, into `*out`. On an error `*out` is set to
/// null (when `out` is not null) and the message is `ehservo run`'s.
///
/// # Safety
/// `path` is null or a NUL-terminated string; `out` is null or valid for a
/// write of a pointer.
#[no_mangle]
pub unsafe extern "C" fn ehservo_sim_new(
    path: *const c_char,
    out: *mut *mut EhservoSim,
) -> EhservoStatus {
    const F: &str = "ehservo_sim_new";
    guard(F, || {
        if out.is_null() {
            return Err(null(F, "out"));
        }
        // SAFETY: checked non-null; writable by the contract.
        unsafe { out.write(std::ptr::null_mut()) };
        // SAFETY: the caller's contract on `path`.
        let path = unsafe { path_arg(F, "path", path) }?;
        let s = load_scenario(&path)?;
        let inner = LoopStepper::new(&s);
        let sim = Box::new(EhservoSim {
            inner,
            name: s.name().to_string(),
        });
        // SAFETY: as above.
        unsafe { out.write(Box::into_raw(sim)) };
        Ok(EhservoStatus::Ok)
    })
}

/// Frees a loop made by [`ehservo_sim_new`]; null is allowed and ignored.
///
/// # Safety
/// `sim` is null or a handle from `ehservo_sim_new` not yet freed.
#[no_mangle]
pub unsafe extern "C" fn ehservo_sim_free(sim: *mut EhservoSim) {
    if !sim.is_null() {
        // SAFETY: made by Box::into_raw in ehservo_sim_new, freed once.
        drop(unsafe { Box::from_raw(sim) });
    }
}

/// Produces the sample at t_k into `*out` and advances the loop to
/// t_{k+1}: `EHSERVO_STATUS_OK`. Once the run has stopped (after the
/// horizon's sample, or when it diverged) it writes nothing and returns
/// `EHSERVO_STATUS_STOPPED`; `ehservo_last_error` then says why.
///
/// # Safety
/// `sim` is null or a live handle; `out` is null or valid for a write of
/// an `EhservoSample`.
#[no_mangle]
pub unsafe extern "C" fn ehservo_sim_step(
    sim: *mut EhservoSim,
    out: *mut EhservoSample,
) -> EhservoStatus {
    const F: &str = "ehservo_sim_step";
    guard(F, || {
        // SAFETY: null or a live handle, used from one thread.
        let sim = unsafe { sim.as_mut() }
            .ok_or_else(|| null(F, "sim"))
            .map_err(|Fail(s, m)| {
                Fail(
                    s,
                    format!("{m} (make it with ehservo_sim_new and check its status)"),
                )
            })?;
        if out.is_null() {
            return Err(null(F, "out"));
        }
        let Some(s) = sim.inner.step() else {
            let why = match sim.inner.stopped() {
                Some(Stop::Diverged(d)) => format!(
                    "{}: the run diverged at t = {} s: {}",
                    sim.name,
                    d.t,
                    d.reason.describe()
                ),
                _ => format!(
                    "{}: the run reached its horizon ({} steps of {} s)",
                    sim.name,
                    sim.inner.steps(),
                    sim.inner.period()
                ),
            };
            set_error(&why);
            return Ok(EhservoStatus::Stopped);
        };
        let sample = EhservoSample {
            k: s.k,
            t: s.t,
            theta_d: s.z[0],
            theta: s.x[0],
            theta_dot: s.x[1],
            theta_ddot: s.x[2],
            e: s.e,
            u: s.u,
            u_plant: s.u_plant,
            flags: u32::from(s.flags),
        };
        // SAFETY: checked non-null above; writable by the contract.
        unsafe { put(F, "out", out, sample) }?;
        Ok(EhservoStatus::Ok)
    })
}

/// A metric of the samples so far, as `summary.json` names it on the
/// scenario's axis (rotary: `e_max_deg`, `e_rms_deg`, `e_final_deg`; linear:
/// `e_max`, `e_rms`, `e_final` in mm, also spelled `e_max_mm` …; any axis:
/// `u_max`, `u_rms`, `samples`, …), computed as `ehservo run` computes it at
/// the end of its run. The bare `e_max`, `e_rms` and `e_final` are accepted
/// on a rotary axis too (in degrees): [`ehservo_sim_axis_unit`] names the
/// unit. A metric not defined yet writes NaN and returns
/// `EHSERVO_STATUS_UNAVAILABLE`.
///
/// # Safety
/// `sim` is null or a live handle; `name` null or NUL-terminated; `out`
/// null or valid for a write of a double.
#[no_mangle]
pub unsafe extern "C" fn ehservo_sim_metric(
    sim: *const EhservoSim,
    name: *const c_char,
    out: *mut f64,
) -> EhservoStatus {
    const F: &str = "ehservo_sim_metric";
    guard(F, || {
        // SAFETY: null or a live handle.
        let sim = unsafe { sim.as_ref() }.ok_or_else(|| null(F, "sim"))?;
        // SAFETY: the caller's contract on `name`.
        let name = unsafe { str_arg(F, "name", name) }?;
        if out.is_null() {
            return Err(null(F, "out"));
        }
        let m = sim.inner.metrics();
        use ehservo_scenario::metrics::Metrics;
        let names = Metrics::names(m.axis);
        let known = names.contains(&name)
            || Metrics::csv_names(m.axis).contains(&name)
            || Metrics::NAMES_LINEAR.contains(&name);
        if !known {
            return Err(invalid(
                F,
                format!(
                    "unknown metric {name:?} on a {} axis, expected one of {}",
                    m.axis.name(),
                    names.join(", ")
                ),
            ));
        }
        let v = m.get(name);
        // SAFETY: checked non-null above.
        unsafe { put(F, "out", out, v.unwrap_or(f64::NAN)) }?;
        match v {
            Some(_) => Ok(EhservoStatus::Ok),
            None => Err(Fail(
                EhservoStatus::Unavailable,
                format!("{F}: `{name}` is not defined for the samples so far"),
            )),
        }
    })
}

/// `ehservo_sim_metric(sim, "e_max", out)`: max |e| over t ≥
/// `simulation.settle`, in the axis's unit (degrees on a rotary axis,
/// millimetres on a linear one: [`ehservo_sim_axis_unit`]).
///
/// # Safety
/// As [`ehservo_sim_metric`].
#[no_mangle]
pub unsafe extern "C" fn ehservo_sim_e_max(sim: *const EhservoSim, out: *mut f64) -> EhservoStatus {
    // SAFETY: the same contract.
    unsafe { ehservo_sim_metric(sim, c"e_max".as_ptr(), out) }
}

/// `ehservo_sim_metric(sim, "e_max_deg", out)`: max |e| over t ≥
/// `simulation.settle` (degrees), on a rotary axis; on a linear one it
/// returns `EHSERVO_STATUS_INVALID_ARGUMENT` (use [`ehservo_sim_e_max`]).
///
/// # Safety
/// As [`ehservo_sim_metric`].
#[no_mangle]
pub unsafe extern "C" fn ehservo_sim_e_max_deg(
    sim: *const EhservoSim,
    out: *mut f64,
) -> EhservoStatus {
    // SAFETY: the same contract.
    unsafe { ehservo_sim_metric(sim, c"e_max_deg".as_ptr(), out) }
}

/// The display unit of the scenario's axis, as a static NUL-terminated
/// string: `"deg"` (rotary), `"mm"` (linear), `"kN"` (a force loop) or
/// `"bar"` (a load-pressure loop); null for a null handle. Positions and
/// errors in the C ABI's samples are SI (rad, m, N or Pa); the metrics are
/// in this unit.
///
/// # Safety
/// `sim` is null or a live handle.
#[no_mangle]
pub unsafe extern "C" fn ehservo_sim_axis_unit(sim: *const EhservoSim) -> *const c_char {
    // SAFETY: null or a live handle.
    match unsafe { sim.as_ref() } {
        None => std::ptr::null(),
        Some(s) => match s.inner.metrics().axis {
            ehservo_scenario::axis::Axis::Rotary => c"deg".as_ptr(),
            ehservo_scenario::axis::Axis::Linear => c"mm".as_ptr(),
            ehservo_scenario::axis::Axis::Force => c"kN".as_ptr(),
            ehservo_scenario::axis::Axis::Pressure => c"bar".as_ptr(),
        },
    }
}

/// The loop's sample period h (s) and number of steps N (the horizon is
/// N·h; a run to the horizon produces N + 1 samples). Either output may be
/// null.
///
/// # Safety
/// `sim` is null or a live handle; `period`, `steps` null or writable.
#[no_mangle]
pub unsafe extern "C" fn ehservo_sim_info(
    sim: *const EhservoSim,
    period: *mut f64,
    steps: *mut u64,
) -> EhservoStatus {
    const F: &str = "ehservo_sim_info";
    guard(F, || {
        // SAFETY: null or a live handle.
        let sim = unsafe { sim.as_ref() }.ok_or_else(|| null(F, "sim"))?;
        if !period.is_null() {
            // SAFETY: non-null, writable by the contract.
            unsafe { period.write(sim.inner.period()) };
        }
        if !steps.is_null() {
            // SAFETY: non-null, writable by the contract.
            unsafe { steps.write(sim.inner.steps()) };
        }
        Ok(EhservoStatus::Ok)
    })
}

// ---------------------------------------------------------- the controller

/// A scenario's controller in the sampled loop (opaque). Made by
/// [`ehservo_controller_new`], freed by [`ehservo_controller_free`].
pub struct EhservoController {
    inner: ControllerStepper,
}

/// Makes the controller of the scenario file `path` in its initial state
/// into `*out`. The scenario must be in the sampled mode; the controller
/// runs at its `simulation.step` with its `[fault]` policy. Its sensors,
/// estimator and actuator are not part of it. On an error `*out` is set to
/// null (when `out` is not null).
///
/// # Safety
/// As [`ehservo_sim_new`].
#[no_mangle]
pub unsafe extern "C" fn ehservo_controller_new(
    path: *const c_char,
    out: *mut *mut EhservoController,
) -> EhservoStatus {
    const F: &str = "ehservo_controller_new";
    guard(F, || {
        if out.is_null() {
            return Err(null(F, "out"));
        }
        // SAFETY: checked non-null; writable by the contract.
        unsafe { out.write(std::ptr::null_mut()) };
        // SAFETY: the caller's contract on `path`.
        let path = unsafe { path_arg(F, "path", path) }?;
        let s = load_scenario(&path)?;
        let inner =
            ControllerStepper::new(&s).map_err(|e| Fail(EhservoStatus::Scenario, e.to_string()))?;
        // SAFETY: as above.
        unsafe { out.write(Box::into_raw(Box::new(EhservoController { inner }))) };
        Ok(EhservoStatus::Ok)
    })
}

/// Frees a controller; null is allowed and ignored.
///
/// # Safety
/// `ctl` is null or a handle from `ehservo_controller_new` not yet freed.
#[no_mangle]
pub unsafe extern "C" fn ehservo_controller_free(ctl: *mut EhservoController) {
    if !ctl.is_null() {
        // SAFETY: made by Box::into_raw, freed once.
        drop(unsafe { Box::from_raw(ctl) });
    }
}

/// The scenario's reference at `t`: z = (θd, θ̇d, θ̈d, θ⃛d) in rad, rad/s,
/// rad/s², rad/s³, written to `z[0..4]`.
///
/// # Safety
/// `ctl` is null or a live handle; `z` null or valid for 4 doubles.
#[no_mangle]
pub unsafe extern "C" fn ehservo_controller_reference(
    ctl: *const EhservoController,
    t: f64,
    z: *mut f64,
) -> EhservoStatus {
    const F: &str = "ehservo_controller_reference";
    guard(F, || {
        // SAFETY: null or a live handle.
        let ctl = unsafe { ctl.as_ref() }.ok_or_else(|| null(F, "ctl"))?;
        let t = finite(F, "t", t)?;
        if z.is_null() {
            return Err(null(F, "z"));
        }
        let v = ctl.inner.reference(t);
        // SAFETY: non-null, 4 doubles by the contract.
        unsafe { std::ptr::copy_nonoverlapping(v.as_ptr(), z, 4) };
        Ok(EhservoStatus::Ok)
    })
}

/// One sample of the controller at time `t` (s; the caller's clock, one
/// call per sample period h): the law at the measurement x = (θ, θ̇, θ̈)
/// (rad, rad/s, rad/s²) and the reference z (4 doubles as
/// `ehservo_controller_reference` gives; null: the scenario's reference at
/// `t`), then its state advanced by h. Writes the command (V) to `*u`.
///
/// `t` and `z` must be finite (else `EHSERVO_STATUS_INVALID_ARGUMENT`,
/// nothing changed). A non-finite or out-of-range x is a measurement
/// fault, answered as the simulator answers it: u is the safe command of
/// `fault.safe_command` and the status `EHSERVO_STATUS_MEASUREMENT_FAULT`.
///
/// # Safety
/// `ctl` is null or a live handle; `x` null or valid for 3 doubles; `z`
/// null or valid for 4; `u` null or writable.
#[no_mangle]
pub unsafe extern "C" fn ehservo_controller_step(
    ctl: *mut EhservoController,
    t: f64,
    x: *const f64,
    z: *const f64,
    u: *mut f64,
) -> EhservoStatus {
    const F: &str = "ehservo_controller_step";
    guard(F, || {
        // SAFETY: null or a live handle, used from one thread.
        let ctl = unsafe { ctl.as_mut() }.ok_or_else(|| {
            Fail(
                EhservoStatus::NullPointer,
                format!(
                    "{F}: `ctl` is null (make it with ehservo_controller_new and check its status)"
                ),
            )
        })?;
        if x.is_null() {
            return Err(null(F, "x"));
        }
        if u.is_null() {
            return Err(null(F, "u"));
        }
        let t = finite(F, "t", t)?;
        let mut xv = [0.0; 3];
        // SAFETY: non-null, 3 doubles by the contract.
        unsafe { std::ptr::copy_nonoverlapping(x, xv.as_mut_ptr(), 3) };
        let zv = if z.is_null() {
            ctl.inner.reference(t)
        } else {
            let mut zv = [0.0; 4];
            // SAFETY: non-null, 4 doubles by the contract.
            unsafe { std::ptr::copy_nonoverlapping(z, zv.as_mut_ptr(), 4) };
            for (i, &v) in zv.iter().enumerate() {
                finite(F, &format!("z[{i}]"), v)?;
            }
            zv
        };
        let o = ctl.inner.step(t, xv, zv);
        // SAFETY: checked non-null above.
        unsafe { put(F, "u", u, o.u) }?;
        use ehservo_scenario::core::control::flags;
        if o.flags & flags::MEASUREMENT_FAULT != 0 {
            let which = xv
                .iter()
                .position(|v| !v.is_finite())
                .map(|i| format!("`x[{i}]` is {:?}", xv[i]))
                .unwrap_or_else(|| "x is beyond `fault.measurement_limit`".into());
            Err(Fail(
                EhservoStatus::MeasurementFault,
                format!("{F}: a measurement fault at t = {t} s: {which}; u = {} V is the safe command of `fault.safe_command`, the controller's state is unchanged", o.u),
            ))
        } else if o.flags & (flags::NON_FINITE_CONTROL | flags::NON_FINITE_STATE) != 0 {
            Err(Fail(
                EhservoStatus::ControlFault,
                format!("{F}: the law returned a non-finite command or state at t = {t} s; u = {} V is the safe command, the controller's state is unchanged", o.u),
            ))
        } else {
            Ok(EhservoStatus::Ok)
        }
    })
}

/// Back to the initial state (weights, integrators, the held command).
///
/// # Safety
/// `ctl` is null or a live handle.
#[no_mangle]
pub unsafe extern "C" fn ehservo_controller_reset(ctl: *mut EhservoController) -> EhservoStatus {
    const F: &str = "ehservo_controller_reset";
    guard(F, || {
        // SAFETY: null or a live handle.
        let ctl = unsafe { ctl.as_mut() }.ok_or_else(|| null(F, "ctl"))?;
        ctl.inner.reset();
        Ok(EhservoStatus::Ok)
    })
}

/// The controller's sample period h (s) and the scenario's number of steps
/// N (its horizon is N·h). Either output may be null.
///
/// # Safety
/// `ctl` is null or a live handle; `period`, `steps` null or writable.
#[no_mangle]
pub unsafe extern "C" fn ehservo_controller_info(
    ctl: *const EhservoController,
    period: *mut f64,
    steps: *mut u64,
) -> EhservoStatus {
    const F: &str = "ehservo_controller_info";
    guard(F, || {
        // SAFETY: null or a live handle.
        let ctl = unsafe { ctl.as_ref() }.ok_or_else(|| null(F, "ctl"))?;
        if !period.is_null() {
            // SAFETY: non-null, writable by the contract.
            unsafe { period.write(ctl.inner.period()) };
        }
        if !steps.is_null() {
            // SAFETY: non-null, writable by the contract.
            unsafe { steps.write(ctl.inner.steps()) };
        }
        Ok(EhservoStatus::Ok)
    })
}

#[cfg(test)]
mod tests;
