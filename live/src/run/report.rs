//! What a run reports at its end: the final `summary.json` (the figures `dicstream run` prints
//! come from it too).

use super::{start::RunStart, Ending};
use crate::acceptance::Acceptance;
use crate::config::{CameraSource, RigSource};
use crate::latency::Percentiles;
use serde::Serialize;
use std::path::PathBuf;

/// The correlator's error against the ground truth, node by node.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct TruthReport {
    /// `homogeneous motion` (the sheet's one stretch), or `finite-element field` (the
    /// specimen as a structure: each node against the solved field it shows).
    pub compared_with: &'static str,
    pub fields_compared: u64,
    /// Fields of a finite-element specimen whose solves were not received: no truth.
    pub fields_without_truth: u64,
    /// The specimen's solved states received (`specimen` service).
    pub specimen_solves: u64,
    /// Valid nodes compared, over all fields, and their error percentiles (px).
    pub nodes_compared: u64,
    pub node_error_p50_px: Option<f64>,
    pub node_error_p99_px: Option<f64>,
    /// The same per test kind ("uniaxial": the strip's frames, "equibiaxial": the
    /// cruciform's, "no test": between tests; `status::load_case_name`), those with nodes
    /// compared only.
    pub node_error_by_load_case: Vec<NodeErrorReport>,
}

/// The node errors of one load case's fields.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct NodeErrorReport {
    pub load_case: &'static str,
    pub nodes_compared: u64,
    pub node_error_p50_px: Option<f64>,
    pub node_error_p99_px: Option<f64>,
}

impl TruthReport {
    pub fn of(recorder: &crate::recorder::Recorder) -> Option<TruthReport> {
        let solves = recorder.specimen_solves_received();
        (recorder.fields_compared + recorder.fields_without_truth > 0).then(|| TruthReport {
            compared_with: match solves {
                0 => "homogeneous motion",
                _ => "finite-element field",
            },
            fields_compared: recorder.fields_compared,
            fields_without_truth: recorder.fields_without_truth,
            specimen_solves: solves,
            nodes_compared: recorder.node_errors.count(),
            node_error_p50_px: recorder.node_errors.quantile_px(0.5),
            node_error_p99_px: recorder.node_errors.quantile_px(0.99),
            node_error_by_load_case: (0u32..)
                .zip(&recorder.node_errors_by_case)
                .filter(|(_, e)| e.count() > 0)
                .map(|(code, e)| NodeErrorReport {
                    load_case: crate::status::load_case_name(code),
                    nodes_compared: e.count(),
                    node_error_p50_px: e.quantile_px(0.5),
                    node_error_p99_px: e.quantile_px(0.99),
                })
                .collect(),
        })
    }
}

/// A strain-controlled test's target against the largest stretch its control gauge reached
/// (the rig's log says why a test stopped short: the stroke, the settling limit, an interlock).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct StrainTargetReport {
    pub target_stretch: f64,
    pub reached_stretch: f64,
    /// Within the tolerance the rig ends a program by ([`rig::strain::settle`]).
    pub reached: bool,
    /// The holds by an interlock (stale fields: a correlator or a link to it gone quiet) and
    /// the resumptions after them.
    pub holds: crate::recorder::StrainHolds,
}

impl StrainTargetReport {
    /// None without a strain-controlled test.
    pub fn of(
        config: &crate::config::RunConfig,
        recorder: &crate::recorder::Recorder,
    ) -> Option<StrainTargetReport> {
        let test = config.strain_test().ok().flatten()?;
        // A strain test runs alone in its campaign: its load case's largest stretch.
        let reached_stretch = recorder.max_stretch.iter().copied().fold(1.0, f64::max);
        let target_log = test.stretch.ln();
        Some(StrainTargetReport {
            target_stretch: test.stretch,
            reached_stretch,
            reached: (reached_stretch.ln() - target_log).abs()
                <= rig::strain::settle::tolerance_log(target_log),
            holds: recorder.strain_holds,
        })
    }

