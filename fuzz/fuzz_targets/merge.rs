//! Two shards' outputs, one of them mangled by the fuzzer (its study.json
//! or its results.csv), merged: never a panic; either refused or merged
//! into exactly the runs promised.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

/// Real shards 0/2 and 1/2 of a tiny study, made once.
fn shards() -> &'static (PathBuf, PathBuf, PathBuf) {
    static S: OnceLock<(PathBuf, PathBuf, PathBuf)> = OnceLock::new();
    S.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("ehservo-fuzz-merge-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let base = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/paper/fig2.toml");
        let study = dir.join("s.toml");
        std::fs::write(
            &study,
            format!(
                "name = \"fz\"\nbase = {base:?}\nseed = 3\nset = [\"simulation.horizon=0.2\", \"simulation.settle=0.1\"]\n\
                 [[axis]]\nkey = \"controller.gamma1\"\nvalues = [50.0, 100.0, 150.0, 200.0]\n"
            ),
        )
        .unwrap();
        let plan = ehservo::study::Plan::load(&study).unwrap();
        let mut out = Vec::new();
        for k in 0..2 {
            let d = dir.join(format!("shard{k}"));
            let opts = ehservo::study::SweepOptions {
                out: d.clone(),
                shard: Some((k, 2)),
                threads: Some(1),
                progress: false,
                plots: false,
            };
            ehservo::study::sweep(&plan, &opts).unwrap();
            out.push(d);
        }
        (dir, out[0].clone(), out[1].clone())
    })
}

/// Retries a file operation that libFuzzer's SIGALRM (its -timeout timer)
/// interrupted with EINTR: the harness's own set-up, not the code under test.
fn retry<T>(mut f: impl FnMut() -> std::io::Result<T>) -> T {
    loop {
        match f() {
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            r => return r.unwrap(),
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let (dir, a, b) = shards();
    if data.is_empty() {
        return;
    }
    let m = dir.join(format!("mangled-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&m);
    retry(|| std::fs::create_dir_all(&m));
    for f in ["study.json", "results.csv"] {
        retry(|| std::fs::copy(b.join(f), m.join(f)));
    }
    // The first byte picks the file; the rest replaces it.
    let target = if data[0] % 2 == 0 { "study.json" } else { "results.csv" };
    retry(|| std::fs::write(m.join(target), &data[1..]));
    let out = dir.join("merged");
    let _ = std::fs::remove_dir_all(&out);
    if let Ok(n) = ehservo::study::merge(&[a.clone(), m.clone()], &out) {
        let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
        assert_eq!(text.lines().count() as u64, n + 1, "rows = runs + header");
        assert!(!text.to_lowercase().contains("nan"));
    }
});
