//! `dicstream producer`: the camera process. Publishes `frames` (zero-copy `[u16]` slices behind
//! a `FrameHeader`) from a simulated scenario, a replayed image folder, or the rig state
//! (`--follow-rig`), paced to `--fps`, or the images of a watched folder as they become
//! complete (`--watch`, `producer_watch.rs`), or a real GenICam camera (`--camera`,
//! `producer_genicam.rs`, feature `genicam`). Says "ready" on stderr once the publisher exists
//! and prints one final line on stdout (also after SIGINT/SIGTERM, then exits 0).

use super::sim_args::SimArgs;
use std::path::{Path, PathBuf};

use anyhow::Context;
use producer::settings::{ProducerSettings, SourceSettings};
use producer::stream::{
    check_shm_for_frames, stream, stream_following_rig, StreamEvent, StreamReport, StreamSettings,
};
use producer::{
    FrameSource, Replay, RigCamera, RigEnvelope, RigFollowConfig, SimulatedConfig,
    DEFAULT_MAX_OFFSET_MM, DEFAULT_MAX_ROTATION_DEG, DEFAULT_MAX_STRETCH, DEFAULT_MM_PER_PX,
    DEFAULT_STRIP_MM_PER_PX,
};

/// Options of `dicstream producer`.
#[derive(Debug, clap::Args)]
pub struct ProducerArgs {
    /// Every setting from this JSON file (as `dicstream run` writes them in
    /// `<results>/settings/producer.json`), instead of the other options
    #[arg(long, exclusive = true)]
    pub settings: Option<PathBuf>,
    #[command(flatten)]
    pub sim: SimArgs,
    /// Replay images instead of simulating: a folder (every .png/.tif/.tiff/.bmp, natural
    /// order) or a glob such as 'dir/img_*.tif'
    #[arg(long, value_name = "DIR|GLOB", conflicts_with_all = ["scenario", "params", "width", "height", "follow_rig"])]
    pub replay: Option<PathBuf>,
    /// With --replay: start again from the first image after the last one, endlessly
    #[arg(long = "loop", requires = "replay")]
    pub looping: bool,
    /// Watch a folder: publish each image another program writes into DIR once it is complete
    /// (unchanged for --settle-ms, or renamed from a temporary name), in natural order, each
    /// file once; name and modification time of each frame on stderr (and in --log)
    #[arg(long, value_name = "DIR", conflicts_with_all = ["scenario", "params", "width", "height", "follow_rig", "replay", "fps"])]
    pub watch: Option<PathBuf>,
    /// With --watch: also publish the images already in the folder at start
    #[arg(long, requires = "watch")]
    pub from_start: bool,
    /// With --watch: end (exit 0, with the summary) after this many seconds without a new image
    #[arg(long, value_name = "S", requires = "watch")]
    pub idle_timeout_s: Option<f64>,
    /// With --watch: a file whose size and modification time stay unchanged this long is
    /// complete, ms
    #[arg(long, default_value_t = producer::DEFAULT_SETTLE_MS, requires = "watch")]
    pub settle_ms: u64,
    /// With --watch: write one CSV row per frame (frame_id,file,modified_unix_ns,size_bytes,
    /// renamed) to this file. With --camera: (frame_id,camera_frame_id,camera_timestamp_ns,
    /// host_receive_ns)
    #[arg(long, value_name = "FILE")]
    pub log: Option<PathBuf>,
    #[command(flatten)]
    pub genicam: super::producer_genicam::CameraArgs,
    /// Render each frame from the most recent rig/state sample (the rig deforms the specimen);
    /// waits for the first sample
    #[arg(long, conflicts_with_all = ["scenario", "params"])]
    pub follow_rig: bool,
    /// With --follow-rig: image scale, mm per px
    #[arg(long, default_value_t = DEFAULT_MM_PER_PX, requires = "follow_rig")]
    pub mm_per_px: f64,
    /// With --follow-rig: image scale when the rig mounts a finite-element strip (two grips),
    /// mm per px
    #[arg(long, default_value_t = DEFAULT_STRIP_MM_PER_PX, requires = "follow_rig")]
    pub strip_mm_per_px: f64,
    /// With --follow-rig: largest stretch the camera can show, both axes (the pattern also
    /// covers the lateral contraction max^-1/2); rig states beyond are skipped and counted
    #[arg(long, default_value_t = DEFAULT_MAX_STRETCH, requires = "follow_rig")]
    pub max_stretch: f64,
    /// With --follow-rig: largest specimen rotation the camera can show, degrees
    #[arg(long, default_value_t = DEFAULT_MAX_ROTATION_DEG, requires = "follow_rig")]
    pub max_rotation_deg: f64,
    /// With --follow-rig: largest specimen centre offset the camera can show, mm per axis
    #[arg(long, default_value_t = DEFAULT_MAX_OFFSET_MM, requires = "follow_rig")]
    pub max_offset_mm: f64,
    /// Frames per second to pace to (0: as fast as frames render)
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Frames to send. A scenario ramps over them [default: 100]; a replay sends each image
    /// once [default: all] (endlessly with --loop); --follow-rig runs until stopped [default]
    #[arg(long)]
    pub frames: Option<u64>,
    /// Id of the first frame; ids go on consecutively from it (a restarted camera continues
    /// the numbering of the one it replaces)
    #[arg(long, default_value_t = 0)]
    pub first_frame_id: u64,
    /// Instance name (shared-memory prefix); runs with different names never meet
    #[arg(long, default_value_t = wire::Instance::default_name())]
    pub instance: String,
}

