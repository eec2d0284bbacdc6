//! What the dashboard knows of an instance (pure: fed with the samples of the four services,
//! no IPC), and the snapshot it sends to every viewer. Everything kept is bounded: the latest
//! frame header, field and report, histories that halve their resolution when full, and a
//! thumbnail encoded at most every `image_every_ns`. A snapshot is one JSON object of bounded
//! size (the field is sent decimated to at most `max_nodes_side`² nodes).

use crate::forces::ForceHistory;
use crate::image::{downsample, encode_png};
use crate::latency::LatencyStats;
use crate::map_ranges::SentStrains;
use crate::series::{significant, Decimated, Rate};
use crate::test_clock::TestClock;
use crate::user_gauges::FieldTime;
use material::InvariantFn;
use serde_json::{json, Value};
use wire::stats::IdGaps;
use wire::{FieldHeader, FieldNode, FrameHeader, IdentificationReport, NodeStatus, RigState};

/// Who serves the page: `dicstream run` (knows its processes) or `dicstream monitor`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Run,
    Monitor,
}

#[derive(Clone, Debug)]
pub struct Settings {
    pub instance: String,
    pub mode: Mode,
    /// Shortest time between two encoded images (ns): 250 ms, 4 images per second.
    pub image_every_ns: u64,
    pub max_image_side_px: usize,
    /// The field is sent with at most this many nodes on a side (every k-th node beyond).
    pub max_nodes_side: usize,
    /// Points kept per history (gauge strains, rig, stress-stretch curves).
    pub history_points: usize,
}

impl Settings {
    pub fn new(instance: &str, mode: Mode) -> Settings {
        Settings {
            instance: instance.to_string(),
            mode,
            image_every_ns: 250_000_000,
            max_image_side_px: crate::image::MAX_SIDE_PX,
            max_nodes_side: 64,
            history_points: 400,
        }
    }
}

/// Window of the rates shown (ns).
const RATE_WINDOW_NS: u64 = 3_000_000_000;
/// Names of `ActuatorState::limit_flags` bits (the rig's `LimitKind` order).
pub const LIMIT_NAMES: [&str; 5] = ["stroke", "force", "following_error", "rate", "invalid"];
/// `RigState::program_state` codes (the rig's `log::program_code`).
pub const PROGRAM_NAMES: [&str; 5] = ["idle", "running", "held", "stopped", "finished"];
/// `ActuatorState::mode` codes (the rig's `codes::MODE_*`).
pub const MODE_NAMES: [&str; 4] = [
    "displacement",
    "force",
    "centroid displacement",
    "centroid force",
];
const LOAD_CASES: [&str; 3] = ["none", "uniaxial", "equibiaxial"];

/// What the gauge history's time is: the test's (the rig's `t_sim_s`) or, without a rig,
/// the time since the dashboard started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GaugeClock {
    Test,
    Dashboard,
}

/// The thumbnail last encoded, as described to viewers (the PNG itself is served apart).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageInfo {
    pub version: u64,
    pub frame_id: u64,
    pub width_px: usize,
    pub height_px: usize,
    /// Full-resolution px per thumbnail px.
    pub factor: usize,
}

pub struct LiveState {
    settings: Settings,
    t0_ns: u64,
    frames_seen: u64,
    frame_ids: IdGaps,
    frame_rate: Rate,
    last_frame: Option<FrameHeader>,
    image: Option<ImageInfo>,
    last_image_ns: Option<u64>,
    image_error: Option<String>,
    fields_seen: u64,
    field_ids: IdGaps,
    field_rate: Rate,
    last_field: Option<FieldHeader>,
    nodes: Vec<FieldNode>,
    latency_field: LatencyStats,
    latency_identification: LatencyStats,
    /// t (s: the test's time, or since the dashboard started without a rig: `gauge_clock`),
    /// then exx, eyy, exy for each of the 4 measures.
    gauge: Decimated<13>,
    gauge_clock: GaugeClock,
    /// The rig samples' test time, for the fields.
    clock: TestClock,
    /// Each loaded actuator's force against test time and grip displacement.
    forces: ForceHistory,
    rig_seen: u64,
    rig_ids: IdGaps,
    rig_rate: Rate,
    last_rig: Option<RigState>,
    /// t_sim, stretch x, y, force X, Y (N).
    rig_history: Decimated<5>,
    /// Per load case (uniaxial, equibiaxial): stretch, nominal stress (MPa).
    curves: [Decimated<2>; 2],
    reports_seen: u64,
    last_report: Option<IdentificationReport>,
}

