//! Controllers as dynamic systems, and the one interface every controller
//! meets.
//!
//! A controller has a configuration (gains, surface, network) and a state ξ
//! (∫e, and for the NNBVSC the weights W). It is evaluated as
//! `u = h(t, ξ, x, z)` with `ξ̇ = f(t, ξ, x, z)` by [`Controller::law`], which
//! returns `u` and the parts of its law ([`Output`]) and writes ξ̇. It never
//! integrates itself: the simulator (continuous or sampled) or
//! [`crate::sampled::SampledController`] (hardware) decides how ξ advances.
//!
//! **Parts are named signals.** Each controller declares its own parts type
//! (`Controller::Parts`), as a PID has p, i and d: a plain `Copy` struct that
//! lists its signals with units ([`Signals::SIGNALS`]) and writes their
//! values in that order ([`Signals::write`]). Traces, plots and bindings read
//! them generically, by key. [`Output`] dereferences to its parts, so
//! `out.sigma` reads the σ of a sliding-mode law.
//!
//! **Configuration as data.** Each controller kind has a parameter type that
//! implements [`Config`]: its kind name, whether it uses the switching
//! surface, and how to build the controller from the [`Design`] context (the
//! nominal model, the surface, the sample period). With the `serde` feature
//! these parameter types are (de)serialisable: a scenario's `[controller]`
//! table is exactly one of them.
//!
//! **The sign of the valve.** The sliding-mode laws divide by the nominal
//! gain `b̄(t) = b(x, sgn u)`, which itself depends on `sgn(u)` through the
//! valve root (2). The circle is exact to break: with `β = bound_b·b̄`, the
//! product `v = b̄·u` does not depend on `b̄` (for (11)–(14):
//! `v = N + sgn(σ)·[Σα_i|x_i| + γ + bound_b·|N|]/(1 − bound_b)`; for
//! (23)–(25): `v = N + WᵀΦ + [γ1σΔ + γ2σΔ/(|σΔ| + μ)]/(1 − bound_b)`), and
//! `b̄ > 0`, so `sgn(u) = sgn(v)`; then `b̄ = b(x, sgn v)` and `u = v/b̄`
//! ([`crate::servo::NominalModel::gain_for`]).

pub mod adrc;
pub mod arc;
pub mod backstepping;
pub mod force_pi;
/// Serde for an enum written in scenarios by name: `as_str` out, `parse`
/// in, and the names listed in the error for anything else.
#[cfg(feature = "serde")]
macro_rules! serde_by_name {
    ($t:ty, $expecting:literal, $names:expr) => {
        impl serde::Serialize for $t {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(self.as_str())
            }
        }

        impl<'de> serde::Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                struct V;
                impl serde::de::Visitor<'_> for V {
                    type Value = $t;
                    fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
                        f.write_str($expecting)
                    }
                    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<$t, E> {
                        <$t>::parse(v).ok_or_else(|| E::unknown_variant(v, &$names))
                    }
                }
                d.deserialize_str(V)
            }
        }

        #[cfg(feature = "schema")]
        impl schemars::JsonSchema for $t {
            fn schema_name() -> std::borrow::Cow<'static, str> {
                stringify!($t).into()
            }
            fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
                schemars::json_schema!({
                    "type": "string",
                    "enum": $names,
                })
            }
        }
    };
}

pub mod nn_robust;
pub mod nnvsc;
pub mod open_loop;
pub mod pid;
pub mod sliding;
pub mod sta;
pub mod state_feedback;
pub mod vsc;

use crate::error::ParamError;
use crate::math::Real;
use crate::rk4::OdeState;
use crate::servo::NominalModel;
use crate::surface::SwitchingSurface;

/// A parameter of a controller kind that a tuner may search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tunable {
    /// Its key in `[controller]`.
    pub key: &'static str,
    /// Lowest value searched.
    pub low: f64,
    /// Highest value searched.
    pub high: f64,
    /// Searched on a log scale (then `0 < low`).
    pub log: bool,
}

impl Tunable {
    /// A parameter searched on a log scale over `[low, high]`.
    pub const fn log(key: &'static str, low: f64, high: f64) -> Self {
        Self {
            key,
            low,
            high,
            log: true,
        }
    }

    /// A parameter searched on a linear scale over `[low, high]`.
    pub const fn linear(key: &'static str, low: f64, high: f64) -> Self {
        Self {
            key,
            low,
            high,
            log: false,
        }
    }
}

