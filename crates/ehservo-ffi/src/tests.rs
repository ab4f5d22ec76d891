//! The extern functions called as C calls them, pointers and all.
#![allow(clippy::float_cmp)] // bit-identical results are the point

use super::*;
use ehservo_scenario::run::{run, Keep};
use std::ffi::CString;
use std::ptr::{null, null_mut};

fn scenario_path(rel: &str) -> CString {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel);
    CString::new(p.to_str().unwrap()).unwrap()
}

fn last_error() -> String {
    // SAFETY: the library's own NUL-terminated buffer.
    unsafe { CStr::from_ptr(ehservo_last_error()) }
        .to_str()
        .unwrap()
        .to_string()
}

/// A scenario file in a temporary directory.
fn temp_scenario(text: &str) -> (tempfile::TempDir, CString) {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("bad.toml");
    std::fs::write(&p, text).unwrap();
    let c = CString::new(p.to_str().unwrap()).unwrap();
    (d, c)
}

fn new_sim(path: &CStr) -> *mut EhservoSim {
    let mut sim = null_mut();
    // SAFETY: valid arguments.
    let st = unsafe { ehservo_sim_new(path.as_ptr(), &mut sim) };
    assert_eq!(st, EhservoStatus::Ok, "{}", last_error());
    assert!(!sim.is_null());
    sim
}

fn new_ctl(path: &CStr) -> *mut EhservoController {
    let mut ctl = null_mut();
    // SAFETY: valid arguments.
    let st = unsafe { ehservo_controller_new(path.as_ptr(), &mut ctl) };
    assert_eq!(st, EhservoStatus::Ok, "{}", last_error());
    ctl
}

#[test]
fn stepping_fig2_from_c_gives_the_runs_e_max_to_the_bit() {
    let path = scenario_path("scenarios/paper/fig2.toml");
    let sim = new_sim(&path);
    let mut s = EhservoSample::default();
    let mut e = 0.0;
    // SAFETY: a live handle and valid outputs throughout.
    unsafe {
        assert_eq!(
            ehservo_sim_e_max_deg(sim, &mut e),
            EhservoStatus::Unavailable
        );
        assert!(e.is_nan());
        let mut n = 0u64;
        while ehservo_sim_step(sim, &mut s) == EhservoStatus::Ok {
            assert_eq!(s.k, n);
            n += 1;
        }
        assert_eq!(n, 1001, "N + 1 samples for 10 s at 0.01 s");
        assert!(
            last_error().contains("reached its horizon"),
            "{}",
            last_error()
        );
        assert_eq!(s.t, 10.0);
        assert_eq!(ehservo_sim_step(sim, &mut s), EhservoStatus::Stopped);
        assert_eq!(ehservo_sim_e_max_deg(sim, &mut e), EhservoStatus::Ok);
        ehservo_sim_free(sim);
    }
    let scen = Loop::load(std::path::Path::new(path.to_str().unwrap()), &[]).unwrap();
    let r = run(&scen, Keep::Nothing);
    assert_eq!(e.to_bits(), r.metrics.e_max.unwrap().to_bits());
    // The README's figure for this case, as an order-of-magnitude check of
    // what was compared.
    assert!((e - 0.2091).abs() < 1e-4, "{e}");
}

#[test]
fn the_controller_handle_reproduces_the_loops_commands() {
    let path = scenario_path("scenarios/paper/fig2.toml");
    let sim = new_sim(&path);
    let ctl = new_ctl(&path);
    let mut s = EhservoSample::default();
    let (mut period, mut steps) = (0.0, 0);
    // SAFETY: live handles and valid buffers.
    unsafe {
        assert_eq!(
            ehservo_controller_info(ctl, &mut period, &mut steps),
            EhservoStatus::Ok
        );
        assert_eq!((period, steps), (0.01, 1000));
        for k in 0..300 {
            assert_eq!(ehservo_sim_step(sim, &mut s), EhservoStatus::Ok);
            let x = [s.theta, s.theta_dot, s.theta_ddot];
            let mut z = [0.0; 4];
            assert_eq!(
                ehservo_controller_reference(ctl, s.t, z.as_mut_ptr()),
                EhservoStatus::Ok
            );
            assert_eq!(z[0], s.theta_d);
            let mut u = f64::NAN;
            // Half the samples with z given, half with the scenario's.
            let zp = if k % 2 == 0 { z.as_ptr() } else { null() };
            assert_eq!(
                ehservo_controller_step(ctl, s.t, x.as_ptr(), zp, &mut u),
                EhservoStatus::Ok
            );
            assert_eq!(u.to_bits(), s.u.to_bits(), "k = {k}");
        }
        ehservo_sim_free(sim);
        ehservo_controller_free(ctl);
    }
}

