//! Frame producer: simulated speckle camera with exact ground truth, and image-folder replay.
//!
//! Pure library, no IPC, except the thin streaming shell (`stream`), which publishes what a
//! [`FrameSource`] (scenario, replay), the rig-driven [`RigCamera`] or a watched folder
//! ([`Watcher`]) gives.

#![forbid(unsafe_code)]

pub mod camera;
mod error;
pub mod field_motion;
pub mod genicam;
mod image_io;
mod image_out;
pub mod motion;
mod natural_sort;
pub mod parallel;
mod render_exact;
mod render_fast;
mod replay;
mod rig_follow;
pub mod row_inverse;
mod scenario;
pub mod settings;
mod simulated;
mod source;
pub mod specimen_states;
pub mod speckle;
#[cfg(feature = "process")]
pub mod stream;
mod watch;

pub use camera::{CameraModel, BIT_DEPTHS};
pub use error::ProducerError;
pub use field_motion::{FieldMotion, Framing, ReferenceMesh, View, BACKDROP};
pub use image_io::{decode_into, read_image, read_shape, Image16, ImageShape};
pub use image_out::{write_atomic, write_frame, ImageFormatOut};
pub use motion::{Affine, Bulge, Chirp, Motion};
pub use natural_sort::natural_cmp;
pub use render_exact::{exact_test_frame, gauss_legendre, ExactRenderer};
pub use render_fast::FastRenderer;
pub use replay::{list_images, Replay, IMAGE_EXTENSIONS};
pub use rig_follow::{
    BeyondEnvelope, NextMotion, RigCamera, RigEnvelope, RigFollowConfig, RigFollower,
    RigKinematics, RigMotion, DEFAULT_MAX_OFFSET_MM, DEFAULT_MAX_ROTATION_DEG, DEFAULT_MAX_STRETCH,
    DEFAULT_MM_PER_PX, DEFAULT_STRIP_MM_PER_PX, RIG_SCENARIO_ID,
};
pub use scenario::{Scenario, ScenarioKind, SCENARIO_NAMES};
pub use simulated::{
    check_frame_size, motion_reach_px, MotionSource, RendererKind, ScenarioTimeline,
    SimulatedCamera, SimulatedConfig, MAX_SIDE_PX,
};
pub use source::{FrameDims, FrameInfo, FrameSource, Truth};
pub use speckle::{Speckle, SpeckleParams};
pub use watch::{
    is_temporary_name, WatchCounts, WatchEnd, WatchNote, WatchSettings, WatchedFile, Watcher,
    DEFAULT_FAILURE_WAIT_SETTLES, DEFAULT_POLL_MS, DEFAULT_SETTLE_MS, TEMPORARY_SUFFIXES,
};
