//! The live `correlator` process shell: subscribes to `frames`, correlates the newest frame
//! against the reference with the pure [`Correlator`], publishes `fields` zero-copy, and saves
//! its reference to a state folder so that a restarted process resumes against it. All IPC of
//! the crate lives in this file; the core knows nothing of it.
//!
//! - Sleeps in a WaitSet on the `frames` event (no polling, no sleeps); a timeout of at most a
//!   second serves the status line and the idle timeout.
//! - Always works on the newest frame: after a wake-up the queue is drained, older samples are
//!   released at once and counted as skipped; gaps in frame ids (the camera's safe overflow
//!   dropped them before they reached us) are counted as lost. Dropped = skipped + lost.
//! - A frame is correlated straight from shared memory (no copy) and its sample is released as
//!   soon as its field is out and the reference renewed (the correlator copies a new reference
//!   itself). The frames
//!   dropped since the last one correlated are told to the correlator, whose predictions then
//!   extrapolate over them (`Correlator::correlate_after`).
//! - Lost frames: `frames` keeps two samples per subscriber (`wire::services::FRAMES`); while a
//!   frame takes longer than two frame periods, the camera's safe overflow replaces the oldest
//!   waiting one, and its id never arrives. Skipped frames did arrive but were older than the
//!   newest when the correlator was free again.
//! - A field that calls for a new reference is published first; its frame becomes the reference
//!   after (`Correlator::renew_reference`), and the new bases are measured against the origin a
//!   quarter of the mesh after each frame (`Correlator::measure_pending_bases`): a renewal's work
//!   is off the renewing frame's latency and spread over the next frames.
//! - A new reference (and again its bases once measured against the origin) is handed to the
//!   state folder's writer thread (`state/writer.rs`), which saves it off the frame path.
//! - A field is written in place into a loaned `[FieldNode]` slice and sent.
//! - A bad frame (header inconsistent with its payload, unknown bit depth, another size than the
//!   reference) is a logged error for that frame (rate-limited); the process goes on.
//! - No allocation per frame in the shell's own code apart from the status line (at most once
//!   per `status_interval`). iceoryx2 0.10 itself allocates three small blocks per frame: two
//!   vectors of triggered file descriptors per WaitSet wake-up and a reference-counted state
//!   per loaned sample; see `tests/process_allocations.rs`.

use crate::settings::{CorrelatorSettings, Method};
use crate::state::writer::StateWriter;
use crate::state::{ReferenceIds, SavedReference, StateDir, REFERENCE_FROM_FILE};
use crate::{Correlator, Field};
use iceoryx2::prelude::*;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use wire::pubsub::{SlicePublisher, SliceSubscriber};
use wire::stats::{Durations, IdGaps, IdStep};
use wire::{services, FieldHeader, FieldNode, FrameHeader, GaugeStrain, Instance};

