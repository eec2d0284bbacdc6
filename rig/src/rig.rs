//! The rig: hydraulics, controller, specimen, programs and limits, stepped at the control rate
//! in simulated time. One `step()` is one control period; no allocation inside it.
//!
//! Order within a step: program set-points → controller (feedback of the previous step) →
//! plant with the valve commands of the previous step (one sample of delay) → specimen forces →
//! sensors (seeded load-cell noise) → snapshot → detectors and their actions.

use crate::actuator::Actuator;
use crate::config::RigConfig;
use crate::control::{AxisControl, ControlMode, Controller, Feedback};
use crate::hydraulics::{Hydraulics, ACTUATOR_COUNT};
use crate::ids::{ActuatorId, Axis, Channel};
use crate::limits::{
    violations, ChannelLimits, ChannelSignals, LimitAction, LimitActions, LimitKind,
    EMERGENCY_STOP_BIT, SPECIMEN_BREAK_BIT,
};
use crate::program::{Program, Run, StopTransition};
use crate::refusal::Refusal;
use crate::snapshot::{ProgramStatus, RigSnapshot, SpecimenKinematics};
use crate::specimen::{Specimen, SpecimenConfig};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// What an operator, a process shell or a test asks of the rig.
#[derive(Clone, Debug, PartialEq)]
pub enum RigCommand {
    /// New set-point of an active channel (mm or kN by its mode), applied as a step.
    SetSetpoint {
        channel: Channel,
        value: f64,
    },
    /// Mode of one actuator of an independent pair (bumpless).
    SetActuatorMode {
        actuator: ActuatorId,
        mode: ControlMode,
    },
    /// Independent or centroid control of a pair (bumpless).
    SetAxisControl {
        axis: Axis,
        control: AxisControl,
    },
    /// Apply the program's setup (bumpless) and run it from the present set-points.
    StartProgram(Box<Program>),
    HoldProgram,
    ResumeProgram,
    /// Stop the program; None uses the program's own stop transition.
    StopProgram {
        transition: Option<StopTransition>,
    },
    SetLimits {
        actuator: ActuatorId,
        limits: ChannelLimits,
    },
    SetLimitActions(LimitActions),
    /// Clear latched trips whose condition has cleared.
    ResetLimits,
    HydraulicsOn,
    HydraulicsOff,
    /// Valves closed, supply off, program stopped; latched until `ResetEmergencyStop`.
    EmergencyStop,
    ResetEmergencyStop,
    /// Tear the specimen now (to exercise the break detector).
    BreakSpecimen,
    /// Mount another specimen (or none): only with no program active and the grips back at the
    /// mounting position (every elongation within [`MOUNT_TOLERANCE_MM`]).
    MountSpecimen(Option<Box<SpecimenConfig>>),
}

/// How far from the mounting position (zero elongation) the grips may be for a specimen change.
pub const MOUNT_TOLERANCE_MM: f64 = 0.5;

pub struct Rig {
    config: RigConfig,
    dt_s: f64,
    hydraulics: Hydraulics,
    controller: Controller,
    /// Valve commands computed on the previous step: the one-sample delay of the valve input.
    valve_delayed: [f64; ACTUATOR_COUNT],
    external_force_n: [f64; ACTUATOR_COUNT],
    feedback: Feedback,
    specimen: Option<Specimen>,
    kinematics: SpecimenKinematics,
    rng: ChaCha8Rng,
    hydraulics_on: bool,
    emergency_stop: bool,
    run: Option<Run>,
    program: ProgramStatus,
    /// Latched trips (bits of `LimitKind::bit`, break and emergency stop).
    tripped: u32,
    /// 20 ms running mean of each pair force, for the break detector.
    pair_force_mean_kn: [f64; 3],
    /// The specimen's solve failed on this step (a break: its reason is the specimen's fault).
    specimen_failed: bool,
    snapshot: RigSnapshot,
}

