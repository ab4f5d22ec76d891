//! A scenario's loop and its controller as values a caller steps one sample
//! at a time, with the controller kind and the plant model erased behind a
//! trait object: what the C ABI (`crates/ehservo-ffi`), its FMI 3.0 export
//! and the Python package (`bindings/python`: `ehservo.Controller`) hold in
//! a handle.
//!
//! [`LoopStepper`] is the simulation `ehservo run` runs (the same
//! [`Simulation`], reference and stages, metrics accumulated the same way),
//! so stepping it to the horizon gives `ehservo run`'s metrics to the bit.
//! [`ControllerStepper`] is the scenario's controller alone in the sampled
//! loop ([`SampledController`]: the law, forward Euler on its state, the
//! `[fault]` policy) at the scenario's step: fed the measurements a run's
//! controller saw, it returns the run's commands to the bit.

use crate::metrics::{Metrics, MetricsAccumulator};
use crate::plant::Plant;
use crate::scenario::{AnyReference, ControllerConfig, KeyError, Loop, ScenarioError};
use crate::scenario::{LoopPlant, LoopVisit, Typed};
use crate::simulation::{Divergence, Mode, PlantAlone, PlantOutput, Sample, Simulation, Stop};
use ehservo_core::control::{Controller, Signal, Signals, Truth};
use ehservo_core::reference::Reference;
use ehservo_core::sampled::SampledController;

/// A simulation of any kind and plant, stepped by the caller.
trait LoopStep {
    fn step(&mut self) -> Option<Sample>;
    fn metrics(&self) -> Metrics;
    fn stopped(&self) -> Option<Stop>;
    fn time(&self) -> f64;
}

struct Looped<P: Plant, C: Controller> {
    sim: Simulation<P, C, AnyReference>,
    acc: MetricsAccumulator,
}

impl<P: Plant, C: Controller> LoopStep for Looped<P, C> {
    fn step(&mut self) -> Option<Sample> {
        let s = self.sim.step()?;
        self.acc.push(&s);
        Some(s)
    }
    fn metrics(&self) -> Metrics {
        self.acc.finish(self.sim.outcome().diverged)
    }
    fn stopped(&self) -> Option<Stop> {
        self.sim.stopped()
    }
    fn time(&self) -> f64 {
        self.sim.time()
    }
}

/// A scenario's closed loop, one sample per [`LoopStepper::step`].
pub struct LoopStepper {
    inner: Box<dyn LoopStep>,
    step: f64,
    steps: u64,
    axis: crate::axis::Axis,
}

impl std::fmt::Debug for LoopStepper {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LoopStepper")
            .field("step", &self.step)
            .field("steps", &self.steps)
            .field("time", &self.inner.time())
            .finish()
    }
}

/// Builds a [`Looped`] of the loop's typed plant and controller.
struct BuildLoop;

impl LoopVisit for BuildLoop {
    type Out = Box<dyn LoopStep>;
    fn visit<P: LoopPlant, K: ControllerConfig>(self, t: Typed<'_, P, K>) -> Self::Out {
        let lp = t.lp;
        let acc = crate::run::accumulator(lp, &t.plant, &t.controller);
        Box::new(Looped {
            sim: t.simulation(),
            acc,
        })
    }
}

impl LoopStepper {
    /// The loop of a built scenario, at t = 0.
    pub fn new(lp: &Loop) -> Self {
        Self {
            inner: lp.simulate(BuildLoop),
            step: lp.sim().step,
            steps: lp.sim().steps,
            axis: lp.axis(),
        }
    }

    /// The plant's axis (the unit of the metrics: deg or mm).
    pub fn axis(&self) -> crate::axis::Axis {
        self.axis
    }

    /// The sample at t_k, and the loop advanced to t_{k+1}; `None` once the
    /// run has stopped (the horizon's sample was produced, or it diverged:
    /// see [`LoopStepper::stopped`]).
    pub fn step(&mut self) -> Option<Sample> {
        self.inner.step()
    }

