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
//! | [`behaviour`] | what a run did besides its errors: end-stop contacts, saturation share, sustained oscillation |
//! | [`triple`] | serde for the scenarios' `[f64; 3]` keys, naming the length a key takes |
//!
//! Controllers come from [`ehservo_core`]: any [`Controller`](ehservo_core::control::Controller)
//! runs here, its parts logged as named signals.
//!
//! The paper's Fig. 2 run, 10 s, and its metrics (SPEC §9):
//!
//! ```
//! use ehservo_sim::actuator::Actuator;
//! use ehservo_sim::core::prelude::*;
//! use ehservo_sim::metrics::MetricsAccumulator;
//! use ehservo_sim::plant::{Plant, ThirdOrderPlant, UncertaintySpec};
//! use ehservo_sim::sensor::Sensor;
//! use ehservo_sim::simulation::{Mode, SimConfig, Simulation, Stages};
//!
//! // The paper's Fig. 2 case: the NNBVSC on the third-order plant (8) with
//! // Δa_i = |ā_i| and Δb = 0.25·b̄, sampled at 100 Hz, RK4 at 0.01 s.
//! let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
//! let design = Design {
//!     model: *plant.nominal(),
//!     surface: SwitchingSurface::paper(),
//!     dt: 0.01,
//! };
//! let nn = NnVscConfig::default().build(&design)?;
//! let stages = Stages {
//!     uncertainty: UncertaintySpec::default(),
//!     actuator: Actuator::IDENTITY,
//!     sensor: Sensor::identity(),
//!     policy: FaultPolicy::default(),
//!     estimator: None,
//! };
//! let cfg = SimConfig {
//!     steps: 1000,
//!     step: 0.01,
//!     mode: Mode::Sampled,
//!     substeps: 1,
//!     theta_limit: 1.0,
//!     x0: [0.0; 3],
//!     computation_delay: false,
//! };
//! let mut sim = Simulation::new(plant, nn, Sine::paper(), stages, cfg)?;
//!
//! // Horizon 10 s, metrics after the 2-s transient, a 1-s reference period,
//! // a controller with a network (‖W‖ and the dead zone are read).
//! let mut acc = MetricsAccumulator::new(10.0, 2.0, 1.0, true);
//! let outcome = sim.run(&mut |s| acc.push(s));
//! let m = acc.finish(outcome.diverged);
//! assert_eq!(m.samples, 1001); // k = 0..=1000
//! // max |e| over t ≥ 2 s, as two independent implementations of the same
//! // loop print it: shared/peers/c/nnvsc.c and bench/peers/nnvsc_numpy.py.
//! let e_max = m.e_max.expect("samples after the transient");
//! assert!((e_max - 0.2090949957971938).abs() < 1e-9 * e_max, "{e_max}");
//! # Ok::<(), ParamError>(())
//! ```

pub mod accumulator;
pub mod actuator;
pub mod axis;
pub mod behaviour;
pub mod cylinder;
pub mod environment;
pub mod error;
pub mod estimator;
pub mod force;
pub mod hose;
pub mod ifac9007;
pub mod metrics;
pub mod pc_pump;
pub mod physical;
pub mod plant;
pub mod relief;
pub mod sensor;
pub mod simulation;
pub mod supply;
pub mod third_order;
pub mod triple;
pub mod uncertainty;
pub mod valve;

pub use ehservo_core as core;
