//! The real-camera loop of the producer shell (feature `genicam`): opens the camera (a camera
//! that cannot be opened or set up is an error before anything is published), opens the
//! `frames` publisher with the camera's image size, then copies each complete buffer once,
//! converting, into a loaned slice and sends it. Incomplete, failed or misshapen buffers are
//! counted and given back unpublished. A lost camera (the driver's control-lost signal, or
//! silence while it should be sending) is dropped and reopened with backoff; frame ids go on
//! consecutively across the gap. Consumers never hold the camera up: publishing never waits
//! (safe overflow), and the driver keeps its own queue of buffers.
//!
//! Clocks: the header's `t_capture_ns` is the host's receive time, [`wire::monotonic_ns`]
//! taken when the driver hands the complete buffer over, so a consumer's latency is from the
//! frame's arrival on the host (exposure, readout and transfer come before it). The camera's
//! own timestamp (its clock, its epoch) is the header's `t_camera_ns`, and goes beside the
//! frame too, in [`CameraNote::Frame`] (the `--log` rows).

use std::time::{Duration, Instant};

use super::{Shell, StreamError, StreamEvent, StreamReport, StreamSettings};
use crate::genicam::device::{Acquisition, GenicamError};
use crate::genicam::{
    convert_into, BufferCounts, CameraSettings, CameraSpec, Link, PixelFormat, Trigger,
};
use crate::{FrameDims, FrameInfo};
use wire::Instance;

/// Longest single wait for a buffer: signals and the link are looked at within it.
const POLL: Duration = Duration::from_millis(100);

/// What the camera loop tells its caller as it goes.
#[derive(Debug)]
pub enum CameraNote<'a> {
    /// The camera is open and streaming.
    Opened {
        id: &'a str,
        format: PixelFormat,
        width_px: u32,
        height_px: u32,
    },
    /// A frame was published.
    Frame {
        frame_id: u64,
        camera_frame_id: u64,
        /// The camera's timestamp, ns on its own clock.
        camera_timestamp_ns: u64,
        /// Host receive time, [`wire::monotonic_ns`] (the header's `t_capture_ns`).
        host_receive_ns: u64,
    },
    /// A buffer was skipped (not published); `counts` after it.
    Skipped { counts: BufferCounts },
    /// The camera is gone; reconnection attempts follow.
    Lost { id: &'a str, reason: &'a str },
    /// A reconnection attempt failed; the next one in `retry_in`.
    RetryFailed {
        attempt: u32,
        retry_in: Duration,
        error: &'a GenicamError,
    },
    /// The camera is back after `away`.
    Reconnected { id: &'a str, away: Duration },
}

/// What the camera loop did, beside the stream's report.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CameraReport {
    pub id: String,
    pub counts: BufferCounts,
    pub losses: u64,
    pub reconnections: u64,
    /// Frames the driver dropped because every buffer was taken (summed over connections).
    pub driver_underruns: u64,
    /// True when the run ended while the camera was lost.
    pub ended_lost: bool,
}

