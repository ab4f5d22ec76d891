//! No heap allocation in a control step, nor in a simulation step.
//!
//! A counting global allocator wraps the system one; the counter, one per
//! thread (the test harness's own threads may allocate meanwhile), is read
//! around the calls under test. (This file is its own test binary, so the
//! allocator is installed only here.)

// The one unsafe block of the project: a global allocator must be an
// `unsafe impl`. It only counts, then delegates to the system allocator.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    /// Allocations made by this thread.
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    // try_with: a thread being torn down has no counter left to bump.
    let _ = COUNT.try_with(|c| c.set(c.get() + 1));
}

/// Allocations made so far by the calling thread.
fn allocs() -> usize {
    COUNT.with(Cell::get)
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        count();
        System.alloc(l)
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        System.dealloc(p, l)
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        count();
        System.realloc(p, l, n)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

use ehservo::actuator::Actuator;
use ehservo::plant::{ThirdOrderPlant, UncertaintySpec};
use ehservo::sensor::Sensor;
use ehservo::simulation::{Mode, SimConfig, Simulation, Stages};
use ehservo_core::prelude::*;

#[test]
fn control_and_simulation_steps_do_not_allocate() {
    let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
    let model = NominalModel::new(ServoParams::paper(), Load::paper());
    let nn = NnVsc::try_new(
        model,
        SwitchingSurface::paper(),
        NnVscParams::paper(),
        Rbf::paper(),
    )
    .unwrap();
    let vsc = Vsc::try_new(model, SwitchingSurface::paper(), VscParams::paper()).unwrap();
    let reference = Sine::paper();
    let mut ctl = SampledController::new(nn, 1e-3).unwrap();

    let before = allocs();
    let mut acc = 0.0;
    for k in 0..1000 {
        let t = k as f64 * 1e-3;
        let o = ctl.step(t, [0.01 * t, 0.0, 0.0], reference.z(t));
        acc += o.u;
        let o = vsc.law(
            &Measurement {
                t,
                x: [0.0; 3],
                z: reference.z(t),
            },
            &[0.0],
            &mut [0.0],
        );
        acc += o.u;
    }
    assert!(acc.is_finite());
    assert_eq!(allocs() - before, 0, "a control step allocated");

    // The whole closed loop, both modes, with a non-allocating observer.
    for mode in [Mode::Sampled, Mode::Continuous] {
        let cfg = SimConfig {
            steps: 2000,
            step: 1e-3,
            mode,
            substeps: 2,
            theta_limit: 1.0,
            x0: [0.0; 3],
            computation_delay: false,
        };
        let stages = Stages {
            uncertainty: UncertaintySpec {
                a_random: 0.5,
                b_random: 0.25,
                ..UncertaintySpec::NONE
            },
            actuator: Actuator::IDENTITY,
            sensor: Sensor::identity(),
            policy: FaultPolicy::default(),
            estimator: None,
        };
        let mut sim = Simulation::new(plant, nn, reference, stages, cfg).unwrap();
        let mut sum = 0.0;
        let before = allocs();
        let out = sim.run(&mut |s| sum += s.u);
        let n = allocs() - before;
        assert!(out.diverged.is_none() && sum.is_finite());
        assert_eq!(n, 0, "{mode:?}: {n} allocations in 2000 simulation steps");
    }
}

/// The stepper the Python binding and the C ABI drive: `step`, `step_parts`
/// and `peek` (which steps a copy) allocate nothing once it is built.
#[test]
fn a_stepped_controller_does_not_allocate() {
    use ehservo::scenario::Loop;
    use ehservo::stepper::ControllerStepper;
    let s = Loop::parse("name = \"fig2\"\n").unwrap();
    let mut c = ControllerStepper::new(&s).unwrap();
    let mut parts = vec![0.0; c.signals().len()];
    let before = allocs();
    let mut acc = 0.0;
    for k in 0..500 {
        let t = k as f64 * c.period();
        let (x, z) = ([0.01 * t, 0.0, 0.0], c.reference(t));
        acc += c.peek(t, x, z).u;
        acc += c.step_parts(t, x, z, &mut parts).u;
        acc += c.step(t + c.period(), x, z).u;
    }
    let n = allocs() - before;
    assert!(acc.is_finite());
    assert_eq!(n, 0, "{n} allocations in 500 stepped samples");
}
