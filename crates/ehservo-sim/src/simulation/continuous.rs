//! The continuous mode: the law is evaluated inside every RK4 stage, and
//! the plant, actuator and controller states are integrated together
//! (the augmented state).

use super::{Augmented, Sample, Simulation, Stop, TruthAt};
use crate::plant::{refinement, Plant};
use ehservo_core::control::{Controller, Measurement};
use ehservo_core::reference::Reference;
use ehservo_core::rk4::{rk4_step, rk4_step_with_k1, OdeState};
use std::ops::ControlFlow;

impl<P: Plant, C: Controller, R: Reference> Simulation<P, C, R> {
    /// [`Simulation::advance`] in continuous mode, from the measurement `x`
    /// and the reference `z` at `t_k`: `Break` with what `advance` returns
    /// when the sample ends the run, else `Continue` once the augmented
    /// state has been integrated to `t_{k+1}`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn advance_continuous(
        &mut self,
        sample: &mut Sample,
        k: u64,
        t: f64,
        x: [f64; 3],
        z: [f64; 4],
        var: P::Variation,
        h: f64,
    ) -> ControlFlow<bool> {
        // The first RK4 stage: ξ̇ from the logged law, the plant's
        // derivative below (the sampled mode never needs this 1 kB
        // state, so only this mode makes one).
        let mut dy = Augmented::<P::State, C::State>::zero();
        let truth = TruthAt {
            plant: &self.plant,
            s: &self.y.pa.x,
            x,
            var,
            stage: None,
        };
        let c = self.ctrl.controller();
        let xm = self.sensor.measure(x);
        let mut out = c.law(&Measurement { t, x: xm, z }, &self.y.xi, &mut dy.xi);
        if out.u.is_finite() {
            c.annotate(&self.y.xi, &mut out, &truth);
        }
        if !self.log(sample, t, z, x, xm, out.u, &out) {
            return ControlFlow::Break(false);
        }
        if k == self.cfg.steps {
            self.stop = Some(Stop::Horizon);
            return ControlFlow::Break(true);
        }
        let (plant, act, u) = (&self.plant, &self.actuator, out.u);
        plant.deriv(t, &self.y.pa.x, sample.u_plant, &var, &mut dy.pa.x);
        act.deriv(&self.y.pa.a, u, &mut dy.pa.a);
        let (c, sensor, reference) = (self.ctrl.controller(), &self.sensor, &self.reference);
        let f =
            |tt: f64, s: &Augmented<P::State, C::State>, ds: &mut Augmented<P::State, C::State>| {
                let xs = sensor.measure(plant.measure(tt, &s.pa.x, &var));
                let meas = Measurement {
                    t: tt,
                    x: xs,
                    z: reference.z(tt),
                };
                let o = c.law(&meas, &s.xi, &mut ds.xi);
                plant.deriv(tt, &s.pa.x, act.output(&s.pa.a, o.u), &var, &mut ds.pa.x);
                act.deriv(&s.pa.a, o.u, &mut ds.pa.a);
            };
        let n = refinement(plant.stiffness(t, &self.y.pa.x, sample.u_plant, &var), h);
        if n > 1 {
            let hr = h / f64::from(n);
            rk4_step_with_k1(f, t, &mut self.y, &dy, hr);
            plant.limit_state(&mut self.y.pa.x);
            for i in 1..n {
                rk4_step(f, t + f64::from(i) * hr, &mut self.y, hr);
                plant.limit_state(&mut self.y.pa.x);
            }
        } else {
            rk4_step_with_k1(f, t, &mut self.y, &dy, h);
            plant.limit_state(&mut self.y.pa.x);
        }
        ControlFlow::Continue(())
    }
}
