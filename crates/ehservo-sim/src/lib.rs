//! # ehservo-sim
//!
//! The closed loop of an electrohydraulic servo, with no I/O: what the
//! command line, the studies and the bindings all run.
//!
//! | module | role |
//! |---|---|
//! | [`plant`] | the "true" plants (third-order and physical) with the parameter variations the controller does not know |
//! | [`cylinder`] | a valve-controlled double-rod cylinder on a rack and pinion, a second plant family |
//! | [`actuator`] | the valve between controller and plant: saturation, rate limit, first-order lag |
//! | [`sensor`] | what the controller measures: bias and quantisation |
//! | [`simulation`] | the resumable loop, continuous and sampled, with its stop reasons |
//! | [`metrics`] | SPEC §9 metrics, computed online |
//!
//! Controllers come from [`ehservo_core`]: any [`Controller`](ehservo_core::control::Controller)
//! runs here, its parts logged as named signals.

pub mod actuator;
pub mod cylinder;
pub mod estimator;
pub mod metrics;
pub mod plant;
pub mod sensor;
pub mod simulation;
pub mod triple;

pub use ehservo_core as core;