impl LiveState {
    pub fn new(settings: Settings, t0_ns: u64) -> LiveState {
        let n = settings.history_points;
        LiveState {
            settings,
            t0_ns,
            frames_seen: 0,
            frame_ids: IdGaps::default(),
            frame_rate: Rate::new(RATE_WINDOW_NS),
            last_frame: None,
            image: None,
            last_image_ns: None,
            image_error: None,
            fields_seen: 0,
            field_ids: IdGaps::default(),
            field_rate: Rate::new(RATE_WINDOW_NS),
            last_field: None,
            nodes: Vec::new(),
            latency_field: LatencyStats::default(),
            latency_identification: LatencyStats::default(),
            gauge: Decimated::new(n),
            gauge_clock: GaugeClock::Dashboard,
            clock: TestClock::default(),
            forces: ForceHistory::new(n),
            rig_seen: 0,
            rig_ids: IdGaps::default(),
            rig_rate: Rate::new(RATE_WINDOW_NS),
            last_rig: None,
            rig_history: Decimated::new(n),
            curves: [Decimated::new(n), Decimated::new(n)],
            reports_seen: 0,
            last_report: None,
        }
    }

    pub fn frames_seen(&self) -> u64 {
        self.frames_seen
    }

    /// Whether a frame received at `now_ns` should be encoded (the image rate cap).
    pub fn image_due(&self, now_ns: u64) -> bool {
        self.last_image_ns
            .is_none_or(|t| now_ns.saturating_sub(t) >= self.settings.image_every_ns)
    }

    /// A frame, looked at in place. With `encode` (the caller has viewers) and when the rate
    /// cap allows, returns the frame's thumbnail as PNG.
    pub fn on_frame(
        &mut self,
        header: &FrameHeader,
        pixels: &[u16],
        now_ns: u64,
        encode: bool,
    ) -> Option<Vec<u8>> {
        self.frames_seen += 1;
        self.frame_ids.observe(header.frame_id);
        self.last_frame = Some(*header);
        if !(encode && self.image_due(now_ns)) || header.validate(pixels.len()).is_err() {
            return None;
        }
        self.last_image_ns = Some(now_ns);
        let thumbnail = downsample(
            pixels,
            header.width_px as usize,
            header.height_px as usize,
            header.bit_depth,
            self.settings.max_image_side_px,
        )?;
        match encode_png(&thumbnail) {
            Ok(png) => {
                self.image = Some(ImageInfo {
                    version: self.image.map_or(1, |i| i.version + 1),
                    frame_id: header.frame_id,
                    width_px: thumbnail.width_px,
                    height_px: thumbnail.height_px,
                    factor: thumbnail.factor,
                });
                Some(png)
            }
            Err(e) => {
                self.image_error = Some(e);
                None
            }
        }
    }

    /// A field, looked at in place; returns its time on the charts' clock.
    pub fn on_field(&mut self, header: &FieldHeader, nodes: &[FieldNode]) -> FieldTime {
        self.fields_seen += 1;
        self.field_ids.observe(header.frame_id);
        self.latency_field
            .record_ns(header.t_capture_ns, header.t_published_ns);
        let (clock, t_s) = match self
            .clock
            .test_time_s(header.rig_sample_id, header.t_capture_ns)
        {
            Some(t_s) => (GaugeClock::Test, t_s),
            None => (
                GaugeClock::Dashboard,
                header.t_capture_ns.saturating_sub(self.t0_ns) as f64 / 1e9,
            ),
        };
        // One clock per chart: the first rig sample restarts the history on the test's.
        let restarted = clock != self.gauge_clock;
        if restarted {
            self.gauge.clear();
            self.gauge_clock = clock;
        }
        let mut row = [t_s; 13];
        for (m, g) in header.gauge.iter().enumerate() {
            row[1 + 3 * m] = g.exx;
            row[2 + 3 * m] = g.eyy;
            row[3 + 3 * m] = g.exy;
        }
        self.gauge.push(row);
        self.last_field = Some(*header);
        self.nodes.clear();
        if nodes.len() == header.node_count() {
            self.nodes.extend_from_slice(nodes);
        }
        FieldTime { t_s, restarted }
    }

