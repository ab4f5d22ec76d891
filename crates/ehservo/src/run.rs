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
    let params = s.plant.params.to_servo();
    let load = s.load_model();
    match s.plant.model {
        PlantModel::ThirdOrder => with_controller(&ThirdOrderPlant::new(params, load), s, keep),
        PlantModel::Physical => with_controller(&PhysicalPlant::new(params, load), s, keep),
    }
}

fn with_controller<P: Plant>(plant: &P, s: &Scenario, keep: Keep) -> Result<RunResult> {
    let surface = s.surface().map_err(|(k, r)| anyhow!("{k}: {r}"))?;
    let model = *plant.nominal();
    match s.controller.kind {
        ControllerKind::Nnvsc => {
            let rbf = s.rbf().map_err(|e| anyhow!("controller.{e}"))?;
            let c = NnVsc::try_new(model, surface, s.nnvsc_params(), rbf)
                .map_err(|e| anyhow!("controller.{e}"))?;
            Ok(execute(plant, &c, s, keep, true))
        }
        ControllerKind::Vsc | ControllerKind::VscSat => {
            let c = Vsc::try_new(model, surface, s.vsc_params())
                .map_err(|e| anyhow!("controller.{e}"))?;
            Ok(execute(plant, &c, s, keep, false))
        }
    }
}

fn execute<P: Plant, C: Controller>(
    plant: &P,
    ctrl: &C,
    s: &Scenario,
    keep: Keep,
    network: bool,
) -> RunResult {
    let cfg = s.sim_config();
    let reference = s.reference();
    let mut unc = UncertaintySignal::new(s.uncertainty_spec(), plant.nominal().coeffs.as_array());
    let mut acc = MetricsAccumulator::new(
        s.simulation.horizon,
        s.simulation.settle,
        1.0 / s.reference.frequency_hz,
        network,
    );
    let mut trace = Vec::new();
    let every = match keep {
        Keep::Nothing => 0,
        Keep::Every(n) => n.max(1) as u64,
    };
    if let Some(n) = cfg.steps.checked_div(every) {
        trace.reserve((n + 2) as usize);
    }
    let mut last: Option<Sample> = None;
    let outcome = simulate(
        plant,
        ctrl,
        &reference,
        &mut unc,
        &cfg,
        &mut |smp: &Sample| {
            acc.push(smp);
            if every > 0 {
                if smp.k % every == 0 {
                    trace.push(*smp);
                } else {
                    last = Some(*smp);
                }
            }
        },
    );
    if let Some(l) = last {
        if trace.last().map(|t| t.k) != Some(l.k) && l.k > trace.last().map(|t| t.k).unwrap_or(0) {
            trace.push(l);
        }
    }
    RunResult {
        metrics: acc.finish(outcome.diverged),
        outcome,
        trace,
    }
}
