//! The integration-test kit of dicstream, used as a dev-dependency by the tests of every
//! package: a child process with its stderr read line by line ([`Proc`]: readiness, signals,
//! exit), one hang guard ([`HANG_GUARD`]), a test's own instance whose shared-memory files are
//! removed even when the test fails ([`TestInstance`]), a test's instance, children and scratch
//! folder together ([`Run`]), unique instance names, polling for a condition no line announces
//! ([`until`]), HTTP clients ([`send_request`], and [`stalled_client`] that stops reading),
//! and the path to the reference data `testdata/` ([`shared_data`]: skipped with a message, or
//! a failure under `DICSTREAM_REQUIRE_SHARED=1`).
//!
//! Timeouts here only guard against a hang (a test that would otherwise never end); no test
//! asserts a wall-clock time.

mod http;
mod instance;
mod proc;
mod run;
mod shared;
mod until;

pub use http::{send_request, stalled_client};
pub use instance::{unique_instance, TestInstance};
pub use proc::{signal, Proc};
pub use run::Run;
pub use shared::{shared_data, REQUIRE_SHARED_VAR, SHARED_DATA_VAR};
pub use until::until;

use std::time::Duration;

/// The one bound on anything a test waits for (start-up, a line, a field, an exit): a hang
/// guard, generous enough for a loaded two-core machine.
pub const HANG_GUARD: Duration = Duration::from_secs(180);