/// What the controller measures at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Measurement<T = f64> {
    /// Time (s).
    pub t: T,
    /// x = (θm, θ̇m, θ̈m) (rad, rad/s, rad/s²); Assumption A4.
    pub x: [T; 3],
    /// z = (θd, θ̇d, θ̈d, θ⃛d); Assumption A3.
    pub z: [T; 4],
}

/// Flags a law may raise (bit set in [`Output::flags`]).
///
/// ```
/// use ehservo_core::control::flags;
///
/// // One bit each: a sample's flags say every reason at once.
/// let bits = flags::ALL.iter().fold(0u8, |acc, &(_, bit, _)| {
///     assert_eq!(bit.count_ones(), 1);
///     assert_eq!(acc & bit, 0);
///     acc | bit
/// });
/// assert_eq!(bits, 0b111_1111);
/// ```
pub mod flags {
    /// The valve root of (2) had a negative argument and was clamped at 0;
    /// the nominal gain b̄ was floored to keep u finite.
    pub const VALVE_ROOT_CLAMPED: u8 = 1;
    /// ‖E‖ = 0: σΔ, μ and ξ were set to 0 (no division by ‖E‖).
    pub const ZERO_ERROR_NORM: u8 = 2;
    /// A measurement was non-finite or out of its plausible range: the safe
    /// command was returned and the state left alone
    /// ([`crate::sampled::SampledController`]).
    pub const MEASUREMENT_FAULT: u8 = 4;
    /// The law produced a non-finite u: the safe command was returned and
    /// the state left alone.
    pub const NON_FINITE_CONTROL: u8 = 8;
    /// u was clamped to the valve range (or a controller's own output limit).
    pub const SATURATED: u8 = 16;
    /// The state update ξ + dt·ξ̇ was non-finite: the safe command was
    /// returned and the state left alone.
    pub const NON_FINITE_STATE: u8 = 32;
    /// The command of an off-board controller (processor-in-the-loop) did
    /// not arrive usable: a corrupted, dropped or late frame, or a board
    /// that reset. The fault policy's safe command was applied instead and
    /// the board's state left as it was before the sample
    /// (`crates/ehservo-wire`, `ehservo pil`).
    pub const LINK_FAULT: u8 = 64;

    /// Every flag as (name, value, meaning), in bit order: what the C
    /// header's `EHSERVO_FLAG_*` constants and the documentation
    /// (docs/flags.md) are checked against.
    pub const ALL: [(&str, u8, &str); 7] = [
        (
            "VALVE_ROOT_CLAMPED",
            VALVE_ROOT_CLAMPED,
            "the valve root of (2) had a negative argument and was clamped at 0",
        ),
        (
            "ZERO_ERROR_NORM",
            ZERO_ERROR_NORM,
            "‖E‖ = 0: σΔ, μ and ξ were set to 0",
        ),
        (
            "MEASUREMENT_FAULT",
            MEASUREMENT_FAULT,
            "a measurement was non-finite or beyond its limit: the safe command was returned",
        ),
        (
            "NON_FINITE_CONTROL",
            NON_FINITE_CONTROL,
            "the law produced a non-finite u: the safe command was returned",
        ),
        (
            "SATURATED",
            SATURATED,
            "u was clamped to the valve range (or the controller's output limit)",
        ),
        (
            "NON_FINITE_STATE",
            NON_FINITE_STATE,
            "the state update was non-finite: the safe command was returned",
        ),
        (
            "LINK_FAULT",
            LINK_FAULT,
            "an off-board controller's command did not arrive usable (processor-in-the-loop): the safe command was applied",
        ),
    ];
}

/// One named signal of a controller's parts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Signal {
    /// The key code looks it up by (`"sigma"`, `"p"`).
    pub key: &'static str,
    /// Its column in `trace.csv`, unit included (`"sigma_rad_s2"`); empty
    /// when the signal is kept in memory but not written.
    pub column: &'static str,
    /// Its unit, for people (`"rad/s²"`; empty when dimensionless).
    pub unit: &'static str,
    /// One line on what it is.
    pub doc: &'static str,
}

impl Signal {
    /// A signal written to traces under `column`.
    pub const fn new(
        key: &'static str,
        column: &'static str,
        unit: &'static str,
        doc: &'static str,
    ) -> Self {
        Self {
            key,
            column,
            unit,
            doc,
        }
    }
}

