//! The process's options of its settings ([`RigSettings`]), checked: the program read, the
//! campaign and the strain-controlled test on the law given.

use super::{ProcessOptions, StrainOptions};
use crate::config::RigConfig;
use crate::settings::{RigSettings, SettingsError};

impl ProcessOptions {
    pub fn from_settings(settings: &RigSettings) -> Result<ProcessOptions, SettingsError> {
        settings.check_law()?;
        let (program, specimen) = settings.program()?;
        let mut config = RigConfig::default();
        if specimen.is_some() {
            config.specimen = specimen;
        }
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
