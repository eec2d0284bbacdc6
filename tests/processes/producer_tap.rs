//! The wire end to end, with real processes: `dicstream producer` publishing, `dicstream tap`
//! receiving (every frame intact, ids consecutive), a tap killed with SIGKILL mid-run while the
//! producer keeps going, SIGTERM ending the producer cleanly, and `/dev/shm` clean afterwards.
//! Then the rig-driven camera against a real `dicstream rig`.

use crate::common;

use common::{tap_json, Run, HANG_GUARD};
use iceoryx2::prelude::*;
use std::collections::HashMap;
use std::time::Instant;
use wire::pubsub::{SliceSubscriber, ValueSubscriber};
use wire::{services, FrameHeader, RigState};

/// Frames of this size at this rate: a modest load that a tap keeps up with even while the
/// other core builds.
const SIDE: &str = "256";
const FPS: &str = "30";

/// The number just before `marker` in `text` (e.g. "12 frames sent" → 12).
fn number_before(text: &str, marker: &str) -> u64 {
    let at = text
        .find(marker)
        .unwrap_or_else(|| panic!("no {marker:?} in {text:?}"));
    text[..at]
        .rsplit(|c: char| !c.is_ascii_digit())
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no number before {marker:?} in {text:?}"))
}

fn assert_clean_shutdown_left_nothing(run: &Run) {
    run.instance.cleanup_dead_nodes();
    let left = run.leftovers_after_clean_shutdown();
    assert!(
        left.is_empty(),
        "files of instance {} left after every process stopped: {left:?}",
        run.name()
    );
}

#[test]
fn tap_receives_every_frame_intact_survives_a_killed_tap_and_shm_is_clean() {
    let mut run = Run::new("producer_tap");
    let instance = run.name().to_string();
    let producer = run.spawn(
        "producer",
        &[
            "producer",
            "--instance",
            &instance,
            "--scenario",
            "rotation",
            "--width",
            SIDE,
            "--height",
            SIDE,
            "--fps",
            FPS,
            "--frames",
            "1000000",
            "--threads",
            "1",
        ],
    );
    let ready = producer.wait_for_stderr("ready line", |l| l.contains("producer: ready"));
    assert!(
        ready.contains(&instance) && ready.contains("256x256"),
        "{ready}"
    );

    // 1. A tap counting 90 frames: all intact, consecutive, none dropped.
    let (status, stdout, stderr) = run.run_to_end(
        "tap1",
        &[
            "tap",
            "frames",
            "--json",
            "--count",
            "90",
            "--instance",
            &instance,
        ],
    );
    assert!(status.success(), "tap failed: {stderr}");
    let first = tap_json(&stdout);
    assert_eq!(first["service"], "frames");
    assert_eq!(first["received"], 90, "{first}");
    assert_eq!(first["drops"], 0, "{first}");
    assert_eq!(first["checksum_failures"], 0, "{first}");
    assert_eq!(first["invalid"], 0, "{first}");
    assert_eq!(first["restarts"], 0, "{first}");
    assert_eq!(first["stopped_by"], "count");
    let (first_id, last_id) = (
        first["first_id"].as_u64().unwrap(),
        first["last_id"].as_u64().unwrap(),
    );
    assert_eq!(last_id - first_id + 1, 90, "ids not consecutive: {first}");
    assert_eq!(first["last"]["width_px"], 256);
    assert_eq!(first["last"]["checksum_ok"], true);
    assert_eq!(first["last"]["has_truth"], true);
    assert!(first["latency_us"]["p50"].as_f64().unwrap() > 0.0);

    // 2. A tap killed with SIGKILL once it has received frames.
    let tap2 = run.spawn(
        "tap2",
        &["tap", "frames", "--json", "--instance", &instance],
    );
    tap2.wait_for_stderr("a per-second line with frames", |l| {
        l.starts_with("tap frames:") && l.contains(" Hz, drops")
    });
    tap2.signal(libc::SIGKILL);
    let (status, _, _) = tap2.wait();
    assert!(!status.success(), "SIGKILL ends the tap");
    assert!(
        run.child("producer").is_running(),
        "the producer survives a dead consumer"
    );

    // 3. A new tap receives: the producer kept going.
    let (status, stdout, stderr) = run.run_to_end(
        "tap3",
        &[
            "tap",
            "frames",
            "--json",
            "--count",
            "60",
            "--instance",
            &instance,
        ],
    );
    assert!(status.success(), "tap failed: {stderr}");
    let third = tap_json(&stdout);
    assert_eq!(third["received"], 60, "{third}");
    assert_eq!(third["drops"], 0, "{third}");
    assert_eq!(third["checksum_failures"], 0, "{third}");
    let third_first = third["first_id"].as_u64().unwrap();
    let third_last = third["last_id"].as_u64().unwrap();
    assert_eq!(third_last - third_first + 1, 60, "{third}");
    assert!(
        third_first > last_id,
        "frame ids go on across taps: {third}"
    );
    assert!(run.child("producer").is_running());

    // 4. SIGTERM: the producer prints its final line and exits 0.
    let producer = run.child("producer");
    producer.signal(libc::SIGTERM);
    let (status, stdout, stderr) = producer.wait();
    assert!(
        status.success(),
        "producer exit {status:?}; stderr:\n{stderr}"
    );
    let line = stdout
        .lines()
        .find(|l| l.starts_with("producer: "))
        .unwrap_or_else(|| panic!("no final line in {stdout:?}"));
    assert!(line.contains("stopped by signal"), "{line}");
    let sent = number_before(line, " frames sent");
    assert!(sent > third_last, "{line}");
    assert!(
        line.contains("received by nobody") && line.contains("fps measured"),
        "{line}"
    );

    // 5. Only what a clean shutdown leaves: nothing but iceoryx2's persistent node counter.
    assert_clean_shutdown_left_nothing(&run);
    run.teardown();
    assert!(run.instance.leftover_files().is_empty());
}

