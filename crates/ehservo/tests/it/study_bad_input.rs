//! Hostile input to `sweep` and `merge`.
//!
//! - `tests/bad-input-study/`: study files, each rejected by `sweep` before
//!   anything runs.
//! - `tests/bad-input-merge/`: merge cases built from real shards (a 6-run
//!   study in 3 shards, and shard 2/3 of the same study with another seed),
//!   each naming the shards to merge and edited copies of them.
//!
//! Every case starts with `# expect: NEEDLE` and must end with exit code 2,
//! one line on stderr containing the needle and naming the file or shard,
//! no panic, and nothing written (no output, no staging directory).

use crate::common;
use common::{corpus, ehservo, rejected, rejected_naming};
use std::path::{Path, PathBuf};

#[test]
fn every_bad_study_is_rejected_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    for c in corpus("bad-input-study", 15) {
        let out = tmp.path().join(c.path.file_stem().unwrap());
        let o = ehservo()
            .arg("sweep")
            .arg(&c.path)
            .arg("--out")
            .arg(&out)
            .args(["--quiet", "--no-plot"])
            .output()
            .unwrap();
        rejected_naming(&c.name, &o, &c.expect);
        assert!(!out.exists(), "{}: output written for bad input", c.name);
    }
    // Nothing was left behind in the parent either (no staging directories).
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}

/// 6 runs (3 values × 2 replicates, a drawn γ1) of the Fig. 2 case over
/// 0.5 s.
fn write_study(dir: &Path, seed: u64) -> PathBuf {
    let base = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper/fig2.toml")
        .canonicalize()
        .unwrap();
    let p = dir.join(format!("study{seed}.toml"));
    std::fs::write(
        &p,
        format!(
            r#"name = "tiny"
base = "{}"
seed = {seed}
set = ["simulation.horizon=0.5", "simulation.settle=0.25"]

[[axis]]
key = "controller.eta"
values = [0.0, 0.1, 0.2]

[monte_carlo]
runs = 2
[[monte_carlo.draw]]
key = "controller.gamma1"
dist = "uniform"
low = 80.0
high = 120.0
"#,
            base.display()
        ),
    )
    .unwrap();
    p
}