impl Rig {
    /// A rig at rest, actuators at mid stroke (the specimen mounted there, unloaded),
    /// hydraulics on, every actuator in displacement control holding its position.
    pub fn new(config: RigConfig, seed: u64) -> Result<Rig, Refusal> {
        config.validate().map_err(Refusal::invalid)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let actuators = std::array::from_fn(|i| {
            let z: f64 = StandardNormal.sample(&mut rng);
            let bias = (z * config.spool_bias_std).clamp(-0.05, 0.05);
            Actuator::new(config.actuators[i], 0.0, bias)
        });
        let specimen = match &config.specimen {
            Some(c) => Some(Specimen::new(c.clone()).map_err(Refusal::invalid)?),
            None => None,
        };
        let feedback = Feedback::default();
        let controller = Controller::new(config.gains, &feedback);
        let mut rig = Rig {
            dt_s: config.dt_s(),
            config,
            hydraulics: Hydraulics::new(actuators),
            controller,
            valve_delayed: [0.0; ACTUATOR_COUNT],
            external_force_n: [0.0; ACTUATOR_COUNT],
            feedback,
            specimen,
            kinematics: SpecimenKinematics::default(),
            rng,
            hydraulics_on: true,
            emergency_stop: false,
            run: None,
            program: ProgramStatus::Idle,
            tripped: 0,
            pair_force_mean_kn: [0.0; 3],
            specimen_failed: false,
            snapshot: RigSnapshot::default(),
        };
        rig.load_specimen();
        rig.read_sensors();
        rig.publish();
        Ok(rig)
    }

    pub fn config(&self) -> &RigConfig {
        &self.config
    }

    pub fn state(&self) -> &RigSnapshot {
        &self.snapshot
    }

    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    pub fn specimen(&self) -> Option<&Specimen> {
        self.specimen.as_ref()
    }

    /// One control period.
    pub fn step(&mut self) {
        if self.program == ProgramStatus::Running || self.program == ProgramStatus::Stopped {
            self.advance_program();
        }
        if self.hydraulics_on {
            self.controller.update(&self.feedback, self.dt_s);
        } else {
            self.controller.track(&self.feedback);
        }
        let outputs = *self.controller.output();
        let applied = if self.hydraulics_on {
            self.valve_delayed
        } else {
            [0.0; ACTUATOR_COUNT]
        };
        self.hydraulics.step(
            self.dt_s,
            self.config.plant_substeps,
            &applied,
            self.hydraulics_on,
            &self.external_force_n,
        );
        self.valve_delayed = outputs;
        self.snapshot.step += 1;
        self.load_specimen();
        self.read_sensors();
        self.publish();
        self.detect();
    }

    /// Steps until the simulated time reaches `t_s` (bounded by the step count it implies).
    pub fn advance_to(&mut self, t_s: f64) {
        assert!(t_s.is_finite() && t_s < 1.0e7, "advance_to({t_s})");
        let target_step = (t_s * self.config.control_hz).round().max(0.0) as u64;
        while self.snapshot.step < target_step {
            self.step();
        }
    }

    /// Apply a command now (between steps); the snapshot shows its effect at once.
    pub fn command(&mut self, command: RigCommand) -> Result<(), Refusal> {
        let result = self.apply(command);
        self.publish();
        result
    }