/// A controller's parts as named signals.
///
/// ```
/// use ehservo_core::control::pid::PidParts;
/// use ehservo_core::control::Signals;
///
/// let parts = PidParts { p: 0.5, i: 0.25, d: -0.125, ff: 1.0, u_unsat: 1.625 };
/// let mut values = [0.0; 5];
/// parts.write(&mut values);
/// // Read by key, as a trace or a binding does, knowing no field.
/// let at = |key: &str| PidParts::<f64>::SIGNALS.iter().position(|s| s.key == key).unwrap();
/// assert_eq!(values[at("i")], 0.25);
/// assert_eq!(PidParts::<f64>::SIGNALS[at("i")].column, "i_V");
/// ```
pub trait Signals: Copy + Default {
    /// The signals, in the order [`Signals::write`] writes them.
    const SIGNALS: &'static [Signal];
    /// Writes the values in the order of [`Signals::SIGNALS`];
    /// `out.len() >= SIGNALS.len()`.
    fn write(&self, out: &mut [f64]);
    /// The parts whose [`Signals::write`] gives `v` (its inverse), for a
    /// host that fills, from a board's values, the diagnostics that need
    /// the true plant (`ehservo-wire`). `None` (the default): this kind's
    /// parts are not rebuilt, because none of its diagnostics needs the
    /// plant.
    fn rebuild<F: Real>(_v: &[F]) -> Option<Self> {
        None
    }
}

/// No parts at all.
impl Signals for () {
    const SIGNALS: &'static [Signal] = &[];
    fn write(&self, _out: &mut [f64]) {}
}

/// The result of a law at one instant: the command, the law's flags and its
/// parts. Dereferences to the parts.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Output<P, T = f64> {
    /// Control voltage u (V).
    pub u: T,
    /// Bit set of [`flags`].
    pub flags: u8,
    /// The parts of the law.
    pub parts: P,
}

impl<P, T> core::ops::Deref for Output<P, T> {
    type Target = P;
    fn deref(&self) -> &P {
        &self.parts
    }
}

impl<P, T> core::ops::DerefMut for Output<P, T> {
    fn deref_mut(&mut self) -> &mut P {
        &mut self.parts
    }
}

/// What the simulator knows of the true plant at a sample, for the
/// diagnostics a law may log (never for the law itself).
pub trait Truth {
    /// The part of θ⃛ the nominal model misses when the law's equivalent
    /// control is `u_eq` with nominal gain `b_bar` and the applied command
    /// is `u`: `Σ Δa_i x_i − Δb·u_eq + d` of (19), without ξ.
    fn lumped_uncertainty(&self, u: f64, u_eq: f64, b_bar: f64) -> f64;
}

/// A control law with state, computing in the float type `T` (f64 by
/// default; f32 on a board's single-precision FPU).
///
/// A law is a dynamic system that never integrates itself: `law` returns
/// u and writes ξ̇; the caller (the simulator, or
/// [`SampledController`](crate::sampled::SampledController)) advances ξ.
///
/// ```
/// use ehservo_core::control::{Controller, Measurement, Output};
///
/// /// u = kp·e + ξ with ξ̇ = ki·e: a PI law, e = θd − θ.
/// struct Pi { kp: f64, ki: f64 }
///
/// impl Controller for Pi {
///     type State = [f64; 1];
///     type Parts = ();
///     fn initial_state(&self) -> [f64; 1] {
///         [0.0]
///     }
///     fn law(&self, m: &Measurement, s: &[f64; 1], ds: &mut [f64; 1]) -> Output<()> {
///         let e = m.z[0] - m.x[0];
///         ds[0] = self.ki * e;
///         Output { u: self.kp * e + s[0], flags: 0, parts: () }
///     }
/// }
///
/// let c = Pi { kp: 2.0, ki: 10.0 };
/// let m = Measurement { t: 0.0, x: [0.1, 0.0, 0.0], z: [0.3, 0.0, 0.0, 0.0] };
/// // e = 0.2 with ξ = 0.5: u = 2·0.2 + 0.5 = 0.9, ξ̇ = 10·0.2 = 2.
/// let mut ds = [0.0];
/// let out = c.law(&m, &[0.5], &mut ds);
/// assert!((out.u - 0.9).abs() < 1e-12 && (ds[0] - 2.0).abs() < 1e-12);
/// // The law and a forward-Euler step at dt = 0.01: ξ + dt·ξ̇ = 0.5 + 0.02.
/// let mut next = [0.0];
/// let (_, finite) = c.law_euler(&m, &[0.5], &mut next, 0.01);
/// assert!(finite && (next[0] - 0.52).abs() < 1e-12);
/// ```
pub trait Controller<T: Real = f64> {
    /// The controller state ξ.
    type State: OdeState<T>;
    /// The parts of the law, as named signals.
    type Parts: Signals;

