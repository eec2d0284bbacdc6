//! Configuration of a rig run: sampling, plant parameters, gains, specimen, limits.

use crate::control::ControlGains;
use crate::hydraulics::ACTUATOR_COUNT;
use crate::limits::{ChannelLimits, LimitActions, Limits, LimitsError};
use crate::params::ActuatorParams;
use crate::specimen::{SpecimenConfig, SpecimenError};

/// Why a rig configuration was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ConfigError {
    #[error("control_hz {control_hz} not in [100, 100000]")]
    ControlRate { control_hz: f64 },
    #[error("plant_substeps {plant_substeps} not in [1, 64]")]
    PlantSubsteps { plant_substeps: u32 },
    #[error("control gains are not finite or not ordered")]
    Gains,
    #[error("spool_bias_std {spool_bias_std} not in [0, 0.02)")]
    SpoolBias { spool_bias_std: f64 },
    #[error("load_cell_noise_kn {load_cell_noise_kn} is not ≥ 0")]
    LoadCellNoise { load_cell_noise_kn: f64 },
    #[error("break_detect_min_kn {break_detect_min_kn} is not > 0")]
    BreakDetect { break_detect_min_kn: f64 },
    #[error(transparent)]
    Specimen(#[from] SpecimenError),
    #[error(transparent)]
    Limits(#[from] LimitsError),
}

#[derive(Clone, Debug, PartialEq)]
pub struct RigConfig {
    /// Control rate of the digital controller (Schenck-class: 5 kHz).
    pub control_hz: f64,
    /// Plant sub-steps per control period (4 ⇒ 20 kHz plant, ω·h ≈ 0.05 at 144 Hz).
    pub plant_substeps: u32,
    pub actuators: [ActuatorParams; ACTUATOR_COUNT],
    pub gains: ControlGains,
    /// Standard deviation of the spool null bias drawn per actuator from the seed (fraction of
    /// full opening). Real valves are nulled to a fraction of a percent.
    pub spool_bias_std: f64,
    /// Load-cell noise, standard deviation (kN): ≈0.002 % of the 100 kN range.
    pub load_cell_noise_kn: f64,
    /// The sheet between the X and Y grips; None for an empty machine.
    pub specimen: Option<SpecimenConfig>,
    pub limits: Limits,
    /// Break detector: a pair force that falls below half its 20 ms running mean, once that
    /// mean exceeds this level, is a break.
    pub break_detect_min_kn: f64,
}

impl Default for RigConfig {
    fn default() -> Self {
        let h = ActuatorParams::horizontal();
        let v = ActuatorParams::vertical();
        let actuators = [h, h, h, h, v, v];
        let channels =
            actuators.map(|a| ChannelLimits::for_actuator(a.half_stroke_mm(), a.rated_force_kn));
        RigConfig {
            control_hz: 5000.0,
            plant_substeps: 4,
            actuators,
            gains: ControlGains::default_for_machine(),
            spool_bias_std: 0.002,
            load_cell_noise_kn: 0.002,
            specimen: Some(SpecimenConfig::default()),
            limits: Limits {
                channels,
                actions: LimitActions::default(),
            },
            break_detect_min_kn: 0.05,
        }
    }
}

impl RigConfig {
    pub fn dt_s(&self) -> f64 {
        1.0 / self.control_hz
    }

    pub fn validate(&self) -> Result<(), ConfigError> {
        if !(self.control_hz.is_finite() && (100.0..=100_000.0).contains(&self.control_hz)) {
            return Err(ConfigError::ControlRate {
                control_hz: self.control_hz,
            });
        }
        if !(1..=64).contains(&self.plant_substeps) {
            return Err(ConfigError::PlantSubsteps {
                plant_substeps: self.plant_substeps,
            });
        }
        if !self.gains.is_valid() {
            return Err(ConfigError::Gains);
        }
        if !(self.spool_bias_std.is_finite() && (0.0..0.02).contains(&self.spool_bias_std)) {
            return Err(ConfigError::SpoolBias {
                spool_bias_std: self.spool_bias_std,
            });
        }
        if !(self.load_cell_noise_kn.is_finite() && self.load_cell_noise_kn >= 0.0) {
            return Err(ConfigError::LoadCellNoise {
                load_cell_noise_kn: self.load_cell_noise_kn,
            });
        }
        if !(self.break_detect_min_kn.is_finite() && self.break_detect_min_kn > 0.0) {
            return Err(ConfigError::BreakDetect {
                break_detect_min_kn: self.break_detect_min_kn,
            });
        }
        if let Some(specimen) = &self.specimen {
            specimen.validate()?;
        }
        Ok(self.limits.validate()?)
    }
}
