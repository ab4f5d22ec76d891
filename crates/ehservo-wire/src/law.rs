//! Any kind's sampled controller in the float type `F`, built from a
//! [`Hello`]: what the board steps, and what a host steps to compute the
//! board's bits ([`crate::board::Board`] runs on both).
//!
//! The controller is designed in f64 (`Config::build`, as the simulator
//! designs it), then cast to `F` (its constants recomputed in `F`) and put
//! in a [`SampledController`] with the scenario's fault policy in `F`.

use crate::config::WireController;
use crate::msg::{Hello, MAX_PARTS};
use ehservo_core::control::{flags, Config, Controller, Design, Output, Signal, Signals, Truth};
use ehservo_core::error::ParamError;
use ehservo_core::math::Real;
use ehservo_core::rk4::OdeState;
use ehservo_core::sampled::{FaultPolicy, Limits, SafeCommand, SampledController, Sampling};
use ehservo_core::servo::NominalModel;
use ehservo_core::surface::SwitchingSurface;
use heapless::Vec;

/// The flags of a step whose command is the fault policy's.
pub const FAULT_FLAGS: u8 =
    flags::MEASUREMENT_FAULT | flags::NON_FINITE_CONTROL | flags::NON_FINITE_STATE;

/// A step timer: the board's SysTick or DWT, the host's none.
pub trait Ticks {
    /// A reading to pass to [`Ticks::since`].
    fn now(&mut self) -> u32;
    /// Ticks elapsed since `start`.
    fn since(&mut self, start: u32) -> u32;
}

/// No timer (ticks are 0).
pub struct NoTicks;

impl Ticks for NoTicks {
    fn now(&mut self) -> u32 {
        0
    }
    fn since(&mut self, _start: u32) -> u32 {
        0
    }
}

/// What a board knows of the true plant: nothing. Its lumped-uncertainty
/// diagnostic is 0 here and filled on the host ([`AnyLaw::annotate_host`]).
struct NoPlant;

impl Truth for NoPlant {
    fn lumped_uncertainty(&self, _u: f64, _u_eq: f64, _b_bar: f64) -> f64 {
        0.0
    }
}

/// A truth that answers `v` whatever it is asked (the probe of
/// [`AnyLaw::truth_slots`]).
struct Constant(f64);

impl Truth for Constant {
    fn lumped_uncertainty(&self, _u: f64, _u_eq: f64, _b_bar: f64) -> f64 {
        self.0
    }
}

/// One step's result.
#[derive(Debug, Clone, PartialEq)]
pub struct Stepped<F> {
    /// The command (V).
    pub u: F,
    /// The step's flags.
    pub flags: u8,
    /// Timer ticks of `SampledController::step`.
    pub ticks: u32,
    /// The parts, in `Signals::SIGNALS` order (plant-dependent diagnostics
    /// as with a plant that answers 0).
    pub parts: Vec<F, MAX_PARTS>,
}

macro_rules! any_law {
    ($($variant:ident $name:literal => $ty:ty),* $(,)?) => {
        /// A kind's controller in the sampled loop, in `F`: one variant
        /// per line of [`ehservo_core::controller_kinds!`].
        #[derive(Clone)]
        pub enum AnyLaw<F: Real> {
            $(
                #[doc = concat!("`kind = \"", $name, "\"`.")]
                $variant(SampledController<<$ty as Config>::Law<F>, F>),
            )*
        }

        impl<F: Real> AnyLaw<F> {
            /// The parts' signals.
            pub fn signals(&self) -> &'static [Signal] {
                match self {
                    $(Self::$variant(_) => <<<$ty as Config>::Law<F> as Controller<F>>::Parts as Signals>::SIGNALS,)*
                }
            }

            /// One step of the sampled loop at `t` with measurement `x` and
            /// reference `z`, timed by `clock`; returns the result and the
            /// loop as it was before the step (whose state the law saw: the
            /// diagnostics are computed with it, and the board goes back to
            /// it if the host does not use the reply).
            pub fn step<T: Ticks>(&mut self, t: F, x: [F; 3], z: [F; 4], clock: &mut T) -> (Stepped<F>, AnyLaw<F>) {
                match self {
                    $(Self::$variant(c) => {
                        let (r, saw) = step_one(c, t, x, z, clock);
                        (r, Self::$variant(saw))
                    })*
                }
            }

            /// Steps that returned the safe command.
            pub fn fault_count(&self) -> u64 {
                match self {
                    $(Self::$variant(c) => c.fault_count(),)*
                }
            }

            /// Whether the controller has network weights.
            pub fn has_network(&self) -> bool {
                match self {
                    $(Self::$variant(c) => !c.controller().weights(c.state()).is_empty(),)*
                }
            }

            /// The signals whose value depends on what the true plant
            /// answers (the lumped uncertainty): found by annotating one
            /// output twice, with a plant answering 0 and one answering 1.
            pub fn truth_slots(&self) -> [bool; MAX_PARTS] {
                match self {
                    $(Self::$variant(c) => probe(c.controller()),)*
                }
            }

            /// Whether this kind's parts can be rebuilt on the host
            /// ([`Signals::rebuild`]).
            pub fn rebuilds(&self) -> bool {
                let zeros = [F::ZERO; MAX_PARTS];
                match self {
                    $(Self::$variant(_) => <<<$ty as Config>::Law<F> as Controller<F>>::Parts as Signals>::rebuild(&zeros).is_some(),)*
                }
            }

            /// Fills the signals of `slots` (from [`AnyLaw::truth_slots`])
            /// in `values` as the kind's `annotate` computes them with
            /// `truth`, from the other values (the law's parts as the board
            /// sent them) and the command `u`. Values outside `slots` are
            /// left as they are. Nothing happens for a kind without such
            /// signals.
            pub fn annotate_host(&self, u: F, flags: u8, values: &mut [F], slots: &[bool; MAX_PARTS], truth: &dyn Truth) {
                match self {
                    $(Self::$variant(c) => fill_truth(c.controller(), u, flags, values, slots, truth),)*
                }
            }

            /// The kind of `controller` built in `F` on `design`, in its
            /// sampled loop.
            fn of(
                controller: &WireController,
                design: &Design,
                sampling: Sampling<F>,
            ) -> Result<Self, ParamError> {
                Ok(match controller {
                    $(WireController::$variant(c) => {
                        Self::$variant(SampledController::sampled(c.build_in::<F>(design)?, sampling))
                    })*
                })
            }
        }
    };
}

