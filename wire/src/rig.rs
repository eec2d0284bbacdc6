//! `rig/state` (a fixed [`RigState`] sample, decimated from the rig's control rate) and
//! `rig/command` (request [`RigCommand`], response [`RigReply`]).

#[cfg(feature = "ipc")]
use iceoryx2::prelude::ZeroCopySend;

/// [`RigState::load_case`] codes.
pub const LOAD_CASE_NONE: u32 = 0;
pub const LOAD_CASE_UNIAXIAL: u32 = 1;
pub const LOAD_CASE_EQUIBIAXIAL: u32 = 2;

/// Actuators in this order everywhere: X+, X−, Y+, Y−, Z+, Z−.
pub const ACTUATOR_NAMES: [&str; 6] = ["X+", "X-", "Y+", "Y-", "Z+", "Z-"];
/// Axes in this order everywhere: X, Y, Z.
pub const AXIS_NAMES: [&str; 3] = ["X", "Y", "Z"];

/// An actuator is "loaded" when its |force| ever exceeded this fraction of the largest
/// actuator's peak |force|; below, it only shows its load cell's noise (the y pair of a uniaxial
/// test, the Z pair of a planar one). One rule for the run's figures and the dashboard.
pub const LOADED_FORCE_FRACTION: f64 = 0.1;

/// Which of the actuators whose peak |force| is `peaks_abs` (any unit) carried a load
/// ([`LOADED_FORCE_FRACTION`] of the largest peak); none before any force.
pub fn loaded_actuators(peaks_abs: &[f64]) -> Vec<bool> {
    let largest = peaks_abs.iter().copied().fold(0.0, f64::max);
    peaks_abs
        .iter()
        .map(|p| largest > 0.0 && *p >= LOADED_FORCE_FRACTION * largest)
        .collect()
}

/// One servo-hydraulic actuator at one instant.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.ActuatorState.v6")
)]
pub struct ActuatorState {
    pub position_mm: f64,
    pub command_mm: f64,
    pub following_error_mm: f64,
    pub force_kn: f64,
    /// Control mode code of this channel (rig crate: displacement, force, centroid).
    pub mode: u32,
    /// Bit set of tripped limits of this channel (rig crate defines the bits).
    pub limit_flags: u32,
}

/// One decimated sample of the rig.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.RigState.v6")
)]
pub struct RigState {
    pub layout_version: u32,
    /// Program state code (rig crate: idle, running, holding, stopped, tripped).
    pub program_state: u32,
    /// Consecutive from 0; frames name the sample they were taken at.
    pub sample_id: u64,
    /// Simulated time since the rig started (s), and when this sample was published (monotonic ns).
    /// A followed machine log (`rig --follow-csv`) puts there the row's machine time plus the
    /// configured offset, and the row's instant on the monotonic clock: what a field whose
    /// frame names no rig sample is paired to by time.
    pub t_sim_s: f64,
    pub t_published_ns: u64,
    pub actuators: [ActuatorState; 6],
    /// Per axis X, Y, Z: centre position ((p+ − p−)/2) and elongation (p+ + p−), mm.
    pub axis_centre_mm: [f64; 3],
    pub axis_elongation_mm: [f64; 3],
    /// Specimen kinematics for the camera: in-plane stretches, rotation, centre offset.
    pub specimen_stretch_x: f64,
    pub specimen_stretch_y: f64,
    pub specimen_rotation_rad: f64,
    pub specimen_centre_offset_mm: [f64; 2],
    /// Current specimen cross-sections normal to X and Y (mm²), for Cauchy stress = force / area.
    pub specimen_section_x_mm2: f64,
    pub specimen_section_y_mm2: f64,
    /// Load case code of the running test: [`LOAD_CASE_NONE`], [`LOAD_CASE_UNIAXIAL`] (on a
    /// structure: the uniaxial strip is mounted) or [`LOAD_CASE_EQUIBIAXIAL`] (the cruciform).
    pub load_case: u32,
    /// 1 when the hydraulics are on.
    pub hydraulics_on: u32,
    /// Which test of the running campaign (from 0; 0 without a campaign): a camera starts a
    /// new frame sequence when it changes.
    pub test_index: u32,
    /// A [`RigControl`] code: what closes the loop of the running test (displacement, the
    /// correlator's strain, or a strain test held by an interlock).
    pub control_mode: u32,
    /// The log strains (ln λx, ln λy) a strain-controlled test aims at this instant (also while
    /// held: the frozen target). NaN when there is none (displacement control): read them
    /// through [`RigState::strain_target`].
    pub target_log_exx: f64,
    pub target_log_eyy: f64,
    /// The specimen's last solved state (`specimen` service) when the specimen is a
    /// finite-element structure, else [`crate::NO_SPECIMEN_SOLVE`]; and the grips' axial
    /// displacements at this sample (mm, the solve's grip order), to which the solve's field is
    /// followed through its grip modes (`SpecimenHeader`).
    pub specimen_solve_id: u64,
    pub specimen_grip_mm: [f64; 4],
}

