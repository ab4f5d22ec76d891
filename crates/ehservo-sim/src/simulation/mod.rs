//! The closed loop as a resumable simulation: one type owns time, the
//! integrator, the sampling of the controller and the stages around it.
//!
//! ```text
//!            z(t)                       u                 u_plant
//! reference ─────▶ controller ─────────────▶ actuator ─────────────▶ plant
//!                      ▲                                                │ x = (θ, θ̇, θ̈)
//!                      └───────────────── sensor ◀──────────────────────┘
//! ```
//!
//! Time is `t_k = k·h`, never accumulated. Two readings of the paper's
//! "fourth-order Runge–Kutta with a 0.01 s interval" (SPEC §7):
//!
//! - [`Mode::Continuous`]: the law is evaluated inside every RK4 stage and
//!   the plant state, the actuator state and the controller state are
//!   integrated together;
//! - [`Mode::Sampled`]: at `t_k` the core's
//!   [`SampledController`] — the
//!   same loop a board runs, with its valve range and fault policy — computes
//!   `u` and advances the controller state once by forward Euler; `u` is
//!   held over `[t_k, t_k + h)` (zero-order hold) while the plant and the
//!   actuator are integrated by `substeps` RK4 steps of `h/substeps`.
//!
//! Under an adaptive solver (`simulation.solver`, [`SolverKind`]) the
//! sampled mode integrates the plant and the actuator from each sample
//! instant exactly to the next with error control instead ([`solver`]).
//!
//! The parameter variation is drawn at the start of each (sub)step and held
//! over it; under an adaptive solver, once per sample. [`Simulation::step`] produces one sample and advances to the
//! next; [`Simulation::run_until`] and [`Simulation::run`] repeat it. A run
//! stops at its horizon, or early — as a result, never as NaN — when the
//! state stops being finite, |θ| exceeds `theta_limit`, a cylinder's rod
//! is past a stop by more than its stated penetration, or the controller
//! faults (a non-finite command or state update) ([`Stop`]). Nothing here
//! does I/O.

mod continuous;
mod plant_alone;
mod sample;
mod sampled;
mod solver;

pub use plant_alone::{PlantAlone, PlantOutput};
pub use sample::{Divergence, DivergenceReason, Outcome, Sample, Stop, MAX_PARTS, MAX_STATES};
use sampled::FirstStage;
pub use solver::{AdaptiveConfig, Atol, SolverKind, MAX_ATOL};

use crate::actuator::Actuator;
use crate::estimator::AnyEstimator;
use crate::plant::{Plant, UncertaintySpec};
use crate::sensor::{Channels, Sensor};
use crate::uncertainty::Varying;
use ehservo_core::control::{flags, Controller, Output, Signals, Truth};
use ehservo_core::error::ParamError;
use ehservo_core::reference::Reference;
use ehservo_core::rk4::OdeState;
use ehservo_core::sampled::{FaultPolicy, SampledController, Sampling};
use serde::{Deserialize, Serialize};
use std::ops::ControlFlow;

/// How the controller is coupled to the integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// Law inside every RK4 stage; controller state integrated with the plant.
    Continuous,
    /// Zero-order hold at the sample period; controller state by forward Euler.
    Sampled,
}

impl Mode {
    /// The scenario spelling.
    pub fn as_str(&self) -> &'static str {
        match self {
            Mode::Continuous => "continuous",
            Mode::Sampled => "sampled",
        }
    }
}

/// The loop's settings (validated by the scenario loader).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimConfig {
    /// Number of steps N; the horizon is `N·step`.
    pub steps: u64,
    /// Step h (s): the sample period in sampled mode.
    pub step: f64,
    /// Coupling of controller and integrator.
    pub mode: Mode,
    /// RK4 sub-steps of the plant per sample (sampled mode).
    pub substeps: u32,
    /// Divergence bound on |θ| (rad).
    pub theta_limit: f64,
    /// Initial x = (θ, θ̇, θ̈).
    pub x0: [f64; 3],
    /// Sampled mode: the command computed at t_k is applied from t_{k+1}
    /// (a controller whose computation takes one sample period).
    pub computation_delay: bool,
}

