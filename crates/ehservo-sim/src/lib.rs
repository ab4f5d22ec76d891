//! # ehservo-sim
//!
//! The closed loop of an electrohydraulic servo, with no I/O: what the
//! command line, the studies and the bindings all run.
//!
//! | module | role |
//! |---|---|
//! | [`plant`] | the [`Plant`](plant::Plant) trait, what a plant is in a scenario ([`PlantConfig`](plant::PlantConfig)) and the paper's form of the variation |
//! | [`third_order`], [`physical`] | the paper's servo: (8)–(9) and (1)–(6) |
//! | [`uncertainty`] | the variations the controller does not know: the paper's Δa_i/Δb and the physical form, seeded and held |
//! | [`axis`] | rotary (rad, shown in degrees) or linear (m, shown in mm) |
//! | [`cylinder`] | a valve-controlled single- or double-rod cylinder: a linear axis, its load and end stops |
//! | [`valve`], [`supply`], [`force`] | the cylinder's 4/3 valve, its pump or fixed supply, an external force signal |
//! | [`actuator`] | the servo valve between controller and plant: saturation, rate limit, first- or second-order spool dynamics (time constant or bandwidth), dead band, null bias |
//! | [`sensor`] | what the controller measures, and when: which channels, bias, quantisation, seeded noise, a delay |
//! | [`estimator`] | the channels the sensors do not measure, estimated at the controller's rate by one of the core's [`estimate`](ehservo_core::estimate) components (Levant's differentiator, a Luenberger or steady-state Kalman observer) |
//! | [`simulation`] | the resumable loop, continuous and sampled, with its stop reasons |
//! | [`metrics`] | SPEC §9 metrics, computed online |
//! | [`triple`] | serde for the scenarios' `[f64; 3]` keys, naming the length a key takes |
//!
//! Controllers come from [`ehservo_core`]: any [`Controller`](ehservo_core::control::Controller)
//! runs here, its parts logged as named signals.

pub mod actuator;
pub mod axis;
pub mod cylinder;
pub mod error;
pub mod estimator;
pub mod force;
pub mod metrics;
pub mod physical;
pub mod plant;
pub mod sensor;
pub mod simulation;
pub mod supply;
pub mod third_order;
pub mod triple;
pub mod uncertainty;
pub mod valve;

pub use ehservo_core as core;
