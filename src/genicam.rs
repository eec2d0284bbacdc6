//! Real GenICam cameras (GigE Vision, USB3 Vision) through Aravis, feature `genicam`: the
//! driver's part (`device.rs`: list, open, configure, acquire) and the loop that publishes a
//! camera's buffers on `frames` with producer's stream [`producer::stream::Shell`]
//! (`stream.rs`). Everything decided without a camera (pixel formats, regions, triggers, the
//! link's bookkeeping) is producer's pure `producer::genicam`. The code lives in the binary so
//! that the feature, which needs the system's libaravis, changes no workspace crate.

pub mod device;
mod stream;

pub use stream::{stream_genicam, CameraNote, CameraReport};
