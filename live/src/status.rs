//! The live status line, once a second: simulated time and test, stretch, forces, frames
//! captured / correlated / dropped, latency p50/p99, the identified coefficients.

use crate::recorder::Recorder;
use std::fmt::Write as _;

pub fn load_case_name(code: u32) -> &'static str {
    match code {
        1 => "uniaxial",
        2 => "equibiaxial",
        _ => "no test",
    }
}

/// One line describing the run `wall_s` seconds after its start.
pub fn status_line(recorder: &Recorder, wall_s: f64) -> String {
    let mut line = format!("[{wall_s:6.1} s]");
    match recorder.latest_rig() {
        Some(rig) => {
            let a = &rig.actuators;
            let _ = write!(
                line,
                " sim {:6.1} s {:<11} λ {:.3} x {:.3} | F {:7.1} / {:7.1} N |",
                rig.t_sim_s,
                load_case_name(rig.load_case),
                rig.specimen_stretch_x,
                rig.specimen_stretch_y,
                500.0 * (a[0].force_kn + a[1].force_kn),
                500.0 * (a[2].force_kn + a[3].force_kn),
            );
        }
        None => line.push_str(" rig: no sample yet |"),
    }
    let dropped = recorder.last_field.map_or(0, |f| f.frames_dropped);
    let _ = write!(
        line,
        " frames {} captured, {} correlated, {} dropped",
        recorder.last_frame_id.map_or(0, |id| id + 1),
        recorder.fields_seen,
        dropped
    );
    if let Some(field) = &recorder.last_field {
        let log = field.gauge_of(wire::StrainMeasure::Log);
        let _ = write!(
            line,
            " | gauge log {:+.4} {:+.4} ({} nodes)",
            log.exx, log.eyy, field.valid_nodes
        );
    }
    let p = recorder.latency_field.percentiles();
    if p.count > 0 {
        let _ = write!(line, " | latency p50 {:.0} ms p99 {:.0} ms", p.p50, p.p99);
    }
    if let Some(report) = &recorder.last_report {
        let coefficients = |c: &[f64]| {
            c.iter()
                .map(|v| format!("{v:.3e}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let _ = write!(
            line,
            " | points {}/{} a [{}] b [{}]",
            report.points[0],
            report.points[1],
            coefficients(&report.a[..report.a_count as usize]),
            coefficients(&report.b[..report.b_count as usize]),
        );
    }
    line
}
