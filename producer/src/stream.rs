//! The producer process shell: renders frames straight into loaned shared-memory slices of the
//! `frames` service, stamps the header, paces to the requested rate and never waits for a
//! consumer (safe overflow: a slow or dead reader loses frames, the camera never blocks).
//!
//! The loops share the same shell: [`stream`] pulls a [`FrameSource`] (scenario, replay),
//! [`stream_following_rig`] subscribes to `rig/state` and renders each frame from the most
//! recent rig sample with a [`RigCamera`], and [`stream_watched`] (`stream/watched.rs`)
//! publishes the images of a watched folder as they become complete. The [`Shell`] is public:
//! the binary's real-camera loop (feature `genicam`, `src/genicam/stream.rs`) drives it, so
//! Aravis stays out of this crate. Everything else (rendering, the rig kinematics, the
//! envelope, the folder watcher) lives in the pure modules.

use crate::{FrameDims, FrameInfo, FrameSource, NextMotion, ProducerError, RigCamera};
use iceoryx2::prelude::*;
use std::time::{Duration, Instant};
use wire::frame::pixel_checksum;
use wire::pubsub::{SlicePublisher, SliceSubscriber, ValueSubscriber};
use wire::{services, FrameHeader, GroundTruth, Instance, InstanceError, RigState};

mod watched;
pub use watched::stream_watched;

/// Longest sleep while waiting for the first rig sample (a signal is seen within it).
const RIG_WAIT_SLICE: Duration = Duration::from_millis(200);

/// How to stream.
#[derive(Debug, Clone)]
pub struct StreamSettings {
    /// Frames per second to pace to; `None` streams as fast as the source renders.
    pub fps: Option<f64>,
    /// Stop after this many frames (the source may end earlier).
    pub max_frames: Option<u64>,
    /// Id of the first frame (ids are consecutive from it): a restarted camera continues the
    /// numbering of the one it replaces, so consumers see no id going back.
    pub first_frame_id: u64,
}

impl crate::settings::ProducerSettings {
    /// How its frames are streamed.
    pub fn stream(&self) -> StreamSettings {
        StreamSettings {
            fps: self.fps,
            max_frames: self.max_frames,
            first_frame_id: self.first_frame_id,
        }
    }
}

/// What a stream did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StreamReport {
    pub frames_sent: u64,
    /// From the first frame slot (after the first rig sample when following the rig) to the end.
    pub elapsed_s: f64,
    /// From the first frame sent to the last one.
    pub send_span_s: f64,
    /// Frames that had no subscriber at the moment they were sent.
    pub frames_unseen: u64,
    /// Frame slots skipped because the rig state lay outside the camera's envelope.
    pub frames_beyond_envelope: u64,
    /// Rig samples received (following the rig only).
    pub rig_samples_received: u64,
    /// The rig sample of the last frame sent (following the rig only).
    pub last_rig_sample_id: Option<u64>,
    /// True when a termination signal (SIGINT, SIGTERM, SIGHUP) ended the stream.
    pub interrupted: bool,
}

impl StreamReport {
    /// Frames per second actually sent: frame intervals over the time between the first and
    /// the last frame (frames over the elapsed time when fewer than two were sent).
    pub fn rate_hz(&self) -> f64 {
        if self.frames_sent >= 2 && self.send_span_s > 0.0 {
            (self.frames_sent - 1) as f64 / self.send_span_s
        } else if self.elapsed_s > 0.0 {
            self.frames_sent as f64 / self.elapsed_s
        } else {
            0.0
        }
    }
}

/// What the shell tells its caller as it goes (for the command's messages).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StreamEvent<'a> {
    /// The publisher exists: consumers may connect. `dead_nodes_cleaned` of the instance's
    /// dead processes were cleaned first.
    Ready {
        dims: FrameDims,
        dead_nodes_cleaned: usize,
    },
    /// A frame was sent.
    Frame(&'a FrameHeader),
    /// Following the rig: no rig sample has arrived yet; the camera waits for one.
    WaitingForRig,
    /// Following the rig: the first rig sample arrived, frames start.
    RigArrived { sample_id: u64 },
    /// Following the rig: the rig state of this frame slot lies outside the camera's envelope;
    /// the slot is skipped. `first` is true the first time it happens in a row.
    RigBeyond {
        sample_id: u64,
        reason: crate::rig_follow::BeyondEnvelope,
        first: bool,
    },
}

