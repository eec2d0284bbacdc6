/* dicstream_wire.h: the shared-memory layouts of dicstream's services, layout version 6.
 * Generated from the Rust definitions (wire::layouts::c_header): do not edit. Regenerate with
 *   cargo run --release -p wire --example wire_header > wire/include/dicstream_wire.h
 * Services (iceoryx2 publish-subscribe, with an event service of the same name) live under
 * the instance's prefix "<instance>_" (wire::instance). frames: a uint16_t slice (row-major
 * pixels) behind a DicstreamFrameHeader; fields: a DicstreamFieldNode slice (row-major mesh)
 * behind a DicstreamFieldHeader; rig/state: a DicstreamRigState; identification: a
 * DicstreamIdentificationReport. Every reader checks layout_version first. */
#ifndef DICSTREAM_WIRE_H
#define DICSTREAM_WIRE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
#define DICSTREAM_STATIC_ASSERT static_assert
#else
#define DICSTREAM_STATIC_ASSERT _Static_assert
#endif

#define DICSTREAM_LAYOUT_VERSION 6u
#define DICSTREAM_SERVICE_FRAMES "frames"
#define DICSTREAM_SERVICE_FIELDS "fields"
#define DICSTREAM_SERVICE_RIG_STATE "rig/state"
#define DICSTREAM_SERVICE_IDENTIFICATION "identification"

typedef struct DicstreamGroundTruth {
    double deformation_gradient[4];
    double translation_px[2];
    double centre_px[2];
    uint64_t specimen_solve_id;
    double specimen_grip_mm[4];
#ifdef __cplusplus
    static constexpr const char* IOX2_TYPE_NAME = "dicstream.GroundTruth.v6";
#endif
} DicstreamGroundTruth;
DICSTREAM_STATIC_ASSERT(sizeof(DicstreamGroundTruth) == 104, "DicstreamGroundTruth size");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamGroundTruth, deformation_gradient) == 0, "DicstreamGroundTruth.deformation_gradient offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamGroundTruth, translation_px) == 32, "DicstreamGroundTruth.translation_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamGroundTruth, centre_px) == 48, "DicstreamGroundTruth.centre_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamGroundTruth, specimen_solve_id) == 64, "DicstreamGroundTruth.specimen_solve_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamGroundTruth, specimen_grip_mm) == 72, "DicstreamGroundTruth.specimen_grip_mm offset");

typedef struct DicstreamFrameHeader {
    uint32_t layout_version;
    uint32_t bit_depth;
    uint64_t frame_id;
    uint64_t t_capture_ns;
    uint32_t width_px;
    uint32_t height_px;
    uint64_t rig_sample_id;
    uint32_t scenario_id;
    uint32_t has_truth;
    DicstreamGroundTruth truth;
    uint64_t pixel_checksum;
    uint32_t sequence_id;
    uint32_t reserved;
    uint64_t t_camera_ns;
#ifdef __cplusplus
    static constexpr const char* IOX2_TYPE_NAME = "dicstream.FrameHeader.v6";
#endif
} DicstreamFrameHeader;
DICSTREAM_STATIC_ASSERT(sizeof(DicstreamFrameHeader) == 176, "DicstreamFrameHeader size");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, layout_version) == 0, "DicstreamFrameHeader.layout_version offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, bit_depth) == 4, "DicstreamFrameHeader.bit_depth offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, frame_id) == 8, "DicstreamFrameHeader.frame_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, t_capture_ns) == 16, "DicstreamFrameHeader.t_capture_ns offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, width_px) == 24, "DicstreamFrameHeader.width_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, height_px) == 28, "DicstreamFrameHeader.height_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, rig_sample_id) == 32, "DicstreamFrameHeader.rig_sample_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, scenario_id) == 40, "DicstreamFrameHeader.scenario_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, has_truth) == 44, "DicstreamFrameHeader.has_truth offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, truth) == 48, "DicstreamFrameHeader.truth offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, pixel_checksum) == 152, "DicstreamFrameHeader.pixel_checksum offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, sequence_id) == 160, "DicstreamFrameHeader.sequence_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, reserved) == 164, "DicstreamFrameHeader.reserved offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFrameHeader, t_camera_ns) == 168, "DicstreamFrameHeader.t_camera_ns offset");

