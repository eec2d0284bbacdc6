//! A test machine's CSV force log followed live (`dicstream rig --follow-csv`), and
//! `dicstream run` on a "real" test: a watched folder the test writes images into while it
//! appends rows to a machine's CSV. Real processes on a unique instance; a writer thread
//! appends rows at 100 Hz, each written in two pieces (a partial last line), plus one
//! malformed line, while this test, subscribed to `rig/state` before the follower starts,
//! receives every sample. A log as Excel writes it in a decimal-comma locale (BOM, quoted
//! cells) with an extra cell: read as written, the bad line counted. Timeouts only guard
//! against a hang; no assertion on a wall-clock time. The run's `summary.json` counts the
//! machine log's malformed line. Also: a GenICam camera the binary cannot open fails the run at
//! start, said.

use crate::common;

use common::bench_run::{rows, start_run, summary};
use common::Run;
use std::io::Write;
use std::path::Path;
use std::time::Duration;
use wire::pubsub::ValueSubscriber;
use wire::{services, Instance, RigState};

/// Appends `text` to `path` and flushes it.
fn append(path: &Path, text: &str) {
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .unwrap();
    file.write_all(text.as_bytes()).unwrap();
    file.flush().unwrap();
}

/// `dicstream rig` following `csv` on instance `name`: its `Time` column and `force` as the X
/// force, then `more`.
fn follow_args(name: &str, csv: &Path, force: &str, more: &[&str]) -> Vec<String> {
    let mut args = vec!["rig".to_string(), "--instance".into(), name.into()];
    args.extend(["--follow-csv".into(), csv.display().to_string()]);
    args.extend(["--time-column", "Time", "--force-x-column", force].map(String::from));
    args.extend(more.iter().map(|a| a.to_string()));
    args
}

fn strs(args: &[String]) -> Vec<&str> {
    args.iter().map(String::as_str).collect()
}

/// Row k of the machine's log: time ms, Fx kN, Fy N, Dx mm.
fn row(k: u64) -> (f64, f64, f64, f64) {
    (
        10.0 * k as f64,
        0.01 * k as f64,
        3.0 * k as f64,
        0.02 * k as f64,
    )
}

const ROWS: u64 = 150;
const OFFSET_S: f64 = 1.5;

