//! From a scenario to its [`Loop`], checked once: the loop's settings, the
//! variation, the reference, the plant and its nominal model, the surface,
//! the stages around the plant and the controller, built. Validation *is*
//! this construction: a scenario is valid exactly when [`Loop::new`]
//! succeeds, and each key is checked here, in the step that uses it.

use super::closed_loop::{Loop, Parts};
use super::{AnyReference, ControllerCfg, EstimatorCfg, SafeCommandCfg, Scenario, MAX_STEPS};
use ehservo_core::control::Design;
use ehservo_core::error::ParamError;
use ehservo_core::sampled::{FaultPolicy, Limits, SafeCommand};
use ehservo_core::servo::{Load, NominalModel, ServoParams};
use ehservo_core::surface::SwitchingSurface;
use ehservo_sim::actuator::Actuator;
use ehservo_sim::axis::Axis;
use ehservo_sim::error::{non_negative, positive, KeyError, Reason};
use ehservo_sim::estimator::AnyEstimator;
use ehservo_sim::plant::{PlantContext, UncertaintySpec};
use ehservo_sim::sensor::Sensor;
use ehservo_sim::simulation::{Mode, Settings, SimConfig, SolverKind, Stages};

/// Most draws of the random variation one run may ask for (horizon/hold).
pub const MAX_DRAWS: f64 = 1.0e8;

/// `Err` of key `key` for `reason`.
fn bad<T>(key: &str, reason: impl Into<Reason>) -> Result<T, KeyError> {
    Err(KeyError::new(key, reason))
}

