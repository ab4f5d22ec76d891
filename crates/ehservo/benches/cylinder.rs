//! The cost of a cylinder sample against a sample of the paper's
//! third-order plant (issue #35: at most 2×), side by side in one run: the
//! same controller kind (`pid`; each scenario's own gains), the same sample
//! period (1 ms) and RK4 sub-steps (10), one second of the loop (1000
//! samples) with `run_metrics` as a sweep runs it.
//!
//! - `third_order`: `scenarios/paper/fig2.toml`'s plant (8)–(9) under a PID;
//! - `physical`: the same servo as the physical model (1)–(6);
//! - `cylinder`: `scenarios/cylinders/chrono-single-rod.toml` (single rod,
//!   4/3 valve with laminar regions, fixed supply, end stops, gravity; a
//!   P law);
//! - `hopsan_pump`: `scenarios/hopsan/position-servo.toml` (double rod,
//!   overlapped valve with a second-order spool, a pump with its relief
//!   valve and line volume: the stiffest state, which the plant's own step
//!   splitting refines; a PI), its step moved to 0.2 s so that the second
//!   holds it.
//!
//! ```text
//! cargo bench -p ehservo --bench cylinder
//! ```

use criterion::{criterion_group, criterion_main, Criterion};
use ehservo::run::run_metrics;
use ehservo::scenario::Loop;
use std::path::Path;
use std::time::Duration;

fn scenario(rel: &str, set: &[&str]) -> Loop {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel);
    let mut all: Vec<String> = [
        "simulation.horizon=1.0",
        "simulation.settle=0.5",
        "simulation.step=0.001",
        "simulation.substeps=10",
        "simulation.mode=\"sampled\"",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    all.extend(set.iter().map(|s| s.to_string()));
    Loop::load(&p, &all).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn bench_cylinder(c: &mut Criterion) {
    let pid = [
        "controller.kind=\"pid\"",
        "controller.kp=26.2",
        "controller.ki=310.0",
        "controller.kd=0.0375",
    ];
    let cases = [
        ("third_order", scenario("scenarios/paper/fig2.toml", &pid)),
        (
            "physical",
            scenario(
                "scenarios/paper/fig2.toml",
                &[&pid[..], &["plant.model=\"physical\""]].concat(),
            ),
        ),
        (
            "cylinder",
            scenario("scenarios/cylinders/chrono-single-rod.toml", &[]),
        ),
        (
            "hopsan_pump",
            scenario(
                "scenarios/hopsan/position-servo.toml",
                &["reference.start=0.2"],
            ),
        ),
    ];
    let mut g = c.benchmark_group("per_1000_samples");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for (name, setup) in &cases {
        // Each run is whole (bounded over its 1000 steps): a diverged run
        // would measure fewer samples.
        let (outcome, m) = run_metrics(setup, &mut |_| {});
        assert!(outcome.diverged.is_none(), "{name} diverged");
        assert_eq!(m.samples, 1001, "{name}");
        g.bench_function(*name, |b| b.iter(|| run_metrics(setup, &mut |_| {})));
    }
    g.finish();
}

// No plots: criterion's plotters backend needs system fonts.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_cylinder
}
criterion_main!(benches);
