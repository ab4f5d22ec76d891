//! Get and Set of the FMU's variables: Float64 by value reference (the
//! controller's inputs and outputs, the closed loop's sample), and the
//! other types, of which this FMU has none.

use super::{with, Body, Instance, Phase, Status, OK};
use ehservo_scenario::fmi::{vr, FmuKind};
use std::ffi::{c_char, c_int, c_void};

impl Instance {
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
            FmuKind::Plant => {
                if let Body::Plant {
                    plant,
                    u,
                    f_load,
                    out,
                } = &self.body
                {
                    let states = plant.states();
                    let pressure = |i: usize| states.get(i).filter(|s| s.unit == "Pa").is_some();
                    return match r {
                        vr::THETA | vr::THETA_DOT | vr::THETA_DDOT => {
                            Ok(out.x[(r - vr::THETA) as usize])
                        }
                        vr::U => Ok(*u),
                        vr::U_PLANT => Ok(out.u_plant),
                        vr::F_LOAD if plant.takes_external_load() => Ok(*f_load),
                        _ if r >= vr::PRESSURE && pressure((r - vr::PRESSURE) as usize) => {
                            Ok(out.states[(r - vr::PRESSURE) as usize])
                        }
                        _ => Err(format!("no Float64 variable has value reference {r}")),
                    };
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
            Body::Plant {
                plant,
                u,
                f_load,
                out,
            } if r == vr::U || (r == vr::F_LOAD && plant.takes_external_load()) => {
                let name = if r == vr::U { "u" } else { "f_load" };
                if !v.is_finite() {
                    return Err(format!(
                        "input `{name}` (value reference {r}) must be finite (got {v:?})"
                    ));
                }
                if r == vr::U {
                    *u = v;
                } else {
                    *f_load = v;
                    plant.set_external_load(v);
                }
                *out = plant.output(*u);
                Ok(())
            }
            _ => Err(format!(
                "value reference {r} is not an input of this {} FMU",
                self.kind.as_str()
            )),
        }
    }
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
