//! `frames.csv`: one row per correlated frame, everything a test engineer plots afterwards
//! — ids and times, the gauge strains of the four measures, the stretches and invariants
//! they give, the rig's forces and Cauchy stresses at the frame's rig sample (and, under strain
//! control, the log strains the rig aimed at then: empty cells otherwise), the latency,
//! and, for simulated frames, the correlator's actual error against the ground truth.

use crate::truth;
use producer::FieldMotion;
use std::collections::VecDeque;
use std::fmt::Write as _;
use wire::{FieldHeader, FieldNode, GroundTruth, RigState, StrainMeasure};

/// Column names, in order.
pub const COLUMNS: [&str; 47] = [
    "frame_id",
    "reference_frame_id",
    "rig_sample_id",
    "t_capture_s",
    "t_sim_s",
    "load_case",
    "small_exx",
    "small_eyy",
    "small_exy",
    "green_exx",
    "green_eyy",
    "green_exy",
    "nominal_exx",
    "nominal_eyy",
    "nominal_exy",
    "log_exx",
    "log_eyy",
    "log_exy",
    "stretch_x",
    "stretch_y",
    "i1",
    "i2",
    "force_x_n",
    "force_y_n",
    "cauchy_x_mpa",
    "cauchy_y_mpa",
    "rig_stretch_x",
    "rig_stretch_y",
    "target_log_exx",
    "target_log_eyy",
    "nodes",
    "valid_nodes",
    "u_mean_px",
    "v_mean_px",
    "disp_error_mean_px",
    "disp_error_max_px",
    "log_exx_error",
    "log_eyy_error",
    "latency_field_ms",
    "latency_seen_ms",
    "correlate_ms",
    "frames_dropped",
    // Appended (a reader of the columns above is unaffected): each grip's own force, X+, X-,
    // Y+, Y- (the field route's external virtual work), and the frame sequence (one test),
    // last: a row always ends with a number.
    "force_x+_n",
    "force_x-_n",
    "force_y+_n",
    "force_y-_n",
    "sequence_id",
];

/// The columns that compare with the ground truth: absent (not empty, not zero) from the
/// `frames.csv` of a real camera, whose frames have none.
pub const TRUTH_COLUMNS: [&str; 4] = [
    "disp_error_mean_px",
    "disp_error_max_px",
    "log_exx_error",
    "log_eyy_error",
];

pub fn csv_header() -> String {
    COLUMNS.join(",")
}

/// The header with the truth columns, or without them (a camera without ground truth).
pub fn csv_header_for(truth: bool) -> String {
    csv_header_with(truth, "")
}

/// The header with or without the truth columns, and the user's gauges' columns (each
/// preceded by a comma, `gauge_columns::header`) before the last, `sequence_id`.
pub fn csv_header_with(truth: bool, gauge_columns: &str) -> String {
    let mut header = COLUMNS
        .iter()
        .filter(|c| truth || !TRUTH_COLUMNS.contains(c))
        .copied()
        .collect::<Vec<_>>()
        .join(",");
    let last = header.rfind(',').expect("several columns");
    header.insert_str(last, gauge_columns);
    header
}

/// Recent rig samples by id, bounded: fields name the sample their frame was taken at.
#[derive(Debug)]
pub struct RigHistory {
    samples: VecDeque<RigState>,
    capacity: usize,
}

impl RigHistory {
    pub fn new(capacity: usize) -> RigHistory {
        assert!(capacity > 0);
        RigHistory {
            samples: VecDeque::with_capacity(capacity),
            capacity,
        }
    }

    /// Adds a sample; a sample id that goes back (a restarted rig) clears the history.
    pub fn push(&mut self, state: RigState) {
        if self
            .samples
            .back()
            .is_some_and(|last| state.sample_id <= last.sample_id)
        {
            self.samples.clear();
        }
        if self.samples.len() == self.capacity {
            self.samples.pop_front();
        }
        self.samples.push_back(state);
    }

