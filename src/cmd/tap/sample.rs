//! The one-line and JSON summaries of the last sample `dicstream tap` saw.

use serde_json::{json, Value};
use wire::{
    FieldHeader, FieldNode, FrameHeader, GradientSource, IdentificationReport, NodeStatus,
    RigState, StrainMeasure,
};

/// The last sample seen, kept to summarise it.
#[derive(Debug, Clone)]
pub(super) enum LastSample {
    Frame {
        header: FrameHeader,
        checksum_ok: bool,
    },
    Field {
        header: FieldHeader,
        /// Mean displacement gradient of the `ok` nodes: du/dx, du/dy, dv/dx, dv/dy.
        mean_gradient: [f64; 4],
        /// `wire::field::nodes_checksum` of its nodes: another reader of the field (the Python
        /// package) proves it read the same node values.
        nodes_checksum: u64,
    },
    Rig {
        state: RigState,
    },
    Identification {
        // Boxed: a report is three times a frame header (and comes a few times a second).
        report: Box<IdentificationReport>,
    },
}

/// Mean of an actuator pair's forces (kN): the axis force, as the identifier reads it.
pub(super) fn axis_force_kn(state: &RigState, axis: usize) -> f64 {
    0.5 * (state.actuators[2 * axis].force_kn + state.actuators[2 * axis + 1].force_kn)
}

/// Mean displacement gradient (du/dx, du/dy, dv/dx, dv/dy) of the `ok` nodes (zeros when none).
pub(super) fn mean_gradient(nodes: &[FieldNode]) -> [f64; 4] {
    let mut sum = [0.0; 4];
    let mut count = 0usize;
    for n in nodes.iter().filter(|n| n.status == NodeStatus::Ok as u32) {
        for (s, g) in sum.iter_mut().zip([n.du_dx, n.du_dy, n.dv_dx, n.dv_dy]) {
            *s += f64::from(g);
        }
        count += 1;
    }
    sum.map(|s| if count > 0 { s / count as f64 } else { 0.0 })
}

/// The header's gradient source as a word (`unknown` for a code this build does not know).
fn gradient_source(header: &FieldHeader) -> &'static str {
    GradientSource::from_code(header.gradient_source).map_or("unknown", GradientSource::name)
}

pub(super) fn rig_id(id: u64) -> Value {
    if id == wire::NO_RIG_SAMPLE {
        Value::Null
    } else {
        json!(id)
    }
}

impl LastSample {
    pub(super) fn line(&self) -> String {
        match self {
            LastSample::Frame {
                header,
                checksum_ok,
            } => {
                let mut line = format!(
                    "frame {}: {}x{} {} bit, checksum {}",
                    header.frame_id,
                    header.width_px,
                    header.height_px,
                    header.bit_depth,
                    if *checksum_ok { "ok" } else { "BAD" }
                );
                if header.rig_sample_id != wire::NO_RIG_SAMPLE {
                    line.push_str(&format!(", rig sample {}", header.rig_sample_id));
                }
                if header.has_truth == 1 {
                    let f = header.truth.deformation_gradient;
                    line.push_str(&format!(
                        ", truth F [{:.5} {:.5}; {:.5} {:.5}] t ({:.3}, {:.3}) px",
                        f[0],
                        f[1],
                        f[2],
                        f[3],
                        header.truth.translation_px[0],
                        header.truth.translation_px[1]
                    ));
                }
                line
            }
            LastSample::Field {
                header,
                mean_gradient: d,
                ..
            } => {
                let g = header.gauge_of(StrainMeasure::Log);
                format!(
                    "field of frame {}: {}/{} valid nodes, u mean {:.4} px, v mean {:.4} px, \
                     gauge log strain xx {:.3e} yy {:.3e} xy {:.3e}, mean gradient ({}) \
                     du/dx {:.3e} du/dy {:.3e} dv/dx {:.3e} dv/dy {:.3e}",
                    header.frame_id,
                    header.valid_nodes,
                    header.node_count(),
                    header.u_mean_px,
                    header.v_mean_px,
                    g.exx,
                    g.eyy,
                    g.exy,
                    gradient_source(header),
                    d[0],
                    d[1],
                    d[2],
                    d[3]
                )
            }
            LastSample::Rig { state } => {
                let mut line = format!(
                    "rig sample {}: t_sim {:.3} s, stretch x {:.4} y {:.4}, force X {:.4} kN Y {:.4} kN, control {}",
                    state.sample_id,
                    state.t_sim_s,
                    state.specimen_stretch_x,
                    state.specimen_stretch_y,
                    axis_force_kn(state, 0),
                    axis_force_kn(state, 1),
                    state.control().name()
                );
                if let Some([x, y]) = state.strain_target() {
                    line.push_str(&format!(", target ln λ x {x:.4} y {y:.4}"));
                }
                line
            }
            LastSample::Identification { report } => {
                let coefficients = |values: &[f64], count: u32| {
                    values[..(count as usize).min(values.len())]
                        .iter()
                        .map(|v| format!("{v:.4e}"))
                        .collect::<Vec<_>>()
                        .join(" ")
                };
                let best = if report.ranked_count > 0 {
                    wire::text::read_fixed(&report.ranking[0].name)
                } else {
                    "-".to_string()
                };
                format!(
                    "identification at frame {}: points uniaxial {} equibiaxial {} shear {}, \
                     a [{}], b [{}], rms {:.4} MPa, best {best}",
                    report.frame_id,
                    report.points[0],
                    report.points[1],
                    report.points[2],
                    coefficients(&report.a, report.a_count),
                    coefficients(&report.b, report.b_count),
                    report.rms_mpa
                )
            }
        }
    }

