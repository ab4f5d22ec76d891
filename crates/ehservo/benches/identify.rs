//! Issue #37's target: a grey-box fit of six parameters to 20 s of 1 kHz
//! data in ≤ 5 s on 2 cores. The data: `ehservo excite`'s default
//! multisine (0.05 V, 0.5–40 Hz) on the paper's servo with its load
//! 2·sin 4θ, the physical plant, a 16-bit encoder and 10⁻⁵ rad of noise,
//! run as `ehservo run` does. Each iteration is a whole `identify` (both
//! nonparametric estimates, the linear fit, the grey-box fit of
//! beta_e, Kce, Jt, Bm, Kv, G with the identifiability test, the residual
//! tests; nothing written), on one and on two threads (rayon's pool, as
//! `--threads` would set it). The grey-box fit is most of the time.

use criterion::{criterion_group, criterion_main, Criterion};
use ehservo::identify::excite::{excite_to_dir, Loop, Phases, Signal, Spec};
use ehservo::identify::{identify, Options};
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

fn data() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ehservo-bench-identify-{}", std::process::id()));
    let spec = Spec {
        signal: Signal::Multisine,
        loop_kind: Loop::Open,
        amplitude: 0.05,
        f0: 0.5,
        f1: 40.0,
        duration: 20.0,
        rate: 1000.0,
        period: 4096,
        phases: Phases::Crest,
        order: 10,
        clock: 5,
        hold: 0.5,
        seed: 1,
        kp: None,
    };
    let set: Vec<String> = [
        "plant.model=physical",
        "sensor.resolution=[9.587379924285257e-5,0,0]",
        "sensor.noise=[1e-5,0,0]",
        "sensor.seed=1",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let ex = dir.join("excite");
    excite_to_dir(&spec, None, &set, &ex).expect("excite");
    let s = ehservo::scenario::Loop::load(&ex.join("scenario.toml"), &[]).expect("scenario");
    let run = dir.join("run");
    ehservo::output::run_to_dir(&run, &s, false).expect("run");
    run.join("trace.csv")
}

fn bench_identify(c: &mut Criterion) {
    let trace = data();
    let opts = Options {
        files: vec![trace],
        lags: 25,
        map: ehservo::identify::data::ColumnMap {
            pressure: Some("none".into()),
            ..Default::default()
        },
        ..Default::default()
    };
    // What the fit finds, once: six free, how many identifiable.
    let o = identify(&opts).expect("identify");
    let g = o.greybox.as_ref().expect("grey-box");
    eprintln!(
        "grey-box: free {:?}, {} evaluations, termination {}",
        g.fit.free_keys, g.fit.evaluations, g.fit.termination
    );
    let mut grp = c.benchmark_group("identify");
    grp.sample_size(10);
    grp.measurement_time(Duration::from_secs(30));
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        grp.bench_function(format!("greybox_6_params_20s_1kHz_{threads}_thread"), |b| {
            b.iter(|| {
                pool.install(|| {
                    black_box(identify(&opts).expect("identify").linear.fit.residual_sd)
                })
            })
        });
    }
    grp.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_identify
}
criterion_main!(benches);
