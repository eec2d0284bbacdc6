//! The rig process shell: runs the core in simulated time, paced to the wall clock (real time,
//! N× or as fast as possible), publishes `rig/state` (decimated, 500 Hz by default), answers
//! `rig/command` (request-response: accepted or refused with the reason) and writes `rig.csv`
//! as it goes. All IPC of the crate lives in this file; the core knows nothing of it.

use crate::builtin::TestError;
use crate::campaign::{Campaign, CampaignError};
use crate::codes;
use crate::config::RigConfig;
use crate::ids::{ActuatorId, Axis};
use crate::limits::LimitKind;
use crate::program::{Program, ProgramError};
use crate::refusal::Refusal;
use crate::rig::Rig;
use crate::session::SessionError;
use crate::specimen::SpecimenConfig;
use crate::strain::{ProgramEnd, StrainRunEvent, StrainTest};
use iceoryx2::prelude::*;
use std::path::{Path, PathBuf};
use wire::rig::RigState;

mod command;
mod from_settings;
pub use from_settings::RigProcessSettings;
mod resume;
mod shell;
mod specimen_port;

/// The rig's place on an instance, one for the simulated rig and the CSV follower: the claim
/// of the `rig` role (a second rig is refused), its node (dead nodes of the instance cleaned,
/// and said) and the `rig/state` publisher.
/// Fields drop in declaration order: the publisher, then the node, then the owner claim, and
/// the instance last, which removes iceoryx2's node counter once no node of it is left.
pub(crate) struct StatePort {
    pub publisher: wire::pubsub::ValuePublisher<RigState>,
    pub node: Node<ipc::Service>,
    pub _owner: wire::owner::Owner,
    pub instance: wire::Instance,
}

impl StatePort {
    pub fn open(instance_name: &str) -> Result<StatePort, wire::InstanceError> {
        let instance = wire::Instance::new(instance_name)?;
        let _owner = instance.claim("rig")?;
        let (node, removed) = instance.create_node("rig")?;
        if removed > 0 {
            eprintln!(
                "rig: cleaned {removed} dead node(s) of instance {}",
                instance.name()
            );
        }
        let publisher =
            wire::pubsub::ValuePublisher::<RigState>::create(&node, &wire::services::RIG_STATE)?;
        Ok(StatePort {
            instance,
            _owner,
            node,
            publisher,
        })
    }
}

