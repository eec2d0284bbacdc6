//! A run of the rig as the process drives it, without any IPC: the machine, its campaign (or
//! program), and the publication period (a campaign step, then `publish_every` control steps,
//! logging every `log_every`th). The process shell runs periods live; a restarted rig runs the
//! journal's count of periods at once to be where it was ([`Session::resume`]): the same code
//! both times, so the replay is exact.

use crate::campaign::{Campaign, CampaignEvent};
use crate::journal::{Cadence, Journal, JournalError, Mismatch};
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
    #[error("the journal cannot be followed: {0}")]
    Journal(JournalError),
    #[error("the replay ended the {what} after {periods} periods (t = {t_s:.3} s), the journal says {journal_periods} (t = {journal_t_s:.3} s): a rig that ends when done cannot have run on")]
    BeyondTheEnd {
        /// `campaign`, `program` or `strain-controlled test`.
        what: &'static str,
        periods: u64,
        t_s: f64,
        journal_periods: u64,
        journal_t_s: f64,
    },
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

    /// How this session counts periods, steps and log rows (what its journals fit).
    pub fn cadence(&self) -> Cadence {
        Cadence {
            steps_per_period: self.publish_every,
            log_every: self.log_every,
            dt_s: self.rig.dt_s(),
            actuators: self.rig.state().actuators.len(),
        }
    }

    /// What the session runs, for messages: `campaign`, `program` or `strain-controlled test`.
    pub fn what(&self) -> &'static str {
        if self.campaign.is_some() {
            "campaign"
        } else if self.strain.is_some() {
            "strain-controlled test"
        } else {
            "program"
        }
    }

    /// Runs `journal.periods` periods at once and checks that the machine is where the journal
    /// says it was, bit for bit; refused (with why) otherwise, when commands were accepted, or
    /// when the journal's figures do not fit together. `ends_when_done` is `Some(has_program)`
    /// for a rig that stops once done (`--exit-when-done`): a journal beyond that end is
    /// refused as soon as the replay gets there. `after_period` is handed each period's log
    /// rows (they are what the log holds, from its header on); its error ends the replay (a
    /// termination request).
    pub fn resume<E: From<SessionError>>(
        &mut self,
        journal: &Journal,
        ends_when_done: Option<bool>,
        mut after_period: impl FnMut(&str) -> Result<(), E>,
    ) -> Result<(), E> {
        if journal.commands_accepted > 0 {
            return Err(SessionError::CommandsTaken {
                count: journal.commands_accepted,
            }
            .into());
        }
        journal
            .check(&self.cadence())
            .map_err(SessionError::Journal)?;
        let mut rows = String::new();
        while self.periods < journal.periods {
            if let Some(has_program) = ends_when_done {
                if self.done(has_program) {
                    return Err(SessionError::BeyondTheEnd {
                        what: self.what(),
                        periods: self.periods,
                        t_s: self.rig.state().t_s,
                        journal_periods: journal.periods,
                        journal_t_s: journal.t_s,
                    }
                    .into());
                }
            }
            rows.clear();
            self.period(Some(&mut rows))?;
            after_period(&rows)?;
        }
        match journal.mismatch(self.rig.state()) {
            Some(why) => Err(SessionError::Mismatch(why).into()),
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
        let mut replayed_rows = String::new();
        again
            .resume(&journal, None, |r: &str| {
                replayed_rows.push_str(r);
                Ok::<(), SessionError>(())
            })
            .unwrap();
        // The replay gives the very rows the live session logged.
        assert_eq!(replayed_rows, rows);
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
        let refused = other.resume(&journal, None, no_rows);
        assert!(
            matches!(refused, Err(SessionError::Mismatch(_))),
            "{refused:?}"
        );
        // A rig that took commands cannot resume.
        let mut commanded = journal.clone();
        commanded.commands_accepted = 1;
        assert_eq!(
            session().resume(&commanded, None, no_rows),
            Err(SessionError::CommandsTaken { count: 1 })
        );
    }

    fn no_rows(_: &str) -> Result<(), SessionError> {
        Ok(())
    }

    #[test]
    fn a_journal_whose_figures_do_not_fit_is_refused_before_any_replay() {
        let mut live = session();
        for _ in 0..20 {
            live.period(None).unwrap();
        }
        let journal = live.journal(1, 0, 0, 0);
        // An edited periods count (10^12 would replay for years): refused at once.
        let absurd = Journal {
            periods: 1_000_000_000_000,
            ..journal.clone()
        };
        let mut fresh = session();
        let refused = fresh.resume(&absurd, None, no_rows).unwrap_err();
        assert!(
            matches!(
                refused,
                SessionError::Journal(JournalError::StepsPerPeriod { .. })
            ),
            "{refused:?}"
        );
        assert_eq!(fresh.periods, 0, "nothing replayed");
        let late = Journal {
            t_s: journal.t_s + 1.0,
            ..journal.clone()
        };
        assert!(matches!(
            session().resume(&late, None, no_rows),
            Err(SessionError::Journal(JournalError::Time { .. }))
        ));
        let nan = Journal {
            positions_mm: vec![f64::NAN; 6],
            ..journal.clone()
        };
        assert!(matches!(
            session().resume(&nan, None, no_rows),
            Err(SessionError::Journal(JournalError::Positions { .. }))
        ));
        let rows = Journal {
            rows_logged: 3,
            log_bytes: 1000,
            ..journal.clone()
        };
        assert!(matches!(
            session().resume(&rows, None, no_rows),
            Err(SessionError::Journal(JournalError::RowsLogged { .. }))
        ));
        session().resume(&journal, None, no_rows).unwrap();
    }

    #[test]
    fn a_journal_beyond_the_end_of_a_campaign_that_ends_when_done_is_refused() {
        let campaign = Campaign::parse("uniaxial:1.02@0.2").unwrap();
        let new = || {
            Session::new(
                &RigConfig::default(),
                7,
                None,
                Some(campaign.clone()),
                10,
                50,
            )
        };
        let mut live = new().unwrap();
        for _ in 0..100_000 {
            if live.done(false) {
                break;
            }
            live.period(None).unwrap();
        }
        assert!(live.done(false), "the campaign ended");
        let end = live.journal(1, 0, 0, 0);
        // The end itself resumes (a finished campaign restarted).
        new().unwrap().resume(&end, Some(false), no_rows).unwrap();
        // Ten periods on: a rig that ends when done cannot have written it.
        for _ in 0..10 {
            live.period(None).unwrap();
        }
        let beyond = live.journal(1, 0, 0, 0);
        let mut replay = new().unwrap();
        let refused = replay.resume(&beyond, Some(false), no_rows).unwrap_err();
        assert!(
            matches!(refused, SessionError::BeyondTheEnd { periods, .. } if periods == end.periods),
            "{refused:?}"
        );
        assert!(refused.to_string().contains("campaign"), "{refused}");
        // A rig that runs on once done may have.
        new().unwrap().resume(&beyond, None, no_rows).unwrap();
    }
}
