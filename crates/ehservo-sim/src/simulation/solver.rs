//! How the plant is integrated between samples: the solvers, one line
//! each in [`solver_kinds!`], and the sampled mode's adaptive step.
//!
//! `"rk4"` is the fixed step with `simulation.substeps` (the loop's own,
//! [`super::sampled`]). An adaptive pair ([`ehservo_core::solver`])
//! integrates the plant and the actuator from each sample instant exactly
//! to the next under the held command, restarting there (no step crosses
//! a sample), with the accepted step size kept as the next sample's first
//! guess. The random parameter variation is drawn once per sample under an
//! adaptive solver (not per sub-step), so that the model does not depend
//! on the steps the solver happens to take.

use super::{DivergenceReason, PlantAct, Simulation};
use crate::actuator::Actuator;
use crate::plant::Plant;
use ehservo_core::control::Controller;
use ehservo_core::error::ParamError;
use ehservo_core::reference::Reference;
use ehservo_core::solver::rosenbrock23::{self, Components, FiniteDifference, Rosenbrock23};
use ehservo_core::solver::{scaled_rms, Adaptive, Failure, Method, StepControl, Tableau};
use serde::{Deserialize, Serialize};

/// The most plant states a per-state `atol` may list.
pub const MAX_ATOL: usize = 8;

/// How an adaptive kind steps: an explicit pair, or the linearly
/// implicit (stiff) Rosenbrock triple with its Jacobian.
#[derive(Debug, Clone, Copy)]
pub enum Scheme {
    /// An embedded explicit Runge–Kutta pair.
    Explicit(&'static Tableau),
    /// `ode23s`'s Rosenbrock triple, J by forward differences.
    Rosenbrock23,
}

impl Scheme {
    /// The method's name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Explicit(t) => t.name,
            Self::Rosenbrock23 => rosenbrock23::NAME,
        }
    }

    /// Right-hand side evaluations a step takes for `dim` integrated
    /// components (the plant's and the actuator's two).
    pub fn evaluations(&self, dim: usize) -> usize {
        match self {
            Self::Explicit(t) => t.stages(),
            Self::Rosenbrock23 => Method::<[f64; 1]>::evaluations(&ROS_FD, dim),
        }
    }

    /// Whether the method needs a Jacobian (and so a state of at most
    /// [`rosenbrock23::MAX_DIM`] components).
    pub fn needs_jacobian(&self) -> bool {
        matches!(self, Self::Rosenbrock23)
    }
}