/// The plant and actuator states, integrated together.
#[derive(Debug, Clone, Copy)]
struct PlantAct<S: OdeState> {
    x: S,
    a: [f64; 2],
}

impl<S: OdeState> OdeState for PlantAct<S> {
    #[inline]
    fn zero() -> Self {
        Self {
            x: S::zero(),
            a: [0.0; 2],
        }
    }
    #[inline]
    fn axpy(&mut self, a: f64, o: &Self) {
        self.x.axpy(a, &o.x);
        self.a.axpy(a, &o.a);
    }
    #[inline]
    fn set_axpy(&mut self, base: &Self, a: f64, o: &Self) {
        self.x.set_axpy(&base.x, a, &o.x);
        self.a.set_axpy(&base.a, a, &o.a);
    }
    #[inline]
    fn all_finite(&self) -> bool {
        self.x.all_finite() && self.a.all_finite()
    }
}

/// Plant, actuator and controller state integrated together (continuous mode).
#[derive(Debug, Clone, Copy)]
struct Augmented<S: OdeState, X: OdeState> {
    pa: PlantAct<S>,
    xi: X,
}

impl<S: OdeState, X: OdeState> OdeState for Augmented<S, X> {
    #[inline]
    fn zero() -> Self {
        Self {
            pa: PlantAct::zero(),
            xi: X::zero(),
        }
    }
    #[inline]
    fn axpy(&mut self, a: f64, o: &Self) {
        self.pa.axpy(a, &o.pa);
        self.xi.axpy(a, &o.xi);
    }
    #[inline]
    fn set_axpy(&mut self, base: &Self, a: f64, o: &Self) {
        self.pa.set_axpy(&base.pa, a, &o.pa);
        self.xi.set_axpy(&base.xi, a, &o.xi);
    }
    #[inline]
    fn all_finite(&self) -> bool {
        self.pa.all_finite() && self.xi.all_finite()
    }
}

/// What the loop knows of the true plant at a sample.
struct TruthAt<'a, P: Plant> {
    plant: &'a P,
    s: &'a P::State,
    x: [f64; 3],
    var: P::Variation,
    /// Sampled mode: the first RK4 stage of the step that follows the
    /// sample, evaluated together with the lumped uncertainty.
    stage: Option<FirstStage<'a, P>>,
}

impl<P: Plant> Truth for TruthAt<'_, P> {
    fn lumped_uncertainty(&self, u: f64, u_eq: f64, b_bar: f64) -> f64 {
        // A plant that steps itself has no derivative for a first stage.
        let Some(st) = self.stage.as_ref().filter(|_| !P::STEPS_ITSELF) else {
            return self
                .plant
                .lumped_uncertainty(self.s, &self.x, u, u_eq, b_bar, &self.var);
        };
        // What the RK4 step's derivative computes first (see `advance`).
        let mut k1 = PlantAct::<P::State>::zero();
        let lumped = self.plant.deriv_and_lumped(
            st.prepared.as_ref(),
            st.t,
            &st.y.x,
            st.act.output(&st.y.a, u),
            &self.var,
            &mut k1.x,
            u,
            u_eq,
            b_bar,
        );
        st.act.deriv(&st.y.a, u, &mut k1.a);
        st.k1.set(Some((u.to_bits(), k1)));
        lumped
    }
}

/// Everything a simulation is built from besides its plant, controller and
/// reference.
#[derive(Debug, Clone)]
pub struct Stages {
    /// The true parameter variation.
    pub uncertainty: UncertaintySpec,
    /// Between controller and plant.
    pub actuator: Actuator,
    /// Between plant and controller.
    pub sensor: Sensor,
    /// The sampled loop's fault policy and valve range (sampled mode).
    pub policy: FaultPolicy,
    /// What estimates the channels the sensors do not measure (sampled mode).
    pub estimator: Option<AnyEstimator>,
}

