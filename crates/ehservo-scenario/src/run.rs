//! From a validated [`Scenario`] to a finished run: the registry hands the
//! typed controller parameters to [`Runner`], which builds the plant and the
//! controller and runs the [`Simulation`], keeping the metrics (and the
//! trace if asked).

use crate::metrics::{Metrics, MetricsAccumulator};
use crate::plant::Plant;
use crate::scenario::{ControllerConfig, PlantVisit, Scenario, ScenarioError, Setup, Visit};
use crate::simulation::{Outcome, Sample, Simulation};
use ehservo_core::control::Controller;
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

/// Runs a scenario.
pub fn run(s: &Scenario, keep: Keep) -> Result<RunResult, ScenarioError> {
    let every = match keep {
        Keep::Nothing => 0,
        Keep::Every(n) => n.max(1) as u64,
    };
    let mut trace = Vec::new();
    if let Some(n) = s.sim_config().steps.checked_div(every) {
        trace.reserve((n + 2) as usize);
    }
    let mut last: Option<Sample> = None;
    let (outcome, metrics) = run_observed(s, &mut |smp: &Sample| {
        if every > 0 {
            if smp.k % every == 0 {
                trace.push(*smp);
            } else {
                last = Some(*smp);
            }
        }
    })?;
    // Always keep the last sample.
    if let Some(l) = last {
        if trace.last().is_none_or(|t| t.k < l.k) {
            trace.push(l);
        }
    }
    Ok(RunResult {
        outcome,
        metrics,
        trace,
    })
}

/// Runs a scenario, handing every sample to `observe` (which may stream it
/// to a file) and keeping only the metrics.
pub fn run_observed(
    s: &Scenario,
    observe: &mut dyn FnMut(&Sample),
) -> Result<(Outcome, Metrics), ScenarioError> {
    let setup = s.setup()?;
    Ok(setup.controller.visit(Runner {
        setup: &setup,
        observe,
        states: true,
        map: Same,
    }))
}

/// Runs a built scenario, for its metrics: the samples carry no plant
/// states ([`Sample::states`]), which only traces need.
pub fn run_setup(setup: &Setup, observe: &mut dyn FnMut(&Sample)) -> (Outcome, Metrics) {
    setup.controller.visit(Runner {
        setup,
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

/// [`run_setup`] with the controller replaced by `map`'s, the samples
/// carrying the plant's states as `ehservo run`'s do.
pub fn run_setup_mapped<M: MapController>(
    setup: &Setup,
    map: M,
    observe: &mut dyn FnMut(&Sample),
) -> (Outcome, Metrics) {
    setup.controller.visit(Runner {
        setup,
        observe,
        states: true,
        map,
    })
}

/// Builds the plant and the controller of a [`Setup`] and runs them: the
/// generic half of [`run_setup`], monomorphised per kind and plant.
pub struct Runner<'a, 'b, M = Same> {
    setup: &'a Setup,
    observe: &'b mut dyn FnMut(&Sample),
    states: bool,
    map: M,
}

impl<M: MapController> Visit for Runner<'_, '_, M> {
    type Out = (Outcome, Metrics);
    fn visit<K: ControllerConfig>(self, cfg: &K) -> Self::Out {
        let ctrl = self.map.map(
            cfg,
            cfg.build(&self.setup.design)
                .expect("Setup::new built this controller once already"),
        );
        self.setup.plant.visit(WithPlant {
            ctrl,
            setup: self.setup,
            observe: self.observe,
            states: self.states,
        })
    }
}

/// The second half of [`Runner`]: the controller built, the plant typed.
struct WithPlant<'a, 'b, C> {
    ctrl: C,
    setup: &'a Setup,
    observe: &'b mut dyn FnMut(&Sample),
    states: bool,
}

impl<C: Controller> PlantVisit for WithPlant<'_, '_, C> {
    type Out = (Outcome, Metrics);
    fn visit<P: Plant + Clone + std::fmt::Debug + Send + Sync + 'static>(
        self,
        plant: &P,
    ) -> Self::Out {
        execute(
            plant.clone(),
            self.ctrl,
            self.setup,
            self.observe,
            self.states,
        )
    }
}

fn execute<P: Plant, C: Controller>(
    plant: P,
    ctrl: C,
    setup: &Setup,
    observe: &mut dyn FnMut(&Sample),
    states: bool,
) -> (Outcome, Metrics) {
    let network = !ctrl.weights(&<C::State as OdeState>::zero()).is_empty();
    let mut acc =
        MetricsAccumulator::new(setup.horizon, setup.settle, setup.period, network).on(setup.axis);
    let mut sim = Simulation::new(
        plant,
        ctrl,
        setup.reference.clone(),
        setup.stages.clone(),
        setup.sim,
    )
    .expect("Setup::new validated the sample period and the policy");
    sim.log_states(states);
    // In chunks, so that a host's Ctrl-C can stop it (crate::cancel).
    let outcome = crate::cancel::run_chunked(&mut sim, setup, &mut |smp: &Sample| {
        acc.push(smp);
        observe(smp);
    });
    (outcome, acc.finish(outcome.diverged))
}
