//! From a scenario to what a simulation is made of, checked once: the
//! nominal model, the surface, the controller's design context, the stages
//! around the plant, the loop's settings and the reference. Validation *is*
//! this construction: a scenario is valid exactly when [`Setup::new`]
//! succeeds, so no key is checked in one place and used unchecked in another.

use super::{AnyReference, ControllerCfg, PlantModel, SafeCommandCfg, Scenario, MAX_STEPS};
use ehservo_core::control::Design;
use ehservo_core::error::ParamError;
use ehservo_core::sampled::{FaultPolicy, Limits, SafeCommand};
use ehservo_core::servo::{Load, NominalModel, ServoParams};
use ehservo_core::surface::SwitchingSurface;
use ehservo_sim::actuator::Actuator;
use ehservo_sim::plant::UncertaintySpec;
use ehservo_sim::sensor::Sensor;
use ehservo_sim::simulation::{SimConfig, Stages};

/// Most evaluations (law or plant RK4 steps) one run may ask for: 4·10⁸,
/// about a minute or two of computing.
pub const MAX_WORK: f64 = 4.0e8;

/// Most draws of the random variation one run may ask for (horizon/hold).
pub const MAX_DRAWS: f64 = 1.0e8;

/// A validated scenario, built.
#[derive(Debug, Clone)]
pub struct Setup {
    /// Which true plant.
    pub plant: PlantModel,
    /// The nominal model (physical parameters and load).
    pub model: NominalModel,
    /// What the controller is designed from.
    pub design: Design,
    /// The controller kind and its parameters.
    pub controller: ControllerCfg,
    /// Variation, actuator, sensor, fault policy.
    pub stages: Stages,
    /// The loop's settings.
    pub sim: SimConfig,
    /// The desired trajectory.
    pub reference: AnyReference,
    /// End of the transient for the metrics (s).
    pub settle: f64,
    /// Horizon (s).
    pub horizon: f64,
    /// Period of the reference (s): the window of `e_final_deg`
    /// ([`super::ReferenceCfg::period`]).
    pub period: f64,
}

/// A core parameter error as a key path under `prefix` and a reason.
pub(crate) fn param_err(prefix: &str, e: ParamError) -> (String, String) {
    let reason = if e.value.is_nan() {
        e.reason.to_string()
    } else {
        format!("{} (got {:?})", e.reason, e.value)
    };
    (format!("{prefix}.{}", e.name), reason)
}

