//! What the run's monitor keeps of the samples it sees, without any IPC: it pairs fields with
//! rig samples and frame truths, writes `frames.csv` and every Nth field as it goes, records
//! the latencies, and remembers what the status line and the final figures need.

use crate::frames::{FrameRow, OriginTruth, RigHistory, TruthHistory};
use crate::latency::{FieldLatencyParts, Latency};
use crate::origin_frames::OriginFrames;
use crate::results::ResultsDir;
use crate::truth::NodeErrors;
use producer::specimen_states::SpecimenStates;
use wire::files::{write_atomic, FileError, RowFile};
use wire::{FieldHeader, FieldNode, FrameHeader, IdentificationReport, RigState};

/// Rig samples and frame truths kept for pairing (about 40 s at 200 Hz, 100 s at 10 fps).
const RIG_HISTORY: usize = 8192;
const TRUTH_HISTORY: usize = 1024;

/// Settings of the recorder.
#[derive(Clone, Debug)]
pub struct RecorderSettings {
    pub fields_every: u32,
    pub vtk: bool,
    /// The camera's frames carry the ground truth (simulated): `frames.csv` has the truth
    /// columns. A real camera's has none: the columns are absent.
    pub truth: bool,
    /// How the simulated camera frames a finite-element specimen, whose field is the truth
    /// node by node.
    pub framing: producer::Framing,
    /// The user's gauges (`frames.csv`'s last columns) and the control gauge the fields'
    /// header carries (its truth is taken over the same nodes).
    pub gauges: Vec<correlator::Gauge>,
    pub control_gauge: correlator::ControlGauge,
    /// The fields' scale, for their mm columns (`field_scale`).
    pub scale: crate::field_scale::FieldScale,
}

pub struct Recorder {
    settings: RecorderSettings,
    results: ResultsDir,
    frames_csv: RowFile,
    /// Monotonic ns of the run's start: frames.csv times count from it.
    t0_ns: u64,
    rigs: RigHistory,
    truths: TruthHistory,
    /// The finite-element specimen's solves (the truth of its frames), and the frames' size.
    specimen: SpecimenStates,
    frame_size_px: Option<[u32; 2]>,
    /// Fields of a finite-element specimen whose truth could not be made (its solves not
    /// received), and samples refused.
    pub fields_without_truth: u64,
    pub specimen_refused: u64,
    /// Fields compared with the truth, and every valid node's error in them.
    pub fields_compared: u64,
    pub node_errors: NodeErrors,
    /// The same by the rig's load case of each field (none, uniaxial, equibiaxial).
    pub node_errors_by_case: [NodeErrors; 3],
    pub latency_field: Latency,
    /// Where the field latency goes: waiting, correlating, delivering.
    pub latency_field_parts: FieldLatencyParts,
    pub latency_identification: Latency,
    /// Frames seen on `frames` (the monitor may miss some: its queue drops when it is slow).
    pub frames_seen: u64,
    pub last_frame_id: Option<u64>,
    pub fields_seen: u64,
    pub last_field: Option<FieldHeader>,
    /// Nodes of the last field (buffer reused).
    pub last_nodes: Vec<FieldNode>,
    pub last_report: Option<IdentificationReport>,
    /// The field route's last report (`identification`'s reports of `ReportRoute::Field`).
    pub last_field_report: Option<IdentificationReport>,
    pub rig_samples_seen: u64,
    /// A strain-controlled test's holds by an interlock (strain control then held), and the
    /// rig's simulated time held in all after strain control first ran.
    pub strain_holds: StrainHolds,
    /// Frames the correlators that have ended skipped (their last `frames_dropped`), and the
    /// running one's so far: a restarted correlator counts from 0.
    pub frames_dropped_by_ended_correlators: u64,
    pub frames_dropped_by_correlator: u64,
    /// The image the latest sequence's fields are measured in (its origin frame).
    pub origin_frames: OriginFrames,
    /// The most strained field of the latest sequence (largest gauge log strain), for the
    /// strain map: its header and nodes.
    pub peak_field: Option<(FieldHeader, Vec<FieldNode>)>,
    /// Largest measured stretch per load case code (1 uniaxial, 2 equibiaxial).
    pub max_stretch: [f64; 3],
    row: String,
    /// The user's gauges' readings on the field being recorded (for its row and the
    /// dashboard's history), and their cells of the row.
    gauge_readings: Vec<correlator::GaugeReading>,
    gauge_cells: String,
    text: String,
    /// The VTK fields written so far, as one time series (`fields/fields.vtk.series`), and
    /// their `.vts` twins as a ParaView collection (`fields/fields.pvd`).
    vtk_series: crate::vtk_series::VtkSeries,
    pvd: correlator::pvd::Pvd,
    /// The user's gauges' readings against the test's time, for the dashboard.
    pub gauge_history: crate::gauge_history::GaugeHistory,
    /// Errors writing results (the run goes on, the error is reported once).
    pub write_error: Option<FileError>,
}

