//! Real GenICam acquisition through a real GigE Vision stack: Aravis' fake camera
//! (`arv-fake-gv-camera-0.8`, package aravis-tools) streaming to `dicstream producer --camera`.
//!
//! GigE Vision discovery broadcasts on every interface, so nothing GenICam runs on the host's
//! network: each test creates its own network namespace (`unshare -n`, loopback up), and runs
//! the fake camera, `dicstream cameras` and the producer inside it (`nsenter --net`). The
//! consumers (a `dicstream tap`, the test's own subscriber) stay on the host: iceoryx2's data
//! is in /dev/shm and its events are pathname unix sockets under /tmp, neither of which a
//! network namespace separates, so a frame crossing is itself part of the check. Where no
//! namespace can be made (not root, no user namespaces), each test says so and is skipped, except
//! under CI (`CI` set), where that is a failure (as the dashboard test without chromium).

#![cfg(feature = "genicam")]

mod common;

use common::{tap_json, Proc, Run};
use std::process::Command;
use std::time::{Duration, Instant};
use wire::pubsub::SliceSubscriber;
use wire::{services, FrameHeader};

const FAKE_CAMERA: &str = "arv-fake-gv-camera-0.8";
/// The id Aravis gives the fake camera with its default serial (GV01).
const FAKE_ID: &str = "Aravis-Fake-GV01";
const DICSTREAM: &str = env!("CARGO_BIN_EXE_dicstream");

/// A network namespace of the test's own (held by a `sleep`), and the processes started in
/// it; all are killed when it drops.
struct Netns {
    holder: Proc,
    procs: Vec<Proc>,
}

impl Netns {
    /// A fresh namespace with loopback up, or `None` (with a visible message) where none can
    /// be made.
    fn new(test: &str) -> Option<Netns> {
        let probe = Command::new("unshare").args(["-n", "true"]).output();
        if !probe.as_ref().is_ok_and(|o| o.status.success()) {
            // CI (`CI` set) runs as root, where a namespace can always be made: there a
            // failure is one, not a skip.
            assert!(
                std::env::var_os("CI").is_none(),
                "{test}: cannot create a network namespace (`unshare -n` failed: {probe:?})"
            );
            eprintln!(
                "SKIPPED {test}: cannot create a network namespace here (`unshare -n` failed: \
                 {probe:?}); the GenICam tests never run on the host's network"
            );
            return None;
        }
        assert!(
            Command::new(FAKE_CAMERA).arg("--help").output().is_ok(),
            "{FAKE_CAMERA} not found: install the Debian package aravis-tools"
        );
        let mut holder = Command::new("unshare");
        holder.args([
            "-n",
            "sh",
            "-c",
            "ip link set lo up && echo netns-ready >&2 && exec sleep 3600",
        ]);
        let mut holder = Proc::spawn("netns", holder);
        holder.wait_for_stderr("the namespace", |l| l.contains("netns-ready"));
        Some(Netns {
            holder,
            procs: Vec::new(),
        })
    }

    /// `program ARGS` inside the namespace.
    fn command(&self, program: &str, args: &[&str]) -> Command {
        let mut command = Command::new("nsenter");
        command
            .arg(format!("--net=/proc/{}/ns/net", self.holder.pid()))
            .arg(program)
            .args(args);
        command
    }

    fn spawn(&mut self, name: &str, program: &str, args: &[&str]) -> &mut Proc {
        let command = self.command(program, args);
        self.procs.push(Proc::spawn(name, command));
        self.procs.last_mut().unwrap()
    }

    fn child(&mut self, name: &str) -> &mut Proc {
        self.procs
            .iter_mut()
            .rev()
            .find(|p| p.name == name)
            .unwrap_or_else(|| panic!("no child {name}"))
    }

    /// Starts the fake camera on loopback and waits until Aravis discovers it.
    fn start_camera(&mut self, name: &str) {
        self.spawn(name, FAKE_CAMERA, &["-i", "127.0.0.1"]);
        testkit::until("the fake camera discovered by `dicstream cameras`", || {
            let listed = self.cameras_json();
            listed
                .as_array()
                .is_some_and(|a| a.iter().any(|c| c["id"] == FAKE_ID))
                .then_some(())
        });
    }