/// A closed loop that can be stepped, run to a time, and resumed.
///
/// ```
/// use ehservo_sim::actuator::Actuator;
/// use ehservo_sim::core::prelude::*;
/// use ehservo_sim::plant::{Plant, ThirdOrderPlant, UncertaintySpec};
/// use ehservo_sim::sensor::Sensor;
/// use ehservo_sim::simulation::{Mode, SimConfig, Simulation, Stages, Stop};
///
/// // The paper's Fig. 2 case: the NNBVSC on the third-order plant (8) with
/// // Δa_i = |ā_i| and Δb = 0.25·b̄, sampled at 100 Hz, RK4 at 0.01 s.
/// let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
/// let design = Design {
///     model: *plant.nominal(),
///     surface: SwitchingSurface::paper(),
///     dt: 0.01,
/// };
/// let nn = NnVscConfig::default().build(&design)?;
/// let stages = Stages {
///     uncertainty: UncertaintySpec::default(),
///     actuator: Actuator::IDENTITY,
///     sensor: Sensor::identity(),
///     policy: FaultPolicy::default(),
///     estimator: None,
/// };
/// let cfg = SimConfig {
///     steps: 100,
///     step: 0.01,
///     mode: Mode::Sampled,
///     substeps: 1,
///     theta_limit: 1.0,
///     x0: [0.0; 3],
///     computation_delay: false,
/// };
/// let mut sim = Simulation::new(plant, nn, Sine::paper(), stages, cfg)?;
///
/// // Samples at t_k = k·h, k = 0..=100: 101 of them over 1 s.
/// let outcome = sim.run(&mut |_| {});
/// assert_eq!(outcome.samples, 101);
/// assert_eq!(sim.stopped(), Some(Stop::Horizon));
/// assert!(outcome.diverged.is_none());
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Simulation<P: Plant, C: Controller, R: Reference> {
    plant: P,
    reference: R,
    unc: Varying<P::Variation>,
    actuator: Actuator,
    sensor: Sensor,
    cfg: SimConfig,
    ctrl: SampledController<C>,
    y: Augmented<P::State, C::State>,
    /// The adaptive solver's settings and memory, if it integrates the plant.
    adaptive: Option<solver::AdaptiveRun>,
    per_hold: Option<u64>,
    /// Whether `y.xi` is finite in sampled mode, where it never changes
    /// (the sampled controller keeps its own state): the check after each
    /// step then need not scan it again.
    xi_finite: bool,
    /// The last sample's plant was stiffer than RK4 split
    /// [`crate::plant::MAX_REFINE`] times can follow: a `too-stiff`
    /// divergence unless an earlier check names the cause.
    unresolved: bool,
    estimator: Option<AnyEstimator>,
    /// The command applied over the current sample period (the previous
    /// one with a computation delay; the estimator's input).
    u_applied: f64,
    log_states: bool,
    k: u64,
    stop: Option<Stop>,
    outcome: Outcome,
}

/// A loop's stages and settings, checked together: a [`Simulation`] made
/// from them cannot fail ([`Simulation::from_settings`]). What a scenario's
/// loop holds once it is built.
#[derive(Debug, Clone)]
pub struct Settings {
    stages: Stages,
    cfg: SimConfig,
    sampling: Sampling,
    adaptive: Option<AdaptiveConfig>,
}

impl Settings {
    /// Checks `stages` against `cfg`: the sampled-only stages (sensor noise
    /// and delay, an estimator, a computation delay) need the sampled mode,
    /// unmeasured channels an estimator, and the sample period and the
    /// fault policy must be valid.
    pub fn try_new(stages: Stages, cfg: SimConfig) -> Result<Self, ParamError> {
        if cfg.mode == Mode::Continuous {
            if stages.sensor.is_sampled() {
                return Err(ParamError::new(
                    "sensor",
                    "noise and delay need the sampled mode (a continuous law has no samples to draw them at)",
                    f64::NAN,
                ));
            }
            if stages.estimator.is_some() || stages.sensor.measured() != Channels::ALL {
                return Err(ParamError::new(
                    "estimator",
                    "an estimator runs at the controller's rate: it needs the sampled mode",
                    f64::NAN,
                ));
            }
            if cfg.computation_delay {
                return Err(ParamError::new(
                    "computation_delay",
                    "a computation delay of one sample needs the sampled mode",
                    f64::NAN,
                ));
            }
        }
        if stages.sensor.measured() != Channels::ALL && stages.estimator.is_none() {
            return Err(ParamError::new(
                "measured",
                "channels that are not measured must be estimated: set an estimator",
                f64::NAN,
            ));
        }
        let sampling = Sampling::try_new(cfg.step, stages.policy)?;
        Ok(Self {
            stages,
            cfg,
            sampling,
            adaptive: None,
        })
    }

