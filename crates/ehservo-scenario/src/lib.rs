//! # ehservo-scenario
//!
//! What every way into ehservo needs of a scenario — the command line and
//! the lab (`ehservo`), the C ABI and the FMU (`ehservo-ffi`), the browser
//! (`ehservo-web`) and Python: the file read with clear errors, the
//! registries of plants and controllers, a run, and a loop stepped by a
//! caller. It does no file output and draws nothing; the plants and the
//! simulator are `ehservo-sim`'s, the laws `ehservo-core`'s.
//!
//! | module | role |
//! |---|---|
//! | [`scenario`] | the TOML schema with the paper's defaults, `--set` overrides, validation (file, key, reason); the plant and controller registries; [`Loop`]: a scenario built, once, and the one way into its typed loop |
//! | [`run`] | a [`Loop`] run to its horizon: trace and metrics |
//! | [`stepper`] | a scenario's loop, or its controller alone, stepped one sample at a time by a caller (the C ABI, FMUs) |
//! | [`observer_design`] | design of the linear observers of `ehservo_core::estimate`: discretisation, Luenberger, steady-state Kalman, noise gains |
//! | [`limits`] | the work one run may ask for, counted before any of it |
//! | [`cancel`] | stopping long work from a host that stays alive (Python's Ctrl-C) |
//! | [`error`] | the kinds of error: bad input (exit 2) or a failure of the machine (exit 1) |
//! | [`input`] | reading an input file, bounded, with its name in the error |
//! | [`fmi`] | the FMI 3.0 contract shared by the FMU's writer and its binary: variables, value references, token |

pub mod cancel;
pub mod error;
pub mod fmi;
#[cfg(feature = "fmu-import")]
pub mod fmu_plant;
pub mod input;
pub mod limits;
pub mod observer_design;
pub mod run;
pub mod scenario;
pub mod stepper;

pub use ehservo_sim::{
    actuator, axis, behaviour, metrics, physical, plant, sensor, simulation, third_order,
    uncertainty,
};

pub use ehservo_core as core;
pub use scenario::{Loop, ScenarioError};
