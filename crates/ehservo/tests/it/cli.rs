//! The command line as a user meets it: outputs, exit codes, bad input.

use crate::common::{ehservo, repo};
use std::path::{Path, PathBuf};

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn run_writes_trace_summary_and_plot() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("fig2");
    let o = ehservo()
        .args(["run"])
        .arg(repo().join("scenarios/paper/fig2.toml"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("e_max"), "{stdout}");

    let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    for col in [
        "t_s",
        "theta_d_deg",
        "theta_deg",
        "e_deg",
        "u_V",
        "u_eq_V",
        "u_sw_V",
        "sigma_rad_s2",
        "sigma_delta_rad_s2",
        "wphi_rad_s3",
        "uncertainty_rad_s3",
        "w_norm",
        "w_1",
        "w_128",
    ] {
        assert!(
            header.split(',').any(|h| h == col),
            "missing column {col} in {header}"
        );
    }
    // 10 s at 0.01 s: samples k = 0..=1000.
    assert_eq!(lines.clone().count(), 1001);
    assert!(!csv.contains("NaN") && !csv.contains("inf"));

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let m = &json["metrics"];
    for key in [
        "e_max_deg",
        "e_final_deg",
        "e_rms_deg",
        "u_max",
        "chattering",
        "w_norm_max",
        "w_norm_final",
        "diverged",
        "diverged_at_s",
    ] {
        assert!(m.get(key).is_some(), "metrics.{key} missing");
    }
    assert_eq!(m["diverged"], false);
    assert!(json["software"]["version"].is_string());
    assert_eq!(json["scenario"]["name"], "fig2");
    let png = std::fs::read(out.join("trace.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    // No staging directory left behind.
    let leftovers: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
        .collect();
    assert!(leftovers.is_empty());
}

#[test]
fn set_overrides_reach_the_summary() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("g200");
    let o = ehservo()
        .arg("run")
        .arg(repo().join("scenarios/paper/fig2.toml"))
        .args([
            "--set",
            "controller.gamma1=200",
            "--no-plot",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    assert!(o.stdout.is_empty());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["scenario"]["controller"]["gamma1"], 200.0);
    assert!(!out.join("trace.png").exists());
}

#[test]
fn a_diverged_run_is_a_result_with_exit_code_0() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = write(
        tmp.path(),
        "vsc.toml",
        "name = \"vsc-fig2\"\n[controller]\nkind = \"vsc\"\n",
    );
    let out = tmp.path().join("vsc");
    let o = ehservo()
        .arg("run")
        .arg(&sc)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("UNBOUNDED at t ="));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["metrics"]["diverged"], true);
    assert!(json["metrics"]["diverged_at_s"].as_f64().unwrap() > 0.0);
    assert_eq!(json["metrics"]["e_max_deg"], serde_json::Value::Null);
    let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    assert!(!csv.to_lowercase().contains("nan") && !csv.contains("inf"));
}

