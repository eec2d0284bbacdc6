//! The numeric codes the rig uses on the wire (`wire::RigState`, `wire::RigCommand`): one
//! table, here, so the process shell and its clients agree.

use crate::control::{AxisControl, ControlMode};
use crate::ids::{ActuatorId, Axis, Channel};
use crate::snapshot::ProgramStatus;
use crate::specimen::Loading;

/// `ActuatorState::mode` and `SetMode` values.
pub const MODE_DISPLACEMENT: u32 = 0;
pub const MODE_FORCE: u32 = 1;
/// Centroid modes apply to an axis (`channel` = axis index 0..3 in `SetMode`).
pub const MODE_CENTROID_DISPLACEMENT: u32 = 2;
pub const MODE_CENTROID_FORCE: u32 = 3;
/// Back to independent actuators (axis `channel`).
pub const MODE_INDEPENDENT: u32 = 4;

/// `SetLimit` limit codes (units of the limit: mm, kN, mm/s).
pub const LIMIT_STROKE_MIN_MM: u32 = 0;
pub const LIMIT_STROKE_MAX_MM: u32 = 1;
pub const LIMIT_FORCE_MIN_KN: u32 = 2;
pub const LIMIT_FORCE_MAX_KN: u32 = 3;
pub const LIMIT_FOLLOWING_ERROR_MM: u32 = 4;
pub const LIMIT_FOLLOWING_ERROR_KN: u32 = 5;
pub const LIMIT_RATE_MM_S: u32 = 6;

/// `StartProgram` with an empty `text`: `value` names a built-in test.
pub const TEST_UNIAXIAL: f64 = 1.0;
pub const TEST_EQUIBIAXIAL: f64 = 2.0;

/// `RigState::load_case` (defined in `wire`).
pub use wire::rig::{LOAD_CASE_EQUIBIAXIAL, LOAD_CASE_NONE, LOAD_CASE_UNIAXIAL};

pub fn actuator_mode(control: AxisControl, mode: Option<ControlMode>) -> u32 {
    match (control, mode) {
        (AxisControl::Centroid(ControlMode::Displacement), _) => MODE_CENTROID_DISPLACEMENT,
        (AxisControl::Centroid(ControlMode::Force), _) => MODE_CENTROID_FORCE,
        (AxisControl::Independent, Some(ControlMode::Force)) => MODE_FORCE,
        (AxisControl::Independent, _) => MODE_DISPLACEMENT,
    }
}

pub fn program_state(status: ProgramStatus) -> u32 {
    u32::from(crate::log::program_code(status))
}

pub fn load_case(loading: Option<Loading>) -> u32 {
    match loading {
        None => LOAD_CASE_NONE,
        Some(Loading::Uniaxial(_)) => LOAD_CASE_UNIAXIAL,
        Some(Loading::Equibiaxial) => LOAD_CASE_EQUIBIAXIAL,
    }
}

/// `SetPoint` channel codes: 0..6 actuators, 6..9 elongation X, Y, Z, 9..12 centre X, Y, Z.
pub fn channel(code: u32) -> Option<Channel> {
    let c = code as usize;
    match c {
        0..6 => Some(Channel::Actuator(ActuatorId::ALL[c])),
        6..9 => Some(Channel::Elongation(Axis::ALL[c - 6])),
        9..12 => Some(Channel::Centre(Axis::ALL[c - 9])),
        _ => None,
    }
}
