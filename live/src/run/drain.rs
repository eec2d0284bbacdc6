//! The end of a campaign: the camera is stopped, the correlator finishes the last frames (or
//! its time runs out), then the identifier refits on the last points and is stopped.

use super::open::{Phase, Run};
use crate::children::Role;
use std::time::{Duration, Instant};

/// Longest wait for the correlator and identifier to finish the last frames.
const DRAIN_TIMEOUT: Duration = Duration::from_secs(10);
/// The identifier's time for its last fits once the correlator has stopped.
const LAST_FITS: Duration = Duration::from_millis(500);

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
        self.supervisor.stop(Role::Correlator, self.stop_timeout());
        // The identifier refits on the last points, then writes its final fits.
        let quiet_since = Instant::now();
        while quiet_since.elapsed() < LAST_FITS {
            std::thread::sleep(Duration::from_millis(50));
            self.subscriptions.drain(&mut self.recorder)?;
        }
        self.supervisor.stop(Role::Identifier, self.stop_timeout());
        self.subscriptions
            .drain_all(&mut self.recorder, super::stop::FINAL_DRAIN_ROUNDS)?;
        Ok(true)
    }
}