#[test]
fn tap_ends_on_sigint_with_its_summary() {
    let mut run = Run::new("tap_sigint");
    let instance = run.name().to_string();
    let tap = run.spawn("tap", &["tap", "rig/state", "--instance", &instance]);
    tap.wait_for_stderr("the watching line", |l| {
        l.contains("tap: watching rig/state")
    });
    tap.signal(libc::SIGINT);
    let (status, stdout, stderr) = tap.wait();
    assert!(status.success(), "tap exit {status:?}: {stderr}");
    assert!(
        stdout.contains("tap rig/state: 0 received"),
        "summary missing: {stdout}"
    );
    assert_clean_shutdown_left_nothing(&run);
}

/// What the test saw of one frame.
struct SeenFrame {
    header: FrameHeader,
    checksum_ok: bool,
}

#[test]
fn follow_rig_renders_each_frame_from_a_real_rig_sample_with_exact_truth() {
    let mut run = Run::new("follow_rig");
    let instance = run.name().to_string();
    const FRAMES: usize = 40;
    let producer = run.spawn(
        "producer",
        &[
            "producer",
            "--follow-rig",
            "--instance",
            &instance,
            "--width",
            SIDE,
            "--height",
            SIDE,
            "--fps",
            "10",
            "--frames",
            &FRAMES.to_string(),
            "--threads",
            "1",
        ],
    );
    producer.wait_for_stderr("ready line", |l| l.contains("producer: ready"));
    producer.wait_for_stderr("the waiting line", |l| {
        l.contains("waiting for the first rig/state sample")
    });

    // This test is a consumer too: it watches rig/state and frames, before the rig starts.
    let (node, _) = run.instance.create_node("test").expect("test node");
    let frames: SliceSubscriber<u16, FrameHeader> =
        SliceSubscriber::create(&node, &services::FRAMES).expect("frames subscriber");
    let rig_states: ValueSubscriber<RigState> =
        ValueSubscriber::create(&node, &services::RIG_STATE).expect("rig/state subscriber");
    let waitset = WaitSetBuilder::new().create::<ipc::Service>().unwrap();
    let _frames_guard = waitset.attach_notification(frames.listener()).unwrap();
    let _rig_guard = waitset.attach_notification(rig_states.listener()).unwrap();

    run.spawn(
        "rig",
        &[
            "rig",
            "--instance",
            &instance,
            "--test",
            "uniaxial",
            // The analytic sheet: its frames' truth is uniaxial exactly (F22 = F11^-1/2).
            "--specimen",
            "homogeneous",
            "--speed",
            "20",
            "--publish-hz",
            "50",
            "--duration-s",
            "3000",
        ],
    );

    let mut states: HashMap<u64, RigState> = HashMap::new();
    let mut seen: Vec<SeenFrame> = Vec::new();
    let give_up = Instant::now() + HANG_GUARD;
    while seen.len() < FRAMES {
        assert!(
            Instant::now() < give_up,
            "hang guard: {} frames",
            seen.len()
        );
        waitset
            .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, HANG_GUARD)
            .unwrap();
        frames.clear_events();
        rig_states.clear_events();
        while let Some(state) = rig_states.receive().unwrap() {
            states.insert(state.sample_id, state);
        }
        while let Some(sample) = frames.receive().unwrap() {
            let header = *sample.user_header();
            let checksum_ok =
                wire::frame::pixel_checksum(sample.payload()) == header.pixel_checksum;
            seen.push(SeenFrame {
                header,
                checksum_ok,
            });
        }
    }

    let (status, stdout, stderr) = run.child("producer").wait();
    assert!(status.success(), "producer: {stderr}");
    assert!(
        stdout.contains(&format!("producer: {FRAMES} frames sent")),
        "{stdout}"
    );
    assert!(stderr.contains("following the rig from sample"), "{stderr}");
    let rig = run.child("rig");
    rig.signal(libc::SIGTERM);
    let (status, _, stderr) = rig.wait();
    assert!(status.success(), "rig: {stderr}");

    let centre = (256.0 - 1.0) / 2.0;
    let mut matched = 0;
    let mut previous_sample = 0;
    for (k, frame) in seen.iter().enumerate() {
        let h = &frame.header;
        assert!(frame.checksum_ok, "frame {} arrived damaged", h.frame_id);
        assert_eq!(h.frame_id, k as u64, "frame ids consecutive from 0");
        assert_ne!(
            h.rig_sample_id,
            wire::NO_RIG_SAMPLE,
            "frame {k} names its rig sample"
        );
        assert!(h.rig_sample_id >= previous_sample, "rig samples go forward");
        previous_sample = h.rig_sample_id;
        assert_eq!(h.has_truth, 1);
        assert_eq!(h.scenario_id, producer::RIG_SCENARIO_ID);
        assert_eq!(h.truth.centre_px, [centre, centre]);
        // The exact rig kinematics of that sample, when this test kept it.
        if let Some(state) = states.get(&h.rig_sample_id) {
            matched += 1;
            let (s, c) = state.specimen_rotation_rad.sin_cos();
            let (lx, ly) = (state.specimen_stretch_x, state.specimen_stretch_y);
            let expected = [c * lx, -s * ly, s * lx, c * ly];
            for (got, want) in h.truth.deformation_gradient.iter().zip(expected) {
                assert!((got - want).abs() < 1e-12, "frame {k}: F {got} vs {want}");
            }
            for axis in 0..2 {
                let t = state.specimen_centre_offset_mm[axis] / producer::DEFAULT_MM_PER_PX;
                assert!((h.truth.translation_px[axis] - t).abs() < 1e-9);
            }
        }
        // Uniaxial tension of an incompressible sheet: F22 = F11^-1/2.
        let [f11, _, _, f22] = h.truth.deformation_gradient;
        assert!(
            (f22 - 1.0 / f11.sqrt()).abs() < 1e-9,
            "frame {k}: {f11} {f22}"
        );
    }
    assert!(
        matched >= FRAMES / 2,
        "only {matched} frames matched a kept rig sample"
    );
    let f11 = |k: usize| seen[k].header.truth.deformation_gradient[0];
    assert!(
        f11(FRAMES - 1) > f11(0) + 0.02,
        "F11 grows with the stretch: {} -> {}",
        f11(0),
        f11(FRAMES - 1)
    );
    for k in 1..FRAMES {
        assert!(
            f11(k) >= f11(k - 1) - 1e-4,
            "F11 follows the ramp at frame {k}"
        );
    }
    // A consumer computes the exact displacement from the header: the corner moves by
    // (F - 1)(X - c) + t.
    let last = seen[FRAMES - 1].header.truth;
    let (u, v) = last.displacement_px(0.0, 0.0);
    let [f11, f12, f21, f22] = last.deformation_gradient;
    assert!((u - ((f11 - 1.0) * -centre + f12 * -centre + last.translation_px[0])).abs() < 1e-9);
    assert!((v - (f21 * -centre + (f22 - 1.0) * -centre + last.translation_px[1])).abs() < 1e-9);

    drop(_frames_guard);
    drop(_rig_guard);
    drop(waitset);
    drop(frames);
    drop(rig_states);
    drop(node);
    assert_clean_shutdown_left_nothing(&run);
}

