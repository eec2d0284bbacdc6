//! The digital controller: per-actuator PIDF loops in displacement or force, and the centroid
//! mode of each opposed pair (paper section 2, Fig. 2): the elongation (sum of the two
//! displacements, or the mean pair force) and the centre (half their difference) are controlled,
//! and the two loop outputs are mapped back to the actuators, u± = u_elongation ± u_centre.
//!
//! Positions are positive outward, so with p+ and p− the two displacements:
//! elongation = p+ + p−, centre = (p+ − p−) / 2. Both actuators have the same valve gain, so
//! the sum moves at twice, and the centre at once, the single-actuator speed per unit command.

use crate::hydraulics::ACTUATOR_COUNT;
use crate::ids::{ActuatorId, Axis, Channel};
use crate::pidf::{Pidf, PidfGains};
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ControlMode {
    /// Position in mm.
    Displacement,
    /// Load-cell force in kN.
    Force,
}

/// How an axis pair is driven.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum AxisControl {
    /// Each actuator in its own mode.
    Independent,
    /// Centroid mode; the elongation loop in the given quantity, the centre in displacement.
    Centroid(ControlMode),
}

/// Gains of every loop, by actuator size. Valve command per mm or per kN.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ControlGains {
    pub horizontal_displacement: PidfGains,
    pub vertical_displacement: PidfGains,
    pub horizontal_force: PidfGains,
    pub vertical_force: PidfGains,
}

impl ControlGains {
    /// Position loop tuned for a velocity constant of ≈60 rad/s (valve gain ≈590 mm/s per unit
    /// command), well below the 2 ζ_h ω_h ≈ 190 rad/s stability bound of the oil column; force
    /// loops tuned for the soft default rubber specimen (≈0.01 kN/mm).
    pub fn default_for_machine() -> ControlGains {
        let displacement = PidfGains {
            kp: 0.1,
            ki_per_s: 0.2,
            kd_s: 0.0,
            derivative_filter_hz: 200.0,
            feedforward_s: 1.0 / 590.0,
            output_min: -1.0,
            output_max: 1.0,
        };
        let force = PidfGains {
            kp: 2.0,
            ki_per_s: 20.0,
            kd_s: 0.0,
            derivative_filter_hz: 100.0,
            feedforward_s: 0.0,
            output_min: -1.0,
            output_max: 1.0,
        };
        ControlGains {
            horizontal_displacement: displacement,
            vertical_displacement: displacement,
            horizontal_force: force,
            vertical_force: force,
        }
    }

    fn for_actuator(&self, id: ActuatorId, mode: ControlMode) -> PidfGains {
        let vertical = id.axis() == Axis::Z;
        match (mode, vertical) {
            (ControlMode::Displacement, false) => self.horizontal_displacement,
            (ControlMode::Displacement, true) => self.vertical_displacement,
            (ControlMode::Force, false) => self.horizontal_force,
            (ControlMode::Force, true) => self.vertical_force,
        }
    }

    /// Elongation loop: the sum moves twice as fast per unit command, so half the gain
    /// (in displacement); the mean pair force moves at the single-actuator rate per unit.
    fn for_elongation(&self, axis: Axis, mode: ControlMode) -> PidfGains {
        let mut gains = self.for_actuator(axis.plus(), mode);
        if mode == ControlMode::Displacement {
            gains.kp *= 0.5;
            gains.ki_per_s *= 0.5;
            gains.kd_s *= 0.5;
            gains.feedforward_s *= 0.5;
        }
        gains
    }

    pub fn is_valid(&self) -> bool {
        self.horizontal_displacement.is_valid()
            && self.vertical_displacement.is_valid()
            && self.horizontal_force.is_valid()
            && self.vertical_force.is_valid()
    }
}

/// Feedback read by the controller on one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Feedback {
    pub position_mm: [f64; ACTUATOR_COUNT],
    pub force_kn: [f64; ACTUATOR_COUNT],
}

impl Feedback {
    pub fn elongation_mm(&self, axis: Axis) -> f64 {
        self.position_mm[axis.plus().index()] + self.position_mm[axis.minus().index()]
    }

    pub fn centre_mm(&self, axis: Axis) -> f64 {
        0.5 * (self.position_mm[axis.plus().index()] - self.position_mm[axis.minus().index()])
    }

    pub fn pair_force_kn(&self, axis: Axis) -> f64 {
        0.5 * (self.force_kn[axis.plus().index()] + self.force_kn[axis.minus().index()])
    }

