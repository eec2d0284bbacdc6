//! `dicstream run` as a user runs it, with real processes on a unique instance: Ctrl-C; a
//! correlator slower than the camera (frames dropped and counted, never queued); bad
//! configurations refused at start. Faults (kills, stops, signals, a full disk) are in
//! `faults.rs`.
//! Waits poll result files with a hang guard; nothing asserts a wall-clock time.

use crate::common;

use common::bench_run::{child_pid, config, rows, start_run, summary, wait_rows, SHORT_CAMPAIGN};
use common::Run;
use std::path::Path;

#[test]
fn ctrl_c_stops_every_process_and_keeps_the_results() {
    let mut run = Run::new("run_ctrl_c");
    let config = config(&run, "", SHORT_CAMPAIGN);
    let out = run.dir.join("out");
    let parent = start_run(&mut run, "run", &config, &out, &[]);
    wait_rows(&out.join("frames.csv"), 0, 10);
    let children: Vec<i32> = ["rig", "producer", "correlator", "identifier"]
        .iter()
        .map(|role| child_pid(parent, role).expect("child"))
        .collect();
    run.child("run").signal(libc::SIGINT);
    let (status, stdout, stderr) = run.child("run").wait();
    // Exit 128 + SIGINT, as a shell reports an interrupted command.
    assert_eq!(status.code(), Some(130), "{stdout}\n{stderr}");
    assert!(stderr.contains("SIGINT received"), "{stderr}");
    assert_eq!(summary(&out)["ending"], "interrupted");
    assert_eq!(summary(&out)["exit_code"], 130);
    for pid in children {
        assert!(
            !Path::new(&format!("/proc/{pid}")).exists(),
            "child {pid} still runs"
        );
    }
    for file in ["frames.csv", "rig.csv", "config.toml", "latency.hgrm"] {
        assert!(out.join(file).is_file(), "{file} missing");
    }
    assert!(run.instance.leftover_files().is_empty());
}

#[test]
fn a_correlator_slower_than_the_camera_drops_frames_and_counts_them() {
    let mut run = Run::new("run_slow");
    // 512x512 at 30 frames/s with a 4-px step (over 15,000 ZOIs per frame) on one thread:
    // far more than the correlator can do.
    let config = config(
        &run,
        "",
        "[[rig.tests]]\nkind = \"uniaxial\"\nstretch = 1.2\nrate_per_s = 0.1\n",
    );
    let text = std::fs::read_to_string(&config)
        .unwrap()
        .replace(
            "width_px = 256\nheight_px = 256\nfps = 10.0",
            "width_px = 512\nheight_px = 512\nfps = 30.0",
        )
        .replace(
            "[correlator]\nthreads = 1",
            "[correlator]\nthreads = 1\nstep_px = 4",
        );
    std::fs::write(&config, text).unwrap();
    let out = run.dir.join("out");
    start_run(&mut run, "run", &config, &out, &["--quiet"]);
    let (status, stdout, stderr) = run.child("run").wait();
    let s = summary(&out);
    // Dropping frames is no fault; with so few fields the identification may fail or find
    // nothing, which makes the results doubtful (exit 2), and is said.
    let failure = s["failure"].as_str().unwrap_or("");
    assert!(
        status.code() == Some(0)
            || (status.code() == Some(2)
                && (failure.contains("acceptance") || failure.contains("nothing was identified"))),
        "{stdout}\n{stderr}"
    );
    assert_eq!(s["frames_lost_to_faults"], 0, "{s}");
    let captured = s["frames_captured"].as_u64().unwrap();
    let correlated = s["fields"].as_u64().unwrap();
    let dropped = s["frames_not_correlated"].as_u64().unwrap();
    eprintln!("captured {captured}, correlated {correlated}, dropped {dropped}");
    assert!(correlated > 0 && correlated < captured, "{s}");
    // Every frame is either correlated or counted as dropped (the last ones may still be on
    // their way when the camera stops).
    assert!(dropped > 0 && correlated + dropped <= captured, "{s}");
    // The correlator works on the newest frame: the ids it measured have gaps.
    let ids: Vec<u64> = rows(&out.join("frames.csv"))
        .iter()
        .map(|r| r[0].parse().unwrap())
        .collect();
    assert!(ids.windows(2).any(|w| w[1] > w[0] + 1), "{ids:?}");
}

#[test]
fn bad_configurations_are_refused_at_start_with_the_key_named() {
    let mut run = Run::new("run_bad_config");
    let cases = [
        ("[camera]\nwidht_px = 512\n", "widht_px"),
        (
            "[camera]\nwidth_px = 128\nheight_px = 128\n[correlator]\nzoi_px = 256\n",
            "larger than the ROI",
        ),
        (
            "[[rig.tests]]\nkind = \"uniaxial\"\nstretch = 7.0\nrate_per_s = 0.08\n",
            "stroke",
        ),
        (
            "[[rig.tests]]\nkind = \"equibiaxial\"\nstretch = 1.5\nrate_per_s = 50.0\n",
            "rate",
        ),
    ];
    for (k, (toml, expected)) in cases.iter().enumerate() {
        let path = run.dir.join(format!("bad{k}.toml"));
        std::fs::write(&path, toml).unwrap();
        let out = run.dir.join(format!("out{k}"));
        let (path_arg, out_arg) = (path.display().to_string(), out.display().to_string());
        let (status, _, stderr) = run.run_to_end(
            &format!("bad{k}"),
            &["run", "--config", &path_arg, "--out", &out_arg],
        );
        assert!(!status.success(), "{toml} was accepted");
        assert!(stderr.contains(expected), "{toml}: {stderr}");
        assert!(!out.exists(), "a refused run made its results folder");
    }
}

#[test]
fn a_dashboard_address_in_use_is_refused_before_anything_is_written() {
    let mut run = Run::new("run_port_in_use");
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let out = run.dir.join("out");
    let out_arg = out.display().to_string();
    let (status, _, stderr) =
        run.run_to_end("run", &["run", "--dashboard", &addr, "--out", &out_arg]);
    assert!(!status.success());
    assert!(
        stderr.contains(&addr) && stderr.contains("in use"),
        "{stderr}"
    );
    assert!(!out.exists(), "a refused run made its results folder");
}

/// `bench pipeline --json` prints the JSON alone on stdout (the run's own lines go to stderr).
#[test]
fn bench_pipeline_json_is_json_alone() {
    let mut run = Run::new("pipeline_json");
    let out = run.dir.join("bench").display().to_string();
    let (status, stdout, stderr) = run.run_to_end(
        "bench",
        &[
            "bench",
            "pipeline",
            "--width",
            "256",
            "--height",
            "256",
            "--fps",
            "10",
            "--seconds",
            "5",
            "--threads",
            "1",
            "--out",
            &out,
            "--json",
        ],
    );
    assert!(status.success(), "{stderr}");
    let json: serde_json::Value = serde_json::from_str(stdout.trim())
        .unwrap_or_else(|e| panic!("stdout is not JSON alone ({e}):\n{stdout}"));
    assert!(json["frames"].as_u64().is_some_and(|f| f > 0), "{json}");
    assert!(stderr.contains("run: results in"), "{stderr}");
}