/// Frames of a scenario when `--frames` is not given.
const DEFAULT_SCENARIO_FRAMES: u64 = 100;

pub fn run(args: ProducerArgs) -> anyhow::Result<()> {
    let settings = match &args.settings {
        Some(file) => super::settings_file::read(file)?,
        None => settings_of(&args)?,
    };
    let instance = wire::Instance::new(&settings.instance)?;
    let stream = settings.stream();
    let mut printer = EventPrinter {
        instance: &instance,
        warned_beyond: false,
    };
    let mut on_event = |event: StreamEvent| printer.print(event);
    let (report, source_line) = match &settings.source {
        SourceSettings::FollowRig { camera, follow } => {
            follow_rig(camera, follow, &instance, &stream, &mut on_event)?
        }
        SourceSettings::Watch {
            dir,
            from_start,
            idle_timeout_s,
            settle_ms,
            log,
        } => {
            let watch = super::producer_watch::WatchArgs {
                dir,
                from_start: *from_start,
                idle_timeout_s: *idle_timeout_s,
                settle_ms: *settle_ms,
                log: log.as_ref(),
            };
            super::producer_watch::run(watch, &instance, &stream, &mut on_event)?
        }
        SourceSettings::Genicam {
            camera,
            settings,
            log,
        } => {
            let camera = super::producer_genicam::GenicamArgs {
                spec: camera,
                camera: settings,
                log: log.as_ref(),
            };
            super::producer_genicam::run(camera, &instance, &stream, &mut on_event)?
        }
        SourceSettings::Replay { files, looping } => {
            replay(files, *looping, &instance, &stream, &mut on_event)?
        }
        SourceSettings::Scenario {
            camera,
            scenario: spec,
            frames,
        } => scenario(camera, spec, *frames, &instance, &stream, &mut on_event)?,
    };
    let paced = match settings.source {
        SourceSettings::Watch { .. } | SourceSettings::Genicam { .. } => None,
        _ => settings.fps,
    };
    println!("{}", final_line(&report, paced, &source_line));
    Ok(())
}

/// The settings of the command line's flags, refused with the flag named.
fn settings_of(args: &ProducerArgs) -> anyhow::Result<ProducerSettings> {
    check(args)?;
    let source = if args.follow_rig {
        SourceSettings::FollowRig {
            camera: args.sim.config()?,
            follow: RigFollowConfig {
                mm_per_px: args.mm_per_px,
                strip_mm_per_px: args.strip_mm_per_px,
                envelope: RigEnvelope {
                    max_stretch: args.max_stretch,
                    max_rotation_rad: args.max_rotation_deg.to_radians(),
                    max_offset_mm: args.max_offset_mm,
                },
            },
        }
    } else if let Some(dir) = &args.watch {
        SourceSettings::Watch {
            dir: dir.clone(),
            from_start: args.from_start,
            idle_timeout_s: args.idle_timeout_s,
            settle_ms: args.settle_ms,
            log: args.log.clone(),
        }
    } else if let Some(spec) = &args.genicam.camera {
        SourceSettings::Genicam {
            camera: spec.clone(),
            settings: args.genicam.settings(args.fps),
            log: args.log.clone(),
        }
    } else if let Some(files) = &args.replay {
        SourceSettings::Replay {
            files: files.clone(),
            looping: args.looping,
        }
    } else {
        // Cheap checks first (scenario, camera), then the costly pattern when it runs.
        args.sim.scenario()?;
        SourceSettings::Scenario {
            camera: args.sim.config()?,
            scenario: args.sim.scenario_spec(),
            frames: args.frames.unwrap_or(DEFAULT_SCENARIO_FRAMES),
        }
    };
    Ok(ProducerSettings {
        instance: args.instance.clone(),
        source,
        fps: (args.fps > 0.0).then_some(args.fps),
        max_frames: args.frames,
        first_frame_id: args.first_frame_id,
    })
}

