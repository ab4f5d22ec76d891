//! A repeatable figure for one control step: a plain loop of `n` steps, to
//! run under `valgrind --tool=callgrind` (or `--tool=lackey`) twice with
//! different `n`; the difference of the instruction counts divided by the
//! difference of `n` is the instructions of one step, independent of the
//! machine's load (BENCHMARKS.md gives the command). Under `cargo bench` it
//! runs each step a million times and prints a rough time per step.
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

/// Runs `n` steps of `kind`; returns a checksum so nothing is elided.
fn run(kind: &str, n: u64) -> f64 {
    let f = common::fig2();
    let r = record();
    let (m, s) = (r.fixed, r.state);
    let mut acc = 0.0;
    match kind {
        "nnvsc_law" => {
            let mut ds = NnState::zero();
            for _ in 0..n {
                let o = f.nn.law(black_box(&m), black_box(&s), black_box(&mut ds));
                acc += black_box(o).u;
            }
        }
        "nnvsc_step" => {
            let mut ctl = SampledController::new(f.nn, H).expect("dt > 0");
            let rec = &r.measurements;
            let mut k = 0;
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
        }
        "vsc_law" => {
            let (s1, mut ds1) = ([s.int_e], [0.0]);
            for _ in 0..n {
                let o = f
                    .vsc
                    .law(black_box(&m), black_box(&s1), black_box(&mut ds1));
                acc += black_box(o).u;
            }
        }
        "rbf_phi" => {
            let rbf = *f.nn.rbf();
            let mut phi = [0.0; N_PHI];
            for _ in 0..n {
                acc += rbf.phi(black_box(&m.x), black_box(&m.z), black_box(&mut phi));
            }
        }
        other => panic!("unknown kind {other:?}; one of {KINDS:?}"),
    }
    acc
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
            let acc = run(&k, n);
            println!("{k}: {n} steps, checksum {acc:e}");
        }
        _ => {
            for k in KINDS {
                let t0 = Instant::now();
                let acc = run(k, n);
                let dt = t0.elapsed().as_secs_f64();
                println!(
                    "{k:>10}: {n} steps in {dt:.3} s ≈ {:.1} ns/step (incl. set-up; checksum {acc:e})",
                    dt / n as f64 * 1e9
                );
            }
        }
    }
}
