//! The "true" plants the controllers are tried on: the [`Plant`] trait, the
//! paper's form of the variation, and [`PlantConfig`], what a plant is in a
//! scenario.
//!
//! A plant is one file and one registry line
//! (`crates/ehservo-scenario/src/scenario/plants.rs`):
//!
//! | plant | file | axis | state |
//! |---|---|---|---|
//! | `third-order` | [`third_order`](crate::third_order) | rotary | (θ, θ̇, θ̈), eq. (8)–(9) |
//! | `physical` | [`physical`](crate::physical) | rotary | (θ, θ̇, Pl), eqs. (1)–(6) |
//! | `cylinder` | [`cylinder`](crate::cylinder) | linear (rotary through a rack and pinion) | (y, ẏ, P1, P2, Ps, relief) |
//! | `ifac9007` | [`ifac9007`](crate::ifac9007) | linear (the benchmark's length unit) | (y, ẏ, p), IFAC benchmark 9007 |
//! | `fmu` | `ehservo_scenario::fmu_plant` (it reads files) | from the FMU's position unit | x itself, stepped by the FMU ([`Plant::STEPS_ITSELF`]) |
//!
//! Each has its own configuration type (its `[plant]` keys, serde, a
//! [`PlantConfig`]), its own variation type ([`Plant::Variation`], made from
//! the scenario's `[uncertainty]` by [`Plant::variation`]), its own prepared
//! data ([`Plant::Prepared`]: what a sample can compute of the state before
//! the command is known) and its axis ([`Plant::axis`]), which every output
//! reads for its units. The controller is designed on the plant's
//! [`Plant::nominal`] third-order model, in the axis's SI unit.
//!
//! **The paper's variation** ([`Variation`]) belongs to the third-order
//! family: `Δa_i = |ā_i|·(a_bias + a_random·r_i)` and
//! `Δb = b_ref·b(t)·(b_bias + b_random·r_b)` (crate::uncertainty).

use crate::axis::Axis;
use crate::error::KeyError;
use ehservo_core::control::Signal;
use ehservo_core::rk4::OdeState;
use ehservo_core::servo::{Load, NominalModel};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::fmt::Debug;

pub use crate::physical::PhysicalPlant;
pub use crate::third_order::ThirdOrderPlant;
pub use crate::uncertainty::{
    Draw, Factors, PhysicalSpec, Spread, UncertaintySignal, UncertaintySpec, Varying,
};

/// The third-order family's parameters at one instant, as they differ from
/// the nominal (the paper's Δa_i and Δb).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variation {
    /// Δa1, Δa2, Δa3.
    pub da: [f64; 3],
    /// δb, with true `b = (1 + δb)·b_nominal` (so `Δb = δb·b_nominal`).
    pub db_rel: f64,
}

impl Variation {
    /// No variation.
    pub const NONE: Variation = Variation {
        da: [0.0; 3],
        db_rel: 0.0,
    };

    /// The paper's form of `spec` for the draw `r`, on a plant with the
    /// nominal coefficients `abar`: `Δa_i = |ā_i|·(a_bias + a_random·r_i)`,
    /// `δb = b_ref·(b_bias + b_random·r_b)`.
    #[inline]
    pub fn of(spec: &UncertaintySpec, abar: &[f64; 3], r: &Draw) -> Variation {
        let s = spec;
        let da = core::array::from_fn(|i| abar[i].abs() * (s.a_bias + s.a_random * r.paper[i]));
        Variation {
            da,
            db_rel: s.b_reference * (s.b_bias + s.b_random * r.paper[3]),
        }
    }
}

/// Most physical states a plant may log per sample ([`Plant::STATES`]).
pub const MAX_STATES: usize = 7;

/// Most RK4 steps one (sub)step is split into for a stiff plant
/// ([`Plant::stiffness`]).
pub const MAX_REFINE: u32 = 4096;

/// RK4's stability limit on the negative real axis, |λ·h| ≤ 2.785
/// (Hairer & Wanner, *Solving ODEs II*, §IV.2, Fig. 2.1), rounded down.
pub const RK4_STABLE: f64 = 2.78;

