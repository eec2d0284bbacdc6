//! `dicstream run` as a user runs it, with real processes on a unique instance: each of the
//! four processes killed with SIGKILL in turn while the others keep running (reported,
//! restarted, the correlator resuming from its state, the identifier rebuilding from its
//! journal, the camera continuing its frame ids); Ctrl-C; a correlator slower than the camera
//! (frames dropped and counted, never queued); bad configurations refused at start.
//! Waits poll result files with a hang guard; nothing asserts a wall-clock time.

mod common;

use common::{Run, HANG_GUARD};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// A small, quick bench: 256x256 frames, a short uniaxial then equibiaxial campaign.
fn config(run: &Run, extra: &str) -> PathBuf {
    let text = format!(
        "[run]\nresults_dir = \"{}\"\nstatus_interval_s = 0.5\n\
         [camera]\nwidth_px = 256\nheight_px = 256\nfps = 10.0\n\
         [correlator]\nthreads = 1\n\
         [rig]\npublish_hz = 100.0\nlog_hz = 20.0\n{extra}",
        run.dir.join("results").display()
    );
    let path = run.dir.join("bench.toml");
    std::fs::write(&path, text).unwrap();
    path
}

const SHORT_CAMPAIGN: &str =
    "[[rig.tests]]\nkind = \"uniaxial\"\nstretch = 1.5\nrate_per_s = 0.1\n\
     [[rig.tests]]\nkind = \"equibiaxial\"\nstretch = 1.3\nrate_per_s = 0.05\n";