/// Why the correlator process could not start or stopped. A state file that could not be
/// written stays reachable through `source()` (for `wire::exit::code_of`).
#[derive(Debug, thiserror::Error)]
pub enum ProcessError {
    #[error(transparent)]
    Settings(#[from] crate::settings::SettingsError),
    /// Also the `source()`: a subscriber that cannot connect keeps its exit code.
    #[error("{0}")]
    Instance(#[from] wire::InstanceError),
    #[error(transparent)]
    State(#[from] crate::state::StateError),
    #[error("settings refused for the {width_px}x{height_px} px reference {label}: {reason}")]
    ReferenceSettings {
        width_px: usize,
        height_px: usize,
        label: String,
        reason: crate::settings::SettingsError,
    },
    #[error("reference image {label} is flat: no ZOI has texture to correlate")]
    FlatReference { label: String },
    #[error("{0}")]
    WaitSetCreate(#[from] wire::resources::WaitSetError),
    #[error(transparent)]
    WaitSetAttach(#[from] iceoryx2::waitset::WaitSetAttachmentError),
    #[error(transparent)]
    WaitSetRun(#[from] iceoryx2::waitset::WaitSetRunError),
}

/// A reference image given by the user instead of the first frame.
#[derive(Clone, Debug)]
pub struct ReferenceImage {
    pub pixels: Vec<u16>,
    pub width_px: usize,
    pub height_px: usize,
    /// Where it came from, for messages.
    pub label: String,
}

/// Settings of the process: what `dicstream run` writes for its correlator (`--settings`),
/// and what the command line's flags make.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProcessConfig {
    pub instance: String,
    pub settings: CorrelatorSettings,
    /// Reference image; None: the first valid frame is the reference. Given in memory (the
    /// command line's `--reference` file), not in a settings file.
    #[serde(skip)]
    pub reference: Option<ReferenceImage>,
    /// Folder where the reference and what is needed to resume are saved whenever the reference
    /// changes; a process started on a folder holding a saved reference resumes against it.
    pub state_dir: Option<PathBuf>,
    /// Stop after this many fields were published.
    pub max_frames: Option<u64>,
    /// Stop after this long without any frame (None: never).
    #[serde(with = "wire::seconds::option", rename = "idle_timeout_s", default)]
    pub idle_timeout: Option<Duration>,
    /// Least time between two status lines (a line is printed only when frames arrived).
    #[serde(with = "wire::seconds", rename = "status_interval_s")]
    pub status_interval: Duration,
}

impl ProcessConfig {
    pub fn new(instance: &str, settings: CorrelatorSettings) -> Self {
        ProcessConfig {
            instance: instance.to_string(),
            settings,
            reference: None,
            state_dir: None,
            max_frames: None,
            idle_timeout: None,
            status_interval: Duration::from_secs(1),
        }
    }
}

/// Why the process stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum StopReason {
    /// SIGINT, SIGTERM or SIGHUP (the signal number).
    Signal(i32),
    #[default]
    MaxFrames,
    IdleTimeout,
}

impl StopReason {
    pub fn describe(self) -> String {
        match self {
            StopReason::Signal(signal) => wire::signals::name(signal),
            StopReason::MaxFrames => "--max-frames reached".into(),
            StopReason::IdleTimeout => "idle timeout".into(),
        }
    }
}

/// What the run did.
#[derive(Clone, Debug, Default)]
pub struct ProcessSummary {
    /// Frames taken out of the queue.
    pub frames_received: u64,
    /// Frames correlated (= fields published).
    pub frames_correlated: u64,
    /// Frames received but superseded by a newer one before they could be correlated.
    pub frames_skipped: u64,
    /// Frames never received: gaps in the frame ids (the camera's queue overflowed).
    pub frames_lost: u64,
    /// Frames refused (bad header, another size than the reference, ...).
    pub frames_rejected: u64,
    /// Median and 99th percentile of the correlation time per frame (ms).
    pub correlate_p50_ms: f64,
    pub correlate_p99_ms: f64,
    /// Frame id of the current reference (`state::REFERENCE_FROM_FILE` for an image file).
    pub reference_frame_id: Option<u64>,
    /// True when the reference was read back from the state folder.
    pub resumed: bool,
    /// Times the reference was saved to the state folder.
    pub state_saves: u64,
    /// WaitSet wake-ups.
    pub wakeups: u64,
    pub stop: StopReason,
}

impl ProcessSummary {
    /// Frames the correlator did not correlate: skipped plus lost.
    pub fn frames_dropped(&self) -> u64 {
        self.frames_skipped + self.frames_lost
    }

    /// One line for the end of a run.
    pub fn final_line(&self) -> String {
        format!(
            "correlator: stopped ({}): frames in {}, correlated {}, dropped {} (skipped {}, lost {}), rejected {}; correlate p50 {:.1} ms, p99 {:.1} ms; reference {}{}",
            self.stop.describe(),
            self.frames_received,
            self.frames_correlated,
            self.frames_dropped(),
            self.frames_skipped,
            self.frames_lost,
            self.frames_rejected,
            self.correlate_p50_ms,
            self.correlate_p99_ms,
            ReferenceId(self.reference_frame_id),
            if self.state_saves > 0 {
                format!("; state saved {} time(s)", self.state_saves)
            } else {
                String::new()
            },
        )
    }
}

/// Longest WaitSet wait: the status line and the idle timeout are checked at least this often.
const MAX_WAIT: Duration = Duration::from_secs(1);
/// Rejected frames logged in full before the log is limited to one line per second.
const REJECT_LOG_BURST: u64 = 5;

/// Runs the process until SIGINT/SIGTERM, `max_frames` or the idle timeout.
pub fn run(config: ProcessConfig) -> Result<ProcessSummary, ProcessError> {
    config.settings.validate()?;
    let instance = Instance::new(&config.instance)?;
    let _owner = instance.claim("correlator")?;
    let mut state = match &config.state_dir {
        Some(dir) => Some(StateDir::open(dir)?),
        None => None,
    };
    let saved = match &state {
        Some(state) => state.load()?,
        None => None,
    };
    let (node, cleaned) = instance.create_node("correlator")?;
    if cleaned > 0 {
        eprintln!(
            "correlator: cleaned {cleaned} dead node(s) of instance {}",
            instance.name()
        );
    }
    let frames: SliceSubscriber<u16, FrameHeader> =
        SliceSubscriber::create(&node, &services::FRAMES)?;
    let waitset = wire::signals::waitset()?;
    let frames_guard = waitset.attach_notification(frames.listener())?;

    let mut live = Live::new(&config);
    let starting_reference = start(&mut live, &node, saved, state.as_mut(), &config)?;
    print_ready(&config, &instance, &starting_reference);
    let mut writer = state.map(StateWriter::spawn);

    let started = Instant::now();
    let mut last_activity = started;
    let mut status = StatusLine::new(started);
    loop {
        let mut timeout = MAX_WAIT.min(config.status_interval);
        if let Some(idle) = config.idle_timeout {
            timeout = timeout.min(idle.saturating_sub(last_activity.elapsed()));
        }
        // An early wake-up (a signal, SIGCONT after SIGSTOP) only ends the wait.
        waitset.wait_and_process_once_with_timeout(
            |id| {
                if id.has_event_from(&frames_guard) {
                    frames.clear_events();
                }
                CallbackProgression::Continue
            },
            timeout,
        )?;
        live.summary.wakeups += 1;
        if let Some(signal) = wire::signals::requested() {
            live.summary.stop = StopReason::Signal(signal);
            break;
        }
        // Drain: keep only the newest sample, release the others at once.
        let mut newest = None;
        while let Some(sample) = frames.receive()? {
            let t_received_ns = wire::monotonic_ns();
            live.note_received(sample.user_header());
            if newest.replace((sample, t_received_ns)).is_some() {
                live.summary.frames_skipped += 1;
            }
        }
        if let Some((sample, t_received_ns)) = newest {
            last_activity = Instant::now();
            live.handle(&node, sample, t_received_ns, writer.as_mut())?;
        }
        if status.due(config.status_interval) {
            status.print(&mut live);
        }
        if config
            .max_frames
            .is_some_and(|m| live.summary.frames_correlated >= m)
        {
            live.summary.stop = StopReason::MaxFrames;
            break;
        }
        if config
            .idle_timeout
            .is_some_and(|t| last_activity.elapsed() >= t)
        {
            live.summary.stop = StopReason::IdleTimeout;
            break;
        }
    }
    let mut summary = live.summary.clone();
    summary.correlate_p50_ms = live.run_hist.median_ms();
    summary.correlate_p99_ms = live.run_hist.quantile_ms(0.99);
    summary.state_saves = match writer {
        Some(writer) => writer.finish()?,
        None => 0,
    };
    Ok(summary)
}

/// The reference the process starts from: the state folder's (resumed), a reference image
/// (saved to the state folder), or the first frame; said in the ready line.
fn start(
    live: &mut Live,
    node: &Node<ipc::Service>,
    saved: Option<SavedReference>,
    mut state: Option<&mut StateDir>,
    config: &ProcessConfig,
) -> Result<String, ProcessError> {
    Ok(match (saved, &config.reference) {
        (Some(saved), reference) => {
            let path = state.as_ref().expect("saved implies a state dir").path();
            if let Some(image) = reference {
                eprintln!(
                    "correlator: resuming from {}; --reference {} ignored",
                    path.display(),
                    image.label
                );
            }
            live.resume(node, &saved, path)?;
            format!(
                "resumed {} from {}",
                ReferenceId(Some(saved.reference_frame_id)),
                path.display()
            )
        }
        (None, Some(image)) => {
            live.start_from_image(node, image)?;
            if let (Some(state), Some(correlator)) = (state.as_mut(), live.correlator.as_ref()) {
                state.save(correlator, ReferenceIds::FROM_FILE)?;
                live.summary.state_saves += 1;
            }
            format!(
                "reference image {} ({}x{} px)",
                image.label, image.width_px, image.height_px
            )
        }
        (None, None) => "reference: the first frame".to_string(),
    })
}

/// The ready line: the services, the settings, where the reference comes from.
fn print_ready(config: &ProcessConfig, instance: &Instance, starting_reference: &str) {
    let s = &config.settings;
    eprintln!(
        "correlator: ready: instance {}, subscribed to '{}', publishing '{}'; ZOI {} px, step {} px, {:?} reference, {:?} guess, {} strain, {} thread(s); {starting_reference}{}",
        instance.name(),
        services::FRAMES.name,
        services::FIELDS.name,
        s.zoi_px,
        s.step_px,
        s.reference,
        s.guess,
        s.strain.name(),
        s.threads,
        match &config.state_dir {
            Some(dir) => format!("; state in {}", dir.display()),
            None => String::new(),
        }
    );
}

type FieldPublisher = SlicePublisher<FieldNode, FieldHeader>;

/// Everything that lives across frames.
struct Live {
    settings: CorrelatorSettings,
    correlator: Option<Correlator>,
    publisher: Option<FieldPublisher>,
    /// Frame id of the reference the next frame is correlated against.
    reference_frame_id: Option<u64>,
    /// The frame the mesh is defined in, and the frame sequence the reference belongs to
    /// (None for a reference image file: it holds for every sequence).
    origin_frame_id: u64,
    sequence_id: Option<u32>,
    /// Frame ids received: gaps are lost frames.
    frame_ids: IdGaps,
    /// Sequence and id of the last frame correlated.
    last_correlated: Option<(u32, u64)>,
    summary: ProcessSummary,
    /// Correlation time per frame (ns): whole run, and since the last status line.
    run_hist: Durations,
    window_hist: Durations,
    rejects: RateLimit,
    /// Frames with fewer than half their nodes valid.
    few_valid: RateLimit,
}

impl Live {
    fn new(config: &ProcessConfig) -> Live {
        Live {
            settings: config.settings.clone(),
            correlator: None,
            publisher: None,
            reference_frame_id: None,
            origin_frame_id: 0,
            sequence_id: None,
            frame_ids: IdGaps::default(),
            last_correlated: None,
            summary: ProcessSummary::default(),
            run_hist: Durations::new(),
            window_hist: Durations::new(),
            rejects: RateLimit::default(),
            few_valid: RateLimit::default(),
        }
    }

    /// Makes the fields publisher for a mesh of `nodes` (needs free shared memory).
    fn open_publisher(
        &mut self,
        node: &Node<ipc::Service>,
        nodes: usize,
    ) -> Result<(), ProcessError> {
        let bytes = services::FIELDS.shm_bytes(
            std::mem::size_of::<FieldHeader>(),
            nodes * std::mem::size_of::<FieldNode>(),
        );
        wire::shm::ensure_free(wire::shm::SHM_PATH, bytes)?;
        self.publisher = Some(SlicePublisher::create(node, &services::FIELDS, nodes)?);
        Ok(())
    }

    fn resume(
        &mut self,
        node: &Node<ipc::Service>,
        saved: &SavedReference,
        path: &std::path::Path,
    ) -> Result<(), ProcessError> {
        let correlator = saved.restore(self.settings.clone(), path)?;
        let (nx, ny) = correlator.mesh_size();
        self.open_publisher(node, nx * ny)?;
        self.correlator = Some(correlator);
        self.reference_frame_id = Some(saved.reference_frame_id);
        self.origin_frame_id = saved.origin_frame_id;
        self.sequence_id =
            (saved.reference_frame_id != REFERENCE_FROM_FILE).then_some(saved.sequence_id);
        self.summary.reference_frame_id = self.reference_frame_id;
        self.summary.resumed = true;
        Ok(())
    }

    fn start_from_image(
        &mut self,
        node: &Node<ipc::Service>,
        image: &ReferenceImage,
    ) -> Result<(), ProcessError> {
        let mut correlator =
            Correlator::new(self.settings.clone(), image.width_px, image.height_px).map_err(
                |reason| ProcessError::ReferenceSettings {
                    width_px: image.width_px,
                    height_px: image.height_px,
                    label: image.label.clone(),
                    reason,
                },
            )?;
        correlator.set_reference(&image.pixels)?;
        if correlator.reference_textured_nodes() == 0 {
            return Err(ProcessError::FlatReference {
                label: image.label.clone(),
            });
        }
        let (nx, ny) = correlator.mesh_size();
        self.open_publisher(node, nx * ny)?;
        self.correlator = Some(correlator);
        self.reference_frame_id = Some(REFERENCE_FROM_FILE);
        self.origin_frame_id = REFERENCE_FROM_FILE;
        self.sequence_id = None;
        self.summary.reference_frame_id = self.reference_frame_id;
        Ok(())
    }

    /// Counts a received frame and the gap in frame ids before it.
    fn note_received(&mut self, header: &FrameHeader) {
        self.summary.frames_received += 1;
        let id = header.frame_id;
        match self.frame_ids.observe(id) {
            IdStep::Forward { skipped } => self.summary.frames_lost += skipped,
            IdStep::Back { from: last } if self.rejects.allow() => eprintln!(
                "correlator: frame id went back from {last} to {id} (producer restarted?); counting drops from here"
            ),
            _ => {}
        }
    }

    fn reject(&mut self, frame_id: u64, reason: &dyn std::fmt::Display) {
        self.summary.frames_rejected += 1;
        if self.rejects.allow() {
            eprintln!("correlator: error: frame {frame_id} rejected: {reason}");
        }
    }

    /// Validates, correlates and publishes one frame; releases its sample as soon as possible.
    fn handle(
        &mut self,
        node: &Node<ipc::Service>,
        sample: iceoryx2::sample::Sample<ipc::Service, [u16], FrameHeader>,
        t_received_ns: u64,
        mut state: Option<&mut StateWriter>,
    ) -> Result<(), ProcessError> {
        let header = *sample.user_header();
        let pixels: &[u16] = sample.payload();
        if let Err(reason) = header.validate(pixels.len()) {
            self.reject(header.frame_id, &reason);
            return Ok(());
        }
        self.check_sequence(&header);
        let Some(new_origin) = self.ready_reference(node, &header, pixels)? else {
            return Ok(());
        };
        let correlator = self.correlator.as_mut().expect("made above");
        let reference_frame_id = self.reference_frame_id.expect("set with the correlator");
        // Camera frames since the last one correlated (dropped ones in between), 1 after a
        // new reference or sequence.
        let frame_step = match self.last_correlated {
            Some((sequence, id)) if sequence == header.sequence_id && header.frame_id > id => {
                header.frame_id - id
            }
            _ => 1,
        };
        let t = Instant::now();
        correlator.correlate_field(pixels, frame_step)?;
        self.last_correlated = Some((header.sequence_id, header.frame_id));
        let correlate_ns = t.elapsed().as_nanos() as u64;
        self.warn_few_valid(header.frame_id);
        self.run_hist.record_ns(correlate_ns);
        self.window_hist.record_ns(correlate_ns);
        self.summary.frames_correlated += 1;
        // A new origin (the first frame, a new sequence) is written before its first field
        // goes out: a restart must never resume on the previous origin's reference once a
        // field of the new one was seen.
        if let Some(state) = state.as_deref_mut().filter(|_| new_origin) {
            self.save_reference(state)?;
            state.flush()?;
        }
        let times = FieldTimes {
            reference_frame_id,
            origin_frame_id: self.origin_frame_id,
            t_received_ns,
            correlate_ns,
            frames_dropped: self.summary.frames_dropped(),
        };
        self.publish_field(&header, times)?;
        // The field is out: a renewal it called for is made now, its bases measured against
        // the origin a part per frame from here (`Correlator::renew_reference`). Handed to the
        // writer after the field: the state folder holds an earlier reference of the same
        // origin until the writer is done (`state/writer.rs`).
        let correlator = self.correlator.as_mut().expect("made above");
        if correlator.field().reference_updated {
            correlator.renew_reference(pixels)?;
            self.reference_frame_id = Some(header.frame_id);
            if let Some(state) = state.as_deref_mut() {
                self.save_reference(state)?;
            }
        }
        self.summary.reference_frame_id = self.reference_frame_id;
        // The frame is no longer needed: the correlator copied it if it became the reference.
        drop(sample);
        self.measure_pending_bases(state)
    }

    /// A part of the current reference's bases measured against the origin (a pass takes
    /// [`crate::ORIGIN_PASS_FRAMES`] frames); the reference saved again when the pass is
    /// complete.
    fn measure_pending_bases(
        &mut self,
        state: Option<&mut StateWriter>,
    ) -> Result<(), ProcessError> {
        let correlator = self.correlator.as_mut().expect("made above");
        if correlator.pending_bases() > 0 && correlator.measure_pending_bases() {
            if let Some(state) = state {
                self.save_reference(state)?;
            }
        }
        Ok(())
    }

    /// The last field (a correlator exists once a frame was handled).
    fn field(&self) -> &Field {
        self.correlator.as_ref().expect("made above").field()
    }

    /// A new frame sequence (the next test, a new specimen) starts from a new reference.
    fn check_sequence(&mut self, header: &FrameHeader) {
        if self.reference_frame_id.is_some()
            && self.sequence_id.is_some_and(|s| s != header.sequence_id)
        {
            eprintln!(
                "correlator: frame {} starts frame sequence {} (was {}): it becomes the new reference",
                header.frame_id,
                header.sequence_id,
                self.sequence_id.unwrap_or(0)
            );
            self.reference_frame_id = None;
        }
    }

    /// A correlator with a reference for this frame: whether the frame just became the
    /// reference, or None when the frame is refused (logged).
    fn ready_reference(
        &mut self,
        node: &Node<ipc::Service>,
        header: &FrameHeader,
        pixels: &[u16],
    ) -> Result<Option<bool>, ProcessError> {
        let (w, h) = (header.width_px as usize, header.height_px as usize);
        if !self.make_correlator(header.frame_id, (w, h)) {
            return Ok(None);
        }
        match &mut self.correlator {
            // The first frame of the right size becomes the reference, unless it is flat
            // (lens cap, lights off): then every later field would be invalid.
            Some(correlator)
                if self.reference_frame_id.is_none() && correlator.image_size() == (w, h) =>
            {
                correlator.set_reference(pixels)?;
                if correlator.reference_textured_nodes() == 0 {
                    self.reject(
                        header.frame_id,
                        &"it is flat (no ZOI has texture): not taken as the reference; waiting for a textured frame",
                    );
                    return Ok(None);
                }
                let (nx, ny) = correlator.mesh_size();
                let region = format!(
                    "over {}, {} in the region ({})",
                    correlator.roi().extent(),
                    correlator.nodes_in_region(),
                    correlator.settings().region
                );
                if self.publisher.is_none() {
                    self.open_publisher(node, nx * ny)?;
                }
                self.reference_frame_id = Some(header.frame_id);
                self.origin_frame_id = header.frame_id;
                self.sequence_id = Some(header.sequence_id);
                eprintln!(
                    "correlator: frame {} ({w}x{h} px, {} bit) is the reference; mesh {nx}x{ny} nodes {region}",
                    header.frame_id, header.bit_depth
                );
                Ok(Some(true))
            }
            Some(correlator) if correlator.image_size() != (w, h) => {
                let (rw, rh) = correlator.image_size();
                self.reject(
                    header.frame_id,
                    &format_args!(
                        "it is {w}x{h} px but the reference is {rw}x{rh} px: every frame must have the reference's size"
                    ),
                );
                Ok(None)
            }
            _ => Ok(Some(false)),
        }
    }

    /// No correlator yet, or one made for a flat first frame of another size: a new one for
    /// images of `size`; false when the settings refuse it (the frame is refused, logged).
    fn make_correlator(&mut self, frame_id: u64, (w, h): (usize, usize)) -> bool {
        let fits = |c: &Correlator| c.image_size() == (w, h);
        if self.reference_frame_id.is_some() || self.correlator.as_ref().is_some_and(fits) {
            return true;
        }
        self.correlator = None;
        match Correlator::new(self.settings.clone(), w, h) {
            Ok(correlator) => {
                self.correlator = Some(correlator);
                true
            }
            Err(e) => {
                self.reject(
                    frame_id,
                    &format_args!("cannot be a reference with these settings: {e}"),
                );
                false
            }
        }
    }

    /// A rate-limited warning when fewer than half the nodes are valid.
    fn warn_few_valid(&mut self, frame_id: u64) {
        let field = self.correlator.as_ref().expect("made above").field();
        if 2 * field.valid < field.nodes.len() && self.few_valid.allow() {
            eprintln!(
                "correlator: warning: frame {frame_id}: only {} of {} nodes valid ({})",
                field.valid,
                field.nodes.len(),
                field.refusals()
            );
        }
    }

    /// The reference the last field left behind, to the state folder's writer.
    fn save_reference(&self, state: &mut StateWriter) -> Result<(), ProcessError> {
        let ids = ReferenceIds {
            reference_frame_id: self.reference_frame_id.expect("set"),
            origin_frame_id: self.origin_frame_id,
            sequence_id: self.sequence_id.unwrap_or(0),
        };
        state.submit(self.correlator.as_ref().expect("made above"), ids)?;
        Ok(())
    }

    /// The last field, written in place into a loaned `[FieldNode]` slice.
    fn publish_field(&self, header: &FrameHeader, times: FieldTimes) -> Result<(), ProcessError> {
        let field = self.field();
        let publisher = self.publisher.as_ref().expect("opened with the correlator");
        let settings = &self.settings;
        publisher
            .publish(field.nodes.len(), |out, nodes| {
                fill_field(out, nodes, field, header, times, settings);
                Ok::<bool, std::convert::Infallible>(true)
            })?
            .unwrap_or_else(|never| match never {});
        Ok(())
    }
}

struct FieldTimes {
    reference_frame_id: u64,
    origin_frame_id: u64,
    t_received_ns: u64,
    correlate_ns: u64,
    frames_dropped: u64,
}

/// IC-GN's own gradient with `icgn1`/`icgn2`, the neighbours' least-squares fit with `correli`
/// (`Field::gradients`). `icgn` reports `Icgn1` (the wire's codes are fixed): its gradients
/// are each node's own shape function's too, the first-order part of a second-order one on
/// the nodes it re-ran at second order (`Field::second_order`).
fn wire_gradient_source(method: Method) -> wire::GradientSource {
    match method {
        Method::Correli => wire::GradientSource::NeighbourFit,
        Method::Icgn1 | Method::Icgn => wire::GradientSource::Icgn1,
        Method::Icgn2 => wire::GradientSource::Icgn2,
    }
}

/// Writes the header and every node of one field in place (shared memory).
fn fill_field(
    out: &mut FieldHeader,
    nodes: &mut [FieldNode],
    field: &Field,
    frame: &FrameHeader,
    times: FieldTimes,
    settings: &CorrelatorSettings,
) {
    assert_eq!(nodes.len(), field.nodes.len());
    assert_eq!(field.gradients.len(), field.nodes.len());
    for ((o, n), g) in nodes.iter_mut().zip(&field.nodes).zip(&field.gradients) {
        *o = FieldNode {
            x_px: n.x_px as f32,
            y_px: n.y_px as f32,
            u_px: n.u_px as f32,
            v_px: n.v_px as f32,
            exx: n.exx as f32,
            eyy: n.eyy as f32,
            exy: n.exy as f32,
            score: n.score as f32,
            iterations: n.iterations,
            status: n.status as u32,
            du_dx: g[0][0] as f32,
            du_dy: g[0][1] as f32,
            dv_dx: g[1][0] as f32,
            dv_dy: g[1][1] as f32,
        };
    }
    let gauge = |s: crate::Strain2| GaugeStrain {
        exx: s.exx,
        eyy: s.eyy,
        exy: s.exy,
    };
    let g = &field.gauge;
    *out = FieldHeader {
        layout_version: wire::LAYOUT_VERSION,
        strain_measure: settings.strain as u32,
        frame_id: frame.frame_id,
        reference_frame_id: times.reference_frame_id,
        origin_frame_id: times.origin_frame_id,
        t_capture_ns: frame.t_capture_ns,
        rig_sample_id: frame.rig_sample_id,
        t_received_ns: times.t_received_ns,
        t_published_ns: 0,
        correlate_ns: times.correlate_ns,
        frames_dropped: times.frames_dropped,
        mesh_cols: field.nx as u32,
        mesh_rows: field.ny as u32,
        zoi_px: settings.zoi_px as u32,
        step_px: settings.step_px as u32,
        valid_nodes: field.valid as u32,
        has_truth: frame.has_truth,
        truth: frame.truth,
        u_mean_px: field.u_mean_px,
        v_mean_px: field.v_mean_px,
        // Order of wire::StrainMeasure::ALL: small, green, nominal, log.
        gauge: [
            gauge(g.small),
            gauge(g.green),
            gauge(g.nominal),
            gauge(g.log),
        ],
        sequence_id: frame.sequence_id,
        gradient_source: wire_gradient_source(settings.method) as u32,
    };
    out.t_published_ns = wire::monotonic_ns();
}

/// At most a few lines in a burst, then one per second.
#[derive(Default)]
struct RateLimit {
    printed: u64,
    last: Option<Instant>,
    suppressed: u64,
}

impl RateLimit {
    fn allow(&mut self) -> bool {
        let now = Instant::now();
        let quiet = self
            .last
            .is_none_or(|t| now.duration_since(t) >= Duration::from_secs(1));
        if self.printed < REJECT_LOG_BURST || quiet {
            if self.suppressed > 0 {
                eprintln!(
                    "correlator: ({} similar message(s) suppressed)",
                    self.suppressed
                );
                self.suppressed = 0;
            }
            self.printed += 1;
            self.last = Some(now);
            true
        } else {
            self.suppressed += 1;
            false
        }
    }
}

/// The once-a-second status line.
struct StatusLine {
    last_print: Instant,
    last_received: u64,
    last_correlated: u64,
}

impl StatusLine {
    fn new(now: Instant) -> Self {
        StatusLine {
            last_print: now,
            last_received: 0,
            last_correlated: 0,
        }
    }

    fn due(&self, interval: Duration) -> bool {
        self.last_print.elapsed() >= interval
    }

    fn print(&mut self, live: &mut Live) {
        let s = &live.summary;
        if s.frames_received == self.last_received {
            self.last_print = Instant::now();
            return;
        }
        let elapsed_s = self.last_print.elapsed().as_secs_f64();
        let rate = (s.frames_correlated - self.last_correlated) as f64 / elapsed_s;
        let p50_ms = live.window_hist.median_ms();
        eprintln!(
            "correlator: frames in {}, correlated {}, dropped {} (skipped {}, lost {}), rejected {}; correlate p50 {p50_ms:.1} ms; {rate:.1} fields/s; reference {}",
            s.frames_received,
            s.frames_correlated,
            s.frames_dropped(),
            s.frames_skipped,
            s.frames_lost,
            s.frames_rejected,
            ReferenceId(s.reference_frame_id),
        );
        live.window_hist.reset();
        self.last_received = s.frames_received;
        self.last_correlated = s.frames_correlated;
        self.last_print = Instant::now();
    }
}

/// Displays a reference id without allocating.
struct ReferenceId(Option<u64>);

impl std::fmt::Display for ReferenceId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            None => write!(f, "none yet"),
            Some(REFERENCE_FROM_FILE) => write!(f, "image file"),
            Some(id) => write!(f, "frame {id}"),
        }
    }
}
