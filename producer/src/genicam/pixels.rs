//! GenICam pixel formats the camera may send and their conversion into the `frames` payload
//! (`u16` per pixel, the significant bits in the low bits as the frame header's bit depth
//! says): the one copy from the driver's buffer into the loaned slice.
//!
//! Codes are the GenICam PFNC values (the `PixelFormat` feature's integer values).

/// A monochrome pixel format dicstream can publish.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PixelFormat {
    /// 8 bits in one byte.
    Mono8,
    /// 10 bits in the low bits of a little-endian 16-bit word.
    Mono10,
    /// 12 bits in the low bits of a little-endian 16-bit word.
    Mono12,
    /// 16 bits, little-endian.
    Mono16,
    /// 10 bits, packed LSB first: 4 pixels in 5 bytes (PFNC `Mono10p`).
    Mono10p,
    /// 12 bits, packed LSB first: 2 pixels in 3 bytes (PFNC `Mono12p`).
    Mono12p,
    /// 12 bits, GigE Vision packing: 2 pixels in 3 bytes, byte 1 holds both low nibbles
    /// (`Mono12Packed`).
    Mono12Packed,
}

wire::named!(PixelFormat, "pixel format", ignore_case, {
    Mono8 => "Mono8", Mono10 => "Mono10", Mono12 => "Mono12", Mono16 => "Mono16",
    Mono10p => "Mono10p", Mono12p => "Mono12p", Mono12Packed => "Mono12Packed",
});

impl PixelFormat {
    /// The PFNC code.
    pub fn code(self) -> u32 {
        match self {
            PixelFormat::Mono8 => 0x0108_0001,
            PixelFormat::Mono10 => 0x0110_0003,
            PixelFormat::Mono12 => 0x0110_0005,
            PixelFormat::Mono16 => 0x0110_0007,
            PixelFormat::Mono10p => 0x010A_0046,
            PixelFormat::Mono12p => 0x010C_0047,
            PixelFormat::Mono12Packed => 0x010C_0006,
        }
    }

    /// The format of a PFNC code, if dicstream can publish it.
    pub fn from_code(code: u32) -> Option<PixelFormat> {
        Self::ALL.iter().copied().find(|f| f.code() == code)
    }

    /// Significant bits per pixel (the frame header's bit depth).
    pub fn bit_depth(self) -> u8 {
        match self {
            PixelFormat::Mono8 => 8,
            PixelFormat::Mono10 | PixelFormat::Mono10p => 10,
            PixelFormat::Mono12 | PixelFormat::Mono12p | PixelFormat::Mono12Packed => 12,
            PixelFormat::Mono16 => 16,
        }
    }

    /// Bytes a `width_px` x `height_px` image takes in this format (rows are not padded).
    pub fn image_bytes(self, width_px: u32, height_px: u32) -> usize {
        let pixels = width_px as usize * height_px as usize;
        match self {
            PixelFormat::Mono8 => pixels,
            PixelFormat::Mono10 | PixelFormat::Mono12 | PixelFormat::Mono16 => 2 * pixels,
            PixelFormat::Mono10p => (pixels * 10).div_ceil(8),
            PixelFormat::Mono12p | PixelFormat::Mono12Packed => (pixels * 12).div_ceil(8),
        }
    }
}

/// Why a buffer could not be converted: it is not the image the camera was set to send.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ConvertError {
    #[error("the buffer holds {got_bytes} bytes, a {width_px}x{height_px} {format} image needs {need_bytes}")]
    ShortBuffer {
        format: PixelFormat,
        width_px: u32,
        height_px: u32,
        got_bytes: usize,
        need_bytes: usize,
    },
    #[error("the loaned slice holds {got_px} pixels, the image has {need_px}")]
    WrongSlice { got_px: usize, need_px: usize },
}

/// Converts one image of `format` from the driver's `bytes` into `pixels` (the loaned slice):
/// widening, unpacking, masking to the format's bit depth. Bytes past the image (padding,
/// chunk data) are ignored.
pub fn convert_into(
    format: PixelFormat,
    bytes: &[u8],
    width_px: u32,
    height_px: u32,
    pixels: &mut [u16],
) -> Result<(), ConvertError> {
    let need_px = width_px as usize * height_px as usize;
    if pixels.len() != need_px {
        return Err(ConvertError::WrongSlice {
            got_px: pixels.len(),
            need_px,
        });
    }
    let need_bytes = format.image_bytes(width_px, height_px);
    if bytes.len() < need_bytes {
        return Err(ConvertError::ShortBuffer {
            format,
            width_px,
            height_px,
            got_bytes: bytes.len(),
            need_bytes,
        });
    }
    let bytes = &bytes[..need_bytes];
    match format {
        PixelFormat::Mono8 => {
            for (p, &b) in pixels.iter_mut().zip(bytes) {
                *p = u16::from(b);
            }
        }
        PixelFormat::Mono10 | PixelFormat::Mono12 | PixelFormat::Mono16 => {
            let mask = mask(format);
            for (p, word) in pixels.iter_mut().zip(bytes.chunks_exact(2)) {
                *p = u16::from_le_bytes([word[0], word[1]]) & mask;
            }
        }
        PixelFormat::Mono12p => unpack_lsb_first(bytes, 12, pixels),
        PixelFormat::Mono10p => unpack_lsb_first(bytes, 10, pixels),
        PixelFormat::Mono12Packed => {
            let mut pairs = pixels.chunks_exact_mut(2);
            let mut groups = bytes.chunks_exact(3);
            for (pair, g) in (&mut pairs).zip(&mut groups) {
                pair[0] = (u16::from(g[0]) << 4) | u16::from(g[1] & 0x0F);
                pair[1] = (u16::from(g[2]) << 4) | u16::from(g[1] >> 4);
            }
            if let ([last], [b0, b1, ..]) = (pairs.into_remainder(), groups.remainder()) {
                *last = (u16::from(*b0) << 4) | u16::from(b1 & 0x0F);
            }
        }
    }
    Ok(())
}

