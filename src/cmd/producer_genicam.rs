//! `dicstream producer --camera genicam[:ID]`: a real GenICam camera (GigE Vision, USB3
//! Vision) through Aravis, published on `frames`. The options exist in every build (so `--help`
//! and `dicstream run` configs show them); using them needs the `genicam` feature.
//!
//! The header's `t_capture_ns` is the host's receive time (monotonic clock, when the driver
//! hands the complete buffer over); the camera's own timestamp (its clock) goes beside the
//! frame, with `--log FILE`: one CSV row per frame (`frame_id,camera_frame_id,
//! camera_timestamp_ns,host_receive_ns`). A lost camera is reported on stderr and reopened
//! with backoff; the final line counts published, skipped and lost.

use std::path::PathBuf;

use producer::genicam::{CameraSettings, CameraSpec, PixelFormat, Roi, Trigger};
use producer::stream::{StreamEvent, StreamReport, StreamSettings};

/// The header of the `--log` CSV for a camera.
#[cfg_attr(not(feature = "genicam"), allow(dead_code))]
pub const LOG_HEADER: &str = "frame_id,camera_frame_id,camera_timestamp_ns,host_receive_ns";

/// The camera options of `dicstream producer`.
#[derive(Debug, clap::Args)]
pub struct CameraArgs {
    /// Publish a real GenICam camera: `genicam` (the first found) or `genicam:ID` (an id from
    /// `dicstream cameras`); needs a build with the `genicam` feature. --fps sets its frame
    /// rate (free-running) or trigger rate (software trigger); 0 leaves the camera's
    #[arg(long, value_name = "genicam[:ID]", conflicts_with_all = ["scenario", "params", "width", "height", "follow_rig", "replay", "watch"])]
    pub camera: Option<CameraSpec>,
    /// With --camera: exposure time, µs (turns auto exposure off)
    #[arg(long, value_name = "US", requires = "camera")]
    pub exposure_us: Option<f64>,
    /// With --camera: analog gain, dB (turns auto gain off)
    #[arg(
        long,
        value_name = "DB",
        requires = "camera",
        allow_negative_numbers = true
    )]
    pub gain_db: Option<f64>,
    /// With --camera: pixel format, Mono8|Mono10|Mono12|Mono16 (also the packed Mono10p,
    /// Mono12p, Mono12Packed); published as 16-bit values with that bit depth [default: the
    /// camera's, if monochrome]
    #[arg(long, value_name = "FORMAT", requires = "camera")]
    pub pixel_format: Option<PixelFormat>,
    /// With --camera: region of interest x,y,w,h in px, checked against the sensor and the
    /// camera's steps [default: the camera's]
    #[arg(long, value_name = "X,Y,W,H", requires = "camera")]
    pub roi: Option<Roi>,
    /// With --camera: free (the camera runs at --fps), software (the producer triggers each
    /// frame at --fps), hardware (an external pulse on Line1 triggers each frame; --fps does
    /// not apply)
    #[arg(long, value_name = "MODE", default_value = "free", requires = "camera")]
    pub trigger: Trigger,
}

/// What the camera process streams from a GenICam camera.
#[cfg_attr(not(feature = "genicam"), allow(dead_code))]
pub struct GenicamArgs<'a> {
    pub spec: &'a CameraSpec,
    pub camera: &'a CameraSettings,
    pub log: Option<&'a PathBuf>,
}

impl CameraArgs {
    /// The camera's settings of the flags, `fps` the rate asked (`--fps`; 0, or a hardware
    /// trigger: the camera's own).
    pub fn settings(&self, fps: f64) -> CameraSettings {
        CameraSettings {
            exposure_us: self.exposure_us,
            gain_db: self.gain_db,
            fps: self.trigger.rate_fps(fps),
            pixel_format: self.pixel_format,
            roi: self.roi,
            trigger: self.trigger,
        }
    }
}

/// Streams the camera; returns the report with the final line's source part.
#[cfg(not(feature = "genicam"))]
pub fn run(
    _args: GenicamArgs,
    _instance: &wire::Instance,
    _settings: &StreamSettings,
    _on_event: impl FnMut(StreamEvent),
) -> anyhow::Result<(StreamReport, String)> {
    anyhow::bail!(super::cameras::NO_GENICAM)
}

/// Streams the camera; returns the report with the final line's source part.
#[cfg(feature = "genicam")]
pub fn run(
    args: GenicamArgs,
    instance: &wire::Instance,
    settings: &StreamSettings,
    on_event: impl FnMut(StreamEvent),
) -> anyhow::Result<(StreamReport, String)> {
    use crate::genicam::stream_genicam;

    let camera = args.camera;
    camera.check()?;
    let mut notes = NotePrinter {
        args: &args,
        camera,
        log: super::log_rows::LogRows::create(args.log, LOG_HEADER)?,
        last_status: std::time::Instant::now(),
        published: 0,
        last_frame_id: None,
        id: String::new(),
        first_frame_id: settings.first_frame_id,
    };
    let (report, camera_report) =
        stream_genicam(args.spec, camera, instance, settings, on_event, |note| {
            notes.print(note)
        })?;
    let id = std::mem::take(&mut notes.id);
    notes.log.finish()?;
    Ok((report, summary_line(&id, &camera_report)))
}

