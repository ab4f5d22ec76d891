//! The command line's integration tests, as one test binary: each file here
//! was once its own binary under `tests/`, and linking 25 of them (each with
//! the whole library) was most of CI's test step. Run one group with its
//! module name as the filter, e.g. `cargo test -p ehservo --test it league::`.
//! `tests/no_alloc.rs` stays a binary of its own: it installs a counting
//! global allocator, which would count every other test's allocations.

mod common;

mod analysis;
mod bad_input;
mod breaking_scan;
mod cli;
mod cluster;
mod controllers;
mod environment;
mod faults;
mod fmu_import;
mod fmu_import_fmi2;
mod force;
mod freq;
mod freq_cylinder;
mod golden;
mod guide;
mod guide_keys;
mod hopsan;
mod hopsan_supply;
mod house;
mod identify;
mod identify_axis;
mod identify_hostile;
mod ifac9007;
mod independent;
mod k1_closed_form;
mod league;
mod linear_axis;
mod models;
mod nn_robust;
mod outcome;
mod outputs;
mod pil;
mod properties;
mod realistic;
mod reliability;
mod reliability_four;
mod reproduce_bad_input;
mod reproduction;
mod sampled_loop;
mod schema;
mod solvers;
mod stages;
mod stochastic;
mod study;
mod study_bad_input;
mod tune;
