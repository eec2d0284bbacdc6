//! Fault injection on `dicstream run`, with real processes and a short campaign: kill -9 of
//! each child at three moments and of two children in a row, SIGSTOP/SIGCONT of each child
//! (short, and past the stale time) and of `run`, SIGINT at 1 ms, 100 ms and mid-run, SIGHUP,
//! SIGINT with a dashboard viewer that never reads, a second `run` on the same instance,
//! kill -9 of a run over an earlier run's folder, too few file descriptors, a full disk. Each
//! ends either "completed" with exit 0 and consistent results, or with a non-zero exit whose
//! `summary.json` names what failed (with results still consistent), and leaves nothing of its
//! instance in `/dev/shm` or iceoryx2's folder. Every case prints a row of the fault table
//! (`--nocapture` shows them). No wall-clock assertion: waits are on result files, bounded by
//! the hang guard.

use crate::common;

use common::bench_run::{
    check_consistency, child_pid, config, signal, start_run, stray_file, summary, wait_child,
    wait_rows, whole_rows, SHORT_CAMPAIGN,
};
use common::{dashboard_address, Run};
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::ExitStatus;
use std::time::Duration;

const FIELDS_EVERY: u64 = 10;
const LOG_HZ: f64 = 20.0;
/// `[run] stale_after_s` of these runs: a child stopped longer is killed and restarted.
const STALE_S: f64 = 2.0;

/// The run keys of every case: the rig twice real time (a campaign of about 9 s), a short stale
/// time.
fn run_keys() -> String {
    format!("stale_after_s = {STALE_S}")
}

fn bench(run: &Run) -> std::path::PathBuf {
    config(run, &run_keys(), &format!("speed = 2.0\n{SHORT_CAMPAIGN}"))
}

/// How the run ended, for the table and the checks.
struct Outcome {
    exit: Option<i32>,
    signal: Option<i32>,
    ending: String,
    failure: String,
    consistency: String,
}

/// Waits for the run, checks its results and its instance's files, prints the table row.
fn finish(run: &mut Run, name: &str, fault: &str, out: &Path) -> Outcome {
    let (status, stdout, stderr) = run.child(name).wait();
    let outcome = judge(status, out, &stdout, &stderr);
    let leftovers = run.instance.leftover_files();
    assert!(
        leftovers.is_empty(),
        "{fault}: files of the instance left: {leftovers:?}"
    );
    eprintln!(
        "| {fault} | {}{} | {} | {} |",
        outcome.ending,
        if outcome.failure.is_empty() || outcome.ending == "no results" {
            String::new()
        } else {
            format!(": {}", outcome.failure)
        },
        match (outcome.exit, outcome.signal) {
            (Some(code), _) => code.to_string(),
            (None, Some(signal)) => format!("killed by signal {signal}"),
            _ => "?".into(),
        },
        outcome.consistency
    );
    outcome
}

fn judge(status: ExitStatus, out: &Path, stdout: &str, stderr: &str) -> Outcome {
    if !out.join("summary.json").exists() {
        return Outcome {
            exit: status.code(),
            signal: status.signal(),
            ending: "no results".into(),
            failure: stderr.to_string(),
            consistency: "nothing written".into(),
        };
    }
    let s = summary(out);
    let consistency = check_consistency(out, FIELDS_EVERY, LOG_HZ)
        .unwrap_or_else(|e| panic!("inconsistent results: {e}\n{stdout}\n{stderr}"));
    let outcome = Outcome {
        exit: status.code(),
        signal: status.signal(),
        ending: s["ending"].as_str().unwrap().to_string(),
        failure: s["failure"].as_str().unwrap_or("").to_string(),
        consistency,
    };
    assert_eq!(
        status.code(),
        s["exit_code"].as_i64().map(|c| c as i32),
        "the exit code is the summary's\n{stdout}\n{stderr}"
    );
    // Completed with exit 0, or a non-zero exit that names what failed.
    if outcome.exit == Some(0) {
        assert_eq!(outcome.ending, "completed", "{s}");
        assert!(outcome.failure.is_empty(), "{s}");
    } else {
        assert!(!outcome.failure.is_empty(), "no failure named: {s}");
    }
    outcome
}

