//! Stopping long work from outside: what an interpreter's Ctrl-C needs.
//!
//! The command line needs none of this (a signal ends the process and
//! `ehservo::interrupt` removes what it was writing). A host that stays
//! alive — the Python package, whose `KeyboardInterrupt` must arrive while
//! `ehservo.run`, `sweep`, `tune` or `league` is computing — calls
//! [`request`]: every run in progress then stops at its next chunk of
//! samples (at most about [`CHUNK_WORK`] evaluations, milliseconds), the
//! sweeps, tunes and leagues start no new run, their entry points return
//! [`Cancelled`], and no output is committed (`ehservo::output::Staging`
//! refuses): an interrupted call leaves nothing behind.
//!
//! The request holds while any [`Scope`] is alive and is cleared when the
//! last one ends, so a call that began before the request always sees it
//! (and none of its truncated runs can pass for a result).

use crate::scenario::Loop;
use crate::simulation::{Outcome, Sample, Simulation};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

static REQUESTED: AtomicBool = AtomicBool::new(false);
static ACTIVE: Mutex<usize> = Mutex::new(0);

/// Evaluations between two looks at the request inside a run: 2¹⁶, about
/// 20 ms at 0.3 µs an evaluation.
pub const CHUNK_WORK: u64 = 1 << 16;

/// The error of work stopped by [`request`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cancelled;

impl std::fmt::Display for Cancelled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("interrupted: the work was stopped and nothing was written")
    }
}

impl std::error::Error for Cancelled {}

/// Whether work in progress is asked to stop.
#[inline]
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}

/// Asks every computation in progress (inside a [`Scope`]) to stop.
pub fn request() {
    REQUESTED.store(true, Ordering::Relaxed);
}

/// Whether an error is, or was caused by, a cancellation.
pub fn is_cancelled(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.is::<Cancelled>())
}

/// A computation that a [`request`] may stop; the request is cleared when
/// the last scope ends.
#[derive(Debug)]
pub struct Scope(());

impl Scope {
    /// Enters a scope.
    pub fn enter() -> Scope {
        *ACTIVE.lock().unwrap_or_else(|e| e.into_inner()) += 1;
        Scope(())
    }
}

impl Drop for Scope {
    fn drop(&mut self) {
        let mut n = ACTIVE.lock().unwrap_or_else(|e| e.into_inner());
        *n -= 1;
        if *n == 0 {
            REQUESTED.store(false, Ordering::Relaxed);
        }
    }
}

/// Runs `sim` to its end as [`Simulation::run`] does (the same samples,
/// the same bits), looking at [`requested`] between chunks of about
/// [`CHUNK_WORK`] evaluations; a requested stop ends it early (its outcome
/// then describes a truncated run: the caller discards it).
pub(crate) fn run_chunked<P, C, R>(
    sim: &mut Simulation<P, C, R>,
    lp: &Loop,
    observe: &mut dyn FnMut(&Sample),
) -> Outcome
where
    P: crate::plant::Plant,
    C: ehservo_core::control::Controller,
    R: ehservo_core::reference::Reference,
{
    let s = lp.sim();
    let per_sample = crate::limits::sample_evaluations(s, lp.stages());
    let chunk = (CHUNK_WORK / per_sample.max(1)).max(1);
    loop {
        if requested() {
            return sim.outcome();
        }
        // The samples k … k + chunk − 1: run_until stops before the next
        // sample would be later than t_end (half a step before it).
        let k = (sim.time() / s.step).round();
        let t_end = (k + chunk as f64 - 0.5) * s.step;
        if sim.run_until(t_end, observe).is_some() {
            return sim.outcome();
        }
    }
}
