//! The estimator the sampled loop runs at the controller's rate, for the
//! channels of x the sensors do not measure (the core's `estimate`
//! module: Levant's differentiator, a Luenberger observer, a steady-state
//! Kalman filter).

/// One of the core's estimators, built from a scenario.
#[derive(Debug, Clone)]
pub enum AnyEstimator {}

impl AnyEstimator {
    /// Back to rest at the measured angle.
    pub fn reset(&mut self, _theta0: f64) {
        match *self {}
    }

    /// One update with the measured θ and the command applied over the
    /// last period; the estimate (θ̂, θ̂̇, θ̂̈).
    pub fn update(&mut self, _theta: f64, _u_prev: f64) -> [f64; 3] {
        match *self {}
    }
}