    pub(super) fn json(&self) -> Value {
        match self {
            LastSample::Frame {
                header,
                checksum_ok,
            } => json!({
                "frame_id": header.frame_id,
                "width_px": header.width_px,
                "height_px": header.height_px,
                "bit_depth": header.bit_depth,
                "checksum_ok": checksum_ok,
                "rig_sample_id": rig_id(header.rig_sample_id),
                "scenario_id": header.scenario_id,
                "has_truth": header.has_truth == 1,
                "deformation_gradient": header.truth.deformation_gradient,
                "translation_px": header.truth.translation_px,
                "centre_px": header.truth.centre_px,
            }),
            LastSample::Field {
                header,
                mean_gradient: d,
                nodes_checksum,
            } => {
                let g = header.gauge_of(StrainMeasure::Log);
                json!({
                    "frame_id": header.frame_id,
                    "rig_sample_id": rig_id(header.rig_sample_id),
                    "valid_nodes": header.valid_nodes,
                    "nodes": header.node_count(),
                    "u_mean_px": header.u_mean_px,
                    "v_mean_px": header.v_mean_px,
                    "gauge_log_strain": {"xx": g.exx, "yy": g.eyy, "xy": g.exy},
                    "correlator_frames_dropped": header.frames_dropped,
                    "gradient_source": gradient_source(header),
                    "mean_gradient": {"du_dx": d[0], "du_dy": d[1], "dv_dx": d[2], "dv_dy": d[3]},
                    // A string: a u64 beyond 2^53 does not survive JSON readers as a number.
                    "nodes_checksum": nodes_checksum.to_string(),
                })
            }
            LastSample::Rig { state } => json!({
                "sample_id": state.sample_id,
                "t_sim_s": state.t_sim_s,
                "stretch_x": state.specimen_stretch_x,
                "stretch_y": state.specimen_stretch_y,
                "force_x_kn": axis_force_kn(state, 0),
                "force_y_kn": axis_force_kn(state, 1),
                "control": state.control().name(),
                // null under displacement control.
                "target_log": state.strain_target(),
            }),
            LastSample::Identification { report } => json!({
                "frame_id": report.frame_id,
                "points": report.points,
                "a": &report.a[..(report.a_count as usize).min(report.a.len())],
                "b": &report.b[..(report.b_count as usize).min(report.b.len())],
                "rms_mpa": report.rms_mpa,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rig_sample_shows_its_control_mode_and_strain_target() {
        let displacement = LastSample::Rig {
            state: RigState {
                target_log_exx: f64::NAN,
                target_log_eyy: f64::NAN,
                ..RigState::default()
            },
        };
        assert!(displacement.line().ends_with(", control displacement"));
        let json = displacement.json();
        assert_eq!(json["control"], "displacement");
        assert!(json["target_log"].is_null());
        let strain = LastSample::Rig {
            state: RigState {
                control_mode: wire::RigControl::Strain as u32,
                target_log_exx: 0.25,
                target_log_eyy: 0.125,
                ..RigState::default()
            },
        };
        assert!(
            strain
                .line()
                .ends_with(", control strain, target ln λ x 0.2500 y 0.1250"),
            "{}",
            strain.line()
        );
        assert_eq!(strain.json()["target_log"], json!([0.25, 0.125]));
    }
}