    /// `dicstream cameras --json` inside the namespace.
    fn cameras_json(&self) -> serde_json::Value {
        let out = self
            .command(DICSTREAM, &["cameras", "--json"])
            .output()
            .expect("dicstream cameras");
        assert!(out.status.success(), "{out:?}");
        serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
            panic!("cameras --json printed no JSON ({e}): {out:?}");
        })
    }
}

impl Drop for Netns {
    fn drop(&mut self) {
        for p in &mut self.procs {
            p.kill();
        }
        self.holder.kill();
    }
}

/// The producer on the fake camera, inside `ns`, with `extra` options.
fn spawn_producer<'a>(ns: &'a mut Netns, run: &Run, extra: &[&str]) -> &'a mut Proc {
    let mut args = vec![
        "producer",
        "--instance",
        run.name(),
        "--camera",
        "genicam:Aravis-Fake-GV01",
        "--fps",
        "20",
    ];
    args.extend_from_slice(extra);
    ns.spawn("producer", DICSTREAM, &args)
}

/// A tap on the host counting `count` frames.
fn tap(run: &mut Run, name: &str, count: u32) -> serde_json::Value {
    let instance = run.name().to_string();
    let count = count.to_string();
    let (status, stdout, stderr) = run.run_to_end(
        name,
        &[
            "tap",
            "frames",
            "--json",
            "--count",
            &count,
            "--instance",
            &instance,
        ],
    );
    assert!(status.success(), "tap failed: {stderr}");
    tap_json(&stdout)
}

#[test]
fn cameras_lists_the_fake_camera_with_its_sensor_and_formats() {
    let Some(mut ns) = Netns::new("cameras_lists_the_fake_camera") else {
        return;
    };
    ns.start_camera("camera");
    let listed = ns.cameras_json();
    let fake = listed
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["id"] == FAKE_ID)
        .unwrap_or_else(|| panic!("{listed}"));
    assert_eq!(fake["vendor"], "Aravis", "{fake}");
    assert_eq!(fake["serial"], "GV01", "{fake}");
    assert!(
        fake["address"].as_str().unwrap().contains("127.0.0.1"),
        "{fake}"
    );
    assert!(fake["sensor_width_px"].as_u64().unwrap() > 0, "{fake}");
    assert!(fake["sensor_height_px"].as_u64().unwrap() > 0, "{fake}");
    let formats: Vec<&str> = fake["pixel_formats"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    assert!(formats.contains(&"Mono8"), "{fake}");
    assert_eq!(fake["open_error"], serde_json::Value::Null, "{fake}");

    // The human listing names it and says how to use it.
    let out = ns.command(DICSTREAM, &["cameras"]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && text.contains(FAKE_ID), "{text}");
    assert!(text.contains("--camera genicam:"), "{text}");
}

