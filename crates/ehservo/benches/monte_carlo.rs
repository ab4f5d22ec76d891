//! The Monte Carlo target of issue 5: 10 000 runs of the Fig. 8 case (10 s,
//! sampled at 0.01 s, each with its own random parameter signal), on one
//! and on two threads. Each iteration is a whole study, so criterion takes
//! its minimum of 10 samples.

use criterion::{criterion_group, criterion_main, Criterion};
use ehservo::study::{execute, Plan};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

fn plan(runs: u32) -> Plan {
    let fig8 = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper/fig8.toml")
        .canonicalize()
        .expect("scenarios/paper/fig8.toml");
    let dir = std::env::temp_dir().join(format!("ehservo-bench-mc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let study = dir.join("mc.toml");
    std::fs::write(
        &study,
        format!(
            "name = \"fig8-mc\"\nbase = \"{}\"\nseed = 2024\n[monte_carlo]\nruns = {runs}\n",
            fig8.display()
        ),
    )
    .expect("study file");
    Plan::load(&study).expect("study")
}

fn bench_mc(c: &mut Criterion) {
    let p = plan(10_000);
    let hidden = indicatif::ProgressBar::hidden();
    let mut g = c.benchmark_group("monte_carlo");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(60));
    for threads in [1usize, 2] {
        g.bench_function(format!("fig8_10000_runs_{threads}_thread"), |b| {
            b.iter(|| {
                let rows = execute(&p, 0..p.runs, Some(threads), &hidden).expect("runs");
                black_box(rows.len())
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_mc
}
criterion_main!(benches);