#[test]
fn follow_rig_skips_and_counts_states_beyond_the_envelope_with_one_warning() {
    let mut run = Run::new("follow_rig_beyond");
    let instance = run.name().to_string();
    let producer = run.spawn(
        "producer",
        &[
            "producer",
            "--follow-rig",
            "--instance",
            &instance,
            "--width",
            "64",
            "--height",
            "64",
            "--fps",
            "20",
            "--max-stretch",
            "1.1",
            "--threads",
            "1",
        ],
    );
    producer.wait_for_stderr("ready line", |l| l.contains("producer: ready"));
    // Uniaxial to λ 1.5 at 0.05 /s, 20x real time: beyond 1.1 within a second of wall time.
    run.spawn(
        "rig",
        &[
            "rig",
            "--instance",
            &instance,
            "--test",
            "uniaxial",
            // The analytic sheet: stretch_x leaves the envelope first.
            "--specimen",
            "homogeneous",
            "--rate",
            "0.05",
            "--stretch",
            "1.5",
            "--speed",
            "20",
            "--publish-hz",
            "50",
            "--duration-s",
            "3000",
        ],
    );
    let producer = run.child("producer");
    let warning = producer.wait_for_stderr("the envelope warning", |l| l.contains("warning"));
    assert!(
        warning.contains("stretch_x") && warning.contains("--max-stretch 1.1"),
        "{warning}"
    );
    // The warning comes with the first skipped slot: the count is at least 1 from here on.
    producer.signal(libc::SIGTERM);
    let (status, stdout, stderr) = producer.wait();
    assert!(status.success(), "producer: {stderr}");
    assert_eq!(
        stderr
            .lines()
            .filter(|l| l.contains("producer: warning:"))
            .count(),
        1,
        "the warning is shown once:\n{stderr}"
    );
    let skipped = number_before(&stdout, " skipped (rig beyond the envelope)");
    assert!(skipped >= 1, "{stdout}");
    let rig = run.child("rig");
    rig.signal(libc::SIGTERM);
    let (status, _, stderr) = rig.wait();
    assert!(status.success(), "rig: {stderr}");
    assert_clean_shutdown_left_nothing(&run);
}