    /// The same loop with the plant integrated by an adaptive solver
    /// between samples. Refused in continuous mode (the law inside an
    /// adaptive solver's stages is not in this version) and with a
    /// `max_step` above the sample period.
    pub fn with_adaptive(mut self, a: AdaptiveConfig) -> Result<Self, ParamError> {
        if self.cfg.mode == Mode::Continuous {
            return Err(ParamError::new(
                "solver",
                "an adaptive solver needs the sampled mode (continuous mode runs rk4)",
                f64::NAN,
            ));
        }
        if a.max_step() > self.cfg.step {
            return Err(ParamError::new(
                "max_step",
                "must be at most the sample period (simulation.step)",
                a.max_step(),
            ));
        }
        self.adaptive = Some(a);
        Ok(self)
    }

    /// The adaptive solver, if the plant is integrated by one.
    pub fn adaptive(&self) -> Option<&AdaptiveConfig> {
        self.adaptive.as_ref()
    }

    /// The stages.
    pub fn stages(&self) -> &Stages {
        &self.stages
    }

    /// The loop's settings.
    pub fn config(&self) -> &SimConfig {
        &self.cfg
    }

    /// The sample period and the fault policy, checked: what the sampled
    /// controller is made with.
    pub fn sampling(&self) -> Sampling {
        self.sampling
    }

    /// The same loop with the fault policy's limits replaced by `limits`
    /// (an off-board controller applies its own).
    pub fn with_limits(self, limits: ehservo_core::sampled::Limits) -> Result<Self, ParamError> {
        let mut stages = self.stages;
        stages.policy.limits = limits;
        let adaptive = self.adaptive;
        let s = Self::try_new(stages, self.cfg)?;
        match adaptive {
            Some(a) => s.with_adaptive(a),
            None => Ok(s),
        }
    }

    /// The same loop run for `steps` steps (the other checks do not depend
    /// on the horizon).
    pub fn with_steps(mut self, steps: u64) -> Self {
        self.cfg.steps = steps;
        self
    }

    /// The same loop started from x(0) = `x0`.
    pub fn with_x0(mut self, x0: [f64; 3]) -> Self {
        self.cfg.x0 = x0;
        self
    }
}

impl<P: Plant, C: Controller, R: Reference> Simulation<P, C, R> {
    /// A simulation at t = 0 with x(0) = `cfg.x0` and the controller's
    /// initial state. Fails when the stages do not suit the mode, or the
    /// sample period or the policy is invalid ([`Settings::try_new`]).
    ///
    /// ```
    /// # use ehservo_sim::actuator::Actuator;
    /// # use ehservo_sim::core::prelude::*;
    /// # use ehservo_sim::plant::{Plant, ThirdOrderPlant, UncertaintySpec};
    /// # use ehservo_sim::sensor::Sensor;
    /// # use ehservo_sim::simulation::{Mode, SimConfig, Simulation, Stages, Stop};
    /// # // The paper's Fig. 2 case: the NNBVSC on the third-order plant (8) with
    /// # // Δa_i = |ā_i| and Δb = 0.25·b̄, sampled at 100 Hz, RK4 at 0.01 s.
    /// # let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
    /// # let design = Design {
    /// #     model: *plant.nominal(),
    /// #     surface: SwitchingSurface::paper(),
    /// #     dt: 0.01,
    /// # };
    /// # let nn = NnVscConfig::default().build(&design)?;
    /// # let stages = Stages {
    /// #     uncertainty: UncertaintySpec::default(),
    /// #     actuator: Actuator::IDENTITY,
    /// #     sensor: Sensor::identity(),
    /// #     policy: FaultPolicy::default(),
    /// #     estimator: None,
    /// # };
    /// # let cfg = SimConfig {
    /// #     steps: 100,
    /// #     step: 0.01,
    /// #     mode: Mode::Sampled,
    /// #     substeps: 1,
    /// #     theta_limit: 1.0,
    /// #     x0: [0.0; 3],
    /// #     computation_delay: false,
    /// # };
    /// # let mut sim = Simulation::new(plant, nn, Sine::paper(), stages, cfg)?;
    /// assert_eq!((sim.time(), sim.stopped()), (0.0, None));
    /// // The controller starts from W = 0.
    /// assert!(sim.controller_state().w.iter().all(|&w| w == 0.0));
    /// # Ok::<(), ParamError>(())
    /// ```
    pub fn new(
        plant: P,
        ctrl: C,
        reference: R,
        stages: Stages,
        cfg: SimConfig,
    ) -> Result<Self, ParamError> {
        Settings::try_new(stages, cfg).map(|s| Self::from_settings(plant, ctrl, reference, s))
    }