/// kill -9 of `role` once `frames.csv` has `after_rows` rows; the run goes on with it restarted.
fn kill_child(role: &str, after_rows: usize) {
    let mut run = Run::new(&format!("kill_{role}_{after_rows}"));
    let config = bench(&run);
    let out = run.dir.join("out");
    let parent = start_run(&mut run, "run", &config, &out, &["--quiet"]);
    wait_rows(&out.join("frames.csv"), 0, after_rows);
    let Some(pid) = child_pid(parent, role) else {
        // The campaign was over already (the rig, then the camera, have ended).
        let o = finish(&mut run, "run", &format!("kill -9 {role} too late"), &out);
        assert_eq!(o.ending, "completed");
        return;
    };
    signal(pid, libc::SIGKILL);
    let o = finish(
        &mut run,
        "run",
        &format!("kill -9 {role} after {after_rows} fields"),
        &out,
    );
    let s = summary(&out);
    assert!(
        s["faults"].as_array().unwrap().iter().any(|f| f
            .as_str()
            .unwrap()
            .starts_with(&format!("{role} killed by signal 9"))),
        "{s}"
    );
    assert_ne!(o.ending, "interrupted", "{s}");
    // The restarted process went on from its state: the rig where it was, the correlator
    // from its saved reference, the identifier from its journal.
    let log = std::fs::read_to_string(out.join(format!("logs/{role}.log"))).unwrap();
    let resumed = match role {
        "rig" => Some("resumed at t ="),
        "correlator" => Some("resumed"),
        "identifier" if after_rows >= 30 => Some("rebuilt the load path"),
        _ => None,
    };
    if let Some(line) = resumed.filter(|_| o.ending == "completed") {
        assert!(log.contains(line), "{log}");
    }
    if o.exit != Some(0) {
        // Only what a fault really costs: frames lost while the correlator was dead, or an
        // identification that the lost data made fail.
        assert!(
            o.failure.contains("lost to faults") || o.failure.contains("acceptance"),
            "{}",
            o.failure
        );
    }
}

#[test]
fn kill_rig_early() {
    kill_child("rig", 3);
}
#[test]
fn kill_rig_mid() {
    kill_child("rig", 35);
}
#[test]
fn kill_rig_late() {
    kill_child("rig", 75);
}
#[test]
fn kill_producer_early() {
    kill_child("producer", 3);
}
#[test]
fn kill_producer_mid() {
    kill_child("producer", 35);
}
#[test]
fn kill_producer_late() {
    kill_child("producer", 75);
}
#[test]
fn kill_correlator_early() {
    kill_child("correlator", 3);
}
#[test]
fn kill_correlator_mid() {
    kill_child("correlator", 35);
}
#[test]
fn kill_correlator_late() {
    kill_child("correlator", 75);
}
#[test]
fn kill_identifier_early() {
    kill_child("identifier", 3);
}
#[test]
fn kill_identifier_mid() {
    kill_child("identifier", 35);
}
#[test]
fn kill_identifier_late() {
    kill_child("identifier", 75);
}

