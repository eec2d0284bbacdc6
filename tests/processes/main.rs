//! The multi-process tests of the `dicstream` binary that share the machine two at a time
//! anyway, as one test binary: each file below was a test binary of its own, and those that read
//! shared memory (wire's subscribers over iceoryx2) cost about a minute each to build in
//! release, the same generic code compiled once per binary. One binary builds it once.
//! `cargo test --release --test processes faults::` runs one file's tests.
//!
//! The runs that judge a whole bench (`default_run.rs`, `field_route.rs`, `structure_run.rs`),
//! the independent finite-element check and the GenICam tests (another feature) stay binaries
//! of their own, so each runs alone on the machine.

#[path = "../common/mod.rs"]
mod common;
mod dashboard_support;

mod bench_correlate;
mod cli_refusals;
mod correlate_offline;
mod correlator_live;
mod correlator_restart;
mod dashboard;
mod faults;
mod genicam_absent;
mod identify_machine_files;
mod producer_bad_input;
mod producer_tap;
mod producer_watch;
mod rig_follow_csv;
mod rig_resume;
mod run_bench;
mod shm_leftovers;
mod specimen;
mod strain_loop;