impl Setup {
    /// Checks every key of `s` and builds. The error is the key path and
    /// the reason of the first failure.
    pub fn new(s: &Scenario) -> Result<Setup, (String, String)> {
        let sim = &s.simulation;
        let bad = |k: &str, r: String| Err((k.to_string(), r));
        if !(sim.step.is_finite() && sim.step > 0.0) {
            return bad(
                "simulation.step",
                format!("must be finite and > 0 (got {:?})", sim.step),
            );
        }
        if !(sim.horizon.is_finite() && sim.horizon > 0.0) {
            return bad(
                "simulation.horizon",
                format!("must be finite and > 0 (got {:?})", sim.horizon),
            );
        }
        let n = sim.horizon / sim.step;
        if n > MAX_STEPS as f64 {
            return bad(
                "simulation.step",
                format!("horizon/step = {n:.3e} steps exceeds the limit of {MAX_STEPS}"),
            );
        }
        if (n - n.round()).abs() > 1e-6 * n.max(1.0) || n.round() < 1.0 {
            return bad(
                "simulation.horizon",
                format!(
                    "must be a whole number of steps: {} / {} = {n}",
                    sim.horizon, sim.step
                ),
            );
        }
        if sim.substeps == 0 || sim.substeps > 10_000 {
            return bad(
                "simulation.substeps",
                format!("must be in 1..=10000 (got {})", sim.substeps),
            );
        }
        // The work, bounded up front: plant RK4 steps (four law evaluations
        // each in continuous mode; one law evaluation per sample in sampled).
        let steps = n.round();
        let work = match sim.mode {
            ehservo_sim::simulation::Mode::Sampled => steps * (1.0 + sim.substeps as f64),
            ehservo_sim::simulation::Mode::Continuous => 4.0 * steps,
        };
        if work > MAX_WORK {
            return bad(
                "simulation.substeps",
                format!(
                    "{steps:.3e} steps × {} sub-steps is about {work:.2e} evaluations, more than the limit of {MAX_WORK:.0e} (minutes of computing): lower the horizon or the sub-steps",
                    sim.substeps
                ),
            );
        }
        // settle ≥ horizon is allowed: the windowed metrics are then absent.
        if !(sim.settle.is_finite() && sim.settle >= 0.0) {
            return bad(
                "simulation.settle",
                format!("must be finite and >= 0 (got {:?})", sim.settle),
            );
        }
        if !(sim.theta_limit.is_finite() && sim.theta_limit > 0.0) {
            return bad(
                "simulation.theta_limit",
                format!("must be finite and > 0 (got {:?})", sim.theta_limit),
            );
        }
        if let Some(v) = sim.x0.iter().find(|v| !v.is_finite()) {
            return bad("simulation.x0", format!("must be finite (got {v})"));
        }
        if sim.x0[0].abs() > sim.theta_limit {
            return bad(
                "simulation.x0",
                "θ(0) is beyond simulation.theta_limit".into(),
            );
        }

        s.plant
            .params
            .validate()
            .map_err(|e| param_err("plant.params", e))?;
        s.load_model().validate().map_err(|e| {
            let prefix = if matches!(e.name, "amplitude" | "wavenumber") {
                "load"
            } else {
                "load.friction"
            };
            param_err(prefix, e)
        })?;

        let u = &s.uncertainty;
        for (k, v) in [
            ("uncertainty.a_bias", u.a_bias),
            ("uncertainty.a_random", u.a_random),
            ("uncertainty.b_bias", u.b_bias),
            ("uncertainty.b_random", u.b_random),
        ] {
            if !v.is_finite() {
                return bad(k, format!("must be finite (got {v})"));
            }
        }
        if !(u.hold.is_finite() && u.hold > 0.0) {
            return bad(
                "uncertainty.hold",
                format!("must be finite and > 0 (got {:?})", u.hold),
            );
        }
        let draws = sim.horizon / u.hold;
        if (u.a_random != 0.0 || u.b_random != 0.0) && draws > MAX_DRAWS {
            return bad(
                "uncertainty.hold",
                format!(
                    "a random variation held {:?} s over {:?} s is {draws:.2e} draws, more than the limit of {MAX_DRAWS:.0e}",
                    u.hold, sim.horizon
                ),
            );
        }
        if !(u.b_reference.is_finite() && u.b_reference > 0.0) {
            return bad(
                "uncertainty.b_reference",
                format!("must be finite and > 0 (got {:?})", u.b_reference),
            );
        }
        // The true b must stay positive: 1 + b_ref·(b_bias ± b_random) > 0.
        if 1.0 + u.b_reference * (u.b_bias - u.b_random.abs()) <= 0.0 {
            return bad(
                "uncertainty.b_bias",
                "the true b = b̄·(1 + b_reference·(b_bias + b_random·r)) must stay > 0 (Assumption A1)"
                    .into(),
            );
        }

        let reference = s.reference()?;

        let surface = s.surface()?;
        if !s.controller.uses_surface() && s.surface != Default::default() {
            return bad(
                "surface",
                format!(
                    "controller kind `{}` does not use a switching surface: remove [surface]",
                    s.controller.kind()
                ),
            );
        }
        if s.output.decimate == 0 {
            return bad("output.decimate", "must be >= 1".into());
        }
        let actuator = Actuator::try_new(&s.actuator).map_err(|e| param_err("actuator", e))?;
        let sensor = Sensor::try_new(&s.sensor).map_err(|e| param_err("sensor", e))?;
        let policy = FaultPolicy {
            safe: match s.fault.safe_command {
                SafeCommandCfg::HoldLast => SafeCommand::HoldLast,
                SafeCommandCfg::Zero => SafeCommand::Zero,
            },
            limits: Limits {
                x: s.fault.measurement_limit.unwrap_or([f64::INFINITY; 3]),
                u: actuator.limit(),
            },
        };
        policy.validate().map_err(|e| {
            let (_, r) = param_err("fault", e);
            ("fault.measurement_limit".to_string(), r)
        })?;
        let model = NominalModel::new(s.servo(), s.load_model());
        let sim_cfg = s.sim_config();
        let design = Design {
            model,
            surface,
            dt: sim_cfg.step,
        };
        s.controller.visit(Check(&design))?;
        Ok(Setup {
            plant: s.plant.model,
            model,
            design,
            controller: s.controller.clone(),
            stages: Stages {
                uncertainty: s.uncertainty_spec(),
                actuator,
                sensor,
                policy,
            },
            sim: sim_cfg,
            reference,
            settle: s.simulation.settle,
            horizon: s.simulation.horizon,
            period: s.reference.period(s.simulation.horizon),
        })
    }
}

