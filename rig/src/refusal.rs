//! Why a command was refused. A command is never clamped silently: it is accepted as given or
//! refused with one of these reasons.

use crate::ids::Channel;
use std::fmt;

#[derive(Clone, Debug, PartialEq)]
pub enum Refusal {
    /// A NaN or infinite number in the command.
    NotFinite { what: &'static str },
    /// A value outside a configured limit.
    BeyondLimit {
        channel: Channel,
        what: &'static str,
        value: f64,
        limit: f64,
    },
    /// The channel is not driven in the present mode (e.g. an actuator of a centroid pair).
    ChannelInactive { channel: Channel },
    /// Hydraulics are off (after an emergency stop or a trip).
    HydraulicsOff,
    /// An emergency stop is latched; reset it first.
    EmergencyStopLatched,
    /// A program is running; hold or stop it first.
    ProgramRunning,
    /// No program is loaded, running or held, as the command needs.
    NoProgram { expected: &'static str },
    /// A latched limit trip (bit set of `RigSnapshot::limits_tripped`); reset limits first.
    LimitTripped { bits: u32 },
    /// The command is malformed (parse errors of program files and the like).
    Invalid { reason: String },
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refusal::NotFinite { what } => write!(f, "{what} is not a finite number"),
            Refusal::BeyondLimit {
                channel,
                what,
                value,
                limit,
            } => {
                write!(
                    f,
                    "{what} {} on {channel} is beyond the limit {}",
                    number(*value),
                    number(*limit)
                )
            }
            Refusal::ChannelInactive { channel } => {
                write!(f, "{channel} is not driven in the present control mode")
            }
            Refusal::HydraulicsOff => write!(f, "hydraulics are off"),
            Refusal::EmergencyStopLatched => {
                write!(f, "emergency stop is latched: reset it first")
            }
            Refusal::ProgramRunning => write!(f, "a program is running: hold or stop it first"),
            Refusal::NoProgram { expected } => write!(f, "no program {expected}"),
            Refusal::LimitTripped { bits } => {
                write!(
                    f,
                    "limits are tripped (bits {bits:#010x}): reset limits first"
                )
            }
            Refusal::Invalid { reason } => write!(f, "invalid command: {reason}"),
        }
    }
}

impl std::error::Error for Refusal {}

impl Refusal {
    /// A malformed command, refused with `reason` (a program's or configuration's error).
    pub fn invalid(reason: impl fmt::Display) -> Refusal {
        Refusal::Invalid {
            reason: reason.to_string(),
        }
    }
}

/// A number as a person reads it: plain when moderate, in exponent form when huge or tiny
/// (1e300, not three hundred digits).
pub fn number(value: f64) -> String {
    let magnitude = value.abs();
    if value == 0.0 || (1e-4..1e7).contains(&magnitude) {
        format!("{value}")
    } else {
        format!("{value:e}")
    }
}