    pub fn on_rig(&mut self, state: &RigState) {
        self.rig_seen += 1;
        self.rig_ids.observe(state.sample_id);
        self.clock
            .on_rig(state.sample_id, state.t_sim_s, state.t_published_ns);
        self.forces.push(state);
        let force_kn = |axis: usize| {
            0.5 * (state.actuators[2 * axis].force_kn + state.actuators[2 * axis + 1].force_kn)
        };
        self.rig_history.push([
            state.t_sim_s,
            state.specimen_stretch_x,
            state.specimen_stretch_y,
            1e3 * force_kn(0),
            1e3 * force_kn(1),
        ]);
        // Nominal stress along x: F / S0 = sigma / lambda, sigma = F / S (incompressible sheet,
        // uniaxial or equibiaxial: S = S0 / lambda).
        let case = state.load_case as usize;
        let (stretch, section) = (state.specimen_stretch_x, state.specimen_section_x_mm2);
        if (1..=2).contains(&case) && state.hydraulics_on == 1 && section > 0.0 && stretch > 0.0 {
            let nominal_mpa = 1e3 * force_kn(0) / section / stretch;
            if nominal_mpa.is_finite() {
                self.curves[case - 1].push([stretch, nominal_mpa]);
            }
        }
        self.last_rig = Some(*state);
    }

    /// The gauge route's reports (the field route's are in the run's `identification.json`;
    /// the dashboard does not draw them yet).
    pub fn on_report(&mut self, report: &IdentificationReport) {
        if report.route() != Some(wire::identification::ReportRoute::Gauge) {
            return;
        }
        self.reports_seen += 1;
        self.latency_identification
            .record_ns(report.t_capture_ns, report.t_published_ns);
        self.last_report = Some(*report);
    }

    /// The snapshot sent to every viewer. `processes` is what `dicstream run` knows of its
    /// children (`null` for a monitor).
    pub fn snapshot(&mut self, now_ns: u64, viewers: usize, processes: &Value) -> Value {
        self.frame_rate.mark(now_ns, self.frames_seen);
        self.field_rate.mark(now_ns, self.fields_seen);
        self.rig_rate.mark(now_ns, self.rig_seen);
        json!({
            "instance": self.settings.instance,
            "mode": match self.settings.mode { Mode::Run => "run", Mode::Monitor => "monitor" },
            "t_s": now_ns.saturating_sub(self.t0_ns) as f64 / 1e9,
            "test_time_s": self.last_rig.map(|r| r.t_sim_s),
            "viewers": viewers,
            "frames": self.frames_json(),
            "image": self.image.map(|i| json!({
                "version": i.version,
                "frame_id": i.frame_id,
                "width_px": i.width_px,
                "height_px": i.height_px,
                "factor": i.factor,
            })),
            "image_error": self.image_error,
            "field": self.field_json(),
            "correlator": {
                "fields_seen": self.fields_seen,
                "rate_hz": self.field_rate.per_s(),
                "restarts_seen": self.field_ids.restarts,
                "frames_skipped": self.last_field.map(|f| f.frames_dropped),
                "correlate_ms": self.last_field.map(|f| f.correlate_ns as f64 / 1e6),
                "latency_ms": self.latency_field.json(),
            },
            "gauge": self.gauge_json(),
            "rig": self.rig_json(),
            "forces": self.forces.json(),
            "stretch_states": self.stretch_states_json(),
            "identification": self.identification_json(),
            "processes": processes,
        })
    }

    fn frames_json(&self) -> Value {
        json!({
            "seen": self.frames_seen,
            "last_id": self.frame_ids.last,
            "rate_hz": self.frame_rate.per_s(),
            "missed_by_dashboard": self.frame_ids.lost,
            "camera_restarts_seen": self.frame_ids.restarts,
            "width_px": self.last_frame.map(|f| f.width_px),
            "height_px": self.last_frame.map(|f| f.height_px),
            "bit_depth": self.last_frame.map(|f| f.bit_depth),
        })
    }