/// Whether [`MAX_REFINE`] RK4 steps of `h/MAX_REFINE` keep the rate
/// `lambda` within [`RK4_STABLE`] (a NaN rate is left to the state's
/// own check, `non-finite-state`). A plant
/// whose rate is beyond it stops as `too-stiff` (a relief valve of 1e-8 s
/// ran 2 minutes unstable before, 1e-300 s went non-finite).
///
/// ```
/// use ehservo_sim::plant::resolvable;
///
/// // 4096 steps of 1e-4/4096 s: |λ| up to 2.78·4096/1e-4 = 1.1387e8 1/s.
/// assert!(resolvable(1.1e8, 1e-4));
/// assert!(!resolvable(1.2e8, 1e-4));
/// assert!(resolvable(0.0, 1e-4));
/// ```
#[inline(always)]
pub fn resolvable(lambda: f64, h: f64) -> bool {
    let beyond = lambda * h > RK4_STABLE * MAX_REFINE as f64;
    !beyond
}

/// How many RK4 steps of `h/n` resolve the rate `lambda` over `h > 0`:
/// ⌈|λ|·h/2.5⌉ within [1, MAX_REFINE] (2.5 keeps inside RK4's stability
/// limit of about 2.8 on the real and the imaginary axis).
///
/// A rate ≤ 0 is answered first, before any arithmetic on `h`: for a plant
/// whose [`Plant::stiffness`] is the constant 0 (the default: the paper's
/// plants) the answer is then the constant 1 and the simulator's split
/// step is compiled out. Without it `0·h/2.5` cannot be folded (h could
/// be infinite), and the split's set-up, `ceil` among it, was computed
/// ahead of its test at every step (≈ 65 instructions a Fig. 2 sample).
///
/// ```
/// use ehservo_sim::plant::{refinement, MAX_REFINE};
///
/// // |λ| = 1000 1/s over h = 0.01 s: ⌈1000·0.01/2.5⌉ = 4 steps of 2.5 ms.
/// assert_eq!(refinement(1000.0, 0.01), 4);
/// assert_eq!(refinement(100.0, 0.01), 1); // |λ|·h = 1: the step is fine
/// assert_eq!(refinement(1e12, 0.01), MAX_REFINE);
/// ```
#[inline(always)]
pub fn refinement(lambda: f64, h: f64) -> u32 {
    if lambda <= 0.0 {
        return 1;
    }
    let n = lambda * h / 2.5;
    if n <= 1.0 {
        1
    } else if n < MAX_REFINE as f64 {
        n.ceil() as u32
    } else {
        MAX_REFINE
    }
}

