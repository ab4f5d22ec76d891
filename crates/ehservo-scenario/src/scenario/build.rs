//! From a scenario to what a simulation is made of, checked once: the
//! nominal model, the surface, the controller's design context, the stages
//! around the plant, the loop's settings and the reference. Validation *is*
//! this construction: a scenario is valid exactly when [`Setup::new`]
//! succeeds, so no key is checked in one place and used unchecked in another.

use super::{
    AnyPlant, AnyReference, ControllerCfg, EstimatorCfg, SafeCommandCfg, Scenario, MAX_STEPS,
};
use ehservo_core::control::Design;
use ehservo_core::error::ParamError;
use ehservo_core::sampled::{FaultPolicy, Limits, SafeCommand};
use ehservo_core::servo::{Load, NominalModel, ServoParams};
use ehservo_core::surface::SwitchingSurface;
use ehservo_sim::actuator::Actuator;
use ehservo_sim::axis::Axis;
use ehservo_sim::estimator::AnyEstimator;
use ehservo_sim::plant::{PlantContext, UncertaintySpec};
use ehservo_sim::sensor::Sensor;
use ehservo_sim::simulation::Mode;
use ehservo_sim::simulation::{SimConfig, Stages};

/// Most draws of the random variation one run may ask for (horizon/hold).
pub const MAX_DRAWS: f64 = 1.0e8;