    /// A simulation at t = 0 of checked settings: infallible.
    pub fn from_settings(plant: P, ctrl: C, reference: R, settings: Settings) -> Self {
        assert!(
            C::Parts::SIGNALS.len() <= MAX_PARTS,
            "a controller logs at most {MAX_PARTS} parts"
        );
        let Settings {
            stages,
            cfg,
            sampling,
            adaptive,
        } = settings;
        let adaptive = adaptive.map(|cfg| solver::AdaptiveRun {
            cfg,
            state: ehservo_core::solver::Adaptive::new(),
        });
        let xi = ctrl.initial_state_at(&cfg.x0);
        let mut ctrl = SampledController::sampled(ctrl, sampling);
        ctrl.start_at(&cfg.x0);
        let mut unc = Varying::new(&plant, stages.uncertainty);
        let hs = Self::hs(&cfg, adaptive.is_some());
        let per_hold = unc.signal().steps_per_hold(hs);
        let var0 = unc.at_step(&plant, 0, hs, per_hold);
        Self {
            y: Augmented {
                pa: PlantAct {
                    x: plant.initial_state(cfg.x0, &var0),
                    a: stages.actuator.initial_state(),
                },
                xi,
            },
            plant,
            reference,
            unc,
            actuator: stages.actuator,
            sensor: stages.sensor,
            cfg,
            ctrl,
            adaptive,
            per_hold,
            xi_finite: xi.all_finite(),
            unresolved: false,
            estimator: stages.estimator,
            u_applied: 0.0,
            log_states: false,
            k: 0,
            stop: None,
            outcome: Outcome::default(),
        }
    }

    /// Whether each sample carries the plant's physical states
    /// ([`Sample::states`]; off by default: sweeps need only the metrics).
    pub fn log_states(&mut self, on: bool) {
        self.log_states = on;
    }

    /// The step of the variation's clock: the RK4 sub-step in sampled mode,
    /// the sample period under an adaptive solver.
    fn hs(cfg: &SimConfig, adaptive: bool) -> f64 {
        match cfg.mode {
            Mode::Sampled if !adaptive => cfg.step / cfg.substeps.max(1) as f64,
            _ => cfg.step,
        }
    }

    /// The time of the next sample (s).
    pub fn time(&self) -> f64 {
        self.k as f64 * self.cfg.step
    }

    /// Why the run stopped, once it has.
    pub fn stopped(&self) -> Option<Stop> {
        self.stop
    }

    /// The counts so far.
    pub fn outcome(&self) -> Outcome {
        self.outcome
    }

    /// The controller.
    pub fn controller(&self) -> &C {
        self.ctrl.controller()
    }

    /// The controller state (the one the next sample's law will see).
    pub fn controller_state(&self) -> &C::State {
        match self.cfg.mode {
            Mode::Sampled => self.ctrl.state(),
            Mode::Continuous => &self.y.xi,
        }
    }

    fn diverge(&mut self, t: f64, reason: DivergenceReason) {
        let d = Divergence { t, reason };
        self.outcome.diverged = Some(d);
        self.stop = Some(Stop::Diverged(d));
    }