/// A plant as a pure derivative over its own state (of any dimension: a
/// spool, a cylinder's pressures, a supply), with an output map to the
/// x = (position, velocity, acceleration) of its axis, in SI, that the
/// sensors see.
///
/// ```
/// use ehservo_sim::core::servo::{Load, ServoParams};
/// use ehservo_sim::plant::{Factors, PhysicalPlant, Plant, ThirdOrderPlant, Variation};
/// use ehservo_sim::physical::PhysicalVariation;
///
/// // Any plant: the state that holds x(0), and the x the sensors then see.
/// fn round_trip<P: Plant>(p: &P, x0: [f64; 3], v: &P::Variation) -> [f64; 3] {
///     p.measure(0.0, &p.initial_state(x0, v), v)
/// }
/// let x0 = [0.1, 0.0, 2.0];
/// // The third-order plant's state is x itself.
/// let third = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
/// assert_eq!(round_trip(&third, x0, &Variation::NONE), x0);
/// // The physical one keeps Pl, from the torque balance (4), and gives θ̈
/// // back from (4).
/// let phys = PhysicalPlant::new(ServoParams::paper(), Load::paper());
/// let v = PhysicalVariation { paper: Variation::NONE, factors: Factors::ONE };
/// let x = round_trip(&phys, x0, &v);
/// assert!((x[0] - 0.1).abs() < 1e-15 && (x[2] - 2.0).abs() < 1e-9);
/// ```
pub trait Plant {
    /// The plant's state: its components in SI units, in a fixed order
    /// (the order of a per-state `simulation.atol`).
    type State: OdeState + AsRef<[f64]> + AsMut<[f64]>;
    /// What one hold interval's variation is for this plant.
    type Variation: Copy + Debug;
    /// What [`Plant::prepare`] computes of a state before the command is
    /// known (`()` for a plant that prepares nothing).
    type Prepared: Copy;
    /// The physical states beyond x that a trace carries (a load pressure,
    /// chamber pressures), at most [`MAX_STATES`].
    const STATES: &'static [Signal] = &[];
    /// The physical states this plant's trace carries: [`Plant::STATES`],
    /// or a longer list a plant's configuration asks for (a cylinder's
    /// environment force), at most [`MAX_STATES`].
    fn signals(&self) -> &'static [Signal] {
        Self::STATES
    }
    /// The number of components of [`Plant::State`].
    fn state_dim(&self) -> usize {
        Self::State::zero().as_ref().len()
    }
    /// The axis: the quantity of x and its display unit.
    fn axis(&self) -> Axis {
        Axis::Rotary
    }
    /// The end stops of the axis, as the positions x₀ (SI, the axis's
    /// own: rad or m) below the first and above the second of which the
    /// plant is in contact with a stop; `None` (the default) for a plant
    /// without stops. The metrics count contacts from it
    /// ([`crate::metrics::Behaviour`]).
    fn end_stops(&self) -> Option<[f64; 2]> {
        None
    }
    /// Whether the state lies where the model no longer holds (a
    /// cylinder's rod past an end stop by more than the stop's stated
    /// penetration): the simulator then reports a divergence
    /// ([`crate::simulation::DivergenceReason::BeyondEndStop`]). False (the
    /// default) for a plant without such a bound.
    #[inline(always)]
    fn beyond_stops(&self, _s: &Self::State, _v: &Self::Variation) -> bool {
        false
    }
    /// The values of [`Plant::signals`] at time `t` and state `s`, whose
    /// output is `x`.
    fn states(&self, _t: f64, _s: &Self::State, _x: &[f64; 3], _out: &mut [f64; MAX_STATES]) {}
    /// The plant state that corresponds to x(0) under the variation `v`.
    fn initial_state(&self, x0: [f64; 3], v: &Self::Variation) -> Self::State;
    /// x = (position, velocity, acceleration) from the plant state (SI) at
    /// time `t`, under the variation `v` (a varied mass changes the
    /// acceleration a force gives; a time-varying load force acts on it).
    fn measure(&self, t: f64, s: &Self::State, v: &Self::Variation) -> [f64; 3];
    /// The largest rate |λ| (1/s) of the plant's own dynamics at this
    /// state and input that an explicit step must resolve: the simulator
    /// splits an RK4 (sub)step of h into ⌈|λ|·h/2.5⌉ (at most
    /// [`MAX_REFINE`]) so that it stays inside RK4's stability region (a
    /// valve edge near ΔP = 0 between two stiff volumes). 0 (the default):
    /// the step as configured is fine.
    #[inline(always)]
    fn stiffness(&self, _t: f64, _s: &Self::State, _u: f64, _v: &Self::Variation) -> f64 {
        0.0
    }
    /// The state derivative under input `u` (the valve command, V) and
    /// variation `v`.
    fn deriv(&self, t: f64, s: &Self::State, u: f64, v: &Self::Variation, ds: &mut Self::State);
    /// Whether the plant advances itself over a sample period with its
    /// input held ([`Plant::step_held`]) instead of being integrated from
    /// [`Plant::deriv`]: a co-simulation FMU, whose `doStep` is its only
    /// way forward. False (the default) for every plant ehservo writes.
    const STEPS_ITSELF: bool = false;
    /// Advances `s` from `t` over one sample period `h` with the plant's
    /// input `u` held, when [`Plant::STEPS_ITSELF`]; a failure is reported
    /// by [`Plant::failed`] afterwards. Nothing (the default) otherwise.
    fn step_held(&self, _t: f64, _h: f64, _u: f64, _s: &mut Self::State) {}
    /// Whether the plant has failed (an FMU returned an error status or
    /// panicked): the simulator then ends the run as a result
    /// ([`crate::simulation::DivergenceReason::PlantFailed`]). False (the
    /// default) for a plant that cannot fail.
    fn failed(&self) -> bool {
        false
    }
    /// Whether [`Plant::set_external_load`] acts on this plant (false, the
    /// default: the paper's plants take their load from the scenario's
    /// `[load]` alone).
    const EXTERNAL_LOAD: bool = false;
    /// An external load held from now on, in addition to the plant's own:
    /// a force (N, opposing extension) on a linear axis, a torque (N·m,
    /// opposing positive rotation) on a rotary one; what a plant FMU's
    /// `f_load` input sets. Nothing (the default) for a plant without
    /// [`Plant::EXTERNAL_LOAD`].
    fn set_external_load(&mut self, _load: f64) {}
    /// Puts a state with hard limits back inside them after an RK4 step:
    /// a limited integrator (the relief valve's opening, held in
    /// [0, x_max] as Hopsan's filter holds its output) has its derivative
    /// zeroed at a limit it pushes against, but a step that crosses the
    /// limit ends beyond it; the simulator calls this after every RK4
    /// (sub)step, so the stored state is the limited one and nothing winds
    /// up. Nothing (the default) for a plant without such a state.
    #[inline(always)]
    fn limit_state(&self, _s: &mut Self::State) {}
    /// The nominal third-order model (what a controller is told).
    fn nominal(&self) -> &NominalModel;
    /// The variation of `spec` for one hold interval's draw `r` (all zero:
    /// the bias alone).
    fn variation(&self, spec: &UncertaintySpec, r: &Draw) -> Self::Variation;
    /// The lumped uncertainty of (19) without ξ, `Σ Δa_i x_i − Δb·u_eq + d`
    /// (`Δb = b_true − b̄`, b_true at the sign of the applied `u`), at the
    /// state `s` whose output is `x`: what the law's network should learn.
    /// A plant outside the third-order family defines it by the same
    /// identity (its module doc).
    fn lumped_uncertainty(
        &self,
        s: &Self::State,
        x: &[f64; 3],
        u: f64,
        u_eq: f64,
        b_bar: f64,
        v: &Self::Variation,
    ) -> f64;

    /// [`Plant::deriv`] at `s` under the input `u_plant`, and
    /// [`Plant::lumped_uncertainty`] at `s` for the command `u`: the
    /// simulator asks for both at once for the first RK4 stage of a sample
    /// (whose state is the sample's), so that a plant can evaluate what
    /// the two share only once, with what [`Plant::prepare`] made at `s` if
    /// anything. Must return exactly what the two calls return; the
    /// default makes them.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn deriv_and_lumped(
        &self,
        prepared: Option<&Self::Prepared>,
        t: f64,
        s: &Self::State,
        u_plant: f64,
        v: &Self::Variation,
        ds: &mut Self::State,
        u: f64,
        u_eq: f64,
        b_bar: f64,
    ) -> f64 {
        self.deriv_prepared(prepared, t, s, u_plant, v, ds);
        self.lumped_uncertainty(s, &self.measure(t, s, v), u, u_eq, b_bar, v)
    }

    /// What the derivative at state `s` needs of `s` alone, before the
    /// command is known: the simulator asks for it as a sample begins, so
    /// that its latency (for the third-order plant: the load's sine, and
    /// the division and root of both valve directions) runs beside the
    /// law's instead of after the command, and hands it to
    /// [`Plant::deriv_prepared`] and [`Plant::deriv_and_lumped`] for the
    /// sample's first RK4 stage, at that same state `s` only (the
    /// caller's contract: nothing checks it). `None` (the default):
    /// nothing.
    #[inline]
    fn prepare(&self, _s: &Self::State) -> Option<Self::Prepared> {
        None
    }

    /// [`Plant::deriv`] at the state `prepared` was made from, by
    /// [`Plant::prepare`]: must give exactly what `deriv` gives; the
    /// default calls it.
    #[inline]
    fn deriv_prepared(
        &self,
        _prepared: Option<&Self::Prepared>,
        t: f64,
        s: &Self::State,
        u: f64,
        v: &Self::Variation,
        ds: &mut Self::State,
    ) {
        self.deriv(t, s, u, v, ds);
    }
}

