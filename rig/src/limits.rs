//! Limits and detectors on every channel, and what a trip does.
//!
//! Each actuator has stroke, force, following-error and rate limits, and an invalid-signal
//! detector (NaN or infinite position, force or plant state). A trip runs its configured action
//! once, on the rising edge, and stays latched (shown in `RigSnapshot::limits_tripped`) until
//! `RigCommand::ResetLimits` with the condition cleared. Set-points and programs that would go
//! beyond a limit are refused before they start (see `Rig::command`).

use crate::hydraulics::ACTUATOR_COUNT;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LimitAction {
    /// Show the trip, change nothing.
    Indicate,
    /// Pause the running program (set-points freeze).
    ProgramHold,
    /// Stop the running program, staying at the present level.
    ProgramStop,
    /// Close the valves and cut the supply.
    HydraulicsOff,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LimitKind {
    Stroke = 0,
    Force = 1,
    FollowingError = 2,
    Rate = 3,
    Invalid = 4,
}

impl LimitKind {
    pub const ALL: [LimitKind; 5] = [
        LimitKind::Stroke,
        LimitKind::Force,
        LimitKind::FollowingError,
        LimitKind::Rate,
        LimitKind::Invalid,
    ];

    /// Bit of `RigSnapshot::limits_tripped` for this kind on actuator `index`.
    pub fn bit(self, actuator_index: usize) -> u32 {
        assert!(actuator_index < ACTUATOR_COUNT);
        1 << (self as usize * ACTUATOR_COUNT + actuator_index)
    }

    pub fn name(self) -> &'static str {
        ["stroke", "force", "following_error", "rate", "invalid"][self as usize]
    }
}

/// Bit of `limits_tripped` set when a specimen break was detected.
pub const SPECIMEN_BREAK_BIT: u32 = 1 << 30;
/// Bit of `limits_tripped` set while the emergency stop is latched.
pub const EMERGENCY_STOP_BIT: u32 = 1 << 31;

/// Limits of one actuator. Following error is in mm in displacement-type control and in kN in
/// force control.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChannelLimits {
    pub stroke_min_mm: f64,
    pub stroke_max_mm: f64,
    pub force_min_kn: f64,
    pub force_max_kn: f64,
    pub following_error_mm: f64,
    pub following_error_kn: f64,
    pub rate_max_mm_s: f64,
}

impl ChannelLimits {
    /// Inside the mechanical stroke (±125 mm) and the rated force.
    pub fn for_actuator(half_stroke_mm: f64, rated_force_kn: f64) -> ChannelLimits {
        ChannelLimits {
            stroke_min_mm: -(half_stroke_mm - 5.0),
            stroke_max_mm: half_stroke_mm - 5.0,
            force_min_kn: -0.95 * rated_force_kn,
            force_max_kn: 0.95 * rated_force_kn,
            following_error_mm: 5.0,
            following_error_kn: 0.05 * rated_force_kn,
            rate_max_mm_s: 400.0,
        }
    }

    pub fn validate(&self) -> Result<(), ChannelLimitsError> {
        let all = [
            self.stroke_min_mm,
            self.stroke_max_mm,
            self.force_min_kn,
            self.force_max_kn,
            self.following_error_mm,
            self.following_error_kn,
            self.rate_max_mm_s,
        ];
        if !all.iter().all(|v| v.is_finite()) {
            return Err(ChannelLimitsError::NotFinite);
        }
        if self.stroke_min_mm >= self.stroke_max_mm || self.force_min_kn >= self.force_max_kn {
            return Err(ChannelLimitsError::Order);
        }
        if self.following_error_mm <= 0.0
            || self.following_error_kn <= 0.0
            || self.rate_max_mm_s <= 0.0
        {
            return Err(ChannelLimitsError::NotPositive);
        }
        Ok(())
    }
}

/// Why one actuator's limits were refused.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum ChannelLimitsError {
    #[error("a limit is not a finite number")]
    NotFinite,
    #[error("a lower limit is not below its upper limit")]
    Order,
    #[error("following-error and rate limits must be positive")]
    NotPositive,
}

/// Why the limits of the machine were refused: the first actuator (0..6) whose limits are.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("actuator {actuator}: {reason}")]
pub struct LimitsError {
    pub actuator: usize,
    pub reason: ChannelLimitsError,
}

/// The action of each kind of limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct LimitActions {
    pub stroke: LimitAction,
    pub force: LimitAction,
    pub following_error: LimitAction,
    pub rate: LimitAction,
    pub invalid: LimitAction,
}

impl Default for LimitActions {
    fn default() -> Self {
        LimitActions {
            stroke: LimitAction::HydraulicsOff,
            force: LimitAction::ProgramStop,
            following_error: LimitAction::ProgramHold,
            rate: LimitAction::Indicate,
            invalid: LimitAction::HydraulicsOff,
        }
    }
}

impl LimitActions {
    pub fn of(&self, kind: LimitKind) -> LimitAction {
        match kind {
            LimitKind::Stroke => self.stroke,
            LimitKind::Force => self.force,
            LimitKind::FollowingError => self.following_error,
            LimitKind::Rate => self.rate,
            LimitKind::Invalid => self.invalid,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    pub channels: [ChannelLimits; ACTUATOR_COUNT],
    pub actions: LimitActions,
}

impl Limits {
    pub fn validate(&self) -> Result<(), LimitsError> {
        for (actuator, c) in self.channels.iter().enumerate() {
            c.validate()
                .map_err(|reason| LimitsError { actuator, reason })?;
        }
        Ok(())
    }
}

/// What the detector sees of one actuator on one step.
#[derive(Clone, Copy, Debug)]
pub struct ChannelSignals {
    pub position_mm: f64,
    pub velocity_mm_s: f64,
    pub force_kn: f64,
    /// Following error, and whether it is a force (kN) rather than a position (mm).
    pub error: f64,
    pub error_is_force: bool,
    pub plant_finite: bool,
}

/// The conditions violated now by one actuator, as a bit set of `LimitKind::bit`.
pub fn violations(limits: &ChannelLimits, s: &ChannelSignals, index: usize) -> u32 {
    let mut bits = 0;
    let finite = s.plant_finite
        && s.position_mm.is_finite()
        && s.velocity_mm_s.is_finite()
        && s.force_kn.is_finite()
        && s.error.is_finite();
    if !finite {
        return LimitKind::Invalid.bit(index);
    }
    if s.position_mm < limits.stroke_min_mm || s.position_mm > limits.stroke_max_mm {
        bits |= LimitKind::Stroke.bit(index);
    }
    if s.force_kn < limits.force_min_kn || s.force_kn > limits.force_max_kn {
        bits |= LimitKind::Force.bit(index);
    }
    let error_limit = if s.error_is_force {
        limits.following_error_kn
    } else {
        limits.following_error_mm
    };
    if s.error.abs() > error_limit {
        bits |= LimitKind::FollowingError.bit(index);
    }
    if s.velocity_mm_s.abs() > limits.rate_max_mm_s {
        bits |= LimitKind::Rate.bit(index);
    }
    bits
}
