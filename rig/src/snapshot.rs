//! What the rig shows at the end of a step: the one read-only view of its state.

use crate::control::{AxisControl, ControlMode};
use crate::hydraulics::ACTUATOR_COUNT;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ActuatorSnapshot {
    pub position_mm: f64,
    pub velocity_mm_s: f64,
    /// Position command (mm) in displacement-type control, force command (kN) in force control.
    pub command: f64,
    /// Command minus feedback, in the unit of `command`.
    pub error: f64,
    /// Load-cell reading (kN, tension positive), with noise.
    pub force_kn: f64,
    /// Servo-valve command in [−1, 1].
    pub valve: f64,
    pub mode: Option<ControlMode>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisSnapshot {
    pub control: AxisControl,
    /// Half the difference of the pair's displacements (mm).
    pub centre_mm: f64,
    /// Sum of the pair's displacements (mm).
    pub elongation_mm: f64,
    /// Mean load-cell force of the pair (kN).
    pub force_kn: f64,
}

impl Default for AxisSnapshot {
    fn default() -> Self {
        AxisSnapshot {
            control: AxisControl::Independent,
            centre_mm: 0.0,
            elongation_mm: 0.0,
            force_kn: 0.0,
        }
    }
}

/// Specimen kinematics for the camera: in-plane stretches, rotation and centre offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecimenKinematics {
    pub stretch_x: f64,
    pub stretch_y: f64,
    pub rotation_deg: f64,
    pub centre_x_mm: f64,
    pub centre_y_mm: f64,
    pub broken: bool,
}

impl Default for SpecimenKinematics {
    fn default() -> Self {
        SpecimenKinematics {
            stretch_x: 1.0,
            stretch_y: 1.0,
            rotation_deg: 0.0,
            centre_x_mm: 0.0,
            centre_y_mm: 0.0,
            broken: false,
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProgramStatus {
    #[default]
    Idle,
    Running,
    Held,
    /// Stopped by a command or a limit, transition finished or under way.
    Stopped,
    Finished,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RigSnapshot {
    pub step: u64,
    pub t_s: f64,
    pub hydraulics_on: bool,
    pub emergency_stop: bool,
    pub program: ProgramStatus,
    /// Program time (s) of the running or held program.
    pub program_t_s: f64,
    pub actuators: [ActuatorSnapshot; ACTUATOR_COUNT],
    pub axes: [AxisSnapshot; 3],
    /// Bit set of tripped limits, see `limits::LimitKind::bit`.
    pub limits_tripped: u32,
    pub specimen: SpecimenKinematics,
    /// Fraction of the valves' demand the power station delivered on the last step.
    pub supply_flow_scale: f64,
}
