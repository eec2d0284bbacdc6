//! From a program file to a checked [`Program`]: the TOML form, CSV profiles, and the checks
//! a program passes before it may run. Every refusal is a [`ProgramError`] naming the channel,
//! the file or the line.

use super::{
    Program, Step, StopTransition, MAX_PROFILE_SAMPLES, MAX_PROGRAM_CHANNELS, MAX_SEGMENTS,
};
use crate::control::{AxisControl, ControlMode};
use crate::ids::{Axis, Channel};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Why a program was refused.
#[derive(Debug, thiserror::Error)]
pub enum ProgramError {
    #[error("program TOML: {error}{}", hint.as_deref().map(|h| format!("\n{h}")).unwrap_or_default())]
    Toml {
        error: Box<toml::de::Error>,
        /// What to write instead of a bare word (`wire::toml_hint`).
        hint: Option<Box<str>>,
    },
    #[error("setup axis {axis:?}: expected x, y or z")]
    SetupAxis { axis: String },
    #[error(
        "setup control {control:?}: expected independent, centroid_displacement or centroid_force"
    )]
    SetupControl { control: String },
    #[error("channel target {target:?}: expected x+, x-, x.elongation, x.centre, ...")]
    ChannelTarget { target: String },
    #[error("CSV profile {}: {reason}", .path.display())]
    ProfileUnreadable {
        path: PathBuf,
        reason: std::io::Error,
    },
    #[error("CSV profile {}: {reason}", .path.display())]
    Profile { path: PathBuf, reason: ProfileError },
    #[error("a program drives 1 to {MAX_PROGRAM_CHANNELS} channels, this one {count}")]
    ChannelCount { count: usize },
    #[error("stop_rate_per_s {rate_per_s} must be positive")]
    StopRate { rate_per_s: f64 },
    #[error("{channel:?} is programmed twice")]
    ProgrammedTwice { channel: Channel },
    #[error("{channel:?}: 1 to {MAX_SEGMENTS} segments expected")]
    SegmentCount { channel: Channel, count: usize },
    #[error("{channel:?}: {reason}")]
    Step { channel: Channel, reason: StepError },
}

/// Why one segment of a channel was refused.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum StepError {
    #[error("{name} = {value}, expected a positive finite number")]
    NotPositive { name: &'static str, value: f64 },
    #[error("ramp level {to} is not finite")]
    RampLevel { to: f64 },
    #[error("amplitude {amplitude} is not finite")]
    Amplitude { amplitude: f64 },
    #[error("a CSV profile needs 2 or more (t_s, value) rows")]
    ProfileRows,
    #[error("a CSV profile starts at t_s = 0")]
    ProfileStart,
    #[error("CSV profile times must increase and values be finite")]
    ProfileOrder,
}

