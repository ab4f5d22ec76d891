//! An FMI 2.0 co-simulation binary and its instances: the entry points of
//! the FMI 2.0.4 standard (`fmi2Functions.h`, sections 2.1 and 4.2) that a
//! plant needs, as [`super::binary`] does for FMI 3.0, with the same
//! status rules and errors.
#![allow(unsafe_code)]

use super::binary::{status_name, FmuError};
use super::FmuInstance;
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::Path;
use std::sync::{Arc, Mutex};

type Status = c_int;
const OK: Status = 0;
const WARNING: Status = 1;
/// fmi2Type's fmi2CoSimulation.
const CO_SIMULATION: c_int = 1;

/// FMI 2.0's logger is variadic (`…` after the message, for its `%`
/// arguments). Stable Rust cannot define a variadic function; this one
/// takes the five named arguments, which every C ABI ehservo runs on
/// (x86-64 System V, AArch64) passes exactly as to a variadic callee,
/// and keeps the message as it is, its `%` directives unexpanded.
type Logger =
    unsafe extern "C" fn(*mut c_void, *const c_char, Status, *const c_char, *const c_char);

#[repr(C)]
struct Callbacks {
    logger: Option<Logger>,
    allocate: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    free: Option<unsafe extern "C" fn(*mut c_void)>,
    step_finished: Option<unsafe extern "C" fn(*mut c_void, Status)>,
    env: *mut c_void,
}

extern "C" {
    fn calloc(n: usize, size: usize) -> *mut c_void;
    fn free(p: *mut c_void);
}

type Instantiate = unsafe extern "C" fn(
    *const c_char,
    c_int,
    *const c_char,
    *const c_char,
    *const Callbacks,
    c_int,
    c_int,
) -> *mut c_void;
type Setup = unsafe extern "C" fn(*mut c_void, c_int, f64, f64, c_int, f64) -> Status;
type Unary = unsafe extern "C" fn(*mut c_void) -> Status;
type Free = unsafe extern "C" fn(*mut c_void);
type SetReal = unsafe extern "C" fn(*mut c_void, *const u32, usize, *const f64) -> Status;
type GetReal = unsafe extern "C" fn(*mut c_void, *const u32, usize, *mut f64) -> Status;
type DoStep = unsafe extern "C" fn(*mut c_void, f64, f64, c_int) -> Status;

/// The loaded binary's entry points.
#[derive(Debug)]
pub(crate) struct Binary2 {
    _lib: libloading::Library,
    instantiate: Instantiate,
    setup: Setup,
    enter_init: Unary,
    exit_init: Unary,
    terminate: Unary,
    free: Free,
    set_real: SetReal,
    get_real: GetReal,
    do_step: DoStep,
}

impl Binary2 {
    /// Loads `path` and resolves the entry points; the error is the reason.
    pub fn load(path: &Path) -> Result<Arc<Binary2>, String> {
        // SAFETY: as FMI 3.0's (binary.rs): the FMU's binary is the model.
        let lib = unsafe { libloading::Library::new(path) }
            .map_err(|e| format!("binary cannot be loaded: {e}"))?;
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: the symbol's type is FMI 2.0's for that name.
                *unsafe { lib.get(concat!($name, "\0").as_bytes()) }
                    .map_err(|_| format!("binary has no {}", $name))?
            };
        }
        Ok(Arc::new(Binary2 {
            instantiate: sym!("fmi2Instantiate"),
            setup: sym!("fmi2SetupExperiment"),
            enter_init: sym!("fmi2EnterInitializationMode"),
            exit_init: sym!("fmi2ExitInitializationMode"),
            terminate: sym!("fmi2Terminate"),
            free: sym!("fmi2FreeInstance"),
            set_real: sym!("fmi2SetReal"),
            get_real: sym!("fmi2GetReal"),
            do_step: sym!("fmi2DoStep"),
            _lib: lib,
        }))
    }
}

unsafe extern "C" fn log_message(
    env: *mut c_void,
    _name: *const c_char,
    status: Status,
    _category: *const c_char,
    message: *const c_char,
) {
    if env.is_null() || message.is_null() {
        return;
    }
    // SAFETY: `env` is this instance's `Mutex<String>` (alive while it
    // is); `message` is NUL-terminated by FMI's contract.
    let (last, text) = unsafe { (&*(env as *const Mutex<String>), CStr::from_ptr(message)) };
    if let Ok(mut last) = last.lock() {
        *last = format!("[{}] {}", status_name(status), text.to_string_lossy());
    }
}