    pub fn get(&self, sample_id: u64) -> Option<&RigState> {
        self.samples
            .binary_search_by_key(&sample_id, |s| s.sample_id)
            .ok()
            .map(|i| &self.samples[i])
    }

    pub fn latest(&self) -> Option<&RigState> {
        self.samples.back()
    }

    /// The last sample at or before `t_ns` on the monotonic clock (`t_published_ns`): the rig
    /// state of a frame that names no rig sample (a real camera's).
    pub fn at_time(&self, t_ns: u64) -> Option<&RigState> {
        let after = self.samples.partition_point(|s| s.t_published_ns <= t_ns);
        after.checked_sub(1).map(|i| &self.samples[i])
    }
}

/// Recent frames' ground truth by frame id, bounded (the truth of a field's origin frame).
#[derive(Debug)]
pub struct TruthHistory {
    truths: VecDeque<(u64, GroundTruth)>,
    capacity: usize,
}

impl TruthHistory {
    pub fn new(capacity: usize) -> TruthHistory {
        assert!(capacity > 0);
        TruthHistory {
            truths: VecDeque::with_capacity(capacity),
            capacity,
        }
    }

    /// Adds a frame's truth; ids going back (a restarted camera) clear the history.
    pub fn push(&mut self, frame_id: u64, truth: GroundTruth) {
        if self.truths.back().is_some_and(|(id, _)| frame_id <= *id) {
            self.truths.clear();
        }
        if self.truths.len() == self.capacity {
            self.truths.pop_front();
        }
        self.truths.push_back((frame_id, truth));
    }

    pub fn get(&self, frame_id: u64) -> Option<&GroundTruth> {
        self.truths
            .binary_search_by_key(&frame_id, |(id, _)| *id)
            .ok()
            .map(|i| &self.truths[i].1)
    }
}

/// One row of `frames.csv`. Absent values are written as empty cells.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameRow {
    pub frame_id: u64,
    pub reference_frame_id: u64,
    pub rig_sample_id: Option<u64>,
    pub t_capture_s: f64,
    pub t_sim_s: Option<f64>,
    pub load_case: u32,
    /// Gauge strains in the order of [`StrainMeasure::ALL`], each (exx, eyy, exy).
    pub gauge: [[f64; 3]; 4],
    pub stretch: [f64; 2],
    pub invariants: [f64; 2],
    pub force_n: Option<[f64; 2]>,
    pub cauchy_mpa: Option<[f64; 2]>,
    pub rig_stretch: Option<[f64; 2]>,
    /// The strain program's target (ln λx, ln λy) at the frame's rig sample (also while held by
    /// an interlock); None under displacement control or without a rig sample.
    pub target_log: Option<[f64; 2]>,
    pub nodes: usize,
    pub valid_nodes: u32,
    pub u_mean_px: f64,
    pub v_mean_px: f64,
    /// Mean and max displacement error (px) over valid nodes.
    pub displacement_error_px: Option<[f64; 2]>,
    /// Measured minus true gauge log strain, exx and eyy.
    pub log_strain_error: Option<[f64; 2]>,
    pub latency_field_ms: f64,
    pub latency_seen_ms: f64,
    pub correlate_ms: f64,
    pub frames_dropped: u64,
    /// The frame sequence (one test) of the frame.
    pub sequence_id: u32,
    /// Each grip's force at the frame's rig sample, N, actuators X+, X-, Y+, Y-.
    pub grip_forces_n: Option<[f64; 4]>,
}

/// The forces (N) along x and y: the mean of each axis's two actuator forces (kN).
fn forces_n(rig: &RigState) -> [f64; 2] {
    let a = &rig.actuators;
    [
        500.0 * (a[0].force_kn + a[1].force_kn),
        500.0 * (a[2].force_kn + a[3].force_kn),
    ]
}

