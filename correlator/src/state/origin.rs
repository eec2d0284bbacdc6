//! `origin.state`, beside `reference.state`: the frame the mesh is defined in, which the
//! correlator measures its bases against at every reference update (see
//! `correlator/reanchor.rs`). It changes only with a new sequence (a new origin), so it is
//! written only then, atomically, before the reference state that refers to it. All
//! little-endian:
//!
//! | offset | size | content |
//! |---|---|---|
//! | 0 | 8 | magic `DICSORG1` |
//! | 8 | 4 | format version (1) |
//! | 12 | 8 | width, height (px, u32 each) |
//! | 20 | 8 | origin frame id (u64; `u64::MAX`: an image file) |
//! | 28 | 2 w h | origin pixels, row-major u16 |
//! | … | 8 | checksum (u64) of every byte before it |
//!
//! A missing file, or one of another origin frame or size (a reference state written before
//! the new origin was), is no origin: the restored correlator then carries its bases as a
//! correlator without the origin does.

use super::Corruption;

const MAGIC: &[u8; 8] = b"DICSORG1";
const FORMAT_VERSION: u32 = 1;
const HEADER_BYTES: usize = 28;
/// Name of the origin file inside the state folder.
pub const ORIGIN_FILE: &str = "origin.state";

/// The origin read back from its file.
pub(super) struct SavedOrigin {
    pub width_px: usize,
    pub height_px: usize,
    pub origin_frame_id: u64,
    pub pixels: Vec<u16>,
}

pub(super) fn encode(
    (width_px, height_px): (usize, usize),
    origin_frame_id: u64,
    pixels: &[u16],
    out: &mut Vec<u8>,
) {
    assert_eq!(pixels.len(), width_px * height_px);
    out.clear();
    out.reserve(HEADER_BYTES + 2 * pixels.len() + 8);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(width_px as u32).to_le_bytes());
    out.extend_from_slice(&(height_px as u32).to_le_bytes());
    out.extend_from_slice(&origin_frame_id.to_le_bytes());
    for &p in pixels {
        out.extend_from_slice(&p.to_le_bytes());
    }
    let sum = wire::frame::byte_checksum(out);
    out.extend_from_slice(&sum.to_le_bytes());
}

pub(super) fn decode(bytes: &[u8]) -> Result<SavedOrigin, Corruption> {
    if bytes.len() < HEADER_BYTES + 8 {
        return Err(Corruption::Short {
            len_bytes: bytes.len(),
        });
    }
    if &bytes[..8] != MAGIC {
        return Err(Corruption::Magic);
    }
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
    let version = u32_at(8);
    if version != FORMAT_VERSION {
        return Err(Corruption::Version {
            version,
            expected: FORMAT_VERSION,
        });
    }
    let (width_px, height_px) = (u32_at(12) as usize, u32_at(16) as usize);
    let origin_frame_id = u64::from_le_bytes(bytes[20..28].try_into().expect("8 bytes"));
    let expected = HEADER_BYTES + 2 * width_px * height_px + 8;
    if bytes.len() != expected {
        return Err(Corruption::OriginLength {
            len_bytes: bytes.len(),
            width_px,
            height_px,
            expected_bytes: expected,
        });
    }
    let body = &bytes[..expected - 8];
    let stored = u64::from_le_bytes(bytes[expected - 8..].try_into().expect("8 bytes"));
    if wire::frame::byte_checksum(body) != stored {
        return Err(Corruption::Checksum);
    }
    let pixels = body[HEADER_BYTES..]
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect();
    Ok(SavedOrigin {
        width_px,
        height_px,
        origin_frame_id,
        pixels,
    })
}