/// Prints the camera loop's notes on stderr and writes the frames' rows in the `--log` file.
#[cfg(feature = "genicam")]
struct NotePrinter<'a> {
    args: &'a GenicamArgs<'a>,
    camera: &'a producer::genicam::CameraSettings,
    log: super::log_rows::LogRows,
    last_status: std::time::Instant,
    published: u64,
    last_frame_id: Option<u64>,
    /// The camera's id, once open.
    id: String,
    first_frame_id: u64,
}

#[cfg(feature = "genicam")]
impl NotePrinter<'_> {
    fn print(&mut self, note: &crate::genicam::CameraNote) {
        use crate::genicam::CameraNote;
        use producer::genicam::{FIRST_RETRY, MAX_RETRY};
        match note {
            CameraNote::Opened {
                id,
                format,
                width_px,
                height_px,
            } => self.opened(id, format, (*width_px, *height_px)),
            CameraNote::Frame {
                frame_id,
                camera_frame_id,
                camera_timestamp_ns,
                host_receive_ns,
            } => {
                self.log.append(|| {
                    format!(
                        "{frame_id},{camera_frame_id},{camera_timestamp_ns},{host_receive_ns}\n"
                    )
                });
                self.frame(*frame_id);
            }
            CameraNote::Skipped { counts } => {
                let skipped = counts.skipped();
                // The first one, then at 10, 100, 1000...: visible, never a flood.
                if is_power_of_ten(skipped) {
                    eprintln!(
                        "producer: camera buffer skipped, not published ({} incomplete, {} \
                         failed, {} of the wrong size or format so far)",
                        counts.incomplete, counts.failed, counts.wrong_shape
                    );
                }
            }
            // `dicstream run` reads the lost / attempt / reconnected lines below
            // (`live::camera_events`): keep their beginnings as they are.
            CameraNote::Lost { id, reason } => eprintln!(
                "producer: camera {id} lost: {reason}; reconnecting (first attempt in {:.1} s, \
                 then backing off up to {} s between attempts); frame ids will go on from {}",
                FIRST_RETRY.as_secs_f64(),
                MAX_RETRY.as_secs(),
                self.last_frame_id.map_or(self.first_frame_id, |f| f + 1)
            ),
            CameraNote::RetryFailed {
                attempt,
                retry_in,
                error,
            } => eprintln!(
                "producer: camera reconnection attempt {attempt} failed: {error}; next in {:.1} s",
                retry_in.as_secs_f64()
            ),
            CameraNote::Reconnected { id, away } => eprintln!(
                "producer: camera {id} reconnected after {:.1} s away",
                away.as_secs_f64()
            ),
        }
    }

    fn opened(&mut self, id: &str, format: &PixelFormat, (width_px, height_px): (u32, u32)) {
        self.id = id.to_string();
        eprintln!(
            "producer: camera {id} open: {width_px}x{height_px} px {format}, trigger \
             {}{}; header t_capture_ns = host receive time (monotonic clock), camera \
             timestamps (the camera's clock) {}",
            self.camera.trigger,
            self.camera
                .fps
                .map_or_else(String::new, |fps| format!(" at {fps} fps")),
            if self.args.log.is_some() {
                "in --log"
            } else {
                "not kept (pass --log FILE)"
            }
        )
    }

    /// A published frame: counted, and a status line every [`STATUS_EVERY`].
    fn frame(&mut self, frame_id: u64) {
        self.published += 1;
        self.last_frame_id = Some(frame_id);
        if self.last_status.elapsed() >= STATUS_EVERY {
            self.last_status = std::time::Instant::now();
            eprintln!(
                "producer: camera status: streaming, {} frame(s) published, last frame \
                 {frame_id}",
                self.published
            );
        }
    }
}

/// Seconds between two status lines while frames flow.
#[cfg(feature = "genicam")]
const STATUS_EVERY: std::time::Duration = std::time::Duration::from_secs(5);

/// The final line's source part: the camera's buffers, losses and reconnections.
#[cfg(feature = "genicam")]
fn summary_line(id: &str, report: &crate::genicam::CameraReport) -> String {
    let c = report.counts;
    format!(
        "camera {id}: {} buffer(s) published, {} skipped ({} incomplete, {} failed, {} of the \
         wrong size or format), {} dropped by the driver (no free buffer), lost {} time(s), \
         reconnected {} time(s){}",
        c.published,
        c.skipped(),
        c.incomplete,
        c.failed,
        c.wrong_shape,
        report.driver_underruns,
        report.losses,
        report.reconnections,
        if report.ended_lost {
            "; ended while the camera was lost"
        } else {
            ""
        }
    )
}

/// 1, 10, 100, ...: when a count is worth a line.
#[cfg_attr(not(feature = "genicam"), allow(dead_code))]
fn is_power_of_ten(mut n: u64) -> bool {
    while n >= 10 && n.is_multiple_of(10) {
        n /= 10;
    }
    n == 1
}

#[cfg(test)]
mod tests {
    #[test]
    fn skipped_buffers_are_reported_at_powers_of_ten() {
        let reported: Vec<u64> = (0..=1000).filter(|&n| super::is_power_of_ten(n)).collect();
        assert_eq!(reported, [1, 10, 100, 1000]);
    }
}