/// The Cauchy stresses (MPa) of `force_n` on the specimen's current sections (0 without one).
fn cauchy_mpa(rig: &RigState, force_n: [f64; 2]) -> [f64; 2] {
    let stress = |force: f64, section_mm2: f64| match section_mm2 > 0.0 {
        true => force / section_mm2,
        false => 0.0,
    };
    [
        stress(force_n[0], rig.specimen_section_x_mm2),
        stress(force_n[1], rig.specimen_section_y_mm2),
    ]
}

/// What a field is compared with: the homogeneous motion of its origin frame (the field's own
/// header holds the current one), or the finite-element fields of its origin frame and of its
/// own frame (the specimen as a structure), with the control gauge whose nodes the gauge's
/// truth is the mean over.
#[derive(Clone, Copy)]
pub enum OriginTruth<'a> {
    Motion(&'a GroundTruth),
    Field {
        origin: &'a FieldMotion,
        current: &'a FieldMotion,
        control: &'a correlator::gauges::ControlRegion<'a>,
    },
}

/// The field's errors against the ground truth: the mean and max node displacement error
/// (px), and the measured minus true gauge log strain.
fn truth_errors(
    header: &FieldHeader,
    nodes: &[FieldNode],
    origin: OriginTruth<'_>,
    each: &mut dyn FnMut(f64),
) -> (Option<[f64; 2]>, Option<[f64; 2]>) {
    let log = header.gauge_of(StrainMeasure::Log);
    let strain_error = |t: [f64; 3]| [log.exx - t[0], log.eyy - t[1]];
    match origin {
        OriginTruth::Motion(origin) => {
            let current = &header.truth;
            let displacement_error_px = truth::displacement_error(nodes, current, origin, each)
                .map(|(mean, max, _)| [mean, max]);
            let log_strain_error = truth::relative_gradient(current, origin)
                .and_then(|f| truth::log_strain(&f))
                .map(strain_error);
            (displacement_error_px, log_strain_error)
        }
        OriginTruth::Field {
            origin,
            current,
            control,
        } => {
            let in_gauge =
                |n: &FieldNode| control.contains(correlator::gauges::GaugeNode::position_px(n));
            match truth::field_errors(nodes, current, origin, in_gauge, each) {
                Some(e) => (
                    Some([e.mean_px, e.max_px]),
                    e.mean_gradient
                        .and_then(|g| truth::log_strain(&g))
                        .map(strain_error),
                ),
                None => (None, None),
            }
        }
    }
}

