//! Every standalone process (rig, producer, correlator, identifier, tap) leaves nothing of its
//! instance in `/dev/shm` or iceoryx2's folder at a normal exit, not even iceoryx2's node
//! counter (`<prefix>…_node.<version>.global_mgmt`): the last user of an instance removes it.
//! Each test runs real processes on an instance of its own and looks before the `Run`'s own
//! cleanup.

use crate::common;

use common::Run;

/// Runs `dicstream ARGS --instance <the run's>` to a normal exit and asserts that nothing of
/// the instance is left.
fn assert_leaves_nothing(test: &str, args: &[&str]) {
    let mut run = Run::new(test);
    let instance = run.name().to_string();
    let mut full: Vec<&str> = args.to_vec();
    full.extend(["--instance", &instance]);
    let (status, _, stderr) = run.run_to_end(test, &full);
    assert!(status.success(), "{args:?} failed ({status}):\n{stderr}");
    let left = run.instance.leftover_files();
    assert!(
        left.is_empty(),
        "{args:?} exited normally but left files of instance {instance}: {left:?}\n{stderr}"
    );
}

#[test]
fn rig_leaves_nothing() {
    assert_leaves_nothing("shm_rig", &["rig", "--speed", "max", "--duration-s", "0.2"]);
}

#[test]
fn producer_leaves_nothing() {
    assert_leaves_nothing(
        "shm_producer",
        &[
            "producer",
            "--scenario",
            "translation",
            "--width",
            "64",
            "--height",
            "64",
            "--frames",
            "3",
        ],
    );
}

#[test]
fn correlator_leaves_nothing() {
    assert_leaves_nothing("shm_correlator", &["correlator", "--idle-timeout-s", "0.3"]);
}

#[test]
fn identifier_leaves_nothing() {
    let output = std::env::temp_dir().join(format!("dicstream-shm-id-{}", std::process::id()));
    let output_arg = output.to_string_lossy().into_owned();
    assert_leaves_nothing(
        "shm_identifier",
        &[
            "identifier",
            "--idle-timeout-s",
            "0.3",
            "--output",
            &output_arg,
        ],
    );
    let _ = std::fs::remove_dir_all(&output);
}

#[test]
fn tap_leaves_nothing() {
    assert_leaves_nothing("shm_tap", &["tap", "frames", "--seconds", "0.3"]);
}

/// Two processes on one instance: the camera ends first while the tap still watches (the
/// instance is still in use: it must not take anything from the tap), then the tap, stopped by
/// SIGTERM (a normal exit), is the last user and leaves the instance empty.
#[test]
fn the_last_of_two_processes_leaves_nothing() {
    let mut run = Run::new("shm_two");
    let instance = run.name().to_string();
    run.spawn("tap", &["tap", "frames", "--instance", &instance])
        .wait_for_stderr("the tap's start", |line| line.contains("tap: watching"));
    let (status, _, stderr) = run.run_to_end(
        "producer",
        &[
            "producer",
            "--scenario",
            "translation",
            "--width",
            "64",
            "--height",
            "64",
            "--frames",
            "5",
            "--instance",
            &instance,
        ],
    );
    assert!(status.success(), "producer failed ({status}):\n{stderr}");
    let tap = run.child("tap");
    assert!(tap.is_running(), "the tap ended with the camera");
    tap.signal(libc::SIGTERM);
    let (status, _, stderr) = tap.wait();
    assert!(status.success(), "tap failed ({status}):\n{stderr}");
    let left = run.instance.leftover_files();
    assert!(left.is_empty(), "files left on {instance}: {left:?}");
}