    /// The measured value of a channel in the given mode.
    pub fn value(&self, channel: Channel, mode: ControlMode) -> f64 {
        match (channel, mode) {
            (Channel::Actuator(id), ControlMode::Displacement) => self.position_mm[id.index()],
            (Channel::Actuator(id), ControlMode::Force) => self.force_kn[id.index()],
            (Channel::Elongation(axis), ControlMode::Displacement) => self.elongation_mm(axis),
            (Channel::Elongation(axis), ControlMode::Force) => self.pair_force_kn(axis),
            (Channel::Centre(axis), _) => self.centre_mm(axis),
        }
    }
}

#[derive(Clone, Debug)]
pub struct Controller {
    gains: ControlGains,
    actuator_mode: [ControlMode; ACTUATOR_COUNT],
    axis_control: [AxisControl; 3],
    actuator_setpoint: [f64; ACTUATOR_COUNT],
    elongation_setpoint: [f64; 3],
    centre_setpoint_mm: [f64; 3],
    actuator_loop: [Pidf; ACTUATOR_COUNT],
    elongation_loop: [Pidf; 3],
    centre_loop: [Pidf; 3],
    output: [f64; ACTUATOR_COUNT],
}

impl Controller {
    /// All actuators in displacement control, holding `feedback`.
    pub fn new(gains: ControlGains, feedback: &Feedback) -> Controller {
        assert!(gains.is_valid(), "invalid control gains");
        let mode = ControlMode::Displacement;
        let actuator_loop = ActuatorId::ALL.map(|id| Pidf::new(gains.for_actuator(id, mode)));
        let elongation_loop = Axis::ALL.map(|axis| Pidf::new(gains.for_elongation(axis, mode)));
        let centre_loop = Axis::ALL.map(|axis| Pidf::new(gains.for_actuator(axis.plus(), mode)));
        let mut controller = Controller {
            gains,
            actuator_mode: [mode; ACTUATOR_COUNT],
            axis_control: [AxisControl::Independent; 3],
            actuator_setpoint: [0.0; ACTUATOR_COUNT],
            elongation_setpoint: [0.0; 3],
            centre_setpoint_mm: [0.0; 3],
            actuator_loop,
            elongation_loop,
            centre_loop,
            output: [0.0; ACTUATOR_COUNT],
        };
        for axis in Axis::ALL {
            controller.set_axis_control(axis, AxisControl::Independent, feedback);
        }
        controller
    }

    pub fn actuator_mode(&self, id: ActuatorId) -> ControlMode {
        self.actuator_mode[id.index()]
    }

    pub fn axis_control(&self, axis: Axis) -> AxisControl {
        self.axis_control[axis.index()]
    }

    pub fn output(&self) -> &[f64; ACTUATOR_COUNT] {
        &self.output
    }

    /// The mode in which a channel is driven now, or None when the channel is not active
    /// (an actuator of a centroid pair, or the elongation of an independent pair).
    pub fn channel_mode(&self, channel: Channel) -> Option<ControlMode> {
        match channel {
            Channel::Actuator(id) => match self.axis_control[id.axis().index()] {
                AxisControl::Independent => Some(self.actuator_mode[id.index()]),
                AxisControl::Centroid(_) => None,
            },
            Channel::Elongation(axis) => match self.axis_control[axis.index()] {
                AxisControl::Independent => None,
                AxisControl::Centroid(mode) => Some(mode),
            },
            Channel::Centre(axis) => match self.axis_control[axis.index()] {
                AxisControl::Independent => None,
                AxisControl::Centroid(_) => Some(ControlMode::Displacement),
            },
        }
    }

    pub fn setpoint(&self, channel: Channel) -> f64 {
        match channel {
            Channel::Actuator(id) => self.actuator_setpoint[id.index()],
            Channel::Elongation(axis) => self.elongation_setpoint[axis.index()],
            Channel::Centre(axis) => self.centre_setpoint_mm[axis.index()],
        }
    }

    /// Sets the set-point of an active channel. The caller has validated the value.
    pub fn set_setpoint(&mut self, channel: Channel, value: f64) {
        assert!(value.is_finite());
        assert!(
            self.channel_mode(channel).is_some(),
            "{channel:?} is not active"
        );
        match channel {
            Channel::Actuator(id) => self.actuator_setpoint[id.index()] = value,
            Channel::Elongation(axis) => self.elongation_setpoint[axis.index()] = value,
            Channel::Centre(axis) => self.centre_setpoint_mm[axis.index()] = value,
        }
    }

    /// Bumpless switch of one actuator's mode (its pair must be independent): the set-point
    /// becomes the feedback and the loop output is kept.
    pub fn set_actuator_mode(&mut self, id: ActuatorId, mode: ControlMode, feedback: &Feedback) {
        assert_eq!(
            self.axis_control[id.axis().index()],
            AxisControl::Independent
        );
        let i = id.index();
        self.actuator_mode[i] = mode;
        let measured = feedback.value(Channel::Actuator(id), mode);
        self.actuator_setpoint[i] = measured;
        self.actuator_loop[i].gains = self.gains.for_actuator(id, mode);
        self.actuator_loop[i].reset_bumpless(measured, self.output[i]);
    }