/// The checks of the options no parser makes.
fn check(args: &ProducerArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.fps.is_finite() && args.fps >= 0.0,
        "--fps {}: expected a rate in frames per second, or 0 for as fast as possible",
        args.fps
    );
    anyhow::ensure!(
        args.frames != Some(0),
        "--frames 0: expected at least 1 frame"
    );
    anyhow::ensure!(
        args.log.is_none() || args.watch.is_some() || args.genicam.camera.is_some(),
        "--log: only with --watch (one row per file) or --camera (one row per frame's timestamps)"
    );
    Ok(())
}

/// The stream's events on stderr; a rig state beyond the envelope is told once.
struct EventPrinter<'a> {
    instance: &'a wire::Instance,
    warned_beyond: bool,
}

impl EventPrinter<'_> {
    fn print(&mut self, event: StreamEvent) {
        let name = self.instance.name();
        match event {
            StreamEvent::Ready {
                dims,
                dead_nodes_cleaned,
            } => {
                if dead_nodes_cleaned > 0 {
                    eprintln!(
                        "producer: cleaned {dead_nodes_cleaned} dead node(s) of instance {name}"
                    );
                }
                eprintln!(
                    "producer: ready (instance {name}, {}x{} px, {} bit)",
                    dims.width, dims.height, dims.bit_depth
                );
            }
            StreamEvent::WaitingForRig => eprintln!(
                "producer: waiting for the first rig/state sample of instance {name} (start \
                 `dicstream rig --instance {name}`)"
            ),
            StreamEvent::RigArrived { sample_id } => {
                eprintln!("producer: following the rig from sample {sample_id}")
            }
            StreamEvent::RigBeyond {
                sample_id, reason, ..
            } => {
                if !self.warned_beyond {
                    self.warned_beyond = true;
                    eprintln!(
                        "producer: warning: rig sample {sample_id} is beyond what the camera can \
                         show: {reason}; such frames are skipped and counted (this warning is \
                         shown once)"
                    );
                }
            }
            StreamEvent::Frame(_) => {}
        }
    }
}

/// `--follow-rig`: frames rendered from the rig's state; the report and the final line's part.
fn follow_rig(
    config: &SimulatedConfig,
    follow: &RigFollowConfig,
    instance: &wire::Instance,
    settings: &StreamSettings,
    on_event: impl FnMut(StreamEvent),
) -> anyhow::Result<(StreamReport, String)> {
    check_shm_for_frames(config.width, config.height)?;
    let mut camera = RigCamera::new(*config, *follow).context("building the rig-driven camera")?;
    let report = stream_following_rig(&mut camera, instance, settings, on_event)?;
    let line = format!(
        "{} rig samples received, last frame at rig sample {}",
        report.rig_samples_received,
        report
            .last_rig_sample_id
            .map_or_else(|| "-".to_string(), |id| id.to_string())
    );
    Ok((report, line))
}

/// `--replay`: the images of `source`; the report and the final line's part.
fn replay(
    source: &Path,
    looping: bool,
    instance: &wire::Instance,
    settings: &StreamSettings,
    on_event: impl FnMut(StreamEvent),
) -> anyhow::Result<(StreamReport, String)> {
    let mut replay = Replay::open(source)?;
    let dims = replay.dims();
    check_shm_for_frames(dims.width, dims.height)?;
    replay.set_looping(looping);
    let line = format!(
        "replay of {} image(s) from {}{}",
        replay.files().len(),
        source.display(),
        if looping { ", looping" } else { "" }
    );
    let report = stream(&mut replay, instance, settings, on_event)?;
    Ok((report, line))
}

/// A simulated scenario; the report and the final line's part.
fn scenario(
    config: &SimulatedConfig,
    spec: &str,
    frames: u64,
    instance: &wire::Instance,
    settings: &StreamSettings,
    on_event: impl FnMut(StreamEvent),
) -> anyhow::Result<(StreamReport, String)> {
    check_shm_for_frames(config.width, config.height)?;
    let mut camera = super::sim_args::scenario_camera(config, spec, frames)
        .context("building the simulated camera")?;
    let report = stream(&mut camera, instance, settings, on_event)?;
    Ok((report, format!("scenario {spec} over {frames} frames")))
}

/// The one line a run ends with.
fn final_line(report: &StreamReport, fps: Option<f64>, source: &str) -> String {
    let asked = match fps {
        Some(fps) => format!("{fps} asked"),
        None => "unpaced".to_string(),
    };
    let mut line = format!(
        "producer: {} frames sent in {:.2} s ({:.1} fps measured, {asked}), {} received by \
         nobody, {} skipped (rig beyond the envelope); {source}",
        report.frames_sent,
        report.elapsed_s,
        report.rate_hz(),
        report.frames_unseen,
        report.frames_beyond_envelope,
    );
    if report.interrupted {
        line.push_str("; stopped by signal");
    }
    line
}
