//! The rig process's settings, one struct: what `dicstream run` writes for its rig
//! (`<results>/settings/rig.json`, `dicstream rig --settings FILE`) and what the command line's
//! flags make. [`RigSettings::options`] checks them and builds the process's options.

use crate::builtin::BuiltinTest;
use crate::campaign::{Campaign, CampaignError, CampaignTest};
use crate::program::{Program, ProgramError};
use crate::specimen::{SpecimenConfig, SpecimenSettings};
use crate::strain::test::{StrainTest, StrainTestError};
use material::{InvariantLaw, LawError};
use std::path::PathBuf;

/// How fast simulated time runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Speed {
    Realtime,
    /// N× real time.
    Factor(f64),
    /// As fast as the core steps while a program runs; real time once it has ended.
    Max,
}

/// `--speed` or a settings file's `speed`: not one of realtime, max or a positive factor.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("--speed {text:?}: expected realtime, max or a positive factor")]
pub struct SpeedError {
    pub text: String,
}

impl std::str::FromStr for Speed {
    type Err = SpeedError;

    fn from_str(text: &str) -> Result<Speed, SpeedError> {
        match text.trim() {
            "realtime" => Ok(Speed::Realtime),
            "max" => Ok(Speed::Max),
            n => match n.parse::<f64>() {
                Ok(f) if f.is_finite() && f > 0.0 => Ok(Speed::Factor(f)),
                _ => Err(SpeedError { text: n.into() }),
            },
        }
    }
}

/// As `--speed` takes it.
impl std::fmt::Display for Speed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Speed::Realtime => f.write_str("realtime"),
            Speed::Max => f.write_str("max"),
            Speed::Factor(factor) => write!(f, "{factor}"),
        }
    }
}

impl serde::Serialize for Speed {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(self)
    }
}

impl<'de> serde::Deserialize<'de> for Speed {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Speed, D::Error> {
        let text = String::deserialize(deserializer)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// What the rig runs from its start.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RigStart {
    /// Nothing: it waits for commands on `rig/command`.
    Idle,
    /// A program file (TOML).
    Program { file: PathBuf },
    /// A built-in test on its own specimen.
    Builtin { test: CampaignTest },
    /// Built-in tests one after the other, each on its own specimen.
    Campaign { tests: Vec<CampaignTest> },
    /// A strain-controlled test on the cruciform: the correlator's fields close the loop.
    Strain { test: StrainTest },
}

/// The specimens' law as the coefficients of eqs. 22 and 25: ln f(I1) = Σ a_i (I1 − 3)^i,
/// ln g(I2) = Σ b_i (I2 − 3)^i (f, g in MPa).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LawCoefficients {
    pub f: Vec<f64>,
    pub g: Vec<f64>,
}

impl LawCoefficients {
    pub fn law(&self) -> Result<InvariantLaw, LawError> {
        InvariantLaw::exp_poly(&self.f, &self.g)
    }
}

/// Everything the rig process needs to start.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigSettings {
    pub instance: String,
    pub start: RigStart,
    /// The law of a campaign's or a strain-controlled test's specimens (None: each built-in
    /// specimen's own, Smactane).
    pub law: Option<LawCoefficients>,
    /// Stretch rate (/s) and level of the built-in tests started over `rig/command`.
    pub test_rate_per_s: f64,
    pub test_stretch: f64,
    pub speed: Speed,
    /// Publication rate of `rig/state`, Hz of simulated time.
    pub publish_hz: f64,
    /// CSV log of the rig state, and its rate (Hz of simulated time).
    pub log: Option<PathBuf>,
    pub log_hz: f64,
    /// Seed of the simulation (valve offsets, load-cell noise).
    pub seed: u64,
    /// Stop after this much simulated time.
    pub duration_s: Option<f64>,
    /// Stop once the started program has finished (or was stopped).
    pub exit_when_done: bool,
    /// Folder of the resume journal (see `process`).
    pub state_dir: Option<PathBuf>,
    /// The specimens' model (homogeneous or the finite-element structure) and geometries.
    #[serde(default)]
    pub specimen: SpecimenSettings,
}

impl Default for RigSettings {
    fn default() -> Self {
        RigSettings {
            instance: String::new(),
            start: RigStart::Idle,
            law: None,
            test_rate_per_s: 1e-3,
            test_stretch: 2.0,
            speed: Speed::Realtime,
            publish_hz: 500.0,
            log: None,
            log_hz: 100.0,
            seed: 1,
            duration_s: None,
            exit_when_done: false,
            state_dir: None,
            specimen: SpecimenSettings::default(),
        }
    }
}

