//! # ehservo
//!
//! Simulation and control of electrohydraulic servo systems, built around
//! C.-L. Hwang's neural-network-based variable structure control (NNBVSC).
//! The controllers and the servo mathematics live in the `no_std` crate
//! [`ehservo_core`]; this crate adds what experiments need:
//!
//! | module | role |
//! |---|---|
//! | [`plant`], [`actuator`], [`sensor`], [`simulation`], [`metrics`] | the closed loop, re-exported from `ehservo-sim` (std, no I/O) |
//! | [`scenario`] | TOML scenario files with the paper's defaults and clear errors; the controller registry |
//! | [`run`] | scenario → plant + controller → result |
//! | [`output`], [`plot`] | CSV, JSON and PNG/SVG outputs, written atomically |
//! | [`reproduce`] | the paper's Section IV: cases, claims, figures, report |
//! | [`estimation`] | design of the linear observers of `ehservo_core::estimate`: discretisation, Luenberger, steady-state Kalman, noise gains |
//! | [`study`] | sweeps and Monte Carlo, sharded across machines |
//! | [`tune`], [`league`] | controller tuning by particle swarm; every controller of a suite, tuned alike, on every scenario |
//! | [`stepper`] | a scenario's loop, or its controller alone, stepped one sample at a time by a caller (the C ABI, FMUs) |
//! | [`fmu`] | `ehservo fmu`: the FMI 3.0 model description and archive |
//! | [`identify`] | `ehservo excite` and `ehservo identify`: experiments designed, logged data turned into a scenario (docs/identification.md) |
//! | [`pil`] | `ehservo pil`: the controller on a board (QEMU or serial), the rest simulated, in lock-step; `ehservo run --float f32` |
//! | [`cancel`] | stopping long work from a host that stays alive (Python's Ctrl-C) |
//! | [`limits`] | the work a run, a tune or a league may ask for, counted before any of it |
//! | [`freq`] | `ehservo linearize` and `ehservo freq`: linear models, frequency responses and margins, computed and measured |
//! | `cli` | the command line's arguments and commands, one file per family (feature `cli`; `src/main.rs` only parses and dispatches) |

pub mod analysis;
pub mod bisection;
pub mod cancel;
#[cfg(feature = "cli")]
pub mod cli;
pub mod error;
pub mod estimation;
pub mod fmu;
pub mod freq;
pub mod identify;
pub mod input;
pub mod league;
pub mod limits;
pub mod output;
#[cfg(not(target_arch = "wasm32"))]
pub mod pil;
pub mod plot;
pub mod reproduce;
pub mod run;
pub mod scenario;
pub mod schema;
pub mod signals;
pub mod stepper;
pub mod study;
pub mod tune;

pub use ehservo_sim::{
    actuator, axis, metrics, physical, plant, sensor, simulation, third_order, uncertainty,
};

pub use ehservo_core as core;
