//! The exits of the children as the loop finds them: the rig's success ends the campaign, the
//! camera stopped on purpose or out of images is expected, any other exit is a death.

use super::event_loop::interrupted;
use super::open::{Phase, Run};
use super::Ending;
use crate::children::{Exit, Role};
use crate::config::CameraSource;

impl Run<'_> {
    /// Handles every exit noticed since the last look (in order); the ending when a
    /// termination signal came while a dead child was handled.
    pub(super) fn handle_exits(&mut self) -> anyhow::Result<Option<Ending>> {
        for exit in self.supervisor.take_exits() {
            if self.expected(&exit)? {
                continue;
            }
            self.subscriptions.drain(&mut self.recorder)?;
            if exit.role == Role::Correlator {
                self.recorder.correlator_ended();
            }
            self.handle_death(exit)?;
            if let Some(signal) = wire::signals::requested() {
                return Ok(Some(interrupted(signal)));
            }
            // The restarted child is watched afresh (the others too: the restart paused them).
            self.watch_all_from_now();
        }
        Ok(None)
    }

    /// Whether `exit` is part of the run's course, not a death: the campaign's end (which
    /// starts the drain), the camera stopped for it, a real camera out of images.
    fn expected(&mut self, exit: &Exit) -> anyhow::Result<bool> {
        let campaign_done = exit.role == Role::Rig && exit.success;
        if campaign_done && matches!(self.phase, Phase::Running) {
            self.start_draining()?;
            return Ok(true);
        }
        if matches!(self.phase, Phase::Draining { .. }) && exit.role == Role::Producer {
            // Stopped on purpose when the drain started.
            return Ok(true);
        }
        let camera = self.config().camera.source;
        if exit.role == Role::Producer && exit.success && camera != CameraSource::Simulated {
            // A replay at its last image, a watched folder idle for its timeout.
            eprintln!(
                "run: the camera ({camera}) has no more images; waiting for the rig to finish"
            );
            return Ok(true);
        }
        Ok(false)
    }
}