/// Builds the loop of `s`, checking every key. The error is the first
/// key that fails, with the reason.
pub(super) fn build(s: &Scenario) -> Result<Parts, KeyError> {
    check_simulation(s)?;
    // The work, bounded up front (law, RK4 and estimator evaluations).
    crate::limits::check_run(s)?;
    check_position_limit(s)?;
    let spec = check_uncertainty(s)?;
    check_quantity(s)?;
    let reference = s.reference()?;
    let reference_range = reference_range(s, &reference)?;
    let plant = s.plant.build(&PlantContext {
        load: s.load,
        load_given: s.load.is_some(),
        uncertainty: spec,
        x0: s.simulation.x0,
        base_dir: s.base_dir.clone(),
        reference_range,
        quantity: s.reference.quantity,
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
    if let (Axis::Linear, ControllerCfg::OpenLoop(c)) = (plant.axis(), &s.controller) {
        if c.volts_per_deg.is_some() {
            return bad(
                "controller.volts_per_deg",
                "is a rotary axis's gain (V/°): on this linear axis give volts_per_mm (V/mm)",
            );
        }
        if c.volts_per_mm.is_none() {
            return bad(
                "controller.volts_per_mm",
                "is required by kind `open-loop` on a linear axis (the default of 1 is V/°, a rotary axis's)",
            );
        }
    }
    if s.output.decimate == 0 {
        return bad("output.decimate", "must be >= 1");
    }
    if s.plant.steps_itself() {
        // A co-simulation FMU is advanced by its doStep over each sample
        // period: it has no derivative for these to integrate.
        if s.simulation.mode != Mode::Sampled {
            return bad(
                "simulation.mode",
                "a co-simulation FMU plant steps itself each sample period: use mode = \"sampled\"",
            );
        }
        if s.simulation.solver != SolverKind::Rk4 {
            return bad(
                "simulation.solver",
                "a co-simulation FMU plant steps itself each sample period with its own solver: use solver = \"rk4\"",
            );
        }
    }
    let sim = s.sim_config();
    let stages = stages(s, spec, &model)?;
    let settings = Settings::try_new(stages, sim).map_err(|e| KeyError::param("simulation", e))?;
    let settings = match super::solver::adaptive(s, plant.state_dim())? {
        Some(a) => settings
            .with_adaptive(a)
            .map_err(|e| KeyError::param("simulation", e))?,
        None => settings,
    };
    let design = Design {
        model,
        surface,
        dt: sim.step,
    };
    let controller = s
        .controller
        .build(&design)
        .map_err(|e| design_refusal(e, &model, plant.axis().si_unit()))?;
    Ok(Parts {
        axis: plant.axis(),
        plant,
        model,
        design,
        controller,
        settings,
        reference,
        settle: s.simulation.settle,
        horizon: s.simulation.horizon,
        period: s.reference.period(s.simulation.horizon),
    })
}

/// A controller's refusal under `controller.<name>`. A refusal that
/// depends on the plant (a pole the model cannot take, a gain of the wrong
/// sign) also names the nominal model's numbers it was judged on, so the
/// user can see why and what to set instead; a plain out-of-range value
/// (not finite, not > 0) is the value's own fault and says only that.
fn design_refusal(e: ParamError, model: &NominalModel, unit: &str) -> KeyError {
    let own = matches!(
        e.reason,
        "must be finite and > 0" | "must be finite and >= 0" | "must be finite"
    );
    if own {
        return KeyError::param("controller", e);
    }
    KeyError::new(
        format!("controller.{}", e.name),
        format!("{}; {}", Reason::Param(e), model_numbers(model, unit)),
    )
}

/// The nominal third-order model's numbers in one phrase: ā1, ā2, ā3, b̄0,
/// and the hydraulic resonance `s² + ā3·s + ā2` as ω_h = √ā2 and
/// ζ_h = ā3/(2ω_h) when ā2 > 0. `unit` is the axis's SI unit (m or rad).
pub(crate) fn model_numbers(model: &NominalModel, unit: &str) -> String {
    let a = model.coeffs.as_array();
    let mut s = format!(
        "nominal model ā1 = {:.4e} 1/s³, ā2 = {:.4e} 1/s², ā3 = {:.4e} 1/s, b̄0 = {:.4e} {unit}/(s³·V)",
        a[0],
        a[1],
        a[2],
        model.b_at_rest()
    );
    if a[1] > 0.0 && a[1].is_finite() {
        let wh = a[1].sqrt();
        s.push_str(&format!(
            ", ω_h = {wh:.1} rad/s ({:.2} Hz), ζ_h = {:.4}",
            wh / std::f64::consts::TAU,
            a[2] / (2.0 * wh)
        ));
    } else {
        s.push_str(", no hydraulic resonance (ā2 <= 0)");
    }
    s
}

/// `[simulation]`: the step, the horizon (a whole number of steps, at most
/// [`MAX_STEPS`]), the sub-steps and the settling time.
fn check_simulation(s: &Scenario) -> Result<(), KeyError> {
    let sim = &s.simulation;
    positive("simulation.step", sim.step)?;
    positive("simulation.horizon", sim.horizon)?;
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
    Ok(())
}

/// `simulation.settle`, `simulation.theta_limit` and `simulation.x0`: the
/// position limit applies to a plant without end stops only.
fn check_position_limit(s: &Scenario) -> Result<(), KeyError> {
    let sim = &s.simulation;
    // settle ≥ horizon is allowed: the windowed metrics are then absent.
    non_negative("simulation.settle", sim.settle)?;
    positive("simulation.theta_limit", sim.theta_limit)?;
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
    if s.plant.axis() == Axis::Rotary && !s.plant.end_stops() && sim.x0[0].abs() > sim.theta_limit {
        return bad("simulation.x0", "θ(0) is beyond simulation.theta_limit");
    }
    Ok(())
}

/// `[uncertainty]` and `[load]` for the plant's family, resolved.
fn check_uncertainty(s: &Scenario) -> Result<UncertaintySpec, KeyError> {
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
    let u = s.uncertainty_spec();
    for (k, v) in [
        ("uncertainty.a_bias", u.a_bias),
        ("uncertainty.a_random", u.a_random),
        ("uncertainty.b_bias", u.b_bias),
        ("uncertainty.b_random", u.b_random),
    ] {
        if !v.is_finite() {
            return bad(k, Reason::NotFinite(v));
        }
    }
    positive("uncertainty.hold", u.hold)?;
    u.physical
        .validate()
        .map_err(|e| e.under("uncertainty.physical"))?;
    let draws = s.simulation.horizon / u.hold;
    if u.is_random() && draws > MAX_DRAWS {
        return bad(
            "uncertainty.hold",
            format!(
                "a random variation held {:?} s over {:?} s is {draws:.2e} draws, more than the limit of {MAX_DRAWS:.0e}",
                u.hold, s.simulation.horizon
            ),
        );
    }
    positive("uncertainty.b_reference", u.b_reference)?;
    // The true b must stay positive: 1 + b_ref·(b_bias ± b_random) > 0.
    if 1.0 + u.b_reference * (u.b_bias - u.b_random.abs()) <= 0.0 {
        return bad(
            "uncertainty.b_bias",
            "the true b = b̄·(1 + b_reference·(b_bias + b_random·r)) must stay > 0 (Assumption A1)",
        );
    }
    Ok(u)
}

/// The reference's smallest and largest position, sampled where something
/// needs it: a linear axis's stroke, a plant with end stops, or a rotary
/// reference with an offset (the kinds' own checks cover the rest, and a
/// sweep builds this for every run). A rotary reference must stay inside
/// the position limit. The open loop's reference is a command
/// (`volts_per_deg`·θd), not a position: it has no range to check.
fn reference_range(s: &Scenario, reference: &AnyReference) -> Result<Option<(f64, f64)>, KeyError> {
    let axis = s.plant.axis();
    let position = s.controller.kind() != "open-loop" && s.reference.quantity.is_position();
    let range = (position
        && (axis == Axis::Linear || s.plant.end_stops() || s.reference.offset_deg.is_some()))
    .then(|| range_of(reference, s.simulation.horizon, s.simulation.step));
    if range
        .filter(|_| axis == Axis::Rotary && !s.plant.end_stops())
        .is_some_and(|(lo, hi)| lo.abs().max(hi.abs()) >= s.simulation.theta_limit)
    {
        return bad(
            "reference",
            "the reference reaches simulation.theta_limit: every run would count as diverged",
        );
    }
    Ok(range)
}

/// The loop's quantity (`reference.quantity`) against the plant and the
/// controller: a force or a pressure needs a plant with pressure states
/// (a cylinder: the rest it checks itself, `CylinderCfg::build`), and each
/// controller kind closes one kind of loop ([`Config::CLOSES_ON_FORCE`]).
///
/// [`Config::CLOSES_ON_FORCE`]: ehservo_core::control::Config::CLOSES_ON_FORCE
fn check_quantity(s: &Scenario) -> Result<(), KeyError> {
    let q = s.reference.quantity;
    let kind = s.controller.kind();
    if !q.is_position() && s.plant.model() != "cylinder" {
        return bad(
            "reference.quantity",
            format!(
                "`{}` needs a plant with chamber pressures: model `{}` has none (use model = \"cylinder\")",
                q.name(),
                s.plant.model()
            ),
        );
    }
    if !q.is_position() && s.estimator.is_some() {
        // The estimators are designed on the position's model: x = (q, ẏ, ÿ)
        // is not a chain of derivatives they could estimate.
        return bad(
            "estimator",
            format!(
                "an estimator of x is designed on the position's model: a `{}` loop measures its channels (set [sensor] measured to all three)",
                q.name()
            ),
        );
    }
    match (q.is_position(), s.controller.closes_on_force()) {
        (true, true) => bad(
            "controller.kind",
            format!("`{kind}` closes a force or pressure loop: set [reference] quantity = \"force\" or \"load-pressure\""),
        ),
        (false, false) => bad(
            "controller.kind",
            format!(
                "`{kind}` closes a position loop; this loop's quantity is `{}`: use kind = \"force-pi\"",
                q.name()
            ),
        ),
        _ => Ok(()),
    }
}

/// The stages around the plant: the variation, the valve, the sensors,
/// the estimator and the fault policy.
fn stages(s: &Scenario, spec: UncertaintySpec, model: &NominalModel) -> Result<Stages, KeyError> {
    let actuator = Actuator::try_new(&s.actuator).map_err(|e| KeyError::param("actuator", e))?;
    check_spool_rate(s, &actuator)?;
    let sensor = Sensor::try_new(&s.sensor).map_err(|e| KeyError::param("sensor", e))?;
    let estimator = s.estimator_for(model, s.simulation.step)?;
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
    policy
        .validate()
        .map_err(|e| KeyError::param("fault", e).at("fault.measurement_limit"))?;
    Ok(Stages {
        uncertainty: spec,
        actuator,
        sensor,
        policy,
        estimator,
    })
}

/// RK4 is stable for a real or lightly damped eigenvalue λ while
/// |λ|·h ≲ 2.5–2.8: a faster spool than the plant's step would make the
/// run numerical noise, so it is refused with the fix.
fn check_spool_rate(s: &Scenario, actuator: &Actuator) -> Result<(), KeyError> {
    let sim = &s.simulation;
    let hs = match sim.mode {
        Mode::Sampled => sim.step / sim.substeps as f64,
        Mode::Continuous => sim.step,
    };
    let rate = actuator.fastest_rate();
    if rate * hs <= 2.5 {
        return Ok(());
    }
    let key = if s.actuator.bandwidth_hz.is_some() {
        "actuator.bandwidth_hz"
    } else if s.actuator.natural_frequency.is_some() {
        "actuator.natural_frequency"
    } else {
        "actuator.time_constant"
    };
    let fix = match sim.mode {
        Mode::Sampled => format!(
            "set simulation.substeps >= {}",
            (rate * sim.step / 2.5).ceil() as u64
        ),
        Mode::Continuous => format!("set simulation.step <= {:.3e}", 2.5 / rate),
    };
    bad(
        key,
        format!(
            "the spool's dynamics (|λ| = {rate:.4} 1/s) are too fast for the plant's RK4 step of {hs:e} s (unstable beyond |λ|·h ≈ 2.5): {fix}"
        ),
    )
}

/// The estimator of `[estimator]` for the sample period `h`.
fn build_estimator(
    cfg: &EstimatorCfg,
    model: &NominalModel,
    h: f64,
    sensor: &ehservo_sim::sensor::SensorConfig,
) -> Result<AnyEstimator, KeyError> {
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
        KeyError::new(key, Reason::Param(e))
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
                return bad(
                    "estimator.poles",
                    format!("must be finite and < 0 (got {p:?})"),
                );
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
                return bad(
                    "estimator.measurement_noise",
                    if measurement_noise.is_none() {
                        "θ's sensor is exact (sensor.noise and sensor.resolution of θ are 0): give the variance the filter should assume".to_string()
                    } else {
                        format!("must be finite and > 0 (got {r:?})")
                    },
                );
            }
            AnyEstimator::Linear(
                crate::observer_design::kalman(model, process_noise, r, h).map_err(err)?,
            )
        }
    })
}

