//! Nothing moves: every scenario under `scenarios/` (and a few overridden
//! variants that reach the continuous mode, the physical plant and the
//! boundary-layer VSC) gives the same `trace.csv`, byte for byte in every
//! captured column (columns added since — θ̇, θ̈, the load pressure — follow
//! the captured ones on each line), and the
//! same metrics, divergence and fault counts in `summary.json`, bit for bit,
//! as the outputs captured in `tests/golden/` before the platform rework
//! (commit 477679b). A refactoring that changes one floating-point operation
//! on the paper's path fails here. `examples/pid-valve.toml` came with the
//! PID and the actuator; its outputs were captured when it was added, as
//! were those of `examples/{step,chirp,csv}.toml` with the reference kinds.
//!
//! To re-capture after an intended change of results (never for a
//! refactoring): `cargo run --release -- run FILE --out DIR --no-plot`, then
//! gzip DIR/trace.csv and copy the three keys of DIR/summary.json.

use crate::common::repo;
use flate2::read::GzDecoder;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;

fn golden() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

/// (golden name, scenario file, overrides).
fn cases() -> Vec<(String, PathBuf, Vec<&'static str>)> {
    let mut v = Vec::new();
    for dir in ["scenarios/paper", "scenarios/examples"] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(repo().join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .filter(|p| p.file_stem().is_some_and(|s| s != "manifest"))
            .collect();
        files.sort();
        for f in files {
            let name = f.file_stem().unwrap().to_string_lossy().into_owned();
            v.push((name, f, vec![]));
        }
    }
    let paper = |f: &str| repo().join("scenarios/paper").join(f);
    v.push((
        "x-fig2-continuous".into(),
        paper("fig2.toml"),
        vec!["simulation.mode=continuous", "simulation.step=0.001"],
    ));
    v.push((
        "x-fig3-physical".into(),
        paper("fig3.toml"),
        vec!["plant.model=physical"],
    ));
    v.push((
        "x-fig3-vsc-sat".into(),
        paper("fig3.toml"),
        vec!["controller.kind=vsc-sat"],
    ));
    v.push((
        "x-fig8-physical-sub4".into(),
        paper("fig8.toml"),
        vec!["plant.model=physical", "simulation.substeps=4"],
    ));
    v
}

/// The first line where `b` does not continue `a`'s line: the same
/// bytes, then nothing or a comma and the columns added since the capture
/// (the plant's physical states, what the sensors measured).
fn first_difference(a: &str, b: &str) -> Option<String> {
    for (i, (la, lb)) in a.lines().zip(b.lines()).enumerate() {
        let same = lb
            .strip_prefix(la)
            .is_some_and(|rest| rest.is_empty() || rest.starts_with(','));
        if !same {
            return Some(format!("line {}:\n  golden: {la}\n  now:    {lb}", i + 1));
        }
    }
    (a.lines().count() != b.lines().count()).then(|| {
        format!(
            "{} lines in the golden file, {} now",
            a.lines().count(),
            b.lines().count()
        )
    })
}

#[test]
fn every_scenario_gives_the_captured_outputs_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let cases = cases();
    assert!(cases.len() >= 20, "scenarios went missing: {}", cases.len());
    let mut failures = Vec::new();
    for (name, file, sets) in cases {
        let gold_json = golden().join(format!("{name}.json"));
        assert!(
            gold_json.exists(),
            "no golden output for scenario {name}: capture it (see the module doc)"
        );
        let out = tmp.path().join(&name);
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_ehservo"));
        cmd.arg("run").arg(&file).arg("--out").arg(&out);
        cmd.args(["--no-plot", "-q"]);
        for s in sets {
            cmd.args(["--set", s]);
        }
        let o = cmd.output().unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );

        let mut gz = Vec::new();
        std::fs::File::open(golden().join(format!("{name}.trace.csv.gz")))
            .map(GzDecoder::new)
            .and_then(|mut d| d.read_to_end(&mut gz))
            .unwrap();
        let want = String::from_utf8(gz).unwrap();
        let got = std::fs::read_to_string(out.join("trace.csv")).unwrap();
        if let Some(d) = first_difference(&want, &got) {
            failures.push(format!("{name}: trace.csv differs at {d}"));
        }

        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let gold: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&gold_json).unwrap()).unwrap();
        for key in ["metrics", "divergence", "faults"] {
            // Both printed by serde_json's shortest round-trip writer:
            // equal text is equal bits (and tells 0.0 from -0.0).
            let (now, want) = (summary[key].to_string(), gold[key].to_string());
            if now != want {
                failures.push(format!(
                    "{name}: summary.json `{key}` differs:\n  golden: {want}\n  now:    {now}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
