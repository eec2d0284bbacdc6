//! The rig process restarted from its journal (`dicstream rig --state-dir`) over what a user
//! or a fault left: a log cut mid-row or deleted (the missing rows written again from the
//! replay, the log then byte for byte that of a run never stopped), another run's log
//! (refused untouched), a journal that cannot be read or whose figures no run could have
//! written (refused at once, exit 75), a long replay stopped by SIGTERM, and a full `/dev/shm`
//! (refused before anything is created). Real processes on a unique instance; timeouts only
//! guard against a hang.

use crate::common;

use common::Run;
use std::path::{Path, PathBuf};
use std::process::ExitStatus;

/// The campaign the rig runs (a few seconds of simulated time, at full speed).
const CAMPAIGN: &str = "uniaxial:1.3@0.1";

/// `dicstream rig` on the test's instance with the campaign, at full speed, journalling in
/// `state`, logging to `log` (if any), then `extra`; started as `rig`.
fn spawn_rig<'r>(
    run: &'r mut Run,
    state: &Path,
    log: Option<&Path>,
    extra: &[&str],
) -> &'r mut common::Proc {
    let mut args: Vec<String> = ["rig", "--instance", run.name(), "--campaign", CAMPAIGN]
        .iter()
        .map(|s| s.to_string())
        .collect();
    args.extend(["--speed".into(), "max".into(), "--state-dir".into()]);
    args.push(state.display().to_string());
    if let Some(log) = log {
        args.extend(["--log".into(), log.display().to_string()]);
    }
    args.extend(extra.iter().map(|s| s.to_string()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    run.spawn("rig", &args)
}

/// [`spawn_rig`] ending when the campaign is done (`extra` after), run to its end: its exit
/// status and stderr.
fn rig(run: &mut Run, state: &Path, log: Option<&Path>, extra: &[&str]) -> (ExitStatus, String) {
    let extra: Vec<&str> = std::iter::once("--exit-when-done")
        .chain(extra.iter().copied())
        .collect();
    let (status, _, stderr) = spawn_rig(run, state, log, &extra).wait();
    (status, stderr)
}

/// A run stopped at `t_s` of the campaign, logging or not: its journal's folder and its log,
/// in the scratch folder `label`.
fn stopped_at(run: &mut Run, label: &str, t_s: &str, logged: bool) -> (PathBuf, PathBuf) {
    let dir = run.temp_dir(label);
    let (state, log) = (dir.join("state"), dir.join("rig.csv"));
    let log_arg = logged.then_some(log.as_path());
    let (status, stderr) = rig(run, &state, log_arg, &["--duration-s", t_s]);
    assert!(status.success(), "{stderr}");
    (state, log)
}

fn journal_text(state: &Path) -> String {
    std::fs::read_to_string(state.join("rig.journal")).unwrap()
}

/// `text` with the value of `key` replaced by `value`.
fn with_value(text: &str, key: &str, value: &str) -> String {
    text.lines()
        .map(|l| match l.split_once('=') {
            Some((k, _)) if k.trim() == key => format!("{key} = {value}"),
            _ => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

#[test]
fn a_cut_or_deleted_log_is_written_again_and_another_log_refused() {
    let mut run = Run::new("rig_resume_cut_log");
    // The log of a campaign run to its end without a stop.
    let whole = run.temp_dir("whole");
    let full_log = whole.join("rig.csv");
    let (status, stderr) = rig(&mut run, &whole.join("state"), Some(&full_log), &[]);
    assert!(status.success(), "{stderr}");
    let full = std::fs::read(&full_log).unwrap();

    // Cut mid-row: the rows the cut lost and the torn one come back from the replay.
    let (state, log) = stopped_at(&mut run, "cut", "2.5", true);
    let held = std::fs::read(&log).unwrap();
    let mut cut = held.len() / 2;
    if held[cut - 1] == b'\n' {
        cut += 1;
    }
    std::fs::write(&log, &held[..cut]).unwrap();
    let (status, stderr) = rig(&mut run, &state, Some(&log), &[]);
    assert!(status.success(), "{stderr}");
    assert!(
        stderr.contains("rig.csv held") && stderr.contains("torn"),
        "{stderr}"
    );
    assert!(
        std::fs::read(&log).unwrap() == full,
        "the resumed log is not the uninterrupted run's"
    );

    // Deleted: written again whole.
    let (state, log) = stopped_at(&mut run, "deleted", "2.5", true);
    std::fs::remove_file(&log).unwrap();
    let (status, stderr) = rig(&mut run, &state, Some(&log), &[]);
    assert!(status.success(), "{stderr}");
    assert!(stderr.contains("rig.csv was missing"), "{stderr}");
    assert!(
        std::fs::read(&log).unwrap() == full,
        "the regenerated log is not the uninterrupted run's"
    );

    // Another log (two rows swapped): refused, exit 75, the file untouched.
    let (state, log) = stopped_at(&mut run, "other", "2.5", true);
    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    lines.swap(3, 4);
    let other = lines.join("\n") + "\n";
    std::fs::write(&log, &other).unwrap();
    let (status, stderr) = rig(&mut run, &state, Some(&log), &[]);
    assert_eq!(status.code(), Some(75), "{stderr}");
    assert!(
        stderr.contains("rig.csv: it is not this run's log: its line 4 differs")
            && stderr.contains(&format!("it holds {} rows", lines.len() - 1))
            && stderr.contains("move it aside"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(&log).unwrap(), other);
}

#[test]
fn a_journal_that_cannot_be_read_is_refused_with_exit_75() {
    let mut run = Run::new("rig_resume_unreadable");
    let state = run.temp_dir("state");
    std::fs::write(state.join("rig.journal"), b"periods = \xff\xfe\n").unwrap();
    let (status, stderr) = rig(&mut run, &state, None, &[]);
    assert_eq!(status.code(), Some(75), "{stderr}");
    assert!(
        stderr.contains("rig.journal: not UTF-8 text (byte 10)"),
        "{stderr}"
    );

    std::fs::remove_file(state.join("rig.journal")).unwrap();
    std::fs::create_dir(state.join("rig.journal")).unwrap();
    let (status, stderr) = rig(&mut run, &state, None, &[]);
    assert_eq!(status.code(), Some(75), "{stderr}");
    assert!(
        stderr.contains("rig.journal: cannot read it: Is a directory"),
        "{stderr}"
    );
}

#[test]
fn an_absurd_periods_count_is_refused_at_once_and_a_long_replay_ends_on_sigterm() {
    let mut run = Run::new("rig_resume_periods");
    let (state, _) = stopped_at(&mut run, "periods", "0.2", false);
    let journal = journal_text(&state);

    // periods edited alone: it does not fit the journal's steps.
    let periods = 1_000_000_000_000u64;
    let edited = with_value(&journal, "periods", &periods.to_string());
    std::fs::write(state.join("rig.journal"), &edited).unwrap();
    let (status, stderr) = rig(&mut run, &state, None, &[]);
    assert_eq!(status.code(), Some(75), "{stderr}");
    assert!(
        stderr.contains("periods = 1000000000000 times the 10 control steps")
            && !stderr.contains("replaying"),
        "{stderr}"
    );

    // A journal whose figures fit, 6 years of simulated time on: a rig that ends when done
    // cannot have run past its campaign, refused once the replay gets there.
    let step = periods * 10;
    let t_s = step as f64 * (1.0 / 5000.0);
    let consistent = with_value(
        &with_value(&edited, "step", &step.to_string()),
        "t_s_bits",
        &format!("{:016x}", t_s.to_bits()),
    );
    std::fs::write(state.join("rig.journal"), &consistent).unwrap();
    let (status, stderr) = rig(&mut run, &state, None, &[]);
    assert_eq!(status.code(), Some(75), "{stderr}");
    assert!(
        stderr.contains("the replay ended the campaign after"),
        "{stderr}"
    );

    // A rig that runs on once done could have: the replay goes on until SIGTERM ends it.
    let rig = spawn_rig(&mut run, &state, None, &[]);
    rig.wait_line("replaying 1000000000000 periods");
    rig.signal(libc::SIGTERM);
    let (status, _, stderr) = rig.wait();
    assert_eq!(status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("stopped by SIGTERM while replaying"),
        "{stderr}"
    );
    assert_eq!(journal_text(&state), consistent, "the journal untouched");
}

/// `/dev/shm` a one-page tmpfs (in a mount namespace of the test's own): the restarted rig
/// refuses before creating a service, naming `/dev/shm`, instead of dying of SIGBUS.
#[test]
fn a_restart_without_room_in_dev_shm_is_refused() {
    let mut run = Run::new("rig_resume_shm");
    let (state, _) = stopped_at(&mut run, "shm", "0.2", false);
    let script = format!(
        "mount -t tmpfs -o size=4k tmpfs /dev/shm && exec {exe} rig --instance {instance} \
         --campaign {CAMPAIGN} --speed max --exit-when-done --state-dir {state}",
        exe = env!("CARGO_BIN_EXE_dicstream"),
        instance = run.name(),
        state = state.display(),
    );
    let Some(outcome) = common::namespace::run_in_mount_namespace(&script) else {
        return;
    };
    let stderr = String::from_utf8_lossy(&outcome.stderr);
    assert_eq!(outcome.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("/dev/shm has"), "{stderr}");
}
