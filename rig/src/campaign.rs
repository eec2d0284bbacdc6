//! A test campaign: built-in tests run one after the other on one rig, each on its own
//! specimen (the paper's section 4: a uniaxial test, then an equibiaxial test). Each test
//! loads to its stretch, holds, unloads to the mounting position; the next specimen is then
//! mounted and its test started. Pure logic on [`Rig`]: the process shell calls
//! [`Campaign::advance`] between steps.

use crate::builtin::{BuiltinTest, TestError};
use crate::config::RigConfig;
use crate::program::{Program, Step};
use crate::refusal::Refusal;
use crate::rig::{Rig, RigCommand};
use crate::snapshot::ProgramStatus;
use crate::specimen::{SpecimenConfig, SpecimenSettings};
use material::InvariantLaw;

/// One test of a campaign: a built-in test to a stretch at a stretch rate.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignTest {
    pub test: BuiltinTest,
    /// Final stretch λ of the loading ramp.
    pub stretch: f64,
    /// Stretch rate of the loading ramp (/s of simulated time).
    pub rate_per_s: f64,
}

/// Why a campaign was refused: its text, its tests' programs, or the machine it would run on.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    #[error("campaign test {text:?}: expected TEST:STRETCH@RATE, e.g. uniaxial:3@0.08")]
    Syntax { text: String },
    #[error("campaign test {text:?}: unknown test {name:?} (uniaxial or equibiaxial)")]
    UnknownTest { text: String, name: String },
    #[error("campaign test {text:?}: {what} {value:?} is not a number")]
    NotANumber {
        text: String,
        what: &'static str,
        value: String,
    },
    #[error("campaign test {text:?}: {reason}")]
    Test { text: String, reason: TestError },
    #[error("a campaign needs at least one test")]
    Empty,
    #[error(transparent)]
    Program(#[from] TestError),
    /// The rig refuses the campaign's configuration (its specimen, its limits).
    #[error("{at}: {reason}")]
    Machine { at: NumberedTest, reason: Refusal },
    #[error("{at}: {reason}")]
    TestProgram { at: NumberedTest, reason: TestError },
    #[error("{at} is refused by the rig: {reason}")]
    RefusedByRig { at: NumberedTest, reason: Refusal },
}

/// A test of a campaign as a refusal names it: its number (from 1) and what it does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NumberedTest {
    pub number: usize,
    pub test: CampaignTest,
}

impl std::fmt::Display for NumberedTest {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "campaign test {} ({} to λ {} at {} /s)",
            self.number,
            self.test.test.name(),
            self.test.stretch,
            self.test.rate_per_s
        )
    }
}

/// How fast a test unloads, relative to its loading rate.
pub const UNLOAD_RATE_FACTOR: f64 = 5.0;
/// Hold at the mounting position after unloading (s).
pub const UNLOADED_HOLD_S: f64 = 0.5;

impl CampaignTest {
    /// The test's program on `specimen`: hold, ramp to the stretch, hold, ramp back to zero
    /// elongation at [`UNLOAD_RATE_FACTOR`] times the rate, hold.
    pub fn program(&self, specimen: &SpecimenConfig) -> Result<Program, TestError> {
        let mut program = self.test.program(specimen, self.rate_per_s, self.stretch)?;
        let gauge_mm = specimen.gauge_mm()[0];
        for (_, steps) in &mut program.channels {
            steps.push(Step::Ramp {
                to: 0.0,
                rate_per_s: UNLOAD_RATE_FACTOR * self.rate_per_s * gauge_mm,
                relative: false,
            });
            steps.push(Step::Hold {
                duration_s: UNLOADED_HOLD_S,
            });
        }
        program.name = format!("{} and back", program.name);
        program.validate()?;
        Ok(program)
    }