    /// The metrics of the samples so far, as `ehservo run` computes them at
    /// the end of a run (`e_max_deg` is `None` before the settling time).
    pub fn metrics(&self) -> Metrics {
        self.inner.metrics()
    }

    /// Why the run stopped, once it has.
    pub fn stopped(&self) -> Option<Stop> {
        self.inner.stopped()
    }

    /// The time of the next sample (s).
    pub fn time(&self) -> f64 {
        self.inner.time()
    }

    /// The sample period h (s).
    pub fn period(&self) -> f64 {
        self.step
    }

    /// The number of steps N to the horizon (N + 1 samples, t_N = N·h).
    pub fn steps(&self) -> u64 {
        self.steps
    }
}

/// A plant alone of any kind, stepped by the caller.
trait PlantStep {
    fn output(&mut self, u: f64) -> PlantOutput;
    fn hold(&mut self, u: f64) -> Result<(), Divergence>;
    fn set_external_load(&mut self, load: f64);
    fn time(&self) -> f64;
    fn stopped(&self) -> Option<Divergence>;
}

impl<P: LoopPlant> PlantStep for PlantAlone<P> {
    fn output(&mut self, u: f64) -> PlantOutput {
        PlantAlone::output(self, u)
    }
    fn hold(&mut self, u: f64) -> Result<(), Divergence> {
        PlantAlone::hold(self, u)
    }
    fn set_external_load(&mut self, load: f64) {
        PlantAlone::set_external_load(self, load)
    }
    fn time(&self) -> f64 {
        PlantAlone::time(self)
    }
    fn stopped(&self) -> Option<Divergence> {
        PlantAlone::stopped(self)
    }
}

/// Builds the loop's plant alone, and says what it takes and logs.
struct BuildPlant;

impl LoopVisit for BuildPlant {
    type Out = (Box<dyn PlantStep>, &'static [Signal], bool);
    fn visit<P: LoopPlant, K: ControllerConfig>(self, t: Typed<'_, P, K>) -> Self::Out {
        let signals = t.plant.signals();
        (
            Box::new(PlantAlone::from_settings(t.plant, t.lp.settings())),
            signals,
            P::EXTERNAL_LOAD,
        )
    }
}

/// A scenario's plant with its actuator, without the controller, sensors
/// or estimator: the caller gives the command u (V), held over each sample
/// period, and reads the plant's outputs ([`PlantAlone`]). What the plant
/// FMU serves. Fed the commands of a run of the same scenario, it gives
/// that run's x to the bit.
pub struct PlantStepper {
    inner: Box<dyn PlantStep>,
    states: &'static [Signal],
    external_load: bool,
    step: f64,
    axis: crate::axis::Axis,
}

impl std::fmt::Debug for PlantStepper {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PlantStepper")
            .field("step", &self.step)
            .field("time", &self.inner.time())
            .finish()
    }
}

impl PlantStepper {
    /// The plant of a built scenario, at t = 0 and x(0) = the scenario's.
    pub fn new(lp: &Loop) -> Self {
        let (inner, states, external_load) = lp.simulate(BuildPlant);
        Self {
            inner,
            states,
            external_load,
            step: lp.sim().step,
            axis: lp.axis(),
        }
    }

    /// The outputs at the current sample, `u` being the command now.
    pub fn output(&mut self, u: f64) -> PlantOutput {
        self.inner.output(u)
    }

    /// One sample period with `u` (V) held; the divergence that stopped the
    /// plant, if it did.
    pub fn hold(&mut self, u: f64) -> Result<(), Divergence> {
        self.inner.hold(u)
    }

    /// The external load held from now on (N on a linear axis, N·m on a
    /// rotary one), when the plant [`takes_external_load`](Self::takes_external_load).
    pub fn set_external_load(&mut self, load: f64) {
        self.inner.set_external_load(load)
    }

