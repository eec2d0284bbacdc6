//! The real-camera loop of the producer (feature `genicam`), on producer's stream [`Shell`]: opens the camera (a camera
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

use super::device::{Acquisition, Frame, GenicamError};
use producer::genicam::{
    convert_into, BufferCounts, CameraSettings, CameraSpec, Link, PixelFormat, Trigger,
};
use producer::stream::{Shell, StreamError, StreamEvent, StreamReport, StreamSettings};
use producer::{FrameDims, FrameInfo};
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

/// Why the camera's stream could not start or stopped: the shared memory or the stream's
/// shell, the camera, or a camera back with another shape.
#[derive(Debug, thiserror::Error)]
pub enum CameraStreamError {
    #[error(transparent)]
    Stream(#[from] StreamError),
    #[error(transparent)]
    Camera(#[from] GenicamError),
    /// The camera came back with another image size or format than the stream was opened
    /// with: the frames service cannot change shape mid-run.
    #[error("camera {id} came back with {now}, the stream was opened with {before}: restart the producer")]
    CameraChanged {
        id: String,
        before: String,
        now: String,
    },
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
) -> Result<(StreamReport, CameraReport), CameraStreamError> {
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
    let mut cam = CameraLoop {
        spec,
        camera,
        dims,
        format,
        period: camera.expected_period(),
        link: Link::new(Instant::now()),
        next_trigger: Instant::now(),
        report: CameraReport {
            id: first.id().to_string(),
            ..CameraReport::default()
        },
        acquisition: Some(first),
    };
    while !shell.done() {
        if wire::signals::requested().is_some() {
            shell.interrupted();
            break;
        }
        let Some(acq) = cam.acquisition.take() else {
            cam.reconnect(&mut on_note)?;
            continue;
        };
        match cam.serve(&acq, &mut shell, &mut on_event, &mut on_note)? {
            None => cam.acquisition = Some(acq),
            Some(reason) => cam.lose(acq, &reason, &mut on_note),
        }
    }
    let camera_report = cam.finish();
    Ok((shell.finish(), camera_report))
}

/// The camera side of the loop: the camera asked for and its shape, the link's state, the
/// open acquisition (none while lost) and the counts.
struct CameraLoop<'a> {
    spec: &'a CameraSpec,
    camera: &'a CameraSettings,
    /// The stream's frame size, fixed by the first opening.
    dims: FrameDims,
    format: PixelFormat,
    /// The camera's expected frame period, if known.
    period: Option<Duration>,
    link: Link,
    acquisition: Option<Acquisition>,
    /// When the software trigger fires next.
    next_trigger: Instant,
    report: CameraReport,
}

impl CameraLoop<'_> {
    /// Lost: waits for the next attempt (in slices, so a signal is seen), then tries to open
    /// the camera again. A camera back with another shape is an error.
    fn reconnect(
        &mut self,
        on_note: &mut impl FnMut(&CameraNote),
    ) -> Result<(), CameraStreamError> {
        let now = Instant::now();
        let wait = self.link.until_attempt(now).unwrap_or_default();
        if !wait.is_zero() {
            std::thread::sleep(wait.min(POLL));
            return Ok(());
        }
        match Acquisition::open(self.spec, self.camera) {
            Ok(acq) => {
                let (width_px, height_px) = (self.dims.width, self.dims.height);
                if acq.size_px() != (width_px, height_px) || acq.format() != self.format {
                    return Err(CameraStreamError::CameraChanged {
                        id: acq.id().to_string(),
                        before: format!("{width_px}x{height_px} {}", self.format),
                        now: format!("{}x{} {}", acq.size_px().0, acq.size_px().1, acq.format()),
                    });
                }
                let away = self.link.reconnected(Instant::now());
                on_note(&CameraNote::Reconnected { id: acq.id(), away });
                self.next_trigger = Instant::now();
                self.acquisition = Some(acq);
            }
            Err(error) => {
                let (attempt, retry_in) = self.link.attempt_failed(Instant::now());
                on_note(&CameraNote::RetryFailed {
                    attempt,
                    retry_in,
                    error: &error,
                });
            }
        }
        Ok(())
    }

