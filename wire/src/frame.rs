//! `frames`: one camera image as a `[u16]` slice (row-major, `width_px * height_px` values)
//! behind a [`FrameHeader`].

#[cfg(feature = "ipc")]
use iceoryx2::prelude::ZeroCopySend;

/// The exact motion imposed on a simulated frame, as a homogeneous transformation about a
/// centre: a reference point X goes to `x = F (X - centre_px) + centre_px + translation_px`.
/// For heterogeneous scenarios F is the gradient at the centre and the full displacement field
/// comes from the producer library (see `producer::scenario`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.GroundTruth.v6")
)]
pub struct GroundTruth {
    /// Deformation gradient, row-major: `[F11, F12, F21, F22]` (dimensionless).
    pub deformation_gradient: [f64; 4],
    /// Rigid translation added after the deformation (px).
    pub translation_px: [f64; 2],
    /// Centre of the deformation in reference coordinates (px).
    pub centre_px: [f64; 2],
    /// The specimen's solved state (`specimen` service, [`crate::SpecimenHeader::solve_id`])
    /// whose finite-element field this frame shows, or [`NO_SPECIMEN_SOLVE`] when the motion
    /// above is the whole truth. With a solve, the field is the solve's nodal displacements
    /// followed to `specimen_grip_mm` through its grip modes, and the homogeneous map above is
    /// the filmed region's mean.
    pub specimen_solve_id: u64,
    /// The grips' axial displacements (mm, in the solve's grip order; unused slots 0) the
    /// frame was taken at.
    pub specimen_grip_mm: [f64; 4],
}

/// [`GroundTruth::specimen_solve_id`] of a frame whose truth is the homogeneous motion alone.
pub const NO_SPECIMEN_SOLVE: u64 = u64::MAX;

impl GroundTruth {
    /// No motion: the reference configuration.
    pub const IDENTITY: GroundTruth = GroundTruth {
        deformation_gradient: [1.0, 0.0, 0.0, 1.0],
        translation_px: [0.0, 0.0],
        centre_px: [0.0, 0.0],
        specimen_solve_id: NO_SPECIMEN_SOLVE,
        specimen_grip_mm: [0.0; 4],
    };

    /// The specimen's solve this frame shows, when its truth is a finite-element field.
    pub fn specimen_solve(&self) -> Option<u64> {
        (self.specimen_solve_id != NO_SPECIMEN_SOLVE).then_some(self.specimen_solve_id)
    }

    /// Displacement u(X) = x - X of the reference point `(x_px, y_px)` under this motion.
    pub fn displacement_px(&self, x_px: f64, y_px: f64) -> (f64, f64) {
        let [f11, f12, f21, f22] = self.deformation_gradient;
        let dx = x_px - self.centre_px[0];
        let dy = y_px - self.centre_px[1];
        let x = f11 * dx + f12 * dy + self.centre_px[0] + self.translation_px[0];
        let y = f21 * dx + f22 * dy + self.centre_px[1] + self.translation_px[1];
        (x - x_px, y - y_px)
    }
}

/// Header of one frame on the `frames` service.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.FrameHeader.v6")
)]
pub struct FrameHeader {
    /// Always [`crate::LAYOUT_VERSION`]; checked by every reader.
    pub layout_version: u32,
    /// Significant bits per pixel value: 8, 10, 12 or 16.
    pub bit_depth: u32,
    /// Consecutive from 0 for one producer run: a gap seen by a reader is a dropped frame.
    pub frame_id: u64,
    /// Capture time on the system monotonic clock ([`crate::monotonic_ns`]), ns.
    pub t_capture_ns: u64,
    pub width_px: u32,
    pub height_px: u32,
    /// The rig sample this frame was taken at, or [`crate::NO_RIG_SAMPLE`].
    pub rig_sample_id: u64,
    /// Simulated scenario (see `producer::scenario::ScenarioKind::id`); 0 for replayed images.
    pub scenario_id: u32,
    /// 1 when `truth` holds the exact imposed motion (simulated frames), 0 otherwise.
    pub has_truth: u32,
    pub truth: GroundTruth,
    /// [`pixel_checksum`] of the payload, so a reader can prove the frame arrived intact.
    pub pixel_checksum: u64,
    /// Frames of one sequence (one test on one specimen) share it; when it changes, a
    /// consumer starts afresh (a correlator takes a new reference). 0 for a single sequence.
    pub sequence_id: u32,
    /// Always 0 (keeps the layout a multiple of 8 bytes).
    pub reserved: u32,
    /// The camera's own timestamp of the frame, ns on the camera's clock (its epoch is the
    /// camera's, not the host's: use it for intervals between frames, never against
    /// `t_capture_ns`); 0 when the source has no camera clock (simulated, replayed, watched).
    pub t_camera_ns: u64,
}

impl FrameHeader {
    /// Number of `u16` values in the payload.
    pub fn pixel_count(&self) -> usize {
        self.width_px as usize * self.height_px as usize
    }

    /// Checks the header is one this build understands and consistent with its payload length.
    pub fn validate(&self, payload_len: usize) -> Result<(), FrameError> {
        crate::layouts::check_version("frame", self.layout_version)?;
        if payload_len != self.pixel_count() {
            return Err(FrameError::PayloadLength {
                frame_id: self.frame_id,
                width_px: self.width_px,
                height_px: self.height_px,
                payload_len,
            });
        }
        if !matches!(self.bit_depth, 8 | 10 | 12 | 16) {
            return Err(FrameError::BitDepth {
                frame_id: self.frame_id,
                bit_depth: self.bit_depth,
            });
        }
        Ok(())
    }
}

