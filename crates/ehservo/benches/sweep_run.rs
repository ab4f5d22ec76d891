//! A Fig. 2 run inside a sweep, timed like the C yardstick
//! (`shared/peers/c/nnvsc.c`, `nnvsc bench N fast R`): R batches of N
//! whole runs, each batch one `ehservo::study::execute` of a study of N
//! Fig. 2 runs on one thread (what `ehservo sweep --threads 1` does, less
//! the file output: every run is expanded from the study, validated, built
//! and simulated, its metrics kept). Prints the wall and CPU time per run
//! of each batch and the best, in the C program's format, so that
//! `bench/fig2-vs-c.sh` reads both the same way. Also a plain loop for
//! `valgrind --tool=callgrind`: the difference of two counts at N and 2N
//! runs, divided by N, is the instructions of one run (set-up cancels).
//!
//! ```text
//! cargo bench -p ehservo --bench sweep_run                  # 5 batches of 2000
//! target/release/deps/sweep_run-HASH 2000 5                 # N R
//! ```

use ehservo::study::{execute, Plan};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

/// A study of `runs` Fig. 2 runs (Monte Carlo over the seed, which the
/// bias-only Fig. 2 case does not use: every run is the paper's Fig. 2).
fn plan(runs: u64) -> Plan {
    let fig2 = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper/fig2.toml")
        .canonicalize()
        .expect("scenarios/paper/fig2.toml");
    let dir = std::env::temp_dir().join(format!("ehservo-bench-sweep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let study = dir.join("fig2-sweep.toml");
    std::fs::write(
        &study,
        format!(
            "name = \"fig2-sweep\"\nbase = \"{}\"\nseed = 1\n[monte_carlo]\nruns = {runs}\n",
            fig2.display()
        ),
    )
    .expect("study file");
    let p = Plan::load(&study).expect("study");
    let _ = std::fs::remove_dir_all(&dir);
    p
}

/// CPU time of the whole process (all threads, the pool's included), s.
#[cfg(unix)]
fn cpu_s() -> f64 {
    use nix::time::{clock_gettime, ClockId};
    let t = clock_gettime(ClockId::CLOCK_PROCESS_CPUTIME_ID).expect("process CPU clock");
    t.tv_sec() as f64 + 1e-9 * t.tv_nsec() as f64
}

/// Without a process CPU clock, the wall clock (on an idle machine, the same).
#[cfg(not(unix))]
fn cpu_s() -> f64 {
    use std::sync::OnceLock;
    static T0: OnceLock<Instant> = OnceLock::new();
    T0.get_or_init(Instant::now).elapsed().as_secs_f64()
}

fn main() {
    // `cargo bench` passes `--bench`; anything starting with `-` is ignored.
    let args: Vec<u64> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .map(|a| a.parse().expect("usage: sweep_run [N runs] [R batches]"))
        .collect();
    let n = args.first().copied().unwrap_or(2000).max(1);
    let reps = args.get(1).copied().unwrap_or(5).max(1);
    let p = plan(n);
    let hidden = indicatif::ProgressBar::hidden();
    let (mut best, mut bestc, mut check) = (f64::INFINITY, f64::INFINITY, 0.0);
    for _ in 0..reps {
        let (t0, c0) = (Instant::now(), cpu_s());
        let rows = execute(black_box(&p), 0..n, Some(1), &hidden).expect("runs");
        let dc = (cpu_s() - c0) / n as f64;
        let dt = t0.elapsed().as_secs_f64() / n as f64;
        for r in &rows {
            let m = r.metrics.as_ref().expect("a valid Fig. 2 run");
            check += m.e_max.unwrap_or(f64::NAN) + m.w_norm_final.unwrap_or(f64::NAN);
        }
        best = best.min(dt);
        bestc = bestc.min(dc);
        println!(
            "bench sweep: {n} runs, {:.3} us per run (wall), {:.3} us (cpu)",
            dt * 1e6,
            dc * 1e6
        );
    }
    println!(
        "best of {reps}: {:.3} us per run wall, {:.3} us cpu ({:.1} ns cpu per sample); checksum {:.12}",
        best * 1e6,
        bestc * 1e6,
        bestc * 1e9 / 1001.0,
        check / (n * reps) as f64
    );
}
