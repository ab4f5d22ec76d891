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
//!   [`SampledController`](ehservo_core::sampled::SampledController) — the
//!   same loop a board runs, with its valve range and fault policy — computes
//!   `u` and advances the controller state once by forward Euler; `u` is
//!   held over `[t_k, t_k + h)` (zero-order hold) while the plant and the
//!   actuator are integrated by `substeps` RK4 steps of `h/substeps`.
//!
//! The parameter variation is drawn at the start of each (sub)step and held
//! over it. [`Simulation::step`] produces one sample and advances to the
//! next; [`Simulation::run_until`] and [`Simulation::run`] repeat it. A run
//! stops at its horizon, or early — as a result, never as NaN — when the
//! state stops being finite, |θ| exceeds `theta_limit`, or the controller
//! faults (a non-finite command or state update) ([`Stop`]). Nothing here
//! does I/O.

mod continuous;
mod sample;
mod sampled;

pub use sample::{Divergence, DivergenceReason, Outcome, Sample, Stop, MAX_PARTS, MAX_STATES};
use sampled::FirstStage;

use crate::actuator::Actuator;
use crate::estimator::AnyEstimator;
use crate::plant::{Plant, UncertaintySpec};
use crate::sensor::{Channels, Sensor};
use crate::uncertainty::Varying;
use ehservo_core::control::{flags, Controller, Output, Signals, Truth};
use ehservo_core::error::ParamError;
use ehservo_core::reference::Reference;
use ehservo_core::rk4::OdeState;
use ehservo_core::sampled::{FaultPolicy, SampledController};
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
        let Some(st) = &self.stage else {
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
    per_hold: Option<u64>,
    /// Whether `y.xi` is finite in sampled mode, where it never changes
    /// (the sampled controller keeps its own state): the check after each
    /// step then need not scan it again.
    xi_finite: bool,
    estimator: Option<AnyEstimator>,
    /// The command applied over the current sample period (the previous
    /// one with a computation delay; the estimator's input).
    u_applied: f64,
    log_states: bool,
    k: u64,
    stop: Option<Stop>,
    outcome: Outcome,
}

impl<P: Plant, C: Controller, R: Reference> Simulation<P, C, R> {
    /// A simulation at t = 0 with x(0) = `cfg.x0` and the controller's
    /// initial state. Fails when the sample period or the policy is invalid.
    pub fn new(
        plant: P,
        ctrl: C,
        reference: R,
        stages: Stages,
        cfg: SimConfig,
    ) -> Result<Self, ParamError> {
        assert!(
            C::Parts::SIGNALS.len() <= MAX_PARTS,
            "a controller logs at most {MAX_PARTS} parts"
        );
        let xi = ctrl.initial_state();
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
        let ctrl = SampledController::with_policy(ctrl, cfg.step, stages.policy)?;
        let mut unc = Varying::new(&plant, stages.uncertainty);
        let per_hold = unc.signal().steps_per_hold(Self::hs(&cfg));
        let var0 = unc.at_step(&plant, 0, Self::hs(&cfg), per_hold);
        Ok(Self {
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
            per_hold,
            xi_finite: xi.all_finite(),
            estimator: stages.estimator,
            u_applied: 0.0,
            log_states: false,
            k: 0,
            stop: None,
            outcome: Outcome::default(),
        })
    }

    /// Whether each sample carries the plant's physical states
    /// ([`Sample::states`]; off by default: sweeps need only the metrics).
    pub fn log_states(&mut self, on: bool) {
        self.log_states = on;
    }

