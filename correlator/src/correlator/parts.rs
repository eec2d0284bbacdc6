//! The correlator's owned parts: the current reference and what is prepared from it, the
//! origin, what the last frames measured, the frame's results and the scratch buffers. Every
//! buffer is made in `Correlator::new` (or, for the reference and origin images, with the
//! first image given), so the frame loop allocates nothing.

use super::{Entry, RefNode};
use crate::icgn::bspline::Coefficients;
use crate::icgn::subset::SubsetStats;
use crate::interpolate::Mat2;
use crate::keypoints::KeypointSet;
use crate::zoi::{GradientSensitivity, ZoiResult};
use fft2d::Complex32;

/// The current reference image and what is prepared from it for every node.
pub(super) struct Reference {
    /// The image (row-major), None before the first reference.
    pub pixels: Option<Vec<u16>>,
    pub nodes: Vec<RefNode>,
    /// Spectra of the plain FFT ZOIs (`spectrum_len` per node).
    pub plain_spectra: Vec<Complex32>,
    /// Windowed, normalised reference ZOIs (n² per node, spatial).
    pub windowed: Vec<f32>,
    /// Per node, how its rigid estimate shifts under a displacement gradient.
    pub sensitivities: Vec<GradientSensitivity>,
    /// IC-GN: per node, the reference subset's f̂, ∂f̂/∂x, ∂f̂/∂y (3 n² values) and constants,
    /// prepared on first need (the node's first IC-GN against this reference, on the pool),
    /// so that a new reference costs no subset at all until a frame needs it.
    pub subset_planes: Vec<f32>,
    pub subset_stats: Vec<SubsetStats>,
    pub subset_states: Vec<SubsetState>,
    /// Method `icgn`: per node, the subset's second-order constants (the same planes), derived
    /// on its first second-order re-run against this reference (`order_stage.rs`).
    pub second_order_stats: Vec<SubsetStats>,
    pub second_order_states: Vec<SubsetState>,
    /// IC-GN: the reference's B-spline coefficients (the subsets' values), kept beside the
    /// frame's for the subsets prepared later.
    pub coefficients: Option<Coefficients>,
    /// The keypoints of this reference, detected on first need.
    pub keypoints: Option<KeypointSet>,
    /// The global correlator's reference is older than `pixels` (it is renewed only when a
    /// frame needs the global displacement).
    pub global_stale: bool,
    pub frames_since: u64,
    /// Nodes refused in the first frame against this reference (None before it), see
    /// `renewal.rs`.
    pub refused_first: Option<usize>,
    /// This reference is still the origin (the image the mesh was defined in).
    pub is_origin: bool,
    /// Live renewals: the nodes whose base (the total displacement the renewing frame
    /// measured through the references before it) still waits for its measurement against
    /// the origin, in the order they are measured (`reanchor.rs`,
    /// `Correlator::measure_pending_bases`); empty when none is pending.
    pub origin_pending: Vec<Entry>,
    /// The node the next pass against the origin starts from (where the last one stopped).
    pub origin_next_node: usize,
}

/// Whether a node's IC-GN reference subset is prepared.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) enum SubsetState {
    #[default]
    Unprepared,
    Ready,
    /// Flat (or a singular Hessian): the node is `low_contrast` against this reference.
    Flat,
}

/// The image the mesh was defined in (given to `set_reference`), for the measurements against
/// it (`reanchor`).
pub(super) struct Origin {
    pub pixels: Vec<u16>,
    /// IC-GN: its B-spline coefficients.
    pub coefficients: Option<Coefficients>,
}

/// The total displacements of the last two frames against this mesh, for the predictor.
pub(super) struct PreviousFrames {
    /// The last frame's (None: no usable value).
    pub last: Vec<Option<(f64, f64)>>,
    /// The frame before: with `last`, each node's velocity.
    pub before_last: Vec<Option<(f64, f64)>>,
    /// Camera frames from the one before last to the last (1 unless frames were dropped).
    pub last_step: u64,
}

/// What the frames since the mesh was defined measured.
pub(super) struct History {
    /// None before the first frame against this mesh.
    pub previous: Option<PreviousFrames>,
    /// IC-GN: each node's gradient against the current reference in the last frame (the next
    /// frame's guess), None when unknown.
    pub gradients: Vec<Option<Mat2>>,
    /// Nodes valid in every frame since the reference sequence began: they measure their own
    /// material. A node that failed once was carried by an extrapolation since, and may be
    /// off by that extrapolation's error (it follows whatever material it came back on).
    pub never_lost: Vec<bool>,
}

/// The frame being correlated, against the current reference.
pub(super) struct FrameResults {
    /// Initial guess per node (px).
    pub guesses: Vec<(f64, f64)>,
    pub results: Vec<ZoiResult>,
    /// The final check of each node's result (ZNCC, see `verify`), 0 when unchecked.
    pub zncc: Vec<f64>,
    /// IC-GN: the node's result is its prediction, taken without the FFT search (see
    /// `guess.rs`); the search runs when the final check refuses it.
    pub unsearched: Vec<bool>,
}

/// Buffers reused every frame (capacity: every node).
pub(super) struct Scratch {
    /// Nodes found inconsistent with their neighbours in this frame.
    pub outliers: Vec<bool>,
    /// Each node's distance to the affine fit of its neighbours (NaN: no fit).
    pub residuals: Vec<f64>,
    /// Nodes correlated a second time in this frame.
    pub retry: Vec<usize>,
    /// Scores of the valid nodes, for their median.
    pub scores: Vec<f64>,
    pub pairs: Vec<(f64, f64)>,
    /// Nodes to correlate again (growth, keypoints, refinement).
    pub entries: Vec<Entry>,
    /// Verified neighbours a node had when growth last tried it (it is tried again only
    /// when it has more).
    pub grown_from: Vec<u8>,
    /// Results of the returned nodes measured against the origin.
    pub reanchored: Vec<(ZoiResult, f64)>,
    /// Method `icgn`'s second order against the origin.
    pub origin_order: super::origin_order::OriginOrderScratch,
}

impl PreviousFrames {
    pub fn new(nodes: usize) -> Self {
        Self {
            last: vec![None; nodes],
            before_last: vec![None; nodes],
            last_step: 1,
        }
    }
}

impl History {
    pub fn new(nodes: usize) -> Self {
        Self {
            previous: None,
            gradients: vec![None; nodes],
            never_lost: vec![true; nodes],
        }
    }

    /// A new mesh: no previous frame, every node never lost.
    pub fn restart(&mut self) {
        self.previous = None;
        self.never_lost.fill(true);
    }
}

impl FrameResults {
    pub fn new(nodes: usize) -> Self {
        Self {
            guesses: vec![(0.0, 0.0); nodes],
            results: vec![ZoiResult::default(); nodes],
            zncc: vec![0.0; nodes],
            unsearched: vec![false; nodes],
        }
    }
}

impl Scratch {
    pub fn new(nodes: usize) -> Self {
        Self {
            outliers: vec![false; nodes],
            residuals: vec![0.0; nodes],
            retry: Vec::with_capacity(nodes),
            scores: Vec::with_capacity(nodes),
            pairs: vec![(0.0, 0.0); nodes],
            entries: Vec::with_capacity(nodes),
            grown_from: vec![0; nodes],
            reanchored: Vec::with_capacity(nodes),
            origin_order: super::origin_order::OriginOrderScratch::new(nodes),
        }
    }
}
