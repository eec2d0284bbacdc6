//! Why a command was refused. A command is never clamped silently: it is accepted as given or
//! refused with one of these reasons.

use crate::ids::Channel;
use std::fmt;

#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Refusal {
    /// A NaN or infinite number in the command.
    #[error("{what} is not a finite number")]
    NotFinite { what: &'static str },
    /// A value outside a configured limit.
    #[error("{what} {} on {channel} is beyond the limit {}", number(*.value), number(*.limit))]
    BeyondLimit {
        channel: Channel,
        what: &'static str,
        value: f64,
        limit: f64,
    },
    /// The channel is not driven in the present mode (e.g. an actuator of a centroid pair).
    #[error("{channel} is not driven in the present control mode")]
    ChannelInactive { channel: Channel },
    /// Hydraulics are off (after an emergency stop or a trip).
    #[error("hydraulics are off")]
    HydraulicsOff,
    /// An emergency stop is latched; reset it first.
    #[error("emergency stop is latched: reset it first")]
    EmergencyStopLatched,
    /// A program is running; hold or stop it first.
    #[error("a program is running: hold or stop it first")]
    ProgramRunning,
    /// No program is loaded, running or held, as the command needs.
    #[error("no program {expected}")]
    NoProgram { expected: &'static str },
    /// A latched limit trip (bit set of `RigSnapshot::limits_tripped`); reset limits first.
    #[error("limits are tripped (bits {bits:#010x}): reset limits first")]
    LimitTripped { bits: u32 },
    /// The command is malformed (parse errors of program files and the like).
    #[error("invalid command: {reason}")]
    Invalid { reason: String },
}

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
