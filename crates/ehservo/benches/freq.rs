//! Issue 36's target: a 40-frequency sinestream of the Fig. 2 closed loop
//! (the paper's NNBVSC, `scenarios/paper/fig2.toml`) in at most 2 s on 2
//! cores. `ehservo freq`'s default measurement: 40 log-spaced frequencies
//! from 0.1 Hz to 0.9 of Nyquist (45 Hz), each run settling 2 s (or two
//! periods) and measuring at least four periods; the tracking input alone,
//! and both inputs (tracking and disturbance, 80 runs) as `ehservo freq`
//! runs them, on one and on two threads.

use criterion::{criterion_group, criterion_main, Criterion};
use ehservo::freq::measure::{sinestream, Input};
use ehservo::freq::report::FreqOptions;
use ehservo::scenario::Loop;
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

fn bench_sinestream(c: &mut Criterion) {
    let fig2 = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper/fig2.toml");
    let setup = Loop::load(&fig2, &[]).expect("scenarios/paper/fig2.toml");
    let o = FreqOptions::defaults();
    let (lo, hi, n) = (
        o.measure_f_min,
        0.9 * 0.5 / setup.sim().step,
        o.measure_points,
    );
    let freqs: Vec<f64> = (0..n)
        .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
        .collect();
    let s = o.settings;
    let mut g = c.benchmark_group("freq");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(20));
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        g.bench_function(
            format!("sinestream_fig2_40_tracking_{threads}_thread"),
            |b| {
                b.iter(|| {
                    pool.install(|| black_box(sinestream(&setup, Input::Tracking, &freqs, &s)))
                })
            },
        );
        g.bench_function(format!("sinestream_fig2_40_both_{threads}_thread"), |b| {
            b.iter(|| {
                pool.install(|| {
                    black_box(rayon::join(
                        || sinestream(&setup, Input::Tracking, &freqs, &s),
                        || sinestream(&setup, Input::Disturbance, &freqs, &s),
                    ))
                })
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_sinestream
}
criterion_main!(benches);
