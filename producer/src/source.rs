//! The seam the streaming loop uses: a `FrameSource` writes one frame into the caller's buffer
//! (a loaned shared-memory slice) and says what it was.

use crate::error::ProducerError;

/// The exact imposed motion of a simulated frame, x = c + F (X - c) + t.
///
/// For heterogeneous motions `homogeneous` is false and `f`, `translation_px` describe the
/// affine part at the centre (the gradient there and the displacement of the centre); the full
/// field comes from [`crate::Motion`] via [`crate::Scenario::motion_at`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Truth {
    /// Deformation gradient, row-major `[[F11, F12], [F21, F22]]` (dx/dX, dx/dY; dy/dX, dy/dY).
    pub f: [[f64; 2]; 2],
    /// Translation t, px (the displacement of the centre).
    pub translation_px: [f64; 2],
    /// Centre c of the homogeneous part, px, reference coordinates.
    pub centre_px: [f64; 2],
    /// Whether the motion is homogeneous (then the three fields above are the whole truth).
    pub homogeneous: bool,
    /// Stable numeric id of the scenario kind, see [`crate::ScenarioKind::id`].
    pub scenario_id: u32,
    /// The specimen's solve and the grips' displacements (mm) whose finite-element field the
    /// frame shows (`wire::GroundTruth::specimen_solve_id`); the fields above are then the
    /// filmed region's mean.
    pub specimen: Option<(u64, [f64; 4])>,
}

/// What a source says about the frame it wrote.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameInfo {
    /// Frame index within the source, from 0, consecutive.
    pub index: u64,
    /// The imposed motion for simulated frames; `None` for replay.
    pub truth: Option<Truth>,
    /// The rig sample (`wire::RigState::sample_id`) the frame was rendered from, for a
    /// rig-driven camera; `None` otherwise.
    pub rig_sample_id: Option<u64>,
    /// The frame sequence (`FrameHeader::sequence_id`): the rig's test index for rig-driven
    /// frames, 0 otherwise.
    pub sequence_id: u32,
}

/// Frame geometry of a source.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameDims {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Bit depth of the pixel values, 8 to 16; every pixel is below `1 << bit_depth`.
    pub bit_depth: u8,
}

impl FrameDims {
    /// Pixels per frame.
    pub fn len_px(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// A source of frames: the simulated camera or a replayed folder.
pub trait FrameSource {
    /// Frame geometry, constant over the life of the source.
    fn dims(&self) -> FrameDims;
    /// Number of frames the source will give, if finite.
    fn frames_total(&self) -> Option<u64>;
    /// Writes the next frame into `out` (exactly `dims().len_px()` pixels, row-major).
    /// Returns `Ok(None)` once the source is exhausted. No frame-sized allocation per call.
    fn next_frame(&mut self, out: &mut [u16]) -> Result<Option<FrameInfo>, ProducerError>;
}

pub(crate) fn check_buffer(dims: FrameDims, out: &[u16]) -> Result<(), ProducerError> {
    if out.len() == dims.len_px() {
        Ok(())
    } else {
        Err(ProducerError::BufferSize {
            found_px: out.len(),
            expected_px: dims.len_px(),
        })
    }
}