ehservo_core::controller_kinds!(any_law);

impl<F: Real> AnyLaw<F> {
    /// The controller a [`Hello`] describes, in `F`. The errors are the
    /// core's, naming the parameter.
    pub fn build(h: &Hello) -> Result<Self, ParamError> {
        let model = NominalModel::try_new(h.model.params, h.model.load)?;
        let model = NominalModel::with_offset(model.params, model.load, h.model.offset);
        let surface = SwitchingSurface::try_new(h.surface)?;
        let design = Design {
            model,
            surface,
            dt: h.dt,
        };
        let policy = FaultPolicy::<F> {
            safe: if h.policy.hold_last {
                SafeCommand::HoldLast
            } else {
                SafeCommand::Zero
            },
            limits: Limits {
                x: h.policy.limits_x,
                u: h.policy.limit_u,
            }
            .cast(),
        };
        let sampling = Sampling::try_new(F::of(h.dt), policy)?;
        Self::of(&h.controller, &design, sampling)
    }
}

/// `SampledController::step` timed, its diagnostics filled as the
/// simulator fills them (with the state the law saw, on good steps only)
/// but with a plant that answers 0.
#[inline(never)]
fn step_one<C, F, T>(
    c: &mut SampledController<C, F>,
    t: F,
    x: [F; 3],
    z: [F; 4],
    clock: &mut T,
) -> (Stepped<F>, SampledController<C, F>)
where
    C: Controller<F> + Clone,
    F: Real,
    T: Ticks,
{
    let saw = c.clone();
    let t0 = clock.now();
    let mut o = c.step(t, x, z);
    let ticks = clock.since(t0);
    if o.flags & FAULT_FLAGS == 0 {
        saw.controller()
            .annotate_stepped(saw.state(), &mut o, &NoPlant);
    }
    let n = C::Parts::SIGNALS.len().min(MAX_PARTS);
    let mut wide = [0.0f64; MAX_PARTS];
    o.parts.write(&mut wide[..n]);
    let mut parts = Vec::new();
    for &v in &wide[..n] {
        // Every value was an F, widened by write: exact both ways.
        let _ = parts.push(F::of(v));
    }
    (
        Stepped {
            u: o.u,
            flags: o.flags,
            ticks,
            parts,
        },
        saw,
    )
}

/// See [`AnyLaw::truth_slots`].
fn probe<C: Controller<F>, F: Real>(c: &C) -> [bool; MAX_PARTS] {
    let zero = C::State::zero();
    let n = C::Parts::SIGNALS.len().min(MAX_PARTS);
    let mut vals = [[0.0f64; MAX_PARTS]; 2];
    for (i, v) in [0.0, 1.0].into_iter().enumerate() {
        let mut o = Output::<C::Parts, F>::default();
        c.annotate(&zero, &mut o, &Constant(v));
        o.parts.write(&mut vals[i][..n]);
    }
    core::array::from_fn(|i| i < n && vals[0][i].to_bits() != vals[1][i].to_bits())
}

/// See [`AnyLaw::annotate_host`].
fn fill_truth<C, F>(
    c: &C,
    u: F,
    flags: u8,
    values: &mut [F],
    slots: &[bool; MAX_PARTS],
    truth: &dyn Truth,
) where
    C: Controller<F>,
    F: Real,
{
    if !slots.iter().any(|&s| s) {
        return;
    }
    let Some(parts) = C::Parts::rebuild(values) else {
        return;
    };
    let mut o = Output { u, flags, parts };
    // The diagnostics that need the plant do not read the state (the
    // others do, and are the board's: only `slots` are taken from here).
    c.annotate(&C::State::zero(), &mut o, truth);
    let n = C::Parts::SIGNALS.len().min(MAX_PARTS).min(values.len());
    let mut wide = [0.0f64; MAX_PARTS];
    o.parts.write(&mut wide[..n]);
    for i in 0..n {
        if slots[i] {
            values[i] = F::of(wide[i]);
        }
    }
}