#[test]
fn null_pointers_are_errors_that_name_the_argument() {
    let path = scenario_path("scenarios/paper/fig2.toml");
    let mut sim: *mut EhservoSim = null_mut();
    let mut s = EhservoSample::default();
    let mut v = 0.0;
    // SAFETY: the nulls are the point; everything else is valid.
    unsafe {
        assert_eq!(
            ehservo_sim_new(null(), &mut sim),
            EhservoStatus::NullPointer
        );
        assert_eq!(last_error(), "ehservo_sim_new: `path` is null");
        assert!(sim.is_null());
        assert_eq!(
            ehservo_sim_new(path.as_ptr(), null_mut()),
            EhservoStatus::NullPointer
        );
        assert_eq!(last_error(), "ehservo_sim_new: `out` is null");
        // A step before the handle was made.
        assert_eq!(
            ehservo_sim_step(null_mut(), &mut s),
            EhservoStatus::NullPointer
        );
        assert!(last_error()
            .starts_with("ehservo_sim_step: `sim` is null (make it with ehservo_sim_new"));
        assert_eq!(
            ehservo_sim_e_max_deg(null(), &mut v),
            EhservoStatus::NullPointer
        );
        let sim = new_sim(&path);
        assert_eq!(
            ehservo_sim_step(sim, null_mut()),
            EhservoStatus::NullPointer
        );
        assert_eq!(last_error(), "ehservo_sim_step: `out` is null");
        // Nothing was stepped by the failed call: the first sample is k = 0.
        assert_eq!(ehservo_sim_step(sim, &mut s), EhservoStatus::Ok);
        assert_eq!(s.k, 0);
        assert_eq!(
            ehservo_sim_metric(sim, null(), &mut v),
            EhservoStatus::NullPointer
        );
        assert_eq!(
            ehservo_sim_metric(sim, c"samples".as_ptr(), null_mut()),
            EhservoStatus::NullPointer
        );
        ehservo_sim_free(sim);
        ehservo_sim_free(null_mut());

        let mut u = 0.0;
        let x = [0.0; 3];
        assert_eq!(
            ehservo_controller_step(null_mut(), 0.0, x.as_ptr(), null(), &mut u),
            EhservoStatus::NullPointer
        );
        assert!(last_error().contains("make it with ehservo_controller_new"));
        let ctl = new_ctl(&path);
        assert_eq!(
            ehservo_controller_step(ctl, 0.0, null(), null(), &mut u),
            EhservoStatus::NullPointer
        );
        assert_eq!(last_error(), "ehservo_controller_step: `x` is null");
        assert_eq!(
            ehservo_controller_step(ctl, 0.0, x.as_ptr(), null(), null_mut()),
            EhservoStatus::NullPointer
        );
        assert_eq!(
            ehservo_controller_reference(ctl, 0.0, null_mut()),
            EhservoStatus::NullPointer
        );
        assert_eq!(
            ehservo_controller_reset(null_mut()),
            EhservoStatus::NullPointer
        );
        ehservo_controller_free(ctl);
        ehservo_controller_free(null_mut());
    }
}