    fn apply(&mut self, command: RigCommand) -> Result<(), Refusal> {
        match command {
            RigCommand::SetSetpoint { channel, value } => self.set_setpoint(channel, value),
            RigCommand::SetActuatorMode { actuator, mode } => {
                self.refuse_if_program_active()?;
                self.check_active(Channel::Actuator(actuator))?;
                self.controller
                    .set_actuator_mode(actuator, mode, &self.feedback);
                Ok(())
            }
            RigCommand::SetAxisControl { axis, control } => {
                self.refuse_if_program_active()?;
                self.controller
                    .set_axis_control(axis, control, &self.feedback);
                Ok(())
            }
            RigCommand::StartProgram(program) => self.start_program(&program),
            RigCommand::HoldProgram => self.hold_program(),
            RigCommand::ResumeProgram => self.resume_program(),
            RigCommand::StopProgram { transition } => self.stop_program(transition),
            RigCommand::SetLimits { actuator, limits } => {
                limits.validate().map_err(Refusal::invalid)?;
                self.config.limits.channels[actuator.index()] = limits;
                Ok(())
            }
            RigCommand::SetLimitActions(actions) => {
                self.config.limits.actions = actions;
                Ok(())
            }
            RigCommand::ResetLimits => {
                self.reset_limits();
                Ok(())
            }
            RigCommand::HydraulicsOn => self.switch_hydraulics_on(),
            RigCommand::HydraulicsOff => {
                self.hydraulics_off();
                Ok(())
            }
            RigCommand::EmergencyStop => {
                self.emergency_stop = true;
                self.tripped |= EMERGENCY_STOP_BIT;
                self.hydraulics_off();
                Ok(())
            }
            RigCommand::ResetEmergencyStop => {
                self.emergency_stop = false;
                self.tripped &= !EMERGENCY_STOP_BIT;
                Ok(())
            }
            RigCommand::MountSpecimen(config) => self.mount_specimen(config),
            RigCommand::BreakSpecimen => match self.specimen.as_mut() {
                Some(specimen) => {
                    specimen.break_now();
                    Ok(())
                }
                None => Err(Refusal::Invalid {
                    reason: "no specimen is mounted".into(),
                }),
            },
        }
    }

    fn set_setpoint(&mut self, channel: Channel, value: f64) -> Result<(), Refusal> {
        if !value.is_finite() {
            return Err(Refusal::NotFinite { what: "set-point" });
        }
        self.refuse_if_program_active()?;
        let mode = self.check_active(channel)?;
        self.check_level(channel, mode, value)?;
        self.controller.set_setpoint(channel, value);
        Ok(())
    }

    fn hold_program(&mut self) -> Result<(), Refusal> {
        if self.program != ProgramStatus::Running {
            return Err(Refusal::NoProgram {
                expected: "running",
            });
        }
        self.program = ProgramStatus::Held;
        Ok(())
    }

    fn resume_program(&mut self) -> Result<(), Refusal> {
        if self.program != ProgramStatus::Held {
            return Err(Refusal::NoProgram { expected: "held" });
        }
        self.refuse_if_unsafe()?;
        self.program = ProgramStatus::Running;
        Ok(())
    }

    fn stop_program(&mut self, transition: Option<StopTransition>) -> Result<(), Refusal> {
        if !matches!(self.program, ProgramStatus::Running | ProgramStatus::Held) {
            return Err(Refusal::NoProgram {
                expected: "running or held",
            });
        }
        let run = self.run.as_mut().expect("a running program has a run");
        let transition = transition.unwrap_or(run.stop);
        let rate = run.stop_rate_per_s;
        run.stop(transition, rate);
        self.program = ProgramStatus::Stopped;
        Ok(())
    }

    /// Only trips whose condition has cleared are reset.
    fn reset_limits(&mut self) {
        self.tripped &= self.violations_now() | EMERGENCY_STOP_BIT;
    }

    /// The limit bits every actuator violates now.
    fn violations_now(&self) -> u32 {
        ActuatorId::ALL.into_iter().fold(0, |bits, id| {
            bits | violations(
                &self.config.limits.channels[id.index()],
                &self.signals(id),
                id.index(),
            )
        })
    }

    fn switch_hydraulics_on(&mut self) -> Result<(), Refusal> {
        if self.emergency_stop {
            return Err(Refusal::EmergencyStopLatched);
        }
        if !self.hydraulics_on {
            self.controller.track(&self.feedback);
            self.hydraulics_on = true;
        }
        Ok(())
    }

    /// A new specimen (or none), only with both axes back at the mounting position.
    fn mount_specimen(&mut self, config: Option<Box<SpecimenConfig>>) -> Result<(), Refusal> {
        self.refuse_if_program_active()?;
        for axis in Axis::ALL {
            let elongation_mm = self.snapshot.axes[axis.index()].elongation_mm;
            if elongation_mm.abs() > MOUNT_TOLERANCE_MM {
                return Err(Refusal::Invalid {
                    reason: format!(
                        "{axis:?} elongation is {elongation_mm:.2} mm: unload to within \
                         {MOUNT_TOLERANCE_MM} mm of the mounting position before changing \
                         the specimen"
                    ),
                });
            }
        }
        let specimen = match &config {
            Some(c) => Some(Specimen::new((**c).clone()).map_err(Refusal::invalid)?),
            None => None,
        };
        self.specimen = specimen;
        self.config.specimen = config.map(|c| *c);
        self.load_specimen();
        self.read_sensors();
        Ok(())
    }

