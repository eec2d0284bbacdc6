//! A run whose rig is on the other host (`[run] processes` without `rig`; its samples come over
//! `[link]`): the campaign is over when the rig's samples show its last test's program
//! finished, or, that one sample being lost on the way, when the last test's samples reached
//! the campaign's end in simulated time and then stopped (the rig exited); its exit, which ends
//! a one-host campaign, is not seen here. A campaign halted on the other host (a test's program
//! stopped by a limit, a command or an interlock: the rig waits there for its operator) is over
//! here once the rig's samples, the last of them showing the stop, stopped (the other host's
//! run ended): this run ends too, its verdict saying the campaign halted.

use super::open::{Phase, Run};
use crate::config::BenchProcess;
use std::time::{Duration, Instant};
use wire::RigState;

/// How long the rig's samples must have stopped, past the campaign's end, to take it as over.
const QUIET: Duration = Duration::from_secs(2);

/// The rig samples seen so far, and when their count last grew.
#[derive(Debug, Default)]
pub(crate) struct RemoteRig {
    seen: u64,
    since: Option<Instant>,
}

/// How the other host's campaign ended, as its rig's samples show it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Over {
    /// The last test's program finished.
    Finished,
    /// The last test's samples reached the campaign's end, then stopped.
    SamplesStopped,
    /// A test's program stopped before the campaign's end, then the samples stopped.
    Halted,
}

/// Whether the campaign of `tests` tests, `end_s` long in the rig's time, is over, the rig's
/// latest sample being `state` and its samples `quiet` (stopped for [`QUIET`]). A rig whose
/// samples stop mid-test (a link down, a rig restarting) is not over.
fn over(state: &RigState, tests: usize, end_s: f64, quiet: bool) -> Option<Over> {
    let program = |status| state.program_state == rig::codes::program_state(status);
    let last_test = state.test_index as usize + 1 >= tests;
    let past_end = state.t_sim_s >= end_s - 1.0;
    match () {
        _ if last_test && program(rig::ProgramStatus::Finished) => Some(Over::Finished),
        _ if last_test && past_end && quiet => Some(Over::SamplesStopped),
        _ if program(rig::ProgramStatus::Stopped) && quiet => Some(Over::Halted),
        _ => None,
    }
}

impl Run<'_> {
    /// Starts the drain when the other host's rig finished its campaign, or halted it and
    /// stopped.
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
        let Some(over) = over(&state, tests, end_s, quiet) else {
            return Ok(());
        };
        let at = format!("sample {}, t = {:.1} s", state.sample_id, state.t_sim_s);
        match over {
            Over::Finished => {
                eprintln!("run: the rig on the other host finished its last test ({at})")
            }
            Over::SamplesStopped => eprintln!(
                "run: the rig on the other host finished its last test ({at}, its samples \
                 stopped)"
            ),
            Over::Halted => {
                let halted = format!(
                    "the campaign halted on the other host: its rig's program stopped in test \
                     {} of {tests} (a limit, a command or an interlock; {at}) and its samples \
                     stopped there",
                    state.test_index + 1
                );
                eprintln!("run: {halted}; this host's part ends");
                self.incidents.campaign_halted = Some(halted);
            }
        }
        self.start_draining()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(test_index: u32, status: rig::ProgramStatus, t_sim_s: f64) -> RigState {
        RigState {
            test_index,
            program_state: rig::codes::program_state(status),
            t_sim_s,
            ..RigState::default()
        }
    }

    #[test]
    fn the_campaign_is_over_when_its_last_test_finished_or_its_samples_stopped_past_the_end() {
        use rig::ProgramStatus::{Finished, Running};
        assert_eq!(
            over(&state(1, Finished, 50.0), 2, 100.0, false),
            Some(Over::Finished)
        );
        // Test 1 of 2 finished: the next one starts.
        assert_eq!(over(&state(0, Finished, 50.0), 2, 100.0, true), None);
        assert_eq!(
            over(&state(1, Running, 99.5), 2, 100.0, true),
            Some(Over::SamplesStopped)
        );
        assert_eq!(over(&state(1, Running, 99.5), 2, 100.0, false), None);
        // Samples stopped mid-test (a link down): not over.
        assert_eq!(over(&state(1, Running, 40.0), 2, 100.0, true), None);
    }

    #[test]
    fn a_halted_campaign_is_over_once_the_rigs_samples_stopped() {
        use rig::ProgramStatus::{Held, Stopped};
        assert_eq!(
            over(&state(0, Stopped, 20.0), 3, 100.0, true),
            Some(Over::Halted)
        );
        // Halted, the rig still publishing (its operator may go on): not yet.
        assert_eq!(over(&state(0, Stopped, 20.0), 3, 100.0, false), None);
        // Held by an interlock is not stopped.
        assert_eq!(over(&state(0, Held, 20.0), 3, 100.0, true), None);
    }
}