fn mask(format: PixelFormat) -> u16 {
    ((1u32 << format.bit_depth()) - 1) as u16
}

/// PFNC "p" packing: a bit stream, each pixel's least significant bit first.
fn unpack_lsb_first(bytes: &[u8], bits: u32, pixels: &mut [u16]) {
    let mask = (1u64 << bits) - 1;
    let mut acc = 0u64;
    let mut held = 0u32;
    let mut next = bytes.iter();
    for p in pixels.iter_mut() {
        while held < bits {
            acc |= u64::from(*next.next().unwrap_or(&0)) << held;
            held += 8;
        }
        *p = (acc & mask) as u16;
        acc >>= bits;
        held -= bits;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Packs `values` LSB first with `bits` per value (the PFNC "p" formats).
    fn pack_lsb_first(values: &[u16], bits: u32) -> Vec<u8> {
        let mut out = Vec::new();
        let (mut acc, mut held) = (0u64, 0u32);
        for &v in values {
            acc |= u64::from(v) << held;
            held += bits;
            while held >= 8 {
                out.push(acc as u8);
                acc >>= 8;
                held -= 8;
            }
        }
        if held > 0 {
            out.push(acc as u8);
        }
        out
    }

    #[test]
    fn names_and_codes_round_trip_and_unknown_names_are_refused_clearly() {
        for f in PixelFormat::ALL {
            assert_eq!(f.name().parse::<PixelFormat>(), Ok(f));
            assert_eq!(PixelFormat::from_code(f.code()), Some(f));
        }
        assert_eq!("mono12".parse::<PixelFormat>(), Ok(PixelFormat::Mono12));
        let err = "RGB8".parse::<PixelFormat>().unwrap_err().to_string();
        assert!(
            err.contains("\"RGB8\"") && err.contains("Mono8, Mono10"),
            "{err}"
        );
        // BayerRG8 (0x01080009) is not monochrome.
        assert_eq!(PixelFormat::from_code(0x0108_0009), None);
    }

    #[test]
    fn mono8_widens_and_mono16_reads_little_endian() {
        let mut px = [0u16; 4];
        convert_into(PixelFormat::Mono8, &[0, 1, 254, 255, 9], 2, 2, &mut px).unwrap();
        assert_eq!(px, [0, 1, 254, 255]);
        convert_into(
            PixelFormat::Mono16,
            &[0x34, 0x12, 0xFF, 0xFF],
            2,
            1,
            &mut px[..2],
        )
        .unwrap();
        assert_eq!(px[..2], [0x1234, 0xFFFF]);
    }

    #[test]
    fn mono10_and_mono12_keep_only_their_bits() {
        let mut px = [0u16; 2];
        convert_into(
            PixelFormat::Mono12,
            &[0xFF, 0xFF, 0x21, 0x03],
            2,
            1,
            &mut px,
        )
        .unwrap();
        assert_eq!(px, [0x0FFF, 0x0321]);
        convert_into(
            PixelFormat::Mono10,
            &[0xFF, 0xFF, 0x21, 0x03],
            1,
            2,
            &mut px,
        )
        .unwrap();
        assert_eq!(px, [0x03FF, 0x0321]);
    }

    #[test]
    fn packed_formats_unpack_every_pixel_including_an_odd_tail() {
        let values: Vec<u16> = (0..7).map(|i| (i * 601 + 3) as u16 & 0x0FFF).collect();
        let mut px = vec![0u16; 7];
        convert_into(
            PixelFormat::Mono12p,
            &pack_lsb_first(&values, 12),
            7,
            1,
            &mut px,
        )
        .unwrap();
        assert_eq!(px, values);

        let tens: Vec<u16> = values.iter().map(|v| v & 0x03FF).collect();
        convert_into(
            PixelFormat::Mono10p,
            &pack_lsb_first(&tens, 10),
            1,
            7,
            &mut px,
        )
        .unwrap();
        assert_eq!(px, tens);
        assert_eq!(PixelFormat::Mono10p.image_bytes(4, 1), 5);

        // Mono12Packed: 0xABC, 0x123 -> AB, 3C (high nibble: second's low), 12.
        let mut pair = [0u16; 3];
        convert_into(
            PixelFormat::Mono12Packed,
            &[0xAB, 0x3C, 0x12, 0x45, 0x06],
            3,
            1,
            &mut pair,
        )
        .unwrap();
        assert_eq!(pair, [0xABC, 0x123, 0x456]);
    }

    #[test]
    fn a_short_buffer_or_a_wrong_slice_is_refused_and_nothing_is_written() {
        let mut px = [7u16; 4];
        let err = convert_into(PixelFormat::Mono16, &[0; 7], 2, 2, &mut px).unwrap_err();
        assert_eq!(
            err.to_string(),
            "the buffer holds 7 bytes, a 2x2 Mono16 image needs 8"
        );
        assert_eq!(px, [7; 4]);
        assert!(matches!(
            convert_into(PixelFormat::Mono8, &[0; 8], 2, 2, &mut px[..3]),
            Err(ConvertError::WrongSlice {
                got_px: 3,
                need_px: 4
            })
        ));
    }
}