    /// ξ(0).
    fn initial_state(&self) -> Self::State;

    /// ξ(0) for a loop that starts at the state `x` = (θ, θ̇, θ̈) (the
    /// scenario's `x0`): a law with an observer of the output (the ADRC's
    /// ESO) starts it there, not at zero, so that a cylinder started
    /// mid-stroke is not kicked by an observer error of its whole position.
    /// By default [`initial_state`](Controller::initial_state).
    fn initial_state_at(&self, x: &[T; 3]) -> Self::State {
        let _ = x;
        self.initial_state()
    }

    /// Evaluates the law at measurement `m` and state `s`; writes ξ̇ into
    /// `ds`. Infallible and allocation-free.
    fn law(
        &self,
        m: &Measurement<T>,
        s: &Self::State,
        ds: &mut Self::State,
    ) -> Output<Self::Parts, T>;

    /// The law followed by a forward-Euler step of the state: writes
    /// `s + dt·ξ̇` into `next` (each component as [`OdeState::euler_from`]
    /// computes it, except where [`crate::math::Real::FOLDED_EULER`]
    /// applies: f32's NNBVSC weights) and returns the output and whether
    /// every component of `next` is finite. `next` is scratch: it is
    /// written whatever the outcome. The default zeroes `next`, calls
    /// [`Controller::law`] into it and steps in place; a controller may
    /// skip the zeroing or fuse the two (the NNBVSC skips it, and on a
    /// Cortex-M, or in f32, writes ξ + dt·ξ̇ in one pass).
    #[inline]
    fn law_euler(
        &self,
        m: &Measurement<T>,
        s: &Self::State,
        next: &mut Self::State,
        dt: T,
    ) -> (Output<Self::Parts, T>, bool) {
        *next = Self::State::zero();
        let out = self.law(m, s, next);
        let finite = next.euler_from(s, dt);
        (out, finite)
    }

    /// The network weights in `s` (empty for controllers without any).
    fn weights<'a>(&self, _s: &'a Self::State) -> &'a [T] {
        &[]
    }

    /// Fills the parts that are diagnostics rather than law (a weight norm,
    /// the uncertainty the network should learn) once per logged sample,
    /// with the state the law saw and what the simulator knows of the true
    /// plant. The default does nothing.
    fn annotate(&self, _s: &Self::State, _out: &mut Output<Self::Parts, T>, _truth: &dyn Truth) {}

    /// [`Controller::annotate`] for an output of [`Controller::law_euler`]
    /// (the sampled loop, [`crate::sampled::SampledController::step_with`]):
    /// a diagnostic that `law_euler` already filled is kept (the NNBVSC's
    /// ‖W‖, computed beside its Euler pass on hosts). The same values as
    /// `annotate`; the default calls it.
    #[inline]
    fn annotate_stepped(
        &self,
        s: &Self::State,
        out: &mut Output<Self::Parts, T>,
        truth: &dyn Truth,
    ) {
        self.annotate(s, out, truth);
    }
}

/// What a controller is designed from besides its own parameters.
///
/// ```
/// use ehservo_core::prelude::*;
///
/// let design = Design {
///     model: NominalModel::new(ServoParams::paper(), Load::paper()),
///     surface: SwitchingSurface::paper(),
///     dt: 0.01,
/// };
/// let nn = NnVscConfig::default().build(&design)?;
/// assert_eq!(nn.surface().p(), [90.0, 2600.0, 24000.0]);
/// // The same context for a board's f32 build.
/// let board: Design<f32> = design.cast();
/// assert_eq!(board.dt, 0.01f32);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Design<T: Real = f64> {
    /// The nominal model (what the controller is told of the plant).
    pub model: NominalModel<T>,
    /// The switching surface (for the laws that use one).
    pub surface: SwitchingSurface<T>,
    /// The sample period (s) of the loop the controller runs in.
    pub dt: T,
}

impl<T: Real> Design<T> {
    /// The same context in another float type.
    pub fn cast<U: Real>(&self) -> Design<U> {
        Design {
            model: self.model.cast(),
            surface: self.surface.cast(),
            dt: U::of(self.dt.to_f64()),
        }
    }
}