    /// Produces the sample at `t_k` and advances to `t_{k+1}`; `None` once
    /// the run has stopped (see [`Simulation::stopped`]).
    ///
    /// ```
    /// # use ehservo_sim::actuator::Actuator;
    /// # use ehservo_sim::core::prelude::*;
    /// # use ehservo_sim::plant::{Plant, ThirdOrderPlant, UncertaintySpec};
    /// # use ehservo_sim::sensor::Sensor;
    /// # use ehservo_sim::simulation::{Mode, SimConfig, Simulation, Stages, Stop};
    /// # // The paper's Fig. 2 case: the NNBVSC on the third-order plant (8) with
    /// # // Δa_i = |ā_i| and Δb = 0.25·b̄, sampled at 100 Hz, RK4 at 0.01 s.
    /// # let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
    /// # let design = Design {
    /// #     model: *plant.nominal(),
    /// #     surface: SwitchingSurface::paper(),
    /// #     dt: 0.01,
    /// # };
    /// # let nn = NnVscConfig::default().build(&design)?;
    /// # let stages = Stages {
    /// #     uncertainty: UncertaintySpec::default(),
    /// #     actuator: Actuator::IDENTITY,
    /// #     sensor: Sensor::identity(),
    /// #     policy: FaultPolicy::default(),
    /// #     estimator: None,
    /// # };
    /// # let cfg = SimConfig {
    /// #     steps: 100,
    /// #     step: 0.01,
    /// #     mode: Mode::Sampled,
    /// #     substeps: 1,
    /// #     theta_limit: 1.0,
    /// #     x0: [0.0; 3],
    /// #     computation_delay: false,
    /// # };
    /// # let mut sim = Simulation::new(plant, nn, Sine::paper(), stages, cfg)?;
    /// // t = 0: at rest on θd(0) = 0, no error yet.
    /// let s0 = sim.step().expect("a sample");
    /// assert_eq!((s0.k, s0.t, s0.e), (0, 0.0, 0.0));
    /// // t = 0.01 against the independent NumPy implementation of Fig. 2
    /// // (bench/peers/nnvsc_numpy.py; crates/ehservo/tests/it/independent.rs):
    /// // θ = 0.0181445994348°, u = 0.727779612044 V, σ = 41.4188293018 rad/s².
    /// let s1 = sim.step().expect("a sample");
    /// assert!((s1.theta_deg() - 0.0181445994348).abs() < 1e-9 * 0.0181445994348);
    /// assert!((s1.u - 0.727779612044).abs() < 1e-9 * 0.727779612044);
    /// assert!((s1.part("sigma") - 41.4188293018).abs() < 1e-9 * 41.4188293018);
    /// assert_eq!(sim.time(), 0.02);
    /// # Ok::<(), ParamError>(())
    /// ```
    pub fn step(&mut self) -> Option<Sample> {
        let mut sample = Sample::default();
        self.advance(&mut sample).then_some(sample)
    }

    /// [`Simulation::step`] into a sample row the caller keeps: `run` and
    /// `run_until` fill one row in place for the whole run instead of
    /// building, returning and copying a 400-byte row per sample. Returns
    /// whether a sample was produced. The row's `values` past the
    /// controller's signals are never written (they stay as the caller
    /// made them: zero, from [`Sample::default`]).
    fn advance(&mut self, sample: &mut Sample) -> bool {
        if self.stop.is_some() {
            return false;
        }
        let h = self.cfg.step;
        let k = self.k;
        let t = k as f64 * h;
        let m = self.cfg.substeps.max(1) as u64;
        let (j0, hs) = match self.cfg.mode {
            Mode::Sampled if self.adaptive.is_none() => (k * m, h / m as f64),
            _ => (k, h),
        };
        let var = self.unc.at_step(&self.plant, j0, hs, self.per_hold);
        let x = self.plant.measure(t, &self.y.pa.x, &var);
        let z = self.reference.z(t);
        let flow = match self.cfg.mode {
            Mode::Sampled => self.advance_sampled(sample, k, t, x, z, var, j0, hs, m),
            Mode::Continuous => self.advance_continuous(sample, k, t, x, z, var, h),
        };
        if let ControlFlow::Break(produced) = flow {
            return produced;
        }
        self.k += 1;
        let t_next = self.k as f64 * h;
        let finite = match self.cfg.mode {
            Mode::Sampled => self.y.pa.all_finite() && self.xi_finite,
            Mode::Continuous => self.y.all_finite(),
        };
        if self.plant.failed() {
            self.diverge(t_next, DivergenceReason::PlantFailed);
        } else if !finite {
            self.diverge(t_next, DivergenceReason::NonFiniteState);
        } else if self.plant.measure(t_next, &self.y.pa.x, &var)[0].abs() > self.cfg.theta_limit {
            self.diverge(t_next, DivergenceReason::ThetaLimit);
        } else if self.plant.beyond_stops(&self.y.pa.x, &var) {
            self.diverge(t_next, DivergenceReason::BeyondEndStop);
        } else if self.unresolved {
            self.diverge(t_next, DivergenceReason::TooStiff);
        }
        true
    }