macro_rules! solver_kinds {
    ($($(#[$doc:meta])* $variant:ident $name:literal => $scheme:expr),* $(,)?) => {
        /// `simulation.solver`: how the plant is integrated between samples.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema)]
        pub enum SolverKind {
            $($(#[$doc])* #[serde(rename = $name)] $variant,)*
        }

        impl SolverKind {
            /// Every solver as a scenario spells it, in list order.
            pub const NAMES: &'static [&'static str] = &[$($name),*];

            /// The scenario spelling.
            pub fn as_str(&self) -> &'static str {
                match self {
                    $(Self::$variant => $name,)*
                }
            }

            /// How it steps, `None` for the fixed-step RK4.
            pub fn scheme(&self) -> Option<Scheme> {
                match self {
                    $(Self::$variant => $scheme,)*
                }
            }
        }
    };
}

solver_kinds! {
    /// The classic fixed-step RK4 with `simulation.substeps` (default).
    #[default]
    Rk4 "rk4" => None,
    /// Dormand–Prince 5(4) with error control.
    Dopri5 "dopri5" => Some(Scheme::Explicit(&ehservo_core::solver::dopri5::DOPRI5)),
    /// Bogacki–Shampine 3(2) with error control (loose tolerances).
    Bs32 "bs32" => Some(Scheme::Explicit(&ehservo_core::solver::bs32::BS32)),
    /// The stiff `ode23s` Rosenbrock triple (Shampine & Reichelt 1997).
    Rosenbrock23 "rosenbrock23" => Some(Scheme::Rosenbrock23),
}

/// The absolute tolerance: one value for every state, or one per plant
/// state in [`Plant::State`]'s order and SI unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Atol {
    values: [f64; MAX_ATOL],
    len: usize,
}

impl Atol {
    /// One value for every plant state.
    pub fn scalar(v: f64) -> Self {
        Self {
            values: [v; MAX_ATOL],
            len: 1,
        }
    }

    /// One value per plant state (at most [`MAX_ATOL`]).
    pub fn per_state(v: &[f64]) -> Result<Self, ParamError> {
        if v.is_empty() || v.len() > MAX_ATOL {
            return Err(ParamError::new(
                "atol",
                "a per-state list must hold one value per plant state (1 to 8)",
                v.len() as f64,
            ));
        }
        let mut values = [0.0; MAX_ATOL];
        values[..v.len()].copy_from_slice(v);
        Ok(Self {
            values,
            len: v.len(),
        })
    }

    /// The values given (one for a scalar).
    pub fn values(&self) -> &[f64] {
        &self.values[..self.len]
    }

    /// Whether one value serves every state.
    pub fn is_scalar(&self) -> bool {
        self.len == 1
    }
}

/// An adaptive solver's settings, checked ([`AdaptiveConfig::try_new`]).
#[derive(Debug, Clone, Copy)]
pub struct AdaptiveConfig {
    kind: SolverKind,
    scheme: Scheme,
    rtol: f64,
    atol: Atol,
    control: StepControl,
}

impl AdaptiveConfig {
    /// `kind` with its tolerances, its largest step (s) and the run's step
    /// budget. Refused: a kind without error control, rtol outside (0, 1),
    /// an atol negative or not finite, a max_step not finite and > 0.
    pub fn try_new(
        kind: SolverKind,
        rtol: f64,
        atol: Atol,
        max_step: f64,
        max_steps: u64,
    ) -> Result<Self, ParamError> {
        let Some(scheme) = kind.scheme() else {
            return Err(ParamError::new(
                "solver",
                "has no error control (rk4)",
                f64::NAN,
            ));
        };
        if !(rtol > 0.0 && rtol < 1.0) {
            return Err(ParamError::new("rtol", "must be in (0, 1)", rtol));
        }
        if let Some(a) = atol
            .values()
            .iter()
            .find(|a| !(a.is_finite() && **a >= 0.0))
        {
            return Err(ParamError::new("atol", "must be finite and >= 0", *a));
        }
        if !(max_step.is_finite() && max_step > 0.0) {
            return Err(ParamError::new(
                "max_step",
                "must be finite and > 0",
                max_step,
            ));
        }
        Ok(Self {
            kind,
            scheme,
            rtol,
            atol,
            control: StepControl {
                max_step,
                max_steps,
            },
        })
    }

    /// The solver.
    pub fn kind(&self) -> SolverKind {
        self.kind
    }
}

/// The scheme is the kind's: equal kinds, tolerances and bounds are equal.
impl PartialEq for AdaptiveConfig {
    fn eq(&self, o: &Self) -> bool {
        (self.kind, self.rtol, self.atol, self.control) == (o.kind, o.rtol, o.atol, o.control)
    }
}

impl AdaptiveConfig {
    /// The solver's name.
    pub fn name(&self) -> &'static str {
        self.scheme.name()
    }

    /// How it steps.
    pub fn scheme(&self) -> Scheme {
        self.scheme
    }

    /// The relative tolerance.
    pub fn rtol(&self) -> f64 {
        self.rtol
    }

    /// The absolute tolerance.
    pub fn atol(&self) -> &Atol {
        &self.atol
    }

    /// The largest step (s).
    pub fn max_step(&self) -> f64 {
        self.control.max_step
    }

    /// The largest number of steps, accepted and rejected, of a run.
    pub fn max_steps(&self) -> u64 {
        self.control.max_steps
    }
}

/// The spool's states (V, V/s) are weighted as quantities of size 1 V:
/// atol = rtol × 1 V.
const SPOOL_SCALE: f64 = 1.0;

