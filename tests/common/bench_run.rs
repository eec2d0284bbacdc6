//! `dicstream run` as the multi-process tests drive it: a small, quick configuration, the
//! results it leaves (`frames.csv` rows, `summary.json`), its children's pids, and the check
//! that a run's results are consistent whatever fault it met.

use super::{Run, HANG_GUARD};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// A campaign of a few seconds: uniaxial then equibiaxial.
pub const SHORT_CAMPAIGN: &str =
    "[[rig.tests]]\nkind = \"uniaxial\"\nstretch = 1.5\nrate_per_s = 0.1\n\
     [[rig.tests]]\nkind = \"equibiaxial\"\nstretch = 1.3\nrate_per_s = 0.05\n";

/// A small, quick bench (256x256 frames at 10 frames/s, one correlator thread, the
/// homogeneous sheet unless `extra` has a `[specimen]` of its own) with `extra` appended
/// (more keys of its own sections, or `[[rig.tests]]`).
pub fn config(run: &Run, run_keys: &str, extra: &str) -> PathBuf {
    // The tests of faults, files and viewers run on the analytic sheet, light and judged by
    // its gauge; the structure's own tests (structure_run.rs, field_route.rs) name theirs.
    // Last: `extra` may start with keys of `[rig]`.
    let specimen = match extra.contains("[specimen]") {
        true => "",
        false => "[specimen]\nmodel = \"homogeneous\"\n",
    };
    let text = format!(
        "[run]\nresults_dir = \"{}\"\nstatus_interval_s = 0.5\n{run_keys}\n\
         [camera]\nwidth_px = 256\nheight_px = 256\nfps = 10.0\n\
         [correlator]\nthreads = 1\n\
         [rig]\npublish_hz = 100.0\nlog_hz = 20.0\n{extra}\n{specimen}",
        run.dir.join("results").display()
    );
    let path = run.dir.join("bench.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// Rows of `frames.csv` so far (0 if it does not exist yet).
pub fn rows(frames_csv: &Path) -> Vec<Vec<String>> {
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
pub fn wait_rows(frames_csv: &Path, after: usize, count: usize) -> usize {
    let give_up = Instant::now() + HANG_GUARD;
    loop {
        let n = rows(frames_csv).len();
        if n >= after + count {
            return n;
        }
        assert!(Instant::now() < give_up, "frames.csv stuck at {n} rows");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Pid of the `dicstream <role>` child of `parent`.
pub fn child_pid(parent: i32, role: &str) -> Option<i32> {
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

/// Waits (bounded) for a `role` child of `parent` other than `not`.
pub fn wait_child(parent: i32, role: &str, not: Option<i32>) -> i32 {
    let give_up = Instant::now() + HANG_GUARD;
    loop {
        if let Some(pid) = child_pid(parent, role).filter(|&p| Some(p) != not) {
            return pid;
        }
        assert!(Instant::now() < give_up, "no new {role} child");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Starts `dicstream run` with `config`, results into `out`, on the test's instance; returns
/// its pid.
pub fn start_run(run: &mut Run, name: &str, config: &Path, out: &Path, extra: &[&str]) -> i32 {
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
    run.spawn(name, &args).pid()
}

#[allow(unused_imports)]
pub use testkit::signal;

/// Waits for the `run` child that [`start_run`] started and reads its `summary.json` from
/// `out`: the run must have completed, passed (0) or with doubtful results (2: on a
/// heterogeneous field the gauge route's acceptance fails, frames lost to a fault); with the
/// run's stdout.
pub fn completed_summary(run: &mut Run, out: &Path) -> (serde_json::Value, String) {
    let (status, stdout, stderr) = run.child("run").wait();
    assert!(
        matches!(status.code(), Some(0 | 2)),
        "{status:?}\n{stdout}\n{stderr}"
    );
    (summary(out), stdout)
}

pub fn summary(folder: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(folder.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

/// Whole CSV rows: every row has the header's column count and the file ends with a newline.
pub fn whole_rows(path: &Path) -> Result<Vec<Vec<String>>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if !text.is_empty() && !text.ends_with('\n') {
        return Err(format!("{}: torn last row", path.display()));
    }
    let mut lines = text.lines();
    let columns = lines.next().map_or(0, |h| h.split(',').count());
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    if let Some((k, row)) = rows.iter().enumerate().find(|(_, r)| r.len() != columns) {
        return Err(format!(
            "{}: row {} has {} columns, the header {columns}",
            path.display(),
            k + 2,
            row.len()
        ));
    }
    Ok(rows)
}

/// Checks what a run left in `out` (`fields_every` = the configuration's), whatever its
/// ending: `frames.csv` whole, ids increasing and as many as `summary.json` says; every field
/// file among them; `rig.csv` whole and continuous in time (no step longer than 2 log
/// periods, never back); `identification.json` JSON; no temporary or empty file. Returns a
/// one-line description for the fault table.
pub fn check_consistency(out: &Path, fields_every: u64, log_hz: f64) -> Result<String, String> {
    let s = summary(out);
    let frames = whole_rows(&out.join("frames.csv"))?;
    let ids: Vec<u64> = frames.iter().map(|r| r[0].parse().unwrap()).collect();
    if let Some(w) = ids.windows(2).find(|w| w[1] <= w[0]) {
        return Err(format!("frames.csv ids go back: {} then {}", w[0], w[1]));
    }
    if s["fields"].as_u64() != Some(ids.len() as u64) {
        return Err(format!(
            "summary says {} fields, frames.csv has {} rows",
            s["fields"],
            ids.len()
        ));
    }
    for entry in std::fs::read_dir(out.join("fields")).unwrap().flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let id: u64 = name
            .trim_start_matches("field_")
            .split('.')
            .next()
            .and_then(|n| n.parse().ok())
            .ok_or(format!("fields/{name}: not a field file"))?;
        if !ids.contains(&id) || !id.is_multiple_of(fields_every) {
            return Err(format!("fields/{name} is not a row of frames.csv"));
        }
    }
    // A run interrupted before the rig started has no rig.csv.
    let rig_csv = out.join("rig.csv");
    let rig = match rig_csv.exists() || s["ending"] == "completed" {
        true => whole_rows(&rig_csv)?,
        false => Vec::new(),
    };
    let t: Vec<f64> = rig.iter().map(|r| r[0].parse().unwrap()).collect();
    if let Some(w) = t
        .windows(2)
        .find(|w| !(w[1] > w[0] && w[1] - w[0] <= 2.0 / log_hz + 1e-6))
    {
        return Err(format!("rig.csv jumps from t = {} to {} s", w[0], w[1]));
    }
    let identification = out.join("identification.json");
    if identification.exists() {
        let text = std::fs::read_to_string(&identification).unwrap();
        serde_json::from_str::<serde_json::Value>(&text)
            .map_err(|e| format!("identification.json: {e}"))?;
    }
    if let Some(stray) = stray_file(out) {
        return Err(format!("{} left behind", stray.display()));
    }
    Ok(format!(
        "consistent: {} fields, ids increasing, rig.csv 0-{:.1} s continuous",
        ids.len(),
        t.last().copied().unwrap_or(0.0)
    ))
}

/// A temporary or empty file under `out` (logs may be empty), if any.
pub fn stray_file(out: &Path) -> Option<PathBuf> {
    let mut stack = vec![out.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap().flatten() {
            let path = entry.path();
            let meta = entry.metadata().unwrap();
            let name = entry.file_name().to_string_lossy().into_owned();
            if meta.is_dir() {
                stack.push(path);
            } else if name.contains(".tmp") || (meta.len() == 0 && !name.ends_with(".log")) {
                return Some(path);
            }
        }
    }
    None
}