impl Recorder {
    pub fn new(
        results: &ResultsDir,
        settings: RecorderSettings,
        t0_ns: u64,
    ) -> Result<Recorder, FileError> {
        assert!(settings.fields_every > 0);
        let gauge_history =
            crate::gauge_history::GaugeHistory::new(&settings.gauges, settings.scale.in_mm());
        Ok(Recorder {
            frames_csv: RowFile::create(
                &results.frames_csv(),
                &crate::frames::csv_header_with(
                    settings.truth,
                    &crate::gauge_columns::header(&settings.gauges, settings.scale.in_mm()),
                ),
            )?,
            results: results.clone(),
            settings,
            t0_ns,
            rigs: RigHistory::new(RIG_HISTORY),
            truths: TruthHistory::new(TRUTH_HISTORY),
            specimen: SpecimenStates::new(),
            frame_size_px: None,
            fields_without_truth: 0,
            specimen_refused: 0,
            fields_compared: 0,
            node_errors: NodeErrors::default(),
            node_errors_by_case: Default::default(),
            latency_field: Latency::new(),
            latency_field_parts: FieldLatencyParts::default(),
            latency_identification: Latency::new(),
            frames_seen: 0,
            last_frame_id: None,
            fields_seen: 0,
            last_field: None,
            last_nodes: Vec::new(),
            last_report: None,
            last_field_report: None,
            rig_samples_seen: 0,
            strain_holds: StrainHolds::default(),
            frames_dropped_by_ended_correlators: 0,
            frames_dropped_by_correlator: 0,
            origin_frames: OriginFrames::default(),
            vtk_series: crate::vtk_series::VtkSeries::new(),
            pvd: correlator::pvd::Pvd::new(),
            gauge_history,
            peak_field: None,
            max_stretch: [1.0; 3],
            row: String::with_capacity(1024),
            gauge_readings: Vec::new(),
            gauge_cells: String::new(),
            text: String::new(),
            write_error: None,
        })
    }

    /// The finite-element fields of a field's origin frame and of its own frame, when they
    /// show the specimen as a structure: None when they do not, `Some(None)` when the fields
    /// cannot be made (a solve not received).
    #[allow(clippy::type_complexity)]
    fn specimen_fields(
        &self,
        header: &FieldHeader,
        origin: &wire::GroundTruth,
    ) -> Option<Option<(producer::FieldMotion, producer::FieldMotion)>> {
        let current = &header.truth;
        let (Some(origin_id), Some(current_id)) =
            (origin.specimen_solve(), current.specimen_solve())
        else {
            return None;
        };
        let Some([width, height]) = self.frame_size_px else {
            return Some(None);
        };
        let framing = &self.settings.framing;
        let field = |id, grip_mm: &[f64; 4]| {
            let framed = self
                .specimen
                .framed_field(id, grip_mm, framing, [width, height]);
            framed.ok()
        };
        Some(
            field(origin_id, &origin.specimen_grip_mm)
                .zip(field(current_id, &current.specimen_grip_mm)),
        )
    }

    fn note_error(&mut self, result: Result<(), FileError>) {
        if let Err(e) = result {
            if self.write_error.is_none() {
                eprintln!("run: cannot write results: {e}");
                self.write_error = Some(e);
            }
        }
    }