    /// Whether the plant takes an external load (the cylinder does).
    pub fn takes_external_load(&self) -> bool {
        self.external_load
    }

    /// The plant's physical states, in the order of [`PlantOutput::states`].
    pub fn states(&self) -> &'static [Signal] {
        self.states
    }

    /// The time of the current sample (s).
    pub fn time(&self) -> f64 {
        self.inner.time()
    }

    /// Why the plant stopped, once it has.
    pub fn stopped(&self) -> Option<Divergence> {
        self.inner.stopped()
    }

    /// The sample period h (s).
    pub fn period(&self) -> f64 {
        self.step
    }

    /// The plant's axis.
    pub fn axis(&self) -> crate::axis::Axis {
        self.axis
    }
}

/// What one sample of a [`ControllerStepper`] returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawOutput {
    /// The command u (V), after the `[fault]` policy and the valve range.
    pub u: f64,
    /// The law's flags ([`ehservo_core::control::flags`]).
    pub flags: u8,
}

trait LawStep: Send + Sync {
    fn step(&mut self, t: f64, x: [f64; 3], z: [f64; 4]) -> LawOutput;
    fn step_parts(&mut self, t: f64, x: [f64; 3], z: [f64; 4], parts: &mut [f64]) -> LawOutput;
    /// `step` on a copy (on the stack, not boxed).
    fn peek(&self, t: f64, x: [f64; 3], z: [f64; 4]) -> LawOutput;
    fn reset(&mut self);
    fn signals(&self) -> &'static [Signal];
    fn faults(&self) -> u64;
    fn weights(&self) -> &[f64];
    fn boxed(&self) -> Box<dyn LawStep>;
}

/// What a controller stepped outside the simulator knows of the true plant:
/// nothing, so the lumped-uncertainty diagnostic is NaN.
struct NoTruth;

impl Truth for NoTruth {
    fn lumped_uncertainty(&self, _u: f64, _u_eq: f64, _b_bar: f64) -> f64 {
        f64::NAN
    }
}

impl<C> LawStep for SampledController<C>
where
    C: Controller<State: Send + Sync> + Clone + Send + Sync + 'static,
{
    fn step(&mut self, t: f64, x: [f64; 3], z: [f64; 4]) -> LawOutput {
        let o = SampledController::step(self, t, x, z);
        LawOutput {
            u: o.u,
            flags: o.flags,
        }
    }
    fn step_parts(&mut self, t: f64, x: [f64; 3], z: [f64; 4], parts: &mut [f64]) -> LawOutput {
        // As the simulator's sampled loop: the diagnostics are filled with
        // the state the law saw, before the state advances.
        let o = self.step_with(t, x, z, |c, s, o| c.annotate_stepped(s, o, &NoTruth));
        o.parts.write(parts);
        LawOutput {
            u: o.u,
            flags: o.flags,
        }
    }
    fn peek(&self, t: f64, x: [f64; 3], z: [f64; 4]) -> LawOutput {
        LawStep::step(&mut self.clone(), t, x, z)
    }
    fn reset(&mut self) {
        SampledController::reset(self)
    }
    fn signals(&self) -> &'static [Signal] {
        C::Parts::SIGNALS
    }
    fn faults(&self) -> u64 {
        self.fault_count()
    }
    fn weights(&self) -> &[f64] {
        self.controller().weights(self.state())
    }
    fn boxed(&self) -> Box<dyn LawStep> {
        Box::new(self.clone())
    }
}

/// Puts the loop's typed controller in its sampled loop.
struct BuildLaw;

impl LoopVisit for BuildLaw {
    type Out = Box<dyn LawStep>;
    fn visit<P: LoopPlant, K: ControllerConfig>(self, t: Typed<'_, P, K>) -> Self::Out {
        Box::new(SampledController::sampled(
            t.controller,
            t.lp.settings().sampling(),
        ))
    }
}