/// Why the camera's stream could not start or stopped: the shared memory, or its source.
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    #[error(transparent)]
    Wire(#[from] InstanceError),
    #[error(transparent)]
    Source(#[from] ProducerError),
    /// The process's WaitSet could not be made (for want of descriptors: exit 71).
    #[error("{0}")]
    WaitSet(#[from] wire::resources::WaitSetError),
    /// A `specimen` sample the camera cannot read (another layout, a malformed mesh).
    #[error("specimen state refused: {0}")]
    Specimen(#[from] crate::specimen_states::StateError),
}

/// Shared memory the `frames` service needs for frames of `width_px` x `height_px` (bytes).
pub fn frames_shm_bytes(width_px: u32, height_px: u32) -> u64 {
    let payload_bytes = width_px as usize * height_px as usize * std::mem::size_of::<u16>();
    services::FRAMES.shm_bytes(std::mem::size_of::<FrameHeader>(), payload_bytes)
}

/// Fails with a clear error unless `/dev/shm` can hold the `frames` service for frames of this
/// size. Call it before building anything large (the camera's texture).
pub fn check_shm_for_frames(width_px: u32, height_px: u32) -> Result<(), InstanceError> {
    wire::shm::ensure_free(wire::shm::SHM_PATH, frames_shm_bytes(width_px, height_px))
}

/// The part every source's loop shares: node, publisher, pacing, header stamping, the report.
/// Public for a loop that drives its own source, e.g. the binary's real-camera loop (feature
/// `genicam`, `src/genicam/stream.rs`), which keeps Aravis out of this crate.
pub struct Shell {
    /// The camera's claim on the instance (one producer per instance).
    _owner: wire::owner::Owner,
    node: Node<ipc::Service>,
    publisher: SlicePublisher<u16, FrameHeader>,
    dims: FrameDims,
    period: Option<Duration>,
    start: Instant,
    /// Frame slots elapsed (sent or skipped): the pacing clock.
    slots: u64,
    /// When the first frame was sent.
    first_sent: Option<Instant>,
    limit: u64,
    first_frame_id: u64,
    report: StreamReport,
}

impl Shell {
    pub fn open(
        instance: &Instance,
        dims: FrameDims,
        settings: &StreamSettings,
        on_event: &mut dyn FnMut(StreamEvent),
    ) -> Result<Shell, StreamError> {
        check_shm_for_frames(dims.width, dims.height)?;
        let owner = instance.claim("producer")?;
        let (node, dead_nodes_cleaned) = instance.create_node("producer")?;
        let publisher = SlicePublisher::create(&node, &services::FRAMES, dims.len_px())?;
        on_event(StreamEvent::Ready {
            dims,
            dead_nodes_cleaned,
        });
        Ok(Shell {
            _owner: owner,
            node,
            publisher,
            dims,
            period: settings
                .fps
                .filter(|fps| *fps > 0.0 && fps.is_finite())
                .map(|fps| Duration::from_secs_f64(1.0 / fps)),
            start: Instant::now(),
            slots: 0,
            first_sent: None,
            limit: settings.max_frames.unwrap_or(u64::MAX),
            first_frame_id: settings.first_frame_id,
            report: StreamReport::default(),
        })
    }

    pub fn done(&self) -> bool {
        self.report.frames_sent >= self.limit
    }

    /// Restarts the pacing clock (when frames start late, e.g. after the first rig sample).
    pub fn restart_clock(&mut self) {
        self.start = Instant::now();
        self.slots = 0;
    }

    /// Sleeps until the next frame slot is due (`node.wait` returns early on a signal, and a
    /// wake-up that is not a termination request sleeps again). False when a termination signal
    /// arrived.
    pub fn wait_for_slot(&mut self) -> bool {
        let due = self
            .period
            .map(|period| self.start + period.mul_f64(self.slots as f64));
        loop {
            if wire::signals::requested().is_some() {
                self.report.interrupted = true;
                return false;
            }
            let pause = due.map_or(Duration::ZERO, |due| {
                due.saturating_duration_since(Instant::now())
            });
            if pause.is_zero() {
                break;
            }
            let _ = self.node.wait(pause);
        }
        self.slots += 1;
        true
    }

    /// Loans a slice, lets `render` write the pixels, stamps the header and sends it. `None`
    /// when `render` says the source has ended (the loan goes back unsent).
    pub fn publish(
        &mut self,
        render: impl FnOnce(&mut [u16]) -> Result<Option<FrameInfo>, ProducerError>,
    ) -> Result<Option<FrameHeader>, StreamError> {
        self.publish_stamped(None, 0, render)
    }

    /// [`Shell::publish`] with the capture time given (a real camera's host receive time,
    /// [`wire::monotonic_ns`]) instead of read when the slice is loaned, and the camera's own
    /// timestamp (`FrameHeader::t_camera_ns`, 0 for none).
    pub fn publish_stamped(
        &mut self,
        t_capture_ns: Option<u64>,
        t_camera_ns: u64,
        render: impl FnOnce(&mut [u16]) -> Result<Option<FrameInfo>, ProducerError>,
    ) -> Result<Option<FrameHeader>, StreamError> {
        let frame_id = self.first_frame_id + self.report.frames_sent;
        let dims = self.dims;
        let mut sent_header = FrameHeader::default();
        let outcome = self.publisher.publish(dims.len_px(), |header, pixels| {
            let t_capture_ns = t_capture_ns.unwrap_or_else(wire::monotonic_ns);
            let Some(info) = render(pixels)? else {
                return Ok(false);
            };
            *header = FrameHeader {
                frame_id,
                t_capture_ns,
                t_camera_ns,
                width_px: dims.width,
                height_px: dims.height,
                bit_depth: u32::from(dims.bit_depth),
                rig_sample_id: info.rig_sample_id.unwrap_or(wire::NO_RIG_SAMPLE),
                sequence_id: info.sequence_id,
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
                    ..GroundTruth::IDENTITY
                };
                if let Some((solve_id, grip_mm)) = truth.specimen {
                    header.truth.specimen_solve_id = solve_id;
                    header.truth.specimen_grip_mm = grip_mm;
                }
            }
            sent_header = *header;
            Ok::<_, ProducerError>(true)
        })?;
        match outcome? {
            None => return Ok(None),
            Some(0) => self.report.frames_unseen += 1,
            Some(_) => {}
        }
        self.report.frames_sent += 1;
        let first_sent = *self.first_sent.get_or_insert_with(Instant::now);
        self.report.send_span_s = first_sent.elapsed().as_secs_f64();
        if sent_header.rig_sample_id != wire::NO_RIG_SAMPLE {
            self.report.last_rig_sample_id = Some(sent_header.rig_sample_id);
        }
        Ok(Some(sent_header))
    }

    /// Marks the stream as ended by a termination signal (a loop that waits on its own).
    pub fn interrupted(&mut self) {
        self.report.interrupted = true;
    }

    pub fn finish(mut self) -> StreamReport {
        self.report.elapsed_s = self.start.elapsed().as_secs_f64();
        self.report
    }
}

/// Streams `source` on `instance` until it ends, `max_frames` are sent, or a termination
/// signal arrives.
pub fn stream(
    source: &mut dyn FrameSource,
    instance: &Instance,
    settings: &StreamSettings,
    mut on_event: impl FnMut(StreamEvent),
) -> Result<StreamReport, StreamError> {
    let mut shell = Shell::open(instance, source.dims(), settings, &mut on_event)?;
    while !shell.done() && shell.wait_for_slot() {
        match shell.publish(|pixels| source.next_frame(pixels))? {
            Some(header) => on_event(StreamEvent::Frame(&header)),
            None => break,
        }
    }
    Ok(shell.finish())
}

/// Streams the rig-driven `camera` on `instance`: subscribes to `rig/state`, waits (in a
/// WaitSet, no polling) for the first rig sample, then renders each frame slot from the most
/// recent sample until `max_frames` are sent or a termination signal arrives. A slot whose rig
/// state lies outside the camera's envelope is skipped and counted, never clamped.
pub fn stream_following_rig(
    camera: &mut RigCamera,
    instance: &Instance,
    settings: &StreamSettings,
    mut on_event: impl FnMut(StreamEvent),
) -> Result<StreamReport, StreamError> {
    let mut shell = Shell::open(instance, camera.dims(), settings, &mut on_event)?;
    let rig: ValueSubscriber<RigState> =
        ValueSubscriber::create(&shell.node, &services::RIG_STATE)?;
    // A finite-element specimen's solves (a rig of a homogeneous sheet publishes none). Taken
    // before the rig's samples, which name them.
    let specimen: SliceSubscriber<f64, wire::SpecimenHeader> =
        SliceSubscriber::create(&shell.node, &services::SPECIMEN)?;
    let drain = |camera: &mut RigCamera, report: &mut StreamReport| -> Result<(), StreamError> {
        specimen.clear_events();
        while let Some(sample) = specimen.receive()? {
            camera.push_specimen(sample.user_header(), sample.payload())?;
        }
        rig.clear_events();
        while let Some(state) = rig.receive()? {
            camera.push(&state);
            report.rig_samples_received += 1;
        }
        Ok(())
    };

    drain(camera, &mut shell.report)?;
    if camera.follower().latest().is_none() {
        on_event(StreamEvent::WaitingForRig);
        let waitset = wire::signals::waitset()?;
        let _guard = waitset
            .attach_notification(rig.listener())
            .map_err(|e| wait_error(&e))?;
        while camera.follower().latest().is_none() {
            // Wakes on a rig/state event or a signal (bounded, so a signal that lands just
            // before the wait is seen too); the callback only notes the wake-up.
            waitset
                .wait_and_process_once_with_timeout(
                    |_| CallbackProgression::Continue,
                    RIG_WAIT_SLICE,
                )
                .map_err(|e| wait_error(&e))?;
            drain(camera, &mut shell.report)?;
            if wire::signals::requested().is_some() && camera.follower().latest().is_none() {
                shell.report.interrupted = true;
                return Ok(shell.finish());
            }
        }
    }
    if let Some(first) = camera.follower().latest() {
        on_event(StreamEvent::RigArrived {
            sample_id: first.sample_id,
        });
    }
    shell.restart_clock();
    let mut beyond_in_a_row = false;
    while !shell.done() && shell.wait_for_slot() {
        drain(camera, &mut shell.report)?;
        match camera.next_motion() {
            NextMotion::Ready(motion) => {
                beyond_in_a_row = false;
                let header = shell
                    .publish(|pixels| camera.render(&motion, pixels).map(Some))?
                    .expect("a rig-driven frame always renders");
                on_event(StreamEvent::Frame(&header));
            }
            NextMotion::Beyond { sample_id, reason } => {
                shell.report.frames_beyond_envelope += 1;
                on_event(StreamEvent::RigBeyond {
                    sample_id,
                    reason,
                    first: !beyond_in_a_row,
                });
                beyond_in_a_row = true;
            }
            NextMotion::NoSample => unreachable!("a rig sample arrived before the first slot"),
        }
    }
    Ok(shell.finish())
}

fn wait_error(e: &dyn std::fmt::Debug) -> StreamError {
    StreamError::Wire(InstanceError::Service {
        service: services::RIG_STATE.name.to_string(),
        detail: format!("waitset: {e:?}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rate_counts_intervals_between_the_first_and_the_last_frame() {
        let report = StreamReport {
            frames_sent: 31,
            elapsed_s: 3.05,
            send_span_s: 3.0,
            ..StreamReport::default()
        };
        assert!((report.rate_hz() - 10.0).abs() < 1e-12);
        let single = StreamReport {
            frames_sent: 1,
            elapsed_s: 0.5,
            ..StreamReport::default()
        };
        assert!((single.rate_hz() - 2.0).abs() < 1e-12);
        assert_eq!(StreamReport::default().rate_hz(), 0.0);
    }

    #[test]
    fn frames_service_is_sized_from_the_frame() {
        let small = frames_shm_bytes(256, 256);
        let big = frames_shm_bytes(1024, 1024);
        assert!(big > 10 * small, "{small} {big}");
        // Every sample the service may hold at once (per publisher) fits.
        let samples = services::FRAMES.max_publishers * services::FRAMES.pool_samples();
        assert!(big >= samples as u64 * 2 * 1024 * 1024);
    }
}
