//! Frame producer: simulated speckle camera with exact ground truth, and image-folder replay.
//!
//! Pure library, no IPC: the streaming loop (`stream`) and the `dicstream` commands call it
//! through the [`FrameSource`] seam.

mod error;
mod image_io;
mod natural_sort;
mod replay;
mod source;

pub use error::ProducerError;
pub use image_io::{decode_into, read_image, read_shape, Image16, ImageShape};
pub use natural_sort::natural_cmp;
pub use replay::{list_images, Replay, IMAGE_EXTENSIONS};
pub use source::{FrameDims, FrameInfo, FrameSource, Truth};
