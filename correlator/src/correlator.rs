//! The correlator: mesh, reference cache, worker pool, the assembly of a field (final
//! corrections, consistency, strains). The first pass's guesses are in `guess.rs`, the rescue
//! of failed nodes in `growth.rs`, IC-GN in `icgn_stage.rs`, the followed mesh at a reference
//! update in `followed.rs`, when the automatic reference is renewed in `renewal.rs`,
//! measurements against the origin in `reanchor.rs`.

mod assemble;
mod followed;
mod growth;
mod guess;
mod icgn_stage;
mod neighbour_check;
mod order_stage;
mod origin_order;
mod parts;
mod reanchor;
mod renewal;

use crate::field::{Field, Node, NodeStatus};
use crate::global::GlobalCorrelator;
use crate::icgn::bspline::Coefficients;
use crate::icgn::subset::SubsetStats;
use crate::interpolate::{identity_plus, Mat2};
use crate::keypoints::KeypointMatcher;
use crate::mesh::Mesh;
use crate::pool::{Pool, SharedSlice};
use crate::settings::{CorrelatorSettings, GuessMode, Method, Roi, SettingsError};
use crate::strain::AffineSums;
use crate::zoi::{
    spectrum_len, GradientSensitivity, Image, SubpixelIterations, TimeSplit, ZoiResult,
};
use fft2d::Complex32;
use parts::{FrameResults, History, Origin, Reference, Scratch, SubsetState};

/// Per-node state of the current reference image.
#[derive(Clone, Copy, Debug, Default)]
struct RefNode {
    /// ZOI top-left in the current reference image (px).
    top_left: (usize, usize),
    /// Followed position minus ZOI centre (px), |r| <= 0.5: the ZOI is on the pixel grid.
    offset_px: (f64, f64),
    /// Total displacement of the node when the current reference was taken (px).
    base_px: (f64, f64),
    /// Total displacement gradient of the node then (against the origin).
    base_gradient: Mat2,
    /// Ok, or why this node cannot be correlated against this reference.
    status: NodeStatus,
}

/// Frames over which the live path measures a renewed reference's bases against the origin,
/// a part after each frame's field is out ([`Correlator::measure_pending_bases`]): a renewal
/// then adds a quarter of that measurement to each of the next four frames instead of all of it
/// to one.
pub const ORIGIN_PASS_FRAMES: usize = 4;

/// Rings of neighbours whose affine fit places a failed node at a reference update.
const EXTRAPOLATION_RINGS: usize = 2;
/// Rings of neighbours whose affine fit gives what a node's surroundings say of it where the
/// field may be steep: the outlier check's prediction (`neighbour_check.rs`) and the gradient
/// a base is measured through against the origin (`reanchor.rs`); [`EXTRAPOLATION_RINGS`]
/// where this ring holds fewer than [`MIN_EXTRAPOLATION_NODES`] valid nodes. Beside the
/// cruciform's fillets a plane over two rings (64 px at step 16) misses the field's curvature:
/// correli's node error p99 on the finite-element cruciform (`tests/suite/structure.rs`) went
/// from 0.109 to 0.074 px with the nearest ring in both.
const LOCAL_RINGS: usize = 1;
/// Rings of never-lost neighbours whose affine fit carries a node whose material is out of
/// the image (or failed) to the next reference.
const CARRY_RINGS: usize = 5;
/// Valid nodes an extrapolating fit needs.
const MIN_EXTRAPOLATION_NODES: usize = 6;
/// A node whose displacement since the reference is further from what its neighbours (within
/// [`EXTRAPOLATION_RINGS`]) predict (`neighbour_check.rs`) than
/// [`OUTLIER_SCATTER`] times the frame's median distance, bounded to [`OUTLIER_MIN_PX`,
/// `OUTLIER_MAX_PX`], is inconsistent: about seven standard deviations of the measurement noise,
/// never less than the half pixel that makes a wrong value, never more than 2 px.
const OUTLIER_SCATTER: f64 = 6.0;
const OUTLIER_MIN_PX: f64 = 0.5;
const OUTLIER_MAX_PX: f64 = 2.0;

