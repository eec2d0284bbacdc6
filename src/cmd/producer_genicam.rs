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

use producer::genicam::{CameraSpec, PixelFormat, Roi, Trigger};
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

/// Streams the camera; returns the report with the final line's source part.
#[cfg(not(feature = "genicam"))]
pub fn run(
    _spec: &CameraSpec,
    _args: &CameraArgs,
    _fps: f64,
    _log: Option<&PathBuf>,
    _instance: &wire::Instance,
    _settings: &StreamSettings,
    _on_event: impl FnMut(StreamEvent),
) -> anyhow::Result<(StreamReport, String)> {
    anyhow::bail!(super::cameras::NO_GENICAM)
}

/// Streams the camera; returns the report with the final line's source part.
#[cfg(feature = "genicam")]
pub fn run(
    spec: &CameraSpec,
    args: &CameraArgs,
    fps: f64,
    log: Option<&PathBuf>,
    instance: &wire::Instance,
    settings: &StreamSettings,
    on_event: impl FnMut(StreamEvent),
) -> anyhow::Result<(StreamReport, String)> {
    use anyhow::Context;
    use producer::genicam::{CameraSettings, FIRST_RETRY, MAX_RETRY};
    use producer::stream::{stream_genicam, CameraNote};
    use std::time::{Duration, Instant};
    use wire::files::RowFile;

    /// Seconds between two status lines while frames flow.
    const STATUS_EVERY: Duration = Duration::from_secs(5);

    let camera = CameraSettings {
        exposure_us: args.exposure_us,
        gain_db: args.gain_db,
        fps: (fps > 0.0 && args.trigger != Trigger::Hardware).then_some(fps),
        pixel_format: args.pixel_format,
        roi: args.roi,
        trigger: args.trigger,
    };
    camera.check()?;
    let mut rows = match log {
        Some(path) => Some(
            RowFile::create(path, LOG_HEADER)
                .with_context(|| format!("creating the --log file {}", path.display()))?,
        ),
        None => None,
    };
    let mut log_error = None;
    let mut last_status = Instant::now();
    let mut published = 0u64;
    let mut last_frame_id = None;
    let mut id = String::new();
    let (report, camera_report) = stream_genicam(
        spec,
        &camera,
        instance,
        settings,
        on_event,
        |note| match note {
            CameraNote::Opened {
                id: opened,
                format,
                width_px,
                height_px,
            } => {
                id = opened.to_string();
                eprintln!(
                    "producer: camera {opened} open: {width_px}x{height_px} px {format}, trigger \
                     {}{}; header t_capture_ns = host receive time (monotonic clock), camera \
                     timestamps (the camera's clock) {}",
                    args.trigger,
                    camera
                        .fps
                        .map_or_else(String::new, |fps| format!(" at {fps} fps")),
                    if log.is_some() {
                        "in --log"
                    } else {
                        "not kept (pass --log FILE)"
                    }
                )
            }
            CameraNote::Frame {
                frame_id,
                camera_frame_id,
                camera_timestamp_ns,
                host_receive_ns,
            } => {
                published += 1;
                last_frame_id = Some(*frame_id);
                if let (Some(rows), None) = (rows.as_mut(), log_error.as_ref()) {
                    let row = format!(
                        "{frame_id},{camera_frame_id},{camera_timestamp_ns},{host_receive_ns}\n"
                    );
                    if let Err(e) = rows.append(&row) {
                        log_error = Some(e);
                    }
                }
                if last_status.elapsed() >= STATUS_EVERY {
                    last_status = Instant::now();
                    eprintln!(
                        "producer: camera status: streaming, {published} frame(s) published, \
                         last frame {frame_id}"
                    );
                }
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
                last_frame_id.map_or(settings.first_frame_id, |f| f + 1)
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
        },
    )?;
    if let Some(e) = log_error {
        return Err(anyhow::Error::new(e).context("writing the --log file"));
    }
    let c = camera_report.counts;
    let line = format!(
        "camera {id}: {} buffer(s) published, {} skipped ({} incomplete, {} failed, {} of the \
         wrong size or format), {} dropped by the driver (no free buffer), lost {} time(s), \
         reconnected {} time(s){}",
        c.published,
        c.skipped(),
        c.incomplete,
        c.failed,
        c.wrong_shape,
        camera_report.driver_underruns,
        camera_report.losses,
        camera_report.reconnections,
        if camera_report.ended_lost {
            "; ended while the camera was lost"
        } else {
            ""
        }
    );
    Ok((report, line))
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
