//! Studies: parameter sweeps and Monte Carlo over scenarios, on every core
//! and across machines.
//!
//! A study file names a base scenario and how to vary it:
//!
//! ```toml
//! name = "bias-map"
//! base = "../paper/fig3.toml"   # relative to the study file
//! seed = 1                      # the study seed
//! set = ["simulation.horizon=10"]   # optional overrides for every run
//!
//! [[axis]]                      # a grid axis (the grid is their product)
//! keys = ["uncertainty.a_bias", "uncertainty.b_bias"]   # one value, several keys
//! name = "bias"                 # its column in results.csv (default: the first key)
//! values = { from = 0.0, to = 3.0, step = 0.05 }        # or [..], or { from, to, n, scale = "log" }
//!
//! [[axis]]
//! key = "controller.kind"
//! values = ["vsc", "nnvsc"]
//!
//! [monte_carlo]                 # optional: replicates of every grid point
//! runs = 100
//! [[monte_carlo.draw]]
//! key = "controller.gamma1"
//! dist = "uniform"              # uniform | loguniform | normal | choice
//! low = 50.0
//! high = 200.0
//! ```
//!
//! Runs are numbered i = g·R + r (grid point g in row-major order of the
//! axes, replicate r of R). Run i has the seed `derive(study seed, i)`
//! (SplitMix64): it drives the run's draws and, in Monte Carlo studies, its
//! `uncertainty.seed`. Every run is a pure function of (study, i), so the
//! results are identical bit for bit whatever the thread count or the shard
//! split (`--shard K/N` runs the K-th of N contiguous slices, K from 0).

mod exec;
mod limits;
mod merge;
mod plan;
pub mod plots;
mod results;
mod schema;

pub use exec::{execute, resume_state, sweep, Resume, RunRow, SweepOptions};
pub use limits::check_study;
pub use merge::{check_shard, index_list, merge, missing, Missing};
pub use plan::{derive_seed, parse_shard, Plan};
pub use results::{as_f64, results_csv, StudyRecord, METRIC_COLUMNS};
pub(crate) use schema::load_toml;
pub use schema::{value, Axis, AxisValues, Dist, Draw, MonteCarlo, Scale, Study, MAX_RUNS};