/// Streams the camera `spec` set up with `camera` on `instance` until `max_frames` are sent or
/// a termination signal arrives. `settings.fps` does not pace (the camera, or the software
/// trigger at `camera.fps`, does).
pub fn stream_genicam(
    spec: &CameraSpec,
    camera: &CameraSettings,
    instance: &Instance,
    settings: &StreamSettings,
    mut on_event: impl FnMut(StreamEvent),
    mut on_note: impl FnMut(&CameraNote),
) -> Result<(StreamReport, CameraReport), StreamError> {
    let first = Acquisition::open(spec, camera)?;
    let (width_px, height_px) = first.size_px();
    let format = first.format();
    on_note(&CameraNote::Opened {
        id: first.id(),
        format,
        width_px,
        height_px,
    });
    let dims = FrameDims {
        width: width_px,
        height: height_px,
        bit_depth: format.bit_depth(),
    };
    let unpaced = StreamSettings {
        fps: None,
        ..settings.clone()
    };
    let mut shell = Shell::open(instance, dims, &unpaced, &mut on_event)?;
    let mut report = CameraReport {
        id: first.id().to_string(),
        ..CameraReport::default()
    };
    let period = camera.expected_period();
    let mut link = Link::new(Instant::now());
    let mut acquisition = Some(first);
    let mut next_trigger = Instant::now();

    while !shell.done() {
        if wire::signals::requested().is_some() {
            shell.report.interrupted = true;
            break;
        }
        let Some(acq) = acquisition.as_ref() else {
            // Lost: wait for the next attempt (in slices, so a signal is seen), then try.
            let now = Instant::now();
            let wait = link.until_attempt(now).unwrap_or_default();
            if !wait.is_zero() {
                std::thread::sleep(wait.min(POLL));
                continue;
            }
            match Acquisition::open(spec, camera) {
                Ok(acq) => {
                    if acq.size_px() != (width_px, height_px) || acq.format() != format {
                        return Err(StreamError::CameraChanged {
                            id: acq.id().to_string(),
                            before: format!("{width_px}x{height_px} {format}"),
                            now: format!(
                                "{}x{} {}",
                                acq.size_px().0,
                                acq.size_px().1,
                                acq.format()
                            ),
                        });
                    }
                    let away = link.reconnected(Instant::now());
                    on_note(&CameraNote::Reconnected { id: acq.id(), away });
                    next_trigger = Instant::now();
                    acquisition = Some(acq);
                }
                Err(error) => {
                    let (attempt, retry_in) = link.attempt_failed(Instant::now());
                    on_note(&CameraNote::RetryFailed {
                        attempt,
                        retry_in,
                        error: &error,
                    });
                }
            }
            continue;
        };

        let mut timeout = POLL;
        let mut lost_reason = None;
        if camera.trigger == Trigger::Software {
            let now = Instant::now();
            if now >= next_trigger {
                if let Err(e) = acq.software_trigger() {
                    lost_reason = Some(e.to_string());
                }
                let step = period.unwrap_or(POLL);
                next_trigger += step;
                if next_trigger < now {
                    next_trigger = now + step;
                }
            }
            timeout = timeout.min(next_trigger.saturating_duration_since(now));
        }
        if lost_reason.is_none() {
            if let Some(frame) = acq.next_frame(timeout) {
                let host_receive_ns = wire::monotonic_ns();
                link.buffer_arrived(Instant::now());
                let mut publish = report.counts.count(frame.status, frame.shape_ok);
                if publish {
                    let index = report.counts.published - 1;
                    let mut converted = true;
                    let sent = shell.publish_stamped(
                        Some(host_receive_ns),
                        frame.camera_timestamp_ns,
                        |pixels| {
                            if convert_into(format, frame.bytes(), width_px, height_px, pixels)
                                .is_err()
                            {
                                converted = false;
                                return Ok(None);
                            }
                            Ok(Some(FrameInfo {
                                index,
                                truth: None,
                                rig_sample_id: None,
                                sequence_id: 0,
                            }))
                        },
                    )?;
                    match sent {
                        Some(header) => {
                            on_event(StreamEvent::Frame(&header));
                            on_note(&CameraNote::Frame {
                                frame_id: header.frame_id,
                                camera_frame_id: frame.camera_frame_id,
                                camera_timestamp_ns: frame.camera_timestamp_ns,
                                host_receive_ns,
                            });
                        }
                        None => {
                            // Counted as published, found short while copying: move it.
                            debug_assert!(!converted);
                            report.counts.published -= 1;
                            report.counts.wrong_shape += 1;
                            publish = false;
                        }
                    }
                }
                if !publish {
                    on_note(&CameraNote::Skipped {
                        counts: report.counts,
                    });
                }
                acq.requeue(frame);
            }
            if acq.control_lost() {
                lost_reason = Some("the driver lost control of it (no heartbeat reply)".into());
            } else if link.silent_too_long(Instant::now(), period) {
                lost_reason = Some(format!(
                    "no buffer for {} s while it should be sending",
                    crate::genicam::SILENCE.as_secs()
                ));
            }
        }
        if let Some(reason) = lost_reason {
            link.lost(Instant::now());
            report.driver_underruns += acq.underruns();
            on_note(&CameraNote::Lost {
                id: acq.id(),
                reason: &reason,
            });
            acquisition = None;
        }
    }
    if let Some(acq) = acquisition.as_ref() {
        report.driver_underruns += acq.underruns();
    }
    report.ended_lost = acquisition.is_none();
    report.losses = link.losses;
    report.reconnections = link.reconnections;
    drop(acquisition);
    Ok((shell.finish(), report))
}