    /// A frame header (and its pixels, kept only for the first frame).
    pub fn on_frame(&mut self, header: &FrameHeader, pixels: &[u16]) {
        self.frames_seen += 1;
        self.last_frame_id = Some(header.frame_id);
        self.frame_size_px = Some([header.width_px, header.height_px]);
        if header.has_truth == 1 {
            self.truths.push(header.frame_id, header.truth);
        }
        self.origin_frames.on_frame(header, pixels);
    }

    /// The solves of a finite-element specimen received so far.
    pub fn specimen_solves_received(&self) -> u64 {
        self.specimen.received()
    }

    /// A solved state of the finite-element specimen (`specimen`); a refused one is said once.
    pub fn on_specimen(&mut self, header: &wire::SpecimenHeader, payload: &[f64]) {
        if let Err(e) = self.specimen.push(header, payload) {
            if self.specimen_refused == 0 {
                eprintln!("run: specimen state refused (its frames get no truth): {e}");
            }
            self.specimen_refused += 1;
        }
    }

    pub fn on_rig(&mut self, state: RigState) {
        self.rig_samples_seen += 1;
        self.strain_holds.on_rig(&state);
        self.rigs.push(state);
    }

    pub fn latest_rig(&self) -> Option<&RigState> {
        self.rigs.latest()
    }

    /// A field: its `frames.csv` row, its files every Nth frame, its latency.
    pub fn on_field(&mut self, header: &FieldHeader, nodes: &[FieldNode], seen_ns: u64) {
        self.fields_seen += 1;
        self.frames_dropped_by_correlator = header.frames_dropped;
        self.latency_field
            .record_ns(header.t_published_ns.saturating_sub(header.t_capture_ns));
        self.latency_field_parts.record(
            header.t_capture_ns,
            header.t_received_ns,
            header.t_published_ns,
            seen_ns,
        );
        // A frame without a rig sample (a real camera's): the rig state at its capture time.
        let rig = match header.rig_sample_id {
            wire::NO_RIG_SAMPLE => self.rigs.at_time(header.t_capture_ns),
            id => self.rigs.get(id),
        };
        self.origin_frames
            .on_field(header.sequence_id, header.origin_frame_id);
        let origin = self.truths.get(header.origin_frame_id).copied();
        // The origin frame's solve is named by every field of its sequence: keep it.
        if let Some(id) = origin.and_then(|o| o.specimen_solve()) {
            self.specimen.pin(id);
        }
        let fields = origin.and_then(|o| self.specimen_fields(header, &o));
        // The header's gauge is the control gauge: its truth is taken over the same nodes.
        let control = correlator::gauges::ControlRegion::of(
            &self.settings.control_gauge,
            &self.settings.gauges,
            nodes,
        );
        let origin_truth = match (&origin, &fields) {
            (Some(o), None) => Some(OriginTruth::Motion(o)),
            (_, Some(Some((origin, current)))) => Some(OriginTruth::Field {
                origin,
                current,
                control: &control,
            }),
            _ => None,
        };
        let case = rig.map(|s| s.load_case as usize).filter(|&c| c < 3);
        let (all, by_case) = (&mut self.node_errors, &mut self.node_errors_by_case);
        let mut each_error = |e: f64| {
            all.record(e);
            if let Some(c) = case {
                by_case[c].record(e);
            }
        };
        let row = FrameRow::new(
            header,
            nodes,
            rig,
            origin_truth,
            &mut each_error,
            self.t0_ns,
            seen_ns,
        );
        if origin_truth.is_some() {
            self.fields_compared += 1;
        }
        if matches!(fields, Some(None)) {
            self.fields_without_truth += 1;
        }
        if let Some(case) = case {
            let stretch = row.stretch[0].max(row.stretch[1]);
            if header.valid_nodes > 0 && stretch.is_finite() {
                self.max_stretch[case] = self.max_stretch[case].max(stretch);
            }
        }
        self.row.clear();
        self.gauge_cells.clear();
        let step_px = f64::from(header.step_px);
        let gauges = &self.settings.gauges;
        let grips = origin
            .and_then(|o| o.specimen_solve())
            .and_then(|id| self.specimen.solve(id))
            .map(|s| s.field.grip_mm.len());
        let scale = self.settings.scale.of_field(grips);
        crate::gauge_columns::read_all(gauges, nodes, step_px, &mut self.gauge_readings);
        crate::gauge_columns::write_cells(
            gauges,
            &self.gauge_readings,
            self.settings.scale.in_mm(),
            scale,
            &mut self.gauge_cells,
        );
        let test_time_s = row.t_sim_s.unwrap_or(row.t_capture_s);
        self.gauge_history
            .push(&self.gauge_readings, test_time_s, scale);
        row.write_csv_with(&mut self.row, self.settings.truth, &self.gauge_cells);
        let line = std::mem::take(&mut self.row);
        let result = self.frames_csv.append(&line);
        self.row = line;
        self.note_error(result);
        if header
            .frame_id
            .is_multiple_of(u64::from(self.settings.fields_every))
        {
            let result = self.write_field_files(header, nodes, scale);
            self.note_error(result);
        }
        self.last_field = Some(*header);
        self.last_nodes.clear();
        self.last_nodes.extend_from_slice(nodes);
        let strain = |h: &FieldHeader| {
            let g = h.gauge_of(wire::StrainMeasure::Log);
            g.exx.abs().max(g.eyy.abs())
        };
        let is_peak = self.peak_field.as_ref().is_none_or(|(peak, _)| {
            peak.sequence_id != header.sequence_id || strain(header) > strain(peak)
        });
        if is_peak && header.valid_nodes > 0 {
            let (peak_header, peak_nodes) = self
                .peak_field
                .get_or_insert_with(|| (*header, Vec::with_capacity(nodes.len())));
            *peak_header = *header;
            peak_nodes.clear();
            peak_nodes.extend_from_slice(nodes);
        }
    }