/// A validated scenario, built.
#[derive(Debug, Clone)]
pub struct Setup {
    /// The true plant, built.
    pub plant: AnyPlant,
    /// Its axis: what the position is and the unit it is shown in.
    pub axis: Axis,
    /// The nominal model (what the controller is designed on).
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
            // Either key may be the one to change: the message names both.
            return bad(
                "simulation.horizon",
                format!(
                    "horizon/step = {} s / {} s = {n:.3e} steps exceeds the limit of \
                     {MAX_STEPS}: shorten the horizon or lengthen the step",
                    sim.horizon, sim.step
                ),
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
        // The work, bounded up front (law, RK4 and estimator evaluations).
        crate::limits::check_run(s)?;
        // settle ≥ horizon is allowed: the windowed metrics are then absent.
        if !(sim.settle.is_finite() && sim.settle >= 0.0) {
            return bad(
                "simulation.settle",
                format!("must be finite and >= 0 (got {:?})", sim.settle),
            );
        }
        let axis = s.plant.axis();
        if !(sim.theta_limit.is_finite() && sim.theta_limit > 0.0) {
            return bad(
                "simulation.theta_limit",
                format!("must be finite and > 0 (got {:?})", sim.theta_limit),
            );
        }
        // The default's bits exactly: the key was not set (or set to it).
        let limit_set =
            sim.theta_limit.to_bits() != super::SimulationCfg::default().theta_limit.to_bits();
        if s.plant.end_stops() && limit_set {
            return bad(
                "simulation.theta_limit",
                format!(
                    "plant.model = \"{}\" has end stops and runs on at them: there is no position limit (a run diverges only when its state stops being finite)",
                    s.plant.model()
                ),
            );
        }
        if let Some(v) = sim.x0.iter().find(|v| !v.is_finite()) {
            return bad("simulation.x0", format!("must be finite (got {v})"));
        }
        if axis == Axis::Rotary && !s.plant.end_stops() && sim.x0[0].abs() > sim.theta_limit {
            return bad(
                "simulation.x0",
                "θ(0) is beyond simulation.theta_limit".into(),
            );
        }

        if !s.plant.paper_uncertainty() {
            if let Some((k, _)) = s.uncertainty.paper_keys().iter().find(|(_, v)| v.is_some()) {
                return bad(
                    &format!("uncertainty.{k}"),
                    format!(
                        "the paper's Δa_i/Δb form belongs to the third-order family: plant.model = \"{}\" varies by [uncertainty.physical] (mass, bulk_modulus, leakage, supply_pressure, friction, load: {{ bias, random }} fractions)",
                        s.plant.model()
                    ),
                );
            }
        }
        if s.load.is_some() && !s.plant.uses_load() {
            return bad(
                "load",
                format!(
                    "plant.model = \"{}\" takes its loads in [plant.load] (forces on the rod), not the rotary family's [load] torque: remove [load]",
                    s.plant.model()
                ),
            );
        }
        let spec = s.uncertainty_spec();
        let u = &spec;
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
        u.physical
            .validate()
            .map_err(|(k, r)| (format!("uncertainty.physical.{k}"), r))?;
        let draws = sim.horizon / u.hold;
        if u.is_random() && draws > MAX_DRAWS {
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
        // The reference's range is sampled only where something needs it: a
        // linear axis's stroke, or a rotary reference with an offset (the
        // kinds' own checks above cover the rest, and a sweep builds this
        // for every run).
        let reference_range =
            (axis == Axis::Linear || s.plant.end_stops() || s.reference.offset_deg.is_some())
                .then(|| range_of(&reference, s.simulation.horizon, s.simulation.step));
        if reference_range
            .filter(|_| axis == Axis::Rotary && !s.plant.end_stops())
            .is_some_and(|(lo, hi)| lo.abs().max(hi.abs()) >= sim.theta_limit)
        {
            return bad(
                "reference",
                "the reference reaches simulation.theta_limit: every run would count as diverged"
                    .into(),
            );
        }
        let plant = s.plant.build(&PlantContext {
            load: s.load,
            load_given: s.load.is_some(),
            uncertainty: spec,
            x0: sim.x0,
            base_dir: s.base_dir.clone(),
            reference_range,
        })?;
        let model = *plant.nominal();

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
        // RK4 is stable for a real or lightly damped eigenvalue λ while
        // |λ|·h ≲ 2.5–2.8: a faster spool than the plant's step would make
        // the run numerical noise, so it is refused with the fix.
        let hs = match sim.mode {
            ehservo_sim::simulation::Mode::Sampled => sim.step / sim.substeps as f64,
            ehservo_sim::simulation::Mode::Continuous => sim.step,
        };
        let rate = actuator.fastest_rate();
        if rate * hs > 2.5 {
            let key = if s.actuator.bandwidth_hz.is_some() {
                "actuator.bandwidth_hz"
            } else if s.actuator.natural_frequency.is_some() {
                "actuator.natural_frequency"
            } else {
                "actuator.time_constant"
            };
            let fix = match sim.mode {
                ehservo_sim::simulation::Mode::Sampled => format!(
                    "set simulation.substeps >= {}",
                    (rate * sim.step / 2.5).ceil() as u64
                ),
                ehservo_sim::simulation::Mode::Continuous => {
                    format!("set simulation.step <= {:.3e}", 2.5 / rate)
                }
            };
            return bad(
                key,
                format!(
                    "the spool's dynamics (|λ| = {rate:.4} 1/s) are too fast for the plant's RK4 step of {hs:e} s (unstable beyond |λ|·h ≈ 2.5): {fix}"
                ),
            );
        }
        let sensor = Sensor::try_new(&s.sensor).map_err(|e| param_err("sensor", e))?;
        let estimator = s.estimator_for(&model, sim_cfg_step(s))?;
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
        let sim_cfg = s.sim_config();
        let design = Design {
            model,
            surface,
            dt: sim_cfg.step,
        };
        s.controller.visit(Check(&design))?;
        Ok(Setup {
            plant,
            axis,
            model,
            design,
            controller: s.controller.clone(),
            stages: Stages {
                uncertainty: spec,
                actuator,
                sensor,
                policy,
                estimator,
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

/// The estimator of `[estimator]` for the sample period `h`.
fn build_estimator(
    cfg: &EstimatorCfg,
    model: &NominalModel,
    h: f64,
    sensor: &ehservo_sim::sensor::SensorConfig,
) -> Result<AnyEstimator, (String, String)> {
    use ehservo_core::estimate::Levant;
    let err = |e: ParamError| {
        // The design's own names (h, a1, …) are not keys: name the table.
        let key = match e.name {
            "lipschitz" | "substeps" | "poles" | "process_noise" | "measurement_noise" => {
                format!("estimator.{}", e.name)
            }
            n if n.starts_with('p') && n.len() == 2 => "estimator.poles".to_string(),
            _ => "estimator".to_string(),
        };
        let (_, reason) = param_err("estimator", e);
        (key, reason)
    };
    Ok(match *cfg {
        EstimatorCfg::Levant {
            lipschitz,
            substeps,
        } => AnyEstimator::Levant(
            Levant::try_new(lipschitz, h)
                .and_then(|l| l.with_substeps(substeps))
                .map_err(err)?,
        ),
        EstimatorCfg::Luenberger { poles } => {
            if let Some(p) = poles.iter().find(|p| !(p.is_finite() && **p < 0.0)) {
                return Err((
                    "estimator.poles".into(),
                    format!("must be finite and < 0 (got {p:?})"),
                ));
            }
            AnyEstimator::Linear(crate::observer_design::luenberger(model, poles, h).map_err(err)?)
        }
        EstimatorCfg::Kalman {
            process_noise,
            measurement_noise,
        } => {
            // By default the θ channel's noise: the Gaussian σ², plus the
            // quantisation's q²/12.
            let r = measurement_noise.unwrap_or(
                sensor.noise[0] * sensor.noise[0]
                    + sensor.resolution[0] * sensor.resolution[0] / 12.0,
            );
            if !(r.is_finite() && r > 0.0) {
                return Err((
                    "estimator.measurement_noise".into(),
                    if measurement_noise.is_none() {
                        "θ's sensor is exact (sensor.noise and sensor.resolution of θ are 0): give the variance the filter should assume".into()
                    } else {
                        format!("must be finite and > 0 (got {r:?})")
                    },
                ));
            }
            AnyEstimator::Linear(
                crate::observer_design::kalman(model, process_noise, r, h).map_err(err)?,
            )
        }
    })
}

fn sim_cfg_step(s: &Scenario) -> f64 {
    s.simulation.step
}

impl Scenario {
    /// The stages that live on the samples of the sampled loop — sensor
    /// noise and delay, an estimator, a computation delay — checked against
    /// the mode, and the estimator built for the sample period `h`.
    pub fn estimator(&self, h: f64) -> Result<Option<AnyEstimator>, (String, String)> {
        self.estimator_for(&self.nominal_model(), h)
    }

    /// [`Scenario::estimator`] on the nominal model `model`.
    pub fn estimator_for(
        &self,
        model: &NominalModel,
        h: f64,
    ) -> Result<Option<AnyEstimator>, (String, String)> {
        let bad = |k: &str, r: &str| Err((k.to_string(), r.to_string()));
        let sampled = self.simulation.mode == Mode::Sampled;
        let need =
            "needs simulation.mode = \"sampled\" (a continuous law has no samples to draw it at)";
        if !sampled {
            if self.sensor.noise.iter().any(|&v| v != 0.0) {
                return bad("sensor.noise", need);
            }
            if self.sensor.delay > 0 {
                return bad("sensor.delay", need);
            }
            if self.simulation.computation_delay {
                return bad("simulation.computation_delay", need);
            }
            if self.estimator.is_some() {
                return bad(
                    "estimator",
                    "an estimator runs at the controller's rate: it needs simulation.mode = \"sampled\"",
                );
            }
        }
        let missing = self.sensor.measured.missing();
        let Some(cfg) = &self.estimator else {
            if !missing.is_empty() {
                return Err((
                    "sensor.measured".into(),
                    format!(
                        "{} not measured: set an [estimator] (kind = \"levant\", \"luenberger\" or \"kalman\") to estimate {}",
                        missing.join(" and "),
                        if missing.len() > 1 { "them" } else { "it" }
                    ),
                ));
            }
            return Ok(None);
        };
        build_estimator(cfg, model, h, &self.sensor).map(Some)
    }

    /// The nominal model a controller is designed on: the paper family's
    /// `[plant.params]` and `[load]`, or the built plant's (a default one if
    /// the scenario does not build: callers hold validated scenarios).
    pub fn nominal_model(&self) -> NominalModel {
        if let Some(p) = self.paper_params() {
            return NominalModel::new(p, self.load_model());
        }
        self.setup()
            .map(|s| s.model)
            .unwrap_or_else(|_| NominalModel::new(ServoParams::paper(), Load::paper()))
    }

    /// The physical parameters of a plant of the third-order family
    /// (`[plant.params]`).
    pub fn paper_params(&self) -> Option<ServoParams> {
        use ehservo_sim::physical::PhysicalCfg;
        use ehservo_sim::third_order::ThirdOrderCfg;
        self.plant
            .get::<ThirdOrderCfg>()
            .map(|c| c.params)
            .or_else(|| self.plant.get::<PhysicalCfg>().map(|c| c.params))
    }

    /// The paper's parameters of the nominal model.
    pub fn servo(&self) -> ServoParams {
        self.paper_params()
            .unwrap_or_else(|| self.nominal_model().params)
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

    /// The load model of the third-order family: `[load]`, the paper's
    /// `2·sin(4θ)` N·m when absent.
    pub fn load_model(&self) -> Load {
        self.load.unwrap_or_else(Load::paper)
    }

    /// The reference, checked and built (a CSV file is read), on the
    /// plant's axis.
    pub fn reference(&self) -> Result<AnyReference, (String, String)> {
        let axis = self.plant.axis();
        let limit = if self.plant.end_stops() {
            f64::INFINITY
        } else {
            self.simulation.theta_limit
        };
        self.reference.build_on(
            axis,
            self.simulation.horizon,
            limit,
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

    /// The true variation, resolved for the plant (the paper's keys at
    /// the Fig. 2 case for the third-order family, zero for another).
    pub fn uncertainty_spec(&self) -> UncertaintySpec {
        self.uncertainty.resolve(self.plant.paper_uncertainty())
    }

    /// The loop's settings.
    pub fn sim_config(&self) -> SimConfig {
        let s = &self.simulation;
        SimConfig {
            steps: (s.horizon / s.step).round() as u64,
            step: s.step,
            mode: s.mode,
            substeps: s.substeps,
            // A linear axis runs on at its end stops: only a non-finite
            // state ends it.
            theta_limit: if self.plant.end_stops() {
                f64::INFINITY
            } else {
                s.theta_limit
            },
            x0: s.x0,
            computation_delay: s.computation_delay,
        }
    }
}

/// The smallest and largest position of `r` over `[0, horizon]`, sampled
/// at the loop's `step` (at least 10 000 points, at most 2·10⁶).
fn range_of(r: &AnyReference, horizon: f64, step: f64) -> (f64, f64) {
    use ehservo_core::reference::Reference;
    let n = ((horizon / step).ceil() as usize).clamp(10_000, 2_000_000);
    (0..=n)
        .map(|i| r.z(horizon * i as f64 / n as f64)[0])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}
