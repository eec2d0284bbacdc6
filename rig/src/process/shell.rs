//! `RigShell`, the rig process as it runs: its options, the session, the ports (`rig/state`,
//! `rig/command`, `fields` for strain control), the log and the journal, and the pacing. One
//! loop turn is one publication period: commands, the newest field, the period, its
//! publication, a flush every 50 ms, the pacing.

use super::specimen_port::{self, SpecimenPort};
use super::{
    command::handle, refuse_strain_resume, restart_note, resume, settings_fingerprint,
    shm_needed_bytes, strain_message, to_wire, ProcessError, ProcessOptions, ProcessSummary, Speed,
    StatePort,
};
use crate::campaign::CampaignEvent;
use crate::session::{PeriodEvent, Session};
use crate::strain::FieldClock;
use iceoryx2::prelude::*;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use wire::files::RowFile;
use wire::rig::{RigReply, RigState};

/// The `rig/command` server.
type CommandServer =
    iceoryx2::port::server::Server<ipc::Service, wire::RigCommand, (), RigReply, ()>;
/// The `fields` subscriber of a strain-controlled test.
type FieldSubscriber = wire::pubsub::SliceSubscriber<wire::FieldNode, wire::FieldHeader>;

/// The wall clock following simulated time.
struct Pacing {
    started: Instant,
    /// The wall time and simulated time (s) pacing counts from.
    paced_from: (Instant, f64),
    /// The last period ran at full speed (pacing restarts from the next paced one).
    was_max: bool,
}

/// The rig process: everything `run` owns while it runs.
pub(super) struct RigShell {
    options: ProcessOptions,
    /// The fingerprint of the settings the journal records.
    settings: u64,
    session: Session,
    journal_path: Option<PathBuf>,
    // Ports on the node drop before it (fields drop in declaration order): `port` last.
    server: CommandServer,
    fields: Option<FieldSubscriber>,
    /// The structure's solved states on `specimen`.
    specimen: SpecimenPort,
    port: StatePort,
    field_clock: FieldClock,
    log: Option<RowFile>,
    /// Log rows not yet appended.
    rows: String,
    summary: ProcessSummary,
    pacing: Pacing,
    last_flush: Instant,
    /// The mounted specimen's failed solve was said (once per specimen).
    fault_said: bool,
}

impl RigShell {
    /// Checks the options, makes the session (resumed from its journal when there is one),
    /// opens the ports and the log, and says "ready".
    pub fn start(options: ProcessOptions) -> Result<Self, ProcessError> {
        let (publish_every, log_every) = periods(&options)?;
        check_exclusive(&options)?;
        let settings = settings_fingerprint(&options);
        let mut session = Session::new(
            &options.config,
            options.seed,
            options.program.as_ref(),
            options.campaign.clone(),
            publish_every,
            log_every,
        )?;
        let journal_path = journal_path(&options)?;
        let resumed = match &journal_path {
            Some(path) => resume_from(&options, &mut session, path, settings)?,
            None => None,
        };
        if let Some(strain) = &options.strain {
            session.start_strain(strain.test, strain.specimen.clone())?;
        }
        // Room in /dev/shm for the services, or a clear refusal (not a SIGBUS mid-run).
        wire::shm::ensure_free(wire::shm::SHM_PATH, shm_needed_bytes())?;
        let port = StatePort::open(&options.instance)?;
        let server = command_server(&port.node)?;
        // The strain channel: the newest field, put on the rig's clock by its rig sample (the
        // samples of the last 10 s are remembered).
        let fields = match &options.strain {
            Some(_) => Some(FieldSubscriber::create(
                &port.node,
                &wire::services::FIELDS,
            )?),
            None => None,
        };
        let field_clock = FieldClock::new((10.0 * options.publish_hz).ceil() as usize);
        let mut summary = ProcessSummary::default();
        let was_resumed = resumed.is_some();
        // Only now, the role claimed: a second rig refused at the claim has written nothing.
        let log = open_log(&options, resumed, &mut summary)?;
        say_ready(&port, &session, was_resumed);
        summary.samples_published = session.periods;
        let started = Instant::now();
        let t_s = session.rig.state().t_s;
        Ok(Self {
            options,
            settings,
            session,
            journal_path,
            port,
            server,
            fields,
            field_clock,
            log,
            rows: String::with_capacity(4096),
            summary,
            pacing: Pacing {
                started,
                paced_from: (started, t_s),
                was_max: false,
            },
            last_flush: started,
            fault_said: false,
            specimen: SpecimenPort::new(),
        })
    }