    /// `strain control aimed at λ 1.300 in its gauge and reached λ 1.284: SHORT (…)`.
    pub fn line(&self) -> String {
        let verdict = match self.reached {
            true => "reached".to_string(),
            false => "SHORT of it (logs/rig.log says why)".to_string(),
        };
        let holds = match self.holds.holds {
            0 => String::new(),
            n => format!(
                "; HELD {n} time(s) by an interlock ({:.1} s of the rig's time in all), resumed \
                 {} time(s) (logs/rig.log says why)",
                self.holds.held_s, self.holds.resumed
            ),
        };
        format!(
            "strain control aimed at λ {:.3} in its gauge; the largest it measured was λ {:.3}: \
             {verdict}{holds}",
            self.target_stretch, self.reached_stretch
        )
    }
}

/// What the run did, also written as `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    pub results: PathBuf,
    pub instance: String,
    pub ending: Ending,
    /// Start time, pid, configuration, the earlier run set aside (also in the summary written
    /// at the start, `ending` = `running`).
    #[serde(flatten)]
    pub start: RunStart,
    pub failure: Option<String>,
    pub wall_s: f64,
    pub frames_captured: u64,
    pub fields: u64,
    /// Frames captured that have no field: skipped by a correlator that fell behind, lost while
    /// it was dead or stopped, or still on their way when the run stopped.
    pub frames_not_correlated: u64,
    /// Of those, the frames lost while a process was dead or stale (not skipped by a running
    /// correlator): a fault cost them.
    pub frames_lost_to_faults: u64,
    /// Every death and stale process of the run, as noticed.
    pub faults: Vec<String>,
    pub identification_reports: u64,
    pub restarts: Vec<String>,
    /// CPU seconds used per process (user + system, all threads), and as a share of one core
    /// over the run's wall time (1.0 = one core busy all along).
    pub cpu_s: std::collections::BTreeMap<String, f64>,
    pub cpu_cores: std::collections::BTreeMap<String, f64>,
    pub latency_field_ms: Percentiles,
    /// Where the field latency goes: waiting for the correlator, correlating, delivering.
    pub latency_field_parts_ms: crate::latency::FieldLatencyPartsMs,
    pub latency_identification_ms: Percentiles,
    /// Mean over frames of the mean node displacement error against the truth (px), and the
    /// worst node error of the run.
    pub displacement_error_mean_px: Option<f64>,
    /// Node by node against the ground truth (simulated cameras): what the truth was and the
    /// nodes' error percentiles.
    pub truth: Option<TruthReport>,
    /// The gauge route's law against the truth: the run's verdict on the homogeneous sheet;
    /// on a structure informative only (its gauge's force / section is no stress there).
    pub acceptance: Option<Acceptance>,
    /// The field route's law against the truth (`[identifier] route` field or both, with a
    /// ground truth): the run's verdict on a structure (`field_acceptance_decides`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub field_acceptance: Option<crate::field_acceptance::FieldAcceptance>,
    pub field_acceptance_decides: bool,
    /// Why there is no acceptance although a law was identified: a real camera or machine
    /// has no ground truth to compare with.
    pub acceptance_skipped: Option<String>,
    /// Where frames and rig samples came from ([camera] source, [rig] source).
    pub camera_source: CameraSource,
    pub rig_source: RigSource,
    /// With `[rig] source = "csv-follow"`: the machine CSV's rows read, malformed lines
    /// skipped and restarts (truncations, rotations), as the follower kept them in
    /// `machine_csv.json`.
    pub machine_csv: Option<rig::csv_follow::FollowCounters>,
    /// The fields' scale, mm per px, and where it came from.
    pub scale: crate::field_scale::ScaleReport,
    /// What `strain_map.png` shows.
    pub strain_map: Option<StrainMapInfo>,
    /// A strain-controlled test's target and what its gauge reached.
    pub strain_target: Option<StrainTargetReport>,
    /// The link to the other host the run started (`[link] start_with_run`): its counts and
    /// what it lost.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub link: Option<super::LinkReport>,
    /// Files of the instance left once every process had stopped (named, then removed).
    pub leftover_shm_files: usize,
    /// The exit code of `dicstream run` (see [`super::exit_code`]).
    pub exit_code: u8,
}

/// The field drawn in `strain_map.png` (the most strained field of the last test) and its
/// colour scale (the map, and the exx values at the colour bar's ends).
#[derive(Clone, Debug, Serialize)]
pub struct StrainMapInfo {
    pub frame_id: u64,
    pub origin_frame_id: u64,
    pub measure: &'static str,
    pub exx_colours: wire::colour_map::ColourScale,
}
