//! The multi-process tests of the `dicstream` binary that share the machine two at a time
//! anyway, as one test binary: each file below was a test binary of its own, and those that read
//! shared memory (wire's subscribers over iceoryx2) cost about a minute each to build in
//! release, the same generic code compiled once per binary. One binary builds it once.
//! `cargo test --release --test processes faults::` runs one file's tests.
//!
//! The runs that judge a whole bench (`default_run.rs`, `field_route.rs`, `structure_run.rs`),
//! the independent finite-element check and the GenICam tests (another feature) stay binaries
//! of their own, so each runs alone on the machine.
//!
//! Six tests at a time by default, not one per core: these tests mostly wait on real time (a
//! bench filming at 10 frames/s, a stale limit, a restart), so two at a time left the two cores
//! two-thirds idle. Measured on 2 cores with a build running beside: the 101 tests in 105 s at
//! 6 threads, against 191 s at 2 (`faults` alone 91 s at 4, 132 s at 2), using 1.1 cores.
//! `--test-threads N` or `RUST_TEST_THREADS` still decide when given.

/// Sets `RUST_TEST_THREADS` to 6 unless it is set, before `main`, so before libtest reads it
/// (the test harness offers no other hook). Runs from `.init_array` while the process is still
/// single-threaded, so changing the environment is sound.
extern "C" fn waiting_tests_at_once() {
    if std::env::var_os("RUST_TEST_THREADS").is_none() {
        std::env::set_var("RUST_TEST_THREADS", "6");
    }
}
#[used]
#[link_section = ".init_array"]
static WAITING_TESTS_AT_ONCE: extern "C" fn() = waiting_tests_at_once;

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
mod monitor_gauges;
mod producer_bad_input;
mod producer_tap;
mod producer_watch;
mod rig_follow_csv;
mod rig_resume;
mod run_bench;
mod shm_leftovers;
mod specimen;
mod strain_loop;