/// A node to correlate again: its guess (px, against the current reference) and the gradient
/// to sample its deformed ZOI through.
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    node: usize,
    guess_px: (f64, f64),
    gradient: Mat2,
}

/// Least-squares gradient of the `ok` results over the 3x3 nodes around k (ZOI centres of an
/// nx x ny mesh).
fn result_gradient(
    results: &[ZoiResult],
    ref_nodes: &[RefNode],
    mesh: (usize, usize),
    k: usize,
) -> Option<nalgebra::Matrix2<f64>> {
    neighbourhood_gradient(results, ref_nodes, mesh, k, |r| (r.u_px, r.v_px))
}

/// Least-squares gradient, over the `ok` results of the 3x3 nodes around k (ZOI centres of an
/// nx x ny mesh), of the pair of values `value` reads from each result: [[∂a/∂x, ∂a/∂y],
/// [∂b/∂x, ∂b/∂y]]; None with fewer than 3 such nodes or collinear ones.
fn neighbourhood_gradient(
    results: &[ZoiResult],
    ref_nodes: &[RefNode],
    (nx, ny): (usize, usize),
    k: usize,
    value: impl Fn(&ZoiResult) -> (f64, f64),
) -> Option<nalgebra::Matrix2<f64>> {
    let (i, j) = (k % nx, k / nx);
    let mut sums = AffineSums::default();
    for jj in j.saturating_sub(1)..=(j + 1).min(ny - 1) {
        for ii in i.saturating_sub(1)..=(i + 1).min(nx - 1) {
            let m = jj * nx + ii;
            if results[m].status != NodeStatus::Ok {
                continue;
            }
            let (a, b) = (ref_nodes[m].top_left, ref_nodes[k].top_left);
            let (va, vb) = value(&results[m]);
            sums.add(a.0 as f64 - b.0 as f64, a.1 as f64 - b.1 as f64, va, vb);
        }
    }
    sums.gradient()
}

/// Median of the finite `values`, using `scratch` (no allocation once it holds every node);
/// None when there are none.
fn median(values: impl Iterator<Item = f64>, scratch: &mut Vec<f64>) -> Option<f64> {
    scratch.clear();
    scratch.extend(values.filter(|v| v.is_finite()));
    if scratch.is_empty() {
        return None;
    }
    let middle = scratch.len() / 2;
    Some(*scratch.select_nth_unstable_by(middle, f64::total_cmp).1)
}

/// Median score of the valid results (0 when none).
fn median_ok_score(results: impl Iterator<Item = ZoiResult>, scratch: &mut Vec<f64>) -> f64 {
    median(
        results
            .filter(|r| r.status == NodeStatus::Ok)
            .map(|r| r.score),
        scratch,
    )
    .unwrap_or(0.0)
}

/// a − b.
fn difference(a: Mat2, b: Mat2) -> Mat2 {
    [
        [a[0][0] - b[0][0], a[0][1] - b[0][1]],
        [a[1][0] - b[1][0], a[1][1] - b[1][1]],
    ]
}

/// A nalgebra gradient as the row-major matrix of the warps.
fn to_mat2(g: nalgebra::Matrix2<f64>) -> Mat2 {
    [[g[(0, 0)], g[(0, 1)]], [g[(1, 0)], g[(1, 1)]]]
}

/// (I + a)(I + b) − I: the total gradient of a gradient `a` measured against a reference
/// whose own gradient was `b`.
fn compose_gradients(a: Mat2, b: Mat2) -> Mat2 {
    let (fa, fb) = (identity_plus(a), identity_plus(b));
    let mut out = [[0.0; 2]; 2];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, value) in row.iter_mut().enumerate() {
            *value = fa[r][0] * fb[0][c] + fa[r][1] * fb[1][c] - if r == c { 1.0 } else { 0.0 };
        }
    }
    out
}