impl FrameRow {
    /// Builds the row of one field. `rig` is the field's rig sample, `origin_truth` the truth
    /// of the frame its node positions are measured in (its origin frame; with a
    /// finite-element specimen, both frames' fields), each node's error going to
    /// `each_error`, `t0_ns` the
    /// run's start and `seen_ns` when the monitor received the field.
    pub fn new(
        header: &FieldHeader,
        nodes: &[FieldNode],
        rig: Option<&RigState>,
        origin_truth: Option<OriginTruth<'_>>,
        each_error: &mut dyn FnMut(f64),
        t0_ns: u64,
        seen_ns: u64,
    ) -> FrameRow {
        let gauge = StrainMeasure::ALL.map(|m| {
            let g = header.gauge_of(m);
            [g.exx, g.eyy, g.exy]
        });
        let log = header.gauge_of(StrainMeasure::Log);
        let stretch = [log.exx.exp(), log.eyy.exp()];
        let l3 = 1.0 / (stretch[0] * stretch[1]);
        let invariants = [
            stretch[0].powi(2) + stretch[1].powi(2) + l3.powi(2),
            stretch[0].powi(-2) + stretch[1].powi(-2) + l3.powi(-2),
        ];
        let force_n = rig.map(forces_n);
        let cauchy_mpa = rig.zip(force_n).map(|(s, f)| cauchy_mpa(s, f));
        let (displacement_error_px, log_strain_error) = origin_truth
            .filter(|_| header.has_truth == 1)
            .map_or((None, None), |origin| {
                truth_errors(header, nodes, origin, each_error)
            });
        let ms = |ns: u64| ns as f64 * 1e-6;
        FrameRow {
            frame_id: header.frame_id,
            reference_frame_id: header.reference_frame_id,
            rig_sample_id: (header.rig_sample_id != wire::NO_RIG_SAMPLE)
                .then_some(header.rig_sample_id),
            t_capture_s: header.t_capture_ns.saturating_sub(t0_ns) as f64 * 1e-9,
            t_sim_s: rig.map(|s| s.t_sim_s),
            load_case: rig.map_or(0, |s| s.load_case),
            gauge,
            stretch,
            invariants,
            force_n,
            cauchy_mpa,
            rig_stretch: rig.map(|s| [s.specimen_stretch_x, s.specimen_stretch_y]),
            target_log: rig.and_then(RigState::strain_target),
            nodes: nodes.len(),
            valid_nodes: header.valid_nodes,
            u_mean_px: header.u_mean_px,
            v_mean_px: header.v_mean_px,
            displacement_error_px,
            log_strain_error,
            latency_field_ms: ms(header.t_published_ns.saturating_sub(header.t_capture_ns)),
            latency_seen_ms: ms(seen_ns.saturating_sub(header.t_capture_ns)),
            correlate_ms: ms(header.correlate_ns),
            frames_dropped: header.frames_dropped,
            sequence_id: header.sequence_id,
            grip_forces_n: rig.map(|s| std::array::from_fn(|i| 1e3 * s.actuators[i].force_kn)),
        }
    }

    /// Appends the CSV line (with its newline) to `out`.
    pub fn write_csv(&self, out: &mut String) {
        self.write_csv_for(out, true)
    }

    /// Appends the CSV line, with or without the truth columns ([`csv_header_for`]).
    pub fn write_csv_for(&self, out: &mut String, truth: bool) {
        self.write_csv_with(out, truth, "")
    }

