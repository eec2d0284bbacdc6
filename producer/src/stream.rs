//! The producer process shell: pulls frames from a [`FrameSource`] straight into loaned
//! shared-memory slices of the `frames` service, stamps the header, paces to the requested
//! rate and never waits for a consumer (safe overflow: a slow or dead reader loses frames,
//! the camera never blocks).

use crate::{FrameSource, ProducerError};
use std::time::{Duration, Instant};
use wire::frame::pixel_checksum;
use wire::pubsub::SlicePublisher;
use wire::{services, FrameHeader, GroundTruth, Instance, InstanceError};

/// How to stream.
#[derive(Debug, Clone)]
pub struct StreamSettings {
    /// Frames per second to pace to; `None` streams as fast as the source renders.
    pub fps: Option<f64>,
    /// Stop after this many frames (the source may end earlier).
    pub max_frames: Option<u64>,
}

/// What a stream did.
#[derive(Debug, Clone, PartialEq)]
pub struct StreamReport {
    pub frames_sent: u64,
    pub elapsed_s: f64,
    /// Frames that had no subscriber at the moment they were sent.
    pub frames_unseen: u64,
    /// True when a termination signal (SIGINT, SIGTERM) ended the stream.
    pub interrupted: bool,
}

impl StreamReport {
    pub fn rate_hz(&self) -> f64 {
        if self.elapsed_s > 0.0 {
            self.frames_sent as f64 / self.elapsed_s
        } else {
            0.0
        }
    }
}

#[derive(Debug)]
pub enum StreamError {
    Wire(InstanceError),
    Source(ProducerError),
}

impl std::fmt::Display for StreamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StreamError::Wire(e) => write!(f, "{e}"),
            StreamError::Source(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for StreamError {}

impl From<InstanceError> for StreamError {
    fn from(e: InstanceError) -> Self {
        StreamError::Wire(e)
    }
}

/// Shared memory the `frames` service needs for frames of `width_px` x `height_px` (bytes).
pub fn frames_shm_bytes(width_px: u32, height_px: u32) -> u64 {
    let payload_bytes = width_px as usize * height_px as usize * std::mem::size_of::<u16>();
    services::FRAMES.shm_bytes(std::mem::size_of::<FrameHeader>(), payload_bytes)
}

/// Streams `source` on `instance` until it ends, `max_frames` are sent, or a termination
/// signal arrives. `on_frame` sees each header after it was sent (for progress lines).
pub fn stream(
    source: &mut dyn FrameSource,
    instance: &Instance,
    settings: &StreamSettings,
    mut on_frame: impl FnMut(&FrameHeader),
) -> Result<StreamReport, StreamError> {
    let dims = source.dims();
    wire::shm::ensure_free(
        wire::shm::SHM_PATH,
        frames_shm_bytes(dims.width, dims.height),
    )?;
    let (node, _dead_nodes_cleaned) = instance.create_node("producer")?;
    let publisher: SlicePublisher<u16, FrameHeader> =
        SlicePublisher::create(&node, &services::FRAMES, dims.len_px())?;

    let period = settings
        .fps
        .filter(|fps| *fps > 0.0)
        .map(|fps| Duration::from_secs_f64(1.0 / fps));
    let start = Instant::now();
    let mut report = StreamReport {
        frames_sent: 0,
        elapsed_s: 0.0,
        frames_unseen: 0,
        interrupted: false,
    };
    let limit = settings.max_frames.unwrap_or(u64::MAX);
    while report.frames_sent < limit {
        if let Some(period) = period {
            let due = start + period.mul_f64(report.frames_sent as f64);
            let now = Instant::now();
            // `node.wait` sleeps and returns early with an error on SIGINT/SIGTERM.
            if due > now && node.wait(due - now).is_err() {
                report.interrupted = true;
                break;
            }
        } else if node.wait(Duration::ZERO).is_err() {
            report.interrupted = true;
            break;
        }
        let frame_id = report.frames_sent;
        let mut sent_header = FrameHeader::default();
        let outcome = publisher.publish(dims.len_px(), |header, pixels| {
            let t_capture_ns = wire::monotonic_ns();
            let info = match source.next_frame(pixels)? {
                Some(info) => info,
                None => return Ok(false),
            };
            *header = FrameHeader {
                frame_id,
                t_capture_ns,
                width_px: dims.width,
                height_px: dims.height,
                bit_depth: dims.bit_depth as u32,
                pixel_checksum: pixel_checksum(pixels),
                ..FrameHeader::default()
            };
            if let Some(truth) = info.truth {
                header.scenario_id = truth.scenario_id;
                header.has_truth = 1;
                header.truth = GroundTruth {
                    deformation_gradient: [
                        truth.f[0][0],
                        truth.f[0][1],
                        truth.f[1][0],
                        truth.f[1][1],
                    ],
                    translation_px: truth.translation_px,
                    centre_px: truth.centre_px,
                };
            }
            sent_header = *header;
            Ok::<_, ProducerError>(true)
        })?;
        match outcome {
            Ok(Some(0)) => report.frames_unseen += 1,
            Ok(Some(_)) => {}
            // The source ended: the loaned sample went back unsent.
            Ok(None) => break,
            Err(e) => return Err(StreamError::Source(e)),
        }
        report.frames_sent += 1;
        on_frame(&sent_header);
    }
    report.elapsed_s = start.elapsed().as_secs_f64();
    Ok(report)
}