#[test]
fn fake_camera_frames_arrive_intact_consecutive_with_the_camera_pattern_and_timestamps() {
    let Some(mut ns) = Netns::new("fake_camera_frames") else {
        return;
    };
    let mut run = Run::new("genicam_frames");
    ns.start_camera("camera");
    let log = run.dir.join("camera.csv");
    let log_arg = log.to_str().unwrap().to_string();
    let producer = spawn_producer(&mut ns, &run, &["--log", &log_arg]);
    let opened = producer.wait_for_stderr("camera open", |l| l.contains("producer: camera"));
    assert!(
        opened.contains("Mono8") && opened.contains("host receive time"),
        "{opened}"
    );
    producer.wait_for_stderr("ready", |l| l.contains("producer: ready"));

    // A tap on the host: every frame intact (the checksum the producer stamped over what it
    // copied from the camera's buffer), ids consecutive.
    let first = tap(&mut run, "tap", 30);
    assert_eq!(first["received"], 30, "{first}");
    assert_eq!(first["drops"], 0, "{first}");
    assert_eq!(first["checksum_failures"], 0, "{first}");
    assert_eq!(first["invalid"], 0, "{first}");
    let (a, b) = (
        first["first_id"].as_u64().unwrap(),
        first["last_id"].as_u64().unwrap(),
    );
    assert_eq!(b - a + 1, 30, "{first}");
    assert_eq!(first["last"]["bit_depth"], 8, "{first}");
    assert_eq!(first["last"]["has_truth"], false, "{first}");

    // The pixels are the camera's: its diagonal ramp is a function of x + y (plus the frame
    // count), so every pixel equals its lower-left neighbour; a row, stride or conversion
    // error breaks that.
    let (node, _) = run.instance.create_node("test").expect("node");
    let frames: SliceSubscriber<u16, FrameHeader> =
        SliceSubscriber::create(&node, &services::FRAMES).expect("subscriber");
    let deadline = Instant::now() + Duration::from_secs(20);
    let (header, pixels) = loop {
        if let Some(sample) = frames.receive().expect("receive") {
            let header = *sample.user_header();
            break (header, sample.payload().to_vec());
        }
        assert!(
            Instant::now() < deadline,
            "no frame for the test's subscriber"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    let (w, h) = (header.width_px as usize, header.height_px as usize);
    assert_eq!(pixels.len(), w * h);
    assert_eq!(header.pixel_checksum, wire::frame::pixel_checksum(&pixels));
    for y in 0..h - 1 {
        for x in 0..w - 1 {
            assert_eq!(
                pixels[y * w + x + 1],
                pixels[(y + 1) * w + x],
                "frame {} at ({x},{y}): not the camera's diagonal ramp",
                header.frame_id
            );
        }
    }
    assert!(pixels.iter().any(|&p| p != pixels[0]), "a flat frame");
    assert!(
        pixels.iter().all(|&p| p < 256),
        "Mono8 values beyond 8 bits"
    );
    assert!(header.t_capture_ns > 0 && header.t_capture_ns <= wire::monotonic_ns());
    assert!(header.t_camera_ns > 0, "no camera timestamp in the header");

    // SIGTERM: a clean end with the counts; the log holds one row per frame, ids consecutive,
    // the camera's timestamps going forward.
    let producer = ns.child("producer");
    producer.signal(libc::SIGTERM);
    let (status, stdout, stderr) = producer.wait();
    assert!(status.success(), "{stderr}");
    assert!(
        stdout.contains("buffer(s) published") && stdout.contains("lost 0 time(s)"),
        "{stdout}"
    );
    let rows = std::fs::read_to_string(&log).unwrap();
    let mut lines = rows.lines();
    assert_eq!(
        lines.next(),
        Some("frame_id,camera_frame_id,camera_timestamp_ns,host_receive_ns")
    );
    let parsed: Vec<Vec<u64>> = lines
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect();
    assert!(parsed.len() >= 30, "{rows}");
    for pair in parsed.windows(2) {
        assert_eq!(pair[1][0], pair[0][0] + 1, "frame ids: {rows}");
        assert!(pair[1][2] > pair[0][2], "camera time going back: {rows}");
        assert!(pair[1][3] > pair[0][3], "host time going back: {rows}");
    }
}

#[test]
fn a_fake_camera_killed_and_restarted_is_reported_and_reconnected_ids_going_on() {
    let Some(mut ns) = Netns::new("fake_camera_restart") else {
        return;
    };
    let mut run = Run::new("genicam_restart");
    ns.start_camera("camera");
    spawn_producer(&mut ns, &run, &[]).wait_for_stderr("ready", |l| l.contains("producer: ready"));
    let before = tap(&mut run, "tap1", 10);
    assert_eq!(before["received"], 10, "{before}");

    ns.child("camera").kill();
    let lost = ns
        .child("producer")
        .wait_for_stderr("the loss reported", |l| l.contains("lost:"));
    assert!(
        lost.contains(FAKE_ID) && lost.contains("reconnecting"),
        "{lost}"
    );
    ns.spawn("camera2", FAKE_CAMERA, &["-i", "127.0.0.1"]);
    let back = ns
        .child("producer")
        .wait_for_stderr("the reconnection", |l| l.contains("reconnected after"));
    assert!(back.contains(FAKE_ID), "{back}");

    let after = tap(&mut run, "tap2", 10);
    assert_eq!(after["received"], 10, "{after}");
    assert_eq!(after["checksum_failures"], 0, "{after}");
    let (a, b) = (
        after["first_id"].as_u64().unwrap(),
        after["last_id"].as_u64().unwrap(),
    );
    assert_eq!(
        b - a + 1,
        10,
        "ids consecutive after the reconnection: {after}"
    );
    assert!(
        a > before["last_id"].as_u64().unwrap(),
        "ids go on: {before} {after}"
    );

    let producer = ns.child("producer");
    producer.signal(libc::SIGTERM);
    let (status, stdout, stderr) = producer.wait();
    assert!(status.success(), "{stderr}");
    assert!(
        stdout.contains("lost 1 time(s), reconnected 1 time(s)"),
        "{stdout}"
    );
}

#[test]
fn an_unsupported_pixel_format_is_a_clear_error() {
    // Refused by name before any camera is looked for (no namespace needed).
    let out = Command::new(DICSTREAM)
        .args(["producer", "--camera", "genicam", "--pixel-format", "RGB8"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("pixel format \"RGB8\": expected") && stderr.contains("Mono12"),
        "{stderr}"
    );

    // A monochrome format the camera does not offer: refused by the camera's list.
    let Some(mut ns) = Netns::new("unsupported_pixel_format") else {
        return;
    };
    let run = Run::new("genicam_format");
    ns.start_camera("camera");
    let producer = spawn_producer(&mut ns, &run, &["--pixel-format", "Mono12"]);
    let (status, stdout, stderr) = producer.wait();
    assert!(!status.success(), "{stdout}");
    assert!(
        stderr.contains("does not offer pixel format Mono12") && stderr.contains("Mono8"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("producer: ready"),
        "nothing published: {stderr}"
    );
}

/// Median time of `runs` copies of `bytes` bytes, µs (the scale for the figures below).
fn memcpy_median_us(bytes: usize, runs: usize) -> f64 {
    let src = vec![0x5Au8; bytes];
    let mut dst = vec![0u8; bytes];
    let mut times: Vec<f64> = (0..runs)
        .map(|i| {
            let start = Instant::now();
            dst.copy_from_slice(std::hint::black_box(&src));
            std::hint::black_box(&mut dst)[i % bytes] ^= 1;
            start.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[runs / 2]
}

/// Benchmark (run by hand, prints figures, asserts no time): from the driver's complete buffer
/// to a subscriber, per 1 MPx frame in Mono8 and Mono16, against a memcpy of the same sizes in
/// the same run. The latency is the tap's, from `t_capture_ns` (the host receive time, taken
/// when the driver hands the buffer over, before the one conversion copy into the loaned
/// slice) to the tap's receipt: conversion, checksum, publish and the subscriber's wake-up.
///
/// `cargo test --release --features genicam --test genicam bench_ -- --ignored --nocapture`
#[test]
#[ignore = "benchmark: prints figures, run by hand"]
fn bench_genicam_buffer_to_subscriber_per_1_mpx_frame() {
    let Some(mut ns) = Netns::new("bench_genicam") else {
        return;
    };
    ns.start_camera("camera");
    let mut lines = Vec::new();
    for (format, source_bytes) in [("Mono8", 1usize << 20), ("Mono16", 2 << 20)] {
        let mut run = Run::new("genicam_bench");
        spawn_producer(
            &mut ns,
            &run,
            &["--pixel-format", format, "--roi", "0,0,1024,1024"],
        )
        .wait_for_stderr("ready", |l| l.contains("producer: ready"));
        let taps: Vec<serde_json::Value> = (0..3)
            .map(|i| tap(&mut run, &format!("tap{i}"), 60))
            .collect();
        let producer = ns.child("producer");
        producer.signal(libc::SIGTERM);
        producer.wait();
        let memcpy_source = memcpy_median_us(source_bytes, 201);
        let memcpy_payload = memcpy_median_us(2 << 20, 201);
        let mut p50s: Vec<f64> = taps
            .iter()
            .map(|t| {
                assert_eq!(t["checksum_failures"], 0, "{t}");
                t["latency_us"]["p50"].as_f64().unwrap()
            })
            .collect();
        p50s.sort_by(f64::total_cmp);
        let p50 = p50s[1];
        lines.push(format!(
            "genicam {format} 1024x1024: buffer to subscriber p50 {p50:.0} µs (median of 3 taps x \
             60 frames; p50s {p50s:?}, p90s {:?}); memcpy {:.0} µs for the camera's {} MiB, {:.0} \
             µs for the {} MiB payload; ratio to the payload memcpy {:.1}",
            taps.iter()
                .map(|t| t["latency_us"]["p90"].as_f64().unwrap().round())
                .collect::<Vec<_>>(),
            memcpy_source,
            source_bytes >> 20,
            memcpy_payload,
            2,
            p50 / memcpy_payload
        ));
    }
    for line in lines {
        eprintln!("BENCH {line}");
    }
}
