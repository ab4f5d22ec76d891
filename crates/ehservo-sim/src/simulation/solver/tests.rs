//! The sampled loop under an adaptive solver: its settings' refusals, the
//! step budget as a stop, resuming, the per-sample variation, and the
//! agreement with a fine RK4.

use super::super::tests_support::{cfg, nn, stages};
use super::*;
use crate::plant::ThirdOrderPlant;
use crate::simulation::{Mode, Outcome, Sample, Settings, Stop};
use ehservo_core::prelude::{Load, ServoParams, Sine};

fn adaptive(kind: SolverKind, rtol: f64, max_steps: u64) -> AdaptiveConfig {
    AdaptiveConfig::try_new(kind, rtol, Atol::scalar(rtol * 1e-3), 0.01, max_steps).unwrap()
}

type Sim = Simulation<ThirdOrderPlant, ehservo_core::control::nnvsc::NnVsc, Sine>;

/// The tests' loop (tests.rs: the NNBVSC at 10 ms on the third-order plant,
/// random variation held `hold` s), its plant integrated by `a` or by RK4.
fn sim_held(a: Option<AdaptiveConfig>, substeps: u32, hold: f64) -> Sim {
    let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
    let mut c = cfg(Mode::Sampled);
    c.substeps = substeps;
    let mut st = stages(Actuator::IDENTITY);
    st.uncertainty.hold = hold;
    let s = Settings::try_new(st, c).unwrap();
    let s = match a {
        Some(a) => s.with_adaptive(a).unwrap(),
        None => s,
    };
    Simulation::from_settings(plant, nn(), Sine::paper(), s)
}

fn sim_with(a: Option<AdaptiveConfig>, substeps: u32) -> Sim {
    sim_held(a, substeps, 0.01)
}

fn thetas(mut s: Sim) -> (Vec<f64>, Outcome) {
    let mut th = Vec::new();
    let out = s.run(&mut |x: &Sample| th.push(x.x[0]));
    (th, out)
}

/// Refused: no error control (rk4), rtol outside (0, 1), a negative or
/// non-finite atol, a max_step not > 0; the continuous mode and a max_step
/// above the sample period.
#[test]
fn settings_are_refused_with_the_parameter() {
    let a = Atol::scalar(1e-9);
    let name = |r: Result<AdaptiveConfig, ParamError>| r.unwrap_err().name;
    assert_eq!(
        name(AdaptiveConfig::try_new(SolverKind::Rk4, 1e-6, a, 0.01, 10)),
        "solver"
    );
    for rtol in [0.0, 1.0, -1e-3, f64::NAN] {
        assert_eq!(
            name(AdaptiveConfig::try_new(
                SolverKind::Dopri5,
                rtol,
                a,
                0.01,
                10
            )),
            "rtol"
        );
    }
    for bad in [-1e-9, f64::INFINITY, f64::NAN] {
        let atol = Atol::per_state(&[1e-9, bad, 1e-9]).unwrap();
        assert_eq!(
            name(AdaptiveConfig::try_new(
                SolverKind::Bs32,
                1e-6,
                atol,
                0.01,
                10
            )),
            "atol"
        );
    }
    assert_eq!(
        name(AdaptiveConfig::try_new(
            SolverKind::Dopri5,
            1e-6,
            a,
            0.0,
            10
        )),
        "max_step"
    );
    let ok = AdaptiveConfig::try_new(SolverKind::Dopri5, 1e-6, a, 0.01, 10).unwrap();
    let cont = Settings::try_new(stages(Actuator::IDENTITY), cfg(Mode::Continuous)).unwrap();
    assert_eq!(cont.with_adaptive(ok).unwrap_err().name, "solver");
    let long = AdaptiveConfig::try_new(SolverKind::Dopri5, 1e-6, a, 0.011, 10).unwrap();
    let sampled = Settings::try_new(stages(Actuator::IDENTITY), cfg(Mode::Sampled)).unwrap();
    assert_eq!(sampled.with_adaptive(long).unwrap_err().name, "max_step");
}

/// A budget of 40 steps for a 3 s run that needs hundreds: the run stops
/// with `solver-step-budget` at the time reached, as a result, with the
/// 40 steps counted.
#[test]
fn the_step_budget_stops_the_run_as_a_result() {
    let (th, out) = thetas(sim_with(Some(adaptive(SolverKind::Dopri5, 1e-6, 40)), 1));
    let d = out.diverged.expect("stopped");
    assert_eq!(d.reason, DivergenceReason::SolverStepBudget);
    assert!(d.t > 0.0 && d.t < 3.0, "{}", d.t);
    assert_eq!(out.solver_steps.total(), 40);
    assert!(th.len() < 301 && th.iter().all(|v| v.is_finite()));
}

/// Stopping and resuming an adaptive run gives the run in one go, bit for
/// bit (the step size carried over is part of the simulation's state).
#[test]
fn an_adaptive_run_resumes_exactly() {
    let a = Some(adaptive(SolverKind::Bs32, 1e-5, u64::MAX));
    let (whole, out) = thetas(sim_with(a, 1));
    let mut s = sim_with(a, 1);
    let mut parts = Vec::new();
    assert_eq!(s.run_until(1.5, &mut |x| parts.push(x.x[0])), None);
    assert_eq!(
        s.run_until(f64::INFINITY, &mut |x| parts.push(x.x[0])),
        Some(Stop::Horizon)
    );
    assert_eq!(
        whole.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        parts.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );
    assert_eq!(s.outcome(), out);
    assert!(out.solver_steps.accepted >= 300, "{:?}", out.solver_steps);
}

/// The random variation (a_random, b_random here, held 2 ms) is read
/// once per sample, at t_k, under an adaptive solver: runs at rtol 1e-6
/// and 1e-10, whose steps differ, simulate the same model and agree to
/// 10·(atol + rtol·|θ|max) of the looser. RK4 reads it at every sub-step,
/// so at 100 sub-steps it sees five draws a 10 ms sample and differs by
/// far more; with the variation held over the sample (10 ms), RK4 at 100
/// sub-steps and the tight run agree.
#[test]
fn the_variation_is_read_once_per_sample() {
    let run = |a: Option<AdaptiveConfig>, m: u32, hold: f64| thetas(sim_held(a, m, hold)).0;
    let d5 = |rtol: f64| Some(adaptive(SolverKind::Dopri5, rtol, u64::MAX));
    let gap = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    let (loose, tight) = (run(d5(1e-6), 1, 0.002), run(d5(1e-10), 1, 0.002));
    let amp = tight.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let tol = 10.0 * (1e-9 + 1e-6 * amp);
    assert_eq!(loose.len(), 301);
    assert!(
        gap(&loose, &tight) <= tol,
        "{:e} > {tol:e}",
        gap(&loose, &tight)
    );
    let rk4 = run(None, 100, 0.002);
    assert!(gap(&rk4, &tight) > 100.0 * tol, "{:e}", gap(&rk4, &tight));
    let (rk4, tight) = (run(None, 100, 0.01), run(d5(1e-10), 1, 0.01));
    assert!(gap(&rk4, &tight) <= tol, "{:e}", gap(&rk4, &tight));
}
