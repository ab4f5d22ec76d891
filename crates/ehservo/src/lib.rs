//! # ehservo
//!
//! Simulation and control of electrohydraulic servo systems, built around
//! C.-L. Hwang's neural-network-based variable structure control (NNBVSC).
//! This crate is the lab and the command line. It stands on three crates
//! that the bindings share without it: the `no_std` laws and servo
//! mathematics ([`ehservo_core`]), the plants and the simulator
//! (`ehservo-sim`, std, no I/O) and the scenario files with their runs
//! (`ehservo-scenario`); their modules are re-exported here under the
//! paths the lab has always used.
//!
//! | module | role |
//! |---|---|
//! | [`plant`], [`actuator`], [`sensor`], [`simulation`], [`metrics`] | the closed loop, from `ehservo-sim` |
//! | [`scenario`], [`run`], [`stepper`], [`observer_design`], [`limits`], [`cancel`], [`error`], [`input`] | the scenario files, their registries of plants and controllers, a run, a loop stepped by a caller, from `ehservo-scenario` |
//! | [`output`] | CSV, JSON and PNG/SVG outputs of a run, written atomically |
//! | [`plot`] | the figures' back end (PNG/SVG), the `ehservo-plot` crate |
//! | [`reproduce`] | the paper's Section IV: cases, claims, figures, report |
//! | [`analysis`] | the paper's analysis: poles, K1/K2, the α bound of Theorem 2 |
//! | [`study`] | sweeps and Monte Carlo, sharded across machines |
//! | [`tune`], [`league`] | controller tuning by particle swarm; every controller of a suite, tuned alike, on every scenario |
//! | [`fmu`] | `ehservo fmu`: the FMI 3.0 model description and archive (the contract it shares with `ehservo-ffi` is `ehservo_scenario::fmi`) |
//! | [`freq`] | `ehservo linearize` and `ehservo freq`: linear models, frequency responses and margins, computed and measured |
//! | [`identify`] | `ehservo excite` and `ehservo identify`: experiments designed, logged data turned into a scenario (docs/identification.md) |
//! | [`pil`] | `ehservo pil`: the controller on a board (QEMU or serial), the rest simulated, in lock-step; `ehservo run --float f32` |
//! | [`schema`] | `ehservo schema`: the file formats' JSON Schemas and reference pages |
//! | [`interrupt`] | the command line's SIGINT/SIGTERM: what was being written is removed |
//! | `cli` | the command line's arguments and commands, one file per family (feature `cli`; `src/main.rs` only parses and dispatches) |

pub mod analysis;
pub mod bisection;
#[cfg(feature = "cli")]
pub mod cli;
pub mod fmu;
pub mod formats;
pub mod freq;
pub mod identify;
pub mod interrupt;
pub mod league;
pub mod output;
#[cfg(not(target_arch = "wasm32"))]
pub mod pil;
/// Figures (PNG/SVG): the `ehservo-plot` crate.
pub use ehservo_plot as plot;
pub mod reproduce;
pub mod schema;
pub mod study;
pub mod tune;

pub use ehservo_sim::{
    actuator, axis, behaviour, metrics, physical, plant, sensor, simulation, third_order,
    uncertainty,
};

pub use ehservo_core as core;

// What every binding needs (the scenario, a run, the stepper), from
// `ehservo-scenario`, under the paths the lab and its users have always read.
pub use ehservo_scenario::{
    bad_input, cancel, error, input, limits, observer_design, run, scenario, stepper,
};