/// When a renewal measures the new reference's bases against the origin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum OriginBases {
    /// At the renewal ([`Correlator::correlate_after`]).
    Now,
    /// Later, a part at a time ([`Correlator::measure_pending_bases`], the live path).
    Deferred,
}

/// Whose B-spline coefficients an IC-GN measurement against the origin samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FrameCoefficients {
    /// The frame just correlated.
    Frame,
    /// The current reference.
    Reference,
}

/// Which valid nodes an affine fit may use.
#[derive(Clone, Copy)]
enum Support {
    Valid,
    /// Only nodes valid in every frame since the reference sequence began.
    NeverLost,
}

/// An affine fit of total displacements: (u, v) at `origin_px` and the gradient ∇u.
#[derive(Clone, Copy)]
struct AffineFit {
    origin_px: (f64, f64),
    at_origin_px: (f64, f64),
    gradient: nalgebra::Matrix2<f64>,
}

/// CORRELI-GD correlator for images of one size. See the crate documentation.
pub struct Correlator {
    settings: CorrelatorSettings,
    width_px: usize,
    height_px: usize,
    roi: Roi,
    /// Side of the FFT ZOIs (the guess for IC-GN) and their offset inside the node's ZOI or
    /// subset ((zoi − fft) / 2 px, both axes).
    fft_px: usize,
    fft_pad_px: usize,
    /// IC-GN: the B-spline coefficients of the image being correlated (the reference's while
    /// a reference is prepared), made in `new`.
    coefficients: Option<Coefficients>,
    /// The prefilter's time, for the time split (profiling only).
    profiling: bool,
    coefficients_ns: u64,
    mesh: Mesh,
    pool: Pool,
    global: GlobalCorrelator,
    /// Made on first need (a reference whose cheaper guesses did not verify).
    keypoint_matcher: Option<KeypointMatcher>,
    reference: Reference,
    /// The frame the mesh was defined in, while this correlator knows it.
    origin: Option<Origin>,
    /// Counts the origins this correlator has had (the state folder rewrites its copy when it
    /// changes).
    origin_generation: u64,
    history: History,
    /// Camera frames since the last frame correlated (see [`Correlator::correlate_after`]).
    frame_step: u64,
    frame: FrameResults,
    scratch: Scratch,
    field: Field,
}

/// The reference image, which every correlation after the first `set_reference` has.
fn reference_pixels(pixels: &Option<Vec<u16>>) -> &[u16] {
    pixels
        .as_deref()
        .expect("a reference is set before correlating")
}