    /// One turn with the camera open: triggers if it is time, publishes the buffer that
    /// arrives within the wait, if any. Some(reason) when the camera is lost.
    fn serve(
        &mut self,
        acq: &Acquisition,
        shell: &mut Shell,
        on_event: &mut impl FnMut(StreamEvent),
        on_note: &mut impl FnMut(&CameraNote),
    ) -> Result<Option<String>, CameraStreamError> {
        let (timeout, trigger_failed) = self.trigger(acq);
        if trigger_failed.is_some() {
            return Ok(trigger_failed);
        }
        if let Some(frame) = acq.next_frame(timeout) {
            let host_receive_ns = wire::monotonic_ns();
            self.link.buffer_arrived(Instant::now());
            let published = self.publish(&frame, host_receive_ns, shell, on_event, on_note)?;
            if !published {
                on_note(&CameraNote::Skipped {
                    counts: self.report.counts,
                });
            }
            acq.requeue(frame);
        }
        Ok(if acq.control_lost() {
            Some("the driver lost control of it (no heartbeat reply)".into())
        } else if self.link.silent_too_long(Instant::now(), self.period) {
            Some(format!(
                "no buffer for {} s while it should be sending",
                producer::genicam::SILENCE.as_secs()
            ))
        } else {
            None
        })
    }

    /// With the software trigger, fires it when due; the longest wait for a buffer, and the
    /// reason the camera is lost if the trigger failed.
    fn trigger(&mut self, acq: &Acquisition) -> (Duration, Option<String>) {
        if self.camera.trigger != Trigger::Software {
            return (POLL, None);
        }
        let mut lost_reason = None;
        let now = Instant::now();
        if now >= self.next_trigger {
            if let Err(e) = acq.software_trigger() {
                lost_reason = Some(e.to_string());
            }
            let step = self.period.unwrap_or(POLL);
            self.next_trigger += step;
            if self.next_trigger < now {
                self.next_trigger = now + step;
            }
        }
        let timeout = POLL.min(self.next_trigger.saturating_duration_since(now));
        (timeout, lost_reason)
    }

    /// Counts `frame` and, if complete and of the stream's shape, converts it into a loaned
    /// slice and sends it; true when it was published.
    fn publish(
        &mut self,
        frame: &Frame,
        host_receive_ns: u64,
        shell: &mut Shell,
        on_event: &mut impl FnMut(StreamEvent),
        on_note: &mut impl FnMut(&CameraNote),
    ) -> Result<bool, CameraStreamError> {
        if !self.report.counts.count(frame.status, frame.shape_ok) {
            return Ok(false);
        }
        let index = self.report.counts.published - 1;
        let (format, dims) = (self.format, self.dims);
        let mut converted = true;
        let sent =
            shell.publish_stamped(Some(host_receive_ns), frame.camera_timestamp_ns, |pixels| {
                if convert_into(format, frame.bytes(), dims.width, dims.height, pixels).is_err() {
                    converted = false;
                    return Ok(None);
                }
                Ok(Some(FrameInfo {
                    index,
                    truth: None,
                    rig_sample_id: None,
                    sequence_id: 0,
                }))
            })?;
        let Some(header) = sent else {
            // Counted as published, found short while copying: move it.
            debug_assert!(!converted);
            self.report.counts.published -= 1;
            self.report.counts.wrong_shape += 1;
            return Ok(false);
        };
        on_event(StreamEvent::Frame(&header));
        on_note(&CameraNote::Frame {
            frame_id: header.frame_id,
            camera_frame_id: frame.camera_frame_id,
            camera_timestamp_ns: frame.camera_timestamp_ns,
            host_receive_ns,
        });
        Ok(true)
    }

    /// The camera is lost for `reason`: its acquisition is closed, reconnection follows.
    fn lose(&mut self, acq: Acquisition, reason: &str, on_note: &mut impl FnMut(&CameraNote)) {
        self.link.lost(Instant::now());
        self.report.driver_underruns += acq.underruns();
        on_note(&CameraNote::Lost {
            id: acq.id(),
            reason,
        });
        drop(acq);
    }

    /// The report; the acquisition is closed on return.
    fn finish(mut self) -> CameraReport {
        if let Some(acq) = &self.acquisition {
            self.report.driver_underruns += acq.underruns();
        }
        self.report.ended_lost = self.acquisition.is_none();
        self.report.losses = self.link.losses;
        self.report.reconnections = self.link.reconnections;
        self.report
    }
}
