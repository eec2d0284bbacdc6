//! A run of the rig as the process drives it, without any IPC: the machine, its campaign (or
//! program), and the publication period (a campaign step, then `publish_every` control steps,
//! logging every `log_every`th). The process shell runs periods live; a restarted rig runs the
//! journal's count of periods at once to be where it was ([`Session::resume`]): the same code
//! both times, so the replay is exact.

use crate::campaign::{Campaign, CampaignEvent};
use crate::journal::{Journal, Mismatch};
use crate::refusal::Refusal;
use crate::rig::{Rig, RigCommand};
use crate::snapshot::ProgramStatus;
use crate::specimen::SpecimenConfig;
use crate::strain::run::StrainRunError;
use crate::strain::{ControlColumns, GaugeMeasurement, StrainRun, StrainRunEvent, StrainTest};
use crate::{Program, RigConfig};

/// Why a session could not start, go on, or resume.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SessionError {
    /// The rig refused its configuration.
    #[error(transparent)]
    Rig(Refusal),
    #[error("program refused: {0}")]
    ProgramRefused(Refusal),
    #[error("campaign halted: {0}")]
    CampaignHalted(Refusal),
    #[error("{count} command(s) were accepted over rig/command; they are not replayed")]
    CommandsTaken { count: u64 },
    #[error(transparent)]
    Mismatch(Mismatch),
}

pub struct Session {
    pub rig: Rig,
    pub campaign: Option<Campaign>,
    /// The campaign test under way (published as `RigState::test_index`).
    pub test_index: u32,
    /// Periods run so far.
    pub periods: u64,
    publish_every: u64,
    log_every: u64,
    /// A strain-controlled test instead of a program or campaign.
    pub strain: Option<StrainRun>,
    /// The newest field on the rig's clock (set by the shell before each period).
    pub newest_field: Option<GaugeMeasurement>,
    /// What the strain test did in the periods so far (drained by the shell).
    pub strain_events: Vec<(f64, StrainRunEvent)>,
}

/// What happened in a period that the shell reports.
pub enum PeriodEvent {
    Nothing,
    TestStarted(CampaignEvent),
}

impl Session {
    pub fn new(
        config: &RigConfig,
        seed: u64,
        program: Option<&Program>,
        campaign: Option<Campaign>,
        publish_every: u64,
        log_every: u64,
    ) -> Result<Session, SessionError> {
        let mut rig = Rig::new(config.clone(), seed).map_err(SessionError::Rig)?;
        if let Some(program) = program {
            rig.command(RigCommand::StartProgram(Box::new(program.clone())))
                .map_err(SessionError::ProgramRefused)?;
        }
        Ok(Session {
            rig,
            campaign,
            test_index: 0,
            periods: 0,
            publish_every: publish_every.max(1),
            log_every: log_every.max(1),
            strain: None,
            newest_field: None,
            strain_events: Vec::new(),
        })
    }

    /// Runs a strain-controlled test: mounts `specimen` (a cruciform) and waits for fields.
    pub fn start_strain(
        &mut self,
        test: StrainTest,
        specimen: SpecimenConfig,
    ) -> Result<(), StrainRunError> {
        self.strain = Some(StrainRun::new(&mut self.rig, test, specimen)?);
        Ok(())
    }

    /// One publication period; the log rows of its steps are appended to `rows` (if given).
    pub fn period(&mut self, mut rows: Option<&mut String>) -> Result<PeriodEvent, SessionError> {
        let mut event = PeriodEvent::Nothing;
        if let Some(campaign) = self.campaign.as_mut() {
            match campaign.advance(&mut self.rig) {
                Ok(started @ CampaignEvent::Started { index, .. }) => {
                    self.test_index = index as u32;
                    event = PeriodEvent::TestStarted(started);
                }
                Ok(CampaignEvent::Busy | CampaignEvent::Done) => {}
                Err(refusal) => return Err(SessionError::CampaignHalted(refusal)),
            }
        }
        for _ in 0..self.publish_every {
            if let Some(strain) = self.strain.as_mut() {
                if let Some(e) = strain.before_step(&mut self.rig, self.newest_field.as_ref()) {
                    self.strain_events.push((self.rig.state().t_s, e));
                }
            }
            self.rig.step();
            if let Some(rows) = rows.as_deref_mut() {
                if self.rig.state().step.is_multiple_of(self.log_every) {
                    let control = self.control_columns();
                    crate::log::write_csv_row_with(self.rig.state(), &control, rows);
                }
            }
        }
        self.periods += 1;
        Ok(event)
    }