impl Correlator {
    /// Validates the settings against the image size and makes every buffer, plan and thread.
    pub fn new(
        settings: CorrelatorSettings,
        width_px: usize,
        height_px: usize,
    ) -> Result<Self, SettingsError> {
        settings.validate()?;
        let region = settings.resolve_region(width_px, height_px)?;
        for gauge in &settings.gauges {
            gauge
                .check_inside(width_px, height_px)
                .map_err(SettingsError::Gauge)?;
        }
        let mesh = Mesh::of_region(&region, settings.zoi_px, settings.step_px);
        if mesh.measured() == 0 {
            return Err(SettingsError::RegionSmallerThanZoi {
                region: settings.region.to_string(),
                zoi_px: settings.zoi_px,
            });
        }
        // Where the mesh is: the global correlation and the keypoints look there.
        let roi = region.mesh_rect;
        let nodes = mesh.len();
        let fft_px = settings.fft_zoi_px();
        let n2 = spectrum_len(fft_px);
        let icgn = settings.method.is_icgn();
        let adaptive_nodes = if settings.method == Method::Icgn {
            nodes
        } else {
            0
        };
        let subset_values = if icgn {
            crate::icgn::subset::PLANES * settings.zoi_px * settings.zoi_px
        } else {
            0
        };
        let zero = Complex32::new(0.0, 0.0);
        let mut field = Field {
            nx: mesh.nx,
            ny: mesh.ny,
            nodes: vec![Node::default(); nodes],
            gradients: vec![[[0.0; 2]; 2]; nodes],
            second_order: vec![false; nodes],
            gauges: Vec::with_capacity(settings.gauges.len()),
            ..Field::default()
        };
        for (k, node) in field.nodes.iter_mut().enumerate() {
            let (x, y) = mesh.centre_px(k, settings.zoi_px);
            node.x_px = x;
            node.y_px = y;
        }
        let ref_nodes = (0..nodes)
            .map(|k| RefNode {
                top_left: mesh.top_left[k],
                ..RefNode::default()
            })
            .collect();
        Ok(Self {
            pool: Pool::new(settings.threads, fft_px, subset_values),
            fft_px,
            fft_pad_px: (settings.zoi_px - fft_px) / 2,
            coefficients: icgn.then(|| Coefficients::new(width_px, height_px)),
            profiling: false,
            coefficients_ns: 0,
            global: GlobalCorrelator::new(roi),
            keypoint_matcher: None,
            reference: Reference {
                pixels: None,
                nodes: ref_nodes,
                plain_spectra: vec![zero; nodes * n2],
                windowed: vec![0.0; nodes * fft_px * fft_px],
                sensitivities: vec![GradientSensitivity::default(); nodes],
                subset_planes: vec![0.0; nodes * subset_values],
                subset_stats: vec![SubsetStats::default(); if icgn { nodes } else { 0 }],
                subset_states: vec![SubsetState::default(); if icgn { nodes } else { 0 }],
                second_order_stats: vec![SubsetStats::default(); adaptive_nodes],
                second_order_states: vec![SubsetState::default(); adaptive_nodes],
                coefficients: icgn.then(|| Coefficients::new(width_px, height_px)),
                keypoints: None,
                global_stale: true,
                frames_since: 0,
                refused_first: None,
                is_origin: true,
                origin_pending: Vec::with_capacity(nodes),
                origin_next_node: 0,
            },
            origin: None,
            origin_generation: 0,
            history: History::new(nodes),
            frame_step: 1,
            frame: FrameResults::new(nodes),
            scratch: Scratch::new(nodes),
            field,
            settings,
            width_px,
            height_px,
            roi,
            mesh,
        })
    }

    pub fn settings(&self) -> &CorrelatorSettings {
        &self.settings
    }

    /// The rectangle the mesh covers: the ROI, or the bounding box of the region's shape in it.
    pub fn roi(&self) -> Roi {
        self.roi
    }

    /// Nodes whose ZOI lies inside the region (the others are `outside_region` in every field).
    pub fn nodes_in_region(&self) -> usize {
        self.mesh.measured()
    }

    /// Mesh size (nx, ny).
    pub fn mesh_size(&self) -> (usize, usize) {
        (self.mesh.nx, self.mesh.ny)
    }

    /// The last field computed.
    pub fn field(&self) -> &Field {
        &self.field
    }

    fn check_size(&self, what: &'static str, pixels: &[u16]) -> Result<(), SettingsError> {
        let expected = self.width_px * self.height_px;
        if pixels.len() != expected {
            return Err(SettingsError::ImageSize {
                what,
                got: pixels.len(),
                expected,
                width_px: self.width_px,
                height_px: self.height_px,
            });
        }
        Ok(())
    }

    /// Sets the reference image (row-major u16, the size given to `new`); the mesh restarts at
    /// the nodes' initial positions and previous fields are forgotten.
    pub fn set_reference(&mut self, pixels: &[u16]) -> Result<(), SettingsError> {
        self.check_size("reference", pixels)?;
        for (k, r) in self.reference.nodes.iter_mut().enumerate() {
            *r = RefNode {
                top_left: self.mesh.top_left[k],
                ..RefNode::default()
            };
        }
        self.history.restart();
        self.reference.origin_pending.clear();
        self.set_origin_pixels(pixels);
        self.reference.is_origin = true;
        self.take_reference(pixels, false);
        self.origin_coefficients_from_reference();
        Ok(())
    }