    /// `uniaxial:3@0.08` = uniaxial to λ 3 at 0.08 /s.
    pub fn parse(text: &str) -> Result<CampaignTest, CampaignError> {
        let syntax = || CampaignError::Syntax {
            text: text.to_string(),
        };
        let (name, rest) = text.trim().split_once(':').ok_or_else(syntax)?;
        let (stretch, rate) = rest.split_once('@').ok_or_else(syntax)?;
        let test = BuiltinTest::parse(name.trim()).ok_or_else(|| CampaignError::UnknownTest {
            text: text.to_string(),
            name: name.to_string(),
        })?;
        let number = |what: &'static str, value: &str| {
            value
                .trim()
                .parse::<f64>()
                .map_err(|_| CampaignError::NotANumber {
                    text: text.to_string(),
                    what,
                    value: value.to_string(),
                })
        };
        let test = CampaignTest {
            test,
            stretch: number("stretch", stretch)?,
            rate_per_s: number("rate", rate)?,
        };
        let specimen = test.test.specimen(&SpecimenSettings::default());
        test.program(&specimen)
            .map_err(|reason| CampaignError::Test {
                text: text.to_string(),
                reason,
            })?;
        Ok(test)
    }
}

/// What [`Campaign::advance`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CampaignEvent {
    /// Nothing new: a test is under way (or held, or stopped by a limit: the campaign waits).
    Busy,
    /// Test `index` (from 0) was mounted and started.
    Started { index: usize, test: CampaignTest },
    /// Every test has run.
    Done,
}

/// Tests in order, and which one is next.
#[derive(Clone, Debug, PartialEq)]
pub struct Campaign {
    tests: Vec<CampaignTest>,
    next: usize,
    /// The material of every specimen; None: each built-in specimen's own (Smactane).
    law: Option<InvariantLaw>,
    /// The model and geometries of the specimens.
    specimen: SpecimenSettings,
}

impl Campaign {
    /// The paper's campaign on the default specimen, sized for a one-minute live bench: uniaxial
    /// tension to λ 3 (the range of the paper's Figs. 7-8), then equibiaxial tension to λ 2
    /// (Figs. 13-14). Fast rates: the specimen law is rate independent.
    pub fn paper() -> Campaign {
        Campaign::new(vec![
            CampaignTest {
                test: BuiltinTest::Uniaxial,
                stretch: 3.0,
                rate_per_s: 0.08,
            },
            CampaignTest {
                test: BuiltinTest::Equibiaxial,
                stretch: 2.0,
                rate_per_s: 0.04,
            },
        ])
        .expect("the paper campaign is valid")
    }

    pub fn new(tests: Vec<CampaignTest>) -> Result<Campaign, CampaignError> {
        if tests.is_empty() {
            return Err(CampaignError::Empty);
        }
        let specimen = SpecimenSettings::default();
        for test in &tests {
            test.program(&test.test.specimen(&specimen))?;
        }
        Ok(Campaign {
            tests,
            next: 0,
            law: None,
            specimen,
        })
    }

    /// Every specimen of the campaign made of `law` instead of the default material.
    pub fn with_law(mut self, law: InvariantLaw) -> Campaign {
        self.law = Some(law);
        self
    }

    /// Every specimen of the campaign of the model and geometries of `specimen`.
    pub fn with_specimen(mut self, specimen: SpecimenSettings) -> Campaign {
        self.specimen = specimen;
        self
    }

    /// The specimen test `test` mounts.
    pub fn specimen_of(&self, test: &CampaignTest) -> SpecimenConfig {
        let mut specimen = test.test.specimen(&self.specimen);
        if let Some(law) = &self.law {
            specimen.law = law.clone();
        }
        specimen
    }

    /// `uniaxial:3@0.08,equibiaxial:2@0.04`.
    pub fn parse(text: &str) -> Result<Campaign, CampaignError> {
        let tests = text
            .split(',')
            .filter(|t| !t.trim().is_empty())
            .map(CampaignTest::parse)
            .collect::<Result<Vec<_>, _>>()?;
        Campaign::new(tests)
    }

    pub fn tests(&self) -> &[CampaignTest] {
        &self.tests
    }

    /// Simulated duration of the whole campaign (s), for planning.
    pub fn duration_s(&self) -> f64 {
        self.tests
            .iter()
            .map(|t| {
                let ramp_s = (t.stretch - 1.0) / t.rate_per_s;
                2.0 + ramp_s * (1.0 + 1.0 / UNLOAD_RATE_FACTOR) + UNLOADED_HOLD_S
            })
            .sum()
    }

