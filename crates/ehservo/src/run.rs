//! From a validated [`Scenario`] to a finished run: build the plant and the
//! controller, run [`crate::sim::simulate`], keep the metrics (and the trace
//! if asked).

use crate::metrics::{Metrics, MetricsAccumulator};
use crate::plant::{PhysicalPlant, Plant, ThirdOrderPlant, UncertaintySignal};
use crate::scenario::{ControllerKind, PlantModel, Scenario};
use crate::sim::{simulate, Outcome, Sample};
use anyhow::{anyhow, Result};
use ehservo_core::control::nnvsc::NnVsc;
use ehservo_core::control::vsc::Vsc;
use ehservo_core::control::Controller;

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

/// Runs a scenario (which must have passed [`Scenario::validate`]).
pub fn run(s: &Scenario, keep: Keep) -> Result<RunResult> {
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
pub fn run_observed(s: &Scenario, observe: &mut dyn FnMut(&Sample)) -> Result<(Outcome, Metrics)> {
    let params = s.plant.params.to_servo();
    let load = s.load_model();
    match s.plant.model {
        PlantModel::ThirdOrder => with_controller(&ThirdOrderPlant::new(params, load), s, observe),
        PlantModel::Physical => with_controller(&PhysicalPlant::new(params, load), s, observe),
    }
}

fn with_controller<P: Plant>(
    plant: &P,
    s: &Scenario,
    observe: &mut dyn FnMut(&Sample),
) -> Result<(Outcome, Metrics)> {
    let surface = s.surface().map_err(|(k, r)| anyhow!("{k}: {r}"))?;
    let model = *plant.nominal();
    match s.controller.kind {
        ControllerKind::Nnvsc => {
            let rbf = s.rbf().map_err(|e| anyhow!("controller.{e}"))?;
            let c = NnVsc::try_new(model, surface, s.nnvsc_params(), rbf)
                .map_err(|e| anyhow!("controller.{e}"))?;
            Ok(execute(plant, &c, s, observe, true))
        }
        ControllerKind::Vsc | ControllerKind::VscSat => {
            let c = Vsc::try_new(model, surface, s.vsc_params())
                .map_err(|e| anyhow!("controller.{e}"))?;
            Ok(execute(plant, &c, s, observe, false))
        }
    }
}

fn execute<P: Plant, C: Controller>(
    plant: &P,
    ctrl: &C,
    s: &Scenario,
    observe: &mut dyn FnMut(&Sample),
    network: bool,
) -> (Outcome, Metrics) {
    let cfg = s.sim_config();
    let reference = s.reference();
    let mut unc = UncertaintySignal::new(s.uncertainty_spec(), plant.nominal().coeffs.as_array());
    let mut acc = MetricsAccumulator::new(
        s.simulation.horizon,
        s.simulation.settle,
        1.0 / s.reference.frequency_hz,
        network,
    );
    let outcome = simulate(
        plant,
        ctrl,
        &reference,
        &mut unc,
        &cfg,
        &mut |smp: &Sample| {
            acc.push(smp);
            observe(smp);
        },
    );
    (outcome, acc.finish(outcome.diverged))
}
