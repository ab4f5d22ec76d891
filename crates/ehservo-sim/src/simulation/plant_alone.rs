//! The plant alone, with its actuator, stepped by a caller who gives the
//! command: what a plant FMU (`ehservo fmu --kind plant`) serves.
//!
//! Each [`PlantAlone::hold`] integrates one sample period h with the
//! command held, exactly as the closed loop's sampled mode does (the same
//! [`Held`] integration: `substeps` RK4 steps of h/substeps, split further
//! for a stiff plant, the variation drawn on the same clock), so a plant
//! fed the commands of a run gives that run's trace to the bit. The run
//! stops, as a result, on the closed loop's divergence rules: a state that
//! is not finite, |x₀| beyond `theta_limit`, a rod past its stop.

use super::sampled::Held;
use super::{Divergence, DivergenceReason, PlantAct, Settings, MAX_STATES};
use crate::actuator::Actuator;
use crate::plant::Plant;
use crate::uncertainty::Varying;
use ehservo_core::rk4::OdeState;

/// What the plant gives at a sample t_k.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlantOutput {
    /// t_k (s).
    pub t: f64,
    /// x = (position, velocity, acceleration) in the axis's SI unit.
    pub x: [f64; 3],
    /// The plant's physical states ([`Plant::STATES`]).
    pub states: [f64; MAX_STATES],
    /// What the plant receives after the actuator under the command (V).
    pub u_plant: f64,
}

/// A plant and its actuator at t_k = k·h, integrated one period at a time
/// under a held command.
///
/// ```
/// use ehservo_sim::actuator::Actuator;
/// use ehservo_sim::core::prelude::*;
/// use ehservo_sim::plant::{ThirdOrderPlant, UncertaintySpec};
/// use ehservo_sim::sensor::Sensor;
/// use ehservo_sim::simulation::{Mode, PlantAlone, Settings, SimConfig, Stages};
///
/// let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::none());
/// let stages = Stages {
///     uncertainty: UncertaintySpec::NONE,
///     actuator: Actuator::IDENTITY,
///     sensor: Sensor::identity(),
///     policy: FaultPolicy::default(),
///     estimator: None,
/// };
/// let cfg = SimConfig {
///     steps: 100,
///     step: 0.01,
///     mode: Mode::Sampled,
///     substeps: 1,
///     theta_limit: 1.0,
///     x0: [0.0; 3],
///     computation_delay: false,
/// };
/// let mut p = PlantAlone::from_settings(plant, &Settings::try_new(stages, cfg)?);
/// // At rest with no command and no load, it stays at rest.
/// p.hold(0.0).expect("finite");
/// assert_eq!((p.time(), p.output(0.0).x), (0.01, [0.0; 3]));
/// // A positive command turns it the positive way.
/// p.hold(1.0).expect("finite");
/// assert!(p.output(1.0).x[1] > 0.0);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone)]
pub struct PlantAlone<P: Plant> {
    plant: P,
    actuator: Actuator,
    unc: Varying<P::Variation>,
    y: PlantAct<P::State>,
    per_hold: Option<u64>,
    step: f64,
    substeps: u64,
    theta_limit: f64,
    k: u64,
    stop: Option<Divergence>,
}

impl<P: Plant> PlantAlone<P> {
    /// The plant of a loop's checked settings at t = 0, x(0) = the
    /// settings' x0, under their uncertainty and actuator; the sensors,
    /// estimator and fault policy are not part of it.
    pub fn from_settings(plant: P, settings: &Settings) -> Self {
        let (stages, cfg) = (settings.stages(), settings.config());
        let substeps = u64::from(cfg.substeps.max(1));
        let hs = cfg.step / substeps as f64;
        let mut unc = Varying::new(&plant, stages.uncertainty);
        let per_hold = unc.signal().steps_per_hold(hs);
        let var0 = unc.at_step(&plant, 0, hs, per_hold);
        Self {
            y: PlantAct {
                x: plant.initial_state(cfg.x0, &var0),
                a: stages.actuator.initial_state(),
            },
            plant,
            actuator: stages.actuator,
            unc,
            per_hold,
            step: cfg.step,
            substeps,
            theta_limit: cfg.theta_limit,
            k: 0,
            stop: None,
        }
    }

    /// The sample period h (s).
    pub fn period(&self) -> f64 {
        self.step
    }

    /// The index k of the current sample.
    pub fn k(&self) -> u64 {
        self.k
    }

    /// The current time t_k = k·h (s).
    pub fn time(&self) -> f64 {
        self.k as f64 * self.step
    }

    /// Why the plant stopped, once it has.
    pub fn stopped(&self) -> Option<Divergence> {
        self.stop
    }

    /// The plant's axis.
    pub fn axis(&self) -> crate::axis::Axis {
        self.plant.axis()
    }

    /// Sets the external load ([`Plant::set_external_load`]; nothing on a
    /// plant without [`Plant::EXTERNAL_LOAD`]).
    pub fn set_external_load(&mut self, load: f64) {
        self.plant.set_external_load(load);
    }

    /// The sub-step and the variation's clock at sub-step `j`, with the
    /// variation there.
    fn variation(&mut self, j: u64) -> (f64, P::Variation) {
        let hs = self.step / self.substeps as f64;
        (hs, self.unc.at_step(&self.plant, j, hs, self.per_hold))
    }

    /// The outputs at t_k, with `u` the command the actuator receives.
    pub fn output(&mut self, u: f64) -> PlantOutput {
        let t = self.time();
        let (_, var) = self.variation(self.k.saturating_mul(self.substeps));
        let x = self.plant.measure(t, &self.y.x, &var);
        let mut states = [0.0; MAX_STATES];
        self.plant.states(t, &self.y.x, &x, &mut states);
        PlantOutput {
            t,
            x,
            states,
            u_plant: self.actuator.output(&self.y.a, u),
        }
    }

    /// Integrates over [t_k, t_{k+1}) with the command `u` (V) held, to
    /// t_{k+1}. A divergence stops the plant there (and every later call
    /// returns it).
    pub fn hold(&mut self, u: f64) -> Result<(), Divergence> {
        if let Some(d) = self.stop {
            return Err(d);
        }
        let t = self.time();
        let j0 = self.k.saturating_mul(self.substeps);
        let (hs, var) = self.variation(j0);
        let held = Held {
            t,
            h: self.step,
            j0,
            hs,
            m: self.substeps,
            per_hold: self.per_hold,
        };
        let resolved = held.integrate(
            &self.plant,
            &self.actuator,
            &mut self.unc,
            &mut self.y,
            u,
            var,
            None,
        );
        self.k = self.k.saturating_add(1);
        let t_next = self.time();
        // The closed loop's checks, in its order (Simulation::advance).
        let reason = if self.plant.failed() {
            Some(DivergenceReason::PlantFailed)
        } else if !self.y.all_finite() {
            Some(DivergenceReason::NonFiniteState)
        } else if self.plant.measure(t_next, &self.y.x, &var)[0].abs() > self.theta_limit {
            Some(DivergenceReason::ThetaLimit)
        } else if self.plant.beyond_stops(&self.y.x, &var) {
            Some(DivergenceReason::BeyondEndStop)
        } else if !resolved {
            Some(DivergenceReason::TooStiff)
        } else {
            None
        };
        match reason {
            Some(reason) => {
                let d = Divergence { t: t_next, reason };
                self.stop = Some(d);
                Err(d)
            }
            None => Ok(()),
        }
    }
}
