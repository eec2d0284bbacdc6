//! Interlocks: limits trip with their configured action, commands beyond limits and NaN
//! commands are refused, the emergency stop halts, a specimen break goes to displacement hold.

use rig::limits::{EMERGENCY_STOP_BIT, SPECIMEN_BREAK_BIT};
use rig::{
    ActuatorId, AxisControl, Channel, ControlMode, LimitAction, LimitKind, Program, ProgramStatus,
    Refusal, Rig, RigCommand, RigConfig,
};

fn ramp_program(to_mm: f64, rate_mm_s: f64) -> Box<Program> {
    let text = format!(
        r#"
        [[setup]]
        axis = "x"
        control = "centroid_displacement"
        [[setup]]
        axis = "y"
        control = "centroid_displacement"
        [[channel]]
        target = "x.elongation"
        segments = [{{ kind = "ramp", to = {to_mm}, rate_per_s = {rate_mm_s} }}]
        [[channel]]
        target = "y.elongation"
        segments = [{{ kind = "ramp", to = {to_mm}, rate_per_s = {rate_mm_s} }}]
        "#
    );
    Box::new(Program::from_toml(&text, std::path::Path::new(".")).unwrap())
}

#[test]
fn stroke_limit_trips_with_hydraulics_off() {
    let mut rig = Rig::new(RigConfig::default(), 1).unwrap();
    let id = ActuatorId::XPlus;
    rig.command(RigCommand::SetSetpoint {
        channel: Channel::Actuator(id),
        value: 1.9,
    })
    .unwrap();
    rig.advance_to(0.5);
    assert_eq!(rig.state().limits_tripped, 0);
    let mut limits = rig.config().limits.channels[id.index()];
    limits.stroke_max_mm = 1.0;
    rig.command(RigCommand::SetLimits {
        actuator: id,
        limits,
    })
    .unwrap();
    rig.step();
    let s = rig.state();
    assert_ne!(s.limits_tripped & LimitKind::Stroke.bit(id.index()), 0);
    assert!(!s.hydraulics_on, "stroke action is hydraulics off");
    // Latched: reset refused to clear while the condition holds, then clears.
    rig.command(RigCommand::ResetLimits).unwrap();
    assert_ne!(rig.state().limits_tripped, 0);
    limits.stroke_max_mm = 10.0;
    rig.command(RigCommand::SetLimits {
        actuator: id,
        limits,
    })
    .unwrap();
    rig.command(RigCommand::ResetLimits).unwrap();
    assert_eq!(rig.state().limits_tripped, 0);
    rig.command(RigCommand::HydraulicsOn).unwrap();
    let before = rig.state().actuators[id.index()].position_mm;
    rig.advance_to(1.0);
    let after = rig.state().actuators[id.index()].position_mm;
    assert!(
        (after - before).abs() < 0.01,
        "bumpless restart: {before} → {after}"
    );
}

#[test]
fn force_limit_stops_the_program() {
    let mut rig = Rig::new(RigConfig::default(), 2).unwrap();
    for id in [ActuatorId::XPlus, ActuatorId::XMinus] {
        let mut limits = rig.config().limits.channels[id.index()];
        limits.force_max_kn = 0.2;
        rig.command(RigCommand::SetLimits {
            actuator: id,
            limits,
        })
        .unwrap();
    }
    let mut actions = rig.config().limits.actions;
    actions.force = LimitAction::ProgramStop;
    rig.command(RigCommand::SetLimitActions(actions)).unwrap();
    rig.command(RigCommand::StartProgram(ramp_program(60.0, 5.0)))
        .unwrap();
    rig.advance_to(20.0);
    let s = rig.state();
    assert_ne!(
        s.limits_tripped & LimitKind::Force.bit(ActuatorId::XPlus.index()),
        0
    );
    assert_eq!(s.program, ProgramStatus::Stopped);
    assert!(s.hydraulics_on);
    // Stopped "stay": the elongation stays near where the trip happened (≈0.2 kN, λ ≈ 1.15).
    let elongation = s.axes[0].elongation_mm;
    assert!(
        (10.0..25.0).contains(&elongation),
        "elongation {elongation} mm"
    );
    rig.advance_to(22.0);
    assert!((rig.state().axes[0].elongation_mm - elongation).abs() < 0.05);
}

