//! The start of the children: consumers first, each waited for until it says it is ready.

use super::open::Run;
use super::READY_TIMEOUT;
use crate::children::{Role, StoppedBeforeReady};
use crate::config::{BenchProcess, CameraSource, RunConfig};

/// The link first (what comes from the other host is there when the others start), then the
/// consumers, so that nothing the rig and the camera publish is missed.
const START_ORDER: [Role; Role::COUNT] = [
    Role::Link,
    Role::Identifier,
    Role::Correlator,
    Role::Producer,
    Role::Rig,
];

/// Whether the run starts `role`: the processes of `[run] processes` (all four by default), and
/// the link when `[link]` asks.
pub(super) fn starts(role: Role, config: &RunConfig) -> bool {
    let process = match role {
        Role::Rig => BenchProcess::Rig,
        Role::Producer => BenchProcess::Producer,
        Role::Correlator => BenchProcess::Correlator,
        Role::Identifier => BenchProcess::Identifier,
        Role::Link => return config.link_started_by_run(),
    };
    config.runs(process)
}

/// Whether the run waits for `role` to say it is ready before going on: a watched folder's
/// camera is ready only at its first image (which sets the frame size), which may come long
/// after the start; the run goes on at once and handles its exit like any other.
pub(super) fn waits_for_ready(role: Role, config: &RunConfig) -> bool {
    !(role == Role::Producer && config.camera.source == CameraSource::Watch)
}

impl Run<'_> {
    /// Starts every child, each waited for until ready. False when a termination signal came
    /// first (the children started so far are stopped by [`Run::stop`]).
    pub(super) fn start_children(&mut self) -> anyhow::Result<bool> {
        for role in START_ORDER {
            if wire::signals::requested().is_some() {
                return Ok(false);
            }
            if !starts(role, self.config()) {
                continue;
            }
            let args = self.child_args(role, 0)?;
            self.supervisor.spawn(role, args)?;
            let waits = waits_for_ready(role, self.config());
            if waits && !self.wait_ready_at_start(role)? {
                return Ok(false);
            }
            let pid = self.supervisor.pid(role).unwrap_or(0);
            match waits {
                true => eprintln!("run: {} ready (pid {pid})", role.name()),
                false => eprintln!(
                    "run: {} started (pid {pid}); ready at its first image",
                    role.name()
                ),
            }
        }
        // An exit while a later child was starting is kept by the supervisor: handled first
        // thing by the event loop.
        Ok(true)
    }

    /// Waits for `role` to be ready at the start of the run; a GenICam camera that cannot be
    /// opened says what may be missing.
    fn wait_ready_at_start(&mut self, role: Role) -> anyhow::Result<bool> {
        let ready = self.supervisor.wait_ready(role, READY_TIMEOUT);
        // A child that ended before it was ready is a fault of the run, named as a death is,
        // and an exit a restart would repeat (no descriptors, say) says so.
        let ready = ready.map_err(|e| match e.downcast_ref::<StoppedBeforeReady>() {
            Some(StoppedBeforeReady(exit)) => {
                self.incidents
                    .faults
                    .push(format!("{} {}", exit.role.name(), exit.how));
                match super::deaths::not_restarted_why(exit.code) {
                    Some(why) => anyhow::anyhow!("{e}\n({why})"),
                    None => e,
                }
            }
            None => e,
        });
        match (role, self.config().camera.source) {
            (Role::Producer, CameraSource::Genicam) => ready.map_err(|e| {
                e.context(
                    "[camera] source = \"genicam\": the camera could not be opened (a \
                     dicstream built without `--features genicam` says so above)",
                )
            }),
            _ => ready,
        }
    }
}
