//! The estimator the sampled loop runs at the controller's rate, for the
//! channels of x the sensors do not measure: one of the core's
//! [`ehservo_core::estimate`] components (Levant's differentiator, or a
//! linear observer with a Luenberger or a steady-state Kalman gain).

use ehservo_core::estimate::{Estimator, Levant, LinearObserver};

/// One of the core's estimators, built from a scenario.
///
/// ```
/// use ehservo_sim::core::estimate::Levant;
/// use ehservo_sim::estimator::AnyEstimator;
///
/// // `[estimator] kind = "levant", lipschitz = 40` at the loop's 100 Hz.
/// let mut est = AnyEstimator::Levant(Levant::try_new(40.0, 0.01)?);
/// est.reset(0.2);
/// // A shaft held still at 0.2 rad is estimated still.
/// for _ in 0..10 {
///     assert_eq!(est.update(0.2, 0.0), [0.2, 0.0, 0.0]);
/// }
/// # Ok::<(), ehservo_sim::core::error::ParamError>(())
/// ```
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