typedef struct DicstreamFieldNode {
    float x_px;
    float y_px;
    float u_px;
    float v_px;
    float exx;
    float eyy;
    float exy;
    float score;
    uint32_t iterations;
    uint32_t status;
    float du_dx;
    float du_dy;
    float dv_dx;
    float dv_dy;
#ifdef __cplusplus
    static constexpr const char* IOX2_TYPE_NAME = "dicstream.FieldNode.v6";
#endif
} DicstreamFieldNode;
DICSTREAM_STATIC_ASSERT(sizeof(DicstreamFieldNode) == 56, "DicstreamFieldNode size");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, x_px) == 0, "DicstreamFieldNode.x_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, y_px) == 4, "DicstreamFieldNode.y_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, u_px) == 8, "DicstreamFieldNode.u_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, v_px) == 12, "DicstreamFieldNode.v_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, exx) == 16, "DicstreamFieldNode.exx offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, eyy) == 20, "DicstreamFieldNode.eyy offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, exy) == 24, "DicstreamFieldNode.exy offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, score) == 28, "DicstreamFieldNode.score offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, iterations) == 32, "DicstreamFieldNode.iterations offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, status) == 36, "DicstreamFieldNode.status offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, du_dx) == 40, "DicstreamFieldNode.du_dx offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, du_dy) == 44, "DicstreamFieldNode.du_dy offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, dv_dx) == 48, "DicstreamFieldNode.dv_dx offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldNode, dv_dy) == 52, "DicstreamFieldNode.dv_dy offset");

typedef struct DicstreamGaugeStrain {
    double exx;
    double eyy;
    double exy;
#ifdef __cplusplus
    static constexpr const char* IOX2_TYPE_NAME = "dicstream.GaugeStrain.v6";
#endif
} DicstreamGaugeStrain;
DICSTREAM_STATIC_ASSERT(sizeof(DicstreamGaugeStrain) == 24, "DicstreamGaugeStrain size");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamGaugeStrain, exx) == 0, "DicstreamGaugeStrain.exx offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamGaugeStrain, eyy) == 8, "DicstreamGaugeStrain.eyy offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamGaugeStrain, exy) == 16, "DicstreamGaugeStrain.exy offset");

typedef struct DicstreamFieldHeader {
    uint32_t layout_version;
    uint32_t strain_measure;
    uint64_t frame_id;
    uint64_t reference_frame_id;
    uint64_t origin_frame_id;
    uint64_t t_capture_ns;
    uint64_t rig_sample_id;
    uint64_t t_received_ns;
    uint64_t t_published_ns;
    uint64_t correlate_ns;
    uint64_t frames_dropped;
    uint32_t mesh_cols;
    uint32_t mesh_rows;
    uint32_t zoi_px;
    uint32_t step_px;
    uint32_t valid_nodes;
    uint32_t has_truth;
    DicstreamGroundTruth truth;
    double u_mean_px;
    double v_mean_px;
    DicstreamGaugeStrain gauge[4];
    uint32_t sequence_id;
    uint32_t gradient_source;
#ifdef __cplusplus
    static constexpr const char* IOX2_TYPE_NAME = "dicstream.FieldHeader.v6";
#endif
} DicstreamFieldHeader;
DICSTREAM_STATIC_ASSERT(sizeof(DicstreamFieldHeader) == 328, "DicstreamFieldHeader size");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, layout_version) == 0, "DicstreamFieldHeader.layout_version offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, strain_measure) == 4, "DicstreamFieldHeader.strain_measure offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, frame_id) == 8, "DicstreamFieldHeader.frame_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, reference_frame_id) == 16, "DicstreamFieldHeader.reference_frame_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, origin_frame_id) == 24, "DicstreamFieldHeader.origin_frame_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, t_capture_ns) == 32, "DicstreamFieldHeader.t_capture_ns offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, rig_sample_id) == 40, "DicstreamFieldHeader.rig_sample_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, t_received_ns) == 48, "DicstreamFieldHeader.t_received_ns offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, t_published_ns) == 56, "DicstreamFieldHeader.t_published_ns offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, correlate_ns) == 64, "DicstreamFieldHeader.correlate_ns offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, frames_dropped) == 72, "DicstreamFieldHeader.frames_dropped offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, mesh_cols) == 80, "DicstreamFieldHeader.mesh_cols offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, mesh_rows) == 84, "DicstreamFieldHeader.mesh_rows offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, zoi_px) == 88, "DicstreamFieldHeader.zoi_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, step_px) == 92, "DicstreamFieldHeader.step_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, valid_nodes) == 96, "DicstreamFieldHeader.valid_nodes offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, has_truth) == 100, "DicstreamFieldHeader.has_truth offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, truth) == 104, "DicstreamFieldHeader.truth offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, u_mean_px) == 208, "DicstreamFieldHeader.u_mean_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, v_mean_px) == 216, "DicstreamFieldHeader.v_mean_px offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, gauge) == 224, "DicstreamFieldHeader.gauge offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, sequence_id) == 320, "DicstreamFieldHeader.sequence_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamFieldHeader, gradient_source) == 324, "DicstreamFieldHeader.gradient_source offset");

