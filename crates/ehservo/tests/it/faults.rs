//! Numerical faults end or continue a run as documented, are named in
//! summary.json, and never put a NaN into trace.csv.

use std::path::Path;
use std::process::Command;

fn run(dir: &Path, name: &str, text: &str) -> (serde_json::Value, String) {
    let sc = dir.join(format!("{name}.toml"));
    std::fs::write(&sc, text).unwrap();
    let out = dir.join(name);
    let o = Command::new(env!("CARGO_BIN_EXE_ehservo"))
        .arg("run")
        .arg(&sc)
        .arg("--out")
        .arg(&out)
        .arg("--no-plot")
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let lower = csv.to_lowercase();
    assert!(
        !lower.contains("nan") && !lower.contains("inf"),
        "{name}: non-finite value in trace.csv"
    );
    (json, csv)
}

#[test]
fn divergence_ends_the_run_with_its_time_and_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let (j, csv) = run(tmp.path(), "diverge", "[controller]\nkind = \"vsc\"\n");
    assert_eq!(j["metrics"]["diverged"], true);
    assert_eq!(j["divergence"]["reason"], "theta-limit");
    let t = j["divergence"]["t"].as_f64().unwrap();
    assert!(j["divergence"]["message"]
        .as_str()
        .unwrap()
        .contains("unbounded at t ="));
    // The trace stops at the last sample before the divergence.
    let last_t: f64 = csv
        .lines()
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(last_t < t);
}

#[test]
fn a_non_finite_control_ends_the_run_as_such() {
    // θ̇(0) = 1e300 makes the equivalent control overflow at t = 0.
    let tmp = tempfile::tempdir().unwrap();
    let (j, csv) = run(
        tmp.path(),
        "overflow",
        "[simulation]\nx0 = [0.0, 1e300, 0.0]\n",
    );
    assert_eq!(j["metrics"]["diverged"], true);
    assert_eq!(j["divergence"]["reason"], "non-finite-control");
    assert_eq!(j["divergence"]["t"], 0.0);
    assert_eq!(
        csv.lines().count(),
        1,
        "header only: the bad sample is not logged"
    );
}

#[test]
fn the_valve_root_clamp_is_counted_and_the_run_goes_on() {
    // A 0.3 MPa supply cannot hold the ~0.7 MPa load pressure the Fig. 2
    // motion needs: Ps − sgn(u)·Pl < 0 at times; the root is clamped (no
    // flow that way), b̄ floored, and the run continues or diverges — as a
    // result, never as NaN.
    let tmp = tempfile::tempdir().unwrap();
    let (j, _) = run(tmp.path(), "lowps", "[plant.params]\nPs = 0.3e6\n");
    assert!(
        j["faults"]["valve_root_clamped_samples"].as_u64().unwrap() > 0,
        "{}",
        j["faults"]
    );
}

#[test]
fn a_zero_error_norm_is_guarded_and_counted() {
    // θd ≡ 0 and x(0) = 0: E = 0 at rest. σΔ = μ = ξ = 0 there (no division
    // by ‖E‖, no 0/0 in σΔ/(|σΔ| + μ)); u = 0 keeps the plant at rest, so
    // every sample is guarded and the run completes.
    let tmp = tempfile::tempdir().unwrap();
    let (j, csv) = run(
        tmp.path(),
        "rest",
        "[reference]\namplitude_deg = 0.0\n[simulation]\nhorizon = 1.0\nsettle = 0.5\n",
    );
    assert_eq!(j["metrics"]["diverged"], false);
    assert_eq!(
        j["faults"]["zero_error_norm_samples"].as_u64().unwrap(),
        101
    );
    assert_eq!(j["metrics"]["e_max_deg"], 0.0);
    assert!(
        csv.lines()
            .skip(1)
            .all(|l| l.split(',').nth(4) == Some("0")),
        "u = 0 throughout"
    );
}
