//! The third-order model (8)–(9) and the physical model (1)–(6) are one
//! system written in two sets of coordinates: with the same input they must
//! give the same θ(t), to integration accuracy.

use ehservo::physical::PhysicalVariation;
use ehservo::plant::{Factors, PhysicalPlant, Plant, ThirdOrderPlant, Variation};
use ehservo::run::{run, Keep};
use ehservo::scenario::PlantCfg;
use ehservo_core::rk4::rk4_step;
use ehservo_core::servo::{Load, ServoParams};

/// θ(t) on a grid, for an open-loop input u(t) = 0.2·sin(2πt) V held over
/// each step, integrated by RK4 with step h.
fn open_loop<P: Plant>(plant: &P, h: f64, horizon: f64, v: &P::Variation) -> Vec<f64> {
    let n = (horizon / h).round() as usize;
    let mut s = plant.initial_state([0.0; 3], v);
    let mut out = vec![0.0];
    for k in 0..n {
        let t = k as f64 * h;
        let u = 0.2 * (2.0 * std::f64::consts::PI * t).sin();
        rk4_step(
            |tt, y: &P::State, dy: &mut P::State| plant.deriv(tt, y, u, v, dy),
            t,
            &mut s,
            h,
        );
        out.push(plant.measure(t + h, &s, v)[0]);
    }
    out
}

/// The physical plant's form of the paper's variation.
fn phys(v: &Variation) -> PhysicalVariation {
    PhysicalVariation {
        paper: *v,
        factors: Factors::ONE,
    }
}

fn max_diff(a: &[f64], b: &[f64], every: usize) -> f64 {
    a.iter()
        .step_by(every)
        .zip(b.iter())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn same_theta_open_loop_without_variation() {
    let p = ServoParams::paper();
    let third = ThirdOrderPlant::new(p, Load::paper());
    let phys = PhysicalPlant::new(p, Load::paper());
    let v = Variation::NONE;
    // Both at h = 1e-4 over 2 s.
    let a = open_loop(&third, 1e-4, 2.0, &v);
    let b = open_loop(&phys, 1e-4, 2.0, &self::phys(&v));
    let amp = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let d = max_diff(&a, &b, 1);
    // θ reaches ~0.3 rad; the two coordinate systems differ only by RK4's
    // O(h⁴) local errors: a relative 1e-7 is far above them and far below
    // any modelling error (a wrong sign or a missing term changes θ by O(1)).
    assert!(
        amp > 0.01,
        "the input must move the motor (amplitude {amp})"
    );
    assert!(
        d < 1e-7 * amp.max(1.0),
        "max |Δθ| = {d:e} over an amplitude {amp}"
    );

    // And the gap shrinks with the step, as integration error must:
    // h = 1e-3 vs the fine run of each model.
    let a3 = open_loop(&third, 1e-3, 2.0, &v);
    let b3 = open_loop(&phys, 1e-3, 2.0, &self::phys(&v));
    let err_third = max_diff(&a, &a3, 10);
    let err_phys = max_diff(&b, &b3, 10);
    let gap = max_diff(&a3, &b3, 1);
    assert!(
        gap <= 2.0 * (err_third + err_phys) + 1e-12,
        "gap {gap:e} vs errors {err_third:e}, {err_phys:e}"
    );
}

#[test]
fn same_theta_open_loop_with_the_fig2_variation() {
    // The physical model carries Δa_i as an unmodelled flow term and Δb as a
    // valve-flow scale: still the same system as (8) with a = 2ā, b = 1.25b̄.
    let p = ServoParams::paper();
    let v = Variation {
        da: p.coefficients().as_array(),
        db_rel: 0.25,
    };
    let a = open_loop(&ThirdOrderPlant::new(p, Load::paper()), 1e-4, 1.0, &v);
    let b = open_loop(&PhysicalPlant::new(p, Load::paper()), 1e-4, 1.0, &phys(&v));
    let amp = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let d = max_diff(&a, &b, 1);
    assert!(amp > 0.01);
    assert!(d < 1e-7 * amp.max(1.0), "max |Δθ| = {d:e}");
}

#[test]
fn same_closed_loop_fig2_on_both_models() {
    // The Fig. 2 loop in continuous mode at a fine step on both plants.
    let lp = ehservo::scenario::Loop::parse(
        "[simulation]\nmode = \"continuous\"\nstep = 1e-4\nhorizon = 3.0\n",
    )
    .unwrap();
    let third = run(&lp, Keep::Every(100));
    let mut s = lp.scenario().clone();
    s.plant = PlantCfg::default_of("physical").unwrap();
    let phys = run(&ehservo::scenario::Loop::new(s).unwrap(), Keep::Every(100));
    assert!(!third.metrics.diverged && !phys.metrics.diverged);
    let d = third
        .trace
        .iter()
        .zip(phys.trace.iter())
        .map(|(a, b)| (a.x[0] - b.x[0]).abs())
        .fold(0.0, f64::max);
    // θ ~ 0.09 rad and the closed loop is smooth at h = 1e-4: agreement to
    // 1e-8 rad (1e-7 relative) is integration accuracy.
    assert!(d < 1e-8, "max |Δθ| = {d:e}");
}