    /// Period after period until the end; the summary, or why the run stopped before it.
    pub fn run(mut self) -> Result<ProcessSummary, ProcessError> {
        loop {
            self.serve_commands()?;
            self.take_fields()?;
            self.period()?;
            let done =
                self.options.exit_when_done && self.session.done(self.options.program.is_some());
            // A termination signal ends the run here too, so its last rows and journal are
            // written by the one flush below.
            let stopped_by = wire::signals::requested();
            let ending = done
                || stopped_by.is_some()
                || self
                    .options
                    .duration_s
                    .is_some_and(|d| self.session.rig.state().t_s >= d);
            if self.last_flush.elapsed() >= Duration::from_millis(50) || ending {
                self.flush()?;
            }
            if ending {
                return self.finish(stopped_by);
            }
            self.pace();
        }
    }

    /// Commands, between publication periods: each accepted or refused with the reason.
    fn serve_commands(&mut self) -> Result<(), ProcessError> {
        while let Some(active) = self
            .server
            .receive()
            .map_err(|e| ProcessError::command("rig/command receive", e))?
        {
            let reply = match handle(&mut self.session.rig, &active, &self.options) {
                Ok(()) => {
                    self.summary.commands_accepted += 1;
                    RigReply::accepted()
                }
                Err(reason) => {
                    self.summary.commands_refused += 1;
                    eprintln!("rig: command refused: {reason}");
                    RigReply::refused(&reason.to_string())
                }
            };
            active
                .send_copy(reply)
                .map_err(|e| ProcessError::command("rig/command reply", e))?;
        }
        Ok(())
    }

    /// The newest field (strain control), on the rig's clock.
    fn take_fields(&mut self) -> Result<(), ProcessError> {
        if let Some(fields) = &self.fields {
            fields.clear_events();
            while let Some(sample) = fields.receive()? {
                if let Some(m) = self.field_clock.measurement(sample.user_header()) {
                    self.session.newest_field = Some(m);
                }
            }
        }
        Ok(())
    }

    /// One publication period: its control steps, events and log rows, then `rig/state`.
    fn period(&mut self) -> Result<(), ProcessError> {
        let rows = self.log.is_some().then_some(&mut self.rows);
        let event = self.session.period(rows)?;
        for (t_s, event) in self.session.strain_events.drain(..) {
            eprintln!("rig: t = {t_s:.3} s: {}", strain_message(&event));
        }
        let fault = self.session.rig.specimen().and_then(|s| s.fault());
        if let (Some(fault), false) = (fault, self.fault_said) {
            eprintln!(
                "rig: {fault}; the specimen carries no force from now on (break, grips held)"
            );
        }
        self.fault_said = fault.is_some();
        if let PeriodEvent::TestStarted(CampaignEvent::Started { index, test }) = event {
            eprintln!(
                "rig: campaign test {}/{}: {} to λ {} at {} /s, started at t = {:.1} s",
                index + 1,
                self.session
                    .campaign
                    .as_ref()
                    .map_or(0, |c| c.tests().len()),
                test.test.name(),
                test.stretch,
                test.rate_per_s,
                self.session.rig.state().t_s
            )
        }
        self.publish()
    }