/// Why the text of a CSV profile was refused (lines counted from 1).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ProfileError {
    #[error("line {line}: expected t_s,value")]
    Fields { line: usize },
    #[error("line {line}: {text:?} is not two numbers")]
    NotNumbers { line: usize, text: String },
    #[error("more than {MAX_PROFILE_SAMPLES} rows")]
    TooManyRows,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Segment {
    Ramp {
        to: f64,
        rate_per_s: f64,
        #[serde(default)]
        relative: bool,
    },
    Hold {
        duration_s: f64,
    },
    Sine {
        amplitude: f64,
        frequency_hz: f64,
        cycles: f64,
    },
    Triangle {
        amplitude: f64,
        frequency_hz: f64,
        cycles: f64,
    },
    Csv {
        path: String,
        #[serde(default)]
        relative: bool,
    },
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SetupEntry {
    pub axis: String,
    pub control: String,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelProgramFile {
    pub target: String,
    pub segments: Vec<Segment>,
}

/// A program as written in a TOML file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProgramFile {
    #[serde(default)]
    pub name: String,
    #[serde(default)]
    pub stop: StopTransition,
    #[serde(default = "default_stop_rate")]
    pub stop_rate_per_s: f64,
    #[serde(default)]
    pub setup: Vec<SetupEntry>,
    pub channel: Vec<ChannelProgramFile>,
}

fn default_stop_rate() -> f64 {
    1.0
}

impl Program {
    /// Parse a TOML program; CSV paths are relative to `base_dir`.
    pub fn from_toml(text: &str, base_dir: &Path) -> Result<Program, ProgramError> {
        let file: ProgramFile = toml::from_str(text).map_err(|error| ProgramError::Toml {
            hint: error
                .span()
                .and_then(|span| wire::toml_hint::bare_word_hint(text, span.start))
                .map(String::into_boxed_str),
            error: Box::new(error),
        })?;
        Program::from_file(file, base_dir)
    }

    pub fn from_file(file: ProgramFile, base_dir: &Path) -> Result<Program, ProgramError> {
        let mut setup = Vec::new();
        for entry in &file.setup {
            let axis = match entry.axis.to_ascii_lowercase().as_str() {
                "x" => Axis::X,
                "y" => Axis::Y,
                "z" => Axis::Z,
                other => {
                    return Err(ProgramError::SetupAxis {
                        axis: other.to_string(),
                    })
                }
            };
            let control = match entry.control.as_str() {
                "independent" => AxisControl::Independent,
                "centroid_displacement" => AxisControl::Centroid(ControlMode::Displacement),
                "centroid_force" => AxisControl::Centroid(ControlMode::Force),
                other => {
                    return Err(ProgramError::SetupControl {
                        control: other.to_string(),
                    })
                }
            };
            setup.push((axis, control));
        }
        let mut channels = Vec::new();
        for c in file.channel {
            let channel = Channel::parse(&c.target).ok_or_else(|| ProgramError::ChannelTarget {
                target: c.target.clone(),
            })?;
            let mut steps = Vec::new();
            for segment in c.segments {
                steps.push(load_segment(segment, base_dir)?);
            }
            channels.push((channel, steps));
        }
        let program = Program {
            name: file.name,
            stop: file.stop,
            stop_rate_per_s: file.stop_rate_per_s,
            setup,
            channels,
        };
        program.validate()?;
        Ok(program)
    }

    pub fn validate(&self) -> Result<(), ProgramError> {
        if self.channels.is_empty() || self.channels.len() > MAX_PROGRAM_CHANNELS {
            return Err(ProgramError::ChannelCount {
                count: self.channels.len(),
            });
        }
        if !(self.stop_rate_per_s.is_finite() && self.stop_rate_per_s > 0.0) {
            return Err(ProgramError::StopRate {
                rate_per_s: self.stop_rate_per_s,
            });
        }
        for (i, (channel, steps)) in self.channels.iter().enumerate() {
            let channel = *channel;
            if self.channels[..i].iter().any(|(c, _)| *c == channel) {
                return Err(ProgramError::ProgrammedTwice { channel });
            }
            if steps.is_empty() || steps.len() > MAX_SEGMENTS {
                return Err(ProgramError::SegmentCount {
                    channel,
                    count: steps.len(),
                });
            }
            for step in steps {
                validate_step(step).map_err(|reason| ProgramError::Step { channel, reason })?;
            }
        }
        Ok(())
    }
}

fn validate_step(step: &Step) -> Result<(), StepError> {
    let positive = |name: &'static str, value: f64| {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(StepError::NotPositive { name, value })
        }
    };
    match step {
        Step::Ramp { to, rate_per_s, .. } => {
            if !to.is_finite() {
                return Err(StepError::RampLevel { to: *to });
            }
            positive("rate_per_s", *rate_per_s)
        }
        Step::Hold { duration_s } => positive("duration_s", *duration_s),
        Step::Sine {
            amplitude,
            frequency_hz,
            cycles,
        }
        | Step::Triangle {
            amplitude,
            frequency_hz,
            cycles,
        } => {
            if !amplitude.is_finite() {
                return Err(StepError::Amplitude {
                    amplitude: *amplitude,
                });
            }
            positive("frequency_hz", *frequency_hz)?;
            positive("cycles", *cycles)
        }
        Step::Profile { t_s, value, .. } => {
            if t_s.len() < 2 || t_s.len() != value.len() || t_s.len() > MAX_PROFILE_SAMPLES {
                return Err(StepError::ProfileRows);
            }
            if t_s[0] != 0.0 {
                return Err(StepError::ProfileStart);
            }
            if !t_s.windows(2).all(|w| w[1] > w[0]) || !value.iter().all(|v| v.is_finite()) {
                return Err(StepError::ProfileOrder);
            }
            Ok(())
        }
    }
}

fn load_segment(segment: Segment, base_dir: &Path) -> Result<Step, ProgramError> {
    Ok(match segment {
        Segment::Ramp {
            to,
            rate_per_s,
            relative,
        } => Step::Ramp {
            to,
            rate_per_s,
            relative,
        },
        Segment::Hold { duration_s } => Step::Hold { duration_s },
        Segment::Sine {
            amplitude,
            frequency_hz,
            cycles,
        } => Step::Sine {
            amplitude,
            frequency_hz,
            cycles,
        },
        Segment::Triangle {
            amplitude,
            frequency_hz,
            cycles,
        } => Step::Triangle {
            amplitude,
            frequency_hz,
            cycles,
        },
        Segment::Csv { path, relative } => {
            let full = base_dir.join(&path);
            let text = std::fs::read_to_string(&full).map_err(|reason| {
                ProgramError::ProfileUnreadable {
                    path: full.clone(),
                    reason,
                }
            })?;
            let (t_s, value) = parse_profile_csv(&text)
                .map_err(|reason| ProgramError::Profile { path: full, reason })?;
            Step::Profile {
                t_s,
                value,
                relative,
            }
        }
    })
}

/// Rows `t_s,value`; blank lines, `#` comments and one non-numeric header line are skipped.
pub fn parse_profile_csv(text: &str) -> Result<(Vec<f64>, Vec<f64>), ProfileError> {
    let mut t_s = Vec::new();
    let mut value = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut fields = line.split(',').map(str::trim);
        let (Some(a), Some(b)) = (fields.next(), fields.next()) else {
            return Err(ProfileError::Fields { line: number + 1 });
        };
        match (a.parse::<f64>(), b.parse::<f64>()) {
            (Ok(t), Ok(v)) => {
                t_s.push(t);
                value.push(v);
            }
            _ if t_s.is_empty() && number == 0 => continue, // header
            _ => {
                return Err(ProfileError::NotNumbers {
                    line: number + 1,
                    text: line.to_string(),
                })
            }
        }
        if t_s.len() > MAX_PROFILE_SAMPLES {
            return Err(ProfileError::TooManyRows);
        }
    }
    Ok((t_s, value))
}