/// One FMI 2.0 co-simulation instance, initialised, stepping.
#[derive(Debug)]
pub(crate) struct Instance2 {
    bin: Arc<Binary2>,
    ptr: *mut c_void,
    /// FMI 2.0 may keep the callbacks' address: they live as long as the
    /// instance.
    _callbacks: Box<Callbacks>,
    last: Box<Mutex<String>>,
    failed: bool,
}

impl std::fmt::Debug for Callbacks {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Callbacks")
    }
}

// SAFETY: used by one thread at a time (in a Mutex), as FMI 2.0 allows.
unsafe impl Send for Instance2 {}

/// `file:///…` of a directory, as FMI 2.0's resource location.
fn file_uri(dir: &str) -> String {
    let mut s = String::from("file://");
    for c in dir.chars() {
        match c {
            ' ' => s.push_str("%20"),
            '%' => s.push_str("%25"),
            '#' => s.push_str("%23"),
            c => s.push(c),
        }
    }
    s
}

impl Instance2 {
    /// Instantiates, sets the parameters' `starts` and initialises at 0.
    pub fn new(
        bin: &Arc<Binary2>,
        name: &str,
        guid: &str,
        resources: &str,
        starts: &[(u32, f64)],
    ) -> Result<Instance2, FmuError> {
        let call = "fmi2Instantiate";
        let fail = |message: String| FmuError {
            call,
            status: "an error",
            message,
        };
        let c = |s: &str| CString::new(s).map_err(|_| fail("a NUL in a string".into()));
        let (cname, cguid, cres) = (c(name)?, c(guid)?, c(&file_uri(resources))?);
        let last = Box::new(Mutex::new(String::new()));
        let callbacks = Box::new(Callbacks {
            logger: Some(log_message),
            allocate: Some(calloc),
            free: Some(free),
            step_finished: None,
            env: &*last as *const Mutex<String> as *mut c_void,
        });
        // SAFETY: FMI 2.0's contract; the strings live over the call, the
        // callbacks and their environment as long as the instance.
        let ptr = unsafe {
            (bin.instantiate)(
                cname.as_ptr(),
                CO_SIMULATION,
                cguid.as_ptr(),
                cres.as_ptr(),
                &*callbacks,
                0,
                0,
            )
        };
        if ptr.is_null() {
            return Err(fail(last.lock().map(|m| m.clone()).unwrap_or_default()));
        }
        let mut inst = Instance2 {
            bin: Arc::clone(bin),
            ptr,
            _callbacks: callbacks,
            last,
            failed: false,
        };
        for &(vr, v) in starts {
            inst.set(&[vr], &[v])?;
        }
        // SAFETY: a live instance, instantiated (each call below in turn).
        let s = unsafe { (inst.bin.setup)(inst.ptr, 0, 0.0, 0.0, 0, 0.0) };
        inst.check("fmi2SetupExperiment", s)?;
        let s = unsafe { (inst.bin.enter_init)(inst.ptr) };
        inst.check("fmi2EnterInitializationMode", s)?;
        let s = unsafe { (inst.bin.exit_init)(inst.ptr) };
        inst.check("fmi2ExitInitializationMode", s)?;
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
            message: self.last.lock().map(|m| m.clone()).unwrap_or_default(),
        })
    }
}

impl FmuInstance for Instance2 {
    fn set(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), FmuError> {
        debug_assert_eq!(vrs.len(), values.len());
        // SAFETY: a live instance; both slices have `vrs.len()` elements.
        let s = unsafe { (self.bin.set_real)(self.ptr, vrs.as_ptr(), vrs.len(), values.as_ptr()) };
        self.check("fmi2SetReal", s)
    }

    fn get(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), FmuError> {
        debug_assert_eq!(vrs.len(), out.len());
        // SAFETY: a live instance; both slices have `vrs.len()` elements.
        let s = unsafe { (self.bin.get_real)(self.ptr, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
        self.check("fmi2GetReal", s)
    }

    fn step(&mut self, t: f64, h: f64) -> Result<(), FmuError> {
        // SAFETY: a live, initialised instance.
        let s = unsafe { (self.bin.do_step)(self.ptr, t, h, 1) };
        self.check("fmi2DoStep", s)
    }
}

impl Drop for Instance2 {
    fn drop(&mut self) {
        // SAFETY: a live instance, freed once.
        unsafe {
            if !self.failed {
                (self.bin.terminate)(self.ptr);
            }
            (self.bin.free)(self.ptr);
        }
    }
}