typedef struct DicstreamActuatorState {
    double position_mm;
    double command_mm;
    double following_error_mm;
    double force_kn;
    uint32_t mode;
    uint32_t limit_flags;
#ifdef __cplusplus
    static constexpr const char* IOX2_TYPE_NAME = "dicstream.ActuatorState.v6";
#endif
} DicstreamActuatorState;
DICSTREAM_STATIC_ASSERT(sizeof(DicstreamActuatorState) == 40, "DicstreamActuatorState size");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamActuatorState, position_mm) == 0, "DicstreamActuatorState.position_mm offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamActuatorState, command_mm) == 8, "DicstreamActuatorState.command_mm offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamActuatorState, following_error_mm) == 16, "DicstreamActuatorState.following_error_mm offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamActuatorState, force_kn) == 24, "DicstreamActuatorState.force_kn offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamActuatorState, mode) == 32, "DicstreamActuatorState.mode offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamActuatorState, limit_flags) == 36, "DicstreamActuatorState.limit_flags offset");

typedef struct DicstreamRigState {
    uint32_t layout_version;
    uint32_t program_state;
    uint64_t sample_id;
    double t_sim_s;
    uint64_t t_published_ns;
    DicstreamActuatorState actuators[6];
    double axis_centre_mm[3];
    double axis_elongation_mm[3];
    double specimen_stretch_x;
    double specimen_stretch_y;
    double specimen_rotation_rad;
    double specimen_centre_offset_mm[2];
    double specimen_section_x_mm2;
    double specimen_section_y_mm2;
    uint32_t load_case;
    uint32_t hydraulics_on;
    uint32_t test_index;
    uint32_t control_mode;
    double target_log_exx;
    double target_log_eyy;
    uint64_t specimen_solve_id;
    double specimen_grip_mm[4];
#ifdef __cplusplus
    static constexpr const char* IOX2_TYPE_NAME = "dicstream.RigState.v6";
#endif
} DicstreamRigState;
DICSTREAM_STATIC_ASSERT(sizeof(DicstreamRigState) == 448, "DicstreamRigState size");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, layout_version) == 0, "DicstreamRigState.layout_version offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, program_state) == 4, "DicstreamRigState.program_state offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, sample_id) == 8, "DicstreamRigState.sample_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, t_sim_s) == 16, "DicstreamRigState.t_sim_s offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, t_published_ns) == 24, "DicstreamRigState.t_published_ns offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, actuators) == 32, "DicstreamRigState.actuators offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, axis_centre_mm) == 272, "DicstreamRigState.axis_centre_mm offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, axis_elongation_mm) == 296, "DicstreamRigState.axis_elongation_mm offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, specimen_stretch_x) == 320, "DicstreamRigState.specimen_stretch_x offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, specimen_stretch_y) == 328, "DicstreamRigState.specimen_stretch_y offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, specimen_rotation_rad) == 336, "DicstreamRigState.specimen_rotation_rad offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, specimen_centre_offset_mm) == 344, "DicstreamRigState.specimen_centre_offset_mm offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, specimen_section_x_mm2) == 360, "DicstreamRigState.specimen_section_x_mm2 offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, specimen_section_y_mm2) == 368, "DicstreamRigState.specimen_section_y_mm2 offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, load_case) == 376, "DicstreamRigState.load_case offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, hydraulics_on) == 380, "DicstreamRigState.hydraulics_on offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, test_index) == 384, "DicstreamRigState.test_index offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, control_mode) == 388, "DicstreamRigState.control_mode offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, target_log_exx) == 392, "DicstreamRigState.target_log_exx offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, target_log_eyy) == 400, "DicstreamRigState.target_log_eyy offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, specimen_solve_id) == 408, "DicstreamRigState.specimen_solve_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRigState, specimen_grip_mm) == 416, "DicstreamRigState.specimen_grip_mm offset");

