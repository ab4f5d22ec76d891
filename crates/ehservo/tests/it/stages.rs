//! The stages around the plant, from a scenario file: `[actuator]`,
//! `[sensor]` and `[fault]`.

use ehservo::run::{run, Keep};
use ehservo::scenario::Loop;
use std::process::Command;

fn parse(text: &str) -> Result<Loop, ehservo::scenario::ScenarioError> {
    Loop::parse_with(text, "<test>", &[])
}

/// A valve that saturates at 0.5 V and lags by 20 ms: the plant sees the
/// valve (`u_plant_V` in trace.csv), never more than 0.5 V, and the run
/// counts the samples where the command exceeded the range. The Fig. 2
/// NNBVSC needs about 0.73 V at its peak, so the limit is met.
#[test]
fn actuator_from_a_scenario_in_both_modes() {
    for mode in ["sampled", "continuous"] {
        let s = parse(&format!(
            "[simulation]\nmode = \"{mode}\"\nstep = 0.001\nhorizon = 3.0\n\
             [actuator]\nlimit = 0.5\ntime_constant = 0.02\n"
        ))
        .unwrap();
        let r = run(&s, Keep::Every(1));
        assert!(r.outcome.diverged.is_none(), "{mode}");
        assert!(r.trace.iter().all(|x| x.u_plant.abs() <= 0.5 + 1e-12));
        assert!(
            r.outcome.saturated > 0,
            "{mode}: the 0.5 V range was reached"
        );
        // The valve lags the command: somewhere they differ.
        assert!(r.trace.iter().any(|x| (x.u - x.u_plant).abs() > 1e-3));
    }
}

#[test]
fn actuator_and_sensor_keys_are_validated() {
    for (text, key) in [
        ("[actuator]\nlimit = -1.0\n", "actuator.limit"),
        (
            "[actuator]\ntime_constant = 0.0\n",
            "actuator.time_constant",
        ),
        ("[actuator]\nrate_limit = 5.0\n", "actuator.rate_limit"),
        ("[actuator]\nlag = 5.0\n", "actuator.lag"),
        (
            "[sensor]\nresolution = [-1.0, 0.0, 0.0]\n",
            "sensor.resolution",
        ),
        (
            "[fault]\nmeasurement_limit = [0.0, 1.0, 1.0]\n",
            "fault.measurement_limit",
        ),
        ("[fault]\nsafe_command = \"panic\"\n", "fault.safe_command"),
    ] {
        let e = parse(text).unwrap_err();
        assert_eq!(e.key, key, "{text}: {e}");
        assert_eq!(e.line_col.map(|l| l.0), Some(2), "{text}: {e}");
    }
}

/// An encoder of 1024 counts per revolution (step 2π/1024 = 6.1 mrad =
/// 0.35°) quantises what the controller sees, not the plant: the run stays
/// bounded and its error grows (the law sees a staircase), while the trace's
/// θ stays the true, unquantised angle.
#[test]
fn a_quantised_sensor_changes_what_the_controller_sees() {
    let exact = run(&parse("").unwrap(), Keep::Every(1));
    let q = 2.0 * std::f64::consts::PI / 1024.0;
    let coarse = run(
        &parse(&format!("[sensor]\nresolution = [{q}, 0.0, 0.0]\n")).unwrap(),
        Keep::Every(1),
    );
    assert!(coarse.outcome.diverged.is_none());
    assert_ne!(
        exact.metrics.e_max, coarse.metrics.e_max,
        "quantisation changed nothing"
    );
    let off_grid = coarse
        .trace
        .iter()
        .filter(|s| ((s.x[0] / q).round() * q - s.x[0]).abs() > 1e-9)
        .count();
    assert!(
        off_grid > coarse.trace.len() / 2,
        "θ in the trace is the true one"
    );
}

/// trace.csv gains a `u_plant_V` column when an actuator is present, and
/// summary.json counts the saturated samples.
#[test]
fn cli_trace_and_summary_show_the_actuator() {
    let tmp = tempfile::tempdir().unwrap();
    let f = tmp.path().join("valve.toml");
    std::fs::write(&f, "[actuator]\nlimit = 0.5\n").unwrap();
    let out = tmp.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_ehservo"))
        .args(["run", "--no-plot", "-q", "--out"])
        .arg(&out)
        .arg(&f)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    // The law's parts, the valve's output, then the physical states.
    assert!(csv
        .lines()
        .next()
        .unwrap()
        .contains(",b_bar_V_s3,u_plant_V,theta_dot_deg_s,theta_ddot_deg_s2,p_load_Pa"));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["faults"]["saturated_samples"].as_u64().unwrap() > 0);
    assert_eq!(summary["scenario"]["actuator"]["limit"], 0.5);
}
