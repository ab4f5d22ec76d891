//! Issue #14's tuning target: one controller tuned with 2 000 evaluations
//! of the Fig. 2 case in ≤ 5 s on 2 cores. Each iteration is a whole tune
//! (the particle swarm, 40 particles × 50 generations), for the PID and
//! for the NNBVSC, on one and on two threads; criterion takes 10 samples.
//! Issue #45's target beside it: the PID's tune with `[reject]`'s margin
//! minima (the default: every acceptable candidate's loop linearised and
//! its margins computed) costs at most 1.5× the same tune without them
//! (`pid_no_margins`: gain_margin_dB = phase_margin_deg = 0).

use criterion::{criterion_group, criterion_main, Criterion};
use ehservo::tune::{search, Tune};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

fn tune(kind: &str, extra: &str) -> Tune {
    let fig2 = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper/fig2.toml")
        .canonicalize()
        .expect("scenarios/paper/fig2.toml");
    let dir = std::env::temp_dir().join(format!("ehservo-bench-tune-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join(format!("{kind}{}.toml", extra.len()));
    std::fs::write(
        &file,
        format!(
            "scenarios = [\"{}\"]\ncontroller = \"{kind}\"\nbudget = 2000\nparticles = 40\nseed = 1\n{extra}",
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
    let no_margins = "[reject]\ngain_margin_dB = 0.0\nphase_margin_deg = 0.0\n";
    for (name, kind, extra) in [
        ("pid", "pid", ""),
        ("pid_no_margins", "pid", no_margins),
        ("nnvsc", "nnvsc", ""),
    ] {
        let t = tune(kind, extra);
        for threads in [1usize, 2] {
            g.bench_function(
                format!("fig2_{name}_2000_evaluations_{threads}_thread"),
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
