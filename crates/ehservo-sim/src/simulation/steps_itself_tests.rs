//! A plant that steps itself ([`Plant::STEPS_ITSELF`], a co-simulation
//! FMU's shape): the loop and the plant alone hand it each whole sample
//! period once, with the command held, whatever the sub-steps; its failure
//! ends the run as [`DivergenceReason::PlantFailed`].

use super::tests::{cfg, nn, stages};
use super::*;
use crate::plant::Draw;
use ehservo_core::prelude::{Load, NominalModel, ServoParams, Sine};
use std::cell::Cell;

/// An integrator x₀' = u stepped exactly by the plant itself: each call
/// adds u·h to x₀ and keeps u as x₁ and the end of its period as x₂; it
/// fails from its `fail_at`-th call on.
#[derive(Debug, Clone)]
struct SelfStepping {
    nominal: NominalModel,
    calls: Cell<u32>,
    fail_at: u32,
    failed: Cell<bool>,
}

impl SelfStepping {
    fn new(fail_at: u32) -> Self {
        Self {
            nominal: NominalModel::new(ServoParams::paper(), Load::none()),
            calls: Cell::new(0),
            fail_at,
            failed: Cell::new(false),
        }
    }
}

impl Plant for SelfStepping {
    type State = [f64; 3];
    type Variation = ();
    type Prepared = ();
    const STEPS_ITSELF: bool = true;
    fn initial_state(&self, _x0: [f64; 3], _v: &()) -> [f64; 3] {
        [0.0; 3]
    }
    fn measure(&self, _t: f64, s: &[f64; 3], _v: &()) -> [f64; 3] {
        *s
    }
    fn deriv(&self, _t: f64, _s: &[f64; 3], _u: f64, _v: &(), _ds: &mut [f64; 3]) {
        panic!("a plant that steps itself is never integrated");
    }
    fn step_held(&self, t: f64, h: f64, u: f64, s: &mut [f64; 3]) {
        self.calls.set(self.calls.get() + 1);
        if self.calls.get() >= self.fail_at {
            self.failed.set(true);
            return;
        }
        *s = [s[0] + u * h, u, t + h];
    }
    fn failed(&self) -> bool {
        self.failed.get()
    }
    fn nominal(&self) -> &NominalModel {
        &self.nominal
    }
    fn variation(&self, _spec: &UncertaintySpec, _r: &Draw) {}
    fn lumped_uncertainty(
        &self,
        _: &[f64; 3],
        _: &[f64; 3],
        _: f64,
        _: f64,
        _: f64,
        _: &(),
    ) -> f64 {
        0.0
    }
}

fn settings(substeps: u32) -> Settings {
    let mut st = stages(Actuator::IDENTITY);
    st.uncertainty = UncertaintySpec::NONE;
    let c = SimConfig {
        substeps,
        ..cfg(Mode::Sampled)
    };
    Settings::try_new(st, c).unwrap()
}

#[test]
fn the_plant_alone_hands_it_each_period_once_with_the_command_held() {
    // h = 0.01 s and 4 sub-steps: still one call a period, over h.
    let mut p = PlantAlone::from_settings(SelfStepping::new(u32::MAX), &settings(4));
    for u in [2.0, 2.0, -1.0] {
        p.hold(u).unwrap();
    }
    // x₀ = 2·0.01 + 2·0.01 − 1·0.01 = 0.03; x₁ the last u; x₂ = t₂ + h = 0.03.
    let x = p.output(0.0).x;
    assert!((x[0] - 0.03).abs() < 1e-15, "{x:?}");
    // (Called at every sub-step of h/4, x₀ would be 4 times that.)
    assert_eq!(x[1], -1.0);
    assert!((x[2] - 0.03).abs() < 1e-15, "{x:?}");
}

#[test]
fn its_failure_ends_the_run_as_a_result() {
    // The third call fails: the plant alone stops at t₃ = 0.03 s.
    let mut p = PlantAlone::from_settings(SelfStepping::new(3), &settings(2));
    p.hold(1.0).unwrap();
    p.hold(1.0).unwrap();
    let d = p.hold(1.0).unwrap_err();
    assert_eq!(d.reason, DivergenceReason::PlantFailed);
    assert!((d.t - 0.03).abs() < 1e-15, "{d:?}");
    // And the loop: the run diverges there too, not at its horizon.
    let mut sim = Simulation::from_settings(SelfStepping::new(3), nn(), Sine::paper(), settings(2));
    let out = sim.run(&mut |_| {});
    let d = out.diverged.expect("the plant failed");
    assert_eq!(d.reason, DivergenceReason::PlantFailed);
    assert!((d.t - 0.03).abs() < 1e-15, "{d:?}");
}