#[test]
fn non_finite_arguments_are_refused_and_change_nothing() {
    let path = scenario_path("scenarios/paper/fig2.toml");
    let ctl = new_ctl(&path);
    let fresh = new_ctl(&path);
    let x = [0.001, 0.0, 0.0];
    let mut u = 7.0;
    // SAFETY: live handles, valid buffers.
    unsafe {
        assert_eq!(
            ehservo_controller_step(ctl, f64::NAN, x.as_ptr(), null(), &mut u),
            EhservoStatus::InvalidArgument
        );
        assert_eq!(
            last_error(),
            "ehservo_controller_step: `t` must be finite (got NaN)"
        );
        assert_eq!(u, 7.0, "u untouched");
        let z = [0.0, f64::INFINITY, 0.0, 0.0];
        assert_eq!(
            ehservo_controller_step(ctl, 0.0, x.as_ptr(), z.as_ptr(), &mut u),
            EhservoStatus::InvalidArgument
        );
        assert_eq!(
            last_error(),
            "ehservo_controller_step: `z[1]` must be finite (got inf)"
        );
        let mut zz = [0.0; 4];
        assert_eq!(
            ehservo_controller_reference(ctl, f64::NAN, zz.as_mut_ptr()),
            EhservoStatus::InvalidArgument
        );
        // The refused calls did not step: the same command as a fresh one.
        let mut u_fresh = 0.0;
        assert_eq!(
            ehservo_controller_step(ctl, 0.0, x.as_ptr(), null(), &mut u),
            EhservoStatus::Ok
        );
        assert_eq!(
            ehservo_controller_step(fresh, 0.0, x.as_ptr(), null(), &mut u_fresh),
            EhservoStatus::Ok
        );
        assert_eq!(u.to_bits(), u_fresh.to_bits());
        assert!(u != 0.0);

        // A NaN measurement is a measurement fault: the default policy
        // (hold-last) holds the last command, the state stays.
        let bad = [f64::NAN, 0.0, 0.0];
        let mut held = 0.0;
        assert_eq!(
            ehservo_controller_step(ctl, 0.01, bad.as_ptr(), null(), &mut held),
            EhservoStatus::MeasurementFault
        );
        assert_eq!(held.to_bits(), u.to_bits());
        assert!(last_error().contains("`x[0]` is NaN"), "{}", last_error());
        let (mut a, mut b) = (0.0, 0.0);
        assert_eq!(
            ehservo_controller_step(ctl, 0.01, x.as_ptr(), null(), &mut a),
            EhservoStatus::Ok
        );
        assert_eq!(
            ehservo_controller_step(fresh, 0.01, x.as_ptr(), null(), &mut b),
            EhservoStatus::Ok
        );
        assert_eq!(
            a.to_bits(),
            b.to_bits(),
            "the fault left the state as it was"
        );
        // reset: back to the first command.
        assert_eq!(ehservo_controller_reset(ctl), EhservoStatus::Ok);
        assert_eq!(
            ehservo_controller_step(ctl, 0.0, x.as_ptr(), null(), &mut a),
            EhservoStatus::Ok
        );
        assert_eq!(a.to_bits(), u_fresh.to_bits());
        ehservo_controller_free(ctl);
        ehservo_controller_free(fresh);
    }
}

#[test]
fn a_scenario_that_does_not_validate_gives_the_clis_message() {
    let (_d, path) = temp_scenario("[plant.params]\nJt = -0.05\n");
    let mut sim = null_mut();
    // SAFETY: valid arguments.
    let st = unsafe { ehservo_sim_new(path.as_ptr(), &mut sim) };
    assert_eq!(st, EhservoStatus::Scenario);
    assert!(sim.is_null());
    // The README's example message for this error.
    let msg = last_error();
    assert_eq!(
        msg,
        format!(
            "{}:2:6: `plant.params.Jt`: must be finite and > 0 (got -0.05)",
            path.to_str().unwrap()
        )
    );
    let mut ctl = null_mut();
    // SAFETY: valid arguments.
    let st = unsafe { ehservo_controller_new(path.as_ptr(), &mut ctl) };
    assert_eq!(st, EhservoStatus::Scenario);
    assert_eq!(last_error(), msg);

    let (_d, typo) = temp_scenario("[controller]\ngama1 = 200\n");
    // SAFETY: valid arguments.
    let st = unsafe { ehservo_sim_new(typo.as_ptr(), &mut sim) };
    assert_eq!(st, EhservoStatus::Scenario);
    assert!(
        last_error().contains("`controller.gama1`: unknown field `gama1`"),
        "{}",
        last_error()
    );

    let missing = scenario_path("scenarios/no-such-file.toml");
    // SAFETY: valid arguments.
    let st = unsafe { ehservo_sim_new(missing.as_ptr(), &mut sim) };
    assert_eq!(st, EhservoStatus::Scenario);
    assert!(
        last_error().contains("no-such-file.toml"),
        "{}",
        last_error()
    );

    // A controller stepped by the caller needs the sampled mode.
    let (_d, cont) = temp_scenario("[simulation]\nmode = \"continuous\"\n");
    // SAFETY: valid arguments.
    let st = unsafe { ehservo_controller_new(cont.as_ptr(), &mut ctl) };
    assert_eq!(st, EhservoStatus::Scenario);
    assert!(
        last_error().contains("`simulation.mode`"),
        "{}",
        last_error()
    );
}

