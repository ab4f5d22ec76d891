//! An FMI 3.0 co-simulation binary, loaded, and its instances: the dozen
//! entry points of the FMI 3.0 standard (`fmi3Functions.h`, section 2.3
//! and 4.2) that a plant needs, called through `libloading`.
//!
//! Every status the FMU returns is checked: `OK` and `Warning` go on,
//! anything else (`Discard`, `Error`, `Fatal`), and a step that asks to
//! terminate the simulation, is an [`FmuError`] with the FMU's last logged
//! message.
#![allow(unsafe_code)]

use super::FmuInstance;
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::Path;
use std::sync::{Arc, Mutex};

type Status = c_int;
const OK: Status = 0;
const WARNING: Status = 1;

type LogFn = unsafe extern "C" fn(*mut c_void, Status, *const c_char, *const c_char);

type Instantiate = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_char,
    bool,
    bool,
    bool,
    bool,
    *const u32,
    usize,
    *mut c_void,
    Option<LogFn>,
    *const c_void,
) -> *mut c_void;
type EnterInit = unsafe extern "C" fn(*mut c_void, bool, f64, f64, bool, f64) -> Status;
type Unary = unsafe extern "C" fn(*mut c_void) -> Status;
type Free = unsafe extern "C" fn(*mut c_void);
type SetF64 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *const f64, usize) -> Status;
type GetF64 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *mut f64, usize) -> Status;
type DoStep = unsafe extern "C" fn(
    *mut c_void,
    f64,
    f64,
    bool,
    *mut bool,
    *mut bool,
    *mut bool,
    *mut f64,
) -> Status;

/// What an FMU call that failed says: the call, its status, the FMU's
/// last logged message.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{call} returned {status}{}", if message.is_empty() { String::new() } else { format!(": {message}") })]
pub(crate) struct FmuError {
    pub call: &'static str,
    pub status: &'static str,
    pub message: String,
}

/// FMI's name of a status (the same numbers in 2.0 and 3.0).
pub(crate) fn status_name(s: Status) -> &'static str {
    match s {
        0 => "OK",
        1 => "Warning",
        2 => "Discard",
        3 => "Error",
        4 => "Fatal",
        _ => "an unknown status",
    }
}

/// The loaded binary: its entry points (the library stays loaded while
/// any instance lives: they hold this by `Arc`).
#[derive(Debug)]
pub(crate) struct Binary {
    _lib: libloading::Library,
    instantiate: Instantiate,
    enter_init: EnterInit,
    exit_init: Unary,
    terminate: Unary,
    free: Free,
    set_f64: SetF64,
    get_f64: GetF64,
    do_step: DoStep,
}

impl Binary {
    /// Loads `path` and resolves the entry points; the error is the reason.
    pub fn load(path: &Path) -> Result<Arc<Binary>, String> {
        // SAFETY: loading runs the library's initialisers: an FMU's binary
        // is trusted code by FMI's design (it is the model); what can be
        // checked (the file exists, is this platform's) was.
        let lib = unsafe { libloading::Library::new(path) }
            .map_err(|e| format!("binary cannot be loaded: {e}"))?;
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: the symbol's type is FMI 3.0's for that name.
                *unsafe { lib.get(concat!($name, "\0").as_bytes()) }
                    .map_err(|_| format!("binary has no {}", $name))?
            };
        }
        Ok(Arc::new(Binary {
            instantiate: sym!("fmi3InstantiateCoSimulation"),
            enter_init: sym!("fmi3EnterInitializationMode"),
            exit_init: sym!("fmi3ExitInitializationMode"),
            terminate: sym!("fmi3Terminate"),
            free: sym!("fmi3FreeInstance"),
            set_f64: sym!("fmi3SetFloat64"),
            get_f64: sym!("fmi3GetFloat64"),
            do_step: sym!("fmi3DoStep"),
            _lib: lib,
        }))
    }
}

/// The FMU's last message, where the log callback writes (the instance
/// environment).
#[derive(Debug)]
struct Log {
    last: Mutex<String>,
}

unsafe extern "C" fn log_message(
    env: *mut c_void,
    status: Status,
    _category: *const c_char,
    message: *const c_char,
) {
    if env.is_null() || message.is_null() {
        return;
    }
    // SAFETY: `env` is the `Log` this instance was created with (alive
    // while the instance is); `message` is NUL-terminated by FMI's contract.
    let (log, text) = unsafe { (&*(env as *const Log), CStr::from_ptr(message)) };
    // Kept, not printed: a refusal is one line, and a failure during a run
    // is reported once with it (FmuError).
    if let Ok(mut last) = log.last.lock() {
        last.clear();
        last.push_str(&format!(
            "[{}] {}",
            status_name(status),
            text.to_string_lossy()
        ));
    }
}

