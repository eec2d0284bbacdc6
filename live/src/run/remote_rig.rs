//! A run whose rig is on the other host (`[run] processes` without `rig`; its samples come over
//! `[link]`): the campaign is over when the rig's own samples show its last test's program
//! finished, the sample the rig publishes before it exits (its exit, which ends a one-host
//! campaign, is not seen here).

use super::open::{Phase, Run};
use crate::config::BenchProcess;

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
        let tests = self.config().rig.tests.len();
        let Some(&state) = self.recorder.latest_rig() else {
            return Ok(());
        };
        if state.program_state == finished_code() && state.test_index as usize + 1 >= tests {
            eprintln!(
                "run: the rig on the other host finished its last test (sample {})",
                state.sample_id
            );
            self.start_draining()?;
        }
        Ok(())
    }
}