    /// Counts the law's flags and fills `sample` at `t_k`; false (and the
    /// run stopped) when the output or a logged signal is not finite.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn log(
        &mut self,
        sample: &mut Sample,
        t: f64,
        z: [f64; 4],
        x: [f64; 3],
        x_ctrl: [f64; 3],
        u_applied: f64,
        out: &Output<C::Parts>,
    ) -> bool {
        if out.flags & flags::VALVE_ROOT_CLAMPED != 0 {
            self.outcome.valve_root_clamped += 1;
        }
        if out.flags & flags::ZERO_ERROR_NORM != 0 {
            self.outcome.zero_error_norm += 1;
        }
        if out.flags & flags::MEASUREMENT_FAULT != 0 {
            self.outcome.measurement_faults += 1;
        }
        if out.flags & flags::NON_FINITE_STATE != 0 {
            self.diverge(t, DivergenceReason::NonFiniteState);
            return false;
        }
        if out.flags & flags::NON_FINITE_CONTROL != 0 || !out.u.is_finite() {
            self.diverge(t, DivergenceReason::NonFiniteControl);
            return false;
        }
        let u = out.u;
        if out.flags & flags::SATURATED != 0 || u.abs() > self.actuator.limit() {
            self.outcome.saturated += 1;
        }
        sample.k = self.k;
        sample.t = t;
        sample.z = z;
        sample.x = x;
        sample.u = u;
        sample.u_plant = self.actuator.output(&self.y.pa.a, u_applied);
        sample.spool = self.actuator.spool(&self.y.pa.a, u_applied);
        sample.x_ctrl = x_ctrl;
        if self.log_states {
            self.plant.states(t, &self.y.pa.x, &x, &mut sample.states);
        }
        sample.e = z[0] - x[0];
        sample.flags = out.flags;
        sample.signals = C::Parts::SIGNALS;
        out.parts.write(&mut sample.values);
        // Every logged signal must be finite (a finite u can still come with
        // an overflowing ‖E‖ or σ): otherwise the run ends here, as a result.
        if !sample.finite_with(C::Parts::SIGNALS.len()) {
            self.diverge(t, DivergenceReason::NonFiniteControl);
            return false;
        }
        self.outcome.samples += 1;
        true
    }

    /// Steps until the next sample would be later than `t_end` (s) or the
    /// run stops, handing each sample to `observe`. Returns the stop reason
    /// if the run has stopped.
    ///
    /// ```
    /// # use ehservo_sim::actuator::Actuator;
    /// # use ehservo_sim::core::prelude::*;
    /// # use ehservo_sim::plant::{Plant, ThirdOrderPlant, UncertaintySpec};
    /// # use ehservo_sim::sensor::Sensor;
    /// # use ehservo_sim::simulation::{Mode, SimConfig, Simulation, Stages, Stop};
    /// # // The paper's Fig. 2 case: the NNBVSC on the third-order plant (8) with
    /// # // Δa_i = |ā_i| and Δb = 0.25·b̄, sampled at 100 Hz, RK4 at 0.01 s.
    /// # let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
    /// # let design = Design {
    /// #     model: *plant.nominal(),
    /// #     surface: SwitchingSurface::paper(),
    /// #     dt: 0.01,
    /// # };
    /// # let nn = NnVscConfig::default().build(&design)?;
    /// # let stages = Stages {
    /// #     uncertainty: UncertaintySpec::default(),
    /// #     actuator: Actuator::IDENTITY,
    /// #     sensor: Sensor::identity(),
    /// #     policy: FaultPolicy::default(),
    /// #     estimator: None,
    /// # };
    /// # let cfg = SimConfig {
    /// #     steps: 100,
    /// #     step: 0.01,
    /// #     mode: Mode::Sampled,
    /// #     substeps: 1,
    /// #     theta_limit: 1.0,
    /// #     x0: [0.0; 3],
    /// #     computation_delay: false,
    /// # };
    /// # let mut sim = Simulation::new(plant, nn, Sine::paper(), stages, cfg)?;
    /// // To t = 0.5 s: samples k = 0..=50, and the run goes on.
    /// let mut last = None;
    /// assert_eq!(sim.run_until(0.5, &mut |s| last = Some(*s)), None);
    /// let s = last.expect("samples");
    /// assert_eq!((sim.outcome().samples, s.k), (51, 50));
    /// // The independent NumPy implementation of Fig. 2 at t = 0.5
    /// // (crates/ehservo/tests/it/independent.rs): θ = 0.149089034611°,
    /// // u = −0.682616728963 V.
    /// assert!((s.theta_deg() - 0.149089034611).abs() < 1e-9 * 0.149089034611);
    /// assert!((s.u + 0.682616728963).abs() < 1e-9 * 0.682616728963);
    /// // Resumed to the horizon, 1 s.
    /// assert_eq!(sim.run_until(f64::INFINITY, &mut |_| {}), Some(Stop::Horizon));
    /// assert_eq!(sim.outcome().samples, 101);
    /// # Ok::<(), ParamError>(())
    /// ```
    pub fn run_until(&mut self, t_end: f64, observe: &mut dyn FnMut(&Sample)) -> Option<Stop> {
        let tol = 1e-9 * self.cfg.step;
        let mut sample = Sample::default();
        while self.stop.is_none() && self.time() <= t_end + tol {
            if self.advance(&mut sample) {
                observe(&sample);
            }
        }
        self.stop
    }

    /// Runs to the horizon (or the earlier stop), handing each sample to
    /// `observe`.
    ///
    /// ```
    /// # use ehservo_sim::actuator::Actuator;
    /// # use ehservo_sim::core::prelude::*;
    /// # use ehservo_sim::plant::{Plant, ThirdOrderPlant, UncertaintySpec};
    /// # use ehservo_sim::sensor::Sensor;
    /// # use ehservo_sim::simulation::{Mode, SimConfig, Simulation, Stages, Stop};
    /// # // The paper's Fig. 2 case: the NNBVSC on the third-order plant (8) with
    /// # // Δa_i = |ā_i| and Δb = 0.25·b̄, sampled at 100 Hz, RK4 at 0.01 s.
    /// # let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
    /// # let design = Design {
    /// #     model: *plant.nominal(),
    /// #     surface: SwitchingSurface::paper(),
    /// #     dt: 0.01,
    /// # };
    /// # let nn = NnVscConfig::default().build(&design)?;
    /// # let stages = Stages {
    /// #     uncertainty: UncertaintySpec::default(),
    /// #     actuator: Actuator::IDENTITY,
    /// #     sensor: Sensor::identity(),
    /// #     policy: FaultPolicy::default(),
    /// #     estimator: None,
    /// # };
    /// # let cfg = SimConfig {
    /// #     steps: 100,
    /// #     step: 0.01,
    /// #     mode: Mode::Sampled,
    /// #     substeps: 1,
    /// #     theta_limit: 1.0,
    /// #     x0: [0.0; 3],
    /// #     computation_delay: false,
    /// # };
    /// # let mut sim = Simulation::new(plant, nn, Sine::paper(), stages, cfg)?;
    /// // Over 1 s, the largest |e| and the number of samples.
    /// let mut e_max: f64 = 0.0;
    /// let outcome = sim.run(&mut |s| e_max = e_max.max(s.e_deg().abs()));
    /// assert_eq!(outcome.samples, 101);
    /// // Well inside the reference's 5° amplitude: the loop tracks.
    /// assert!(e_max > 0.0 && e_max < 0.5, "{e_max}");
    /// # Ok::<(), ParamError>(())
    /// ```
    pub fn run(&mut self, observe: &mut dyn FnMut(&Sample)) -> Outcome {
        let mut sample = Sample::default();
        while self.stop.is_none() {
            if self.advance(&mut sample) {
                observe(&sample);
            }
        }
        self.outcome
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // bit-for-bit equality is the point
mod tests;
#[cfg(test)]
use tests as tests_support;
#[cfg(test)]
#[allow(clippy::float_cmp)] // u is held: the very bits given
mod steps_itself_tests;