    /// Appends the CSV line with or without the truth columns and with the gauges' cells
    /// (each preceded by a comma) before the last, as [`csv_header_with`] orders them.
    pub fn write_csv_with(&self, out: &mut String, truth: bool, gauge_cells: &str) {
        fn opt<T: std::fmt::Display>(out: &mut String, v: Option<T>) {
            if let Some(v) = v {
                let _ = write!(out, "{v}");
            }
            out.push(',');
        }
        fn pair(out: &mut String, v: Option<[f64; 2]>) {
            opt(out, v.map(|p| p[0]));
            opt(out, v.map(|p| p[1]));
        }
        let _ = write!(out, "{},{},", self.frame_id, self.reference_frame_id);
        opt(out, self.rig_sample_id);
        let _ = write!(out, "{:.6},", self.t_capture_s);
        opt(out, self.t_sim_s.map(|t| format!("{t:.4}")));
        let _ = write!(out, "{},", self.load_case);
        for g in &self.gauge {
            for v in g {
                let _ = write!(out, "{v:.7},");
            }
        }
        let _ = write!(
            out,
            "{:.6},{:.6},{:.6},{:.6},",
            self.stretch[0], self.stretch[1], self.invariants[0], self.invariants[1]
        );
        pair(out, self.force_n);
        pair(out, self.cauchy_mpa);
        pair(out, self.rig_stretch);
        opt(out, self.target_log.map(|t| format!("{:.7}", t[0])));
        opt(out, self.target_log.map(|t| format!("{:.7}", t[1])));
        let _ = write!(
            out,
            "{},{},{:.5},{:.5},",
            self.nodes, self.valid_nodes, self.u_mean_px, self.v_mean_px
        );
        if truth {
            pair(out, self.displacement_error_px);
            pair(out, self.log_strain_error);
        }
        let _ = write!(
            out,
            "{:.3},{:.3},{:.3},{}",
            self.latency_field_ms, self.latency_seen_ms, self.correlate_ms, self.frames_dropped
        );
        match self.grip_forces_n {
            Some(forces) => forces.iter().for_each(|f| {
                let _ = write!(out, ",{f:.6}");
            }),
            None => out.push_str(",,,,"),
        }
        out.push_str(gauge_cells);
        let _ = writeln!(out, ",{}", self.sequence_id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wire::{GaugeStrain, NodeStatus};

    #[test]
    fn row_has_every_column_and_the_truth_error() {
        let lx = 1.5f64;
        let truth = GroundTruth {
            deformation_gradient: [lx, 0.0, 0.0, 1.0 / lx.sqrt()],
            translation_px: [0.0, 0.0],
            centre_px: [64.0, 64.0],
            ..GroundTruth::IDENTITY
        };
        let mut header = FieldHeader {
            frame_id: 12,
            rig_sample_id: 40,
            sequence_id: 3,
            t_capture_ns: 2_000_000_000,
            t_published_ns: 2_050_000_000,
            has_truth: 1,
            truth,
            valid_nodes: 1,
            ..FieldHeader::default()
        };
        // Measured log strain 1 % above the truth along x.
        header.gauge[StrainMeasure::Log as usize] = GaugeStrain {
            exx: lx.ln() + 0.01,
            eyy: -0.5 * lx.ln(),
            exy: 0.0,
        };
        let nodes = [FieldNode {
            x_px: 74.0,
            y_px: 64.0,
            u_px: 5.0 + 0.25,
            v_px: 0.0,
            status: NodeStatus::Ok as u32,
            ..FieldNode::default()
        }];
        let mut rig = RigState {
            sample_id: 40,
            t_sim_s: 3.5,
            specimen_section_x_mm2: 40.0 / lx,
            load_case: 1,
            ..RigState::default()
        };
        rig.actuators[0].force_kn = 0.1;
        rig.actuators[1].force_kn = 0.1;
        let row = FrameRow::new(
            &header,
            &nodes,
            Some(&rig),
            Some(OriginTruth::Motion(&GroundTruth::IDENTITY)),
            &mut |_| {},
            1_000_000_000,
            2_060_000_000,
        );
        assert!((row.stretch[0] - lx * 0.01f64.exp()).abs() < 1e-12);
        assert_eq!(row.force_n.unwrap()[0], 100.0);
        assert!((row.cauchy_mpa.unwrap()[0] - 100.0 * lx / 40.0).abs() < 1e-12);
        let [mean, max] = row.displacement_error_px.unwrap();
        assert!((mean - 0.25).abs() < 1e-5 && (max - 0.25).abs() < 1e-5);
        assert!((row.log_strain_error.unwrap()[0] - 0.01).abs() < 1e-9);
        assert!((row.latency_field_ms - 50.0).abs() < 1e-9);
        assert!((row.t_capture_s - 1.0).abs() < 1e-12);
        assert_eq!(row.target_log, None, "displacement control: no target");
        let mut line = String::new();
        row.write_csv(&mut line);
        assert_eq!(line.trim_end().split(',').count(), COLUMNS.len());
        let cell = |line: &str, name: &str| {
            let at = COLUMNS.iter().position(|c| *c == name).unwrap();
            line.trim_end().split(',').nth(at).unwrap().to_string()
        };
        assert_eq!(cell(&line, "target_log_exx"), "");
        assert_eq!(cell(&line, "target_log_eyy"), "");
        // Each grip's own force and the frame's test, for the field route offline.
        assert_eq!(cell(&line, "force_x+_n"), "100.000000");
        assert_eq!(cell(&line, "force_y-_n"), "0.000000");
        assert_eq!(cell(&line, "sequence_id"), "3");
        // Under strain control (or held), the rig sample's target fills both cells.
        rig.control_mode = wire::RigControl::Held as u32;
        rig.target_log_exx = 0.405_465_1;
        rig.target_log_eyy = -0.2;
        let strained = FrameRow::new(&header, &nodes, Some(&rig), None, &mut |_| {}, 0, 0);
        assert_eq!(strained.target_log, Some([0.405_465_1, -0.2]));
        line.clear();
        strained.write_csv(&mut line);
        assert_eq!(cell(&line, "target_log_exx"), "0.4054651");
        assert_eq!(cell(&line, "target_log_eyy"), "-0.2000000");
        line.clear();
        row.write_csv(&mut line);
        // Without rig sample and truth: empty cells, same count.
        header.has_truth = 0;
        let row = FrameRow::new(&header, &nodes, None, None, &mut |_| {}, 0, 0);
        line.clear();
        row.write_csv(&mut line);
        assert_eq!(line.trim_end().split(',').count(), COLUMNS.len());
        assert!(line.contains(",,"));
    }

    #[test]
    fn histories_pair_by_id_and_forget_on_restart() {
        let mut rigs = RigHistory::new(3);
        for id in 0..5 {
            rigs.push(RigState {
                sample_id: id,
                ..RigState::default()
            });
        }
        assert!(rigs.get(1).is_none());
        assert_eq!(rigs.get(3).unwrap().sample_id, 3);
        rigs.push(RigState::default());
        assert!(rigs.get(3).is_none());
        assert_eq!(rigs.latest().unwrap().sample_id, 0);
        let mut truths = TruthHistory::new(2);
        truths.push(0, GroundTruth::IDENTITY);
        truths.push(1, GroundTruth::IDENTITY);
        truths.push(2, GroundTruth::IDENTITY);
        assert!(truths.get(0).is_none() && truths.get(2).is_some());
    }

    #[test]
    fn without_truth_the_truth_columns_are_absent_and_rows_match_the_header() {
        let header = csv_header_for(false);
        assert!(!header.contains("disp_error") && !header.contains("log_exx_error"));
        assert_eq!(
            header.split(',').count(),
            COLUMNS.len() - TRUTH_COLUMNS.len()
        );
        let field = FieldHeader {
            rig_sample_id: wire::NO_RIG_SAMPLE,
            ..FieldHeader::default()
        };
        let row = FrameRow::new(&field, &[], None, None, &mut |_| {}, 0, 0);
        let mut line = String::new();
        row.write_csv_for(&mut line, false);
        assert_eq!(
            line.trim_end().split(',').count(),
            header.split(',').count()
        );
        // The gauges' columns and cells go before sequence_id, which stays last.
        let header = csv_header_with(true, ",gauge_a_log_exx,ext_b_elongation_px");
        assert!(header.ends_with(",gauge_a_log_exx,ext_b_elongation_px,sequence_id"));
        line.clear();
        row.write_csv_with(&mut line, true, ",,");
        assert!(line.ends_with(",,,0\n"), "{line}");
        assert_eq!(
            line.trim_end().split(',').count(),
            header.split(',').count()
        );
    }

    #[test]
    fn a_rig_state_is_found_by_time() {
        let mut rigs = RigHistory::new(8);
        for k in 0..4u64 {
            rigs.push(RigState {
                sample_id: k,
                t_published_ns: 100 * k,
                ..RigState::default()
            });
        }
        assert!(rigs.at_time(0).is_some_and(|s| s.sample_id == 0));
        assert!(rigs.at_time(250).is_some_and(|s| s.sample_id == 2));
        assert!(rigs.at_time(10_000).is_some_and(|s| s.sample_id == 3));
        rigs.push(RigState {
            sample_id: 10,
            t_published_ns: 1000,
            ..RigState::default()
        });
        assert!(rigs.at_time(999).is_none_or(|s| s.sample_id != 10));
    }
}