/// One co-simulation instance, initialised, in step mode.
#[derive(Debug)]
pub(crate) struct Instance {
    bin: Arc<Binary>,
    ptr: *mut c_void,
    log: Box<Log>,
    /// An error status was returned: only `fmi3FreeInstance` is allowed
    /// then.
    failed: bool,
}

// SAFETY: an instance is used by one thread at a time (it lives in a
// Mutex), as FMI 3.0 allows (§2.1.4: calls on one instance are serial).
unsafe impl Send for Instance {}

impl Instance {
    /// Instantiates, sets the `starts` (parameters: value reference and
    /// value) and initialises at t = 0.
    pub fn new(
        bin: &Arc<Binary>,
        name: &str,
        token: &str,
        resources: &str,
        starts: &[(u32, f64)],
    ) -> Result<Instance, FmuError> {
        let fail = |call, message: String| FmuError {
            call,
            status: "an error",
            message,
        };
        let c = |s: &str| {
            CString::new(s)
                .map_err(|_| fail("fmi3InstantiateCoSimulation", "a NUL in a string".into()))
        };
        let (cname, ctoken, cres) = (c(name)?, c(token)?, c(resources)?);
        let log = Box::new(Log {
            last: Mutex::new(String::new()),
        });
        let env = &*log as *const Log as *mut c_void;
        // SAFETY: FMI 3.0's contract: the strings live over the call, the
        // environment as long as the instance (it is boxed in it).
        let ptr = unsafe {
            (bin.instantiate)(
                cname.as_ptr(),
                ctoken.as_ptr(),
                cres.as_ptr(),
                false,
                true,
                false,
                false,
                std::ptr::null(),
                0,
                env,
                Some(log_message),
                std::ptr::null(),
            )
        };
        if ptr.is_null() {
            let message = log.last.lock().map(|m| m.clone()).unwrap_or_default();
            return Err(fail("fmi3InstantiateCoSimulation", message));
        }
        let mut inst = Instance {
            bin: Arc::clone(bin),
            ptr,
            log,
            failed: false,
        };
        for &(vr, v) in starts {
            inst.set(&[vr], &[v])?;
        }
        // SAFETY: a live instance in the instantiated state.
        let s = unsafe { (inst.bin.enter_init)(inst.ptr, false, 0.0, 0.0, false, 0.0) };
        inst.check("fmi3EnterInitializationMode", s)?;
        // SAFETY: as above, in initialization mode.
        let s = unsafe { (inst.bin.exit_init)(inst.ptr) };
        inst.check("fmi3ExitInitializationMode", s)?;
        Ok(inst)
    }

    fn check(&mut self, call: &'static str, s: Status) -> Result<(), FmuError> {
        if s == OK || s == WARNING {
            return Ok(());
        }
        self.failed = true;
        Err(FmuError {
            call,
            status: status_name(s),
            message: self.log.last.lock().map(|m| m.clone()).unwrap_or_default(),
        })
    }
}

impl FmuInstance for Instance {
    fn set(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), FmuError> {
        debug_assert_eq!(vrs.len(), values.len());
        // SAFETY: a live instance; the slices are as long as their lengths.
        let s = unsafe {
            (self.bin.set_f64)(
                self.ptr,
                vrs.as_ptr(),
                vrs.len(),
                values.as_ptr(),
                values.len(),
            )
        };
        self.check("fmi3SetFloat64", s)
    }

    fn get(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), FmuError> {
        debug_assert_eq!(vrs.len(), out.len());
        // SAFETY: a live instance; the slices are as long as their lengths.
        let s = unsafe {
            (self.bin.get_f64)(
                self.ptr,
                vrs.as_ptr(),
                vrs.len(),
                out.as_mut_ptr(),
                out.len(),
            )
        };
        self.check("fmi3GetFloat64", s)
    }

    fn step(&mut self, t: f64, h: f64) -> Result<(), FmuError> {
        let (mut event, mut terminate, mut early, mut last) = (false, false, false, t);
        // SAFETY: a live instance in step mode; the outputs are writable.
        let s = unsafe {
            (self.bin.do_step)(
                self.ptr,
                t,
                h,
                true,
                &mut event,
                &mut terminate,
                &mut early,
                &mut last,
            )
        };
        self.check("fmi3DoStep", s)?;
        if terminate {
            return Err(FmuError {
                call: "fmi3DoStep",
                status: "terminateSimulation",
                message: self.log.last.lock().map(|m| m.clone()).unwrap_or_default(),
            });
        }
        Ok(())
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: a live instance, freed once; its status does not matter
        // any more.
        unsafe {
            if !self.failed {
                (self.bin.terminate)(self.ptr);
            }
            (self.bin.free)(self.ptr);
        }
    }
}