fn sweep(study: &Path, out: &Path, shard: &str) {
    let o = ehservo()
        .arg("sweep")
        .arg(study)
        .arg("--out")
        .arg(out)
        .args(["--quiet", "--no-plot", "--shard", shard])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

fn int(v: &toml::Value, what: &str) -> usize {
    v.as_integer()
        .and_then(|i| usize::try_from(i).ok())
        .unwrap_or_else(|| panic!("{what}: a whole number"))
}

/// Makes the copy a `[[copy]]` table describes: a shard's files, then its
/// edits of results.csv (lines count from 1, the header) or study.json.
fn make_copy(shards: &Path, dir: &Path, c: &toml::Table) -> PathBuf {
    let s = |k: &str| c.get(k).and_then(|v| v.as_str()).unwrap();
    let to = dir.join(s("name"));
    copy_dir(&shards.join(s("from")), &to);
    let csv_path = to.join("results.csv");
    let text = std::fs::read_to_string(&csv_path).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let head: Vec<String> = lines[0].split(',').map(String::from).collect();
    let mut csv_text = None;
    for (op, v) in c {
        match op.as_str() {
            "name" | "from" => {}
            "keep_lines" => lines.truncate(int(v, op)),
            "append_line" => lines.push(lines[int(v, op) - 1].clone()),
            "copy_line" => {
                let a = v.as_array().unwrap();
                lines[int(&a[1], op) - 1] = lines[int(&a[0], op) - 1].clone();
            }
            "set_line" => {
                let t = v.as_table().unwrap();
                lines[int(&t["line"], op) - 1] = t["text"].as_str().unwrap().into();
            }
            "set_cell" => {
                let t = v.as_table().unwrap();
                let col = head
                    .iter()
                    .position(|h| h == t["column"].as_str().unwrap())
                    .unwrap();
                let l = int(&t["line"], op) - 1;
                // The shards' rows have no quoted cells (no errors).
                let mut cells: Vec<String> = lines[l].split(',').map(String::from).collect();
                cells[col] = t["value"].as_str().unwrap().into();
                lines[l] = cells.join(",");
            }
            "cut_bytes" => {
                let all = lines.join("\n") + "\n";
                csv_text = Some(all[..all.len() - int(v, op)].to_string());
            }
            "replace" | "write" => {
                let t = v.as_table().unwrap();
                let f = to.join(t["file"].as_str().unwrap());
                let new = if op == "write" {
                    t["text"].as_str().unwrap().to_string()
                } else {
                    std::fs::read_to_string(&f)
                        .unwrap()
                        .replace(t["from"].as_str().unwrap(), t["to"].as_str().unwrap())
                };
                std::fs::write(&f, new).unwrap();
                if f == csv_path {
                    return to;
                }
            }
            // results.csv replaced by a symbolic link (to a device).
            "link_results" => {
                std::fs::remove_file(&csv_path).unwrap();
                std::os::unix::fs::symlink(v.as_str().unwrap(), &csv_path).unwrap();
                return to;
            }
            "json" => {
                let t = v.as_table().unwrap();
                let f = to.join("study.json");
                let mut j: serde_json::Value =
                    serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
                *j.pointer_mut(t["pointer"].as_str().unwrap()).unwrap() =
                    serde_json::to_value(t["value"].clone()).unwrap();
                std::fs::write(&f, serde_json::to_string_pretty(&j).unwrap()).unwrap();
            }
            other => panic!("unknown edit `{other}`"),
        }
    }
    let csv_text = csv_text.unwrap_or_else(|| lines.join("\n") + "\n");
    if csv_text != text {
        std::fs::write(&csv_path, csv_text).unwrap();
    }
    to
}

fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut v: Vec<(PathBuf, Vec<u8>)> = walk(dir)
        .into_iter()
        .map(|p| {
            let b = std::fs::read(&p).unwrap();
            (p, b)
        })
        .collect();
    v.sort();
    v
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

#[test]
fn every_bad_merge_is_rejected_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    let shards = tmp.path().join("shards");
    std::fs::create_dir(&shards).unwrap();
    let study = write_study(tmp.path(), 1);
    for k in 0..3 {
        sweep(&study, &shards.join(format!("s{k}")), &format!("{k}/3"));
    }
    sweep(&write_study(tmp.path(), 2), &shards.join("t2"), "2/3");

    // The real shards merge, into exactly their runs, with finite cells.
    let good = tmp.path().join("good");
    let o = ehservo()
        .arg("merge")
        .args((0..3).map(|k| shards.join(format!("s{k}"))))
        .arg("--out")
        .arg(&good)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("6 runs"));
    let merged = std::fs::read_to_string(good.join("results.csv")).unwrap();
    assert_eq!(merged.lines().count(), 7, "header + 6 runs: {merged}");
    let lower = merged.to_lowercase();
    assert!(!lower.contains("nan") && !lower.contains("inf"), "{merged}");

    let before = snapshot(&shards);
    let cases = corpus("bad-input-merge", 10);
    for c in &cases {
        let (name, expect) = (&c.name, &c.expect);
        let spec: toml::Table = toml::from_str(&c.text).unwrap();
        let dir = tmp.path().join(c.path.file_stem().unwrap());
        std::fs::create_dir(&dir).unwrap();
        let mut copies = Vec::new();
        for c in spec
            .get("copy")
            .and_then(|v| v.as_array())
            .into_iter()
            .flatten()
        {
            copies.push(make_copy(&shards, &dir, c.as_table().unwrap()));
        }
        let locate = |n: &str| {
            let c = dir.join(n);
            if c.exists() {
                c
            } else {
                shards.join(n)
            }
        };
        let dirs: Vec<PathBuf> = spec["merge"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| locate(v.as_str().unwrap()))
            .collect();
        let out = match spec.get("out").and_then(|v| v.as_str()) {
            Some(n) => locate(n),
            None => dir.join("merged"),
        };
        let o = ehservo()
            .arg("merge")
            .args(&dirs)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = rejected(name, &o, expect);
        assert!(
            dirs.iter()
                .chain([&out])
                .any(|d| err.contains(&*d.display().to_string())),
            "{name}: the message names a shard: {err}"
        );
        // Nothing written: no output, no staging directory, shards intact.
        if !dirs.contains(&out) {
            assert!(!out.exists(), "{name}: output written for bad input");
        }
        let mut left: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        left.sort();
        copies.sort();
        assert_eq!(left, copies, "{name}: something was left behind");
        assert_eq!(snapshot(&shards), before, "{name}: a shard was changed");
    }
    let mut top: Vec<String> = std::fs::read_dir(&shards)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    top.sort();
    assert_eq!(
        top,
        ["s0", "s1", "s2", "t2"],
        "no staging left beside shards"
    );
}