/// `Σ Δa_i x_i − Δb·u_eq + d` with `Δb = b_true − b̄`, from the nominal
/// `b(x, sgn u)` and `d(x)`: the expression of (19) the third-order family
/// shares.
///
/// ```
/// use ehservo_sim::plant::{lumped, Variation};
///
/// // Δa = (1, 2, 3), δb = 0.25: with b = 100 the true b is 125; the law
/// // used b̄ = 100. At x = (1, 1, 1), u_eq = 2, d = 5:
/// // (1 + 2 + 3) − (125 − 100)·2 + 5 = 6 − 50 + 5 = −39.
/// let v = Variation { da: [1.0, 2.0, 3.0], db_rel: 0.25 };
/// assert_eq!(lumped(&[1.0; 3], 2.0, 100.0, &v, 100.0, 5.0), -39.0);
/// ```
#[inline]
pub fn lumped(x: &[f64; 3], u_eq: f64, b_bar: f64, v: &Variation, b: f64, d: f64) -> f64 {
    let b_true = (1.0 + v.db_rel) * b;
    v.da[0] * x[0] + v.da[1] * x[1] + v.da[2] * x[2] - (b_true - b_bar) * u_eq + d
}

/// What a plant's configuration is built against: the parts of the
/// scenario outside `[plant]` that a plant may read.
#[derive(Debug, Clone)]
pub struct PlantContext {
    /// `[load]`: the third-order family's load torque (the paper's
    /// `2·sin(4θ)` N·m unless the scenario says otherwise); `None` when the
    /// scenario has no `[load]` and the plant's family has no default.
    pub load: Option<Load>,
    /// Whether the scenario gave a `[load]` table at all.
    pub load_given: bool,
    /// The variation, resolved for this plant.
    pub uncertainty: UncertaintySpec,
    /// x(0), SI.
    pub x0: [f64; 3],
    /// The scenario file's directory: a plant's relative file (a force
    /// table) is read from it.
    pub base_dir: Option<std::path::PathBuf>,
    /// The smallest and largest position the reference asks for over the
    /// run (SI), sampled: a plant with a stroke checks it (given for a
    /// linear axis; `None` may be the case on a rotary one).
    pub reference_range: Option<(f64, f64)>,
    /// What the loop closes on (`[reference] quantity`): a plant that can
    /// measure a force or a pressure gives it as x₀ (the cylinder); any
    /// other is refused by the loader before it is built.
    pub quantity: crate::axis::Quantity,
}