/// A controller kind's parameters: what a scenario's `[controller]` table
/// holds, and how to build the controller from it.
///
/// ```
/// use ehservo_core::control::pid::PidConfig;
/// use ehservo_core::control::sliding::{NnVscConfig, VscSatConfig};
/// use ehservo_core::control::{Config, Controller, Design, Measurement};
/// use ehservo_core::prelude::{Load, NominalModel, ServoParams, SwitchingSurface};
///
/// // Any kind, by its parameter type: build, then one evaluation of the law.
/// fn first_command<C: Config>(cfg: &C, design: &Design, m: &Measurement) -> f64 {
///     let ctl = cfg.build(design).expect("valid parameters");
///     let s = ctl.initial_state();
///     let mut ds = s;
///     ctl.law(m, &s, &mut ds).u
/// }
///
/// let design = Design {
///     model: NominalModel::new(ServoParams::paper(), Load::paper()),
///     surface: SwitchingSurface::paper(),
///     dt: 0.01,
/// };
/// assert_eq!((PidConfig::KIND, PidConfig::USES_SURFACE), ("pid", false));
/// assert_eq!((NnVscConfig::KIND, VscSatConfig::KIND), ("nnvsc", "vsc-sat"));
/// // At rest on the reference θd ≡ 0 there is nothing to correct: u = 0.
/// let rest = Measurement::default();
/// assert_eq!(first_command(&PidConfig::default(), &design, &rest), 0.0);
/// assert_eq!(first_command(&NnVscConfig::default(), &design, &rest), 0.0);
/// ```
pub trait Config {
    /// The kind's name in a scenario (`controller.kind`).
    const KIND: &'static str;
    /// Whether the law uses the switching surface (`[surface]`).
    const USES_SURFACE: bool;
    /// The parameters a tuner may search, with their ranges: what
    /// `ehservo tune` varies when the tune file names none. Empty: nothing
    /// to tune.
    const TUNABLE: &'static [Tunable] = &[];
    /// Whether the law closes a force or load-pressure loop (it measures
    /// x = (q, ẏ, ÿ), `[reference] quantity`), not a position loop. A
    /// scenario pairs each kind with its kind of loop. Default false.
    const CLOSES_ON_FORCE: bool = false;
    /// The controller built: plain data, so it can be moved to (and shared
    /// with) another thread (a Python `Controller` stepped from a thread).
    type Controller: Controller<State: Send + Sync> + Clone + Send + Sync;
    /// The same controller computing in the float type `F` (a board's
    /// `f32`): what [`Config::build_in`] gives.
    type Law<F: Real>: Controller<F> + Clone;
    /// Checks every parameter (all of them, whether or not this law reads
    /// them) and builds the controller; the error names the parameter.
    fn build(&self, design: &Design) -> Result<Self::Controller, ParamError>;
    /// The controller designed in f64 ([`Config::build`], as the simulator
    /// designs it), then cast to `F` with its constants recomputed in `F`:
    /// what a board runs (`ehservo-wire`'s `AnyLaw`).
    fn build_in<F: Real>(&self, design: &Design) -> Result<Self::Law<F>, ParamError>;
    /// The law as a linear system while its output limit does not act
    /// ([`LinearForm`]), for the frequency domain; `None` (the default):
    /// the law is nonlinear, and `ehservo linearize` refuses it by its kind.
    fn linear(&self, _design: &Design) -> Option<Result<LinearForm, ParamError>> {
        None
    }
    /// These parameters with the values the design derives written out
    /// (the PID's gains from its poles, the ADRC's bandwidths from the
    /// axis, …): what `ehservo check` shows as designed, and what `tune`
    /// reports when it keeps a kind's defaults. Building from the result
    /// gives the same controller on the same design. `None` (the default):
    /// the kind derives nothing it reports.
    fn designed(&self, _design: &Design) -> Option<Result<Self, ParamError>>
    where
        Self: Sized,
    {
        None
    }
}

