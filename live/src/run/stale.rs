//! The run's watch on its children ([`crate::liveness`] fed with what the monitor saw): a
//! child stopped or silent for the stale time is killed, and handled like a death.

use super::open::Run;
use crate::children::Role;
use crate::config::{CameraSource, RigSource, RunConfig};
use crate::liveness::{Counts, Liveness};
use std::time::{Duration, Instant};

/// The watch of a run's children, before any is watched.
pub(super) fn liveness(config: &RunConfig) -> Liveness {
    let mut liveness = Liveness::new(Duration::from_secs_f64(config.run.stale_after_s));
    // A real camera publishes when images come, a machine's log when rows come: their
    // silence is the test's pace, not a hang (a stopped process is still caught).
    if config.camera.source != CameraSource::Simulated {
        liveness.ignore_silence(Role::Producer);
    }
    if config.rig.source == RigSource::CsvFollow {
        liveness.ignore_silence(Role::Rig);
    }
    liveness
}

impl Run<'_> {
    /// The samples seen so far per service, for the liveness watch.
    fn counts(&mut self) -> Counts {
        Counts {
            rig_states: self.recorder.rig_samples_seen,
            frames: self.recorder.frames_seen,
            fields: self.recorder.fields_seen,
            identifier_heard_fields: self.supervisor.heard_input(Role::Identifier),
        }
    }

    /// Watches every child afresh from now (at the start, and after a restart, which paused
    /// the others too); a process this host does not run (`[run] processes`) is not watched.
    pub(super) fn watch_all_from_now(&mut self) {
        let started: Vec<Role> = Role::ALL
            .into_iter()
            .filter(|&r| self.supervisor.started(r))
            .collect();
        for role in started {
            let counts = self.counts();
            self.liveness.reset(role, &counts, Instant::now());
        }
    }

    /// Kills the children that are stale: their exits are handled like deaths (reported,
    /// restarted if configured).
    pub(super) fn kill_stale(&mut self) {
        let counts = self.counts();
        let supervisor = &self.supervisor;
        let stopped = |role| {
            supervisor
                .pid(role)
                .is_some_and(crate::children::process_stopped)
        };
        for (role, why) in self.liveness.check(&counts, stopped, Instant::now()) {
            self.supervisor.kill(role, &format!("stale: {why}"));
        }
    }
}