impl Default for RigState {
    /// Zeros, but no specimen solve ([`crate::NO_SPECIMEN_SOLVE`]): a zero id would name one.
    fn default() -> Self {
        RigState {
            layout_version: 0,
            program_state: 0,
            sample_id: 0,
            t_sim_s: 0.0,
            t_published_ns: 0,
            actuators: [ActuatorState::default(); 6],
            axis_centre_mm: [0.0; 3],
            axis_elongation_mm: [0.0; 3],
            specimen_stretch_x: 0.0,
            specimen_stretch_y: 0.0,
            specimen_rotation_rad: 0.0,
            specimen_centre_offset_mm: [0.0; 2],
            specimen_section_x_mm2: 0.0,
            specimen_section_y_mm2: 0.0,
            load_case: 0,
            hydraulics_on: 0,
            test_index: 0,
            control_mode: 0,
            target_log_exx: 0.0,
            target_log_eyy: 0.0,
            specimen_solve_id: crate::NO_SPECIMEN_SOLVE,
            specimen_grip_mm: [0.0; 4],
        }
    }
}

impl RigState {
    /// The specimen's solve and the grips' displacements, when the specimen is a structure.
    pub fn specimen_solve(&self) -> Option<(u64, [f64; 4])> {
        (self.specimen_solve_id != crate::NO_SPECIMEN_SOLVE)
            .then_some((self.specimen_solve_id, self.specimen_grip_mm))
    }

    /// The strain target (ln λx, ln λy), when a strain-controlled test sets one (its control
    /// mode is strain or held, and both targets are finite).
    pub fn strain_target(&self) -> Option<[f64; 2]> {
        let mode = RigControl::from_code(self.control_mode)?;
        let target = [self.target_log_exx, self.target_log_eyy];
        (mode != RigControl::Displacement && target.iter().all(|t| t.is_finite())).then_some(target)
    }

    /// The control mode, [`RigControl::Displacement`] for an unknown code.
    pub fn control(&self) -> RigControl {
        RigControl::from_code(self.control_mode).unwrap_or(RigControl::Displacement)
    }
}

/// What closes the loop of the rig's running test ([`RigState::control_mode`]).
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RigControl {
    /// The grips follow a displacement program (or nothing runs): no strain target.
    #[default]
    Displacement = 0,
    /// The correlator's gauge log strains close the loop on the target.
    Strain = 1,
    /// A strain-controlled test held in displacement by an interlock (stale fields, too few
    /// valid nodes, a strain jump or NaN), or waiting for its first usable field.
    Held = 2,
}

impl RigControl {
    pub const ALL: [RigControl; 3] = [
        RigControl::Displacement,
        RigControl::Strain,
        RigControl::Held,
    ];

    pub fn from_code(code: u32) -> Option<RigControl> {
        RigControl::ALL.into_iter().find(|c| *c as u32 == code)
    }

    /// As in `rig.csv`'s `control` column: `displacement`, `strain`, `held`.
    pub fn name(self) -> &'static str {
        match self {
            RigControl::Displacement => "displacement",
            RigControl::Strain => "strain",
            RigControl::Held => "held",
        }
    }

    pub fn parse(name: &str) -> Option<RigControl> {
        RigControl::ALL.into_iter().find(|c| c.name() == name)
    }
}

/// What a [`RigCommand`] asks for.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RigCommandKind {
    /// Start the program file named in `text`, or the built-in test `value` names (rig crate).
    StartProgram = 0,
    Hold = 1,
    Resume = 2,
    /// Stop the program; `value` 0 stays at level, 1 ramps to zero.
    Stop = 3,
    /// Switch `channel` to mode `value` (rig crate codes), bumplessly.
    SetMode = 4,
    /// Set limit `limit` of `channel` to `value` (units of that limit).
    SetLimit = 5,
    EmergencyStop = 6,
    /// Set the command of `channel` directly (mm or kN by its mode).
    SetPoint = 7,
}

