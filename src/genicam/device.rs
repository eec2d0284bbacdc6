//! The Aravis part (feature `genicam`), kept thin: list the cameras, open and configure one,
//! hand its buffers out and back. Everything that can be decided without a camera (formats,
//! conversion, region checks, buffer accounting, reconnect backoff) lives in the pure modules.
//!
//! The one `unsafe` of the binary's camera code is here: viewing the driver's buffer as a byte slice
//! ([`Frame::bytes`]), so that the pixels are copied once, into the loaned slice, instead of
//! twice through the `Vec` the bindings' `image_data` returns.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use aravis::prelude::*;
use aravis::{AcquisitionMode, Auto, Buffer, Camera, Stream};

use producer::genicam::{
    BufferStatus, CameraSettings, CameraSpec, PixelFormat, RoiError, RoiLimits, Trigger,
};

/// Buffers queued to the driver: the camera keeps streaming while the producer publishes one.
const QUEUED_BUFFERS: usize = 10;

/// Why a camera could not be listed, opened or set up.
#[derive(Debug, thiserror::Error)]
pub enum GenicamError {
    #[error("no GenICam camera found{}", match .id { Some(id) => format!(" with id {id:?}"), None => String::new() })]
    NotFound { id: Option<String>, found: String },
    #[error("opening camera {id}: {detail}")]
    Open { id: String, detail: String },
    #[error("camera {id} does not offer pixel format {asked} (it offers {offered}); dicstream publishes {}", <PixelFormat as wire::names::Named>::expected())]
    PixelFormat {
        id: String,
        asked: String,
        offered: String,
    },
    #[error(transparent)]
    Roi(#[from] RoiError),
    #[error("camera {id}: setting {what}: {detail}")]
    Setting {
        id: String,
        what: String,
        detail: String,
    },
    #[error("camera {id}: {what}: {detail}")]
    Stream {
        id: String,
        what: &'static str,
        detail: String,
    },
}

/// One camera as `dicstream cameras` shows it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CameraInfo {
    pub id: String,
    pub vendor: String,
    pub model: String,
    pub serial: String,
    pub address: String,
    pub protocol: String,
    /// Sensor size, px (0 when the camera could not be opened).
    pub sensor_width_px: u32,
    pub sensor_height_px: u32,
    /// Every pixel format the camera offers (the monochrome ones dicstream publishes among
    /// them).
    pub pixel_formats: Vec<String>,
    /// Why the camera could not be opened to read its sensor and formats.
    pub open_error: Option<String>,
}

/// The cameras Aravis finds (GigE Vision discovery on every interface, USB3 Vision), each
/// opened briefly to read its sensor size and pixel formats.
pub fn list_cameras() -> Vec<CameraInfo> {
    let text = |s: &std::ffi::CStr| s.to_string_lossy().into_owned();
    aravis_token()
        .get_device_list()
        .iter()
        .map(|device| {
            let mut info = CameraInfo {
                id: text(&device.id),
                vendor: text(&device.vendor),
                model: text(&device.model),
                serial: String::new(),
                address: text(&device.address),
                protocol: text(&device.protocol),
                sensor_width_px: 0,
                sensor_height_px: 0,
                pixel_formats: Vec::new(),
                open_error: None,
            };
            match Camera::new(Some(&info.id)) {
                Ok(camera) => {
                    if let Ok(serial) = camera.device_serial_number() {
                        info.serial = serial.to_string();
                    }
                    if let Ok((w, h)) = camera.sensor_size() {
                        info.sensor_width_px = w.max(0) as u32;
                        info.sensor_height_px = h.max(0) as u32;
                    }
                    info.pixel_formats = offered_formats(&camera);
                }
                Err(e) => info.open_error = Some(e.to_string()),
            }
            info
        })
        .collect()
}

/// Aravis' token for its global device list (it may be taken once per process).
fn aravis_token() -> &'static aravis::Aravis {
    static TOKEN: std::sync::OnceLock<aravis::Aravis> = std::sync::OnceLock::new();
    TOKEN.get_or_init(|| aravis::Aravis::initialize().expect("Aravis is initialized only here"))
}

