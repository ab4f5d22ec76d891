//! IFAC benchmark 9007 (`plant.model = "ifac9007"`, docs/ifac9007.md): the
//! reduced-budget league (scenarios/ifac9007/league-quick.toml) runs, and
//! its worst case over the box of B, m, KL and FL is recomputed for one
//! controller by running each corner with `ehservo run`, independently of
//! the league's box code.

use crate::common::{self, repo};
use std::collections::HashMap;

/// The rows of a CSV as maps from its header.
fn rows(path: &std::path::Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

fn e_max_of_run(set: &[String]) -> f64 {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = repo().join("scenarios/ifac9007/nominal.toml");
    let mut cmd = common::ehservo();
    cmd.arg("run")
        .arg(&scenario)
        .arg("--no-plot")
        .arg("--out")
        .arg(tmp.path());
    for s in set {
        cmd.arg("--set").arg(s);
    }
    let o = cmd.output().unwrap();
    common::succeeded("ehservo run of a corner", &o);
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(j["metrics"]["diverged"], false, "{set:?}");
    j["metrics"]["e_max"].as_f64().unwrap()
}

#[test]
fn quick_league_worst_over_the_box_is_the_worst_corner_or_draw() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("league");
    let o = common::ehservo()
        .arg("league")
        .arg(repo().join("scenarios/ifac9007/league-quick.toml"))
        .args(["--no-plot", "-q", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    common::succeeded("ehservo league (ifac9007, quick)", &o);
    let runs = rows(&out.join("runs.csv"));
    let mine: Vec<_> = runs
        .iter()
        .filter(|r| r["controller"] == "pid-p1" && r["scenario"] == "box-b-m-kl-fl")
        .collect();
    // 2^4 corners and 4 draws inside.
    assert_eq!(mine.len(), 16 + 4);
    // The corners, made here: bit j of i takes key j's high end (keys in
    // name order: B, FL, KL, m), each run by `ehservo run` with the P law
    // of the suite (kp = 1, given, so the same on every run).
    let ends: [(&str, [f64; 2]); 4] = [
        ("plant.B", [9000.0, 16000.0]),
        ("plant.FL", [0.0, 800.0]),
        ("plant.KL", [0.000103, 0.0035]),
        ("plant.m", [0.05, 0.3]),
    ];
    let mut worst_corner: f64 = 0.0;
    for i in 0..16usize {
        let mut set: Vec<String> = vec![
            "controller.kind=\"pid\"".into(),
            "controller.kp=1.0".into(),
            "controller.ki=0.0".into(),
            "controller.kd=0.0".into(),
        ];
        for (j, (k, r)) in ends.iter().enumerate() {
            set.push(format!("{k}={:?}", r[(i >> j) & 1]));
        }
        let e = e_max_of_run(&set);
        // The league ran the same corner (its `set` column names it).
        let row = mine
            .iter()
            .find(|r| {
                let s = &r["set"];
                ends.iter()
                    .enumerate()
                    .all(|(j, (k, v))| s.contains(&format!("{k}={:?}", v[(i >> j) & 1])))
            })
            .unwrap_or_else(|| panic!("corner {i} not in runs.csv"));
        let le: f64 = row["e_max_mm"].parse().unwrap();
        assert!(
            (le - e).abs() <= 1e-9 * e.abs().max(1e-12),
            "corner {i}: league {le}, run {e}"
        );
        worst_corner = worst_corner.max(e);
    }
    let league = rows(&out.join("league.csv"));
    let row = league
        .iter()
        .find(|r| r["controller"] == "pid-p1" && r["scenario"] == "box-b-m-kl-fl")
        .unwrap();
    let worst: f64 = row["e_max_worst_mm"].parse().unwrap();
    let over_runs = mine
        .iter()
        .map(|r| r["e_max_mm"].parse::<f64>().unwrap())
        .fold(0.0, f64::max);
    // The league's worst is the largest of its runs, to the bit.
    assert_eq!(worst.to_bits(), over_runs.to_bits());
    assert!(worst >= worst_corner);
    // FL = 800 pushes the carriage back and a P law has no integral: its
    // offset heads for (σ + KL)·FL/(A·kp) = 0.242·800/10.75 ≈ 18 L, so
    // the box is far worse than the nominal plant (FL = 0).
    let nominal: f64 = league
        .iter()
        .find(|r| r["controller"] == "pid-p1" && r["scenario"] == "nominal")
        .unwrap()["e_max_worst_mm"]
        .parse()
        .unwrap();
    assert!(
        worst_corner > 100.0 * nominal,
        "{worst_corner} vs {nominal}"
    );
}