/// Builds the controller once to check its parameters.
struct Check<'a>(&'a Design);

impl super::Visit for Check<'_> {
    type Out = Result<(), (String, String)>;
    fn visit<K: super::ControllerConfig>(self, cfg: &K) -> Self::Out {
        cfg.build(self.0)
            .map(|_| ())
            .map_err(|e| param_err("controller", e))
    }
}

impl Scenario {
    /// The physical parameters.
    pub fn servo(&self) -> ServoParams {
        self.plant.params
    }

    /// The switching surface from `poles` or `p` (the paper's by default).
    pub fn surface(&self) -> Result<SwitchingSurface, (String, String)> {
        match (self.surface.poles, self.surface.p) {
            (Some(_), Some(_)) => Err((
                "surface".into(),
                "give either `poles` or `p`, not both".into(),
            )),
            (Some(poles), None) => SwitchingSurface::from_poles(poles).map_err(|e| {
                // The poles are what the user set: name them, and the
                // coefficient they gave if that is what failed.
                let (_, r) = param_err("surface", e);
                let r = if matches!(e.name, "p1" | "p2" | "p3") {
                    format!("these poles give {} out of range: {r}", e.name)
                } else {
                    r
                };
                ("surface.poles".to_string(), r)
            }),
            (None, Some(p)) => SwitchingSurface::try_new(p).map_err(|e| {
                let (_, r) = param_err("surface", e);
                ("surface.p".into(), r)
            }),
            (None, None) => Ok(SwitchingSurface::paper()),
        }
    }

    /// The load model.
    pub fn load_model(&self) -> Load {
        self.load
    }

    /// The reference, checked and built (a CSV file is read).
    pub fn reference(&self) -> Result<AnyReference, (String, String)> {
        self.reference.build(
            self.simulation.horizon,
            self.simulation.theta_limit,
            self.base_dir.as_deref(),
        )
    }

    /// The span (s) along which the analyses sample the reference: one
    /// period of a sine, the horizon otherwise.
    pub fn reference_span(&self) -> f64 {
        match self.reference.kind {
            super::ReferenceKind::Sine => 1.0 / self.reference.frequency_hz.unwrap_or(1.0),
            _ => self.simulation.horizon,
        }
    }

    /// The true variation.
    pub fn uncertainty_spec(&self) -> UncertaintySpec {
        self.uncertainty
    }

    /// The loop's settings.
    pub fn sim_config(&self) -> SimConfig {
        let s = &self.simulation;
        SimConfig {
            steps: (s.horizon / s.step).round() as u64,
            step: s.step,
            mode: s.mode,
            substeps: s.substeps,
            theta_limit: s.theta_limit,
            x0: s.x0,
        }
    }
}
