//! What a run says about itself from its start: `summary.json` is written before any child
//! starts, with `ending` = `running`, the start time, the pid of `dicstream run`, the instance
//! and the configuration, and replaced atomically by the final summary at the end (which
//! keeps these fields). A run killed outright (SIGKILL, a power cut) thus leaves a summary
//! saying it never finished, never an earlier run's verdict.

use crate::results::ResultsDir;
use serde::Serialize;
use std::path::PathBuf;

/// The start of a run, in `summary.json` from the start to the end.
#[derive(Clone, Debug, Serialize)]
pub struct RunStart {
    /// Start time, s since 1970-01-01 UTC.
    pub started_unix_s: f64,
    /// Start time, local `YYYY-MM-DD_HHMMSS`.
    pub started_local: String,
    /// The `dicstream run` process (a summary still `running` whose pid is gone: the run was
    /// killed).
    pub pid: u32,
    /// The configuration of the run (`dicstream run --config` on it reruns it).
    pub config: PathBuf,
    /// Where the earlier run found in the folder was moved (`--out` on a folder in use).
    pub previous_run_moved_to: Option<PathBuf>,
}

impl RunStart {
    /// The start of this run, now.
    pub fn now(results: &ResultsDir, previous_run_moved_to: Option<PathBuf>) -> RunStart {
        RunStart {
            started_unix_s: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64()),
            started_local: crate::results::local_timestamp(),
            pid: std::process::id(),
            config: results.config(),
            previous_run_moved_to,
        }
    }
}

/// `summary.json` while the run goes on (the sources as the final summary writes them).
#[derive(Serialize)]
struct Running<'a, C: Serialize + ?Sized, R: Serialize + ?Sized> {
    results: &'a std::path::Path,
    instance: &'a str,
    /// Always `running`: the final summary replaces this one.
    ending: &'static str,
    #[serde(flatten)]
    start: &'a RunStart,
    camera_source: &'a C,
    rig_source: &'a R,
}

/// Writes `summary.json` saying the run is going on (atomically, like the final one).
pub fn write_running<C: Serialize + ?Sized, R: Serialize + ?Sized>(
    results: &ResultsDir,
    instance: &str,
    start: &RunStart,
    camera_source: &C,
    rig_source: &R,
) -> anyhow::Result<()> {
    let running = Running {
        results: &results.root,
        instance,
        ending: "running",
        start,
        camera_source,
        rig_source,
    };
    wire::files::write_atomic(
        &results.summary_json(),
        serde_json::to_string_pretty(&running)?.as_bytes(),
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_running_summary_names_the_run_and_its_process() {
        let root = std::env::temp_dir().join(format!("start_test_{}", std::process::id()));
        let results = ResultsDir::at(&root).unwrap();
        let start = RunStart::now(&results, Some(root.join("previous-x")));
        write_running(&results, "run_1", &start, "simulated", "simulated").unwrap();
        let text = std::fs::read_to_string(results.summary_json()).unwrap();
        let s: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(s["ending"], "running");
        assert_eq!(s["pid"], std::process::id());
        assert_eq!(s["instance"], "run_1");
        assert!(s["started_unix_s"].as_f64().unwrap() > 1.7e9, "{s}");
        assert_eq!(s["config"], results.config().display().to_string());
        assert!(s["previous_run_moved_to"].is_string(), "{s}");
        std::fs::remove_dir_all(&root).unwrap();
    }
}
