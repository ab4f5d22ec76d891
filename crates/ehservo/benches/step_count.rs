//! A repeatable figure for one control step: a plain loop of `n` steps, to
//! run under `valgrind --tool=callgrind` (or `--tool=lackey`) twice with
//! different `n`; the difference of the instruction counts divided by the
//! difference of `n` is the instructions of one step, independent of the
//! machine's load (BENCHMARKS.md gives the command). Under `cargo bench` it
//! runs each step a million times and prints a rough time per step, and the
//! fastest of 300 batches of 2000 steps: on a shared, loaded machine the
//! batches that ran undisturbed, a steadier figure than a mean.
//!
//! ```text
//! cargo bench -p ehservo --bench step_count                      # all, timed
//! target/release/deps/step_count-HASH nnvsc_law 100000          # one, n steps
//! ```
//!
//! Kinds: `nnvsc_law` (the law at the Fig. 2 state at t = 5 s),
//! `nnvsc_step` (`SampledController::step` replaying the Fig. 2
//! measurements), `vsc_law`, `rbf_phi`.

mod common;

use common::{record, H};
use ehservo_core::prelude::*;
use std::hint::black_box;
use std::time::Instant;

const KINDS: [&str; 4] = ["nnvsc_law", "nnvsc_step", "vsc_law", "rbf_phi"];

/// The steps of one kind, set up once: `run(n)` runs `n` steps and returns
/// a checksum so nothing is elided.
fn stepper(kind: &str) -> Box<dyn FnMut(u64) -> f64> {
    let f = common::fig2();
    let r = record();
    let (m, s) = (r.fixed, r.state);
    match kind {
        "nnvsc_law" => {
            let nn = f.nn;
            let mut ds = NnState::zero();
            Box::new(move |n| {
                let mut acc = 0.0;
                for _ in 0..n {
                    let o = nn.law(black_box(&m), black_box(&s), black_box(&mut ds));
                    acc += black_box(o).u;
                }
                acc
            })
        }
        "nnvsc_step" => {
            let mut ctl = SampledController::new(f.nn, H).expect("dt > 0");
            let rec = r.measurements;
            let mut k = 0;
            Box::new(move |n| {
                let mut acc = 0.0;
                for _ in 0..n {
                    let mm = &rec[k];
                    let o = ctl.step(black_box(mm.t), black_box(mm.x), black_box(mm.z));
                    acc += black_box(o).u;
                    k += 1;
                    if k == rec.len() {
                        k = 0;
                        ctl.reset();
                    }
                }
                acc
            })
        }
        "vsc_law" => {
            let vsc = f.vsc;
            let (s1, mut ds1) = ([s.int_e], [0.0]);
            Box::new(move |n| {
                let mut acc = 0.0;
                for _ in 0..n {
                    let o = vsc.law(black_box(&m), black_box(&s1), black_box(&mut ds1));
                    acc += black_box(o).u;
                }
                acc
            })
        }
        "rbf_phi" => {
            let rbf = *f.nn.rbf();
            let mut phi = [0.0; N_PHI];
            Box::new(move |n| {
                let mut acc = 0.0;
                for _ in 0..n {
                    acc += rbf.phi(black_box(&m.x), black_box(&m.z), black_box(&mut phi));
                }
                acc
            })
        }
        other => panic!("unknown kind {other:?}; one of {KINDS:?}"),
    }
}

fn main() {
    // `cargo bench` passes `--bench`; anything starting with `-` is ignored.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let kind = args.first().cloned();
    let n: u64 = args
        .get(1)
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    match kind {
        Some(k) if KINDS.contains(&k.as_str()) => {
            let acc = stepper(&k)(n);
            println!("{k}: {n} steps, checksum {acc:e}");
        }
        _ => {
            const BATCHES: u32 = 300;
            const BATCH: u64 = 2000;
            for k in KINDS {
                let mut run = stepper(k);
                let t0 = Instant::now();
                let acc = run(n);
                let dt = t0.elapsed().as_secs_f64();
                let mut best = f64::INFINITY;
                for _ in 0..BATCHES {
                    let t0 = Instant::now();
                    black_box(run(BATCH));
                    best = best.min(t0.elapsed().as_secs_f64());
                }
                println!(
                    "{k:>10}: {n} steps in {dt:.3} s ≈ {:.1} ns/step; fastest of {BATCHES} batches of {BATCH}: {:.1} ns/step (checksum {acc:e})",
                    dt / n as f64 * 1e9,
                    best / BATCH as f64 * 1e9
                );
            }
        }
    }
}