#[test]
fn bad_input_exits_2_names_the_key_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let cases = [
        ("[plant.params]\nJt = -0.05\n", "plant.params.Jt"),
        ("[plant.params]\nPs = 0.0\n", "plant.params.Ps"),
        ("[simulation]\nstep = 0.0\n", "simulation.step"),
        ("[simulation]\nhorizon = 10.003\n", "simulation.horizon"),
        ("[surface]\npoles = [-20.0, 30.0, -40.0]\n", "surface.poles"),
        ("[controller]\nkind = \"lqr\"\n", "controller.kind"),
        ("[controller]\ngamma = 3\n", "controller.gamma"),
        ("[simulation]\nstep = \"small\"\n", "simulation.step"),
        ("[simulation\n", "syntax"),
        ("[controller]\nbound_b = 1.5\n", "controller.bound_b"),
    ];
    for (i, (text, needle)) in cases.iter().enumerate() {
        let sc = write(tmp.path(), &format!("bad{i}.toml"), text);
        let out = tmp.path().join(format!("out{i}"));
        let o = ehservo()
            .arg("run")
            .arg(&sc)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "case {i}: {err}");
        assert!(
            err.contains(needle),
            "case {i}: expected {needle:?} in {err}"
        );
        assert!(
            err.contains(&format!("bad{i}.toml")),
            "case {i}: the file is named: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists(), "case {i}: output written for bad input");
    }
    // A missing file and a bad --set are bad input too.
    let o = ehservo()
        .args(["run", "/nonexistent/x.toml"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = ehservo()
        .arg("run")
        .arg(repo().join("scenarios/paper/fig2.toml"))
        .args(["--set", "controller.gamma1"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn a_rerun_replaces_the_outputs_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("o");
    for g in ["100", "200"] {
        let o = ehservo()
            .arg("run")
            .arg(repo().join("scenarios/paper/fig2.toml"))
            .args([
                "--no-plot",
                "-q",
                "--set",
                &format!("controller.gamma1={g}"),
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0));
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["scenario"]["controller"]["gamma1"], 200.0);
}

/// The reference examples run end to end from another directory (the CSV
/// is found next to its scenario); the step's θd starts at 0 and settles
/// at its 5°.
#[test]
fn reference_examples_run_end_to_end() {
    let tmp = tempfile::tempdir().unwrap();
    for name in ["step", "chirp", "csv"] {
        let out = tmp.path().join(name);
        let o = ehservo()
            .current_dir(tmp.path())
            .arg("run")
            .arg(repo().join(format!("scenarios/examples/{name}.toml")))
            .args(["--set", "output.plot=false", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
        assert!(summary.contains("\"diverged\": false"), "{name}: {summary}");
        let csv = std::fs::read_to_string(out.join("trace.csv")).unwrap();
        let theta_d = |line: &str| -> f64 { line.split(',').nth(1).unwrap().parse().unwrap() };
        let mut rows = csv.lines().skip(1);
        let first = theta_d(rows.next().unwrap());
        let last = theta_d(rows.last().unwrap());
        if name == "step" {
            assert!(first.abs() < 1e-12, "{first}");
            assert!((last - 5.0).abs() < 1e-9, "{last}");
        }
    }
}

/// `ehservo run` (and `check`) of a file that is not a scenario names what
/// it is and the command that takes it, exit 2, nothing written.
#[test]
fn run_of_a_study_tune_league_or_manifest_names_it() {
    let tmp = tempfile::tempdir().unwrap();
    let cases = [
        (
            "scenarios/realistic/delay.toml",
            "this is a study (it has [[axis]]), not a scenario: run it with `ehservo sweep",
        ),
        (
            "scenarios/league/tune-pid-fig2.toml",
            "this is a tune file (it has `scenarios`), not a scenario: run it with `ehservo tune",
        ),
        (
            "scenarios/league/suite.toml",
            "this is a league suite (it has [tuning]), not a scenario: run it with `ehservo league",
        ),
        (
            "scenarios/paper/manifest.toml",
            "this is the reproduction's manifest (it has [[reading]]), not a scenario: run it with `ehservo reproduce",
        ),
    ];
    for (file, expect) in cases {
        let out = tmp.path().join("o");
        let run = ehservo()
            .current_dir(repo())
            .args(["run", file, "--no-plot", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        crate::common::rejected_naming(file, &run, expect);
        assert!(!out.exists(), "{file}: nothing written");
        let check = ehservo()
            .current_dir(repo())
            .args(["check", file])
            .output()
            .unwrap();
        crate::common::rejected_naming(file, &check, expect);
    }
    // A study whose only study key is `base` is one too; a scenario with a
    // misspelt key still gets serde's message.
    let base = write(tmp.path(), "b.toml", "base = \"x.toml\"\n");
    let o = ehservo().arg("check").arg(&base).output().unwrap();
    crate::common::rejected(
        &base.display().to_string(),
        &o,
        "this is a study (it has `base`)",
    );
    let typo = write(tmp.path(), "t.toml", "[controller]\ngama1 = 1\n");
    let o = ehservo().arg("check").arg(&typo).output().unwrap();
    crate::common::rejected("t.toml", &o, "unknown field `gama1`");
}

/// `ehservo --version` names the package's version and the commit built.
#[test]
fn version_names_the_commit() {
    let o = ehservo().arg("--version").output().unwrap();
    assert!(o.status.success());
    let v = String::from_utf8(o.stdout).unwrap();
    let want = format!("ehservo {} (commit ", env!("CARGO_PKG_VERSION"));
    assert!(v.starts_with(&want), "{v}");
    let commit = v[want.len()..].trim_end().strip_suffix(')').unwrap_or("");
    // A git checkout's short hash, or "unknown" outside one.
    let is_hash = commit.len() >= 7 && commit.chars().all(|c| c.is_ascii_hexdigit());
    assert!(is_hash || commit == "unknown", "{v}");
    if repo().join(".git").exists() {
        let head = std::process::Command::new("git")
            .args(["rev-parse", "HEAD"])
            .current_dir(repo())
            .output();
        if let Ok(h) = head {
            if h.status.success() {
                let full = String::from_utf8(h.stdout).unwrap();
                assert!(full.starts_with(commit), "{commit} is not HEAD {full}");
            }
        }
    }
}

/// `--set controller.kind=K` on a file of another kind: the kind switches,
/// the file's `[controller]` keys that K does not take (by K's schema) are
/// dropped and named on one line of stderr, the others kept; a key of the
/// old kind given with the switch is still bad input (exit 2, one line
/// naming the file, the key and the reason).
#[test]
fn set_controller_kind_switches_and_names_the_dropped_keys() {
    let file = repo().join("scenarios/hopsan/position-servo.toml");
    let text = std::fs::read_to_string(&file).unwrap();
    let table: toml::Table = toml::from_str(&text).unwrap();
    let given: Vec<String> = table["controller"]
        .as_table()
        .unwrap()
        .keys()
        .filter(|k| *k != "kind")
        .cloned()
        .collect();
    let arc = ehservo::scenario::ControllerCfg::keys_of("arc").unwrap();
    let dropped: Vec<&String> = given.iter().filter(|k| !arc.contains(k)).collect();
    assert!(!dropped.is_empty(), "the file has keys arc does not take");
    let o = ehservo()
        .arg("check")
        .arg(&file)
        .args(["--set", "controller.kind=arc"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let out: toml::Table = toml::from_str(&String::from_utf8_lossy(&o.stdout)).unwrap();
    assert_eq!(out["controller"]["kind"].as_str(), Some("arc"));
    let notes: Vec<&str> = err.lines().filter(|l| l.starts_with("note:")).collect();
    assert_eq!(notes.len(), 1, "{err}");
    for k in &given {
        assert_eq!(
            notes[0].contains(&format!("`{k}`")),
            dropped.contains(&k),
            "{k}: {}",
            notes[0]
        );
    }
    assert!(notes[0].contains("position-servo.toml") && notes[0].contains("controller.kind=arc"));
    // The old kind's key given with the switch: refused.
    let k = dropped[0];
    let o = ehservo()
        .arg("check")
        .arg(&file)
        .args([
            "--set",
            "controller.kind=arc",
            "--set",
            &format!("controller.{k}=1"),
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(
        lines[0].starts_with("error: ")
            && lines[0].contains("position-servo.toml")
            && lines[0].contains(&format!("`controller.{k}`"))
            && lines[0].contains("unknown field"),
        "{err}"
    );
}

/// `--set reference.kind=K` on a file of another reference kind: the keys
/// K does not take are dropped and named, the ones it takes kept (in the
/// axis's unit), and the run builds. The slide's step (`amplitude_mm`,
/// `start`, `prefilter_tau`) switched to a sine keeps `amplitude_mm` and
/// drops `start` and `prefilter_tau` (a sine has neither: docs/guide).
#[test]
fn set_reference_kind_switches_and_names_the_dropped_keys() {
    let dir = tempfile::tempdir().unwrap();
    let file = repo().join("scenarios/cylinders/slide.toml");
    let table: toml::Table = toml::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    let r = table["reference"].as_table().unwrap();
    assert_eq!(r["kind"].as_str(), Some("step"), "the test's premise");
    let text = toml::to_string(&table).unwrap();
    let f = write(dir.path(), "s.toml", &text);
    let o = ehservo()
        .arg("check")
        .arg(&f)
        .args(["--set", "reference.kind=sine"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let out: toml::Table = toml::from_str(&String::from_utf8_lossy(&o.stdout)).unwrap();
    let r2 = out["reference"].as_table().unwrap();
    // The default kind is not written out.
    assert_eq!(
        r2.get("kind").map_or(Some("sine"), |k| k.as_str()),
        Some("sine")
    );
    assert_eq!(r2.get("amplitude_mm"), r.get("amplitude_mm"));
    let note = err
        .lines()
        .find(|l| l.contains("--set reference.kind=sine"))
        .unwrap_or_else(|| panic!("no note: {err}"));
    for k in r.keys().filter(|k| *k != "kind") {
        let kept = ["amplitude_mm", "offset_mm"].contains(&k.as_str());
        assert_eq!(!note.contains(&format!("`{k}`")), kept, "{k}: {note}");
        assert_eq!(r2.contains_key(k), kept, "{k}");
    }
}

/// `check` shows what the design derives: the PID's kp, ki, kd on the
/// paper's servo satisfy its pole placement (the closed loop
/// s⁴ + ā3s³ + (ā2 + b̄0kd)s² + (ā1 + b̄0kp)s + b̄0ki has the double pole
/// −λ, λ = design_pole = 30, module doc of `control::pid`), state
/// feedback's frequency on the slide is ω_h = √ā2, and writing the shown
/// values into the file runs the same loop.
#[test]
fn check_shows_the_designed_parameters_which_rebuild_the_same_loop() {
    let dir = tempfile::tempdir().unwrap();
    let designed = |f: &Path| -> Vec<(String, f64, String)> {
        let o = ehservo().arg("check").arg(f).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = String::from_utf8_lossy(&o.stdout).to_string();
        // The output is still a scenario: the values are comments.
        toml::from_str::<toml::Table>(&text).unwrap();
        text.lines()
            .filter_map(|l| l.strip_prefix("#   "))
            .map(|l| {
                let (kv, unit) = l.split_once("  # ").unwrap();
                let (k, v) = kv.split_once(" = ").unwrap();
                (k.to_string(), v.parse().unwrap(), unit.to_string())
            })
            .collect()
    };
    let pid = write(dir.path(), "pid.toml", "[controller]\nkind = \"pid\"\n");
    let d = designed(&pid);
    let get = |d: &[(String, f64, String)], k: &str| d.iter().find(|x| x.0 == k).unwrap().clone();
    let (kp, ki, kd) = (get(&d, "kp"), get(&d, "ki"), get(&d, "kd"));
    assert_eq!(kp.2, "V/rad");
    let lp = ehservo::scenario::Loop::parse("").unwrap();
    let a = lp.model().coeffs.as_array();
    let b0 = lp.model().b_at_rest();
    let c = [1.0, a[2], a[1] + b0 * kd.1, a[0] + b0 * kp.1, b0 * ki.1];
    let p = |s: f64| c.iter().fold(0.0, |acc, ci| acc * s + ci);
    let dp = |s: f64| 4.0 * s.powi(3) + 3.0 * c[1] * s * s + 2.0 * c[2] * s + c[3];
    assert!(
        p(-30.0).abs() < 1e-9 * c[4] && dp(-30.0).abs() < 1e-9 * c[4],
        "{c:?}"
    );
    // The values written in: the same run, bit for bit.
    let run = |f: &Path, out: &str| -> String {
        let o = ehservo()
            .args(["run", "--no-plot", "-q", "--out"])
            .arg(dir.path().join(out))
            .arg(f)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read_to_string(dir.path().join(out).join("trace.csv")).unwrap()
    };
    let mut text = String::from("[controller]\nkind = \"pid\"\n");
    for (k, v, _) in &d {
        text.push_str(&format!("{k} = {v:e}\n"));
    }
    let written = write(dir.path(), "written.toml", &text);
    assert!(designed(&written).is_empty(), "nothing left to derive");
    assert_eq!(run(&pid, "a"), run(&written, "b"));
    // State feedback on the slide: ω_h = √ā2 of its nominal model.
    let slide = repo().join("scenarios/cylinders/slide.toml");
    let lp = ehservo::scenario::Loop::load(&slide, &[]).unwrap();
    let f = get(&designed(&slide), "frequency");
    let wh = lp.model().coeffs.as_array()[1].sqrt();
    assert!(
        (f.1 - wh).abs() < 1e-12 * wh && f.2 == "rad/s",
        "{f:?} vs {wh}"
    );
}
