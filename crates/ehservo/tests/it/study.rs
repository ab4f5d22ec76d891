//! Sweeps and Monte Carlo: the same numbers, byte for byte, whatever the
//! thread count or the shard split; merge refuses what does not belong
//! together.

use crate::common::ehservo;
use std::path::{Path, PathBuf};

fn paper(file: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper")
        .join(file)
        .canonicalize()
        .unwrap()
        .display()
        .to_string()
}

/// A study of 2 grid values × 6 replicates = 12 runs of the Fig. 8 case
/// over 2 s, with a drawn γ1.
fn study(dir: &Path, seed: u64) -> PathBuf {
    let p = dir.join(format!("s{seed}.toml"));
    std::fs::write(
        &p,
        format!(
            r#"name = "small"
base = "{}"
seed = {seed}
set = ["simulation.horizon=2", "simulation.settle=1"]

[[axis]]
key = "controller.eta"
values = [0.0, 0.25]

[monte_carlo]
runs = 6
[[monte_carlo.draw]]
key = "controller.gamma1"
dist = "uniform"
low = 80.0
high = 120.0
"#,
            paper("fig8.toml")
        ),
    )
    .unwrap();
    p
}

fn sweep(study: &Path, out: &Path, extra: &[&str]) {
    let o = ehservo()
        .arg("sweep")
        .arg(study)
        .arg("--out")
        .arg(out)
        .args(["--quiet", "--no-plot"])
        .args(extra)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn identical_across_threads_and_shards() {
    let tmp = tempfile::tempdir().unwrap();
    let s = study(tmp.path(), 7);
    let one = tmp.path().join("t1");
    let two = tmp.path().join("t2");
    sweep(&s, &one, &["--threads", "1"]);
    sweep(&s, &two, &["--threads", "2"]);
    let a = std::fs::read(one.join("results.csv")).unwrap();
    assert_eq!(
        a,
        std::fs::read(two.join("results.csv")).unwrap(),
        "1 vs 2 threads"
    );
    let text = String::from_utf8(a.clone()).unwrap();
    assert_eq!(text.lines().count(), 13, "header + 12 runs");
    assert!(text
        .lines()
        .next()
        .unwrap()
        .starts_with("run,controller.eta,controller.gamma1,seed,e_max_deg"));

    // Three shards, each its own process, then merged.
    let shards: Vec<PathBuf> = (0..3)
        .map(|k| tmp.path().join(format!("shard{k}")))
        .collect();
    for (k, d) in shards.iter().enumerate() {
        sweep(&s, d, &["--shard", &format!("{k}/3")]);
    }
    let merged = tmp.path().join("merged");
    let o = ehservo()
        .arg("merge")
        .args(&shards)
        .arg("--out")
        .arg(&merged)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(
        a,
        std::fs::read(merged.join("results.csv")).unwrap(),
        "whole vs merged shards"
    );

    // Merge refuses a missing shard …
    let o = ehservo()
        .arg("merge")
        .args(&shards[..2])
        .arg("--out")
        .arg(tmp.path().join("m2"))
        .output()
        .unwrap();
    // Bad input, whatever the command that found it: exit 2.
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing"));
    // … and a shard of another study (another seed).
    let other = tmp.path().join("other");
    sweep(&study(tmp.path(), 8), &other, &["--shard", "2/3"]);
    let o = ehservo()
        .arg("merge")
        .args([&shards[0], &shards[1], &other])
        .arg("--out")
        .arg(tmp.path().join("m3"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("different studies"));
    assert!(!tmp.path().join("m3").exists());
    // A shard folder that is not there is a wrong argument: bad input, exit 2.
    let o = ehservo()
        .arg("merge")
        .arg(tmp.path().join("no-such-shard"))
        .arg("--out")
        .arg(tmp.path().join("m4"))
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Values at the edges of the floats (γ1 up to 1.7e308, η drawn over the
/// whole positive range): results.csv holds short, finite numbers only,
/// and shards merge to the whole run's bytes.
#[test]
fn extreme_values_stay_short_finite_and_shardable() {
    let tmp = tempfile::tempdir().unwrap();
    let s = tmp.path().join("edge.toml");
    std::fs::write(
        &s,
        format!(
            r#"name = "edge"
base = "{}"
seed = 3
set = ["simulation.horizon=0.5", "simulation.settle=0.25"]

[[axis]]
key = "controller.gamma1"
values = [100.0, 1e300, 1.7e308]

[monte_carlo]
runs = 3
[[monte_carlo.draw]]
key = "controller.eta"
dist = "loguniform"
low = 1e-300
high = 1.7976931348623157e308
"#,
            paper("fig2.toml")
        ),
    )
    .unwrap();
    let whole = tmp.path().join("whole");
    sweep(&s, &whole, &[]);
    let bytes = std::fs::read(whole.join("results.csv")).unwrap();
    let text = String::from_utf8(bytes.clone()).unwrap();
    assert_eq!(text.lines().count(), 10, "{text}");
    assert!(text.contains(",1e300,"), "{text}");
    for line in text.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        // run, γ1, η, seed, the metrics (the error cell is last and empty).
        for c in &cells[..cells.len() - 1] {
            assert!(c.len() <= 24, "a long cell {c} in {line}");
            if let Ok(x) = c.parse::<f64>() {
                assert!(x.is_finite(), "{c} in {line}");
            }
        }
    }
    let shards: Vec<PathBuf> = (0..2)
        .map(|k| tmp.path().join(format!("shard{k}")))
        .collect();
    for (k, d) in shards.iter().enumerate() {
        sweep(&s, d, &["--shard", &format!("{k}/2")]);
    }
    let merged = tmp.path().join("merged");
    let o = ehservo()
        .arg("merge")
        .args(&shards)
        .arg("--out")
        .arg(&merged)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("9 runs"));
    assert_eq!(bytes, std::fs::read(merged.join("results.csv")).unwrap());
}

#[test]
fn shipped_studies_parse_and_bad_studies_exit_2() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/studies");
    for f in std::fs::read_dir(&dir).unwrap() {
        let p = f.unwrap().path();
        ehservo::study::Plan::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    }
    let tmp = tempfile::tempdir().unwrap();
    for (text, needle) in [
        ("name = \"x\"\n", "base"),
        (&*format!("name = \"x\"\nbase = \"{}\"\n[[axis]]\nkey = \"controller.gamma1\"\nvalues = [-5.0]\n", paper("fig2.toml")), "gamma1"),
        (&*format!("name = \"x\"\nbase = \"{}\"\n[monte_carlo]\nruns = 0\n", paper("fig2.toml")), "monte_carlo.runs"),
        (&*format!("name = \"x\"\nbase = \"{}\"\ncolour = 1\n", paper("fig2.toml")), "colour"),
        ("name = \"x\"\nbase = \"/nonexistent.toml\"\n", "nonexistent"),
    ] {
        let p = tmp.path().join("bad.toml");
        std::fs::write(&p, text).unwrap();
        let out = tmp.path().join("o");
        let o = ehservo().arg("sweep").arg(&p).arg("--out").arg(&out).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "expected {needle:?} in {err}");
        assert!(!out.exists());
    }
    let o = ehservo()
        .arg("sweep")
        .arg(dir.join("gamma1-eta.toml"))
        .args(["--out", "/tmp/never", "--shard", "3/3"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}