    fn refuse_if_program_active(&self) -> Result<(), Refusal> {
        match self.program {
            ProgramStatus::Running | ProgramStatus::Held => Err(Refusal::ProgramRunning),
            _ => Ok(()),
        }
    }

    fn refuse_if_unsafe(&self) -> Result<(), Refusal> {
        if self.emergency_stop {
            return Err(Refusal::EmergencyStopLatched);
        }
        if !self.hydraulics_on {
            return Err(Refusal::HydraulicsOff);
        }
        if self.tripped != 0 {
            return Err(Refusal::LimitTripped { bits: self.tripped });
        }
        Ok(())
    }

    fn start_program(&mut self, program: &Program) -> Result<(), Refusal> {
        self.refuse_if_program_active()?;
        self.refuse_if_unsafe()?;
        program.validate().map_err(Refusal::invalid)?;
        let saved = self.controller.clone();
        let result = self.bind_program(program);
        if result.is_err() {
            self.controller = saved;
        }
        result
    }

    fn bind_program(&mut self, program: &Program) -> Result<(), Refusal> {
        for &(axis, control) in &program.setup {
            if self.controller.axis_control(axis) != control {
                self.controller
                    .set_axis_control(axis, control, &self.feedback);
            }
        }
        let mut start_levels = Vec::with_capacity(program.channels.len());
        for &(channel, _) in &program.channels {
            self.check_active(channel)?;
            start_levels.push(self.controller.setpoint(channel));
        }
        let run = Run::bind(program, &start_levels);
        for (channel, envelope) in run.envelopes() {
            let mode = self.check_active(channel)?;
            self.check_level(channel, mode, envelope.min)?;
            self.check_level(channel, mode, envelope.max)?;
            if mode == ControlMode::Displacement {
                let per_actuator = match channel {
                    Channel::Elongation(_) => 0.5 * envelope.max_rate_per_s,
                    _ => envelope.max_rate_per_s,
                };
                let limit = self.rate_limit_mm_s(channel);
                if per_actuator > limit {
                    return Err(Refusal::BeyondLimit {
                        channel,
                        what: "rate (mm/s per actuator)",
                        value: per_actuator,
                        limit,
                    });
                }
            }
        }
        self.run = Some(run);
        self.program = ProgramStatus::Running;
        Ok(())
    }

    fn rate_limit_mm_s(&self, channel: Channel) -> f64 {
        let axis = match channel {
            Channel::Actuator(id) => return self.config.limits.channels[id.index()].rate_max_mm_s,
            Channel::Elongation(axis) | Channel::Centre(axis) => axis,
        };
        let c = &self.config.limits.channels;
        c[axis.plus().index()]
            .rate_max_mm_s
            .min(c[axis.minus().index()].rate_max_mm_s)
    }

    fn check_active(&self, channel: Channel) -> Result<ControlMode, Refusal> {
        self.controller
            .channel_mode(channel)
            .ok_or(Refusal::ChannelInactive { channel })
    }