    /// The correlator has ended: its skipped frames are kept, the next one counts from 0.
    pub fn correlator_ended(&mut self) {
        self.frames_dropped_by_ended_correlators +=
            std::mem::take(&mut self.frames_dropped_by_correlator);
    }

    /// Frames skipped by every correlator of the run (behind the camera, they took the newest).
    pub fn frames_dropped_by_correlators(&self) -> u64 {
        self.frames_dropped_by_ended_correlators + self.frames_dropped_by_correlator
    }

    /// A gauge-route report is the run's identification (its latency, its last report); the
    /// field route's is kept apart (`last_field_report`), so neither is mistaken for the other.
    pub fn on_report(&mut self, report: IdentificationReport) {
        if report.route() != Some(wire::identification::ReportRoute::Gauge) {
            self.last_field_report = Some(report);
            return;
        }
        self.latency_identification
            .record_ns(report.t_published_ns.saturating_sub(report.t_capture_ns));
        self.last_report = Some(report);
    }

    fn write_field_files(
        &mut self,
        header: &FieldHeader,
        nodes: &[FieldNode],
        scale: Option<wire::scale::MmPerPx>,
    ) -> Result<(), FileError> {
        let field = to_correlator_field(header, nodes);
        let stem = self
            .results
            .fields()
            .join(format!("field_{:06}", header.frame_id));
        correlator::output::field_csv_scaled(&field, scale, &mut self.text);
        write_atomic(&stem.with_extension("csv"), self.text.as_bytes())?;
        if self.settings.vtk {
            correlator::output::field_vtk(
                &field,
                &format!("dicstream run field of frame {}", header.frame_id),
                &mut self.text,
            );
            let vtk = stem.with_extension("vtk");
            write_atomic(&vtk, self.text.as_bytes())?;
            let name = vtk.file_name().map(|n| n.to_string_lossy().into_owned());
            let time_s = header.t_capture_ns.saturating_sub(self.t0_ns) as f64 * 1e-9;
            self.vtk_series.push(name.unwrap_or_default(), time_s);
            write_atomic(
                &self.results.fields().join(crate::vtk_series::FILE_NAME),
                self.vtk_series.to_json().as_bytes(),
            )?;
            correlator::vts::field_vts(&field, scale, &mut self.text);
            let vts = stem.with_extension("vts");
            write_atomic(&vts, self.text.as_bytes())?;
            let name = vts.file_name().map(|n| n.to_string_lossy().into_owned());
            // A time that does not increase (none expected) is left out of the collection.
            if self.pvd.push(name.unwrap_or_default(), time_s) {
                write_atomic(
                    &self.results.fields().join(PVD_FILE),
                    self.pvd.to_xml().as_bytes(),
                )?;
            }
        }
        Ok(())
    }
}

