//! The rig: hydraulics, controller, specimen, programs and limits, stepped at the control rate
//! in simulated time. One `step()` is one control period; no allocation inside it.

use crate::actuator::Actuator;
use crate::config::RigConfig;
use crate::control::{AxisControl, ControlMode, Controller, Feedback};
use crate::hydraulics::{Hydraulics, ACTUATOR_COUNT};
use crate::ids::{ActuatorId, Axis, Channel};
use crate::refusal::Refusal;
use crate::snapshot::RigSnapshot;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// What an operator, a program shell or a test asks of the rig.
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
    HydraulicsOn,
    HydraulicsOff,
    /// Valves closed, supply off, program stopped; latched until `ResetEmergencyStop`.
    EmergencyStop,
    ResetEmergencyStop,
}

pub struct Rig {
    config: RigConfig,
    dt_s: f64,
    hydraulics: Hydraulics,
    controller: Controller,
    /// Valve commands computed on the previous step: the one-sample delay of the valve input.
    valve_delayed: [f64; ACTUATOR_COUNT],
    external_force_n: [f64; ACTUATOR_COUNT],
    feedback: Feedback,
    rng: ChaCha8Rng,
    hydraulics_on: bool,
    emergency_stop: bool,
    snapshot: RigSnapshot,
}

impl Rig {
    /// A rig at rest, actuators at mid stroke, hydraulics on, displacement control holding.
    pub fn new(config: RigConfig, seed: u64) -> Result<Rig, Refusal> {
        config
            .validate()
            .map_err(|reason| Refusal::Invalid { reason })?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let actuators = std::array::from_fn(|i| {
            let z: f64 = StandardNormal.sample(&mut rng);
            let bias = (z * config.spool_bias_std).clamp(-0.05, 0.05);
            Actuator::new(config.actuators[i], 0.0, bias)
        });
        let hydraulics = Hydraulics::new(actuators);
        let feedback = Feedback::default();
        let controller = Controller::new(config.gains, &feedback);
        let mut rig = Rig {
            dt_s: config.dt_s(),
            config,
            hydraulics,
            controller,
            valve_delayed: [0.0; ACTUATOR_COUNT],
            external_force_n: [0.0; ACTUATOR_COUNT],
            feedback,
            rng,
            hydraulics_on: true,
            emergency_stop: false,
            snapshot: RigSnapshot::default(),
        };
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

    /// One control period.
    pub fn step(&mut self) {
        let outputs = *self.controller.update(&self.feedback, self.dt_s);
        let supply_on = self.hydraulics_on;
        let applied = if supply_on {
            self.valve_delayed
        } else {
            [0.0; ACTUATOR_COUNT]
        };
        self.hydraulics.step(
            self.dt_s,
            self.config.plant_substeps,
            &applied,
            supply_on,
            &self.external_force_n,
        );
        self.valve_delayed = outputs;
        self.snapshot.step += 1;
        self.read_sensors();
        self.publish();
    }

    /// Steps until the simulated time reaches `t_s` (bounded by the step count it implies).
    pub fn advance_to(&mut self, t_s: f64) {
        assert!(t_s.is_finite());
        let target_step = (t_s * self.config.control_hz).round().max(0.0) as u64;
        while self.snapshot.step < target_step {
            self.step();
        }
    }

    pub fn command(&mut self, command: RigCommand) -> Result<(), Refusal> {
        match command {
            RigCommand::SetSetpoint { channel, value } => {
                if !value.is_finite() {
                    return Err(Refusal::NotFinite { what: "set-point" });
                }
                self.check_active(channel)?;
                self.controller.set_setpoint(channel, value);
                Ok(())
            }
            RigCommand::SetActuatorMode { actuator, mode } => {
                let channel = Channel::Actuator(actuator);
                self.check_active(channel)?;
                self.controller
                    .set_actuator_mode(actuator, mode, &self.feedback);
                Ok(())
            }
            RigCommand::SetAxisControl { axis, control } => {
                self.controller
                    .set_axis_control(axis, control, &self.feedback);
                Ok(())
            }
            RigCommand::HydraulicsOn => {
                if self.emergency_stop {
                    return Err(Refusal::EmergencyStopLatched);
                }
                if !self.hydraulics_on {
                    // Restart holding the present state: no jump when pressure returns.
                    self.controller.hold_all(&self.feedback);
                    self.hydraulics_on = true;
                }
                Ok(())
            }
            RigCommand::HydraulicsOff => {
                self.hydraulics_on = false;
                Ok(())
            }
            RigCommand::EmergencyStop => {
                self.emergency_stop = true;
                self.hydraulics_on = false;
                Ok(())
            }
            RigCommand::ResetEmergencyStop => {
                self.emergency_stop = false;
                Ok(())
            }
        }
    }

    fn check_active(&self, channel: Channel) -> Result<ControlMode, Refusal> {
        self.controller
            .channel_mode(channel)
            .ok_or(Refusal::ChannelInactive { channel })
    }

    fn read_sensors(&mut self) {
        for (i, actuator) in self.hydraulics.actuators.iter().enumerate() {
            self.feedback.position_mm[i] = actuator.position_mm();
            let noise: f64 = StandardNormal.sample(&mut self.rng);
            self.feedback.force_kn[i] =
                self.external_force_n[i] * 1.0e-3 + noise * self.config.load_cell_noise_kn;
        }
    }

    fn publish(&mut self) {
        let s = &mut self.snapshot;
        s.t_s = s.step as f64 * self.dt_s;
        s.hydraulics_on = self.hydraulics_on;
        s.emergency_stop = self.emergency_stop;
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
                    a.command = self.controller.setpoint(Channel::Actuator(id));
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