    /// Refuses a level of `channel` that would put an actuator beyond its stroke or force
    /// limits (elongation and centre are mapped to the two actuator positions).
    fn check_level(&self, channel: Channel, mode: ControlMode, value: f64) -> Result<(), Refusal> {
        if !value.is_finite() {
            return Err(Refusal::NotFinite { what: "level" });
        }
        let limits = &self.config.limits.channels;
        let stroke = |id: ActuatorId, position_mm: f64| {
            let l = &limits[id.index()];
            if position_mm > l.stroke_max_mm {
                Err(Refusal::BeyondLimit {
                    channel,
                    what: "stroke (mm)",
                    value: position_mm,
                    limit: l.stroke_max_mm,
                })
            } else if position_mm < l.stroke_min_mm {
                Err(Refusal::BeyondLimit {
                    channel,
                    what: "stroke (mm)",
                    value: position_mm,
                    limit: l.stroke_min_mm,
                })
            } else {
                Ok(())
            }
        };
        let force = |id: ActuatorId, force_kn: f64| {
            let l = &limits[id.index()];
            if force_kn > l.force_max_kn {
                Err(Refusal::BeyondLimit {
                    channel,
                    what: "force (kN)",
                    value: force_kn,
                    limit: l.force_max_kn,
                })
            } else if force_kn < l.force_min_kn {
                Err(Refusal::BeyondLimit {
                    channel,
                    what: "force (kN)",
                    value: force_kn,
                    limit: l.force_min_kn,
                })
            } else {
                Ok(())
            }
        };
        match (channel, mode) {
            (Channel::Actuator(id), ControlMode::Displacement) => stroke(id, value),
            (Channel::Actuator(id), ControlMode::Force) => force(id, value),
            (Channel::Elongation(axis), ControlMode::Displacement) => {
                let centre = self.controller.setpoint(Channel::Centre(axis));
                stroke(axis.plus(), 0.5 * value + centre)?;
                stroke(axis.minus(), 0.5 * value - centre)
            }
            (Channel::Elongation(axis), ControlMode::Force) => {
                force(axis.plus(), value)?;
                force(axis.minus(), value)
            }
            (Channel::Centre(axis), _) => {
                let half = match self.controller.channel_mode(Channel::Elongation(axis)) {
                    Some(ControlMode::Displacement) => {
                        0.5 * self.controller.setpoint(Channel::Elongation(axis))
                    }
                    _ => 0.5 * self.feedback.elongation_mm(axis),
                };
                stroke(axis.plus(), half + value)?;
                stroke(axis.minus(), half - value)
            }
        }
    }

    fn advance_program(&mut self) {
        let Some(run) = self.run.as_mut() else {
            return;
        };
        let controller = &mut self.controller;
        run.advance(self.dt_s, |channel, value| {
            debug_assert!(value.is_finite());
            if controller.channel_mode(channel).is_some() {
                controller.set_setpoint(channel, value);
            }
        });
        if self.program == ProgramStatus::Running && run.is_finished() {
            self.program = ProgramStatus::Finished;
        }
    }

    fn hydraulics_off(&mut self) {
        self.hydraulics_on = false;
        self.stop_program_here();
    }

    /// Stop the program where it is (the transition of limit actions and breaks).
    fn stop_program_here(&mut self) {
        if let (ProgramStatus::Running | ProgramStatus::Held, Some(run)) =
            (self.program, self.run.as_mut())
        {
            let rate = run.stop_rate_per_s;
            run.stop(StopTransition::Stay, rate);
            self.program = ProgramStatus::Stopped;
        }
    }

    fn load_specimen(&mut self) {
        let positions = self.feedback_positions();
        let Some(specimen) = self.specimen.as_mut() else {
            self.external_force_n = [0.0; ACTUATOR_COUNT];
            self.kinematics = SpecimenKinematics::default();
            return;
        };
        let t_s = self.snapshot.step as f64 * self.dt_s;
        let response = specimen.respond(t_s, &positions);
        self.specimen_failed |= response.failed_now;
        self.external_force_n = response.grip_force_n;
        self.kinematics = response.kinematics;
    }

    fn feedback_positions(&self) -> [f64; ACTUATOR_COUNT] {
        std::array::from_fn(|i| self.hydraulics.actuators[i].position_mm())
    }

    fn read_sensors(&mut self) {
        for (i, actuator) in self.hydraulics.actuators.iter().enumerate() {
            self.feedback.position_mm[i] = actuator.position_mm();
            let noise: f64 = StandardNormal.sample(&mut self.rng);
            self.feedback.force_kn[i] =
                self.external_force_n[i] * 1.0e-3 + noise * self.config.load_cell_noise_kn;
        }
    }

