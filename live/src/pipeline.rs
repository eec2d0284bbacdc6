//! `dicstream bench pipeline`: the live bench sized for a measurement. Rig, camera,
//! correlator and identifier run as processes sharing the machine's cores, the camera
//! following a uniaxial test that lasts the requested time; the figures are the per-frame
//! latency from capture to field published and to identification published, the sustained
//! rate, the frames the correlator never measured (`pipeline/gaps.rs`: where and why), what the
//! reference renewals cost the fields around them (`pipeline/renewals.rs`), and the
//! CPU each process used, and what the simulated camera costs filming the finite-element
//! cruciform of a default run (`pipeline/camera_cost.rs`). With
//! `--fps max` trials at increasing rates find the highest rate without a dropped frame.

pub mod camera_cost;
mod gaps;
mod renewals;

pub use camera_cost::CameraCost;
pub use gaps::FrameGaps;
pub use renewals::{FieldCostMs, RenewalCosts};

use crate::config::{RunConfig, TestSection};
use crate::latency::{FieldLatencyPartsMs, Percentiles};
use crate::run::{run, Ending, RunOptions, RunReport};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What to measure.
#[derive(Clone, Debug)]
pub struct PipelineSettings {
    pub width_px: u32,
    pub height_px: u32,
    pub method: correlator::settings::Method,
    pub zoi_px: usize,
    pub step_px: usize,
    pub correlator_threads: usize,
    /// Frames per second; None: search the highest rate without drops.
    pub fps: Option<f64>,
    /// Length of the measured stream (s of wall time), per trial.
    pub seconds: f64,
    /// Where the trials write their results folders.
    pub results_dir: PathBuf,
    pub exe: PathBuf,
}

/// One trial's figures (the JSON of `--json`).
#[derive(Clone, Debug, Serialize)]
pub struct PipelineResult {
    pub fps_requested: f64,
    pub fps_sustained: f64,
    pub frames: u64,
    pub dropped: u64,
    pub latency_ms: BTreeMap<String, Percentiles>,
    /// Where the field latency goes per frame: waiting for the correlator (queueing
    /// included), correlating, delivering to the run's monitor.
    pub latency_field_parts_ms: FieldLatencyPartsMs,
    pub cpu_cores: BTreeMap<String, f64>,
    /// The frames not correlated: where the ids go missing and why.
    pub frame_gaps: FrameGaps,
    /// What the reference renewals cost the fields around them.
    pub renewal_costs: RenewalCosts,
    pub results: PathBuf,
    /// The simulated camera filming the finite-element cruciform (the trials film the
    /// homogeneous sheet): measured once, after the trials.
    pub camera_on_cruciform: Option<CameraCost>,
}

impl PipelineResult {
    /// The field latency's p99 the work allows: the correlator's own p99 per frame plus one
    /// frame period (a frame that arrives while the previous one is correlated waits at most
    /// that), ms.
    pub fn field_p99_budget_ms(&self) -> f64 {
        self.latency_field_parts_ms.correlating.p99 + 1e3 / self.fps_requested
    }
}

/// Rates tried by the search: doubling from here, then bisecting.
const SEARCH_START_FPS: f64 = 4.0;
const SEARCH_MAX_FPS: f64 = 128.0;
const BISECTIONS: usize = 3;

/// The run configuration of a trial: a uniaxial test to λ 2 lasting about `seconds`.
pub fn trial_config(settings: &PipelineSettings, fps: f64, results_dir: &Path) -> RunConfig {
    let mut config = RunConfig::default();
    config.run.results_dir = results_dir.to_path_buf();
    config.run.restart = false;
    config.run.fields_every = u32::MAX;
    config.camera.width_px = settings.width_px;
    config.camera.height_px = settings.height_px;
    config.camera.fps = fps;
    // The homogeneous sheet at the scale the bench always had: it measures the pipeline's
    // rate, comparable from commit to commit, not a specimen's mechanics.
    config.specimen.model = rig::SpecimenModel::Homogeneous;
    config.camera.mm_per_px = 0.015;
    config.correlator.method = settings.method;
    config.correlator.zoi_px = settings.zoi_px;
    config.correlator.step_px = settings.step_px;
    config.correlator.threads = settings.correlator_threads;
    // Hold 1 s, ramp, hold 1 s, unload at 5x, hold 0.5 s (rig::campaign).
    let ramp_s = ((settings.seconds - 2.5) / 1.2).max(1.0);
    config.rig.tests = vec![TestSection::new(
        rig::strain::StrainKind::Uniaxial,
        2.0,
        1.0 / ramp_s,
    )];
    config
}