/// A scenario's controller in the sampled loop, stepped by the caller.
pub struct ControllerStepper {
    inner: Box<dyn LawStep>,
    kind: &'static str,
    reference: AnyReference,
    step: f64,
    steps: u64,
}

impl Clone for ControllerStepper {
    fn clone(&self) -> Self {
        Self {
            inner: self.inner.boxed(),
            kind: self.kind,
            reference: self.reference.clone(),
            step: self.step,
            steps: self.steps,
        }
    }
}

impl std::fmt::Debug for ControllerStepper {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ControllerStepper")
            .field("step", &self.step)
            .field("signals", &self.inner.signals().len())
            .finish()
    }
}

impl ControllerStepper {
    /// The controller of a validated scenario, in its initial state. The
    /// scenario must be in the sampled mode (a continuous law has no
    /// samples to be stepped at); its sensors, estimator and actuator are
    /// not part of it (they are the caller's hardware).
    pub fn new(lp: &Loop) -> Result<Self, ScenarioError> {
        if lp.sim().mode != Mode::Sampled {
            return Err(lp.scenario().error(KeyError::new(
                "simulation.mode",
                "a controller stepped sample by sample needs the sampled mode (got \"continuous\")",
            )));
        }
        Ok(Self {
            inner: lp.simulate(BuildLaw),
            kind: lp.controller().kind(),
            reference: lp.reference().clone(),
            step: lp.sim().step,
            steps: lp.sim().steps,
        })
    }

    /// One sample: the law at (t, x, z), then its state advanced by one
    /// period. A non-finite or out-of-range measurement (`[fault]`) gives
    /// the safe command with `flags::MEASUREMENT_FAULT` and leaves the state.
    pub fn step(&mut self, t: f64, x: [f64; 3], z: [f64; 4]) -> LawOutput {
        self.inner.step(t, x, z)
    }

