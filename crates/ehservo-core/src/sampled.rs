//! A fixed-rate control loop for hardware.
//!
//! Every `dt` seconds the board reads x (and knows z), calls
//! [`SampledController::step`], applies `u` to the servovalve and holds it
//! (zero-order hold) until the next tick. The controller state ξ (∫e, W)
//! advances once per tick by forward Euler with the derivative at the tick:
//! `ξ(k+1) = ξ(k) + dt·ξ̇(k)`. This is the `sampled` reading of the paper's
//! simulation (SPEC §7), and exactly what the simulator does in that mode.
//!
//! No allocation: the state lives inside the struct (about 1 kB for the
//! NNBVSC).

use crate::control::{ControlOutput, Controller, Measurement};
use crate::error::{positive, ParamError};
use crate::rk4::OdeState;

/// A controller with its state and a fixed sample period.
#[derive(Debug, Clone)]
pub struct SampledController<C: Controller> {
    ctrl: C,
    state: C::State,
    dt: f64,
}

impl<C: Controller> SampledController<C> {
    /// Wraps `ctrl` with its initial state and sample period `dt` (s).
    pub fn new(ctrl: C, dt: f64) -> Result<Self, ParamError> {
        positive("dt", dt)?;
        Ok(Self {
            state: ctrl.initial_state(),
            ctrl,
            dt,
        })
    }

    /// One tick at time `t` with measurement `x` and reference `z`: returns
    /// the law's parts and advances the state.
    #[inline]
    pub fn step(&mut self, t: f64, x: [f64; 3], z: [f64; 4]) -> ControlOutput {
        let mut ds = C::State::zero();
        let out = self
            .ctrl
            .law(&Measurement { t, x, z }, &self.state, &mut ds);
        self.state.axpy(self.dt, &ds);
        out
    }

    /// Back to the initial state (∫e = 0, W = 0).
    pub fn reset(&mut self) {
        self.state = self.ctrl.initial_state();
    }

    /// The controller state.
    pub fn state(&self) -> &C::State {
        &self.state
    }

    /// The controller.
    pub fn controller(&self) -> &C {
        &self.ctrl
    }

    /// The sample period (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }
}