    fn field_json(&self) -> Value {
        let Some(h) = &self.last_field else {
            return Value::Null;
        };
        let (cols, rows) = (h.mesh_cols as usize, h.mesh_rows as usize);
        let side = self.settings.max_nodes_side.max(1);
        let stride = cols.max(rows).div_ceil(side).max(1);
        let mut x = Vec::new();
        let (mut y, mut exx, mut eyy, mut exy, mut status) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut strains = Vec::new();
        let (mut sent_cols, mut sent_rows) = (0, 0);
        if self.nodes.len() == cols * rows {
            sent_cols = cols.div_ceil(stride);
            sent_rows = rows.div_ceil(stride);
            for r in (0..rows).step_by(stride) {
                for c in (0..cols).step_by(stride) {
                    let n = &self.nodes[r * cols + c];
                    // Where the node's material is in the current image.
                    let px = |v: f32| (f64::from(v) * 10.0).round() / 10.0;
                    x.push(px(n.x_px + n.u_px));
                    y.push(px(n.y_px + n.v_px));
                    let ok = n.status == NodeStatus::Ok as u32;
                    let e = [n.exx, n.eyy, n.exy].map(f64::from);
                    let strain = (ok && e.iter().all(|v| v.is_finite())).then_some(e);
                    strains.push(strain);
                    let value = |k: usize| strain.map(|e| significant(e[k], 5));
                    exx.push(value(0));
                    eyy.push(value(1));
                    exy.push(value(2));
                    status.push(n.status);
                }
            }
        }
        let measure = wire::StrainMeasure::from_code(h.strain_measure);
        let ranges = match measure {
            Some(measure) if !strains.is_empty() => crate::map_ranges::json(&SentStrains {
                strains: &strains,
                nx: sent_cols,
                ny: sent_rows,
                stride,
                measure,
            }),
            _ => Value::Null,
        };
        let status_counts: Vec<Value> = NodeStatus::ALL
            .iter()
            .map(|&s| {
                let count = self.nodes.iter().filter(|n| n.status == s as u32).count();
                json!({"status": s.name(), "code": s as u32, "count": count})
            })
            .collect();
        json!({
            "frame_id": h.frame_id,
            "reference_frame_id": h.reference_frame_id,
            "origin_frame_id": h.origin_frame_id,
            "measure": measure.map_or("?", |m| m.name()),
            "mesh_cols": cols,
            "mesh_rows": rows,
            "stride": stride,
            "step_px": h.step_px,
            "zoi_px": h.zoi_px,
            "valid_nodes": h.valid_nodes,
            "nodes": cols * rows,
            "status_counts": status_counts,
            "x": x, "y": y, "exx": exx, "eyy": eyy, "exy": exy, "status": status,
            "ranges": ranges,
        })
    }

    fn gauge_json(&self) -> Value {
        let mut measures = serde_json::Map::new();
        for m in wire::StrainMeasure::ALL {
            let i = m as usize;
            measures.insert(
                m.name().to_string(),
                json!({
                    "exx": self.gauge.column(1 + 3 * i),
                    "eyy": self.gauge.column(2 + 3 * i),
                    "exy": self.gauge.column(3 + 3 * i),
                }),
            );
        }
        let clock = match self.gauge_clock {
            GaugeClock::Test => "test",
            GaugeClock::Dashboard => "dashboard",
        };
        json!({"t_s": self.gauge.column(0), "clock": clock, "measures": measures})
    }

    /// The latest field's node states in the (λ1, λ2) plane (null before a field).
    fn stretch_states_json(&self) -> Value {
        let Some(h) = &self.last_field else {
            return Value::Null;
        };
        let measure = wire::StrainMeasure::from_code(h.strain_measure).unwrap_or_default();
        let mut states = crate::stretch_states::json(&self.nodes, measure);
        states["frame_id"] = json!(h.frame_id);
        states
    }

