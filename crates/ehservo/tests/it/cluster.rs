//! The cluster path's recovery (docs/cluster.md) without a cluster: a
//! sweep killed by SIGTERM leaves nothing, `merge` names the missing shard
//! and the flag to rerun it, `merge --missing` lists the indices to
//! resubmit (a damaged shard counting as missing), and `sweep --resume`
//! skips a shard that is already whole and redoes one that is not. The
//! same on a real Slurm: ci/slurm.sh.

use crate::common::ehservo;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn fig8() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper/fig8.toml")
        .canonicalize()
        .unwrap()
        .display()
        .to_string()
}

/// A 6-run Monte Carlo of the Fig. 8 case over 1 s (2 runs per shard of 3).
fn study(dir: &Path) -> PathBuf {
    let p = dir.join("study.toml");
    std::fs::write(
        &p,
        format!(
            "name = \"c\"\nbase = \"{}\"\nseed = 3\nset = [\"simulation.horizon=1\", \"simulation.settle=0.5\"]\n[monte_carlo]\nruns = 6\n",
            fig8()
        ),
    )
    .unwrap();
    p
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn sweep(study: &Path, out: &Path, extra: &[&str]) -> Output {
    ehservo()
        .arg("sweep")
        .arg(study)
        .arg("--out")
        .arg(out)
        .args(["--quiet", "--no-plot"])
        .args(extra)
        .output()
        .unwrap()
}

fn ok(o: &Output) {
    assert_eq!(o.status.code(), Some(0), "{}", stderr(o));
}

fn merge(args: &[&Path], extra: &[&str]) -> Output {
    ehservo()
        .arg("merge")
        .args(args)
        .args(extra)
        .output()
        .unwrap()
}

/// Three shards of the study in `dir/shards/{0,1,2}`.
fn shards(dir: &Path) -> (PathBuf, Vec<PathBuf>) {
    let s = study(dir);
    let d: Vec<PathBuf> = (0..3).map(|k| dir.join(format!("shards/{k}"))).collect();
    for (k, out) in d.iter().enumerate() {
        ok(&sweep(&s, out, &["--shard", &format!("{k}/3")]));
    }
    (s, d)
}

/// (inode, modification time) of a file: the same after a skipped rerun.
fn stamp(p: &Path) -> (u64, std::time::SystemTime) {
    use std::os::unix::fs::MetadataExt;
    let m = std::fs::metadata(p).unwrap();
    (m.ino(), m.modified().unwrap())
}

#[test]
fn merge_names_the_missing_shard_and_the_flag_to_rerun_it() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, d) = shards(tmp.path());
    let out = tmp.path().join("merged");
    // 6 runs in 3 shards: shard 1/3 holds runs 2..4.
    let o = merge(&[&d[0], &d[2]], &["--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.contains("shard 1/3 (runs 2..4) is missing (before")
            && err.contains("rerun it with --shard 1/3"),
        "{err}"
    );
    assert!(err.contains(&*d[2].display().to_string()), "{err}");
    // Two missing at the end: both named.
    let o = merge(&[&d[0]], &["--out", out.to_str().unwrap()]);
    let err = stderr(&o);
    assert!(
        err.contains("shards K/3 for K in 1,2 (runs 2..6) are missing (after")
            && err.contains("rerun each with --shard K/3"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn merge_missing_lists_absent_and_damaged_shards() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, d) = shards(tmp.path());
    // All there: nothing on stdout, exit 0.
    let o = merge(&[&d[0], &d[1], &d[2]], &["--missing"]);
    ok(&o);
    assert_eq!(String::from_utf8_lossy(&o.stdout), "");
    assert!(
        stderr(&o).contains("0 of 3 shard(s) missing"),
        "{}",
        stderr(&o)
    );

    let o = merge(&[&d[0], &d[2]], &["--missing"]);
    ok(&o);
    assert_eq!(String::from_utf8_lossy(&o.stdout), "1\n");
    let o = merge(&[&d[1]], &["--missing"]);
    assert_eq!(String::from_utf8_lossy(&o.stdout), "0,2\n");

    // Shard 2's results.csv loses its last row: set aside, listed.
    let csv = d[2].join("results.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    let cut: Vec<&str> = text.lines().collect();
    std::fs::write(&csv, cut[..cut.len() - 1].join("\n") + "\n").unwrap();
    let o = merge(&[&d[0], &d[1], &d[2]], &["--missing"]);
    ok(&o);
    assert_eq!(String::from_utf8_lossy(&o.stdout), "2\n");
    let err = stderr(&o);
    assert!(
        err.contains(&*d[2].display().to_string())
            && err.contains("counted as missing")
            && err.contains("1 of the 2 rows"),
        "{err}"
    );

    // Nothing whole: N cannot be known.
    let o = merge(&[&d[2]], &["--missing"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("none of the 1 folder(s) given is a whole shard"));
    // --missing writes nothing, so it takes no --out.
    let o = merge(&[&d[0]], &["--missing", "--out", "x"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!Path::new("x").exists());
    // And merge without --out nor --missing is a usage error.
    let o = merge(&[&d[0]], &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--out"), "{}", stderr(&o));
}

#[test]
fn resume_skips_a_whole_shard_and_redoes_a_damaged_one() {
    let tmp = tempfile::tempdir().unwrap();
    let (s, d) = shards(tmp.path());
    let csv = d[1].join("results.csv");
    let bytes = std::fs::read(&csv).unwrap();
    let before = stamp(&csv);

    // Whole: skipped, said so, not rewritten.
    let o = sweep(&s, &d[1], &["--shard", "1/3", "--resume"]);
    ok(&o);
    assert!(
        stderr(&o).contains("c shard 1/3: already complete in"),
        "{}",
        stderr(&o)
    );
    assert_eq!(stamp(&csv), before);

    // Truncated: run again, said why, the same bytes as before.
    std::fs::write(&csv, &bytes[..bytes.len() - 10]).unwrap();
    let o = sweep(&s, &d[1], &["--shard", "1/3", "--resume"]);
    ok(&o);
    let err = stderr(&o);
    assert!(
        err.contains("--resume: running again") && err.contains("truncated"),
        "{err}"
    );
    assert_eq!(std::fs::read(&csv).unwrap(), bytes);

    // Another shard's output in the folder: replaced by this one.
    let o = sweep(&s, &d[1], &["--shard", "2/3", "--resume"]);
    ok(&o);
    assert!(
        stderr(&o).contains("is not this sweep's study.json"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read(d[1].join("results.csv")).unwrap(),
        std::fs::read(d[2].join("results.csv")).unwrap()
    );

    // Nothing there: an ordinary sweep.
    let fresh = tmp.path().join("fresh");
    let o = sweep(&s, &fresh, &["--shard", "1/3", "--resume"]);
    ok(&o);
    assert_eq!(stderr(&o), "");
    assert_eq!(std::fs::read(fresh.join("results.csv")).unwrap(), bytes);
}

#[test]
fn sigterm_in_mid_sweep_leaves_no_output_and_no_staging_folder() {
    let tmp = tempfile::tempdir().unwrap();
    // Three whole shards beside it, which the signal must leave alone.
    shards(tmp.path());
    // A shard that cannot end on its own within the test: 1000 runs of 20 s
    // at 0.1 ms on one thread (a machine's speed must not decide whether
    // the signal comes mid-sweep; a fixed sleep once did).
    let long = tmp.path().join("long.toml");
    std::fs::write(
        &long,
        format!(
            "name = \"c\"\nbase = \"{}\"\nseed = 3\nset = [\"simulation.horizon=20\", \"simulation.step=0.0001\"]\n[monte_carlo]\nruns = 3000\n",
            fig8()
        ),
    )
    .unwrap();
    let shards_dir = tmp.path().join("shards");
    let out = shards_dir.join("long");
    let mut child = ehservo()
        .arg("sweep")
        .arg(&long)
        .arg("--out")
        .arg(&out)
        .args(["--quiet", "--shard", "1/3", "--threads", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // The signal handler is installed first thing in main; half a second
    // in, the shard is running its first runs (its outputs are staged only
    // once they are all done, so nothing may be on disk yet).
    let entries = || -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(&shards_dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    std::thread::sleep(Duration::from_millis(500));
    assert!(
        child.try_wait().unwrap().is_none(),
        "the shard ended before the signal"
    );
    let start = Instant::now();
    let k = Command::new("kill")
        .arg("-TERM")
        .arg(child.id().to_string())
        .status()
        .unwrap();
    assert!(k.success());
    // Wait at most 10 s for it to stop; past that, kill it and fail.
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the shard was still running 10 s after SIGTERM");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(status.code(), Some(130));
    // No output, no staging folder beside the shards.
    assert_eq!(entries(), ["0", "1", "2"]);
}
