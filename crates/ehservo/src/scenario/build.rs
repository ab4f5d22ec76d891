//! From a scenario to what a simulation is made of, checked once: the
//! nominal model, the surface, the controller's design context, the stages
//! around the plant, the loop's settings and the reference. Validation *is*
//! this construction: a scenario is valid exactly when [`Setup::new`]
//! succeeds, so no key is checked in one place and used unchecked in another.

use super::{
    AnyReference, ControllerCfg, EstimatorCfg, PlantModel, SafeCommandCfg, Scenario, MAX_STEPS,
};
use ehservo_core::control::Design;
use ehservo_core::cylinder::CylinderParams;
use ehservo_core::error::ParamError;
use ehservo_core::sampled::{FaultPolicy, Limits, SafeCommand};
use ehservo_core::servo::{Load, NominalModel, ServoParams};
use ehservo_core::surface::SwitchingSurface;
use ehservo_sim::actuator::Actuator;
use ehservo_sim::estimator::AnyEstimator;
use ehservo_sim::plant::UncertaintySpec;
use ehservo_sim::sensor::Sensor;
use ehservo_sim::simulation::Mode;
use ehservo_sim::simulation::{SimConfig, Stages};

/// Most draws of the random variation one run may ask for (horizon/hold).
pub const MAX_DRAWS: f64 = 1.0e8;

/// A validated scenario, built.
#[derive(Debug, Clone)]
pub struct Setup {
    /// Which true plant.
    pub plant: PlantModel,
    /// The cylinder's parameters, with `plant == Cylinder`.
    pub cylinder: Option<CylinderParams>,
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

        let cylinder = s.checked_cylinder()?;

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
        let estimator = s.estimator(sim_cfg_step(s))?;
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
            cylinder,
            model,
            design,
            controller: s.controller.clone(),
            stages: Stages {
                uncertainty: s.uncertainty_spec(),
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
            AnyEstimator::Linear(crate::estimation::luenberger(model, poles, h).map_err(err)?)
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
                crate::estimation::kalman(model, process_noise, r, h).map_err(err)?,
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
        build_estimator(
            cfg,
            &NominalModel::new(self.servo(), self.load_model()),
            h,
            &self.sensor,
        )
        .map(Some)
    }

    /// The physical parameters: `[plant.params]`, or with a cylinder the
    /// paper's parameters equal to its linearisation (docs/cylinder.md).
    pub fn servo(&self) -> ServoParams {
        match self.plant.model {
            PlantModel::Cylinder => self.cylinder().nominal_servo_params(),
            _ => self.plant.params,
        }
    }

    /// `[plant.cylinder]`, the documented typical set when absent.
    pub fn cylinder(&self) -> CylinderParams {
        self.plant.cylinder.unwrap_or_default()
    }

    /// The cylinder's checks (`Some` with `model = "cylinder"`): its
    /// parameters, no `[plant.params]` beside it, the reference and x(0)
    /// inside the stroke; and no `[plant.cylinder]` on another model.
    fn checked_cylinder(&self) -> Result<Option<CylinderParams>, (String, String)> {
        if self.plant.model != PlantModel::Cylinder {
            return match self.plant.cylinder {
                Some(_) => Err((
                    "plant.cylinder".into(),
                    format!(
                        "given, but plant.model is \"{}\": set plant.model = \"cylinder\" or remove [plant.cylinder]",
                        self.plant.model.as_str()
                    ),
                )),
                None => Ok(None),
            };
        }
        if self.plant.params != ServoParams::paper() {
            return Err((
                "plant.params".into(),
                "not used with plant.model = \"cylinder\": the nominal model is derived from [plant.cylinder] (docs/cylinder.md); remove [plant.params]".into(),
            ));
        }
        let c = self.cylinder();
        c.validate().map_err(|e| {
            let prefix = if c.friction.is_some()
                && matches!(
                    e.name,
                    "coulomb" | "stiction" | "stribeck_velocity" | "viscous" | "smoothing"
                ) {
                "plant.cylinder.friction"
            } else {
                "plant.cylinder"
            };
            param_err(prefix, e)
        })?;
        let end = c.stroke_angle();
        // The largest |θd| over the run, sampled at the loop's step (and at
        // least 10 000 points).
        use ehservo_core::reference::Reference;
        let r = self.reference()?;
        let n = ((self.simulation.horizon / self.simulation.step).ceil() as usize).max(10_000);
        let peak = (0..=n)
            .map(|i| r.z(self.simulation.horizon * i as f64 / n as f64)[0].abs())
            .fold(0.0, f64::max);
        if peak >= end {
            return Err((
                match self.reference.kind {
                    super::ReferenceKind::Sine => "reference.amplitude_deg",
                    _ => "reference",
                }
                .into(),
                format!(
                    "the reference reaches the end of the cylinder's stroke, ±{:.4}° (stroke/(2r))",
                    end.to_degrees()
                ),
            ));
        }
        if self.simulation.x0[0].abs() >= end {
            return Err((
                "simulation.x0".into(),
                format!(
                    "θ(0) is beyond the cylinder's stroke, ±{:.4}° (stroke/(2r))",
                    end.to_degrees()
                ),
            ));
        }
        Ok(Some(c))
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
            // A cylinder's run diverges when it reaches the end of its
            // stroke (end stops are not modelled).
            theta_limit: match self.plant.model {
                PlantModel::Cylinder => s.theta_limit.min(self.cylinder().stroke_angle()),
                _ => s.theta_limit,
            },
            x0: s.x0,
            computation_delay: s.computation_delay,
        }
    }
}