    /// Image size this correlator was made for (width, height) in px.
    pub fn image_size(&self) -> (usize, usize) {
        (self.width_px, self.height_px)
    }

    /// The current reference image (row-major), or None before the first reference.
    pub fn reference_pixels(&self) -> Option<&[u16]> {
        self.reference.pixels.as_deref()
    }

    /// Nodes of the current reference that have enough texture to be correlated (0 for a flat
    /// image, or before the first reference).
    pub fn reference_textured_nodes(&self) -> usize {
        if self.reference.pixels.is_none() {
            return 0;
        }
        self.reference
            .nodes
            .iter()
            .filter(|r| r.status == NodeStatus::Ok)
            .count()
    }

    /// Total displacement (px) of every node, row-major, when the current reference was taken:
    /// zero for a reference given to `set_reference`, the accumulated field after an
    /// incremental or automatic reference update. With [`Correlator::reference_pixels`] this is
    /// everything [`Correlator::restore_reference`] needs to resume measuring the same total
    /// displacement in another process.
    pub fn reference_base_px(&self) -> impl ExactSizeIterator<Item = (f64, f64)> + '_ {
        self.reference.nodes.iter().map(|r| r.base_px)
    }

    /// Resumes against a saved reference: its pixels and the per-node base displacements read
    /// from [`Correlator::reference_base_px`] (one pair per node, row-major). Afterwards the
    /// correlator is in the state it was right after that reference was taken, except that the
    /// previous frame's field is unknown (the predictor grows from the centre once) and every
    /// node counts as never lost (the saved state does not say which nodes were carried).
    pub fn restore_reference(
        &mut self,
        pixels: &[u16],
        base_px: &[(f64, f64)],
    ) -> Result<(), SettingsError> {
        self.check_size("reference", pixels)?;
        if base_px.len() != self.reference.nodes.len() {
            return Err(SettingsError::BaseLength {
                got: base_px.len(),
                expected: self.reference.nodes.len(),
            });
        }
        if let Some(k) = base_px
            .iter()
            .position(|b| !(b.0.is_finite() && b.1.is_finite()))
        {
            return Err(SettingsError::BaseNotFinite { node: k });
        }
        for ((k, r), &base) in self.reference.nodes.iter_mut().enumerate().zip(base_px) {
            *r = RefNode {
                top_left: self.mesh.top_left[k],
                base_px: base,
                ..RefNode::default()
            };
        }
        self.history.restart();
        self.reference.origin_pending.clear();
        // The saved state holds the current reference, not the frame the mesh was defined in
        // (unless they are the same: every base is zero).
        self.reference.is_origin = base_px.iter().all(|&b| b == (0.0, 0.0));
        if self.reference.is_origin {
            self.set_origin_pixels(pixels);
        } else {
            self.origin = None;
        }
        // The gradient at each base: the least-squares fit of the saved bases around it.
        for k in 0..self.reference.nodes.len() {
            self.reference.nodes[k].base_gradient = self.base_fit_gradient(k);
        }
        self.take_reference(pixels, false);
        if self.reference.is_origin {
            self.origin_coefficients_from_reference();
        }
        Ok(())
    }

    /// The frame the mesh is defined in (the image given to `set_reference`), while this
    /// correlator knows it: a correlator restored from a saved reference knows it only when
    /// that reference is the origin or [`Correlator::restore_origin`] gave it back.
    pub fn origin_pixels(&self) -> Option<&[u16]> {
        self.origin.as_ref().map(|origin| origin.pixels.as_slice())
    }

    /// Changes whenever the origin changes (a new `set_reference`).
    pub fn origin_generation(&self) -> u64 {
        self.origin_generation
    }

    /// Gives a restored correlator back the frame its mesh is defined in (saved beside the
    /// reference), so that its bases are measured against it again at reference updates.
    pub fn restore_origin(&mut self, pixels: &[u16]) -> Result<(), SettingsError> {
        self.check_size("origin", pixels)?;
        self.set_origin_pixels(pixels);
        let origin = self.origin.as_mut().and_then(|o| o.coefficients.take());
        if let Some(mut coefficients) = origin {
            self.prefilter_into(&mut coefficients, pixels);
            if let Some(origin) = &mut self.origin {
                origin.coefficients = Some(coefficients);
            }
        }
        Ok(())
    }

    /// A new origin: its pixels (into the buffers of the last one when there was one), its
    /// B-spline coefficients still to be computed by the caller.
    fn set_origin_pixels(&mut self, pixels: &[u16]) {
        match &mut self.origin {
            Some(origin) => origin.pixels.copy_from_slice(pixels),
            None => {
                let icgn = self.settings.method.is_icgn();
                self.origin = Some(Origin {
                    pixels: pixels.to_vec(),
                    coefficients: icgn.then(|| Coefficients::new(self.width_px, self.height_px)),
                });
            }
        }
        self.origin_generation += 1;
    }

    /// Copies the pixels as the current reference and prepares the spectra (and IC-GN subsets)
    /// of every node at its followed position (`ref_nodes[k].base_px` must be set).
    /// `coefficients_hold_pixels`: the B-spline coefficients are already those of `pixels`
    /// (the frame just correlated becomes the reference).
    fn take_reference(&mut self, pixels: &[u16], coefficients_hold_pixels: bool) {
        match &mut self.reference.pixels {
            Some(reference) => reference.copy_from_slice(pixels),
            None => self.reference.pixels = Some(pixels.to_vec()),
        }
        self.history.gradients.fill(None);
        let n = self.settings.zoi_px;
        let (fft, pad) = (self.fft_px, self.fft_pad_px);
        let half = (n as f64 - 1.0) / 2.0;
        let image = Image {
            pixels: reference_pixels(&self.reference.pixels),
            width_px: self.width_px,
            height_px: self.height_px,
        };
        for (k, r) in self.reference.nodes.iter_mut().enumerate() {
            let (x, y) = (
                self.field.nodes[k].x_px + r.base_px.0,
                self.field.nodes[k].y_px + r.base_px.1,
            );
            let (tx, ty) = ((x - half).round(), (y - half).round());
            r.offset_px = (x - (tx + half), y - (ty + half));
            if !self.mesh.in_region[k] {
                r.status = NodeStatus::OutsideRegion;
            } else if image.contains_block(tx as i64, ty as i64, n) {
                r.top_left = (tx as usize, ty as usize);
                r.status = NodeStatus::Ok;
            } else {
                r.status = NodeStatus::OutsideImage;
            }
        }
        self.reference.global_stale = true;
        self.reference.keypoints = None;
        let n2 = spectrum_len(fft);
        let plain = SharedSlice::new(&mut self.reference.plain_spectra);
        let windowed = SharedSlice::new(&mut self.reference.windowed);
        let sensitivities = SharedSlice::new(&mut self.reference.sensitivities);
        let ref_nodes = SharedSlice::new(&mut self.reference.nodes);
        self.pool.run(self.mesh.len(), &|engine, k| {
            // SAFETY: item k touches only node k's slots.
            let mut r = unsafe { ref_nodes.read(k) };
            if r.status != NodeStatus::Ok {
                return;
            }
            let nn = fft * fft;
            let (p, w) = unsafe { (plain.slice_mut(k * n2, n2), windowed.slice_mut(k * nn, nn)) };
            let mut sensitivity = GradientSensitivity::default();
            let (x0, y0) = (r.top_left.0 + pad, r.top_left.1 + pad);
            let ok = engine.prepare_reference(image, x0, y0, p, w, &mut sensitivity)
                && !engine.reference_has_flat_side();
            unsafe { sensitivities.write(k, sensitivity) };
            if !ok {
                r.status = NodeStatus::LowContrast;
                unsafe { ref_nodes.write(k, r) };
            }
        });
        if self.settings.method.is_icgn() {
            if !coefficients_hold_pixels {
                self.prefilter(pixels);
            }
            self.keep_reference_coefficients();
        }
        self.reference.frames_since = 0;
        self.reference.refused_first = None;
    }

    /// Correlates one deformed image against the current reference and returns the field.
    /// The image is the camera's next frame after the last one correlated (see
    /// [`Correlator::correlate_after`] when frames were dropped).
    pub fn correlate(&mut self, pixels: &[u16]) -> Result<&Field, SettingsError> {
        self.correlate_after(pixels, 1)
    }

    /// [`Correlator::correlate`] of the camera frame `frame_step` frames after the last one
    /// correlated (a live correlator that dropped frames while busy): the predictions extrapolate
    /// each node's velocity over that many frames, so they still place the ZOIs within a pixel
    /// and the integer search is still skipped. A frame that renews the reference
    /// (`Field::reference_updated`) has become it when this returns, its bases measured
    /// against the origin.
    pub fn correlate_after(
        &mut self,
        pixels: &[u16],
        frame_step: u64,
    ) -> Result<&Field, SettingsError> {
        self.correlate_field(pixels, frame_step)?;
        if self.field.reference_updated {
            self.renew(pixels, OriginBases::Now);
        }
        Ok(&self.field)
    }

    /// The live path's [`Correlator::correlate_after`]: the frame's field, and whether the
    /// frame is to become the reference (`Field::reference_updated`), without renewing it yet:
    /// the caller publishes the field first, then calls [`Correlator::renew_reference`] with
    /// the same pixels before the next frame. A renewal's work is then off the latency of the
    /// frame that calls for it.
    pub fn correlate_field(
        &mut self,
        pixels: &[u16],
        frame_step: u64,
    ) -> Result<&Field, SettingsError> {
        self.field.reference_updated = false;
        self.frame_step = frame_step.max(1);
        self.check_size("deformed", pixels)?;
        if self.reference.pixels.is_none() {
            return Err(SettingsError::NoReference);
        }
        let image = Image {
            pixels,
            width_px: self.width_px,
            height_px: self.height_px,
        };
        self.field.keypoints_used = false;
        let icgn = self.settings.method.is_icgn();
        if icgn {
            self.prefilter(pixels);
        }
        self.run_zois(image);
        self.verify_results(image);
        if icgn {
            self.search_unconfirmed(image);
        }
        if self.settings.guess == GuessMode::Auto {
            self.improve(image);
        }
        if icgn {
            self.refine_icgn(image);
        }
        self.refine_second_order(image);
        self.assemble(image);
        self.decide_renewal();
        Ok(&self.field)
    }

    /// After [`Correlator::correlate_field`] said `reference_updated`: its frame (`pixels`, the
    /// same image) becomes the reference. Its bases, the total displacements it measured
    /// through the references before it, are measured against the origin later, a part at a
    /// time ([`Correlator::measure_pending_bases`]), instead of at once as
    /// [`Correlator::correlate_after`] does (the renewal's largest cost). Does nothing when the
    /// last field did not call for a renewal, or was already renewed.
    pub fn renew_reference(&mut self, pixels: &[u16]) -> Result<(), SettingsError> {
        self.check_size("deformed", pixels)?;
        if self.field.reference_updated && self.reference.frames_since > 0 {
            self.renew(pixels, OriginBases::Deferred);
        }
        Ok(())
    }

    /// Bases of the current reference still to be measured against the origin (after
    /// [`Correlator::renew_reference`]).
    pub fn pending_bases(&self) -> usize {
        self.reference.origin_pending.len()
    }

    /// Measures the next part of the pending bases against the origin (a part is the mesh
    /// over [`ORIGIN_PASS_FRAMES`]: the reference's ZOIs of the origin correlated with the
    /// reference image, each from its base, and the final check) and corrects those that
    /// verify. Returns true when this measured the last one: the bases changed since the
    /// renewal (a saved state is worth writing again).
    pub fn measure_pending_bases(&mut self) -> bool {
        self.measure_some_pending_bases(self.mesh.len().div_ceil(ORIGIN_PASS_FRAMES))
    }

    /// Least-squares gradient of the current results over the 3x3 nodes around k (ZOI centres).
    fn result_gradient(&self, k: usize) -> Option<nalgebra::Matrix2<f64>> {
        result_gradient(
            &self.frame.results,
            &self.reference.nodes,
            (self.mesh.nx, self.mesh.ny),
            k,
        )
    }

    /// Sum of the engines' time splits (profiling must be switched on with `set_profiling`).
    pub fn time_split(&self) -> TimeSplit {
        let mut total = TimeSplit {
            coefficients_ns: self.coefficients_ns,
            ..TimeSplit::default()
        };
        for i in 0..self.pool.threads() {
            total.add(&self.pool.engine(i).split);
        }
        total
    }

    /// Integer FFT searches run by this correlator so far (every ZOI correlation that did not
    /// take a confirmed prediction's shortcut, the measurements against the origin included).
    pub fn fft_searches(&self) -> u64 {
        (0..self.pool.threads())
            .map(|i| self.pool.engine(i).searches)
            .sum()
    }

    /// Switches the per-engine time split on or off and resets it (benchmark only: reads the clock in the hot loop).
    pub fn set_profiling(&mut self, on: bool) {
        self.profiling = on;
        self.coefficients_ns = 0;
        for i in 0..self.pool.threads() {
            let mut engine = self.pool.engine(i);
            engine.profile = on;
            engine.split = TimeSplit::default();
        }
    }
}