    /// The controller's kind, as `[controller] kind` names it.
    pub fn kind(&self) -> &'static str {
        self.kind
    }

    /// The scenario's reference z = (θd, θ̇d, θ̈d, θ⃛d) at t (rad, rad/s, …).
    pub fn reference(&self, t: f64) -> [f64; 4] {
        self.reference.z(t)
    }

    /// [`step`](Self::step), also writing the law's parts, one value per
    /// [`signals`](Self::signals) entry, into `parts` (at least that long).
    /// Diagnostics that need the true plant (the lumped uncertainty) are
    /// NaN: a stepped controller has no plant behind it.
    pub fn step_parts(&mut self, t: f64, x: [f64; 3], z: [f64; 4], parts: &mut [f64]) -> LawOutput {
        self.inner.step_parts(t, x, z, parts)
    }

    /// What [`step`](Self::step) would return now, without advancing the
    /// state (a copy is stepped): the output map of a sampled-data system
    /// whose state update is `step`.
    pub fn peek(&self, t: f64, x: [f64; 3], z: [f64; 4]) -> LawOutput {
        self.inner.peek(t, x, z)
    }

    /// Samples that returned the safe command (a bad measurement or law).
    pub fn faults(&self) -> u64 {
        self.inner.faults()
    }

    /// The network weights W of the current state (empty without a network).
    pub fn weights(&self) -> &[f64] {
        self.inner.weights()
    }

    /// Back to the initial state.
    pub fn reset(&mut self) {
        self.inner.reset()
    }

    /// The law's signals (what `trace.csv` logs for this kind).
    pub fn signals(&self) -> &'static [Signal] {
        self.inner.signals()
    }

    /// The sample period h (s).
    pub fn period(&self) -> f64 {
        self.step
    }

    /// The number of steps N to the scenario's horizon.
    pub fn steps(&self) -> u64 {
        self.steps
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // bit-identical results are the point
mod tests {
    use super::*;
    use crate::run::{run, Keep};

    fn fig2(extra: &str) -> Loop {
        Loop::parse(&format!("name = \"fig2\"\n{extra}")).unwrap()
    }

    #[test]
    fn stepping_the_loop_gives_the_runs_metrics_and_samples() {
        let s = fig2("[simulation]\nhorizon = 3.0\n");
        let r = run(&s, Keep::Every(1));
        let mut l = LoopStepper::new(&s);
        assert_eq!(l.steps(), 300);
        let mut n = 0;
        while let Some(smp) = l.step() {
            assert_eq!(smp.u.to_bits(), r.trace[n].u.to_bits(), "k = {n}");
            assert_eq!(smp.e.to_bits(), r.trace[n].e.to_bits(), "k = {n}");
            n += 1;
        }
        assert_eq!(n, 301);
        assert_eq!(l.stopped(), Some(Stop::Horizon));
        let (a, b) = (l.metrics(), r.metrics);
        assert_eq!(a.e_max.unwrap().to_bits(), b.e_max.unwrap().to_bits());
        assert_eq!(a, b);
    }

    #[test]
    fn the_controller_alone_reproduces_the_runs_commands() {
        // nnvsc (the weights carry state) and pid, exact sensors.
        for extra in ["", "[controller]\nkind = \"pid\"\n"] {
            let s = fig2(&format!("[simulation]\nhorizon = 1.0\n{extra}"));
            let r = run(&s, Keep::Every(1));
            let mut c = ControllerStepper::new(&s).unwrap();
            for smp in &r.trace {
                assert_eq!(c.reference(smp.t), smp.z);
                let o = c.step(smp.t, smp.x, smp.z);
                assert_eq!(o.u.to_bits(), smp.u.to_bits(), "{extra:?} k = {}", smp.k);
            }
            // A snapshot continues as the original does.
            let mut d = c.clone();
            let last = r.trace.last().unwrap();
            assert_eq!(
                c.step(1.01, last.x, last.z).u.to_bits(),
                d.step(1.01, last.x, last.z).u.to_bits()
            );
        }
    }

    #[test]
    fn parts_are_the_runs_and_peek_does_not_advance() {
        let s = fig2("[simulation]\nhorizon = 0.5\n");
        let r = run(&s, Keep::Every(1));
        let mut c = ControllerStepper::new(&s).unwrap();
        assert_eq!(c.kind(), "nnvsc");
        let n = c.signals().len();
        assert!(n > 0 && c.weights().iter().all(|w| *w == 0.0));
        let mut parts = vec![0.0; n];
        for smp in &r.trace {
            let p = c.peek(smp.t, smp.x, smp.z);
            let o = c.step_parts(smp.t, smp.x, smp.z, &mut parts);
            assert_eq!((p.u.to_bits(), p.flags), (o.u.to_bits(), o.flags));
            assert_eq!(o.u.to_bits(), smp.u.to_bits(), "k = {}", smp.k);
            for (i, sig) in c.signals().iter().enumerate() {
                if sig.key == "uncertainty" {
                    // Needs the true plant, which a stepped law has not.
                    assert!(parts[i].is_nan());
                } else {
                    assert_eq!(parts[i].to_bits(), smp.values[i].to_bits(), "{}", sig.key);
                }
            }
        }
        // The weights moved (the law learned), and no step was a fault.
        assert!(c.weights().iter().any(|w| *w != 0.0));
        assert_eq!(c.faults(), 0);
        // A NaN measurement is a fault with the safe command.
        let o = c.step_parts(0.51, [f64::NAN, 0.0, 0.0], c.reference(0.51), &mut parts);
        assert_ne!(o.flags & ehservo_core::control::flags::MEASUREMENT_FAULT, 0);
        assert_eq!(c.faults(), 1);
    }

    #[test]
    fn a_continuous_scenario_has_no_sampled_controller() {
        let s = fig2("[simulation]\nmode = \"continuous\"\n");
        let e = ControllerStepper::new(&s).unwrap_err();
        assert_eq!(e.key, "simulation.mode");
        assert_eq!(LoopStepper::new(&s).steps(), 1000);
    }
}
