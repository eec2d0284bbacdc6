//! What `dicstream rig --settings FILE` reads ([`RigProcessSettings`]: a simulated rig's
//! settings or a followed CSV log's), and the simulated rig's process options of its settings
//! ([`RigSettings`]), checked: the program read, the campaign and the strain-controlled test on
//! the law given.

use super::{ProcessOptions, StrainOptions};
use crate::config::RigConfig;
use crate::settings::{RigSettings, SettingsError};

/// The settings of a rig process, as `dicstream run` writes them (`settings/rig.json`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "source", content = "settings", rename_all = "snake_case")]
pub enum RigProcessSettings {
    /// The simulated machine.
    Simulated(Box<RigSettings>),
    /// A real machine's CSV log, followed.
    CsvFollow(Box<crate::csv_follow::process::FollowOptions>),
}

impl ProcessOptions {
    pub fn from_settings(settings: &RigSettings) -> Result<ProcessOptions, SettingsError> {
        settings.check_law()?;
        let (program, specimen) = settings.program()?;
        let config = RigConfig {
            specimen: Some(specimen),
            ..RigConfig::default()
        };
        Ok(ProcessOptions {
            instance: settings.instance.clone(),
            config,
            seed: settings.seed,
            program,
            campaign: settings.campaign()?,
            test_rate_per_s: settings.test_rate_per_s,
            test_stretch: settings.test_stretch,
            speed: settings.speed,
            publish_hz: settings.publish_hz,
            log_path: settings.log.clone(),
            log_hz: settings.log_hz,
            duration_s: settings.duration_s,
            exit_when_done: settings.exit_when_done,
            state_dir: settings.state_dir.clone(),
            strain: settings
                .strain()?
                .map(|(test, specimen)| StrainOptions { test, specimen }),
        })
    }
}
