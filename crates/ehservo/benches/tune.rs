//! Issue #14's tuning target: one controller tuned with 2 000 evaluations
//! of the Fig. 2 case in ≤ 5 s on 2 cores. Each iteration is a whole tune
//! (the particle swarm, 40 particles × 50 generations), for the PID and
//! for the NNBVSC, on one and on two threads; criterion takes 10 samples.

use criterion::{criterion_group, criterion_main, Criterion};
use ehservo::tune::{search, Tune};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

fn tune(kind: &str) -> Tune {
    let fig2 = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper/fig2.toml")
        .canonicalize()
        .expect("scenarios/paper/fig2.toml");
    let dir = std::env::temp_dir().join(format!("ehservo-bench-tune-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join(format!("{kind}.toml"));
    std::fs::write(
        &file,
        format!(
            "scenarios = [\"{}\"]\ncontroller = \"{kind}\"\nbudget = 2000\nparticles = 40\nseed = 1\n",
            fig2.display()
        ),
    )
    .expect("tune file");
    Tune::load(&file).expect("tune")
}

fn bench_tune(c: &mut Criterion) {
    let hidden = indicatif::ProgressBar::hidden();
    let mut g = c.benchmark_group("tune");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(20));
    for kind in ["pid", "nnvsc"] {
        let t = tune(kind);
        for threads in [1usize, 2] {
            g.bench_function(
                format!("fig2_{kind}_2000_evaluations_{threads}_thread"),
                |b| {
                    b.iter(|| {
                        let r = search(&t, Some(threads), &hidden).expect("tune");
                        assert_eq!(r.evaluations, 2000);
                        black_box(r.objective)
                    })
                },
            );
        }
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_tune
}
criterion_main!(benches);