    /// The step of the variation's clock: the RK4 sub-step in sampled mode.
    fn hs(cfg: &SimConfig) -> f64 {
        match cfg.mode {
            Mode::Sampled => cfg.step / cfg.substeps.max(1) as f64,
            Mode::Continuous => cfg.step,
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
            Mode::Sampled => (k * m, h / m as f64),
            Mode::Continuous => (k, h),
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
        if !finite {
            self.diverge(t_next, DivergenceReason::NonFiniteState);
        } else if self.plant.measure(t_next, &self.y.pa.x, &var)[0].abs() > self.cfg.theta_limit {
            self.diverge(t_next, DivergenceReason::ThetaLimit);
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
mod tests {
    use super::*;
    use crate::actuator::ActuatorConfig;
    use crate::plant::{Draw, ThirdOrderPlant, Variation};
    use ehservo_core::control::nnvsc::{NnVsc, NnVscParams};
    use ehservo_core::prelude::{Load, NominalModel, Rbf, ServoParams, Sine, SwitchingSurface};
    use ehservo_core::rk4::rk4_step;

    fn nn() -> NnVsc {
        NnVsc::try_new(
            NominalModel::new(ServoParams::paper(), Load::paper()),
            SwitchingSurface::paper(),
            NnVscParams::paper(),
            Rbf::paper(),
        )
        .unwrap()
    }

    fn stages(actuator: Actuator) -> Stages {
        Stages {
            uncertainty: UncertaintySpec {
                a_bias: 0.5,
                a_random: 0.5,
                b_bias: 0.25,
                b_random: 0.25,
                seed: 3,
                ..UncertaintySpec::NONE
            },
            actuator,
            sensor: Sensor::identity(),
            policy: FaultPolicy::default(),
            estimator: None,
        }
    }

    fn cfg(mode: Mode) -> SimConfig {
        SimConfig {
            steps: 300,
            step: if mode == Mode::Sampled { 0.01 } else { 0.001 },
            mode,
            substeps: 3,
            theta_limit: 1.0,
            x0: [0.0; 3],
            computation_delay: false,
        }
    }

    fn sim(mode: Mode, a: Actuator) -> Simulation<ThirdOrderPlant, NnVsc, Sine> {
        let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
        Simulation::new(plant, nn(), Sine::paper(), stages(a), cfg(mode)).unwrap()
    }

    /// Stopping at any time and resuming gives the run in one go, bit for bit.
    #[test]
    fn run_until_resumes_exactly() {
        for mode in [Mode::Sampled, Mode::Continuous] {
            let mut whole = Vec::new();
            let out = sim(mode, Actuator::IDENTITY).run(&mut |s| whole.push(*s));
            let mut parts = Vec::new();
            let mut s = sim(mode, Actuator::IDENTITY);
            let h = cfg(mode).step;
            assert_eq!(s.run_until(0.5 * h * 300.0, &mut |x| parts.push(*x)), None);
            assert_eq!(parts.len(), 151, "samples 0..=150");
            assert!((s.time() - 151.0 * h).abs() < 1e-12);
            let one = s.step().unwrap();
            parts.push(one);
            assert_eq!(
                s.run_until(f64::INFINITY, &mut |x| parts.push(*x)),
                Some(Stop::Horizon)
            );
            assert_eq!(s.step(), None, "a stopped simulation stays stopped");
            assert_eq!(whole, parts, "{mode:?}");
            assert_eq!(s.outcome(), out);
            assert_eq!(out.samples, 301);
        }
    }

    /// The finiteness check of a sample looks at every logged number and
    /// nothing else: one ±∞ or NaN anywhere among them fails it.
    #[test]
    fn a_sample_is_finite_exactly_when_every_logged_number_is() {
        use ehservo_core::control::sliding::SlidingParts;
        let mut s = Sample {
            x: [1.0, -2.0, 3e300],
            z: [0.1, 0.2, -0.3, 0.4],
            u: -0.0,
            u_plant: 5e-324,
            e: f64::MAX,
            signals: SlidingParts::<f64>::SIGNALS,
            ..Default::default()
        };
        for (i, v) in s.values.iter_mut().enumerate() {
            *v = i as f64 - 7.5;
        }
        assert!(s.is_finite());
        // A count that is not a multiple of the four lanes.
        let mut short = s;
        short.signals = &SlidingParts::<f64>::SIGNALS[..13];
        short.values[12] = f64::INFINITY;
        assert!(!short.is_finite());
        short.values[12] = 0.0;
        short.values[13] = f64::INFINITY;
        assert!(short.is_finite());
        let n = SlidingParts::<f64>::SIGNALS.len();
        let mut past = s;
        past.values[n] = f64::NAN; // not one of this controller's signals
        assert!(past.is_finite());
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut cases = Vec::new();
            for i in 0..n {
                let mut c = s;
                c.values[i] = bad;
                cases.push(c);
            }
            for i in 0..3 {
                let mut c = s;
                c.x[i] = bad;
                cases.push(c);
            }
            for i in 0..4 {
                let mut c = s;
                c.z[i] = bad;
                cases.push(c);
            }
            for f in [
                |c: &mut Sample, b| c.u = b,
                |c: &mut Sample, b| c.u_plant = b,
                |c: &mut Sample, b| c.e = b,
            ] {
                let mut c = s;
                f(&mut c, bad);
                cases.push(c);
            }
            assert_eq!(cases.len(), n + 10);
            assert!(cases.iter().all(|c| !c.is_finite()), "{bad}");
        }
    }

    /// The third-order plant through the trait's defaults only: no shared
    /// evaluation of k1 and the lumped uncertainty, nothing prepared ahead
    /// of the law (`Plant::prepare`), so every step is `rk4_step`'s.
    #[derive(Debug, Clone, Copy)]
    struct Plain(ThirdOrderPlant);

    impl Plant for Plain {
        type State = [f64; 3];
        type Variation = Variation;
        type Prepared = ();
        fn initial_state(&self, x0: [f64; 3], v: &Variation) -> [f64; 3] {
            self.0.initial_state(x0, v)
        }
        fn measure(&self, t: f64, s: &[f64; 3], v: &Variation) -> [f64; 3] {
            self.0.measure(t, s, v)
        }
        fn deriv(&self, t: f64, s: &[f64; 3], u: f64, v: &Variation, ds: &mut [f64; 3]) {
            self.0.deriv(t, s, u, v, ds)
        }
        fn nominal(&self) -> &NominalModel {
            self.0.nominal()
        }
        fn variation(&self, spec: &UncertaintySpec, r: &Draw) -> Variation {
            self.0.variation(spec, r)
        }
        fn lumped_uncertainty(
            &self,
            s: &[f64; 3],
            x: &[f64; 3],
            u: f64,
            ue: f64,
            bb: f64,
            v: &Variation,
        ) -> f64 {
            self.0.lumped_uncertainty(s, x, u, ue, bb, v)
        }
    }

    /// Every number of a sample, as bits.
    fn bits(s: &Sample) -> Vec<u64> {
        let mut b = vec![s.k, s.t.to_bits(), s.u.to_bits(), s.u_plant.to_bits()];
        b.extend(s.x.iter().chain(&s.z).chain(&s.values).map(|v| v.to_bits()));
        b.extend([s.e.to_bits(), s.flags as u64, s.signals.len() as u64]);
        b
    }

    /// The sampled step that starts from the k1 the diagnostics evaluated
    /// (`Plant::deriv_and_lumped`), or from the one made of what
    /// the plant prepared (`FirstStage::k1`), gives the run the plain RK4
    /// step gives, bit for bit: with the valve passing the command,
    /// lagging it (the plant's input then differs from the command, and
    /// its sign may too), saturating it, with sub-steps, with a computation
    /// delay (the plant gets the previous command), with a law's safe
    /// output after a measurement fault, and for a law without
    /// diagnostics.
    #[test]
    fn the_shared_first_stage_changes_nothing() {
        let lag = Actuator::try_new(&ActuatorConfig {
            time_constant: Some(0.02),
            ..Default::default()
        })
        .unwrap();
        let sat = Actuator::try_new(&ActuatorConfig {
            limit: Some(0.2),
            ..Default::default()
        })
        .unwrap();
        let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
        // (With a computation delay the plant gets the previous command, not
        // the one the diagnostics' k1 was for: k1 comes from what was
        // prepared.)
        for (a, substeps, delay) in [
            (Actuator::IDENTITY, 1, false),
            (lag, 1, false),
            (sat, 1, false),
            (Actuator::IDENTITY, 3, false),
            (Actuator::IDENTITY, 1, true),
            (lag, 2, true),
        ] {
            let mut c = cfg(Mode::Sampled);
            c.substeps = substeps;
            c.computation_delay = delay;
            let mut shared = Vec::new();
            let o1 = Simulation::new(plant, nn(), Sine::paper(), stages(a), c)
                .unwrap()
                .run(&mut |s| shared.push(bits(s)));
            let mut plain = Vec::new();
            let o2 = Simulation::new(Plain(plant), nn(), Sine::paper(), stages(a), c)
                .unwrap()
                .run(&mut |s| plain.push(bits(s)));
            assert_eq!(o1, o2);
            assert_eq!(shared, plain, "{a:?}, {substeps} sub-steps, delay {delay}");
            assert_eq!(shared.len(), 301);
        }
        // The prepared path is the one taken (the plant prepares).
        assert!(plant.prepare(&[0.01, -0.2, 3.0]).is_some());
        // Measurement faults: the law does not run (no diagnostics, no
        // shared k1) and the plant gets the safe output, zero: the step's
        // k1 is made of what was prepared, for a command of sign 0.
        let mut faulty = stages(Actuator::IDENTITY);
        faulty.policy = FaultPolicy {
            safe: ehservo_core::sampled::SafeCommand::Zero,
            limits: ehservo_core::sampled::Limits {
                x: [0.04, f64::INFINITY, f64::INFINITY],
                u: f64::INFINITY,
            },
        };
        let c = cfg(Mode::Sampled);
        let mut f1 = Vec::new();
        let o1 = Simulation::new(plant, nn(), Sine::paper(), faulty.clone(), c)
            .unwrap()
            .run(&mut |s| f1.push(bits(s)));
        let mut f2 = Vec::new();
        let o2 = Simulation::new(Plain(plant), nn(), Sine::paper(), faulty, c)
            .unwrap()
            .run(&mut |s| f2.push(bits(s)));
        assert!(o1.measurement_faults > 10, "{o1:?}");
        assert_eq!(o1, o2);
        assert_eq!(f1, f2);
        // A PID has no diagnostics: no k1 is shared with them; the step's
        // k1 comes from what was prepared, and is rk4_step's all the same.
        let pid = ehservo_core::control::Config::build(
            &ehservo_core::control::pid::PidConfig::default(),
            &ehservo_core::control::Design {
                model: *plant.nominal(),
                surface: SwitchingSurface::paper(),
                dt: 0.01,
            },
        )
        .unwrap();
        let c = cfg(Mode::Sampled);
        let mut a1 = Vec::new();
        Simulation::new(plant, pid, Sine::paper(), stages(lag), c)
            .unwrap()
            .run(&mut |s| a1.push(bits(s)));
        let mut a2 = Vec::new();
        Simulation::new(Plain(plant), pid, Sine::paper(), stages(lag), c)
            .unwrap()
            .run(&mut |s| a2.push(bits(s)));
        assert_eq!(a1, a2);
    }

    /// A valve without spool dynamics gives every RK4 stage the input that
    /// the sampled step computes once for all of them (`advance`): the same
    /// step, bit for bit, as evaluating the valve at each stage, here with
    /// saturation, a dead band and a null bias, with and without sub-steps.
    #[test]
    fn a_static_valve_is_evaluated_once_per_step() {
        let valve = Actuator::try_new(&ActuatorConfig {
            limit: Some(0.3),
            dead_band: Some(0.01),
            null_bias: Some(0.004),
            ..Default::default()
        })
        .unwrap();
        assert!(!valve.has_lag() && !valve.is_identity());
        let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
        for substeps in [1u32, 2] {
            let mut c = cfg(Mode::Sampled);
            c.substeps = substeps;
            let (m, hs) = (u64::from(substeps), c.step / f64::from(substeps));
            let mut sim = Simulation::new(plant, nn(), Sine::paper(), stages(valve), c).unwrap();
            let (mut steps, mut saturated) = (0, 0);
            loop {
                let (k, mut y) = (sim.k, sim.y.pa);
                let smp = sim.step().expect("the paper's loop does not stop early");
                if sim.stopped().is_some() {
                    break;
                }
                let u = smp.u;
                for j in 0..m {
                    let v = sim.unc.at_step(&plant, k * m + j, hs, sim.per_hold);
                    let f = |tt: f64, s: &PlantAct<[f64; 3]>, ds: &mut PlantAct<[f64; 3]>| {
                        plant.deriv(tt, &s.x, valve.output(&s.a, u), &v, &mut ds.x);
                        valve.deriv(&s.a, u, &mut ds.a);
                    };
                    rk4_step(f, k as f64 * c.step + j as f64 * hs, &mut y, hs);
                }
                let b = |p: &PlantAct<[f64; 3]>| {
                    p.x.iter()
                        .chain(&p.a)
                        .map(|v| v.to_bits())
                        .collect::<Vec<_>>()
                };
                assert_eq!(b(&sim.y.pa), b(&y), "step {k}, {substeps} sub-step(s)");
                steps += 1;
                saturated += usize::from(u.abs() > 0.3);
            }
            assert_eq!(steps, 300);
            assert!(saturated > 0, "the limit was reached");
        }
    }

    /// A lag of τ between command and plant: the plant sees the valve
    /// state, which follows the command with the lag's first-order response,
    /// integrated with the plant in both modes.
    #[test]
    fn actuator_lag_is_integrated_with_the_plant() {
        let tau = 0.02;
        let a = Actuator::try_new(&ActuatorConfig {
            time_constant: Some(tau),
            ..Default::default()
        })
        .unwrap();
        for mode in [Mode::Sampled, Mode::Continuous] {
            let mut trace = Vec::new();
            sim(mode, a).run(&mut |s| trace.push(*s));
            assert_eq!(trace[0].u_plant, 0.0, "the valve starts at rest");
            // Over one sample the valve moves toward the command by at most
            // |u − v|·(1 − e^(−h/τ)) plus what the command itself moved.
            let h = cfg(mode).step;
            for w in trace.windows(2) {
                let dv = (w[1].u_plant - w[0].u_plant).abs();
                let bound = (w[0].u - w[0].u_plant)
                    .abs()
                    .max((w[1].u - w[0].u_plant).abs())
                    * (1.0 - (-h / tau).exp())
                    * 1.01
                    + 1e-12;
                assert!(dv <= bound, "{mode:?} at t = {}: {dv} > {bound}", w[1].t);
            }
            // With a lag the plant sees something other than the command.
            assert!(trace.iter().any(|s| (s.u - s.u_plant).abs() > 1e-3));
        }
        // Without one it sees the command exactly.
        let mut trace = Vec::new();
        sim(Mode::Sampled, Actuator::IDENTITY).run(&mut |s| trace.push(*s));
        assert!(trace.iter().all(|s| s.u.to_bits() == s.u_plant.to_bits()));
    }

    /// In sampled mode the valve range is the sampled loop's: the command is
    /// clamped and the clamps are counted.
    #[test]
    fn valve_range_clamps_the_sampled_command() {
        let a = Actuator::try_new(&ActuatorConfig {
            limit: Some(0.2),
            ..Default::default()
        })
        .unwrap();
        let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
        let mut st = stages(a);
        st.policy.limits.u = 0.2;
        let mut s = Simulation::new(plant, nn(), Sine::paper(), st, cfg(Mode::Sampled)).unwrap();
        let mut max_u: f64 = 0.0;
        let out = s.run(&mut |x| max_u = max_u.max(x.u.abs()));
        assert!(max_u <= 0.2);
        assert!(out.saturated > 0);
    }

    /// A plant whose state is not x: θ, θ̇ and a spool position v with
    /// v̇ = (u − v)/τ driving θ̈ = k·v − c·θ̇. Any dimension fits.
    #[derive(Debug, Clone, Copy)]
    struct Spool {
        model: NominalModel,
    }

    impl Plant for Spool {
        type State = [f64; 4];
        type Variation = Variation;
        type Prepared = ();
        fn initial_state(&self, x0: [f64; 3], _v: &Variation) -> [f64; 4] {
            [x0[0], x0[1], 0.0, 0.0]
        }
        fn measure(&self, _t: f64, s: &[f64; 4], _v: &Variation) -> [f64; 3] {
            [s[0], s[1], 50.0 * s[2] - 10.0 * s[1]]
        }
        fn deriv(&self, _t: f64, s: &[f64; 4], u: f64, _v: &Variation, ds: &mut [f64; 4]) {
            ds[0] = s[1];
            ds[1] = 50.0 * s[2] - 10.0 * s[1];
            ds[2] = (u - s[2]) / 0.01;
            ds[3] = 1.0; // a clock, to show every component is integrated
        }
        fn nominal(&self) -> &NominalModel {
            &self.model
        }
        fn variation(&self, spec: &UncertaintySpec, r: &Draw) -> Variation {
            Variation::of(spec, &self.model.coeffs.as_array(), r)
        }
        fn lumped_uncertainty(
            &self,
            _s: &[f64; 4],
            x: &[f64; 3],
            u: f64,
            u_eq: f64,
            b_bar: f64,
            v: &Variation,
        ) -> f64 {
            let (b, d) = self.model.b_and_d(x, ehservo_core::math::sgn(u));
            crate::plant::lumped(x, u_eq, b_bar, v, b, d)
        }
    }

    #[test]
    fn a_plant_with_its_own_state_dimension() {
        let plant = Spool {
            model: NominalModel::new(ServoParams::paper(), Load::none()),
        };
        let pid = ehservo_core::control::pid::PidConfig {
            kp: Some(20.0),
            ki: Some(0.0),
            kd: Some(0.0),
            feedforward: false,
            ..Default::default()
        };
        let ctrl = ehservo_core::control::Config::build(
            &pid,
            &ehservo_core::control::Design {
                model: plant.model,
                surface: SwitchingSurface::paper(),
                dt: 0.001,
            },
        )
        .unwrap();
        let mut s = Simulation::new(
            plant,
            ctrl,
            Sine::paper(),
            stages(Actuator::IDENTITY),
            cfg(Mode::Continuous),
        )
        .unwrap();
        let out = s.run(&mut |_| {});
        assert!(out.diverged.is_none());
        assert_eq!(out.samples, 301);
        // The clock component: 300 steps of 1 ms.
        assert!((s.y.pa.x[3] - 0.3).abs() < 1e-12);
    }

    /// With a computation delay the plant gets each command one sample
    /// late; with a measurement delay of 2 the controller sees x of two
    /// samples back (the first x until then).
    #[test]
    fn computation_and_measurement_delays() {
        let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
        let mut c = cfg(Mode::Sampled);
        c.computation_delay = true;
        let mut st = stages(Actuator::IDENTITY);
        st.sensor = Sensor::try_new(&crate::sensor::SensorConfig {
            delay: 2,
            ..Default::default()
        })
        .unwrap();
        let mut trace = Vec::new();
        Simulation::new(plant, nn(), Sine::paper(), st, c)
            .unwrap()
            .run(&mut |s| trace.push(*s));
        assert_eq!(trace[0].u_plant, 0.0);
        for k in 1..trace.len() {
            assert_eq!(
                trace[k].u_plant.to_bits(),
                trace[k - 1].u.to_bits(),
                "k = {k}"
            );
        }
        for k in 0..trace.len() {
            let src = k.saturating_sub(2);
            assert_eq!(trace[k].x_ctrl, trace[src].x, "k = {k}");
        }
        // A continuous loop refuses both.
        let mut cc = cfg(Mode::Continuous);
        cc.computation_delay = true;
        let e = Simulation::new(plant, nn(), Sine::paper(), stages(Actuator::IDENTITY), cc)
            .unwrap_err();
        assert_eq!(e.name, "computation_delay");
    }
}
