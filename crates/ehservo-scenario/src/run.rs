//! A built [`Loop`] run to its horizon: the loop's plant and controller,
//! typed ([`Loop::simulate`]), in the [`Simulation`], keeping the metrics
//! (and the trace if asked).
//!
//! ```
//! use ehservo_scenario::run::{run, Keep};
//! use ehservo_scenario::scenario::Loop;
//!
//! let lp = Loop::parse("[controller]\nkind = \"pid\"\n[simulation]\nhorizon = 3.0\n").unwrap();
//! let r = run(&lp, Keep::Every(10));
//! // 300 steps, every 10th sample kept: k = 0, 10, …, 300.
//! assert_eq!(r.trace.len(), 31);
//! assert_eq!(r.trace.last().unwrap().k, 300);
//! assert!(r.metrics.e_max.is_some());
//! ```

use crate::metrics::{Checks, Metrics, MetricsAccumulator};
use crate::plant::Plant;
use crate::scenario::{ControllerConfig, Loop, LoopPlant, LoopVisit, Typed};
use crate::simulation::{Outcome, Sample, Simulation};
use ehservo_core::control::Controller;
use ehservo_core::reference::Reference;
use ehservo_core::rk4::OdeState;

/// A finished run.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// How the loop ended, and fault counts.
    pub outcome: Outcome,
    /// SPEC §9 metrics.
    pub metrics: Metrics,
    /// The kept samples (every `decimate`-th; empty if not kept).
    pub trace: Vec<Sample>,
}

/// Which samples to keep in memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Keep {
    /// None: metrics only (sweeps).
    Nothing,
    /// Every n-th sample (n ≥ 1), and always the last one.
    Every(u32),
}

/// Every n-th sample of a run and always the last one: the one
/// decimation of the traces a run keeps, writes and shows (in memory,
/// trace.csv, the playground).
#[derive(Debug, Clone)]
pub struct Decimate {
    every: u64,
    last: Option<Sample>,
}

impl Decimate {
    /// Keeps the samples with k divisible by `every` (at least 1).
    pub fn every(every: u64) -> Self {
        Self {
            every: every.max(1),
            last: None,
        }
    }

    /// `Some(sample)` when `sample` is kept now; otherwise it is held as
    /// the last one, which [`Decimate::finish`] gives back.
    pub fn offer<'a>(&mut self, sample: &'a Sample) -> Option<&'a Sample> {
        if sample.k % self.every == 0 {
            self.last = None;
            Some(sample)
        } else {
            self.last = Some(*sample);
            None
        }
    }

    /// The last sample, if it was not kept: always keep it.
    pub fn finish(self) -> Option<Sample> {
        self.last
    }
}

/// Runs a loop, its samples carrying the plant's physical states.
pub fn run(lp: &Loop, keep: Keep) -> RunResult {
    let mut trace = Vec::new();
    let mut dec = match keep {
        Keep::Nothing => None,
        Keep::Every(n) => {
            let d = Decimate::every(u64::from(n));
            trace.reserve((lp.sim().steps / d.every + 2) as usize);
            Some(d)
        }
    };
    let (outcome, metrics) = run_observed(lp, &mut |smp: &Sample| {
        if let Some(kept) = dec.as_mut().and_then(|d| d.offer(smp)) {
            trace.push(*kept);
        }
    });
    trace.extend(dec.and_then(Decimate::finish));
    RunResult {
        outcome,
        metrics,
        trace,
    }
}

/// Runs a loop, handing every sample (with the plant's physical states) to
/// `observe`, which may stream it to a file; keeps only the metrics.
pub fn run_observed(lp: &Loop, observe: &mut dyn FnMut(&Sample)) -> (Outcome, Metrics) {
    lp.simulate(Runner {
        observe,
        states: true,
        map: Same,
    })
}

/// Runs a loop for its metrics: the samples carry no plant states
/// ([`Sample::states`]), which only traces need (sweeps, tuning).
pub fn run_metrics(lp: &Loop, observe: &mut dyn FnMut(&Sample)) -> (Outcome, Metrics) {
    lp.simulate(Runner {
        observe,
        states: false,
        map: Same,
    })
}

/// What runs in place of the controller a scenario builds: the hook of the
/// off-board runs (`ehservo run --float f32`, `ehservo pil`:
/// `ehservo::pil`), which put the built controller's kind on a board and
/// keep the rest of the loop as it is.
pub trait MapController {
    /// The controller that runs, for kind `K`.
    type Out<K: ControllerConfig>: Controller;
    /// It, from the kind's parameters and the controller they built.
    fn map<K: ControllerConfig>(self, cfg: &K, built: K::Controller) -> Self::Out<K>;
}

/// The built controller itself (every ordinary run).
pub struct Same;

impl MapController for Same {
    type Out<K: ControllerConfig> = K::Controller;
    fn map<K: ControllerConfig>(self, _cfg: &K, built: K::Controller) -> K::Controller {
        built
    }
}

/// [`run_observed`] with the controller replaced by `map`'s.
pub fn run_mapped<M: MapController>(
    lp: &Loop,
    map: M,
    observe: &mut dyn FnMut(&Sample),
) -> (Outcome, Metrics) {
    lp.simulate(Runner {
        observe,
        states: true,
        map,
    })
}

/// Runs the typed loop: the visitor of every run.
struct Runner<'b, M> {
    observe: &'b mut dyn FnMut(&Sample),
    states: bool,
    map: M,
}

impl<M: MapController> LoopVisit for Runner<'_, M> {
    type Out = (Outcome, Metrics);
    fn visit<P: LoopPlant, K: ControllerConfig>(self, t: Typed<'_, P, K>) -> Self::Out {
        let lp = t.lp;
        let ctrl = self.map.map(t.config, t.controller);
        let acc = accumulator(lp, &t.plant, &ctrl);
        let sim =
            Simulation::from_settings(t.plant, ctrl, lp.reference().clone(), lp.settings().clone());
        execute(sim, acc, lp, self.observe, self.states)
    }
}

/// The metrics' accumulator of a loop whose plant is `plant` and
/// controller `ctrl`, with the checks of [`Metrics::behaviour`]: the
/// plant's end stops, the actuator's limit, the reference's period.
pub fn accumulator<P: Plant, C: Controller>(lp: &Loop, plant: &P, ctrl: &C) -> MetricsAccumulator {
    let network = !ctrl.weights(&<C::State as OdeState>::zero()).is_empty();
    let limit = lp.stages().actuator.limit();
    let checks = Checks {
        end_stops: plant.end_stops(),
        limit,
        has_limit: limit.is_finite() || lp.stages().policy.limits.u.is_finite(),
        forcing: lp.forcing(),
        tracking: !lp.is_open(),
        ..Checks::default()
    };
    let after = ((lp.horizon() - lp.settle()).max(0.0) / lp.sim().step) as u64 + 2;
    MetricsAccumulator::new(lp.horizon(), lp.settle(), lp.period(), network)
        .on(lp.axis())
        .with_checks(checks, after)
}

fn execute<P: LoopPlant, C: Controller, R: Reference>(
    mut sim: Simulation<P, C, R>,
    mut acc: MetricsAccumulator,
    lp: &Loop,
    observe: &mut dyn FnMut(&Sample),
    states: bool,
) -> (Outcome, Metrics) {
    sim.log_states(states);
    // In chunks, so that a host's Ctrl-C can stop it (crate::cancel).
    let outcome = crate::cancel::run_chunked(&mut sim, lp, &mut |smp: &Sample| {
        acc.push(smp);
        observe(smp);
    });
    (outcome, acc.finish(outcome.diverged))
}