    /// The rig's state with the session's control columns on `rig/state`.
    fn publish(&mut self) -> Result<(), ProcessError> {
        let control = self.session.control_columns();
        let target = control.target_log.unwrap_or([f64::NAN; 2]);
        let test_index = self.session.test_index;
        let mut published = RigState {
            test_index,
            control_mode: control.mode as u32,
            target_log_exx: target[0],
            target_log_eyy: target[1],
            ..to_wire(&self.session.rig, self.summary.samples_published)
        };
        // A structure's solve first, so a reader of this sample can have the solve it names.
        if let Some(structure) = self.session.rig.specimen().and_then(|s| s.structure()) {
            self.specimen
                .publish(&self.port.node, structure, test_index)?;
            let positions = published.actuators.map(|a| a.position_mm);
            (published.specimen_solve_id, published.specimen_grip_mm) =
                specimen_port::solve_at(structure, test_index, &positions);
        }
        self.port.publisher.publish(published)?;
        self.field_clock.record(
            published.sample_id,
            published.t_published_ns,
            published.t_sim_s,
        );
        self.summary.samples_published += 1;
        Ok(())
    }

    /// Whole rows, then the journal that names them.
    fn flush(&mut self) -> Result<(), ProcessError> {
        if let Some(log) = self.log.as_mut() {
            log.append(&self.rows)?;
            self.summary.rows_logged += self.rows.matches('\n').count() as u64;
            self.rows.clear();
        }
        if let Some(path) = &self.journal_path {
            let journal = self.session.journal(
                self.settings,
                self.summary.rows_logged,
                self.log.as_ref().map_or(0, RowFile::len_bytes),
                self.summary.commands_accepted,
            );
            wire::files::write_atomic(path, journal.to_text().as_bytes())?;
        }
        self.last_flush = Instant::now();
        Ok(())
    }

    /// Pacing: the wall clock follows simulated time / factor.
    fn pace(&mut self) {
        let t_s = self.session.rig.state().t_s;
        let factor = match self.options.speed {
            Speed::Realtime => Some(1.0),
            Speed::Factor(f) => Some(f),
            Speed::Max if self.session.program_active() || !self.session.done(true) => None,
            Speed::Max => Some(1.0),
        };
        let pacing = &mut self.pacing;
        match factor {
            None => pacing.was_max = true,
            Some(f) => {
                if pacing.was_max {
                    pacing.paced_from = (Instant::now(), t_s);
                    pacing.was_max = false;
                }
                let target = Duration::from_secs_f64(((t_s - pacing.paced_from.1) / f).max(0.0));
                let ahead = target.saturating_sub(pacing.paced_from.0.elapsed());
                // Returns early on a signal (seen after the next period); only a termination
                // request stops the rig (a SIGCONT after SIGSTOP just goes on pacing).
                let _ = self.port.node.wait(ahead);
            }
        }
    }

    /// The summary, or `Stopped` when a signal ended a run that was to end when done.
    fn finish(
        mut self,
        stopped_by: Option<std::ffi::c_int>,
    ) -> Result<ProcessSummary, ProcessError> {
        let summary = &mut self.summary;
        summary.simulated_s = self.session.rig.state().t_s;
        summary.wall_s = self.pacing.started.elapsed().as_secs_f64();
        summary.limits_tripped = self.session.rig.state().limits_tripped;
        if let Some(signal) = stopped_by {
            if self.options.exit_when_done && !self.session.done(self.options.program.is_some()) {
                // Not "done": a supervisor must not read this stop as the end of the campaign.
                let strain = self.session.campaign.is_none() && self.session.strain.is_some();
                return Err(ProcessError::Stopped {
                    signal: wire::signals::name(signal),
                    t_s: summary.simulated_s,
                    what: self.session.what(),
                    restart: restart_note(self.journal_path.as_deref(), strain),
                });
            }
        }
        Ok(self.summary)
    }
}