    fn signals(&self, id: ActuatorId) -> ChannelSignals {
        let a = &self.snapshot.actuators[id.index()];
        ChannelSignals {
            position_mm: a.position_mm,
            velocity_mm_s: a.velocity_mm_s,
            force_kn: a.force_kn,
            error: if self.hydraulics_on { a.error } else { 0.0 },
            error_is_force: self.controller.position_command_mm(id).is_none(),
            plant_finite: self.hydraulics.actuators[id.index()].is_finite(),
        }
    }

    /// Limit detectors and the break detector, then their actions (rising edges only).
    fn detect(&mut self) {
        let now = self.violations_now();
        let mut rising = now & !self.tripped;
        // A specimen that cannot be solved any more is unloaded as a torn one.
        if std::mem::take(&mut self.specimen_failed) {
            rising |= SPECIMEN_BREAK_BIT;
        }
        // Break detector on the X and Y pairs.
        let alpha = self.dt_s / 0.020;
        for axis in [Axis::X, Axis::Y] {
            let a = axis.index();
            let force_kn = self.feedback.pair_force_kn(axis);
            let mean = self.pair_force_mean_kn[a];
            if mean > self.config.break_detect_min_kn
                && force_kn < 0.5 * mean
                && self.tripped & SPECIMEN_BREAK_BIT == 0
            {
                rising |= SPECIMEN_BREAK_BIT;
            }
            self.pair_force_mean_kn[a] = mean + alpha * (force_kn - mean);
        }
        if rising == 0 {
            return;
        }
        self.tripped |= rising;
        let actions = self.config.limits.actions;
        let mut worst: Option<LimitAction> = None;
        for kind in LimitKind::ALL {
            let any = ActuatorId::ALL
                .iter()
                .any(|id| rising & kind.bit(id.index()) != 0);
            if any {
                worst = worst.max(Some(actions.of(kind)));
            }
        }
        if rising & SPECIMEN_BREAK_BIT != 0 {
            // A break: displacement hold everywhere, program stopped.
            self.stop_program_here();
            self.controller.displacement_hold(&self.feedback);
        }
        match worst {
            None | Some(LimitAction::Indicate) => {}
            Some(LimitAction::ProgramHold) => {
                if self.program == ProgramStatus::Running {
                    self.program = ProgramStatus::Held;
                }
            }
            Some(LimitAction::ProgramStop) => self.stop_program_here(),
            Some(LimitAction::HydraulicsOff) => self.hydraulics_off(),
        }
        self.publish();
    }

    fn publish(&mut self) {
        let s = &mut self.snapshot;
        s.t_s = s.step as f64 * self.dt_s;
        s.hydraulics_on = self.hydraulics_on;
        s.emergency_stop = self.emergency_stop;
        s.program = self.program;
        s.program_t_s = self.run.as_ref().map_or(0.0, |r| r.t_s);
        s.limits_tripped = self.tripped;
        s.specimen = self.kinematics;
        s.supply_flow_scale = self.hydraulics.last_flow_scale;
        for id in ActuatorId::ALL {
            let i = id.index();
            let actuator = &self.hydraulics.actuators[i];
            let a = &mut s.actuators[i];
            a.position_mm = actuator.position_mm();
            a.velocity_mm_s = actuator.velocity_mm_s();
            a.force_kn = self.feedback.force_kn[i];
            a.valve = self.controller.output()[i];
            a.mode = self.controller.channel_mode(Channel::Actuator(id));
            match self.controller.position_command_mm(id) {
                Some(command) => {
                    a.command = command;
                    a.error = command - a.position_mm;
                }
                None => {
                    a.command = match self.controller.axis_control(id.axis()) {
                        AxisControl::Independent => self.controller.setpoint(Channel::Actuator(id)),
                        AxisControl::Centroid(_) => {
                            self.controller.setpoint(Channel::Elongation(id.axis()))
                        }
                    };
                    a.error = a.command - a.force_kn;
                }
            }
        }
        for axis in Axis::ALL {
            let x = &mut s.axes[axis.index()];
            x.control = self.controller.axis_control(axis);
            x.centre_mm = self.feedback.centre_mm(axis);
            x.elongation_mm = self.feedback.elongation_mm(axis);
            x.force_kn = self.feedback.pair_force_kn(axis);
        }
    }
}