/// A linear law's gains, in the form the frequency domain builds its
/// state-space model from (`ehservo::freq::controllers`, whose module doc
/// gives the equations). Each variant is one family of linear laws;
/// another linear kind returns the form it belongs to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LinearForm {
    /// `u = ff + kp·(θd − θm) + I + kd·(θ̇d − (θm − θf)/tf)`,
    /// `İ = ki·(θd − θm)`, `θ̇f = (θm − θf)/tf`, with the reference
    /// feed-forward `ff = Σ feedforward[i]·z[i]` (z = θd, θ̇d, θ̈d, θ⃛d).
    Pid {
        /// Proportional gain (V/rad).
        kp: f64,
        /// Integral gain (V/(rad·s)).
        ki: f64,
        /// Derivative gain (V·s/rad).
        kd: f64,
        /// Derivative filter's time constant (s).
        tf: f64,
        /// The feed-forward's weights of θd, θ̇d, θ̈d, θ⃛d.
        feedforward: [f64; 4],
        /// The output limit under which the law is linear (V; infinite: none).
        u_limit: f64,
    },
    /// A linear extended-state observer with inputs (θm, u) and the static
    /// law `u = (k·(z_d − ẑ) + θ⃛d − z4 + a·ẑ)/b0` (the ADRC).
    Eso {
        /// Feedback gains k1, k2, k3.
        k: [f64; 3],
        /// Observer gains β1..β4.
        beta: [f64; 4],
        /// The input gain b0 the observer assumes.
        b0: f64,
        /// The nominal a1, a2, a3 the observer and law use (0 without a model).
        a: [f64; 3],
        /// The output limit under which the law is linear (V; infinite: none).
        u_limit: f64,
    },
    /// Full state feedback on the measured `x = (θm, θ̇m, θ̈m)` with an
    /// integral I (`control/state_feedback.rs`):
    /// `v = ff·z + k3·(θ̈d − θ̈m) + k2·(θ̇d − θ̇m) + k1·(θd − θm) + I`,
    /// `İ = ki·(θd − θm)`, `u = v/b0`.
    StateFeedback {
        /// `[k3, k2, k1, ki]`.
        k: [f64; 4],
        /// The feed-forward's weights of θd, θ̇d, θ̈d, θ⃛d (in v's units).
        feedforward: [f64; 4],
        /// The valve gain the law divides by: b̄0, the gain at rest.
        b0: f64,
        /// Whether the law divides by `b(x, sgn v)` instead (its flow
        /// linearisation): then b0 is its value at rest only.
        compensate: bool,
        /// The output limit under which the law is linear (V; infinite: none).
        u_limit: f64,
    },
}

/// `a == b`, for strings, in a `const` context: the check that a kind's
/// line in [`controller_kinds!`] names the kind as its `Config::KIND` does.
pub const fn str_eq(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The one list of controller kinds, in registry order: each kind's
/// variant name, the name a scenario gives it (`controller.kind`), and its
/// parameter type. Every table that must know the kinds is generated from
/// it by a macro given as `$callback`, which receives
/// `Variant "name" => Type, ...`: the scenario's registry and its JSON
/// Schema (`ehservo-scenario`), the wire's `WireController` and the board's
/// `AnyLaw` (`ehservo-wire`). Adding a controller is its file in
/// `control/` (the law and its [`Config`]) and one line here.
///
/// ```
/// macro_rules! names {
///     ($($variant:ident $name:literal => $ty:ty),* $(,)?) => {
///         [$($name),*]
///     };
/// }
/// let kinds = ehservo_core::controller_kinds!(names);
/// assert_eq!(kinds[0], "nnvsc");
/// assert!(kinds.contains(&"vsc-sat") && kinds.contains(&"pid"));
/// ```
#[macro_export]
macro_rules! controller_kinds {
    ($callback:ident) => {
        $callback! {
            Nnvsc "nnvsc" => $crate::control::sliding::NnVscConfig,
            Vsc "vsc" => $crate::control::sliding::VscConfig,
            VscSat "vsc-sat" => $crate::control::sliding::VscSatConfig,
            Pid "pid" => $crate::control::pid::PidConfig,
            NnRobust "nn-robust" => $crate::control::nn_robust::NnRobustConfig,
            Adrc "adrc" => $crate::control::adrc::AdrcConfig,
            Sta "sta" => $crate::control::sta::StaConfig,
            Arc "arc" => $crate::control::arc::ArcConfig,
            Backstepping "backstepping" => $crate::control::backstepping::BacksteppingConfig,
            StateFeedback "state-feedback" => $crate::control::state_feedback::StateFeedbackConfig,
            OpenLoop "open-loop" => $crate::control::open_loop::OpenLoopConfig,
            ForcePi "force-pi" => $crate::control::force_pi::ForcePiConfig,
        }
    };
}

/// Each line of [`controller_kinds!`] names its kind as the kind's
/// `Config::KIND` does: a line that does not, does not compile.
macro_rules! check_kind_names {
    ($($variant:ident $name:literal => $ty:ty),* $(,)?) => {
        $(const _: () = assert!(
            str_eq(<$ty as Config>::KIND, $name),
            concat!("controller_kinds!: the line of `", $name, "` is not its Config::KIND")
        );)*
    };
}
controller_kinds!(check_kind_names);