fn offered_formats(camera: &Camera) -> Vec<String> {
    camera
        .dup_available_pixel_formats_as_strings()
        .map(|v| v.iter().map(|s| s.to_string()).collect())
        .unwrap_or_default()
}

/// A complete or failed buffer the driver handed back, until it is given back with
/// [`Acquisition::requeue`].
pub struct Frame {
    buffer: Buffer,
    /// What the driver said.
    pub status: BufferStatus,
    /// The image is the size and format the camera was set to.
    pub shape_ok: bool,
    /// The camera's timestamp, ns on the camera's own clock (GigE Vision: its tick counter
    /// scaled by Aravis; arbitrary epoch, e.g. the camera's power-on).
    pub camera_timestamp_ns: u64,
    /// The driver's id of the frame (the camera's block id; restarts with the camera).
    pub camera_frame_id: u64,
}

impl Frame {
    /// The driver's buffer as bytes.
    #[allow(unsafe_code)]
    pub fn bytes(&self) -> &[u8] {
        let (data, len) = self.buffer.data();
        if data.is_null() || len == 0 {
            return &[];
        }
        // SAFETY: Aravis owns `len` bytes at `data` for as long as the buffer object lives;
        // `self` holds a reference on it and the stream does not write into a buffer the
        // application has popped until it is pushed back (`requeue` consumes the Frame).
        unsafe { std::slice::from_raw_parts(data, len) }
    }
}

/// The camera `spec` names and its id (as `dicstream cameras` lists it): the one asked for,
/// or the first found, which is the one `Camera::new(None)` opens.
fn connect(spec: &CameraSpec) -> Result<(Camera, String), GenicamError> {
    let camera = Camera::new(spec.id.as_deref()).map_err(|e| {
        let found = list_ids();
        if found.is_empty() || spec.id.is_some() {
            GenicamError::NotFound {
                id: spec.id.clone(),
                found: format!(
                    "{e}; found: {}",
                    if found.is_empty() {
                        "none".into()
                    } else {
                        found.join(", ")
                    }
                ),
            }
        } else {
            GenicamError::Open {
                id: "(first found)".into(),
                detail: e.to_string(),
            }
        }
    })?;
    let id = spec
        .id
        .clone()
        .or_else(|| list_ids().into_iter().next())
        .unwrap_or_else(|| "(first found)".into());
    Ok((camera, id))
}

/// A camera acquiring: its stream, the control-lost flag the driver raises, and its image size.
struct Started {
    stream: Stream,
    control_lost: Arc<AtomicBool>,
    size_px: (u32, u32),
}

/// An opened camera being set up; its errors name it by `id`.
struct Setup<'a> {
    camera: &'a Camera,
    id: &'a str,
}