/// The norm of an error estimate of the plant and actuator state.
fn norm<S: AsRef<[f64]> + ehservo_core::rk4::OdeState>(
    cfg: &AdaptiveConfig,
    y0: &PlantAct<S>,
    y1: &PlantAct<S>,
    e: &PlantAct<S>,
) -> f64 {
    let (x0, x1, ex) = (y0.x.as_ref(), y1.x.as_ref(), e.x.as_ref());
    let n = x0.len();
    let mut atol = [0.0; MAX_ATOL + 2];
    let given = cfg.atol.values();
    for (i, a) in atol.iter_mut().take(n.min(MAX_ATOL)).enumerate() {
        *a = if cfg.atol.is_scalar() {
            given[0]
        } else {
            given[i.min(given.len() - 1)]
        };
    }
    let m = n.min(MAX_ATOL);
    atol[m] = cfg.rtol * SPOOL_SCALE;
    atol[m + 1] = cfg.rtol * SPOOL_SCALE;
    let w = match cfg.scheme {
        Scheme::Explicit(t) => Method::<[f64; 1]>::error_weight(t, cfg.rtol),
        Scheme::Rosenbrock23 => Method::<[f64; 1]>::error_weight(&ROS_FD, cfg.rtol),
    };
    w * scaled_rms(
        &[(x0, x1, ex), (&y0.a, &y1.a, &e.a)],
        cfg.rtol,
        &atol[..m + 2],
    )
}

/// The stiff method with forward differences (no floor: each column's
/// increment follows the component and the step).
const ROS_FD: Rosenbrock23<FiniteDifference> = Rosenbrock23 {
    jacobian: FiniteDifference {
        floor: [0.0; rosenbrock23::MAX_DIM],
    },
};

impl<S: AsRef<[f64]> + AsMut<[f64]> + ehservo_core::rk4::OdeState> Components for PlantAct<S> {
    fn dim(&self) -> usize {
        self.x.as_ref().len() + 2
    }
    fn get(&self, i: usize) -> f64 {
        let x = self.x.as_ref();
        if i < x.len() {
            x[i]
        } else {
            self.a[i - x.len()]
        }
    }
    fn set(&mut self, i: usize, v: f64) {
        let n = self.x.as_ref().len();
        if i < n {
            self.x.as_mut()[i] = v;
        } else {
            self.a[i - n] = v;
        }
    }
}

/// The adaptive integration's state in a simulation.
#[derive(Debug, Clone, Copy)]
pub(super) struct AdaptiveRun {
    pub(super) cfg: AdaptiveConfig,
    pub(super) state: Adaptive,
}

impl<P: Plant, C: Controller, R: Reference> Simulation<P, C, R> {
    /// Integrates the plant and the actuator from `t` to `t_next` under the
    /// held command `u` and the sample's variation `var`; false (and the
    /// run stopped at the time reached) when the solver fails.
    pub(super) fn advance_adaptive(
        &mut self,
        t: f64,
        t_next: f64,
        u: f64,
        var: &P::Variation,
    ) -> bool {
        let Some(run) = self.adaptive.as_mut() else {
            return true;
        };
        let (plant, act): (&P, &Actuator) = (&self.plant, &self.actuator);
        let cfg = run.cfg;
        let f = |tt: f64, s: &PlantAct<P::State>, ds: &mut PlantAct<P::State>| {
            plant.deriv(tt, &s.x, act.output(&s.a, u), var, &mut ds.x);
            act.deriv(&s.a, u, &mut ds.a);
        };
        let nrm = |y0: &_, y1: &_, e: &_| norm(&cfg, y0, y1, e);
        let lim = |y: &mut PlantAct<P::State>| plant.limit_state(&mut y.x);
        let (ctl, y) = (&cfg.control, &mut self.y.pa);
        let result = match cfg.scheme {
            Scheme::Explicit(tab) => run.state.integrate(tab, ctl, f, nrm, lim, t, t_next, y),
            Scheme::Rosenbrock23 => run.state.integrate(&ROS_FD, ctl, f, nrm, lim, t, t_next, y),
        };
        self.outcome.solver_steps = run.state.counts;
        match result {
            Ok(()) => true,
            Err(Failure::StepBudget { t }) => {
                self.diverge(t, DivergenceReason::SolverStepBudget);
                false
            }
            Err(Failure::StepTooSmall { t, .. }) => {
                self.diverge(t, DivergenceReason::SolverStepTooSmall);
                false
            }
        }
    }
}

#[cfg(test)]
mod tests;