impl Scenario {
    /// [`Scenario::estimator`] on the nominal model `model`: the stages
    /// that live on the samples of the sampled loop — sensor noise and
    /// delay, an estimator, a computation delay — checked against the
    /// mode, and the estimator built for the sample period `h`.
    pub(crate) fn estimator_for(
        &self,
        model: &NominalModel,
        h: f64,
    ) -> Result<Option<AnyEstimator>, KeyError> {
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
                return bad(
                    "sensor.measured",
                    format!(
                        "{} not measured: set an [estimator] (kind = \"levant\", \"luenberger\" or \"kalman\") to estimate {}",
                        missing.join(" and "),
                        if missing.len() > 1 { "them" } else { "it" }
                    ),
                );
            }
            return Ok(None);
        };
        build_estimator(cfg, model, h, &self.sensor).map(Some)
    }

    /// The physical parameters of a plant of the third-order family
    /// (`[plant.params]`).
    pub(crate) fn paper_params(&self) -> Option<ServoParams> {
        self.plant.paper_params()
    }

    /// The switching surface from `poles` or `p` (the paper's by default).
    pub(crate) fn surface(&self) -> Result<SwitchingSurface, KeyError> {
        match (self.surface.poles, self.surface.p) {
            (Some(_), Some(_)) => bad("surface", "give either `poles` or `p`, not both"),
            (Some(poles), None) => SwitchingSurface::from_poles(poles).map_err(|e| {
                // The poles are what the user set: name them, and the
                // coefficient they gave if that is what failed.
                let r = Reason::Param(e).to_string();
                let r = if matches!(e.name, "p1" | "p2" | "p3") {
                    format!("these poles give {} out of range: {r}", e.name)
                } else {
                    r
                };
                KeyError::new("surface.poles", r)
            }),
            (None, Some(p)) => SwitchingSurface::try_new(p)
                .map_err(|e| KeyError::new("surface.p", Reason::Param(e))),
            (None, None) => Ok(SwitchingSurface::paper()),
        }
    }

    /// The load model of the third-order family: `[load]`, the paper's
    /// `2·sin(4θ)` N·m when absent.
    pub(crate) fn load_model(&self) -> Load {
        self.load.unwrap_or_else(Load::paper)
    }

    /// The reference, checked and built (a CSV file is read), on the
    /// plant's axis.
    pub(crate) fn reference(&self) -> Result<AnyReference, KeyError> {
        let axis = self.axis();
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

    /// The loop's axis: the plant's, or the force or pressure the loop
    /// closes on (`[reference] quantity`).
    pub fn axis(&self) -> Axis {
        self.reference.quantity.axis_on(self.plant.axis())
    }

    /// The true variation, resolved for the plant (the paper's keys at
    /// the Fig. 2 case for the third-order family, zero for another).
    pub(crate) fn uncertainty_spec(&self) -> UncertaintySpec {
        self.uncertainty.resolve(self.plant.paper_uncertainty())
    }

    /// The loop's settings.
    pub(crate) fn sim_config(&self) -> SimConfig {
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

impl Loop {
    /// The scenario `s` built: every key checked, the plant and the
    /// controller made. The only way to a [`Loop`]; the error names the
    /// scenario (its name as the file), the key and the reason.
    pub fn new(s: Scenario) -> Result<Loop, super::ScenarioError> {
        match build(&s) {
            Ok(parts) => Ok(Loop::from_parts(s, parts)),
            Err(e) => Err(s.error(e)),
        }
    }
}
