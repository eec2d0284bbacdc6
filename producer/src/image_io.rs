//! Reading one image file into 16-bit grayscale pixels: the shared decoder of replay and of
//! `dicstream correlate`.

use std::path::{Path, PathBuf};

use image::{ColorType, ImageDecoder, ImageReader};

use crate::error::ProducerError;
use crate::simulated::MAX_SIDE_PX;

/// A grayscale image with its pixels widened to `u16`, row-major, `pixels[y * width + x]`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image16 {
    /// Width, px (columns).
    pub width: u32,
    /// Height, px (rows).
    pub height: u32,
    /// Bit depth of the file, 8 or 16; every pixel is below `1 << bit_depth`.
    pub bit_depth: u8,
    /// Row-major pixels, `width * height` of them.
    pub pixels: Vec<u16>,
}

/// Size and depth of an image file, read from its header only.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageShape {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Bit depth of the grayscale data, 8 or 16.
    pub bit_depth: u8,
}

impl ImageShape {
    /// Number of pixels.
    pub fn len_px(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// Reads a PNG, TIFF or BMP file (8- or 16-bit, grayscale or colour converted to luma).
///
/// Errors name the file: missing, not an image, truncated, unsupported pixel type.
pub fn read_image(path: impl AsRef<Path>) -> Result<Image16, ProducerError> {
    let path = path.as_ref();
    let shape = read_shape(path)?;
    let mut pixels = vec![0u16; shape.len_px()];
    let mut scratch = Vec::new();
    let read = decode_into(path, &mut scratch, &mut pixels)?;
    assert_eq!(
        read,
        shape,
        "header and data of {} disagree",
        path.display()
    );
    Ok(Image16 {
        width: shape.width,
        height: shape.height,
        bit_depth: shape.bit_depth,
        pixels,
    })
}

fn decode_error(path: &Path, error: impl std::fmt::Display) -> ProducerError {
    ProducerError::Decode {
        path: path.to_path_buf(),
        reason: error.to_string(),
    }
}

/// Opens the decoder and reads the header; refuses a declared size beyond
/// [`MAX_SIDE_PX`] at once (a kilobyte file may declare gigapixels).
fn open_decoder(path: &Path) -> Result<impl ImageDecoder, ProducerError> {
    let io_error = |reason| ProducerError::Io {
        path: path.to_path_buf(),
        reason,
    };
    let reader = ImageReader::open(path).map_err(io_error)?;
    let reader = reader.with_guessed_format().map_err(io_error)?;
    let decoder = reader.into_decoder().map_err(|e| decode_error(path, e))?;
    let (width, height) = decoder.dimensions();
    if width > MAX_SIDE_PX || height > MAX_SIDE_PX {
        return Err(ProducerError::ImageTooLarge {
            path: path.to_path_buf(),
            width,
            height,
            max_side_px: MAX_SIDE_PX,
        });
    }
    Ok(decoder)
}

fn bit_depth_of(path: &Path, color: ColorType) -> Result<u8, ProducerError> {
    match color {
        ColorType::L8 | ColorType::La8 | ColorType::Rgb8 | ColorType::Rgba8 => Ok(8),
        ColorType::L16 | ColorType::La16 | ColorType::Rgb16 | ColorType::Rgba16 => Ok(16),
        other => Err(ProducerError::PixelType {
            path: PathBuf::from(path),
            found: format!("{other:?}"),
        }),
    }
}

/// Reads the size and bit depth of an image file from its header, without decoding the pixels.
pub fn read_shape(path: &Path) -> Result<ImageShape, ProducerError> {
    let decoder = open_decoder(path)?;
    let (width, height) = decoder.dimensions();
    let bit_depth = bit_depth_of(path, decoder.color_type())?;
    Ok(ImageShape {
        width,
        height,
        bit_depth,
    })
}

/// Decodes `path` into `out` (exactly `width * height` pixels), reusing `scratch` for the raw
/// bytes so that a replay loop does not allocate a frame buffer per file.
pub fn decode_into(
    path: &Path,
    scratch: &mut Vec<u8>,
    out: &mut [u16],
) -> Result<ImageShape, ProducerError> {
    let decoder = open_decoder(path)?;
    let (width, height) = decoder.dimensions();
    let color = decoder.color_type();
    let bit_depth = bit_depth_of(path, color)?;
    let shape = ImageShape {
        width,
        height,
        bit_depth,
    };
    if out.len() != shape.len_px() {
        return Err(ProducerError::ImageSize {
            path: path.to_path_buf(),
            found_width: width,
            found_height: height,
            found_bit_depth: bit_depth,
            expected_px: out.len(),
        });
    }
    if color == ColorType::L8 || color == ColorType::L16 {
        let len_bytes =
            usize::try_from(decoder.total_bytes()).map_err(|e| decode_error(path, e))?;
        scratch.resize(len_bytes, 0);
        decoder
            .read_image(scratch)
            .map_err(|e| decode_error(path, e))?;
        if color == ColorType::L8 {
            assert_eq!(scratch.len(), out.len());
            for (o, &b) in out.iter_mut().zip(scratch.iter()) {
                *o = u16::from(b);
            }
        } else {
            assert_eq!(scratch.len(), 2 * out.len());
            for (o, b) in out.iter_mut().zip(scratch.chunks_exact(2)) {
                *o = u16::from_ne_bytes([b[0], b[1]]);
            }
        }
    } else {
        // Colour: rare for DIC; decode and convert to luma (allocates, acceptable here).
        let dynamic =
            image::DynamicImage::from_decoder(decoder).map_err(|e| decode_error(path, e))?;
        if bit_depth == 8 {
            for (o, &b) in out.iter_mut().zip(dynamic.to_luma8().as_raw().iter()) {
                *o = u16::from(b);
            }
        } else {
            out.copy_from_slice(dynamic.to_luma16().as_raw());
        }
    }
    Ok(shape)
}