    fn rig_json(&self) -> Value {
        let Some(s) = &self.last_rig else {
            return Value::Null;
        };
        let actuators: Vec<Value> = s
            .actuators
            .iter()
            .zip(wire::rig::ACTUATOR_NAMES)
            .map(|(a, name)| {
                let limits: Vec<&str> = LIMIT_NAMES
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| a.limit_flags & (1 << k) != 0)
                    .map(|(_, n)| *n)
                    .collect();
                let force_control = matches!(a.mode, 1 | 3);
                json!({
                    "name": name,
                    "position_mm": a.position_mm,
                    "force_n": 1e3 * a.force_kn,
                    "command": a.command_mm * if force_control { 1e3 } else { 1.0 },
                    "error": a.following_error_mm * if force_control { 1e3 } else { 1.0 },
                    "unit": if force_control { "N" } else { "mm" },
                    "mode": MODE_NAMES.get(a.mode as usize).copied().unwrap_or("?"),
                    "limits": limits,
                })
            })
            .collect();
        let h = &self.rig_history;
        json!({
            "sample_id": s.sample_id,
            "samples_seen": self.rig_seen,
            "rate_hz": self.rig_rate.per_s(),
            "restarts_seen": self.rig_ids.restarts,
            "t_sim_s": s.t_sim_s,
            "program": PROGRAM_NAMES.get(s.program_state as usize).copied().unwrap_or("?"),
            "hydraulics_on": s.hydraulics_on == 1,
            "load_case": LOAD_CASES.get(s.load_case as usize).copied().unwrap_or("?"),
            "test_index": s.test_index,
            "stretch": [s.specimen_stretch_x, s.specimen_stretch_y],
            "rotation_deg": s.specimen_rotation_rad.to_degrees(),
            "centre_offset_mm": s.specimen_centre_offset_mm,
            "axis_centre_mm": s.axis_centre_mm,
            "actuators": actuators,
            "limits_tripped": s.actuators.iter().any(|a| a.limit_flags != 0),
            "control": s.control().name(),
            "strain": strain_view(s, self.last_field.as_ref()),
            "history": {
                "t_sim_s": h.column(0),
                "stretch_x": h.column(1),
                "stretch_y": h.column(2),
                "force_x_n": h.column(3),
                "force_y_n": h.column(4),
            },
        })
    }

    fn identification_json(&self) -> Value {
        let curves = |i: usize| json!({"stretch": self.curves[i].column(0), "nominal_mpa": self.curves[i].column(1)});
        let Some(r) = &self.last_report else {
            return json!({"reports": 0, "uniaxial": curves(0), "equibiaxial": curves(1)});
        };
        // A coefficient is shown only once its load case has data (f from the uniaxial
        // points, g from the equibiaxial ones): before, the fit leaves it free.
        let coefficients = |values: &[f64], sigmas: &[f64], count: u32, points: u32| {
            let n = (count as usize).min(values.len());
            (points > 0 && n > 0).then(|| {
                json!({
                    "values": &values[..n],
                    "sigma": sigmas[..n].iter().map(|s| s.is_finite().then_some(*s)).collect::<Vec<_>>(),
                })
            })
        };
        let a = coefficients(&r.a, &r.a_stderr, r.a_count, r.points[0]);
        let b = coefficients(&r.b, &r.b_stderr, r.b_count, r.points[1]);
        let law = (r.a_count > 0 && r.b_count > 0)
            .then(|| {
                material::InvariantLaw::exp_poly(
                    &r.a[..r.a_count as usize],
                    &r.b[..r.b_count as usize],
                )
                .ok()
            })
            .flatten();
        let fit = |i: usize| -> Value {
            let (Some(law), true) = (&law, r.points[i] > 0) else {
                return Value::Null;
            };
            let top = self.curves[i]
                .rows()
                .iter()
                .map(|p| p[0])
                .fold(1.0f64, f64::max);
            let stretch: Vec<f64> = (0..=40)
                .map(|k| 1.0 + (top - 1.0) * k as f64 / 40.0)
                .collect();
            let stress: Vec<f64> = stretch
                .iter()
                .map(|&l| match i {
                    0 => law.uniaxial_nominal_stress_mpa(l),
                    _ => law.equibiaxial_nominal_stress_mpa(l),
                })
                .collect();
            json!({"stretch": stretch, "nominal_mpa": stress})
        };
        let ranking: Vec<Value> = r
            .ranking
            .iter()
            .take((r.ranked_count as usize).min(r.ranking.len()))
            .map(|m| {
                json!({"name": wire::text::read_fixed(&m.name), "aic": m.aic, "rms_mpa": m.rms_mpa})
            })
            .collect();
        let (f_points, g_points) = self.route_points(r);
        let mut uniaxial = curves(0);
        uniaxial["fit"] = fit(0);
        let mut equibiaxial = curves(1);
        equibiaxial["fit"] = fit(1);
        json!({
            "reports": self.reports_seen,
            "frame_id": r.frame_id,
            "points": {"uniaxial": r.points[0], "equibiaxial": r.points[1], "pure_shear": r.points[2]},
            "f_coefficients": a,
            "g_coefficients": b,
            "rms_mpa": r.rms_mpa,
            "ranking": ranking,
            "latency_ms": self.latency_identification.json(),
            "uniaxial": uniaxial,
            "equibiaxial": equibiaxial,
            "f_points": f_points,
            "g_points": g_points,
        })
    }

    /// The route's experimental points (paper Figs. 8 and 14) from this run's stress-stretch
    /// points: f(I1) from the uniaxial ones by eq. 19 (with the identified g once the
    /// equibiaxial test has data, eq. 20 before), g(I2) from the equibiaxial ones by eq. 23
    /// with the identified f. Points nearer λ = 1 than the route's own threshold are left out,
    /// as the route does (their division by a vanishing term turns noise into any value).
    fn route_points(&self, r: &IdentificationReport) -> (Value, Value) {
        use identifier::data::{Curve, LoadCase};
        use identifier::route::{f_points, g_points, ROUTE_MIN_STRETCH};
        let curve = |i: usize, case: LoadCase| {
            let rows: Vec<[f64; 2]> = self.curves[i]
                .rows()
                .iter()
                .copied()
                .filter(|p| p[0] >= ROUTE_MIN_STRETCH && p[1].is_finite())
                .collect();
            Curve {
                case,
                stretch: rows.iter().map(|p| p[0]).collect(),
                nominal_stress_mpa: rows.iter().map(|p| p[1]).collect(),
                reference_rows_dropped: 0,
            }
        };
        let part = |values: &[f64], count: u32, points: u32| {
            let n = (count as usize).min(values.len());
            (points > 0 && n > 0).then(|| InvariantFn::ExpPoly(values[..n].to_vec()))
        };
        let (f, g) = (
            part(&r.a, r.a_count, r.points[0]),
            part(&r.b, r.b_count, r.points[1]),
        );
        let as_json = |points: Vec<(f64, f64)>| {
            let kept: Vec<(f64, f64)> = points.into_iter().filter(|p| p.1.is_finite()).collect();
            json!({
                "invariant": kept.iter().map(|p| p.0).collect::<Vec<_>>(),
                "value_mpa": kept.iter().map(|p| p.1).collect::<Vec<_>>(),
            })
        };
        let f_json = if r.points[0] > 0 {
            as_json(f_points(&curve(0, LoadCase::Uniaxial), g.as_ref()))
        } else {
            Value::Null
        };
        let g_json = match (&f, r.points[1] > 0) {
            (Some(f), true) => as_json(g_points(&curve(1, LoadCase::Equibiaxial), f)),
            _ => Value::Null,
        };
        (f_json, g_json)
    }
}