/// A plant model as a scenario names it: `[plant] model = "…"` and that
/// model's keys. Adding a plant is a file with its plant type and one of
/// these, and a line in the registry.
///
/// ```
/// use ehservo_sim::plant::{PlantConfig, PlantContext, UncertaintySpec};
/// use ehservo_sim::third_order::ThirdOrderCfg;
///
/// // The rest of the scenario, as a plant may read it: nothing here.
/// let ctx = PlantContext {
///     load: None,
///     load_given: false,
///     uncertainty: UncertaintySpec::NONE,
///     x0: [0.0; 3],
///     base_dir: None,
///     reference_range: None,
///     quantity: Default::default(),
/// };
/// assert_eq!(ThirdOrderCfg::MODEL, "third-order");
/// // A bad key comes back as its path from the scenario's root.
/// let cfg: ThirdOrderCfg = toml::from_str("[params]\nJt = -1.0").unwrap();
/// let key = cfg.build(&ctx).unwrap_err().key;
/// assert_eq!(key, "plant.params.Jt");
/// ```
pub trait PlantConfig:
    Serialize + DeserializeOwned + Default + Clone + PartialEq + Debug + Send + Sync + 'static
{
    /// `plant.model`.
    const MODEL: &'static str;
    /// One line on what the model is.
    const DOC: &'static str;
    /// Whether the paper's Δa_i/Δb form of `[uncertainty]` applies (the
    /// third-order family) or only `[uncertainty.physical]`.
    const PAPER_UNCERTAINTY: bool;
    /// Whether the scenario's top-level `[load]` (a torque) is what loads
    /// this plant.
    const USES_LOAD: bool;
    /// Whether the plant has end stops (a run then goes on at them, with
    /// no position limit; `simulation.theta_limit` does not apply).
    const END_STOPS: bool = false;
    /// The plant.
    type Plant: Plant + Clone + Debug + Send + Sync + 'static;
    /// The axis of this configuration's plant.
    fn axis(&self) -> Axis;
    /// The physical states its trace carries (`Plant::STATES`).
    fn states(&self) -> &'static [Signal] {
        <Self::Plant as Plant>::STATES
    }
    /// Checks every key and builds the plant. The error is a key path
    /// (from the scenario's root: `plant.…`, `uncertainty.…`) and the
    /// reason.
    fn build(&self, ctx: &PlantContext) -> Result<Self::Plant, KeyError>;

    /// The paper's physical parameters when this model is of the
    /// third-order family (its `[plant.params]`): what the paper's theory
    /// and identification's grey-box read. `None` (the default) for any
    /// other plant.
    fn paper_params(&self) -> Option<ehservo_core::servo::ServoParams> {
        None
    }
    /// This model with the paper's physical parameters `p` in place of its
    /// own (an identified model of the same family); `None` (the default)
    /// for a plant outside the third-order family.
    fn with_paper_params(&self, _p: ehservo_core::servo::ServoParams) -> Option<Self> {
        None
    }
}