#[test]
fn metrics_by_name() {
    let path = scenario_path("scenarios/paper/fig2.toml");
    let sim = new_sim(&path);
    let mut v = 0.0;
    let mut s = EhservoSample::default();
    // SAFETY: a live handle, valid buffers.
    unsafe {
        for _ in 0..5 {
            ehservo_sim_step(sim, &mut s);
        }
        assert_eq!(
            ehservo_sim_metric(sim, c"samples".as_ptr(), &mut v),
            EhservoStatus::Ok
        );
        assert_eq!(v, 5.0);
        assert_eq!(
            ehservo_sim_metric(sim, c"e_maxx".as_ptr(), &mut v),
            EhservoStatus::InvalidArgument
        );
        assert!(last_error().starts_with(
            "ehservo_sim_metric: unknown metric \"e_maxx\" on a rotary axis, expected one of e_max_deg,"
        ));
        let latin1 = [0xe9u8, 0];
        assert_eq!(
            ehservo_sim_metric(sim, latin1.as_ptr().cast(), &mut v),
            EhservoStatus::InvalidArgument
        );
        assert_eq!(last_error(), "ehservo_sim_metric: `name` is not UTF-8");
        ehservo_sim_free(sim);
    }
}

#[test]
fn a_panic_stops_at_the_boundary() {
    let st = guard("ehservo_test", || panic!("boom"));
    assert_eq!(st, EhservoStatus::Panic);
    assert_eq!(last_error(), "ehservo_test: internal error (a panic): boom");
    let st = guard("ehservo_test", || Ok(EhservoStatus::Ok));
    assert_eq!(st, EhservoStatus::Ok);
    assert_eq!(last_error(), "", "a success clears the message");
}

/// A linear axis from C: the unit is "mm", `e_max` (and `e_max_mm`) is the
/// run's e_max in mm to the bit, and `e_max_deg` is refused there.
#[test]
fn a_linear_axis_says_mm_and_refuses_degrees() {
    let path = scenario_path("scenarios/cylinders/chrono-single-rod.toml");
    let sim = new_sim(&path);
    let mut s = EhservoSample::default();
    let (mut e, mut e_mm) = (0.0, 0.0);
    // SAFETY: a live handle and valid outputs throughout.
    unsafe {
        assert_eq!(
            CStr::from_ptr(ehservo_sim_axis_unit(sim)).to_str().unwrap(),
            "mm"
        );
        assert!(ehservo_sim_axis_unit(null()).is_null());
        while ehservo_sim_step(sim, &mut s) == EhservoStatus::Ok {}
        assert_eq!(ehservo_sim_e_max(sim, &mut e), EhservoStatus::Ok);
        assert_eq!(
            ehservo_sim_metric(sim, c"e_max_mm".as_ptr(), &mut e_mm),
            EhservoStatus::Ok
        );
        assert_eq!(e, e_mm);
        assert_eq!(
            ehservo_sim_e_max_deg(sim, &mut e),
            EhservoStatus::InvalidArgument
        );
        assert!(
            last_error().contains("on a linear axis, expected one of e_max,"),
            "{}",
            last_error()
        );
        ehservo_sim_free(sim);
    }
    // The same run by the library: e_max over t ≥ settle, in mm.
    let scen = Loop::load(std::path::Path::new(path.to_str().unwrap()), &[]).unwrap();
    let r = run(&scen, Keep::Nothing);
    assert_eq!(r.metrics.e_max, Some(e_mm));
    assert_eq!(r.metrics.axis, ehservo_scenario::axis::Axis::Linear);
}