/// Why settings were refused.
#[derive(Debug, thiserror::Error)]
pub enum SettingsError {
    #[error("program {}: {reason}", .file.display())]
    ProgramFile {
        file: PathBuf,
        reason: std::io::Error,
    },
    #[error("program {}: {reason}", .file.display())]
    Program { file: PathBuf, reason: ProgramError },
    #[error(transparent)]
    Campaign(#[from] CampaignError),
    #[error("built-in test: {0}")]
    Builtin(#[from] crate::builtin::TestError),
    #[error("strain-controlled test: {0}")]
    Strain(#[from] StrainTestError),
    #[error("law of the specimens: {0}")]
    Law(#[from] LawError),
    #[error("a law applies to a campaign or a strain-controlled test")]
    LawNotTaken,
}

impl RigSettings {
    /// The program of the start (a file read, or a built-in test's), and the specimen it
    /// mounts (a built-in test's; else the cruciform of the settings' model).
    pub fn program(&self) -> Result<(Option<Program>, SpecimenConfig), SettingsError> {
        let cruciform = BuiltinTest::Equibiaxial.specimen(&self.specimen);
        Ok(match &self.start {
            RigStart::Program { file } => {
                let text =
                    std::fs::read_to_string(file).map_err(|reason| SettingsError::ProgramFile {
                        file: file.clone(),
                        reason,
                    })?;
                let base = file.parent().map(PathBuf::from).unwrap_or_default();
                let program =
                    Program::from_toml(&text, &base).map_err(|reason| SettingsError::Program {
                        file: file.clone(),
                        reason,
                    })?;
                (Some(program), cruciform)
            }
            RigStart::Builtin { test } => {
                let specimen = test.test.specimen(&self.specimen);
                let program = test
                    .test
                    .program(&specimen, test.rate_per_s, test.stretch)?;
                (Some(program), specimen)
            }
            RigStart::Idle | RigStart::Campaign { .. } | RigStart::Strain { .. } => {
                (None, cruciform)
            }
        })
    }

    /// The campaign of the start, on the law if given.
    pub fn campaign(&self) -> Result<Option<Campaign>, SettingsError> {
        let RigStart::Campaign { tests } = &self.start else {
            return Ok(None);
        };
        let campaign = Campaign::new(tests.clone())?.with_specimen(self.specimen.clone());
        Ok(Some(match &self.law {
            Some(law) => campaign.with_law(law.law()?),
            None => campaign,
        }))
    }

    /// The strain-controlled test of the start, checked, and the cruciform it mounts (of the
    /// law if given).
    pub fn strain(&self) -> Result<Option<(StrainTest, SpecimenConfig)>, SettingsError> {
        let RigStart::Strain { test } = &self.start else {
            return Ok(None);
        };
        test.check()?;
        let mut specimen = BuiltinTest::Equibiaxial.specimen(&self.specimen);
        if let Some(law) = &self.law {
            specimen.law = law.law()?;
        }
        Ok(Some((*test, specimen)))
    }

    /// A law is taken by a campaign and a strain-controlled test only.
    pub fn check_law(&self) -> Result<(), SettingsError> {
        match (&self.law, &self.start) {
            (Some(_), RigStart::Campaign { .. } | RigStart::Strain { .. }) | (None, _) => Ok(()),
            (Some(_), _) => Err(SettingsError::LawNotTaken),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::strain::test::StrainKind;

    #[test]
    fn speeds_read_as_the_command_line_writes_them_and_bad_ones_are_refused() {
        for speed in [Speed::Realtime, Speed::Max, Speed::Factor(2.5)] {
            assert_eq!(speed.to_string().parse::<Speed>(), Ok(speed));
        }
        for bad in ["fast", "0", "-1", "inf", "NaN"] {
            assert!(bad.parse::<Speed>().is_err(), "{bad}");
        }
    }

    #[test]
    fn settings_round_trip_through_json_with_their_start_named() {
        let settings = RigSettings {
            instance: "bench".into(),
            start: RigStart::Campaign {
                tests: vec![CampaignTest {
                    test: BuiltinTest::Uniaxial,
                    stretch: 3.0,
                    rate_per_s: 0.08,
                }],
            },
            law: Some(LawCoefficients {
                f: vec![-1.27, -0.025],
                g: vec![-1.02],
            }),
            speed: Speed::Factor(4.0),
            ..RigSettings::default()
        };
        let json = serde_json::to_value(&settings).unwrap();
        assert_eq!(json["start"]["kind"], "campaign");
        assert_eq!(json["start"]["tests"][0]["test"], "uniaxial");
        assert_eq!(json["speed"], "4");
        let back: RigSettings = serde_json::from_value(json).unwrap();
        assert_eq!(back, settings);
        assert_eq!(back.campaign().unwrap().unwrap().tests().len(), 1);
        settings.check_law().unwrap();
    }

    #[test]
    fn bad_settings_are_refused_with_their_reason() {
        // A strain test whose ratio is not its kind's (written by hand in the file).
        let mut test = StrainTest::new(StrainKind::Equibiaxial, None, 1.5, 0.02).unwrap();
        test.ratio = 0.3;
        let settings = RigSettings {
            start: RigStart::Strain { test },
            ..RigSettings::default()
        };
        let error = settings.strain().unwrap_err().to_string();
        assert!(error.contains("ratio 0.3"), "{error}");
        // A law with nothing to take it.
        let settings = RigSettings {
            law: Some(LawCoefficients {
                f: vec![-1.0],
                g: vec![-1.0],
            }),
            ..RigSettings::default()
        };
        assert!(matches!(
            settings.check_law(),
            Err(SettingsError::LawNotTaken)
        ));
        // An empty campaign, a program file that is not there.
        let settings = RigSettings {
            start: RigStart::Campaign { tests: vec![] },
            ..RigSettings::default()
        };
        assert!(settings.campaign().is_err());
        let missing = RigSettings {
            start: RigStart::Program {
                file: "/no/such/program.toml".into(),
            },
            ..RigSettings::default()
        };
        let error = missing.program().unwrap_err().to_string();
        assert!(
            error.starts_with("program /no/such/program.toml: "),
            "{error}"
        );
        // An unknown key.
        let error = serde_json::from_str::<RigSettings>(r#"{"instance": "i", "colour": 1}"#)
            .unwrap_err()
            .to_string();
        assert!(error.contains("unknown field `colour`"), "{error}");
    }
}