/// Rows of `frames.csv` so far (0 if it does not exist yet).
fn rows(frames_csv: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(frames_csv)
        .unwrap_or_default()
        .lines()
        .skip(1)
        .filter(|l| l.ends_with(|c: char| c.is_ascii_digit()))
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// Waits (polling, bounded by the hang guard) until `frames.csv` has `count` more rows than
/// `after`; returns the new count.
fn wait_rows(frames_csv: &Path, after: usize, count: usize) -> usize {
    let give_up = Instant::now() + HANG_GUARD;
    loop {
        let n = rows(frames_csv).len();
        if n >= after + count {
            return n;
        }
        assert!(Instant::now() < give_up, "frames.csv stuck at {n} rows");
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// Pid of the `dicstream <role>` child of `parent`.
fn child_pid(parent: i32, role: &str) -> Option<i32> {
    for entry in std::fs::read_dir("/proc").ok()?.flatten() {
        let Ok(pid) = entry.file_name().to_string_lossy().parse::<i32>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
            continue;
        };
        let ppid: Option<i32> = stat
            .rsplit_once(')')
            .and_then(|(_, rest)| rest.split_whitespace().nth(1)?.parse().ok());
        let cmdline = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
        let args: Vec<&[u8]> = cmdline.split(|&b| b == 0).collect();
        if ppid == Some(parent) && args.get(1) == Some(&role.as_bytes()) {
            return Some(pid);
        }
    }
    None
}

/// Starts `dicstream run` with `config`, results into `out`, on the test's instance; returns
/// its pid.
fn start_run(run: &mut Run, config: &Path, out: &Path, extra: &[&str]) -> i32 {
    let (instance, config_arg, out_arg) = (
        run.name().to_string(),
        config.display().to_string(),
        out.display().to_string(),
    );
    let mut args = vec![
        "run",
        "--config",
        &config_arg,
        "--instance",
        &instance,
        "--out",
        &out_arg,
    ];
    args.extend_from_slice(extra);
    run.spawn("run", &args).pid()
}

fn kill9(pid: i32) {
    // SAFETY: signalling a process of this test's own tree.
    assert_eq!(
        unsafe { libc::kill(pid, libc::SIGKILL) },
        0,
        "kill -9 {pid}"
    );
}

fn results_folder(run: &Run) -> PathBuf {
    run.dir.join("out")
}

fn summary(folder: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(folder.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

#[test]
fn each_process_killed_in_turn_is_reported_restarted_and_the_run_completes() {
    let mut run = Run::new("run_faults");
    let config = config(&run, SHORT_CAMPAIGN);
    let out = results_folder(&run);
    let parent = start_run(&mut run, &config, &out, &[]);
    let frames_csv = out.join("frames.csv");
    let mut seen = wait_rows(&frames_csv, 0, 15);
    for role in ["correlator", "identifier", "producer", "rig"] {
        let pid = child_pid(parent, role).unwrap_or_else(|| panic!("no {role} child"));
        kill9(pid);
        let line = run.child("run").wait_for_stderr("the death report", |l| {
            l.contains(&format!("{role} (pid {pid}) died: killed by signal 9"))
        });
        eprintln!("{line}");
        // The others kept going, the dead one is back: fields keep coming.
        seen = wait_rows(&frames_csv, seen, 10);
        let again = child_pid(parent, role).expect("restarted");
        assert_ne!(again, pid, "{role} restarted with a new pid");
    }
    let (status, stdout, stderr) = run.child("run").wait();
    assert!(status.success(), "run failed:\n{stdout}\n{stderr}");
    let s = summary(&out);
    assert_eq!(s["ending"], "completed", "{s}");
    let restarts = s["restarts"].as_array().unwrap();
    assert_eq!(restarts.len(), 4, "{restarts:?}");
    for (note, role) in restarts
        .iter()
        .zip(["correlator", "identifier", "producer", "rig"])
    {
        assert!(note.as_str().unwrap().starts_with(role), "{note}");
    }
    // The correlator resumed from its saved reference; the identifier from its journal.
    let log =
        |role: &str| std::fs::read_to_string(out.join("logs").join(format!("{role}.log"))).unwrap();
    assert!(
        log("correlator").contains("resumed"),
        "{}",
        log("correlator")
    );
    assert!(
        log("identifier").contains("rebuilt the load path"),
        "{}",
        log("identifier")
    );
    // The restarted camera continued the frame ids: they only go up.
    let ids: Vec<u64> = rows(&frames_csv)
        .iter()
        .map(|r| r[0].parse().unwrap())
        .collect();
    assert!(
        ids.windows(2).all(|w| w[1] > w[0]),
        "ids went back: {ids:?}"
    );
    assert!(s["acceptance"]["a"]
        .as_array()
        .is_some_and(|a| !a.is_empty()));
    // The supervisor removed every file of its instance, iceoryx2's node counter included.
    assert!(
        run.instance.leftover_files().is_empty(),
        "{:?}",
        run.instance.leftover_files()
    );
}

#[test]
fn ctrl_c_stops_every_process_and_keeps_the_results() {
    let mut run = Run::new("run_ctrl_c");
    let config = config(&run, SHORT_CAMPAIGN);
    let out = results_folder(&run);
    let parent = start_run(&mut run, &config, &out, &[]);
    wait_rows(&out.join("frames.csv"), 0, 10);
    let children: Vec<i32> = ["rig", "producer", "correlator", "identifier"]
        .iter()
        .map(|role| child_pid(parent, role).expect("child"))
        .collect();
    run.child("run").signal(libc::SIGINT);
    let (status, stdout, stderr) = run.child("run").wait();
    assert!(status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("interrupted"), "{stdout}");
    assert_eq!(summary(&out)["ending"], "interrupted");
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
    let out = results_folder(&run);
    start_run(&mut run, &config, &out, &["--quiet"]);
    let (status, stdout, stderr) = run.child("run").wait();
    assert!(status.success(), "{stdout}\n{stderr}");
    let s = summary(&out);
    let captured = s["frames_captured"].as_u64().unwrap();
    let correlated = s["fields"].as_u64().unwrap();
    let dropped = s["frames_dropped_by_correlator"].as_u64().unwrap();
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
