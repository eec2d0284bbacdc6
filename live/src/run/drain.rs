//! The end of a campaign: the camera is stopped, the correlator finishes the last frames (or
//! its time runs out), then the identifier refits on the last points and is stopped.

use super::open::{Phase, Run};
use crate::children::Role;
use std::time::{Duration, Instant};

/// Longest wait for the correlator and identifier to finish the last frames.
const DRAIN_TIMEOUT: Duration = Duration::from_secs(10);
/// The identifier's time for its last fits once the correlator has stopped.
const LAST_FITS: Duration = Duration::from_millis(500);
/// The least the identifier gets between its stop and its kill at the drain: it waits for the
/// field route's running fit and fits the last frames before it writes the run's law (one fit
/// of every model over the kept frames took 3.5 s on average and 7.4 s at most on a loaded
/// 2-core machine, `tests/field_route.rs`; up to 19.7 s with two hosts' runs on one machine).
const FINAL_FITS: Duration = Duration::from_secs(60);

impl Run<'_> {
    /// The rig ended its campaign: the camera stops, the drain starts.
    pub(super) fn start_draining(&mut self) -> anyhow::Result<()> {
        eprintln!("run: campaign finished; stopping the camera, finishing the last frames");
        self.supervisor.stop(Role::Producer, self.stop_timeout());
        self.subscriptions.drain(&mut self.recorder)?;
        self.phase = Phase::Draining {
            since: Instant::now(),
            last_frame: self.recorder.last_frame_id,
        };
        Ok(())
    }

    /// Whether the drain is over: the correlator caught up with the last frame (or ran out of
    /// time) and was stopped, then the identifier after its last fits.
    pub(super) fn drained(&mut self) -> anyhow::Result<bool> {
        let Phase::Draining { since, last_frame } = self.phase else {
            return Ok(false);
        };
        let caught_up = match (last_frame, self.recorder.last_field) {
            (Some(frame), Some(field)) => field.frame_id >= frame,
            (None, _) => true,
            _ => false,
        };
        if !caught_up && since.elapsed() <= DRAIN_TIMEOUT {
            return Ok(false);
        }
        if !caught_up {
            eprintln!("run: the correlator did not finish the last frames in time");
        }
        self.stop_in_drain(Role::Correlator, self.stop_timeout());
        // The identifier refits on the last points, then writes its final fits.
        let quiet_since = Instant::now();
        while quiet_since.elapsed() < LAST_FITS {
            std::thread::sleep(Duration::from_millis(50));
            self.subscriptions.drain(&mut self.recorder)?;
        }
        self.stop_in_drain(Role::Identifier, self.stop_timeout().max(FINAL_FITS));
        self.subscriptions
            .drain_all(&mut self.recorder, super::stop::FINAL_DRAIN_ROUNDS)?;
        Ok(true)
    }

    /// Stops `role` within `timeout`, noting it if it had to be killed.
    fn stop_in_drain(&mut self, role: Role, timeout: Duration) {
        if let Some(how) = self.supervisor.stop(role, timeout) {
            super::stop::say_stopped(role, &how, &mut self.killed_in_drain);
        }
    }
}