#[test]
fn rows_appended_at_100_hz_are_published_once_in_order_converted_and_shifted() {
    let mut run = Run::new("csv_follow");
    let csv = run.dir.join("machine.csv");
    let instance = Instance::new(run.name()).unwrap();
    let (node, _) = instance.create_node("test").unwrap();
    let subscriber: ValueSubscriber<RigState> =
        ValueSubscriber::create(&node, &services::RIG_STATE).unwrap();
    // The file does not exist yet: the follower waits for it.
    let args = follow_args(
        run.name(),
        &csv,
        "Fx",
        &[
            "--force-y-column",
            "Fy",
            "--displacement-x-column",
            "Dx",
            "--offset-s",
            "1.5",
            "--idle-timeout-s",
            "1.5",
        ],
    );
    run.spawn("rig", &strs(&args)).wait_line("rig: ready");
    let writer_csv = csv.clone();
    let writer = std::thread::spawn(move || {
        append(&writer_csv, "Time (ms),Fx (kN),Fy (N),Dx (mm)\r\n");
        for k in 0..ROWS {
            let (t, fx, fy, dx) = row(k);
            let line = format!("{t},{fx},{fy},{dx}\r\n");
            // Two pieces: the follower must wait for the newline.
            let (a, b) = line.split_at(line.len() / 2);
            append(&writer_csv, a);
            std::thread::sleep(Duration::from_millis(5));
            append(&writer_csv, b);
            if k == ROWS / 2 {
                append(&writer_csv, "garbage,,x\r\n");
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    });
    let mut received: Vec<RigState> = Vec::new();
    common::notified::wait_notified(subscriber.listener(), || {
        subscriber.clear_events();
        while let Some(state) = subscriber.receive().unwrap() {
            received.push(state);
        }
        ((received.len() as u64) < ROWS).then(|| format!("{} rows", received.len()))
    });
    writer.join().unwrap();
    // Idle: the follower ends by itself, with its summary.
    let (status, _, stderr) = run.child("rig").wait();
    while let Some(state) = subscriber.receive().unwrap() {
        received.push(state);
    }
    assert!(status.success(), "{stderr}");
    assert!(stderr.contains("waiting for"), "{stderr}");
    assert_eq!(
        received.len() as u64,
        ROWS,
        "every row exactly once\n{stderr}"
    );
    let mut last_ns = 0;
    for (k, s) in received.iter().enumerate() {
        let (t_ms, fx_kn, fy_n, dx_mm) = row(k as u64);
        assert_eq!(s.sample_id, k as u64, "in order");
        assert!((s.t_sim_s - (t_ms * 1e-3 + OFFSET_S)).abs() < 1e-9, "{s:?}");
        let a = &s.actuators;
        assert!((500.0 * (a[0].force_kn + a[1].force_kn) - fx_kn * 1e3).abs() < 1e-9);
        assert!((500.0 * (a[2].force_kn + a[3].force_kn) - fy_n).abs() < 1e-9);
        assert!((s.axis_elongation_mm[0] - dx_mm).abs() < 1e-12);
        // Machine time on the monotonic clock: 10 ms apart, as the rows.
        if k > 0 {
            let step_ms = (s.t_published_ns - last_ns) as f64 * 1e-6;
            assert!((step_ms - 10.0).abs() < 1e-3, "row {k}: {step_ms} ms");
        }
        last_ns = s.t_published_ns;
    }
    // The header, rows 0 to ROWS / 2, then the malformed line.
    let malformed_line = ROWS / 2 + 3;
    assert!(
        stderr.contains(&format!("line {malformed_line} skipped"))
            && stderr.contains("1 malformed lines skipped"),
        "{stderr}"
    );
}

#[test]
fn a_log_with_a_bom_quoted_decimal_commas_and_an_extra_cell_is_read_as_written() {
    let mut run = Run::new("csv_follow_quoted");
    let csv = run.dir.join("machine.csv");
    let counts = run.dir.join("counts.json");
    // Excel's "CSV UTF-8" in a decimal-comma locale: a BOM, quoted cells; one row with an
    // extra cell, which must not be read as a force.
    std::fs::write(
        &csv,
        "\u{feff}Time (s),Force (N)\r\n\"4,5\",\"450,5\"\r\n5,1,510\r\n\"5,5\",\"550,5\"\r\n",
    )
    .unwrap();
    let instance = Instance::new(run.name()).unwrap();
    let (node, _) = instance.create_node("test").unwrap();
    let subscriber: ValueSubscriber<RigState> =
        ValueSubscriber::create(&node, &services::RIG_STATE).unwrap();
    let counts_arg = counts.display().to_string();
    let args = follow_args(run.name(), &csv, "Force", &["--counts-json", &counts_arg]);
    run.spawn("rig", &strs(&args));
    // Received while the follower lives (its samples go with it).
    let mut published = Vec::new();
    common::notified::wait_notified(subscriber.listener(), || {
        subscriber.clear_events();
        while let Some(state) = subscriber.receive().unwrap() {
            let a = &state.actuators;
            published.push((state.t_sim_s, 500.0 * (a[0].force_kn + a[1].force_kn)));
        }
        (published.len() < 2).then(|| format!("{published:?}"))
    });
    run.child("rig").signal(libc::SIGTERM);
    let (status, _, stderr) = run.child("rig").wait();
    assert!(status.success(), "{stderr}");
    assert_eq!(published.len(), 2, "{published:?}\n{stderr}");
    for ((t_s, f_n), (t_want, f_want)) in published.iter().zip([(4.5, 450.5), (5.5, 550.5)]) {
        assert!(
            (t_s - t_want).abs() < 1e-9 && (f_n - f_want).abs() < 1e-9,
            "{published:?}"
        );
    }
    assert!(
        stderr.contains("line 3 skipped: 3 cells where the header has 2: \"5,1,510\"")
            && stderr.contains("2 rows published, 1 malformed lines skipped")
            && stderr.contains("stopped by signal"),
        "{stderr}"
    );
    let counts: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&counts).unwrap()).unwrap();
    assert_eq!(counts["malformed_lines"], 1, "{counts}");
    assert_eq!(counts["rows"], 2, "{counts}");
}

#[test]
fn a_log_without_the_configured_column_is_refused_with_the_column_named() {
    let mut run = Run::new("csv_follow_missing");
    let csv = run.dir.join("machine.csv");
    std::fs::write(&csv, "Time (s),Force (kN)\n0,1\n").unwrap();
    let args = follow_args(run.name(), &csv, "Fx", &[]);
    let (status, _, stderr) = run.run_to_end("rig", &strs(&args));
    assert_eq!(status.code(), Some(78), "{stderr}");
    assert!(
        stderr.contains("\"Fx\"") && stderr.contains("Force (kN)"),
        "{stderr}"
    );
}