#[test]
fn commands_beyond_limits_and_nan_are_refused() {
    let mut rig = Rig::new(RigConfig::default(), 3).unwrap();
    let channel = Channel::Actuator(ActuatorId::YMinus);
    let err = rig
        .command(RigCommand::SetSetpoint {
            channel,
            value: f64::NAN,
        })
        .unwrap_err();
    assert_eq!(err, Refusal::NotFinite { what: "set-point" });
    let err = rig
        .command(RigCommand::SetSetpoint {
            channel,
            value: 200.0,
        })
        .unwrap_err();
    assert!(
        matches!(
            err,
            Refusal::BeyondLimit {
                what: "stroke (mm)",
                ..
            }
        ),
        "{err}"
    );
    println!("refused: {err}");
    // A program whose envelope leaves the stroke is refused before it starts, modes restored.
    let err = rig
        .command(RigCommand::StartProgram(ramp_program(400.0, 1.0)))
        .unwrap_err();
    assert!(matches!(err, Refusal::BeyondLimit { .. }), "{err}");
    assert_eq!(rig.state().program, ProgramStatus::Idle);
    assert_eq!(rig.state().axes[0].control, AxisControl::Independent);
    // Too fast a ramp.
    let err = rig
        .command(RigCommand::StartProgram(ramp_program(10.0, 2000.0)))
        .unwrap_err();
    assert!(
        matches!(
            err,
            Refusal::BeyondLimit {
                what: "rate (mm/s per actuator)",
                ..
            }
        ),
        "{err}"
    );
    // An actuator of a centroid pair is not an active channel.
    rig.command(RigCommand::SetAxisControl {
        axis: rig::Axis::Y,
        control: AxisControl::Centroid(ControlMode::Displacement),
    })
    .unwrap();
    let err = rig
        .command(RigCommand::SetSetpoint {
            channel,
            value: 1.0,
        })
        .unwrap_err();
    assert_eq!(err, Refusal::ChannelInactive { channel });
    // NaN in a program file.
    let nan = "[[channel]]\ntarget = \"x+\"\nsegments = [{ kind = \"ramp\", to = nan, rate_per_s = 1.0 }]";
    assert!(Program::from_toml(nan, std::path::Path::new(".")).is_err());
}

#[test]
fn emergency_stop_halts() {
    let mut rig = Rig::new(RigConfig::default(), 4).unwrap();
    rig.command(RigCommand::StartProgram(ramp_program(40.0, 2.0)))
        .unwrap();
    rig.advance_to(5.0);
    rig.command(RigCommand::EmergencyStop).unwrap();
    let s = rig.state();
    assert!(!s.hydraulics_on && s.emergency_stop);
    assert_eq!(s.program, ProgramStatus::Stopped);
    assert_ne!(s.limits_tripped & EMERGENCY_STOP_BIT, 0);
    let before = s.axes[0].elongation_mm;
    rig.advance_to(6.0);
    let after = rig.state().axes[0].elongation_mm;
    println!("emergency stop: elongation {before:.4} → {after:.4} mm in 1 s");
    assert!((after - before).abs() < 0.5, "halted: {before} → {after}");
    assert_eq!(
        rig.command(RigCommand::HydraulicsOn),
        Err(Refusal::EmergencyStopLatched)
    );
    assert!(matches!(
        rig.command(RigCommand::StartProgram(ramp_program(40.0, 2.0))),
        Err(Refusal::ProgramRunning | Refusal::EmergencyStopLatched)
    ));
    rig.command(RigCommand::ResetEmergencyStop).unwrap();
    rig.command(RigCommand::HydraulicsOn).unwrap();
}

#[test]
fn specimen_break_goes_to_displacement_hold() {
    let mut rig = Rig::new(RigConfig::default(), 5).unwrap();
    rig.command(RigCommand::StartProgram(ramp_program(60.0, 5.0)))
        .unwrap();
    rig.advance_to(6.0);
    assert!(rig.state().axes[0].force_kn > 0.2);
    rig.command(RigCommand::BreakSpecimen).unwrap();
    rig.advance_to(6.1);
    let s = rig.state();
    assert_ne!(s.limits_tripped & SPECIMEN_BREAK_BIT, 0, "break detected");
    assert!(s.specimen.broken);
    assert_eq!(s.program, ProgramStatus::Stopped);
    for axis in rig::Axis::ALL {
        assert_eq!(s.axes[axis.index()].control, AxisControl::Independent);
    }
    for a in &s.actuators {
        assert_eq!(a.mode, Some(ControlMode::Displacement));
    }
    let held: Vec<f64> = s.actuators.iter().map(|a| a.position_mm).collect();
    rig.advance_to(7.0);
    for (a, before) in rig.state().actuators.iter().zip(held) {
        assert!(
            (a.position_mm - before).abs() < 0.05,
            "hold: {before} → {}",
            a.position_mm
        );
    }
}

#[test]
fn mode_switches_are_bumpless() {
    let mut rig = Rig::new(RigConfig::default(), 6).unwrap();
    rig.command(RigCommand::SetSetpoint {
        channel: Channel::Actuator(ActuatorId::XPlus),
        value: 3.0,
    })
    .unwrap();
    rig.advance_to(1.0);
    let before = rig.state().actuators;
    rig.command(RigCommand::SetAxisControl {
        axis: rig::Axis::X,
        control: AxisControl::Centroid(ControlMode::Displacement),
    })
    .unwrap();
    rig.advance_to(1.5);
    rig.command(RigCommand::SetAxisControl {
        axis: rig::Axis::X,
        control: AxisControl::Independent,
    })
    .unwrap();
    rig.command(RigCommand::SetActuatorMode {
        actuator: ActuatorId::ZPlus,
        mode: ControlMode::Force,
    })
    .unwrap();
    rig.advance_to(2.0);
    let after = rig.state().actuators;
    // Z+ is now in force control with nothing to push against: it may drift, as a real one
    // would; the others must not have moved.
    let z_plus = ActuatorId::ZPlus.index();
    for (b, a) in before.iter().zip(after.iter()).take(z_plus) {
        assert!(
            (a.position_mm - b.position_mm).abs() < 0.01,
            "{} → {}",
            b.position_mm,
            a.position_mm
        );
    }
}
