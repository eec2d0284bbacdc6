//! The live status line, once a second: simulated time and test, stretch, forces, frames
//! captured / correlated / dropped, latency p50/p99, the identified coefficients. The default
//! line fits [`SHORT_COLUMNS`] columns; the long one (`dicstream run --verbose`) has every
//! figure. Neither prints the coefficients of a load case that has no point yet (the fit
//! leaves them free: they swing wildly).

use crate::recorder::Recorder;
use std::fmt::Write as _;

pub fn load_case_name(code: u32) -> &'static str {
    match code {
        1 => "uniaxial",
        2 => "equibiaxial",
        _ => "no test",
    }
}

/// Width of the default status line (a terminal of 100 columns does not wrap it).
pub const SHORT_COLUMNS: usize = 100;

/// The status line: the short one, or with `verbose` the long one.
pub fn line(recorder: &Recorder, wall_s: f64, verbose: bool) -> String {
    match verbose {
        true => status_line(recorder, wall_s),
        false => short_status_line(recorder, wall_s),
    }
}

fn short_case(code: u32) -> &'static str {
    match code {
        1 => "uniax",
        2 => "equibiax",
        _ => "no test",
    }
}

/// At most [`SHORT_COLUMNS`] characters (up to 4-digit forces and points, 5-digit frame
/// counts): time, test, stretch, forces, frames captured / correlated / skipped, gauge log
/// strains, identification points. Latency and coefficients are in the long line.
pub fn short_status_line(recorder: &Recorder, wall_s: f64) -> String {
    let mut line = format!("[{wall_s:5.0}s]");
    match recorder.latest_rig() {
        Some(rig) => {
            let a = &rig.actuators;
            let _ = write!(
                line,
                " {:<8} λ{:.3} F {:.0}/{:.0}N",
                short_case(rig.load_case),
                rig.specimen_stretch_x,
                500.0 * (a[0].force_kn + a[1].force_kn),
                500.0 * (a[2].force_kn + a[3].force_kn),
            );
        }
        None => line.push_str(" rig: -"),
    }
    let dropped = recorder.last_field.map_or(0, |f| f.frames_dropped);
    let _ = write!(
        line,
        " | fr {}/{} skip {}",
        recorder.last_frame_id.map_or(0, |id| id + 1),
        recorder.fields_seen,
        dropped
    );
    if let Some(field) = &recorder.last_field {
        let log = field.gauge_of(wire::StrainMeasure::Log);
        let _ = write!(line, " | ε {:+.3}/{:+.3}", log.exx, log.eyy);
    }
    if let Some(report) = &recorder.last_report {
        let _ = write!(line, " | pts {}/{}", report.points[0], report.points[1]);
    }
    // Only larger figures than those could pass the width: cut them.
    if line.chars().count() > SHORT_COLUMNS {
        line = line.chars().take(SHORT_COLUMNS - 1).collect::<String>() + "…";
    }
    line
}

/// One long line describing the run `wall_s` seconds after its start (`--verbose`).
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
        // f comes from the uniaxial points, g from the equibiaxial ones.
        let shown = |c: &[f64], points: u32, case: &str| match points {
            0 => format!("[no {case} data yet]"),
            _ => format!("[{}]", coefficients(c)),
        };
        let _ = write!(
            line,
            " | points {}/{} a {} b {}",
            report.points[0],
            report.points[1],
            shown(
                &report.a[..report.a_count as usize],
                report.points[0],
                "uniaxial"
            ),
            shown(
                &report.b[..report.b_count as usize],
                report.points[1],
                "equibiaxial"
            ),
        );
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recorder::RecorderSettings;
    use crate::results::ResultsDir;
    use wire::{FieldHeader, FrameHeader, IdentificationReport, RigState};

    #[test]
    fn the_short_line_fits_100_columns_and_no_line_prints_free_coefficients() {
        let dir = std::env::temp_dir().join(format!("dicstream_status_{}", std::process::id()));
        let results = ResultsDir::at(&dir).unwrap();
        let settings = RecorderSettings {
            fields_every: 10,
            vtk: false,
            truth: true,
            framing: producer::Framing {
                mm_per_px: 0.25,
                strip_mm_per_px: 0.12,
            },
            gauges: Vec::new(),
            control_gauge: correlator::ControlGauge::default(),
            scale: crate::field_scale::FieldScale::None,
        };
        let mut recorder = Recorder::new(&results, settings, 0).unwrap();
        let mut rig = RigState {
            t_sim_s: 9999.6,
            load_case: 2,
            specimen_stretch_x: 2.123,
            specimen_stretch_y: 2.123,
            ..RigState::default()
        };
        for a in rig.actuators.iter_mut() {
            a.force_kn = -9.999;
        }
        recorder.on_rig(rig);
        recorder.on_frame(
            &FrameHeader {
                frame_id: 99_998,
                ..FrameHeader::default()
            },
            &[],
        );
        let field = FieldHeader {
            frame_id: 99_997,
            t_capture_ns: 1_000_000,
            t_published_ns: 1_234_000_000,
            frames_dropped: 9_999,
            valid_nodes: 4096,
            ..FieldHeader::default()
        };
        recorder.on_field(&field, &[], 1_234_000_000);
        let mut report = IdentificationReport {
            points: [9_999, 0, 0],
            a_count: 3,
            b_count: 3,
            ..IdentificationReport::default()
        };
        report.b[..3].copy_from_slice(&[-1.0e7, 3.5, 7.0e4]);
        recorder.on_report(report);
        let short = line(&recorder, 9_999.0, false);
        assert!(short.chars().count() <= SHORT_COLUMNS, "{short}");
        assert!(short.ends_with("pts 9999/0"), "{short}");
        let long = line(&recorder, 99_999.0, true);
        assert!(long.chars().count() > SHORT_COLUMNS);
        assert!(long.contains("b [no equibiaxial data yet]"), "{long}");
        assert!(!long.contains("1.000e7"), "{long}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