impl Setup<'_> {
    /// A refused setting `what` as an error.
    fn set(&self, what: &str, result: Result<(), aravis::glib::Error>) -> Result<(), GenicamError> {
        result.map_err(|e| self.setting(what, e))
    }

    fn setting(&self, what: &str, e: aravis::glib::Error) -> GenicamError {
        GenicamError::Setting {
            id: self.id.to_string(),
            what: what.to_string(),
            detail: e.to_string(),
        }
    }

    fn stream_error(&self, what: &'static str, e: aravis::glib::Error) -> GenicamError {
        GenicamError::Stream {
            id: self.id.to_string(),
            what,
            detail: e.to_string(),
        }
    }

    /// Sets the pixel format `asked` if any (one the camera offers); the camera's format then,
    /// one dicstream publishes.
    fn pixel_format(&self, asked: Option<PixelFormat>) -> Result<PixelFormat, GenicamError> {
        let camera = self.camera;
        if let Some(asked) = asked {
            let offered = offered_formats(camera);
            if !offered.iter().any(|f| f == asked.name()) {
                return Err(GenicamError::PixelFormat {
                    id: self.id.to_string(),
                    asked: asked.name().into(),
                    offered: offered.join(", "),
                });
            }
            self.set(
                "--pixel-format",
                camera.set_pixel_format_from_string(asked.name()),
            )?;
        }
        let current = camera
            .pixel_format()
            .map_err(|e| self.setting("reading PixelFormat", e))?;
        PixelFormat::from_code(current.raw()).ok_or_else(|| GenicamError::PixelFormat {
            id: self.id.to_string(),
            asked: format!(
                "{} (its current one; pass --pixel-format)",
                camera
                    .pixel_format_as_string()
                    .map(|s| s.to_string())
                    .unwrap_or_else(|_| format!("0x{:08X}", current.raw()))
            ),
            offered: offered_formats(camera).join(", "),
        })
    }

    /// The region, exposure, gain, acquisition mode and trigger of `settings`.
    fn apply(&self, settings: &CameraSettings) -> Result<(), GenicamError> {
        let camera = self.camera;
        if let Some(roi) = settings.roi {
            roi.check(&roi_limits(camera, self.id)?)?;
            self.set(
                "--roi",
                camera.set_region(
                    roi.x_px as i32,
                    roi.y_px as i32,
                    roi.width_px as i32,
                    roi.height_px as i32,
                ),
            )?;
        }
        if let Some(exposure_us) = settings.exposure_us {
            let _ = camera.set_exposure_time_auto(Auto::Off);
            self.set("--exposure-us", camera.set_exposure_time(exposure_us))?;
        }
        if let Some(gain_db) = settings.gain_db {
            let _ = camera.set_gain_auto(Auto::Off);
            self.set("--gain-db", camera.set_gain(gain_db))?;
        }
        self.set(
            "AcquisitionMode Continuous",
            camera.set_acquisition_mode(AcquisitionMode::Continuous),
        )?;
        match settings.trigger {
            Trigger::Free => {
                self.set("--trigger free (TriggerMode Off)", camera.clear_triggers())?;
                if let Some(fps) = settings.fps {
                    self.set("--fps", camera.set_frame_rate(fps))?;
                }
                Ok(())
            }
            Trigger::Software => self.set("--trigger software", camera.set_trigger("Software")),
            Trigger::Hardware => {
                self.set("--trigger hardware (Line1)", camera.set_trigger("Line1"))
            }
        }
    }

    /// Queues the buffers and starts acquiring.
    fn start(&self) -> Result<Started, GenicamError> {
        let camera = self.camera;
        let (_, _, width, height) = camera
            .region()
            .map_err(|e| self.setting("reading the region", e))?;
        let payload = camera
            .payload()
            .map_err(|e| self.setting("reading PayloadSize", e))?;
        let stream = camera
            .create_stream()
            .map_err(|e| self.stream_error("creating the stream", e))?;
        for _ in 0..QUEUED_BUFFERS {
            stream.push_buffer(Buffer::new_allocate(payload as usize));
        }
        let control_lost = Arc::new(AtomicBool::new(false));
        if let Some(device) = camera.device() {
            let flag = Arc::clone(&control_lost);
            device.connect_control_lost(move |_| flag.store(true, Ordering::SeqCst));
        }
        camera
            .start_acquisition()
            .map_err(|e| self.stream_error("starting the acquisition", e))?;
        Ok(Started {
            stream,
            control_lost,
            size_px: (width.max(0) as u32, height.max(0) as u32),
        })
    }
}

/// An open, configured, streaming camera.
pub struct Acquisition {
    id: String,
    camera: Camera,
    stream: Stream,
    format: PixelFormat,
    width_px: u32,
    height_px: u32,
    trigger: Trigger,
    control_lost: Arc<AtomicBool>,
}

impl Acquisition {
    /// Opens the camera, applies `settings` (each refused setting is a clear error), queues
    /// the buffers and starts acquiring.
    pub fn open(spec: &CameraSpec, settings: &CameraSettings) -> Result<Acquisition, GenicamError> {
        let (camera, id) = connect(spec)?;
        let setup = Setup {
            camera: &camera,
            id: &id,
        };
        let _ = camera.stop_acquisition();
        let format = setup.pixel_format(settings.pixel_format)?;
        setup.apply(settings)?;
        let Started {
            stream,
            control_lost,
            size_px: (width_px, height_px),
        } = setup.start()?;
        Ok(Acquisition {
            id,
            camera,
            stream,
            format,
            width_px,
            height_px,
            trigger: settings.trigger,
            control_lost,
        })
    }

