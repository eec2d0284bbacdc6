//! The layouts' sizes and field offsets, checked when the crate is built: a layout change
//! fails to build here until these figures are updated, and the figures are kept per
//! [`LAYOUT_VERSION`] so that updating them means bumping it (with the `#[type_name]`
//! suffixes), which makes processes of different versions refuse to connect instead of
//! misreading each other.

use crate::field::{FieldHeader, FieldNode, GaugeStrain};
use crate::frame::{FrameHeader, GroundTruth};
use crate::identification::{IdentificationReport, RankedModel};
use crate::rig::{ActuatorState, RigCommand, RigReply, RigState};
use crate::specimen::SpecimenHeader;
use crate::LAYOUT_VERSION;
use std::mem::{offset_of, size_of};

/// The version the figures below describe.
const CHECKED_VERSION: u32 = 6;

const _: () = assert!(
    LAYOUT_VERSION == CHECKED_VERSION,
    "LAYOUT_VERSION changed: update the sizes and offsets below for the new layouts"
);

const _: () = {
    assert!(
        size_of::<GroundTruth>() == 104,
        "GroundTruth changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(GroundTruth, deformation_gradient) == 0,
        "GroundTruth::deformation_gradient moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(GroundTruth, translation_px) == 32,
        "GroundTruth::translation_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(GroundTruth, centre_px) == 48,
        "GroundTruth::centre_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(GroundTruth, specimen_solve_id) == 64,
        "GroundTruth::specimen_solve_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(GroundTruth, specimen_grip_mm) == 72,
        "GroundTruth::specimen_grip_mm moved: bump LAYOUT_VERSION"
    );
};
const _: () = {
    assert!(
        size_of::<FrameHeader>() == 176,
        "FrameHeader changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, layout_version) == 0,
        "FrameHeader::layout_version moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, bit_depth) == 4,
        "FrameHeader::bit_depth moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, frame_id) == 8,
        "FrameHeader::frame_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, t_capture_ns) == 16,
        "FrameHeader::t_capture_ns moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, width_px) == 24,
        "FrameHeader::width_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, height_px) == 28,
        "FrameHeader::height_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, rig_sample_id) == 32,
        "FrameHeader::rig_sample_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, scenario_id) == 40,
        "FrameHeader::scenario_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, has_truth) == 44,
        "FrameHeader::has_truth moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, truth) == 48,
        "FrameHeader::truth moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, pixel_checksum) == 152,
        "FrameHeader::pixel_checksum moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, sequence_id) == 160,
        "FrameHeader::sequence_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, reserved) == 164,
        "FrameHeader::reserved moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FrameHeader, t_camera_ns) == 168,
        "FrameHeader::t_camera_ns moved: bump LAYOUT_VERSION"
    );
};
const _: () = {
    assert!(
        size_of::<FieldNode>() == 56,
        "FieldNode changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, x_px) == 0,
        "FieldNode::x_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, y_px) == 4,
        "FieldNode::y_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, u_px) == 8,
        "FieldNode::u_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, v_px) == 12,
        "FieldNode::v_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, exx) == 16,
        "FieldNode::exx moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, eyy) == 20,
        "FieldNode::eyy moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, exy) == 24,
        "FieldNode::exy moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, score) == 28,
        "FieldNode::score moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, iterations) == 32,
        "FieldNode::iterations moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, status) == 36,
        "FieldNode::status moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, du_dx) == 40,
        "FieldNode::du_dx moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, du_dy) == 44,
        "FieldNode::du_dy moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, dv_dx) == 48,
        "FieldNode::dv_dx moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldNode, dv_dy) == 52,
        "FieldNode::dv_dy moved: bump LAYOUT_VERSION"
    );
};
const _: () = {
    assert!(
        size_of::<GaugeStrain>() == 24,
        "GaugeStrain changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(GaugeStrain, exx) == 0,
        "GaugeStrain::exx moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(GaugeStrain, eyy) == 8,
        "GaugeStrain::eyy moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(GaugeStrain, exy) == 16,
        "GaugeStrain::exy moved: bump LAYOUT_VERSION"
    );
};
const _: () = {
    assert!(
        size_of::<FieldHeader>() == 328,
        "FieldHeader changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, layout_version) == 0,
        "FieldHeader::layout_version moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, strain_measure) == 4,
        "FieldHeader::strain_measure moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, frame_id) == 8,
        "FieldHeader::frame_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, reference_frame_id) == 16,
        "FieldHeader::reference_frame_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, origin_frame_id) == 24,
        "FieldHeader::origin_frame_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, t_capture_ns) == 32,
        "FieldHeader::t_capture_ns moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, rig_sample_id) == 40,
        "FieldHeader::rig_sample_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, t_received_ns) == 48,
        "FieldHeader::t_received_ns moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, t_published_ns) == 56,
        "FieldHeader::t_published_ns moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, correlate_ns) == 64,
        "FieldHeader::correlate_ns moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, frames_dropped) == 72,
        "FieldHeader::frames_dropped moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, mesh_cols) == 80,
        "FieldHeader::mesh_cols moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, mesh_rows) == 84,
        "FieldHeader::mesh_rows moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, zoi_px) == 88,
        "FieldHeader::zoi_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, step_px) == 92,
        "FieldHeader::step_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, valid_nodes) == 96,
        "FieldHeader::valid_nodes moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, has_truth) == 100,
        "FieldHeader::has_truth moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, truth) == 104,
        "FieldHeader::truth moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, u_mean_px) == 208,
        "FieldHeader::u_mean_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, v_mean_px) == 216,
        "FieldHeader::v_mean_px moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, gauge) == 224,
        "FieldHeader::gauge moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, sequence_id) == 320,
        "FieldHeader::sequence_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(FieldHeader, gradient_source) == 324,
        "FieldHeader::gradient_source moved: bump LAYOUT_VERSION"
    );
};
const _: () = {
    assert!(
        size_of::<ActuatorState>() == 40,
        "ActuatorState changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(ActuatorState, position_mm) == 0,
        "ActuatorState::position_mm moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(ActuatorState, command_mm) == 8,
        "ActuatorState::command_mm moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(ActuatorState, following_error_mm) == 16,
        "ActuatorState::following_error_mm moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(ActuatorState, force_kn) == 24,
        "ActuatorState::force_kn moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(ActuatorState, mode) == 32,
        "ActuatorState::mode moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(ActuatorState, limit_flags) == 36,
        "ActuatorState::limit_flags moved: bump LAYOUT_VERSION"
    );
};
const _: () = {
    assert!(
        size_of::<RigState>() == 448,
        "RigState changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, layout_version) == 0,
        "RigState::layout_version moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, program_state) == 4,
        "RigState::program_state moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, sample_id) == 8,
        "RigState::sample_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, t_sim_s) == 16,
        "RigState::t_sim_s moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, t_published_ns) == 24,
        "RigState::t_published_ns moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, actuators) == 32,
        "RigState::actuators moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, axis_centre_mm) == 272,
        "RigState::axis_centre_mm moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, axis_elongation_mm) == 296,
        "RigState::axis_elongation_mm moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, specimen_stretch_x) == 320,
        "RigState::specimen_stretch_x moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, specimen_stretch_y) == 328,
        "RigState::specimen_stretch_y moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, specimen_rotation_rad) == 336,
        "RigState::specimen_rotation_rad moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, specimen_centre_offset_mm) == 344,
        "RigState::specimen_centre_offset_mm moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, specimen_section_x_mm2) == 360,
        "RigState::specimen_section_x_mm2 moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, specimen_section_y_mm2) == 368,
        "RigState::specimen_section_y_mm2 moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, load_case) == 376,
        "RigState::load_case moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, hydraulics_on) == 380,
        "RigState::hydraulics_on moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, test_index) == 384,
        "RigState::test_index moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, control_mode) == 388,
        "RigState::control_mode moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, target_log_exx) == 392,
        "RigState::target_log_exx moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, target_log_eyy) == 400,
        "RigState::target_log_eyy moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, specimen_solve_id) == 408,
        "RigState::specimen_solve_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigState, specimen_grip_mm) == 416,
        "RigState::specimen_grip_mm moved: bump LAYOUT_VERSION"
    );
};
const _: () = {
    assert!(
        size_of::<RigCommand>() == 264,
        "RigCommand changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigCommand, layout_version) == 0,
        "RigCommand::layout_version moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigCommand, kind) == 4,
        "RigCommand::kind moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigCommand, channel) == 8,
        "RigCommand::channel moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigCommand, limit) == 12,
        "RigCommand::limit moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigCommand, value) == 16,
        "RigCommand::value moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigCommand, text) == 24,
        "RigCommand::text moved: bump LAYOUT_VERSION"
    );
};
const _: () = {
    assert!(
        size_of::<RigReply>() == 256,
        "RigReply changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigReply, layout_version) == 0,
        "RigReply::layout_version moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigReply, accepted) == 4,
        "RigReply::accepted moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RigReply, reason) == 8,
        "RigReply::reason moved: bump LAYOUT_VERSION"
    );
};
const _: () = {
    assert!(
        size_of::<RankedModel>() == 40,
        "RankedModel changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RankedModel, name) == 0,
        "RankedModel::name moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RankedModel, aic) == 24,
        "RankedModel::aic moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(RankedModel, rms_mpa) == 32,
        "RankedModel::rms_mpa moved: bump LAYOUT_VERSION"
    );
};
const _: () = {
    assert!(
        size_of::<IdentificationReport>() == 640,
        "IdentificationReport changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, layout_version) == 0,
        "IdentificationReport::layout_version moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, points) == 4,
        "IdentificationReport::points moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, frame_id) == 16,
        "IdentificationReport::frame_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, t_capture_ns) == 24,
        "IdentificationReport::t_capture_ns moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, t_published_ns) == 32,
        "IdentificationReport::t_published_ns moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, a) == 40,
        "IdentificationReport::a moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, a_stderr) == 104,
        "IdentificationReport::a_stderr moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, b) == 168,
        "IdentificationReport::b moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, b_stderr) == 232,
        "IdentificationReport::b_stderr moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, a_count) == 296,
        "IdentificationReport::a_count moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, b_count) == 300,
        "IdentificationReport::b_count moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, rms_mpa) == 304,
        "IdentificationReport::rms_mpa moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, ranked_count) == 312,
        "IdentificationReport::ranked_count moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, route) == 316,
        "IdentificationReport::route moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(IdentificationReport, ranking) == 320,
        "IdentificationReport::ranking moved: bump LAYOUT_VERSION"
    );
};

const _: () = {
    assert!(
        size_of::<SpecimenHeader>() == 104,
        "SpecimenHeader changed size: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(SpecimenHeader, layout_version) == 0,
        "SpecimenHeader::layout_version moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(SpecimenHeader, grips) == 4,
        "SpecimenHeader::grips moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(SpecimenHeader, solve_id) == 8,
        "SpecimenHeader::solve_id moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(SpecimenHeader, t_sim_s) == 16,
        "SpecimenHeader::t_sim_s moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(SpecimenHeader, node_count) == 24,
        "SpecimenHeader::node_count moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(SpecimenHeader, element_count) == 28,
        "SpecimenHeader::element_count moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(SpecimenHeader, mesh_fingerprint) == 32,
        "SpecimenHeader::mesh_fingerprint moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(SpecimenHeader, grip_mm) == 40,
        "SpecimenHeader::grip_mm moved: bump LAYOUT_VERSION"
    );
    assert!(
        offset_of!(SpecimenHeader, grip_force_n) == 72,
        "SpecimenHeader::grip_force_n moved: bump LAYOUT_VERSION"
    );
};
