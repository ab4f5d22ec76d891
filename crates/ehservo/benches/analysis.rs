//! The theory analysis of the paper's Fig. 2 case alone (what `ehservo run`
//! writes into summary.json's `analysis` and `ehservo analyze` prints),
//! without the simulation:
//!
//! - `analyze`: the whole of `analysis::analyze` (plant, poles, K1 and
//!   Theorem 2, Remark 6's weights, the σ-loop);
//! - `k1`: K1 alone, with exp(Pt) in closed form (what `analyze` uses);
//! - `k1_expm`: K1 by the reference path (nalgebra's exp and the SVD on the
//!   same grids), what `analyze` used before and falls back to for poles
//!   too close for the closed form.
//!
//! ```text
//! cargo bench -p ehservo --bench analysis
//! ```

use criterion::{criterion_group, criterion_main, Criterion};
use ehservo::analysis::{analyze, cubic_roots, k1, k1_expm, p_matrix};
use ehservo::scenario::Loop;
use std::hint::black_box;
use std::time::Duration;

fn bench_analysis(c: &mut Criterion) {
    let s = Loop::parse("").expect("the default scenario is Fig. 2");
    let a = analyze(&s);
    // Sanity: the paper's K1 and the two paths agree.
    let k = a.surface.k1.value.expect("finite K1");
    assert!((k - 2407.09142587584).abs() < 1e-8 * k, "{k}");
    let p = [90.0, 2600.0, 24000.0];
    let (pm, poles) = (p_matrix(p), cubic_roots(p[0], p[1], p[2]));
    let k2 = -poles[0].re;
    let reference = k1_expm(&pm, &poles, k2).value.expect("finite K1");
    assert!((k - reference).abs() < 1e-12 * k, "{k} vs {reference}");

    let mut g = c.benchmark_group("analysis_fig2");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    g.bench_function("analyze", |b| b.iter(|| analyze(black_box(&s))));
    g.bench_function("k1", |b| {
        b.iter(|| k1(black_box(&pm), black_box(&poles), black_box(k2)))
    });
    g.sample_size(10);
    g.bench_function("k1_expm", |b| {
        b.iter(|| k1_expm(black_box(&pm), black_box(&poles), black_box(k2)))
    });
    g.finish();
}

// No plots: criterion's plotters backend needs system fonts, which CI
// machines may not have; the numbers are printed and kept in target/criterion.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_analysis
}
criterion_main!(benches);