/// Target against measured under strain control (null otherwise): the rig's target log strains
/// (ln λx, ln λy), the newest field's gauge log strains (null before the first field) and
/// measured − target per axis. The field is newer than the target it answers by the field
/// latency, so the difference includes the lag of the loop, not only its error.
pub fn strain_view(rig: &RigState, field: Option<&FieldHeader>) -> Value {
    let Some(target) = rig.strain_target() else {
        return Value::Null;
    };
    let measured = field.map(|h| {
        let g = h.gauge_of(wire::StrainMeasure::Log);
        [g.exx, g.eyy]
    });
    json!({
        "target_log": target,
        "measured_log": measured,
        "error_log": measured.map(|m| [m[0] - target[0], m[1] - target[1]]),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(frame_id: u64, cols: u32, rows: u32) -> (FieldHeader, Vec<FieldNode>) {
        let header = FieldHeader {
            frame_id,
            mesh_cols: cols,
            mesh_rows: rows,
            t_capture_ns: 1_000_000_000,
            t_published_ns: 1_020_000_000,
            ..FieldHeader::default()
        };
        let nodes = (0..cols * rows)
            .map(|i| FieldNode {
                x_px: (i % cols) as f32 * 16.0,
                y_px: (i / cols) as f32 * 16.0,
                exx: 0.01,
                status: if i == 0 {
                    NodeStatus::LowZncc as u32
                } else {
                    0
                },
                ..FieldNode::default()
            })
            .collect();
        (header, nodes)
    }

    #[test]
    fn a_large_field_is_sent_decimated_with_its_refused_nodes_named() {
        let mut s = LiveState::new(Settings::new("t", Mode::Monitor), 0);
        let (h, nodes) = field(3, 200, 100);
        s.on_field(&h, &nodes);
        let snap = s.snapshot(2_000_000_000, 1, &Value::Null);
        let f = &snap["field"];
        assert_eq!(f["stride"], 4);
        assert_eq!(f["x"].as_array().unwrap().len(), 50 * 25);
        assert_eq!(f["exx"][0], Value::Null); // refused: no strain drawn
        assert!((f["exx"][1].as_f64().unwrap() - 0.01).abs() < 1e-6);
        assert_eq!(f["status"][0], NodeStatus::LowZncc as u32);
        assert_eq!(f["status_counts"][4]["count"], 1);
        // The map's range resolved here for each measure shown: a uniform field's range is
        // one value's (log strain 0.01 is Green-Lagrange (e^0.02 - 1) / 2).
        for (measure, exx) in [("log", 0.01), ("green", 0.5 * (0.02f64.exp() - 1.0))] {
            let auto = &f["ranges"][measure]["exx"]["auto"];
            let (lo, hi) = (auto["lo"].as_f64().unwrap(), auto["hi"].as_f64().unwrap());
            assert!(lo < exx && hi > exx && hi - lo < 1e-6, "{measure}: {auto}");
        }
        assert!(f["ranges"]["small"].is_null());
        assert!((snap["correlator"]["latency_ms"]["p50"].as_f64().unwrap() - 20.0).abs() < 0.1);
        // A snapshot stays small whatever the mesh.
        assert!(
            snap.to_string().len() < 200_000,
            "{}",
            snap.to_string().len()
        );
    }

    #[test]
    fn fields_are_charted_on_the_tests_time_with_forces_and_stretch_states() {
        let mut s = LiveState::new(Settings::new("t", Mode::Run), 0);
        // Before any rig sample: the dashboard's clock (1 s after it started).
        let (mut h, nodes) = field(1, 4, 4);
        h.strain_measure = wire::StrainMeasure::Log as u32;
        s.on_field(&h, &nodes);
        let snap = s.snapshot(2_000_000_000, 1, &Value::Null);
        assert_eq!(snap["gauge"]["clock"], "dashboard");
        assert_eq!(snap["gauge"]["t_s"][0], 1.0);
        assert_eq!(snap["test_time_s"], Value::Null);
        let mut rig = RigState {
            sample_id: 7,
            t_sim_s: 42.5,
            ..RigState::default()
        };
        rig.actuators[0].force_kn = 1.0;
        rig.actuators[1].force_kn = 1.0;
        s.on_rig(&rig);
        h.rig_sample_id = 7;
        s.on_field(&h, &nodes);
        let snap = s.snapshot(3_000_000_000, 1, &Value::Null);
        assert_eq!(snap["test_time_s"], 42.5);
        // The history restarted on the test's clock.
        assert_eq!(snap["gauge"]["clock"], "test");
        assert_eq!(snap["gauge"]["t_s"], json!([42.5]));
        assert_eq!(snap["forces"]["actuators"].as_array().unwrap().len(), 2);
        assert_eq!(snap["forces"]["t_sim_s"], json!([42.5]));
        // 15 of the 16 nodes are ok (exx 0.01 log: λ1 = e^0.01, λ2 = 1).
        let states = &snap["stretch_states"];
        assert_eq!(states["valid"], 15);
        assert!((states["l1"][0].as_f64().unwrap() - 0.01f64.exp()).abs() < 1e-4);
        assert_eq!(states["l2"][0], 1.0);
    }

    #[test]
    fn images_are_encoded_only_for_viewers_and_at_the_capped_rate() {
        let mut s = LiveState::new(Settings::new("t", Mode::Run), 0);
        let header = FrameHeader {
            width_px: 64,
            height_px: 64,
            ..FrameHeader::default()
        };
        let pixels = vec![30_000u16; 64 * 64];
        assert!(s.on_frame(&header, &pixels, 0, false).is_none());
        assert!(s.on_frame(&header, &pixels, 1, true).is_some());
        assert!(s.on_frame(&header, &pixels, 100_000_000, true).is_none());
        assert!(s.on_frame(&header, &pixels, 300_000_000, true).is_some());
        let snap = s.snapshot(400_000_000, 1, &Value::Null);
        assert_eq!(snap["image"]["version"], 2);
        assert_eq!(snap["frames"]["seen"], 4);
    }

    #[test]
    fn coefficients_wait_for_their_load_case() {
        let mut s = LiveState::new(Settings::new("t", Mode::Run), 0);
        let mut r = IdentificationReport {
            points: [12, 0, 0],
            a_count: 3,
            b_count: 3,
            ..IdentificationReport::default()
        };
        r.a[..3].copy_from_slice(&[-1.27, -2.52e-2, 1.40e-3]);
        r.b[..3].copy_from_slice(&[-1.0e7, 3.0, 7.0e4]);
        s.on_report(&r);
        let snap = s.snapshot(1, 0, &Value::Null);
        let id = &snap["identification"];
        assert_eq!(id["f_coefficients"]["values"][0], -1.27);
        assert_eq!(id["g_coefficients"], Value::Null);
        r.points[1] = 4;
        s.on_report(&r);
        let snap = s.snapshot(2, 0, &Value::Null);
        assert_eq!(snap["identification"]["g_coefficients"]["values"][2], 7.0e4);
    }

    #[test]
    fn strain_control_shows_target_against_measured() {
        let mut rig = RigState {
            control_mode: wire::RigControl::Strain as u32,
            target_log_exx: 0.2,
            target_log_eyy: 0.1,
            ..RigState::default()
        };
        let mut header = FieldHeader::default();
        header.gauge[wire::StrainMeasure::Log as usize].exx = 0.19;
        header.gauge[wire::StrainMeasure::Log as usize].eyy = 0.105;
        let view = strain_view(&rig, Some(&header));
        assert_eq!(view["target_log"], json!([0.2, 0.1]));
        assert_eq!(view["measured_log"], json!([0.19, 0.105]));
        let error = &view["error_log"];
        assert!((error[0].as_f64().unwrap() + 0.01).abs() < 1e-12);
        assert!((error[1].as_f64().unwrap() - 0.005).abs() < 1e-12);
        // Before any field: the target alone.
        let alone = strain_view(&rig, None);
        assert!(alone["measured_log"].is_null() && alone["error_log"].is_null());
        // Displacement control: nothing to compare.
        rig.control_mode = wire::RigControl::Displacement as u32;
        assert!(strain_view(&rig, Some(&header)).is_null());
        // Through the snapshot, with the mode named.
        rig.control_mode = wire::RigControl::Held as u32;
        let mut s = LiveState::new(Settings::new("t", Mode::Run), 0);
        s.on_field(&header, &[]);
        s.on_rig(&rig);
        let snap = s.snapshot(1, 0, &Value::Null);
        assert_eq!(snap["rig"]["control"], "held");
        assert_eq!(snap["rig"]["strain"]["measured_log"], json!([0.19, 0.105]));
    }

    #[test]
    fn rig_limits_program_and_the_stress_curve() {
        let mut s = LiveState::new(Settings::new("t", Mode::Run), 0);
        let mut state = RigState {
            program_state: 1,
            load_case: 1,
            hydraulics_on: 1,
            specimen_stretch_x: 2.0,
            specimen_section_x_mm2: 10.0,
            ..RigState::default()
        };
        state.actuators[0].force_kn = 0.1;
        state.actuators[1].force_kn = 0.1;
        state.actuators[3].limit_flags = 1 << 1;
        s.on_rig(&state);
        let snap = s.snapshot(1, 0, &Value::Null);
        let rig = &snap["rig"];
        assert_eq!(rig["program"], "running");
        assert_eq!(rig["actuators"][3]["limits"][0], "force");
        assert_eq!(rig["limits_tripped"], true);
        // 100 N on 10 mm² at stretch 2: 10 MPa Cauchy, 5 MPa nominal.
        let p = snap["identification"]["uniaxial"]["nominal_mpa"][0]
            .as_f64()
            .unwrap();
        assert!((p - 5.0).abs() < 1e-5, "{p}");
    }
    /// Stress points of the true law give the route's points on the true f and g: f(I1) by
    /// eq. 19 with the identified g, g(I2) by eq. 23 with the identified f; none below λ 1.02.
    #[test]
    fn the_route_points_lie_on_the_law_that_made_the_stresses() {
        let law = material::InvariantLaw::smactane();
        let mut s = LiveState::new(Settings::new("t", Mode::Run), 0);
        let section_mm2 = 10.0;
        let uniaxial = |l: f64| law.uniaxial_nominal_stress_mpa(l);
        let equibiaxial = |l: f64| law.equibiaxial_nominal_stress_mpa(l);
        let cases: [(u32, &dyn Fn(f64) -> f64); 2] = [(1, &uniaxial), (2, &equibiaxial)];
        for (case, nominal) in cases {
            for k in 0..=30 {
                let stretch = 1.0 + 1.5 * k as f64 / 30.0;
                let mut state = RigState {
                    load_case: case,
                    hydraulics_on: 1,
                    specimen_stretch_x: stretch,
                    specimen_section_x_mm2: section_mm2,
                    ..RigState::default()
                };
                let force_kn = nominal(stretch) * section_mm2 * stretch / 1e3;
                state.actuators[0].force_kn = force_kn;
                state.actuators[1].force_kn = force_kn;
                s.on_rig(&state);
            }
        }
        let (a, b) = (law.f.coefficients(), law.g.coefficients());
        let mut r = IdentificationReport {
            points: [31, 31, 0],
            a_count: a.len() as u32,
            b_count: b.len() as u32,
            ..IdentificationReport::default()
        };
        r.a[..a.len()].copy_from_slice(a);
        r.b[..b.len()].copy_from_slice(b);
        s.on_report(&r);
        let id = &s.snapshot(1, 0, &Value::Null)["identification"];
        for (key, function) in [("f_points", &law.f), ("g_points", &law.g)] {
            let invariants = id[key]["invariant"].as_array().unwrap();
            let values = id[key]["value_mpa"].as_array().unwrap();
            // λ = 1 is below the route's threshold (1.02); the 30 others remain.
            assert_eq!(invariants.len(), 30, "{key}");
            for (i, v) in invariants.iter().zip(values) {
                let (i, v) = (i.as_f64().unwrap(), v.as_f64().unwrap());
                let truth = function.value_mpa(i);
                assert!(
                    (v - truth).abs() < 1e-9 * truth.abs().max(1.0),
                    "{key} at {i}: {v} vs {truth}"
                );
            }
        }
    }
}