    /// Bumpless switch of an axis pair between independent and centroid control.
    pub fn set_axis_control(&mut self, axis: Axis, control: AxisControl, feedback: &Feedback) {
        let a = axis.index();
        let (plus, minus) = (axis.plus().index(), axis.minus().index());
        self.axis_control[a] = control;
        match control {
            AxisControl::Independent => {
                for id in [axis.plus(), axis.minus()] {
                    let mode = self.actuator_mode[id.index()];
                    self.set_actuator_mode(id, mode, feedback);
                }
            }
            AxisControl::Centroid(mode) => {
                let u_elongation = 0.5 * (self.output[plus] + self.output[minus]);
                let u_centre = 0.5 * (self.output[plus] - self.output[minus]);
                let elongation = feedback.value(Channel::Elongation(axis), mode);
                let centre = feedback.centre_mm(axis);
                self.elongation_setpoint[a] = elongation;
                self.centre_setpoint_mm[a] = centre;
                self.elongation_loop[a].gains = self.gains.for_elongation(axis, mode);
                self.elongation_loop[a].reset_bumpless(elongation, u_elongation);
                self.centre_loop[a].reset_bumpless(centre, u_centre);
            }
        }
    }

    /// Every active channel holds its present measured value (used on a specimen break and
    /// at a program stop "hold here").
    pub fn hold_all(&mut self, feedback: &Feedback) {
        for axis in Axis::ALL {
            let control = self.axis_control[axis.index()];
            self.set_axis_control(axis, control, feedback);
        }
    }

    /// Follow-up while the hydraulics are off: set-points track the feedback and the loop
    /// outputs restart from zero, so that pressure returns without a jump.
    pub fn track(&mut self, feedback: &Feedback) {
        self.output = [0.0; ACTUATOR_COUNT];
        self.hold_all(feedback);
    }

    /// Everything to displacement, independent, holding the present position (the action on
    /// a specimen break).
    pub fn displacement_hold(&mut self, feedback: &Feedback) {
        for axis in Axis::ALL {
            for id in [axis.plus(), axis.minus()] {
                self.actuator_mode[id.index()] = ControlMode::Displacement;
            }
            self.set_axis_control(axis, AxisControl::Independent, feedback);
        }
    }

    /// One control period: valve commands in [−1, 1] for the six actuators.
    pub fn update(&mut self, feedback: &Feedback, dt_s: f64) -> &[f64; ACTUATOR_COUNT] {
        for axis in Axis::ALL {
            let a = axis.index();
            let (plus, minus) = (axis.plus().index(), axis.minus().index());
            match self.axis_control[a] {
                AxisControl::Independent => {
                    for i in [plus, minus] {
                        let mode = self.actuator_mode[i];
                        let measured = feedback.value(Channel::Actuator(ActuatorId::ALL[i]), mode);
                        let sp = self.actuator_setpoint[i];
                        self.output[i] = self.actuator_loop[i].update(sp, measured, dt_s);
                    }
                }
                AxisControl::Centroid(mode) => {
                    let elongation = feedback.value(Channel::Elongation(axis), mode);
                    let u_e = self.elongation_loop[a].update(
                        self.elongation_setpoint[a],
                        elongation,
                        dt_s,
                    );
                    let centre = feedback.centre_mm(axis);
                    let u_c = self.centre_loop[a].update(self.centre_setpoint_mm[a], centre, dt_s);
                    self.output[plus] = (u_e + u_c).clamp(-1.0, 1.0);
                    self.output[minus] = (u_e - u_c).clamp(-1.0, 1.0);
                }
            }
        }
        &self.output
    }

    /// The position each actuator is asked to be at (mm), in displacement-type control;
    /// None for an actuator in force control (its command is a force).
    pub fn position_command_mm(&self, id: ActuatorId) -> Option<f64> {
        let axis = id.axis();
        let a = axis.index();
        match self.axis_control[a] {
            AxisControl::Independent => match self.actuator_mode[id.index()] {
                ControlMode::Displacement => Some(self.actuator_setpoint[id.index()]),
                ControlMode::Force => None,
            },
            AxisControl::Centroid(ControlMode::Displacement) => {
                let half = 0.5 * self.elongation_setpoint[a];
                let centre = self.centre_setpoint_mm[a];
                Some(if id == axis.plus() {
                    half + centre
                } else {
                    half - centre
                })
            }
            AxisControl::Centroid(ControlMode::Force) => None,
        }
    }
}
