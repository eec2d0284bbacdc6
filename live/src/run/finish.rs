//! The end of a stopped run: its files written ([`super::outputs`]), the identified law
//! judged ([`super::judge`]), the frames counted, the verdict given ([`super::verdict`]), and
//! `summary.json` written atomically in place of the `running` one.

use super::stop::Stopped;
use super::verdict::{verdict, Facts};
use super::{outputs, read_back, RunReport};
use crate::recorder::Recorder;
use crate::results::ResultsDir;
use std::collections::BTreeMap;

/// The frames of a run as the summary counts them.
struct FrameCounts {
    captured: u64,
    /// Captured without a field: skipped, lost, or still on their way at the stop.
    not_correlated: u64,
    /// Of those, lost while a process was dead or stale (not skipped by a running
    /// correlator).
    lost_to_faults: u64,
}

impl FrameCounts {
    fn of(recorder: &Recorder, faults: &[String]) -> FrameCounts {
        let captured = recorder.last_frame_id.map_or(0, |id| id + 1);
        let not_correlated = captured.saturating_sub(recorder.fields_seen);
        // Frames no correlator skipped yet none measured: lost while one was dead or stale.
        let lost_to_faults = match faults.is_empty() {
            true => 0,
            false => not_correlated.saturating_sub(recorder.frames_dropped_by_correlators()),
        };
        FrameCounts {
            captured,
            not_correlated,
            lost_to_faults,
        }
    }
}

impl Stopped<'_> {
    /// Writes the run's results and its summary; the report of the run.
    pub(super) fn finish(self) -> anyhow::Result<RunReport> {
        let config = &self.options.config;
        let results = &self.prepared.results;
        let recorder = &self.recorder;
        let mut outputs = outputs::write(config, results, recorder);
        let judged = super::judge::judge(config, recorder, &results.identification_json());
        outputs::field_route_figures(config, results, judged.field.as_ref(), &mut outputs.notes);
        let displacement_error_mean_px = read_back::mean_displacement_error(&results.frames_csv());
        let machine_csv = read_back::machine_csv_counts(config, results);
        let wall_s = self.started.elapsed().as_secs_f64();
        let frames = FrameCounts::of(recorder, &self.incidents.faults);
        let link = super::LinkReport::of(config, results);
        let verdict = verdict(Facts {
            ending: self.ending,
            failure: self.failure,
            acceptance: judged.acceptance.as_ref(),
            acceptance_skipped: judged.skipped.is_some(),
            field_acceptance: judged.field_decides.then_some(judged.field.as_ref()),
            frames_lost_to_faults: frames.lost_to_faults,
            link: link.as_ref(),
            campaign_halted: self.incidents.campaign_halted.as_deref(),
            signal: self.signal,
            faults: &self.incidents.faults,
            killed_at_stop: &self.killed_at_stop,
            unwritten: &outputs.notes,
        });
        let report = RunReport {
            results: results.root.clone(),
            instance: self.prepared.name,
            ending: verdict.ending,
            start: self.prepared.start,
            failure: verdict.failure,
            wall_s,
            frames_captured: frames.captured,
            fields: recorder.fields_seen,
            frames_not_correlated: frames.not_correlated,
            frames_lost_to_faults: frames.lost_to_faults,
            faults: self.incidents.faults,
            identification_reports: recorder.latency_identification.count(),
            restarts: self.incidents.restarts,
            cpu_cores: cpu_cores(&self.cpu_s, wall_s),
            cpu_s: self.cpu_s,
            latency_field_ms: recorder.latency_field.percentiles(),
            latency_field_parts_ms: recorder.latency_field_parts.percentiles(),
            latency_identification_ms: recorder.latency_identification.percentiles(),
            displacement_error_mean_px,
            truth: super::report::TruthReport::of(recorder),
            acceptance: judged.acceptance,
            field_acceptance: judged.field,
            field_acceptance_decides: judged.field_decides,
            acceptance_skipped: judged.skipped,
            camera_source: config.camera.source,
            rig_source: config.rig.source,
            machine_csv,
            scale: crate::field_scale::ScaleReport::of(config),
            strain_map: outputs.strain_map,
            strain_target: super::report::StrainTargetReport::of(config, recorder),
            link,
            leftover_shm_files: self.leftover_shm_files,
            exit_code: verdict.exit_code,
        };
        write_summary(results, &report, &outputs.notes)?;
        Ok(report)
    }
}

/// CPU seconds as a share of one core over the run's wall time.
fn cpu_cores(cpu_s: &BTreeMap<String, f64>, wall_s: f64) -> BTreeMap<String, f64> {
    cpu_s
        .iter()
        .map(|(name, s)| (name.clone(), s / wall_s.max(1e-9)))
        .collect()
}

/// `summary.json`: the report, with the results files that could not be written (also said
/// on stderr) as `notes`.
fn write_summary(results: &ResultsDir, report: &RunReport, notes: &[String]) -> anyhow::Result<()> {
    let mut json = serde_json::to_value(report)?;
    if !notes.is_empty() {
        json["notes"] = serde_json::json!(notes);
        for note in notes {
            eprintln!("run: {note}");
        }
    }
    wire::files::write_atomic(
        &results.summary_json(),
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    Ok(())
}
