//! The closed loop: one function owns time, the integrator, the sampling of
//! the controller and the logging.
//!
//! Time is `t_k = k·h`, never accumulated. Two readings of the paper's
//! "fourth-order Runge–Kutta with a 0.01 s interval" (SPEC §7):
//!
//! - [`Mode::Continuous`]: the law is evaluated inside every RK4 stage and
//!   the plant state, ∫e and W are integrated together;
//! - [`Mode::Sampled`]: at `t_k` the law is evaluated and `u` held over
//!   `[t_k, t_k + h)` (zero-order hold); the plant is integrated by
//!   `substeps` RK4 steps of `h/substeps` under the held `u`; ∫e and W advance
//!   once per sample by forward Euler with their derivatives at `t_k`.
//!
//! The parameter variation is drawn at the start of each (sub)step and held
//! over it. A run ends early, as a result and never as NaN, when the state
//! stops being finite, |θ| exceeds `theta_limit`, or the law returns a
//! non-finite `u`.

use crate::plant::{Plant, UncertaintySignal};
use ehservo_core::control::{ControlOutput, Controller, Measurement};
use ehservo_core::math::DR;
use ehservo_core::reference::Reference;
use ehservo_core::rk4::{rk4_step, rk4_step_with_k1, OdeState};
use serde::{Deserialize, Serialize};

/// How the controller is coupled to the integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// Law inside every RK4 stage; controller state integrated with the plant.
    Continuous,
    /// Zero-order hold at the sample period; controller state by forward Euler.
    Sampled,
}

impl Mode {
    /// The scenario spelling.
    pub fn as_str(&self) -> &'static str {
        match self {
            Mode::Continuous => "continuous",
            Mode::Sampled => "sampled",
        }
    }
}

/// The loop's settings (validated by the scenario loader).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimConfig {
    /// Number of steps N; the horizon is `N·step`.
    pub steps: u64,
    /// Step h (s): the sample period in sampled mode.
    pub step: f64,
    /// Coupling of controller and integrator.
    pub mode: Mode,
    /// RK4 sub-steps of the plant per sample (sampled mode).
    pub substeps: u32,
    /// Divergence bound on |θ| (rad).
    pub theta_limit: f64,
    /// Initial x = (θ, θ̇, θ̈).
    pub x0: [f64; 3],
}

/// One logged sample at `t_k`: the plant, the law's parts and the weights.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample {
    /// Sample index k.
    pub k: u64,
    /// t_k (s).
    pub t: f64,
    /// z = (θd, θ̇d, θ̈d, θ⃛d).
    pub z: [f64; 4],
    /// x = (θ, θ̇, θ̈).
    pub x: [f64; 3],
    /// The law's parts at t_k.
    pub out: ControlOutput,
    /// The lumped uncertainty of (19): Σ Δa_i x_i − Δb·u_eq + d − ξ (rad/s³).
    pub uncertainty: f64,
    /// ‖W‖ (0 without a network).
    pub w_norm: f64,
    /// The paper's w_1 (first Gaussian's weight), 0 without a network.
    pub w_1: f64,
    /// The paper's w_128 (θ̈d's weight), 0 without a network.
    pub w_128: f64,
}

impl Sample {
    /// θd in degrees.
    pub fn theta_d_deg(&self) -> f64 {
        self.z[0] / DR
    }
    /// θ in degrees.
    pub fn theta_deg(&self) -> f64 {
        self.x[0] / DR
    }
    /// e in degrees.
    pub fn e_deg(&self) -> f64 {
        self.out.e / DR
    }
}

/// Why a run stopped before its horizon.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DivergenceReason {
    /// A plant or controller state became NaN or infinite.
    NonFiniteState,
    /// |θ| exceeded the limit.
    ThetaLimit,
    /// The law returned a non-finite u, or a non-finite part of its law
    /// (σ, ‖E‖, WᵀΦ, …) that would have been logged.
    NonFiniteControl,
}

impl DivergenceReason {
    /// A short human sentence.
    pub fn describe(&self) -> &'static str {
        match self {
            DivergenceReason::NonFiniteState => "the state became non-finite",
            DivergenceReason::ThetaLimit => "|θ| exceeded the divergence limit",
            DivergenceReason::NonFiniteControl => {
                "the control law returned a non-finite value (u or one of its parts)"
            }
        }
    }
}

/// The end of a diverged run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Divergence {
    /// When (s).
    pub t: f64,
    /// Why.
    pub reason: DivergenceReason,
}

/// What the loop reports besides the samples it logged.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Outcome {
    /// Samples passed to the observer.
    pub samples: u64,
    /// Set when the run ended early.
    pub diverged: Option<Divergence>,
    /// Samples at which the valve root of (2) was clamped in the law.
    pub valve_root_clamped: u64,
    /// Samples at which ‖E‖ = 0 was guarded.
    pub zero_error_norm: u64,
}

/// Plant state and controller state integrated together (continuous mode).
#[derive(Debug, Clone, Copy)]
struct Augmented<S: OdeState> {
    x: [f64; 3],
    xi: S,
}

