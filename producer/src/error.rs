//! The one error type of the producer crate: every variant names the input and what was expected.

use std::path::PathBuf;

/// Errors of the simulated camera and of replay.
#[derive(Debug, thiserror::Error)]
pub enum ProducerError {
    /// A file could not be opened or read.
    /// The reason is part of the message, not a separate cause, so that an error chain
    /// (`{:#}`) does not say it twice.
    #[error("cannot read {path}: {reason}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        reason: std::io::Error,
    },
    /// A file is not a decodable image (not an image, truncated, unsupported format).
    #[error("cannot decode image {path}: {reason}")]
    Decode {
        /// The file.
        path: PathBuf,
        /// What went wrong, from the decoder.
        reason: String,
    },
    /// An image file declares a side beyond the largest frame (refused before any pixel is
    /// decoded or allocated).
    #[error("image {path} declares {width}x{height} px, more than the largest frame side of {max_side_px} px: refused before decoding")]
    ImageTooLarge {
        /// The file.
        path: PathBuf,
        /// Declared size, px.
        width: u32,
        height: u32,
        /// The largest frame side, px.
        max_side_px: u32,
    },
    /// An image file's header declares more pixel bytes than the file can hold, even at the
    /// best compression of its format (refused before any pixel is decoded or allocated).
    #[error("image {path} declares {width}x{height} px ({pixel_bytes} bytes of pixels) in a file of {file_bytes} bytes, more than {max_expansion} times its size, which no format read here compresses to: a truncated or corrupt header; refused before decoding")]
    ImageBeyondFile {
        /// The file.
        path: PathBuf,
        /// Declared size, px.
        width: u32,
        height: u32,
        /// Bytes the declared pixels take decoded.
        pixel_bytes: u64,
        /// Size of the file.
        file_bytes: u64,
        /// The largest expansion of any format read ([`crate::image_io::MAX_EXPANSION`]).
        max_expansion: u64,
    },
    /// An image has a pixel type replay does not support.
    #[error("unsupported pixel type in {path}: {found}; expected 8- or 16-bit grayscale (or colour, converted to luma)")]
    PixelType {
        /// The file.
        path: PathBuf,
        /// The pixel type found.
        found: String,
    },
    /// A replay frame differs from the first frame in size or bit depth.
    #[error("{path} is {found_width}x{found_height} at {found_bit_depth} bit, expected {expected_width}x{expected_height} at {expected_bit_depth} bit like the first frame {first}")]
    FrameMismatch {
        /// The offending file.
        path: PathBuf,
        /// The first frame of the sequence, the reference for size and depth.
        first: PathBuf,
        /// Width found, px.
        found_width: u32,
        /// Height found, px.
        found_height: u32,
        /// Bit depth found.
        found_bit_depth: u8,
        /// Width expected, px.
        expected_width: u32,
        /// Height expected, px.
        expected_height: u32,
        /// Bit depth expected.
        expected_bit_depth: u8,
    },
    /// A replay source matched no image file.
    #[error("no image found in {path}: expected files ending in .png, .tif, .tiff or .bmp")]
    NoImages {
        /// The folder or glob given.
        path: PathBuf,
    },
    /// A watched folder that is missing, not a folder, or cannot be listed.
    #[error("cannot watch {path}: {reason}")]
    WatchFolder {
        /// The folder given.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// An image file's size is not the frame buffer's (a file rewritten with another size).
    #[error("image {path} is {found_width}x{found_height} px, the frame buffer holds {expected_px} pixels")]
    ImageSize {
        /// The file.
        path: PathBuf,
        /// Its shape.
        found_width: u32,
        found_height: u32,
        found_bit_depth: u8,
        /// Length of the buffer, pixels.
        expected_px: usize,
    },
    /// The caller's output buffer has the wrong length.
    #[error("frame buffer holds {found_px} pixels, expected {expected_px} (width x height)")]
    BufferSize {
        /// Length given, pixels.
        found_px: usize,
        /// Length expected, pixels.
        expected_px: usize,
    },
    /// A scenario name that is not known.
    #[error("unknown scenario '{name}'; known scenarios: {known}")]
    UnknownScenario {
        /// The name given.
        name: String,
        /// The known names, comma separated.
        known: String,
    },
    /// A parameter out of its valid range or malformed.
    #[error("invalid parameter {name} = {value}: expected {expected}")]
    InvalidParameter {
        /// Parameter name.
        name: String,
        /// Value given.
        value: String,
        /// What was expected.
        expected: String,
    },
}