/// Control steps per publication and per log row, each rate checked against the control
/// rate.
fn periods(options: &ProcessOptions) -> Result<(u64, u64), ProcessError> {
    let control_hz = options.config.control_hz;
    for (name, hz) in [
        ("publish_hz", options.publish_hz),
        ("log_hz", options.log_hz),
    ] {
        if !(hz.is_finite() && hz > 0.0 && hz <= control_hz) {
            return Err(ProcessError::Rate {
                name,
                hz,
                control_hz,
            });
        }
    }
    Ok((
        (control_hz / options.publish_hz).round().max(1.0) as u64,
        (control_hz / options.log_hz).round().max(1.0) as u64,
    ))
}

/// A program, a campaign and a strain-controlled test exclude each other; strain control is
/// paced; a campaign fits the rig.
fn check_exclusive(options: &ProcessOptions) -> Result<(), ProcessError> {
    if options.program.is_some() && options.campaign.is_some() {
        return Err(ProcessError::ProgramAndCampaign);
    }
    if options.strain.is_some() {
        if options.program.is_some() || options.campaign.is_some() {
            return Err(ProcessError::StrainAndProgram);
        }
        if options.speed == Speed::Max {
            return Err(ProcessError::StrainAtMaxSpeed);
        }
    }
    if let Some(campaign) = &options.campaign {
        campaign.check_against(&options.config)?;
    }
    Ok(())
}

/// The journal's path in the state folder, the folder made; None without one.
fn journal_path(options: &ProcessOptions) -> Result<Option<PathBuf>, ProcessError> {
    let Some(dir) = &options.state_dir else {
        return Ok(None);
    };
    std::fs::create_dir_all(dir).map_err(|reason| ProcessError::CreateDir {
        path: dir.clone(),
        reason,
    })?;
    Ok(Some(dir.join(crate::journal::FILE_NAME)))
}

/// Resumes where a journal says an earlier rig of these settings had got to (before anything
/// is published: the replay takes a fraction of a second); a strain-controlled rig refuses to.
fn resume_from(
    options: &ProcessOptions,
    session: &mut Session,
    journal: &Path,
    settings: u64,
) -> Result<Option<resume::Resumed>, ProcessError> {
    if options.strain.is_some() {
        refuse_strain_resume(journal)?;
        return Ok(None);
    }
    resume::resume(
        session,
        journal,
        settings,
        options.log_path.as_deref(),
        options.exit_when_done.then_some(options.program.is_some()),
    )
}

/// The log, which grows by whole rows: a resumed rig's reopened after the rows its journal
/// names (counted in `summary`), else a new one; None without a log path.
fn open_log(
    options: &ProcessOptions,
    resumed: Option<resume::Resumed>,
    summary: &mut ProcessSummary,
) -> Result<Option<RowFile>, ProcessError> {
    let Some(path) = &options.log_path else {
        return Ok(None);
    };
    match resumed.and_then(|r| r.log.map(|finding| (finding, r.rows_logged))) {
        Some((finding, rows_logged)) => {
            summary.rows_logged = rows_logged;
            Ok(Some(resume::reopen_log(path, finding)?))
        }
        None => Ok(Some(RowFile::create(path, &crate::log::csv_header())?)),
    }
}

/// The `rig/command` server.
fn command_server(node: &Node<ipc::Service>) -> Result<CommandServer, ProcessError> {
    let service_name = ServiceName::new(wire::services::RIG_COMMAND)
        .map_err(|e| ProcessError::command("service name rig/command", e))?;
    let command_service = node
        .service_builder(&service_name)
        .request_response::<wire::RigCommand, RigReply>()
        .open_or_create()
        .map_err(|e| ProcessError::command("service rig/command", e))?;
    command_service
        .server_builder()
        .create()
        .map_err(|e| ProcessError::command("server rig/command", e))
}

fn say_ready(port: &StatePort, session: &Session, resumed: bool) {
    eprintln!(
        "rig: ready (instance {}){}",
        port.instance.name(),
        if resumed {
            format!(
                "; resumed at t = {:.3} s, test {} of the campaign",
                session.rig.state().t_s,
                session.test_index + 1
            )
        } else {
            String::new()
        }
    );
}