    /// Checks every test against the limits of `config` as the rig itself would when the test
    /// starts (stroke, force range, rate), so a campaign beyond the machine is refused before
    /// anything runs, with the test named.
    pub fn check_against(&self, config: &RigConfig) -> Result<(), CampaignError> {
        for (k, test) in self.tests.iter().enumerate() {
            let at = NumberedTest {
                number: k + 1,
                test: *test,
            };
            let specimen = self.specimen_of(test);
            let mut scratch_config = config.clone();
            scratch_config.specimen = Some(specimen.clone());
            let mut rig = Rig::new(scratch_config, 0)
                .map_err(|reason| CampaignError::Machine { at, reason })?;
            let program = test
                .program(&specimen)
                .map_err(|reason| CampaignError::TestProgram { at, reason })?;
            rig.command(RigCommand::StartProgram(Box::new(program)))
                .map_err(|reason| CampaignError::RefusedByRig { at, reason })?;
        }
        Ok(())
    }

    /// Between steps: once the rig is idle (no test yet, or the last one finished), mount the
    /// next test's specimen and start it. A test stopped by a limit or a command halts the
    /// campaign where it is (the operator decides).
    pub fn advance(&mut self, rig: &mut Rig) -> Result<CampaignEvent, Refusal> {
        let status = rig.state().program;
        let ready = match status {
            ProgramStatus::Idle => self.next == 0,
            ProgramStatus::Finished => true,
            ProgramStatus::Running | ProgramStatus::Held | ProgramStatus::Stopped => false,
        };
        if !ready {
            return Ok(CampaignEvent::Busy);
        }
        let Some(&test) = self.tests.get(self.next) else {
            return Ok(CampaignEvent::Done);
        };
        let specimen = self.specimen_of(&test);
        let program = test.program(&specimen).map_err(Refusal::invalid)?;
        rig.command(RigCommand::MountSpecimen(Some(Box::new(specimen))))?;
        rig.command(RigCommand::StartProgram(Box::new(program)))?;
        let index = self.next;
        self.next += 1;
        Ok(CampaignEvent::Started { index, test })
    }

    /// True once every test was started and the rig has finished the last one.
    pub fn is_done(&self, rig: &Rig) -> bool {
        self.next == self.tests.len() && rig.state().program == ProgramStatus::Finished
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_refuses_with_reasons() {
        let c = Campaign::parse("uniaxial:3@0.08, equibiaxial:2@0.04").unwrap();
        assert_eq!(c.tests().len(), 2);
        assert_eq!(c.tests()[1].test, BuiltinTest::Equibiaxial);
        assert!(matches!(Campaign::parse(""), Err(CampaignError::Empty)));
        assert!(Campaign::parse("shear:2@0.1")
            .unwrap_err()
            .to_string()
            .contains("unknown test"));
        assert!(Campaign::parse("uniaxial:two@0.1")
            .unwrap_err()
            .to_string()
            .contains("not a number"));
        assert!(Campaign::parse("uniaxial:3")
            .unwrap_err()
            .to_string()
            .contains("STRETCH@RATE"));
        assert!(Campaign::parse("uniaxial:0.5@0.1")
            .unwrap_err()
            .to_string()
            .contains("stretch"));
        assert!(Campaign::parse("uniaxial:NaN@0.1").is_err());
    }

    #[test]
    fn a_stretch_beyond_the_stroke_is_refused_before_the_run() {
        let config = RigConfig::default();
        Campaign::paper().check_against(&config).unwrap();
        // 100 mm gauge to λ 7: 300 mm per actuator, beyond the 250 mm stroke.
        let error = Campaign::parse("uniaxial:7@0.08")
            .unwrap()
            .check_against(&config)
            .unwrap_err()
            .to_string();
        assert!(error.contains("campaign test 1"), "{error}");
        assert!(error.contains("stroke"), "{error}");
        let error = Campaign::parse("equibiaxial:1.5@50")
            .unwrap()
            .check_against(&config)
            .unwrap_err()
            .to_string();
        assert!(error.contains("rate"), "{error}");
    }
}
