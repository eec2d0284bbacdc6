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

/// The most a file read here can expand into pixels: deflate (PNG, TIFF) reaches at most
/// 1032:1 and TIFF's LZW about 1300:1 (12-bit codes for runs of up to 4096 bytes), so an
/// image file declaring more pixel bytes than this many times its own size cannot hold them
/// (a truncated or corrupt header, or an image with nothing to correlate).
pub const MAX_EXPANSION: u64 = 4096;

/// Opens the decoder and reads the header; refuses, before any pixel is decoded or allocated,
/// a declared side beyond [`MAX_SIDE_PX`] (a kilobyte file may declare gigapixels) and a
/// declared size the file cannot hold ([`MAX_EXPANSION`]).
fn open_decoder(path: &Path) -> Result<impl ImageDecoder, ProducerError> {
    let io_error = |reason| ProducerError::Io {
        path: path.to_path_buf(),
        reason,
    };
    let file = std::fs::File::open(path).map_err(io_error)?;
    let file_bytes = file.metadata().map_err(io_error)?.len();
    let reader = ImageReader::new(std::io::BufReader::new(file))
        .with_guessed_format()
        .map_err(io_error)?;
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
    let pixel_bytes = decoder.total_bytes();
    if pixel_bytes > file_bytes.saturating_mul(MAX_EXPANSION) {
        return Err(ProducerError::ImageBeyondFile {
            path: path.to_path_buf(),
            width,
            height,
            pixel_bytes,
            file_bytes,
            max_expansion: MAX_EXPANSION,
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A little-endian TIFF of `len_bytes` bytes whose header declares `side` x `side` px at
    /// 16 bit, uncompressed, in one strip (which the file does not hold).
    pub(crate) fn tiff_declaring(side: u32, len_bytes: usize) -> Vec<u8> {
        let entries: [(u16, u16, u32); 9] = [
            (256, 4, side),            // ImageWidth, LONG
            (257, 4, side),            // ImageLength
            (258, 3, 16),              // BitsPerSample, SHORT
            (259, 3, 1),               // Compression: none
            (262, 3, 1),               // PhotometricInterpretation: BlackIsZero
            (273, 4, 150),             // StripOffsets
            (277, 3, 1),               // SamplesPerPixel
            (278, 4, side),            // RowsPerStrip
            (279, 4, side * side * 2), // StripByteCounts
        ];
        let mut bytes = b"II*\0".to_vec();
        bytes.extend(8u32.to_le_bytes());
        bytes.extend((entries.len() as u16).to_le_bytes());
        for (tag, kind, value) in entries {
            bytes.extend(tag.to_le_bytes());
            bytes.extend(kind.to_le_bytes());
            bytes.extend(1u32.to_le_bytes());
            bytes.extend(value.to_le_bytes());
        }
        bytes.extend(0u32.to_le_bytes());
        bytes.resize(len_bytes, 0);
        bytes
    }

    #[test]
    fn a_header_declaring_more_pixels_than_the_file_can_hold_is_refused_from_the_header() {
        let dir = std::env::temp_dir().join(format!("image_io_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("huge.tif");
        // 16384² px at 16 bit is 512 MiB of pixels in a 200-byte file.
        std::fs::write(&path, tiff_declaring(16_384, 200)).unwrap();
        for result in [read_shape(&path).map(|_| ()), read_image(&path).map(|_| ())] {
            let message = result.expect_err("refused").to_string();
            for part in [
                path.display().to_string().as_str(),
                "16384x16384 px (536870912 bytes of pixels)",
                "file of 200 bytes",
            ] {
                assert!(message.contains(part), "{part:?} not in {message}");
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
