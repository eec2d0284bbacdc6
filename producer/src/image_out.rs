//! Writing frames as PNG (8 or 16 bit) or TIFF, atomically: a temporary file in the same
//! folder, then a rename, so a reader never sees a half-written image.

use std::path::Path;

use crate::error::ProducerError;
use crate::FrameDims;

/// Output image formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormatOut {
    /// 8-bit grayscale PNG (frames of bit depth 8 only).
    Png8,
    /// 16-bit grayscale PNG; values are stored as they are (a 12-bit frame stays in 0..4095).
    Png16,
    /// TIFF, 8-bit for 8-bit frames, 16-bit otherwise (values as they are).
    Tiff,
}

wire::named!(ImageFormatOut, "image format", { Png8 => "png8", Png16 => "png16", Tiff => "tiff" });

impl ImageFormatOut {
    /// File extension.
    pub fn extension(&self) -> &'static str {
        match self {
            ImageFormatOut::Png8 | ImageFormatOut::Png16 => "png",
            ImageFormatOut::Tiff => "tif",
        }
    }

    /// The natural format for a bit depth: PNG 8 for 8 bit, PNG 16 otherwise.
    pub fn for_bit_depth(bit_depth: u8) -> Self {
        if bit_depth <= 8 {
            ImageFormatOut::Png8
        } else {
            ImageFormatOut::Png16
        }
    }
}

/// Writes `bytes` to `path` atomically (temporary sibling, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ProducerError> {
    if path.file_name().is_none() {
        return Err(ProducerError::InvalidParameter {
            name: "output path".to_owned(),
            value: path.display().to_string(),
            expected: "a file path".to_owned(),
        });
    }
    wire::files::write_atomic(path, bytes).map_err(|e| ProducerError::Io {
        path: e.path,
        reason: e.reason,
    })
}

/// Encodes a frame of `dims` (its size and bit depth) in `format` and writes it atomically.
/// `encoded` is a reusable byte buffer.
pub fn write_frame(
    path: &Path,
    dims: FrameDims,
    pixels: &[u16],
    format: ImageFormatOut,
    encoded: &mut Vec<u8>,
) -> Result<(), ProducerError> {
    let FrameDims {
        width,
        height,
        bit_depth,
    } = dims;
    assert_eq!(pixels.len(), width as usize * height as usize, "frame size");
    if format == ImageFormatOut::Png8 && bit_depth > 8 {
        return Err(ProducerError::InvalidParameter {
            name: "format".to_owned(),
            value: "png8".to_owned(),
            expected: format!("png16 or tiff for a {bit_depth}-bit camera"),
        });
    }
    let eight =
        format == ImageFormatOut::Png8 || (format == ImageFormatOut::Tiff && bit_depth <= 8);
    let image = if eight {
        let data: Vec<u8> = pixels.iter().map(|&p| p.min(255) as u8).collect();
        image::DynamicImage::ImageLuma8(
            image::GrayImage::from_raw(width, height, data).expect("frame size checked"),
        )
    } else {
        image::DynamicImage::ImageLuma16(
            image::ImageBuffer::from_raw(width, height, pixels.to_vec())
                .expect("frame size checked"),
        )
    };
    let target = match format {
        ImageFormatOut::Png8 | ImageFormatOut::Png16 => image::ImageFormat::Png,
        ImageFormatOut::Tiff => image::ImageFormat::Tiff,
    };
    encoded.clear();
    image
        .write_to(&mut std::io::Cursor::new(&mut *encoded), target)
        .map_err(|e| ProducerError::Decode {
            path: path.to_path_buf(),
            reason: format!("encoding failed: {e}"),
        })?;
    write_atomic(path, encoded)
}