impl<S: OdeState> OdeState for Augmented<S> {
    #[inline]
    fn zero() -> Self {
        Self {
            x: [0.0; 3],
            xi: S::zero(),
        }
    }
    #[inline]
    fn axpy(&mut self, a: f64, o: &Self) {
        self.x.axpy(a, &o.x);
        self.xi.axpy(a, &o.xi);
    }
    #[inline]
    fn all_finite(&self) -> bool {
        self.x.all_finite() && self.xi.all_finite()
    }
}

fn sample_is_finite(s: &Sample) -> bool {
    let o = &s.out;
    [
        o.u,
        o.u_eq,
        o.u_sw,
        o.e,
        o.sigma,
        o.sigma_delta,
        o.wphi,
        o.phi_norm,
        o.xi,
        o.b_bar,
        o.gain,
        o.mu,
        o.norm_e,
        s.uncertainty,
        s.w_norm,
        s.w_1,
        s.w_128,
    ]
    .iter()
    .chain(s.x.iter())
    .chain(s.z.iter())
    .all(|v| v.is_finite())
}

/// Runs the closed loop from t = 0 to `steps·step`, calling `observe` once
/// per sample k = 0..=N (fewer if the run diverges).
pub fn simulate<P, C, R>(
    plant: &P,
    ctrl: &C,
    reference: &R,
    uncertainty: &mut UncertaintySignal,
    cfg: &SimConfig,
    observe: &mut dyn FnMut(&Sample),
) -> Outcome
where
    P: Plant,
    C: Controller,
    R: Reference,
{
    let h = cfg.step;
    let mut y = Augmented {
        x: plant.initial_state(cfg.x0),
        xi: ctrl.initial_state(),
    };
    let mut outcome = Outcome::default();
    let mut k: u64 = 0;
    loop {
        let t = k as f64 * h;
        let var = uncertainty.at(t);
        let x = plant.measure(&y.x);
        let z = reference.z(t);
        let mut dy = Augmented::<C::State>::zero();
        let out = ctrl.law(&Measurement { t, x, z }, &y.xi, &mut dy.xi);
        if out.flags & ehservo_core::control::flags::VALVE_ROOT_CLAMPED != 0 {
            outcome.valve_root_clamped += 1;
        }
        if out.flags & ehservo_core::control::flags::ZERO_ERROR_NORM != 0 {
            outcome.zero_error_norm += 1;
        }
        if !out.u.is_finite() {
            outcome.diverged = Some(Divergence {
                t,
                reason: DivergenceReason::NonFiniteControl,
            });
            break;
        }
        let w = ctrl.weights(&y.xi);
        let sample = Sample {
            k,
            t,
            z,
            x,
            out,
            uncertainty: plant.lumped_uncertainty(&x, out.u, out.u_eq, out.b_bar, &var) - out.xi,
            w_norm: ehservo_core::math::norm(w),
            w_1: w.get(1).copied().unwrap_or(0.0),
            w_128: w.get(128).copied().unwrap_or(0.0),
        };
        // Every logged signal must be finite (a finite u can still come with
        // an overflowing ‖E‖ or σ): otherwise the run ends here, as a result.
        if !sample_is_finite(&sample) {
            outcome.diverged = Some(Divergence {
                t,
                reason: DivergenceReason::NonFiniteControl,
            });
            break;
        }
        observe(&sample);
        outcome.samples += 1;
        if k == cfg.steps {
            break;
        }

        match cfg.mode {
            Mode::Sampled => {
                let m = cfg.substeps.max(1);
                let hs = h / m as f64;
                for j in 0..m {
                    let ts = t + j as f64 * hs;
                    let v = if j == 0 { var } else { uncertainty.at(ts) };
                    rk4_step(
                        |tt, s: &[f64; 3], ds: &mut [f64; 3]| plant.deriv(tt, s, out.u, &v, ds),
                        ts,
                        &mut y.x,
                        hs,
                    );
                }
                y.xi.axpy(h, &dy.xi);
            }
            Mode::Continuous => {
                plant.deriv(t, &y.x, out.u, &var, &mut dy.x);
                let f = |tt: f64, s: &Augmented<C::State>, ds: &mut Augmented<C::State>| {
                    let xs = plant.measure(&s.x);
                    let m = Measurement {
                        t: tt,
                        x: xs,
                        z: reference.z(tt),
                    };
                    let o = ctrl.law(&m, &s.xi, &mut ds.xi);
                    plant.deriv(tt, &s.x, o.u, &var, &mut ds.x);
                };
                rk4_step_with_k1(f, t, &mut y, &dy, h);
            }
        }
        k += 1;
        let t_next = k as f64 * h;
        if !y.all_finite() {
            outcome.diverged = Some(Divergence {
                t: t_next,
                reason: DivergenceReason::NonFiniteState,
            });
            break;
        }
        if plant.measure(&y.x)[0].abs() > cfg.theta_limit {
            outcome.diverged = Some(Divergence {
                t: t_next,
                reason: DivergenceReason::ThetaLimit,
            });
            break;
        }
    }
    outcome
}
