//! A `rig/command` request to a core command, or the reason it is refused: the layout and
//! kind checked, a program (a file's, or a built-in test on its specimen), a control mode or
//! a limit code read.

use super::{CommandRefused, ProcessOptions};
use crate::builtin::BuiltinTest;
use crate::codes;
use crate::control::{AxisControl, ControlMode};
use crate::ids::{ActuatorId, Axis};
use crate::program::{Program, StopTransition};
use crate::rig::{Rig, RigCommand};
use std::path::PathBuf;
use wire::rig::RigCommandKind;

/// A `wire::RigCommand` to a core command, refused with a reason when malformed or refused.
pub(super) fn handle(
    rig: &mut Rig,
    request: &wire::RigCommand,
    options: &ProcessOptions,
) -> Result<(), CommandRefused> {
    let command = match checked_kind(request)? {
        RigCommandKind::StartProgram => {
            RigCommand::StartProgram(Box::new(program(rig, request, options)?))
        }
        RigCommandKind::Hold => RigCommand::HoldProgram,
        RigCommandKind::Resume => RigCommand::ResumeProgram,
        RigCommandKind::Stop => RigCommand::StopProgram {
            transition: Some(if request.value == 0.0 {
                StopTransition::Stay
            } else {
                StopTransition::RampToZero
            }),
        },
        RigCommandKind::SetMode => set_mode(request)?,
        RigCommandKind::SetLimit => set_limit(rig, request)?,
        RigCommandKind::EmergencyStop => RigCommand::EmergencyStop,
        RigCommandKind::SetPoint => RigCommand::SetSetpoint {
            channel: codes::channel(request.channel).ok_or(CommandRefused::NotAChannel {
                channel: request.channel,
            })?,
            value: request.value,
        },
    };
    Ok(rig.command(command)?)
}

/// The request's kind, once its layout and value are known good.
fn checked_kind(request: &wire::RigCommand) -> Result<RigCommandKind, CommandRefused> {
    wire::layouts::check_version("rig command", request.layout_version)
        .map_err(|e| CommandRefused::LayoutVersion { found: e.found })?;
    let kind = RigCommandKind::from_code(request.kind)
        .ok_or(CommandRefused::UnknownKind { kind: request.kind })?;
    if !request.value.is_finite() {
        return Err(CommandRefused::NotFinite);
    }
    Ok(kind)
}

/// The actuator the request's channel names.
fn actuator(request: &wire::RigCommand) -> Result<ActuatorId, CommandRefused> {
    let channel = request.channel;
    nth(&ActuatorId::ALL, channel).ok_or(CommandRefused::NotAnActuator { channel })
}

/// The axis the request's channel names.
fn axis(request: &wire::RigCommand) -> Result<Axis, CommandRefused> {
    let channel = request.channel;
    nth(&Axis::ALL, channel).ok_or(CommandRefused::NotAnAxis { channel })
}

/// Element `channel` of `all`, if there is one.
fn nth<T: Copy>(all: &[T], channel: u32) -> Option<T> {
    all.get(channel as usize).copied()
}

/// The program a start names: a TOML file's (the request's text), or a built-in test (its
/// value) on its own specimen.
fn program(
    rig: &Rig,
    request: &wire::RigCommand,
    options: &ProcessOptions,
) -> Result<Program, CommandRefused> {
    let text = wire::text::read_fixed(&request.text);
    if !text.is_empty() {
        let path = PathBuf::from(&text);
        let toml =
            std::fs::read_to_string(&path).map_err(|reason| CommandRefused::ProgramUnreadable {
                path: path.clone(),
                reason,
            })?;
        let base = path.parent().map(PathBuf::from).unwrap_or_default();
        return Ok(Program::from_toml(&toml, &base)?);
    }
    let test = if request.value == codes::TEST_UNIAXIAL {
        BuiltinTest::Uniaxial
    } else if request.value == codes::TEST_EQUIBIAXIAL {
        BuiltinTest::Equibiaxial
    } else {
        return Err(CommandRefused::UnknownTest {
            value: request.value,
        });
    };
    let mounted = rig.specimen().map(|s| s.config());
    match mounted {
        Some(specimen) if specimen.loading == test.loading() => {
            Ok(test.program(specimen, options.test_rate_per_s, options.test_stretch)?)
        }
        _ => Err(CommandRefused::NeedsSpecimen {
            test: test.name(),
            mounted: mounted.map(|s| s.loading.name()),
        }),
    }
}

/// An actuator's or an axis's control mode from the request's mode code.
fn set_mode(request: &wire::RigCommand) -> Result<RigCommand, CommandRefused> {
    Ok(match request.value as u32 {
        codes::MODE_DISPLACEMENT => RigCommand::SetActuatorMode {
            actuator: actuator(request)?,
            mode: ControlMode::Displacement,
        },
        codes::MODE_FORCE => RigCommand::SetActuatorMode {
            actuator: actuator(request)?,
            mode: ControlMode::Force,
        },
        codes::MODE_CENTROID_DISPLACEMENT => RigCommand::SetAxisControl {
            axis: axis(request)?,
            control: AxisControl::Centroid(ControlMode::Displacement),
        },
        codes::MODE_CENTROID_FORCE => RigCommand::SetAxisControl {
            axis: axis(request)?,
            control: AxisControl::Centroid(ControlMode::Force),
        },
        codes::MODE_INDEPENDENT => RigCommand::SetAxisControl {
            axis: axis(request)?,
            control: AxisControl::Independent,
        },
        code => return Err(CommandRefused::ModeCode { code }),
    })
}

/// The actuator's limits with the one the request's limit code names set to its value.
fn set_limit(rig: &Rig, request: &wire::RigCommand) -> Result<RigCommand, CommandRefused> {
    let id = actuator(request)?;
    let mut limits = rig.config().limits.channels[id.index()];
    let v = request.value;
    match request.limit {
        codes::LIMIT_STROKE_MIN_MM => limits.stroke_min_mm = v,
        codes::LIMIT_STROKE_MAX_MM => limits.stroke_max_mm = v,
        codes::LIMIT_FORCE_MIN_KN => limits.force_min_kn = v,
        codes::LIMIT_FORCE_MAX_KN => limits.force_max_kn = v,
        codes::LIMIT_FOLLOWING_ERROR_MM => limits.following_error_mm = v,
        codes::LIMIT_FOLLOWING_ERROR_KN => limits.following_error_kn = v,
        codes::LIMIT_RATE_MM_S => limits.rate_max_mm_s = v,
        code => return Err(CommandRefused::LimitCode { code }),
    }
    Ok(RigCommand::SetLimits {
        actuator: id,
        limits,
    })
}
