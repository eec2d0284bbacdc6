//! The rig process tests' starting options.

use rig::process::{ProcessOptions, Speed};
use rig::RigConfig;

/// A rig process on `instance`: the default machine, seed 1, no program, campaign, log,
/// journal or strain test, real time, publishing at 500 Hz, built-in tests over `rig/command`
/// at 1e-3 /s to λ 2, no time limit. A test sets what it needs over it:
/// `ProcessOptions { speed: Speed::Factor(5.0), ..rig_options(&name) }`.
pub fn rig_options(instance: &str) -> ProcessOptions {
    ProcessOptions {
        instance: instance.to_string(),
        config: RigConfig::default(),
        seed: 1,
        program: None,
        campaign: None,
        test_rate_per_s: 1e-3,
        test_stretch: 2.0,
        speed: Speed::Realtime,
        publish_hz: 500.0,
        log_path: None,
        log_hz: 100.0,
        duration_s: None,
        exit_when_done: false,
        state_dir: None,
        strain: None,
    }
}