typedef struct DicstreamRankedModel {
    uint8_t name[24];
    double aic;
    double rms_mpa;
#ifdef __cplusplus
    static constexpr const char* IOX2_TYPE_NAME = "dicstream.RankedModel.v6";
#endif
} DicstreamRankedModel;
DICSTREAM_STATIC_ASSERT(sizeof(DicstreamRankedModel) == 40, "DicstreamRankedModel size");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRankedModel, name) == 0, "DicstreamRankedModel.name offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRankedModel, aic) == 24, "DicstreamRankedModel.aic offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamRankedModel, rms_mpa) == 32, "DicstreamRankedModel.rms_mpa offset");

typedef struct DicstreamIdentificationReport {
    uint32_t layout_version;
    uint32_t points[3];
    uint64_t frame_id;
    uint64_t t_capture_ns;
    uint64_t t_published_ns;
    double a[8];
    double a_stderr[8];
    double b[8];
    double b_stderr[8];
    uint32_t a_count;
    uint32_t b_count;
    double rms_mpa;
    uint32_t ranked_count;
    uint32_t route;
    DicstreamRankedModel ranking[8];
#ifdef __cplusplus
    static constexpr const char* IOX2_TYPE_NAME = "dicstream.IdentificationReport.v6";
#endif
} DicstreamIdentificationReport;
DICSTREAM_STATIC_ASSERT(sizeof(DicstreamIdentificationReport) == 640, "DicstreamIdentificationReport size");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, layout_version) == 0, "DicstreamIdentificationReport.layout_version offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, points) == 4, "DicstreamIdentificationReport.points offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, frame_id) == 16, "DicstreamIdentificationReport.frame_id offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, t_capture_ns) == 24, "DicstreamIdentificationReport.t_capture_ns offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, t_published_ns) == 32, "DicstreamIdentificationReport.t_published_ns offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, a) == 40, "DicstreamIdentificationReport.a offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, a_stderr) == 104, "DicstreamIdentificationReport.a_stderr offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, b) == 168, "DicstreamIdentificationReport.b offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, b_stderr) == 232, "DicstreamIdentificationReport.b_stderr offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, a_count) == 296, "DicstreamIdentificationReport.a_count offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, b_count) == 300, "DicstreamIdentificationReport.b_count offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, rms_mpa) == 304, "DicstreamIdentificationReport.rms_mpa offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, ranked_count) == 312, "DicstreamIdentificationReport.ranked_count offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, route) == 316, "DicstreamIdentificationReport.route offset");
DICSTREAM_STATIC_ASSERT(offsetof(DicstreamIdentificationReport, ranking) == 320, "DicstreamIdentificationReport.ranking offset");

#endif /* DICSTREAM_WIRE_H */