impl RigCommandKind {
    pub fn from_code(code: u32) -> Option<RigCommandKind> {
        use RigCommandKind::*;
        [
            StartProgram,
            Hold,
            Resume,
            Stop,
            SetMode,
            SetLimit,
            EmergencyStop,
            SetPoint,
        ]
        .into_iter()
        .find(|k| *k as u32 == code)
    }
}

/// A request on `rig/command`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.RigCommand.v6")
)]
pub struct RigCommand {
    pub layout_version: u32,
    /// A [`RigCommandKind`] code.
    pub kind: u32,
    /// Actuator index (see [`ACTUATOR_NAMES`]) or axis index, as the kind says.
    pub channel: u32,
    /// Limit code for `SetLimit` (rig crate).
    pub limit: u32,
    pub value: f64,
    /// NUL-padded UTF-8 (a program path), see [`crate::text`].
    pub text: [u8; 240],
}

impl RigCommand {
    pub fn new(kind: RigCommandKind) -> RigCommand {
        RigCommand {
            layout_version: crate::LAYOUT_VERSION,
            kind: kind as u32,
            channel: 0,
            limit: 0,
            value: 0.0,
            text: [0; 240],
        }
    }
}

/// The answer to a [`RigCommand`]: accepted, or refused with the reason.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.RigReply.v6")
)]
pub struct RigReply {
    pub layout_version: u32,
    pub accepted: u32,
    /// NUL-padded UTF-8 reason when refused, see [`crate::text`].
    pub reason: [u8; 248],
}

impl RigReply {
    pub fn accepted() -> RigReply {
        RigReply {
            layout_version: crate::LAYOUT_VERSION,
            accepted: 1,
            reason: [0; 248],
        }
    }

    pub fn refused(reason: &str) -> RigReply {
        let mut reply = RigReply {
            layout_version: crate::LAYOUT_VERSION,
            accepted: 0,
            reason: [0; 248],
        };
        crate::text::write_fixed(&mut reply.reason, reason);
        reply
    }

    pub fn reason(&self) -> String {
        crate::text::read_fixed(&self.reason)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refusal_carries_its_reason() {
        let reply = RigReply::refused("stroke 300 mm beyond the 250 mm limit of X+");
        assert_eq!(reply.accepted, 0);
        assert_eq!(
            reply.reason(),
            "stroke 300 mm beyond the 250 mm limit of X+"
        );
        assert_eq!(RigReply::accepted().accepted, 1);
        assert_eq!(
            RigCommandKind::from_code(6),
            Some(RigCommandKind::EmergencyStop)
        );
        assert_eq!(RigCommandKind::from_code(99), None);
    }

    #[test]
    fn control_mode_codes_and_targets_round_trip() {
        for mode in RigControl::ALL {
            assert_eq!(RigControl::from_code(mode as u32), Some(mode));
            assert_eq!(RigControl::parse(mode.name()), Some(mode));
        }
        assert_eq!(RigControl::from_code(3), None);
        let mut state = RigState {
            control_mode: RigControl::Strain as u32,
            target_log_exx: 0.25,
            target_log_eyy: -0.125,
            ..RigState::default()
        };
        assert_eq!(state.strain_target(), Some([0.25, -0.125]));
        state.control_mode = RigControl::Held as u32;
        assert_eq!(state.control(), RigControl::Held);
        assert_eq!(state.strain_target(), Some([0.25, -0.125]));
        state.control_mode = RigControl::Displacement as u32;
        assert_eq!(state.strain_target(), None);
        state.control_mode = RigControl::Strain as u32;
        state.target_log_eyy = f64::NAN;
        assert_eq!(state.strain_target(), None);
        state.control_mode = 77;
        assert_eq!(state.control(), RigControl::Displacement);
        assert_eq!(state.strain_target(), None);
    }
}

#[cfg(test)]
mod loaded_tests {
    use super::*;

    #[test]
    fn an_actuator_is_loaded_above_a_tenth_of_the_largest_peak() {
        assert_eq!(
            loaded_actuators(&[2.0, 1.9, 0.21, 0.19, 0.0, 0.0]),
            [true, true, true, false, false, false]
        );
        assert!(loaded_actuators(&[0.0; 6]).iter().all(|l| !l));
    }
}
