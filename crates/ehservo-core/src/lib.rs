//! # ehservo-core
//!
//! The allocation-free, `no_std` mathematics of an electrohydraulic servo
//! controller, after C.-L. Hwang, *Neural-network-based variable structure
//! control of electrohydraulic servosystems subject to huge uncertainties
//! without persistent excitation* (equation numbers `(n)` below are the
//! paper's).
//!
//! | module | what it holds | paper |
//! |---|---|---|
//! | [`servo`] | physical parameters (SI) → coefficients `a1, a2, a3`, the state-dependent gain `b` and load term `d`; the load `Tl` | (1)–(9) |
//! | [`reference`](mod@reference) | the desired trajectory and its first three derivatives `z` | A3, §IV |
//! | [`surface`] | the switching surface `σ`, the error vector `E`, design from poles | (10), (15)–(16) |
//! | [`rbf`] | the modified radial-basis vector `Φ(x, z)` (130 entries) | (20) |
//! | [`control`] | the [`Controller`](control::Controller) trait and every law, each a kind with its [`Config`](control::Config): the paper's traditional VSC (`vsc`, `vsc-sat`) and NNBVSC (`nnvsc`), the NNBVSC with a classical robust weight law (`nn-robust`), and the baselines PID (`pid`), super-twisting (`sta`), ADRC (`adrc`), adaptive robust control (`arc`), adaptive backstepping (`backstepping`) and the open loop of an identification experiment (`open-loop`) | (11)–(14), (23)–(34) |
//! | [`rk4`] | one fixed-step classic Runge–Kutta step over any fixed-size state | §IV |
//! | [`estimate`] | estimators of `(θ, θ̇, θ̈)` from θ: Levant's differentiator, a linear observer | — |
//! | [`sampled`] | a fixed-rate loop for hardware: law + forward-Euler controller state | — |
//! | [`onboard`] | a closed loop that fits on a board: the plant (8) with a constant uncertainty, RK4 in the core's float type, around a sampled controller (the firmware's loop and its host check) | (8) |
//! | [`math`] | [`Real`](math::Real), the float type the core computes in (`f64` or `f32`), and the small scalar helpers the laws share | — |
//! | [`error`] | [`ParamError`](error::ParamError), the core's one error: a parameter rejected at construction | — |
//!
//! Nothing here allocates or touches `std`; `exp` and `sqrt` come from
//! `libm`. Parameters are validated once, at construction (`try_new`), with a
//! small `Copy` error naming the parameter; the control step itself is
//! infallible.
//!
//! The paper's Fig. 2 controller in a few lines: the NNBVSC (`kind =
//! "nnvsc"`, every key at its Fig. 2 value) designed on the paper's servo,
//! stepped at 100 Hz against the reference `5°·sin(2πt)`:
//!
//! ```
//! use ehservo_core::prelude::*;
//!
//! // What the controller is told of the plant: the paper's servo and load.
//! let model = NominalModel::new(ServoParams::paper(), Load::paper());
//! // ā2 as the paper prints it in Section IV.
//! assert!((model.coeffs.a2 - 13000.2711).abs() < 1e-3);
//! let design = Design { model, surface: SwitchingSurface::paper(), dt: 0.01 };
//!
//! let nn = NnVscConfig::default().build(&design)?;
//! let mut ctl = SampledController::new(nn, design.dt)?;
//! let reference = Sine::paper();
//! for k in 0..5 {
//!     let t = k as f64 * design.dt;
//!     // The plant held at rest: x = (θ, θ̇, θ̈) = 0.
//!     let out = ctl.step(t, [0.0; 3], reference.z(t));
//!     assert!(out.u.is_finite());
//!     if k == 0 {
//!         // σ = ë + p1·ė + p2·e + p3·∫e (10) with e = ë = ∫e = 0 at t = 0
//!         // and ė = θ̇d(0) = A·ω: σ = 90·(5π/180)·2π.
//!         let sigma = 90.0 * (5.0 * std::f64::consts::PI / 180.0) * 2.0 * std::f64::consts::PI;
//!         assert!((out.sigma - sigma).abs() < 1e-9);
//!         // The error grows (ė > 0): the command pushes forward.
//!         assert!(out.u > 0.0);
//!     }
//! }
//! // The weights learned from the first samples (W(0) = 0).
//! assert!(ctl.state().w.iter().any(|&w| w != 0.0));
//! # Ok::<(), ParamError>(())
//! ```
//!
//! Around a plant: [`onboard::Fig2Loop`] closes the same loop on the
//! plant (8) with Fig. 2's uncertainty, as a board runs it; the simulator
//! with its actuator, sensors and metrics is the crate `ehservo-sim`.
#![cfg_attr(not(any(test, feature = "std")), no_std)]

pub mod control;
pub mod error;
pub mod estimate;
pub mod math;
pub mod onboard;
pub mod rbf;
pub mod reference;
pub mod rk4;
pub mod sampled;
pub mod servo;
pub mod solver;
pub mod surface;

/// The names most users need, in one import.
pub mod prelude {
    pub use crate::control::nnvsc::{MuRule, NnState, NnVsc, NnVscParams};
    pub use crate::control::sliding::{
        NnVscConfig, SlidingConfig, SlidingParts, VscConfig, VscSatConfig,
    };
    pub use crate::control::vsc::{Switching, Vsc, VscParams};
    pub use crate::control::{
        Config, Controller, Design, Measurement, Output, Signal, Signals, Truth, Tunable,
    };
    pub use crate::error::ParamError;
    pub use crate::estimate::{Estimator, Levant, LinearObserver};
    pub use crate::rbf::{Rbf, N_KERNELS, N_PHI};
    pub use crate::reference::{Reference, Sine};
    pub use crate::rk4::{rk4_step, OdeState};
    pub use crate::sampled::{FaultPolicy, Limits, SafeCommand, SampledController};
    pub use crate::servo::{Coefficients, Friction, Load, NominalModel, ServoParams};
    pub use crate::surface::{SurfaceState, SwitchingSurface};
}