fn sustained_fps(frames_csv: &Path) -> f64 {
    let Ok(text) = std::fs::read_to_string(frames_csv) else {
        return 0.0;
    };
    let mut lines = text.lines();
    let Some(column) = lines
        .next()
        .and_then(|h| h.split(',').position(|c| c == "t_capture_s"))
    else {
        return 0.0;
    };
    let times: Vec<f64> = lines
        .filter_map(|l| l.split(',').nth(column)?.parse().ok())
        .collect();
    match (times.first(), times.last()) {
        (Some(first), Some(last)) if times.len() > 1 && last > first => {
            (times.len() - 1) as f64 / (last - first)
        }
        _ => 0.0,
    }
}

fn result_of(report: &RunReport, fps: f64) -> PipelineResult {
    let mut latency_ms = BTreeMap::new();
    latency_ms.insert("field".to_string(), report.latency_field_ms);
    latency_ms.insert(
        "identification".to_string(),
        report.latency_identification_ms,
    );
    PipelineResult {
        fps_requested: fps,
        fps_sustained: sustained_fps(&report.results.join("frames.csv")),
        frames: report.frames_captured,
        dropped: report.frames_captured.saturating_sub(report.fields),
        latency_ms,
        latency_field_parts_ms: report.latency_field_parts_ms,
        cpu_cores: report.cpu_cores.clone(),
        frame_gaps: FrameGaps::of_results(&report.results),
        renewal_costs: RenewalCosts::of_frames_csv(
            &std::fs::read_to_string(report.results.join("frames.csv")).unwrap_or_default(),
        ),
        results: report.results.clone(),
        camera_on_cruciform: None,
    }
}

/// One trial at `fps`.
pub fn trial(settings: &PipelineSettings, fps: f64) -> anyhow::Result<PipelineResult> {
    let config = trial_config(settings, fps, &settings.results_dir);
    config.validate()?;
    let report = run(RunOptions {
        config,
        exe: settings.exe.clone(),
        instance: None,
        results: None,
        status: false,
        verbose: false,
    })?;
    if report.ending != Ending::Completed {
        anyhow::bail!(
            "the trial at {fps} frames/s did not complete: {}",
            report.failure.as_deref().unwrap_or("interrupted")
        );
    }
    Ok(result_of(&report, fps))
}

/// Frames the camera films the cruciform for its cost.
const CAMERA_COST_FRAMES: usize = 30;

/// The requested rate, or the search for the highest rate without drops (`progress` sees
/// each trial as it ends); then the camera's cost on the cruciform at the trials' frame size.
pub fn measure(
    settings: &PipelineSettings,
    progress: impl FnMut(&PipelineResult),
) -> anyhow::Result<PipelineResult> {
    let mut result = trials(settings, progress)?;
    result.camera_on_cruciform = Some(camera_cost::on_cruciform(
        settings.width_px,
        settings.height_px,
        CAMERA_COST_FRAMES,
    )?);
    Ok(result)
}

fn trials(
    settings: &PipelineSettings,
    mut progress: impl FnMut(&PipelineResult),
) -> anyhow::Result<PipelineResult> {
    if let Some(fps) = settings.fps {
        let result = trial(settings, fps)?;
        progress(&result);
        return Ok(result);
    }
    let mut best: Option<PipelineResult> = None;
    let mut fps = SEARCH_START_FPS;
    let mut failing: Option<f64> = None;
    while fps <= SEARCH_MAX_FPS {
        let result = trial(settings, fps)?;
        progress(&result);
        if result.dropped == 0 {
            best = Some(result);
            fps *= 2.0;
        } else {
            failing = Some(fps);
            break;
        }
    }
    if let Some(mut high) = failing {
        let mut low = best.as_ref().map_or(1.0, |b| b.fps_requested);
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (low + high);
            let result = trial(settings, mid)?;
            progress(&result);
            if result.dropped == 0 {
                low = mid;
                best = Some(result);
            } else {
                high = mid;
            }
        }
    }
    best.ok_or_else(|| anyhow::anyhow!("frames were dropped even at {SEARCH_START_FPS} frames/s"))
}