    pub fn id(&self) -> &str {
        &self.id
    }

    pub fn format(&self) -> PixelFormat {
        self.format
    }

    /// Image size, px.
    pub fn size_px(&self) -> (u32, u32) {
        (self.width_px, self.height_px)
    }

    /// True once the driver lost control of the camera (GigE Vision heartbeat failed).
    pub fn control_lost(&self) -> bool {
        self.control_lost.load(Ordering::SeqCst)
    }

    /// Fires a software trigger (with `--trigger software`).
    pub fn software_trigger(&self) -> Result<(), GenicamError> {
        debug_assert_eq!(self.trigger, Trigger::Software);
        self.camera
            .software_trigger()
            .map_err(|e| GenicamError::Stream {
                id: self.id.clone(),
                what: "software trigger",
                detail: e.to_string(),
            })
    }

    /// The next buffer the driver filled (or failed to), waiting at most `timeout`.
    pub fn next_frame(&self, timeout: Duration) -> Option<Frame> {
        let buffer = self
            .stream
            .timeout_pop_buffer(timeout.as_micros().min(u128::from(u64::MAX)) as u64)?;
        let status = match buffer.status() {
            aravis::BufferStatus::Success => BufferStatus::Success,
            aravis::BufferStatus::MissingPackets
            | aravis::BufferStatus::WrongPacketId
            | aravis::BufferStatus::SizeMismatch
            | aravis::BufferStatus::Timeout
            | aravis::BufferStatus::Aborted
            | aravis::BufferStatus::Filling => BufferStatus::Incomplete,
            _ => BufferStatus::Failed,
        };
        let shape_ok = status == BufferStatus::Success
            && matches!(
                buffer.payload_type(),
                aravis::BufferPayloadType::Image | aravis::BufferPayloadType::ExtendedChunkData
            )
            && buffer.image_width() as i64 == i64::from(self.width_px)
            && buffer.image_height() as i64 == i64::from(self.height_px)
            && buffer.image_pixel_format().raw() == self.format.code();
        Some(Frame {
            status,
            shape_ok,
            camera_timestamp_ns: buffer.timestamp(),
            camera_frame_id: buffer.frame_id(),
            buffer,
        })
    }

    /// Gives a buffer back to the driver.
    pub fn requeue(&self, frame: Frame) {
        self.stream.push_buffer(frame.buffer);
    }

    /// Frames the driver dropped for want of a free buffer (its underruns): the camera went on
    /// while every buffer was taken.
    pub fn underruns(&self) -> u64 {
        self.stream.statistics().2
    }
}

impl Drop for Acquisition {
    fn drop(&mut self) {
        let _ = self.camera.stop_acquisition();
    }
}

fn roi_limits(camera: &Camera, id: &str) -> Result<RoiLimits, GenicamError> {
    let err = |what: &str, e: aravis::glib::Error| GenicamError::Setting {
        id: id.to_string(),
        what: format!("reading {what}"),
        detail: e.to_string(),
    };
    let (sensor_w, sensor_h) = camera
        .sensor_size()
        .map_err(|e| err("the sensor size", e))?;
    let (min_w, _) = camera
        .width_bounds()
        .map_err(|e| err("the width bounds", e))?;
    let (min_h, _) = camera
        .height_bounds()
        .map_err(|e| err("the height bounds", e))?;
    let step = |v: Result<i32, aravis::glib::Error>| v.unwrap_or(1).max(1) as u32;
    Ok(RoiLimits {
        sensor_width_px: sensor_w.max(0) as u32,
        sensor_height_px: sensor_h.max(0) as u32,
        min_width_px: min_w.max(1) as u32,
        min_height_px: min_h.max(1) as u32,
        width_step_px: step(camera.width_increment()),
        height_step_px: step(camera.height_increment()),
        x_step_px: step(camera.x_offset_increment()),
        y_step_px: step(camera.y_offset_increment()),
    })
}

fn list_ids() -> Vec<String> {
    aravis_token()
        .get_device_list()
        .iter()
        .map(|d| d.id.to_string_lossy().into_owned())
        .collect()
}
