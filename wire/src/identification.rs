//! `identification`: the current state of the on-line hyperelastic identification.

#[cfg(feature = "ipc")]
use iceoryx2::prelude::ZeroCopySend;

/// Most coefficients one reported model may carry.
pub const MAX_COEFFICIENTS: usize = 8;
/// How many ranked models a report lists.
pub const MAX_RANKED: usize = 8;

/// One fitted model in the ranking.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.RankedModel.v5")
)]
pub struct RankedModel {
    /// NUL-padded model name (identifier crate names), see [`crate::text`].
    pub name: [u8; 24],
    pub aic: f64,
    pub rms_mpa: f64,
}

/// Header-only sample on `identification` (no payload slice).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.IdentificationReport.v5")
)]
pub struct IdentificationReport {
    pub layout_version: u32,
    /// Points of the load path used, per load case: uniaxial, equibiaxial, pure shear.
    pub points: [u32; 3],
    /// The field (frame) that triggered this refit and its capture time (monotonic ns).
    pub frame_id: u64,
    pub t_capture_ns: u64,
    pub t_published_ns: u64,
    /// Coefficients of f: ln f = Σ a_i (I1 − 3)^i (MPa), `a_count` of them; and of g:
    /// ln g = Σ b_i (I2 − 3)^i (MPa), `b_count` of them (the paper's eqs. 22 and 25).
    pub a: [f64; MAX_COEFFICIENTS],
    pub a_stderr: [f64; MAX_COEFFICIENTS],
    pub b: [f64; MAX_COEFFICIENTS],
    pub b_stderr: [f64; MAX_COEFFICIENTS],
    pub a_count: u32,
    pub b_count: u32,
    pub rms_mpa: f64,
    pub ranked_count: u32,
    pub ranking: [RankedModel; MAX_RANKED],
}

impl Default for IdentificationReport {
    fn default() -> Self {
        IdentificationReport {
            layout_version: crate::LAYOUT_VERSION,
            points: [0; 3],
            frame_id: 0,
            t_capture_ns: 0,
            t_published_ns: 0,
            a: [0.0; MAX_COEFFICIENTS],
            a_stderr: [0.0; MAX_COEFFICIENTS],
            b: [0.0; MAX_COEFFICIENTS],
            b_stderr: [0.0; MAX_COEFFICIENTS],
            a_count: 0,
            b_count: 0,
            rms_mpa: 0.0,
            ranked_count: 0,
            ranking: [RankedModel {
                name: [0; 24],
                aic: 0.0,
                rms_mpa: 0.0,
            }; MAX_RANKED],
        }
    }
}
