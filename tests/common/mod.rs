//! Helpers of the multi-process tests of the `dicstream` binary, on the workspace's test kit
//! (`testkit`: child processes, readiness, signals, the hang guard, test instances): [`Run`]
//! is a `testkit::Run` whose children run the binary under test; `bench_run` drives
//! `dicstream run`; `camera` makes the test itself the camera and the field reader of a live
//! correlator; `namespace` runs a script in a mount namespace (a small tmpfs); `notified` waits
//! on a subscriber's notifications under the hang guard; [`dashboard_address`] reads a
//! dashboard's address from its stderr line.

#![allow(dead_code)]

pub mod bench_run;
pub mod camera;
pub mod namespace;
pub mod notified;

pub use testkit::{Proc, HANG_GUARD};

/// A `testkit::Run` (unique instance, children, scratch folder; cleaned on drop) whose
/// children run the `dicstream` binary under test.
pub struct Run(testkit::Run);

impl Run {
    pub fn new(test: &str) -> Run {
        Run(testkit::Run::new(test, env!("CARGO_BIN_EXE_dicstream")))
    }
}

impl std::ops::Deref for Run {
    type Target = testkit::Run;
    fn deref(&self) -> &testkit::Run {
        &self.0
    }
}

impl std::ops::DerefMut for Run {
    fn deref_mut(&mut self) -> &mut testkit::Run {
        &mut self.0
    }
}

/// Runs `dicstream ARGS` (the binary under test) to its end; its exit status and output.
pub fn dicstream(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_dicstream"))
        .args(args)
        .output()
        .expect("run dicstream")
}

/// Parses the one JSON object a `tap --json` prints.
pub fn tap_json(stdout: &str) -> serde_json::Value {
    serde_json::from_str(stdout.trim())
        .unwrap_or_else(|e| panic!("tap --json printed no JSON object ({e}):\n{stdout}"))
}

/// The address a dashboard's stderr `line` gives (`... at http://ADDR:PORT/ ...`), as
/// `ADDR:PORT`; panics unless it is a loopback one.
pub fn dashboard_address(line: &str) -> String {
    let url = line
        .split("http://")
        .nth(1)
        .unwrap_or_else(|| panic!("no URL in {line:?}"));
    let addr = url.split('/').next().unwrap().to_string();
    assert!(addr.starts_with("127.0.0.1:"), "{line}");
    addr
}
