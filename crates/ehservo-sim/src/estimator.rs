//! The estimator the sampled loop runs at the controller's rate, for the
//! channels of x the sensors do not measure: one of the core's
//! [`ehservo_core::estimate`] components (Levant's differentiator, or a
//! linear observer with a Luenberger or a steady-state Kalman gain).

use ehservo_core::estimate::{Estimator, Levant, LinearObserver};

/// One of the core's estimators, built from a scenario.
#[derive(Debug, Clone, Copy)]
pub enum AnyEstimator {
    /// Levant's robust exact differentiator of second order.
    Levant(Levant),
    /// A linear observer of the nominal model (Luenberger or Kalman gain).
    Linear(LinearObserver),
}

impl AnyEstimator {
    /// Back to rest at the measured angle.
    #[inline]
    pub fn reset(&mut self, theta0: f64) {
        match self {
            AnyEstimator::Levant(e) => e.reset(theta0),
            AnyEstimator::Linear(e) => e.reset(theta0),
        }
    }

    /// One update with the measured θ and the command applied over the
    /// last period; the estimate (θ̂, θ̂̇, θ̂̈).
    #[inline]
    pub fn update(&mut self, theta: f64, u_prev: f64) -> [f64; 3] {
        match self {
            AnyEstimator::Levant(e) => e.update(theta, u_prev),
            AnyEstimator::Linear(e) => e.update(theta, u_prev),
        }
    }
}