#[test]
fn a_run_on_a_watched_folder_and_a_machine_log_ends_with_results_without_truth() {
    let mut run = Run::new("run_watch_csv");
    let images = run.temp_dir("images");
    let staged = run.temp_dir("staged");
    let csv = run.dir.join("machine.csv");
    // The "acquisition software"'s images: a speckle stretched along x, 256 x 256.
    let staged_arg = staged.display().to_string();
    let (status, _, stderr) = run.run_to_end(
        "synth",
        &[
            "synth",
            "--scenario",
            "uniaxial",
            "--width",
            "256",
            "--height",
            "256",
            "--frames",
            "6",
            "--out",
            &staged_arg,
        ],
    );
    assert!(status.success(), "{stderr}");
    let mut files: Vec<_> = std::fs::read_dir(&staged)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "png" || e == "tif"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 6, "{files:?}");
    let config = run.dir.join("real.toml");
    std::fs::write(
        &config,
        format!(
            "[run]\nstatus_interval_s = 0.5\ndashboard = \"off\"\n\
             [camera]\nwidth_px = 256\nheight_px = 256\nsource = \"watch\"\nwatch_dir = \"{}\"\n\
             watch_settle_ms = 200\n\
             [correlator]\nthreads = 1\n\
             [rig]\nsource = \"csv-follow\"\n\
             [rig.csv]\nfile = \"{}\"\ntime_column = \"t\"\nforce_x_column = \"F\"\n\
             time_unit = \"s\"\nforce_unit = \"N\"\nsection_x_mm2 = 40.0\nidle_timeout_s = 2.0\n",
            images.display(),
            csv.display()
        ),
    )
    .unwrap();
    let out = run.dir.join("out");
    start_run(&mut run, "run", &config, &out, &["--quiet"]);
    run.child("run").wait_line("run: rig ready");
    append(&csv, "t,F\n");
    let mut t = 0.0;
    for (k, file) in files.iter().enumerate() {
        if k == 3 {
            // One line the machine's software garbled: skipped, and counted in the summary.
            append(&csv, &format!("{t:.2},\"2,5\",x\n"));
        }
        // Rows at 100 Hz over a second, then the image of that moment, by rename.
        for _ in 0..100 {
            t += 0.01;
            append(&csv, &format!("{t:.2},{:.3}\n", 10.0 * t));
            std::thread::sleep(Duration::from_millis(10));
        }
        let ext = file.extension().unwrap().to_str().unwrap();
        let temporary = images.join(format!("img_{k:03}.{ext}.tmp"));
        std::fs::copy(file, &temporary).unwrap();
        std::fs::rename(&temporary, images.join(format!("img_{k:03}.{ext}"))).unwrap();
    }
    // A last second of rows, then the machine stops logging: the test is over.
    for _ in 0..100 {
        t += 0.01;
        append(&csv, &format!("{t:.2},{:.3}\n", 10.0 * t));
        std::thread::sleep(Duration::from_millis(10));
    }
    let (status, stdout, stderr) = run.child("run").wait();
    let s = summary(&out);
    assert_eq!(s["ending"], "completed", "{stdout}\n{stderr}");
    assert!(
        status.code() == Some(0) || status.code() == Some(2),
        "{stdout}\n{stderr}"
    );
    assert_eq!(s["faults"].as_array().map(Vec::len), Some(0), "{s}");
    assert_eq!(s["camera_source"], "watch");
    assert_eq!(s["machine_csv"]["malformed_lines"], 1, "{s}");
    assert_eq!(s["machine_csv"]["rows"], 700, "{s}");
    assert!(
        stderr.contains("run: 1 malformed line(s) of the machine's CSV skipped"),
        "{stderr}"
    );
    assert_eq!(s["frames_captured"], 6, "{s}");
    assert!(s["acceptance"].is_null(), "{s}");
    assert!(s["displacement_error_mean_px"].is_null(), "{s}");
    let text = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    for truth in [
        "disp_error_mean_px",
        "disp_error_max_px",
        "log_exx_error",
        "log_eyy_error",
    ] {
        assert!(!header.contains(&truth), "{truth} in {header:?}");
    }
    let rows = rows(&out.join("frames.csv"));
    assert!(rows.len() >= 5, "{} rows\n{stderr}", rows.len());
    // Forces from the machine's log, paired by time: a real test's rig state in every row.
    let force = header.iter().position(|c| *c == "force_x_n").unwrap();
    for r in &rows {
        assert_eq!(r.len(), header.len());
        let f: f64 = r[force].parse().unwrap_or_else(|_| panic!("{r:?}"));
        assert!(f > 0.0 && f <= 10.0 * t + 1e-9, "{r:?}");
    }
    assert!(out.join("watched_frames.csv").is_file());
}

#[test]
fn a_genicam_camera_the_binary_cannot_open_fails_the_run_at_start_and_says_why() {
    let mut run = Run::new("run_genicam_missing");
    let config = run.dir.join("genicam.toml");
    std::fs::write(
        &config,
        "[run]\ndashboard = \"off\"\n[camera]\nsource = \"genicam\"\nwidth_px = 256\n\
         height_px = 256\n[correlator]\nthreads = 1\n",
    )
    .unwrap();
    let out = run.dir.join("out");
    start_run(&mut run, "run", &config, &out, &["--quiet"]);
    let (status, stdout, stderr) = run.child("run").wait();
    // This test's binary may or may not have the genicam feature; with it, no camera is found
    // here (no network namespace with a fake camera): either way the run fails at start.
    assert_eq!(status.code(), Some(1), "{stdout}\n{stderr}");
    let s = summary(&out);
    assert_eq!(s["ending"], "failed");
    let failure = s["failure"].as_str().unwrap();
    assert!(
        failure.contains("producer") && failure.contains("genicam"),
        "{failure}"
    );
    assert_eq!(s["frames_captured"], 0);
}
