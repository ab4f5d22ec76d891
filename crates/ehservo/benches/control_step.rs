//! One control step, measured: the NNBVSC law (Theorem 3, 125 kernels and
//! 130 weights), the same law inside the hardware loop
//! (`SampledController::step`), the traditional VSC of Theorem 1 for
//! comparison, the RBF vector Φ alone, and the cost of one `exp` (libm's and
//! std's) — the unit of the step's physical limit (BENCHMARKS.md).
//!
//! Every input is realistic: the Fig. 2 closed loop (sampled at 0.01 s, one
//! RK4 sub-step, the scenario defaults) is run once with
//! `SampledController` to record its 1001 measurements, and the controller
//! state at t = 5 s (weights trained) is taken as the fixed point of the
//! single-law benches. The sampled-step benches replay the recorded
//! measurements in order, so they compute exactly the Fig. 2 control
//! sequence (reset at the wrap).
//!
//! ```text
//! cargo bench -p ehservo --bench control_step
//! ```

mod common;

use common::{record, H};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ehservo_core::prelude::*;
use std::hint::black_box;
use std::time::Duration;

fn bench_control(c: &mut Criterion) {
    let f = common::fig2();
    let r = record();
    let (rec, m, s) = (r.measurements, r.fixed, r.state);

    let mut g = c.benchmark_group("control_step");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));

    // The NNBVSC law alone: Φ, WᵀΦ, σΔ, μ, u and Ẇ at one measurement.
    let nn = f.nn;
    let mut ds = NnState::zero();
    g.bench_function("nnvsc_law", |b| {
        b.iter(|| {
            black_box(nn.law(black_box(&m), black_box(&s), black_box(&mut ds)));
        })
    });

    // The hardware loop: checks, law, Euler on (∫e, W), clamp; the recorded
    // Fig. 2 measurements replayed in order.
    let mut ctl = SampledController::new(nn, H).expect("dt > 0");
    let mut k = 0;
    g.bench_function("nnvsc_sampled_step", |b| {
        b.iter(|| {
            let mm = &rec[k];
            let o = ctl.step(black_box(mm.t), black_box(mm.x), black_box(mm.z));
            k += 1;
            if k == rec.len() {
                k = 0;
                ctl.reset();
            }
            black_box(o)
        })
    });

    // The traditional VSC of Theorem 1 at the same measurement.
    let vsc = f.vsc;
    let s1 = [s.int_e];
    let mut ds1 = [0.0];
    g.bench_function("vsc_law", |b| {
        b.iter(|| {
            black_box(vsc.law(black_box(&m), black_box(&s1), black_box(&mut ds1)));
        })
    });
    let mut vctl = SampledController::new(vsc, H).expect("dt > 0");
    let mut k = 0;
    g.bench_function("vsc_sampled_step", |b| {
        b.iter(|| {
            let mm = &rec[k];
            let o = vctl.step(black_box(mm.t), black_box(mm.x), black_box(mm.z));
            k += 1;
            if k == rec.len() {
                k = 0;
                vctl.reset();
            }
            black_box(o)
        })
    });

    // Φ alone (15 exp, 125 products, ‖Φ‖).
    let rbf = *nn.rbf();
    let mut phi = [0.0; N_PHI];
    g.bench_function("rbf_phi", |b| {
        b.iter(|| black_box(rbf.phi(black_box(&m.x), black_box(&m.z), black_box(&mut phi))))
    });
    g.finish();
}

/// The 15 exponent arguments the law evaluates at the t = 5 s measurement:
/// −(x̃_k − L_i)²/δ² for the three axes and five levels.
fn exp_arguments() -> [f64; 15] {
    let m = record().fixed;
    let rbf = Rbf::paper();
    let s = Rbf::paper_scale();
    let levels = rbf.levels();
    let w2 = rbf.width() * rbf.width();
    let mut a = [0.0; 15];
    for k in 0..3 {
        for i in 0..5 {
            let d = m.x[k] / s[k] - levels[i];
            a[5 * k + i] = -d * d / w2;
        }
    }
    a
}

fn bench_exp(c: &mut Criterion) {
    let args = exp_arguments();
    let mut g = c.benchmark_group("exp");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(15));
    // 15 independent exponentials, as in Φ: throughput, not latency.
    g.bench_function("libm_x15", |b| {
        b.iter(|| {
            let a = black_box(&args);
            let mut out = [0.0; 15];
            for (o, v) in out.iter_mut().zip(a.iter()) {
                *o = libm::exp(*v);
            }
            black_box(out)
        })
    });
    g.bench_function("std_x15", |b| {
        b.iter(|| {
            let a = black_box(&args);
            let mut out = [0.0; 15];
            for (o, v) in out.iter_mut().zip(a.iter()) {
                *o = v.exp();
            }
            black_box(out)
        })
    });
    // 15 dependent exponentials (each argument is the previous result):
    // the latency of one call, what a serial chain pays.
    let x0 = args[7];
    g.bench_function("libm_chain15", |b| {
        b.iter(|| {
            let mut x = black_box(x0);
            for _ in 0..15 {
                x = libm::exp(-x);
            }
            black_box(x)
        })
    });
    g.bench_function("std_chain15", |b| {
        b.iter(|| {
            let mut x = black_box(x0);
            for _ in 0..15 {
                x = (-x).exp();
            }
            black_box(x)
        })
    });
    g.bench_function("core_math_exp_x15", |b| {
        b.iter(|| {
            let a = black_box(&args);
            let mut out = [0.0; 15];
            for (o, v) in out.iter_mut().zip(a.iter()) {
                *o = ehservo_core::math::exp(*v);
            }
            black_box(out)
        })
    });
    g.finish();
}

// No plots: criterion's plotters backend needs system fonts, which CI
// machines may not have; the numbers are printed and kept in target/criterion.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_control, bench_exp
}
criterion_main!(benches);