    /// What closes the loop now and the strain target (`rig.csv`'s control columns and the
    /// published `RigState::control_mode` / targets).
    pub fn control_columns(&self) -> ControlColumns {
        self.strain
            .as_ref()
            .map_or(ControlColumns::DISPLACEMENT, StrainRun::columns)
    }

    /// A program or a test is under way (running or held).
    pub fn program_active(&self) -> bool {
        matches!(
            self.rig.state().program,
            ProgramStatus::Running | ProgramStatus::Held
        )
    }

    /// The campaign (or the started program, or the strain test) has ended.
    pub fn done(&self, has_program: bool) -> bool {
        if let Some(strain) = &self.strain {
            return strain.is_done();
        }
        match &self.campaign {
            Some(c) => c.is_done(&self.rig),
            None => has_program && !self.program_active(),
        }
    }

    /// Runs `journal.periods` periods at once and checks that the machine is where the journal
    /// says it was, bit for bit; refused (with why) otherwise, or when commands were accepted.
    pub fn resume(&mut self, journal: &Journal) -> Result<(), SessionError> {
        if journal.commands_accepted > 0 {
            return Err(SessionError::CommandsTaken {
                count: journal.commands_accepted,
            });
        }
        while self.periods < journal.periods {
            self.period(None)?;
        }
        match journal.mismatch(self.rig.state()) {
            Some(why) => Err(SessionError::Mismatch(why)),
            None => Ok(()),
        }
    }

    /// The journal of where the session is now.
    pub fn journal(
        &self,
        settings: u64,
        rows_logged: u64,
        log_bytes: u64,
        commands_accepted: u64,
    ) -> Journal {
        let s = self.rig.state();
        Journal {
            settings,
            periods: self.periods,
            step: s.step,
            t_s: s.t_s,
            positions_mm: Journal::positions_of(s),
            rows_logged,
            log_bytes,
            commands_accepted,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn session() -> Session {
        let campaign = Campaign::parse("uniaxial:1.3@0.2").unwrap();
        Session::new(&RigConfig::default(), 7, None, Some(campaign), 10, 50).unwrap()
    }

    #[test]
    fn a_replayed_session_is_where_the_journal_says_bit_for_bit() {
        let mut live = session();
        let mut rows = String::new();
        for _ in 0..700 {
            live.period(Some(&mut rows)).unwrap();
        }
        assert!(live.program_active());
        let journal = live.journal(1, 0, 0, 0);
        let mut again = session();
        again.resume(&journal).unwrap();
        assert_eq!(again.rig.state().t_s, live.rig.state().t_s);
        assert_eq!(again.test_index, live.test_index);
        // The two go on identically.
        let (mut a, mut b) = (String::new(), String::new());
        for _ in 0..50 {
            live.period(Some(&mut a)).unwrap();
            again.period(Some(&mut b)).unwrap();
        }
        assert_eq!(a, b);
        // Another seed does not reach the same state: refused, with why.
        let mut other = Session::new(
            &RigConfig::default(),
            8,
            None,
            live.campaign.clone(),
            10,
            50,
        )
        .unwrap();
        other.campaign = Some(Campaign::parse("uniaxial:1.3@0.2").unwrap());
        let refused = other.resume(&journal);
        assert!(refused.is_err());
        // A rig that took commands cannot resume.
        let mut commanded = journal.clone();
        commanded.commands_accepted = 1;
        assert_eq!(
            session().resume(&commanded),
            Err(SessionError::CommandsTaken { count: 1 })
        );
    }
}
