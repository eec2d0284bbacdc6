//! `dicstream run`: the whole bench. Checks the configuration, makes the results folder,
//! starts identifier, correlator, producer and rig as child processes on a fresh instance
//! (each waited for until ready), watches every service from the monitor, prints a status
//! line once a second, handles deaths (reported, restarted if configured), stops everything
//! in order on completion or Ctrl-C, then writes the latency histograms, figures and
//! `summary.json`, and leaves nothing in `/dev/shm`.
//!
//! [`run`] reads as those steps: `prepare.rs` (instance claimed, results folder made), a
//! `Run` opened on them (`open.rs`: the children's supervisor, the monitor's ports, the
//! recorder, the dashboard, the loop's state), which starts the children (`launch.rs`),
//! watches them (`event_loop.rs`, `stale.rs`, `exits.rs`, `deaths.rs`, `drain.rs`) and stops
//! them (`stop.rs`); what is left is finished (`finish.rs`: `outputs.rs`, `judge.rs`,
//! `read_back.rs`, the ending from `verdict.rs`, `summary.json` as `report.rs`).

use crate::config::RunConfig;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Duration;

pub(crate) mod child_launch;
mod deaths;
mod drain;
mod event_loop;
mod exits;
mod finish;
mod judge;
mod launch;
mod link_report;
mod open;
mod outputs;
mod prepare;
mod read_back;
mod remote_rig;
mod report;
mod stale;
pub mod start;
mod stop;
mod verdict;

pub use child_launch::{
    child_launch, correlator_settings, identifier_settings, producer_settings, rig_settings,
    ChildLaunch,
};
pub use link_report::LinkReport;
pub use prepare::{remove_dead_runs, shm_needed_bytes};
pub use report::{NodeErrorReport, RunReport, StrainMapInfo};

/// What to run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub config: RunConfig,
    /// The `dicstream` binary the children run.
    pub exe: PathBuf,
    /// Instance name; default `run_<pid>`.
    pub instance: Option<String>,
    /// Results folder; default `<results_dir>/<date-time>/`.
    pub results: Option<PathBuf>,
    /// Print the status line (otherwise only the start and the end are printed).
    pub status: bool,
    /// The long status line (every figure) instead of one that fits 100 columns.
    pub verbose: bool,
}

/// How the run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Ending {
    /// The campaign ran to its end (`failure` then names what makes its results doubtful,
    /// if anything: acceptance not passed, frames lost to a fault, nothing identified).
    Completed,
    /// SIGINT, SIGTERM or SIGHUP (`failure` names it).
    Interrupted,
    /// A process died and could not be kept alive, a results file could not be written, or
    /// the bench could not start.
    Failed,
}

/// Exit codes of `dicstream run`, also written in `summary.json`.
pub mod exit_code {
    /// Completed, and the results are trustworthy.
    pub const PASSED: u8 = 0;
    /// Failed (see [`super::Ending::Failed`]).
    pub const FAILED: u8 = 1;
    /// Completed, but the acceptance was not passed, frames were lost to a fault, or nothing
    /// was identified.
    pub const DOUBTFUL: u8 = 2;
    /// Interrupted by signal N: 128 + N, as a shell reports it.
    pub const SIGNAL_BASE: u8 = 128;
}

/// Seconds a process gets to say it is ready.
const READY_TIMEOUT: Duration = Duration::from_secs(120);

/// Runs the bench to its end: the report, also written as `summary.json`. An error is a run
/// that could not start (nothing of it ran).
pub fn run(options: RunOptions) -> anyhow::Result<RunReport> {
    let prepared = prepare::Prepared::new(&options)?;
    let mut run = open::Run::open(&options, prepared)?;
    let result = run.supervise();
    run.stop(result).finish()
}