/// Why a frame's header was refused by [`FrameHeader::validate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    #[error(transparent)]
    LayoutVersion(#[from] crate::layouts::LayoutVersionError),
    #[error("frame {frame_id} header says {width_px}x{height_px} = {} pixels but the payload holds {payload_len}", *.width_px as usize * *.height_px as usize)]
    PayloadLength {
        frame_id: u64,
        width_px: u32,
        height_px: u32,
        payload_len: usize,
    },
    #[error("frame {frame_id} has bit depth {bit_depth}, expected 8, 10, 12 or 16")]
    BitDepth { frame_id: u64, bit_depth: u32 },
}

impl Default for FrameHeader {
    fn default() -> Self {
        FrameHeader {
            layout_version: crate::LAYOUT_VERSION,
            bit_depth: 16,
            frame_id: 0,
            t_capture_ns: 0,
            width_px: 0,
            height_px: 0,
            rig_sample_id: crate::NO_RIG_SAMPLE,
            scenario_id: 0,
            has_truth: 0,
            truth: GroundTruth::IDENTITY,
            pixel_checksum: 0,
            sequence_id: 0,
            reserved: 0,
            t_camera_ns: 0,
        }
    }
}

/// A fast 64-bit checksum of pixel values (multiply-xorshift over 4-pixel words), about
/// 0.1-0.2 ms for a 1024x1024 frame: cheap enough to stamp every frame.
pub fn pixel_checksum(pixels: &[u16]) -> u64 {
    let mut hash = Checksum::new(pixels.len());
    let mut words = pixels.chunks_exact(4);
    for word in &mut words {
        hash.mix(
            word[0] as u64
                | (word[1] as u64) << 16
                | (word[2] as u64) << 32
                | (word[3] as u64) << 48,
        );
    }
    for &p in words.remainder() {
        hash.mix(p as u64);
    }
    hash.0
}

/// The same checksum over bytes (8-byte little-endian words, the tail byte-wise), for files
/// that must prove they were written whole.
pub fn byte_checksum(bytes: &[u8]) -> u64 {
    let mut hash = Checksum::new(bytes.len());
    let mut words = bytes.chunks_exact(8);
    for word in &mut words {
        hash.mix(u64::from_le_bytes(word.try_into().expect("8 bytes")));
    }
    for &b in words.remainder() {
        hash.mix(b as u64);
    }
    hash.0
}

/// Multiply-xorshift state shared by [`pixel_checksum`] and [`byte_checksum`].
struct Checksum(u64);

impl Checksum {
    fn new(len: usize) -> Self {
        Checksum(0xCBF2_9CE4_8422_2325 ^ len as u64)
    }

    #[inline]
    fn mix(&mut self, word: u64) {
        self.0 = (self.0 ^ word).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        self.0 ^= self.0 >> 29;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checksum_sees_a_single_changed_pixel_and_the_length() {
        let mut pixels: Vec<u16> = (0..1003).map(|i| (i * 7) as u16).collect();
        let a = pixel_checksum(&pixels);
        pixels[1001] ^= 1;
        assert_ne!(a, pixel_checksum(&pixels));
        pixels[1001] ^= 1;
        assert_eq!(a, pixel_checksum(&pixels));
        assert_ne!(a, pixel_checksum(&pixels[..1002]));
    }

    #[test]
    fn truth_displacement_of_a_rotation_about_a_centre() {
        let angle = 5f64.to_radians();
        let truth = GroundTruth {
            deformation_gradient: [angle.cos(), -angle.sin(), angle.sin(), angle.cos()],
            translation_px: [0.5, -0.25],
            centre_px: [100.0, 50.0],
            ..GroundTruth::IDENTITY
        };
        let (u, v) = truth.displacement_px(100.0, 50.0);
        assert!((u - 0.5).abs() < 1e-12 && (v + 0.25).abs() < 1e-12);
        let (u, v) = truth.displacement_px(110.0, 50.0);
        assert!((u - (10.0 * angle.cos() - 10.0 + 0.5)).abs() < 1e-12);
        assert!((v - (10.0 * angle.sin() - 0.25)).abs() < 1e-12);
    }

    #[test]
    fn validate_refuses_wrong_version_size_and_depth() {
        let header = FrameHeader {
            width_px: 4,
            height_px: 2,
            ..FrameHeader::default()
        };
        assert!(header.validate(8).is_ok());
        assert!(header
            .validate(7)
            .unwrap_err()
            .to_string()
            .contains("payload holds 7"));
        let old = FrameHeader {
            layout_version: 0,
            ..header
        };
        assert_eq!(
            old.validate(8).unwrap_err().to_string(),
            format!(
                "frame layout version 0 but this build reads version {}",
                crate::LAYOUT_VERSION
            )
        );
        let odd = FrameHeader {
            bit_depth: 9,
            ..header
        };
        assert_eq!(
            odd.validate(8).unwrap_err().to_string(),
            "frame 0 has bit depth 9, expected 8, 10, 12 or 16"
        );
    }
}