/// The FFT stage's sub-pixel iterations: the paper's with the settings' cap for `correli`;
/// for the IC-GN methods, whose every guess IC-GN refines, at most
/// [`crate::zoi::ICGN_GUESS_ITERATIONS`] with [`crate::zoi::ICGN_GUESS_NOT_CONVERGED_STEP_PX`].
fn fft_iterations(settings: &CorrelatorSettings) -> SubpixelIterations {
    if settings.method.is_icgn() {
        SubpixelIterations {
            max: settings
                .max_iterations
                .min(crate::zoi::ICGN_GUESS_ITERATIONS),
            not_converged_step_px: crate::zoi::ICGN_GUESS_NOT_CONVERGED_STEP_PX,
        }
    } else {
        SubpixelIterations::paper(settings.max_iterations)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::zoi::{ICGN_GUESS_ITERATIONS, ICGN_GUESS_NOT_CONVERGED_STEP_PX};

    /// `correli` keeps the paper's iterations; the IC-GN methods' guess stops at its own cap
    /// (or the settings' when lower) with its own not-converged bound.
    #[test]
    fn the_icgn_guess_has_its_own_iteration_cap_and_correli_the_papers() {
        let with = |method, max_iterations| CorrelatorSettings {
            method,
            zoi_px: if method == Method::Correli { 32 } else { 33 },
            max_iterations,
            ..CorrelatorSettings::default()
        };
        assert_eq!(
            fft_iterations(&with(Method::Correli, 10)),
            SubpixelIterations::paper(10)
        );
        for method in [Method::Icgn1, Method::Icgn2] {
            let cap = fft_iterations(&with(method, 10));
            assert_eq!(cap.max, ICGN_GUESS_ITERATIONS);
            assert_eq!(cap.not_converged_step_px, ICGN_GUESS_NOT_CONVERGED_STEP_PX);
            assert_eq!(fft_iterations(&with(method, 1)).max, 1);
        }
    }
}