/// The rig killed, then the correlator as soon as the new rig's pid appears (while the
/// supervisor waits for the new rig to be ready): both deaths are handled.
#[test]
fn kill_rig_then_correlator_during_its_restart() {
    let mut run = Run::new("kill_two");
    let config = bench(&run);
    let out = run.dir.join("out");
    let parent = start_run(&mut run, "run", &config, &out, &["--quiet"]);
    wait_rows(&out.join("frames.csv"), 0, 20);
    let rig = child_pid(parent, "rig").expect("rig");
    let correlator = child_pid(parent, "correlator").expect("correlator");
    signal(rig, libc::SIGKILL);
    wait_child(parent, "rig", Some(rig));
    signal(correlator, libc::SIGKILL);
    let o = finish(&mut run, "run", "kill -9 rig, then correlator", &out);
    let s = summary(&out);
    let restarts: Vec<&str> = s["restarts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_str().unwrap())
        .collect();
    assert!(
        restarts.iter().any(|r| r.starts_with("rig"))
            && restarts.iter().any(|r| r.starts_with("correlator")),
        "{restarts:?}"
    );
    assert_ne!(o.ending, "interrupted");
    // Fields kept coming after both restarts.
    assert!(s["fields"].as_u64().unwrap() > 40, "{s}");
}

/// SIGSTOP of `role` for `pause`, then SIGCONT.
fn stop_child(role: &str, pause: Duration) {
    let mut run = Run::new(&format!("stop_{role}_{}", pause.as_millis()));
    let config = bench(&run);
    let out = run.dir.join("out");
    let parent = start_run(&mut run, "run", &config, &out, &["--quiet"]);
    wait_rows(&out.join("frames.csv"), 0, 20);
    let pid = child_pid(parent, role).expect("child");
    signal(pid, libc::SIGSTOP);
    std::thread::sleep(pause);
    let _ = unsafe { libc::kill(pid, libc::SIGCONT) };
    let stale = pause.as_secs_f64() > STALE_S + 1.0;
    let o = finish(
        &mut run,
        "run",
        &format!("STOP/CONT {role} for {:.1} s", pause.as_secs_f64()),
        &out,
    );
    let s = summary(&out);
    let faults = s["faults"].as_array().unwrap();
    assert_ne!(o.ending, "interrupted", "{s}");
    if stale {
        assert!(
            faults.iter().any(|f| f.as_str().unwrap().contains("stale")),
            "{s}"
        );
        assert_eq!(s["restarts"].as_array().unwrap().len(), 1, "{s}");
    } else {
        // A pause shorter than the stale time is no fault and no stop.
        assert!(faults.is_empty(), "{s}");
        assert_eq!(o.ending, "completed", "{s}");
    }
}

#[test]
fn stop_each_child_briefly() {
    for role in ["rig", "producer", "correlator", "identifier"] {
        stop_child(role, Duration::from_millis(800));
    }
}
#[test]
fn stop_rig_past_the_stale_time() {
    stop_child("rig", Duration::from_secs(4));
}
#[test]
fn stop_producer_past_the_stale_time() {
    stop_child("producer", Duration::from_secs(4));
}
#[test]
fn stop_correlator_past_the_stale_time() {
    stop_child("correlator", Duration::from_secs(4));
}
#[test]
fn stop_identifier_past_the_stale_time() {
    stop_child("identifier", Duration::from_secs(4));
}

#[test]
fn stop_and_continue_run_itself() {
    let mut run = Run::new("stop_run");
    let config = bench(&run);
    let out = run.dir.join("out");
    let parent = start_run(&mut run, "run", &config, &out, &["--quiet"]);
    wait_rows(&out.join("frames.csv"), 0, 20);
    signal(parent, libc::SIGSTOP);
    std::thread::sleep(Duration::from_secs(3));
    signal(parent, libc::SIGCONT);
    let o = finish(&mut run, "run", "STOP/CONT run for 3 s", &out);
    assert_ne!(o.ending, "interrupted");
    assert!(summary(&out)["faults"].as_array().unwrap().is_empty());
}

/// A termination signal after `delay` (or once `rows` fields are in): the run stops, exit
/// 128 + N, results kept; at 1 ms it may come before the handlers exist (killed by it, nothing
/// written, nothing left).
fn terminate(signal_number: i32, delay: Duration, rows: usize) {
    let name = format!("sig{signal_number}_{}_{rows}", delay.as_micros());
    let mut run = Run::new(&name);
    let config = bench(&run);
    let out = run.dir.join("out");
    let parent = start_run(&mut run, "run", &config, &out, &["--quiet"]);
    std::thread::sleep(delay);
    if rows > 0 {
        wait_rows(&out.join("frames.csv"), 0, rows);
    }
    signal(parent, signal_number);
    let o = finish(
        &mut run,
        "run",
        &format!(
            "signal {signal_number} after {}",
            if rows > 0 {
                format!("{rows} fields")
            } else {
                format!("{} ms", delay.as_millis())
            }
        ),
        &out,
    );
    match o.signal {
        Some(s) => {
            assert_eq!(s, signal_number);
            assert_eq!(o.ending, "no results");
        }
        None => {
            assert_eq!(o.exit, Some(128 + signal_number), "{}", o.failure);
            assert_eq!(o.ending, "interrupted");
        }
    }
}

#[test]
fn sigint_at_1_ms() {
    terminate(libc::SIGINT, Duration::from_millis(1), 0);
}
#[test]
fn sigint_at_100_ms() {
    terminate(libc::SIGINT, Duration::from_millis(100), 0);
}
#[test]
fn sigint_mid_run() {
    terminate(libc::SIGINT, Duration::ZERO, 30);
}
#[test]
fn sighup_mid_run() {
    terminate(libc::SIGHUP, Duration::ZERO, 30);
}

/// A viewer of the run's dashboard that pipelines requests and never reads (issue 29: a laptop
/// asleep behind `ssh -L`): SIGINT still ends the run, with its results, while it is connected.
#[test]
fn sigint_with_a_stalled_dashboard_viewer() {
    let mut run = Run::new("stalled_viewer");
    let config = bench(&run);
    let out = run.dir.join("out");
    let dashboard = ["--quiet", "--dashboard", "127.0.0.1:0"];
    let parent = start_run(&mut run, "run", &config, &out, &dashboard);
    let line = run
        .child("run")
        .wait_for_stderr("dashboard URL", |l| l.contains("http://"));
    let stalled = testkit::stalled_client(&dashboard_address(&line), "/app.js", 600);
    wait_rows(&out.join("frames.csv"), 0, 30);
    signal(parent, libc::SIGINT);
    let o = finish(
        &mut run,
        "run",
        "SIGINT with a stalled dashboard viewer",
        &out,
    );
    assert_eq!(o.exit, Some(130), "{}", o.failure);
    assert_eq!(o.ending, "interrupted");
    drop(stalled);
}

/// `--out` on a folder holding an earlier completed run, then kill -9 of the new run: the
/// earlier run was moved aside whole, and the folder's `summary.json` says the new run is
/// `running` (its pid), never the earlier verdict beside the new data.
#[test]
fn a_run_over_an_earlier_one_moves_it_aside_and_says_running_when_killed() {
    let mut run = Run::new("out_reused");
    let config = bench(&run);
    let out = run.dir.join("out");
    std::fs::create_dir_all(out.join("fields")).unwrap();
    let earlier = r#"{"ending": "completed", "exit_code": 0, "fields": 285}"#;
    std::fs::write(out.join("summary.json"), earlier).unwrap();
    std::fs::write(out.join("config.toml"), "# the earlier run\n").unwrap();
    std::fs::write(out.join("fields/field_999990.csv"), "x\n").unwrap();
    let pid = start_run(&mut run, "run", &config, &out, &["--quiet"]);
    wait_rows(&out.join("frames.csv"), 0, 10);
    signal(pid, libc::SIGKILL);
    let (status, _, stderr) = run.child("run").wait();
    assert_eq!(status.signal(), Some(libc::SIGKILL), "{stderr}");
    let s = summary(&out);
    assert_eq!(s["ending"], "running", "{s}");
    assert_eq!(s["pid"], pid, "{s}");
    let aside = PathBuf::from(s["previous_run_moved_to"].as_str().expect("moved aside"));
    assert!(
        stderr.contains(&format!("its files were moved into {}", aside.display())),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_to_string(aside.join("summary.json")).unwrap(),
        earlier
    );
    assert!(aside.join("fields/field_999990.csv").exists());
    assert!(!out.join("fields/field_999990.csv").exists());
    eprintln!(
        "| kill -9 of a run over an earlier one | running (pid {pid}) | killed by signal 9 | \
         earlier run in {} |",
        aside.display()
    );
}

/// File descriptors each process of these runs may open (`ulimit -n`): too few for the
/// identifier's connection to the correlator's fields (issue 29: the run then ended "nothing
/// was identified" with `faults: []`, the error only in the identifier's log).
const FEW_DESCRIPTORS: u32 = 64;

/// `dicstream run` under `ulimit -n 64`: a process whose subscriber cannot connect, or that
/// cannot open a results file, stops with exit code 71 naming the descriptors and their limit, and the run fails naming it in
/// `faults`, not restarted.
#[test]
fn too_few_file_descriptors_are_a_fault_naming_the_process_and_the_limit() {
    let run = Run::new("few_descriptors");
    let config = bench(&run);
    let out = run.dir.join("out");
    let (status, stdout, stderr) = run_with_descriptors(&run, &config, &out, FEW_DESCRIPTORS);
    assert_eq!(status.code(), Some(1), "{stdout}\n{stderr}");
    let s = summary(&out);
    assert_eq!(s["ending"], "failed", "{s}");
    let faults: Vec<&str> = s["faults"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    let fault = faults
        .iter()
        .find(|f| f.ends_with("exit status 71"))
        .unwrap_or_else(|| panic!("no process ended for its descriptors: {s}"));
    // Which process runs out first, and whether at a connection ("cannot connect to a
    // publisher of") or at a results file ("cannot write", or "cannot read" for the
    // identifier's journal), depends on the machine's iceoryx2
    // segments: both say the same of the descriptors.
    let failure = s["failure"].as_str().unwrap();
    assert!(
        [
            "cannot connect to a publisher of",
            "cannot write",
            "cannot read",
            "cannot open",
            "cannot create"
        ]
        .iter()
        .any(|what| failure.contains(what)),
        "{failure}"
    );
    for part in [
        "file descriptors exhausted",
        &format!("of the limit {FEW_DESCRIPTORS} (RLIMIT_NOFILE"),
        "not restarted",
    ] {
        assert!(failure.contains(part), "{part:?} not in {failure}");
    }
    assert!(
        run.instance.leftover_files().is_empty(),
        "{:?}",
        run.instance.leftover_files()
    );
    eprintln!("| ulimit -n {FEW_DESCRIPTORS} | failed: {fault} | 1 | named in faults |");
    // Fewer still: the run's own monitor cannot open a service (24) or create its node (6),
    // and says why at start.
    for descriptors in [24, 6] {
        let out = run.dir.join(format!("out_{descriptors}"));
        let (status, stdout, stderr) = run_with_descriptors(&run, &config, &out, descriptors);
        assert_eq!(status.code(), Some(1), "{stdout}\n{stderr}");
        assert!(
            stderr.contains("file descriptors exhausted")
                && stderr.contains(&format!("of the limit {descriptors} (RLIMIT_NOFILE")),
            "{stderr}"
        );
        assert!(
            !out.join("summary.json").exists(),
            "a run that never started"
        );
        eprintln!(
            "| ulimit -n {descriptors} | refused at start, naming the descriptors | 1 | nothing \
             written |"
        );
    }
}

/// `dicstream run` on `config` with at most `descriptors` open file descriptors per process.
fn run_with_descriptors(
    run: &Run,
    config: &Path,
    out: &Path,
    descriptors: u32,
) -> (ExitStatus, String, String) {
    let mut command = std::process::Command::new("sh");
    command.args([
        "-c",
        &format!("ulimit -n {descriptors} && exec \"$0\" \"$@\""),
        env!("CARGO_BIN_EXE_dicstream"),
        "run",
        "--config",
        &config.display().to_string(),
        "--instance",
        run.name(),
        "--out",
        &out.display().to_string(),
        "--quiet",
        // The run's own dashboard would need descriptors of the run's process too.
        "--no-dashboard",
    ]);
    common::Proc::spawn("run", command).wait()
}

#[test]
fn a_second_run_on_the_same_instance_is_refused_naming_the_first() {
    let mut run = Run::new("two_runs");
    let config = bench(&run);
    let out = run.dir.join("out");
    let first = start_run(&mut run, "first", &config, &out, &["--quiet"]);
    wait_rows(&out.join("frames.csv"), 0, 5);
    let second_out = run.dir.join("second");
    start_run(&mut run, "second", &config, &second_out, &["--quiet"]);
    let (status, _, stderr) = run.child("second").wait();
    assert_eq!(status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!("already has a run (pid {first})")),
        "{stderr}"
    );
    assert!(!second_out.exists(), "the refused run wrote results");
    eprintln!("| second run on the instance | refused | 1 | nothing written |");
    let o = finish(&mut run, "first", "(the first run, meanwhile)", &out);
    assert_eq!(o.ending, "completed");
    assert!(summary(&out)["faults"].as_array().unwrap().is_empty());
}

/// `--out` on a small tmpfs (mounted in a mount namespace of the test's own): the first
/// failed write stops the run, naming the file; every row before is whole; no temporary or
/// empty file is left.
#[test]
fn a_full_disk_stops_the_run_naming_the_file() {
    let run = Run::new("full_disk");
    let config = bench(&run);
    let small = run.dir.join("small");
    std::fs::create_dir_all(&small).unwrap();
    let out = small.join("out");
    // The tmpfs goes with the namespace: what the run left is copied out before.
    let copy = run.dir.join("copy");
    let script = format!(
        "mount -t tmpfs -o size=300k tmpfs {small} && {exe} run --config {config} --instance {instance} \
         --out {out} --quiet; rc=$?; cp -a {out} {copy}; exit $rc",
        small = small.display(),
        exe = env!("CARGO_BIN_EXE_dicstream"),
        config = config.display(),
        instance = run.name(),
        out = out.display(),
        copy = copy.display(),
    );
    let Some(outcome) = common::namespace::run_in_mount_namespace(&script) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&outcome.stderr);
    let stdout = String::from_utf8_lossy(&outcome.stdout);
    assert_eq!(outcome.status.code(), Some(1), "{stdout}\n{stderr}");
    assert!(
        stderr.contains("No space left on device") && stderr.contains(&*out.to_string_lossy()),
        "{stderr}"
    );
    // Whole rows, no temporary or empty file.
    for file in ["frames.csv", "rig.csv"] {
        whole_rows(&copy.join(file)).unwrap_or_else(|e| panic!("{e}"));
    }
    if let Some(stray) = stray_file(&copy) {
        panic!("{} left behind", stray.display());
    }
    assert!(
        run.instance.leftover_files().is_empty(),
        "{:?}",
        run.instance.leftover_files()
    );
    let named = stderr
        .lines()
        .find(|l| l.contains("No space left on device"))
        .unwrap_or("");
    eprintln!(
        "| full disk (--out on a 300 KiB tmpfs) | failed | 1 | whole rows, no stray file; \"{}\" |",
        named.trim()
    );
}