/// The ParaView collection of the `.vts` fields, in the fields folder.
pub const PVD_FILE: &str = "fields.pvd";

/// A field from the wire as the correlator's own type (for the shared file writers).
pub fn to_correlator_field(header: &FieldHeader, nodes: &[FieldNode]) -> correlator::Field {
    use correlator::NodeStatus as S;
    let status = |code: u32| match wire::NodeStatus::from_code(code) {
        Some(wire::NodeStatus::Ok) => S::Ok,
        Some(wire::NodeStatus::NotConverged) => S::NotConverged,
        Some(wire::NodeStatus::LowContrast) => S::LowContrast,
        Some(wire::NodeStatus::LowZncc) => S::LowZncc,
        Some(wire::NodeStatus::Inconsistent) => S::Inconsistent,
        Some(wire::NodeStatus::NoGuess) => S::NoGuess,
        Some(wire::NodeStatus::OutsideRegion) => S::OutsideRegion,
        Some(wire::NodeStatus::OutsideImage) | None => S::OutsideImage,
    };
    let wire_nodes = nodes;
    let nodes: Vec<correlator::Node> = wire_nodes
        .iter()
        .map(|n| correlator::Node {
            x_px: f64::from(n.x_px),
            y_px: f64::from(n.y_px),
            u_px: f64::from(n.u_px),
            v_px: f64::from(n.v_px),
            exx: f64::from(n.exx),
            eyy: f64::from(n.eyy),
            exy: f64::from(n.exy),
            score: f64::from(n.score),
            iterations: n.iterations,
            status: status(n.status),
        })
        .collect();
    let gradients = wire_nodes
        .iter()
        .map(|n| {
            [
                [f64::from(n.du_dx), f64::from(n.du_dy)],
                [f64::from(n.dv_dx), f64::from(n.dv_dy)],
            ]
        })
        .collect();
    let (nx, ny) = (header.mesh_cols as usize, header.mesh_rows as usize);
    let (nx, ny) = if nx * ny == nodes.len() {
        (nx, ny)
    } else {
        (nodes.len(), 1)
    };
    correlator::Field {
        nx,
        ny,
        valid: nodes.iter().filter(|n| n.status == S::Ok).count(),
        nodes,
        gradients,
        u_mean_px: header.u_mean_px,
        v_mean_px: header.v_mean_px,
        ..correlator::Field::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The wire's node gradient reaches the field files' gradient columns.
    #[test]
    fn the_runs_fields_carry_mm_columns_and_the_pvd_lists_each_vts_with_its_time() {
        let dir = std::env::temp_dir().join(format!("dicstream_pvd_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let results = ResultsDir::at(&dir).unwrap();
        std::fs::create_dir_all(results.fields()).unwrap();
        let settings = RecorderSettings {
            fields_every: 10,
            vtk: true,
            truth: false,
            framing: producer::Framing {
                mm_per_px: 0.25,
                strip_mm_per_px: 0.12,
            },
            gauges: Vec::new(),
            control_gauge: correlator::ControlGauge::default(),
            scale: crate::field_scale::FieldScale::User(wire::scale::MmPerPx::new(0.5).unwrap()),
        };
        let mut recorder = Recorder::new(&results, settings, 0).unwrap();
        let nodes = [FieldNode {
            x_px: 10.0,
            u_px: 2.0,
            status: wire::NodeStatus::Ok as u32,
            ..FieldNode::default()
        }];
        for (frame_id, t_s) in [(10u64, 1.0f64), (20, 2.5)] {
            let header = FieldHeader {
                frame_id,
                mesh_cols: 1,
                mesh_rows: 1,
                rig_sample_id: wire::NO_RIG_SAMPLE,
                t_capture_ns: (t_s * 1e9) as u64,
                t_published_ns: (t_s * 1e9) as u64,
                ..FieldHeader::default()
            };
            recorder.on_field(&header, &nodes, header.t_published_ns);
        }
        assert!(recorder.write_error.is_none(), "{:?}", recorder.write_error);
        let csv = std::fs::read_to_string(results.fields().join("field_000020.csv")).unwrap();
        let mut lines = csv.lines();
        assert!(lines.next().unwrap().ends_with(",x_mm,y_mm,u_mm,v_mm"));
        assert!(lines
            .next()
            .unwrap()
            .ends_with(",5.000000,0.000000,1.0000000,0.0000000"));
        let pvd = std::fs::read_to_string(results.fields().join(PVD_FILE)).unwrap();
        assert!(pvd
            .contains("<DataSet timestep=\"1\" group=\"\" part=\"0\" file=\"field_000010.vts\"/>"));
        assert!(pvd.contains(
            "<DataSet timestep=\"2.5\" group=\"\" part=\"0\" file=\"field_000020.vts\"/>"
        ));
        assert!(results.fields().join("field_000020.vts").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn wire_gradient_reaches_the_field_csv() {
        let header = FieldHeader {
            mesh_cols: 2,
            mesh_rows: 1,
            ..FieldHeader::default()
        };
        let nodes = [
            FieldNode {
                x_px: 10.0,
                du_dx: 0.125,
                du_dy: -0.25,
                dv_dx: 0.5,
                dv_dy: 0.0625,
                status: wire::NodeStatus::Ok as u32,
                ..FieldNode::default()
            },
            FieldNode {
                x_px: 20.0,
                status: wire::NodeStatus::LowZncc as u32,
                ..FieldNode::default()
            },
        ];
        let field = to_correlator_field(&header, &nodes);
        assert_eq!(
            field.gradients,
            vec![[[0.125, -0.25], [0.5, 0.0625]], [[0.0; 2]; 2]]
        );
        let mut text = String::new();
        correlator::output::field_csv(&field, &mut text);
        let rows: Vec<&str> = text.lines().collect();
        assert!(rows[0].ends_with(",du_dx,du_dy,dv_dx,dv_dy"), "{}", rows[0]);
        assert!(
            rows[1].ends_with(",ok,0.1250000,-0.2500000,0.5000000,0.0625000"),
            "{}",
            rows[1]
        );
        assert!(rows[2].ends_with(",low_zncc,0.0000000,0.0000000,0.0000000,0.0000000"));
    }
}

/// The holds of a strain-controlled test as the rig's samples show them: strain control, then
/// held in displacement by an interlock (stale fields, too few nodes, a jump), then resumed.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct StrainHolds {
    /// Times strain control went to held.
    pub holds: u32,
    /// Times it went back from held to strain control.
    pub resumed: u32,
    /// Simulated time held after strain control first ran (s).
    pub held_s: f64,
    #[serde(skip)]
    last: Option<(wire::RigControl, f64)>,
    #[serde(skip)]
    strain_ran: bool,
}

impl StrainHolds {
    fn on_rig(&mut self, state: &RigState) {
        use wire::RigControl::{Held, Strain};
        let control = state.control();
        if let Some((last, t_s)) = self.last {
            match (last, control) {
                (Strain, Held) => self.holds += 1,
                // After a hold (not the wait for a first usable field).
                (Held, Strain) if self.holds > 0 => self.resumed += 1,
                _ => {}
            }
            if last == Held && self.strain_ran {
                self.held_s += (state.t_sim_s - t_s).max(0.0);
            }
        }
        self.strain_ran |= control == Strain;
        self.last = Some((control, state.t_sim_s));
    }
}

#[cfg(test)]
mod strain_hold_tests {
    use super::*;

    #[test]
    fn holds_and_resumptions_are_counted_from_the_rig_samples() {
        let mut holds = StrainHolds::default();
        // Waiting for a first field (held at rest, not counted), strain, held 1.5 s, strain.
        for (k, control) in [2, 2, 1, 1, 2, 2, 2, 2, 1, 1].into_iter().enumerate() {
            holds.on_rig(&RigState {
                control_mode: control,
                t_sim_s: 0.5 * k as f64,
                ..RigState::default()
            });
        }
        assert_eq!((holds.holds, holds.resumed, holds.held_s), (1, 1, 2.0));
    }
}