/// Why the rig process could not start or stopped early. A file that could not be written and
/// a journal that cannot be followed are named as the error's `source()` too, so that
/// `wire::exit::code_of` finds the exit code they ask for.
#[derive(Debug, thiserror::Error)]
pub enum ProcessError {
    #[error("{name} {hz}: expected a rate in (0, {control_hz}] Hz")]
    Rate {
        name: &'static str,
        hz: f64,
        control_hz: f64,
    },
    #[error("a program and a campaign cannot run together: choose one")]
    ProgramAndCampaign,
    #[error("a strain-controlled test runs alone: no program or campaign with it")]
    StrainAndProgram,
    #[error("strain control follows the correlator's fields in real time: --speed max is refused (realtime or a factor)")]
    StrainAtMaxSpeed,
    #[error("strain-controlled test: {0}")]
    Strain(#[from] crate::strain::run::StrainRunError),
    #[error(transparent)]
    Campaign(#[from] CampaignError),
    #[error(transparent)]
    Session(#[from] SessionError),
    #[error("cannot create {}: {reason}", .path.display())]
    CreateDir {
        path: PathBuf,
        reason: std::io::Error,
    },
    #[error("stopped by {signal} while replaying {} (period {periods} of {of}): nothing was published or written", .journal.display())]
    ReplayStopped {
        /// The signal's name (SIGTERM, ...).
        signal: String,
        journal: PathBuf,
        periods: u64,
        of: u64,
    },
    /// The journal cannot be followed safely: exit code [`wire::exit::CANNOT_RESUME`].
    #[error("{0}")]
    CannotResume(#[source] wire::exit::ExitWith),
    #[error(transparent)]
    Instance(#[from] wire::InstanceError),
    /// An iceoryx2 port of `rig/command` could not be made or used.
    #[error("{port}: {detail}")]
    Command { port: &'static str, detail: String },
    #[error("{0}")]
    File(#[from] wire::files::FileError),
    #[error("stopped by {signal} at t = {t_s:.3} s, before the {what} finished{restart}")]
    Stopped {
        /// The signal's name (SIGTERM, ...).
        signal: String,
        t_s: f64,
        /// `campaign`, `program` or `strain-controlled test`.
        what: &'static str,
        /// What a restart does, in parentheses (empty without a journal).
        restart: String,
    },
}

impl ProcessError {
    /// An iceoryx2 error of the `rig/command` port `port`.
    fn command(port: &'static str, error: impl std::fmt::Debug) -> ProcessError {
        ProcessError::Command {
            port,
            detail: format!("{error:?}"),
        }
    }
}

/// Why a command over `rig/command` was refused (the reply carries the message).
#[derive(Debug, thiserror::Error)]
pub enum CommandRefused {
    #[error("layout version {found} is not {}", wire::LAYOUT_VERSION)]
    LayoutVersion { found: u32 },
    #[error("unknown command kind {kind}")]
    UnknownKind { kind: u32 },
    #[error("value is not a finite number")]
    NotFinite,
    #[error("channel {channel} is not an actuator (0..6)")]
    NotAnActuator { channel: u32 },
    #[error("channel {channel} is not an axis (0..3)")]
    NotAnAxis { channel: u32 },
    #[error("channel {channel} is not 0..12")]
    NotAChannel { channel: u32 },
    #[error("program {}: {reason}", .path.display())]
    ProgramUnreadable {
        path: PathBuf,
        reason: std::io::Error,
    },
    #[error(transparent)]
    Program(#[from] ProgramError),
    #[error("built-in test {value} is not 1 (uniaxial) or 2 (equibiaxial)")]
    UnknownTest { value: f64 },
    #[error("built-in test {test} needs its specimen; mounted: {}", .mounted.as_ref().map_or("none".into(), |loading| format!("a {loading} specimen")))]
    NeedsSpecimen {
        test: &'static str,
        /// The loading of the mounted specimen, if any.
        mounted: Option<String>,
    },
    #[error(transparent)]
    Test(#[from] TestError),
    #[error("mode code {code} is not 0..=4")]
    ModeCode { code: u32 },
    #[error("limit code {code} is not 0..=6")]
    LimitCode { code: u32 },
    #[error(transparent)]
    Rig(#[from] Refusal),
}

pub use crate::settings::Speed;

#[derive(Clone, Debug)]
pub struct ProcessOptions {
    pub instance: String,
    pub config: RigConfig,
    pub seed: u64,
    /// Started at once, if any.
    pub program: Option<Program>,
    /// Tests run one after the other (each mounts its specimen), if any; exclusive with
    /// `program`.
    pub campaign: Option<Campaign>,
    /// Stretch rate and level of the built-in tests started over `rig/command`.
    pub test_rate_per_s: f64,
    pub test_stretch: f64,
    pub speed: Speed,
    pub publish_hz: f64,
    pub log_path: Option<PathBuf>,
    pub log_hz: f64,
    /// Stop after this much simulated time.
    pub duration_s: Option<f64>,
    /// Stop once the program has finished or stopped.
    pub exit_when_done: bool,
    /// Folder of the resume journal (`rig.journal`): written as the rig runs, and followed by
    /// a restarted rig of the same settings, which goes on where it was.
    pub state_dir: Option<PathBuf>,
    /// A strain-controlled test (DIC closes the loop on the `fields` service), exclusive with
    /// `program` and `campaign`.
    pub strain: Option<StrainOptions>,
}

/// A strain-controlled test and the specimen it mounts (a cruciform).
#[derive(Clone, Debug)]
pub struct StrainOptions {
    pub test: StrainTest,
    pub specimen: SpecimenConfig,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct ProcessSummary {
    pub simulated_s: f64,
    pub wall_s: f64,
    pub samples_published: u64,
    pub rows_logged: u64,
    pub commands_accepted: u64,
    pub commands_refused: u64,
    pub limits_tripped: u32,
}

/// Runs the rig process until its campaign, program or duration ends or a termination
/// signal stops it (see [`shell::RigShell`]).
pub fn run(options: ProcessOptions) -> Result<ProcessSummary, ProcessError> {
    shell::RigShell::start(options)?.run()
}

/// Shared memory the rig's services need (bytes): `rig/state`, and `rig/command`, whose
/// requests and replies are small (a MiB covers iceoryx2's default clients and queues).
fn shm_needed_bytes() -> u64 {
    wire::services::RIG_STATE.shm_bytes(0, std::mem::size_of::<RigState>()) + (1 << 20)
}

/// The settings that make the simulation what it is, as a fingerprint (not the instance, the
/// log's path, the pacing or the stop conditions).
fn settings_fingerprint(options: &ProcessOptions) -> u64 {
    crate::journal::fingerprint(&format!(
        "{:?}|{}|{:?}|{:?}|{}|{}|{}|{}|{:?}",
        options.config,
        options.seed,
        options.program,
        options.campaign,
        options.test_rate_per_s,
        options.test_stretch,
        options.publish_hz,
        options.log_hz,
        options.strain
    ))
}

/// What a restart after a stop does, for the stop's message: a campaign or program resumes from
/// its journal; a strain-controlled test is never resumed ([`refuse_strain_resume`]).
fn restart_note(journal: Option<&Path>, strain: bool) -> String {
    match journal {
        None => String::new(),
        Some(path) if strain => format!(
            " (a restart with {} is refused: a strain-controlled test is not replayed; start a \
             new test with a new --state-dir)",
            path.display()
        ),
        Some(path) => format!(" (a restart resumes from {})", path.display()),
    }
}

/// What the strain test did, for stderr.
fn strain_message(event: &StrainRunEvent) -> String {
    match event {
        StrainRunEvent::Started { from_log } => format!(
            "strain control started from ln λ ({:.4}, {:.4})",
            from_log[0], from_log[1]
        ),
        StrainRunEvent::Waiting(reason) => {
            format!("strain control waits for a usable field, the grips held at rest: {reason}")
        }
        StrainRunEvent::Held(reason) => {
            format!("strain control HELD, the grips held in displacement: {reason}")
        }
        StrainRunEvent::Resumed => "strain control resumed: fields usable again".into(),
        StrainRunEvent::Unloading(end @ ProgramEnd::Stopped) => format!(
            "strain control {}: unloading in displacement control",
            end.describe()
        ),
        StrainRunEvent::Unloading(end) => format!(
            "strain program done, {}: unloading in displacement control",
            end.describe()
        ),
        StrainRunEvent::Finished => "strain-controlled test finished (unloaded)".into(),
    }
}

/// A strain-controlled rig does not resume: its inputs were the correlator's fields, which a
/// replay cannot have, so the journal of an earlier rig (if any) ends the restart (exit code
/// [`wire::exit::CANNOT_RESUME`]) and the specimen stays unloaded. No journal: a fresh start.
fn refuse_strain_resume(path: &Path) -> Result<(), ProcessError> {
    if !path.exists() {
        return Ok(());
    }
    Err(ProcessError::CannotResume(wire::exit::ExitWith {
        code: wire::exit::CANNOT_RESUME,
        message: format!(
            "cannot resume from {}: a strain-controlled test is not replayed (its inputs were \
             the correlator's fields); the specimen is left unloaded and the rig stopped; start \
             a new test with a new --state-dir",
            path.display()
        ),
    }))
}

/// The published sample. `command_mm` / `following_error_mm` carry kN for an actuator in
/// force control (its `mode` says which).
pub fn to_wire(rig: &Rig, sample_id: u64) -> RigState {
    let s = rig.state();
    let mut state = RigState {
        layout_version: wire::LAYOUT_VERSION,
        program_state: codes::program_state(s.program),
        sample_id,
        t_sim_s: s.t_s,
        t_published_ns: wire::monotonic_ns(),
        hydraulics_on: u32::from(s.hydraulics_on),
        specimen_stretch_x: s.specimen.stretch_x,
        specimen_stretch_y: s.specimen.stretch_y,
        specimen_rotation_rad: s.specimen.rotation_deg.to_radians(),
        specimen_centre_offset_mm: [s.specimen.centre_x_mm, s.specimen.centre_y_mm],
        load_case: codes::load_case(rig.specimen().map(|sp| sp.config().loading)),
        // Displacement control, no strain target, unless the session says otherwise.
        target_log_exx: f64::NAN,
        target_log_eyy: f64::NAN,
        ..RigState::default()
    };
    if let Some(specimen) = rig.specimen() {
        let [x, y] = specimen.current_sections_mm2(s.specimen.stretch_x, s.specimen.stretch_y);
        state.specimen_section_x_mm2 = x;
        state.specimen_section_y_mm2 = y;
    }
    for id in ActuatorId::ALL {
        let a = &s.actuators[id.index()];
        let flags = LimitKind::ALL
            .iter()
            .enumerate()
            .filter(|(_, kind)| s.limits_tripped & kind.bit(id.index()) != 0)
            .fold(0u32, |acc, (k, _)| acc | 1 << k);
        state.actuators[id.index()] = wire::ActuatorState {
            position_mm: a.position_mm,
            command_mm: a.command,
            following_error_mm: a.error,
            force_kn: a.force_kn,
            mode: codes::actuator_mode(s.axes[id.axis().index()].control, a.mode),
            limit_flags: flags,
        };
    }
    for axis in Axis::ALL {
        state.axis_centre_mm[axis.index()] = s.axes[axis.index()].centre_mm;
        state.axis_elongation_mm[axis.index()] = s.axes[axis.index()].elongation_mm;
    }
    state
}

#[cfg(test)]
mod tests {
    use super::restart_note;
    use std::path::Path;

    #[test]
    fn a_stop_says_what_a_restart_does() {
        let journal = Path::new("/r/rig.journal");
        assert_eq!(restart_note(None, false), "");
        assert_eq!(
            restart_note(Some(journal), false),
            " (a restart resumes from /r/rig.journal)"
        );
        let strain = restart_note(Some(journal), true);
        assert!(strain.contains("is refused"), "{strain}");
        assert!(!strain.contains("resumes"), "{strain}");
    }
}