/// A second camera on an instance that has one is refused at start, naming the first one's
/// pid (two used to publish interleaved frames); once the first has ended, a new one starts.
#[test]
fn a_second_producer_on_an_instance_is_refused_naming_the_first() {
    let mut run = Run::new("two_producers");
    let instance = run.name().to_string();
    let args = [
        "producer",
        "--instance",
        &instance,
        "--width",
        SIDE,
        "--height",
        SIDE,
        "--fps",
        FPS,
        "--frames",
        "1000000",
        "--threads",
        "1",
    ];
    let first = run.spawn("first", &args);
    first.wait_for_stderr("ready line", |l| l.contains("producer: ready"));
    let first_pid = first.pid();
    let (status, _, stderr) = run.run_to_end("second", &args);
    assert_eq!(status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!("already has a producer (pid {first_pid})")),
        "{stderr}"
    );
    assert!(!stderr.contains("producer: ready"), "{stderr}");
    run.child("first").signal(libc::SIGKILL);
    run.child("first").wait();
    let third = run.spawn("third", &args);
    third.wait_for_stderr("ready line", |l| l.contains("producer: ready"));
    third.signal(libc::SIGTERM);
    let (status, _, stderr) = run.child("third").wait();
    assert!(status.success(), "{stderr}");
}
