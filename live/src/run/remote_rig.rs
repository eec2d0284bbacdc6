//! A run whose rig is on the other host (`[run] processes` without `rig`; its samples come over
//! `[link]`): the campaign is over when the rig's samples show its last test's program
//! finished, or, that one sample being lost on the way, when the last test's samples reached
//! the campaign's end in simulated time and then stopped (the rig exited); its exit, which ends
//! a one-host campaign, is not seen here.

use super::open::{Phase, Run};
use crate::config::BenchProcess;
use std::time::{Duration, Instant};

/// How long the rig's samples must have stopped, past the campaign's end, to take it as over.
const QUIET: Duration = Duration::from_secs(2);

/// The rig samples seen so far, and when their count last grew.
#[derive(Debug, Default)]
pub(crate) struct RemoteRig {
    seen: u64,
    since: Option<Instant>,
}

/// `RigState::program_state` of a finished program.
fn finished_code() -> u32 {
    rig::codes::program_state(rig::ProgramStatus::Finished)
}

impl Run<'_> {
    /// Starts the drain when the other host's rig finished its campaign.
    pub(super) fn follow_remote_rig(&mut self) -> anyhow::Result<()> {
        if self.config().runs(BenchProcess::Rig) || !matches!(self.phase, Phase::Running) {
            return Ok(());
        }
        let seen = self.recorder.rig_samples_seen;
        if seen != self.remote_rig.seen || self.remote_rig.since.is_none() {
            self.remote_rig = RemoteRig {
                seen,
                since: Some(Instant::now()),
            };
        }
        let quiet = self.remote_rig.since.is_some_and(|t| t.elapsed() >= QUIET);
        let tests = self.config().rig.tests.len();
        // The campaign's length in the rig's simulated time.
        let end_s = self.config().campaign_wall_s()? * self.config().rig.speed;
        let Some(&state) = self.recorder.latest_rig() else {
            return Ok(());
        };
        let last_test = state.test_index as usize + 1 >= tests;
        let finished = state.program_state == finished_code();
        let past_end = state.t_sim_s >= end_s - 1.0;
        if last_test && (finished || (past_end && quiet)) {
            eprintln!(
                "run: the rig on the other host finished its last test (sample {}, t = {:.1} s{})",
                state.sample_id,
                state.t_sim_s,
                if finished {
                    ""
                } else {
                    ", its samples stopped"
                }
            );
            self.start_draining()?;
        }
        Ok(())
    }
}
