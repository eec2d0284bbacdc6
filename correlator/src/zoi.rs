//! One ZOI, CORRELI-GD style (paper section 3.b): integer FFT correlation and move, then
//! modified-Hanning windowed correlation, 3x3 quadratic sub-pixel peak and Fourier-shift
//! iterations while the interpolated maximum increases. A `ZoiEngine` owns its FFT plans and
//! buffers (one per worker thread) and never allocates after `new`.
//!
//! The sub-pixel steps need the windowed correlation only at the 3x3 shifts around its peak, not
//! the whole map: those values are computed directly as circular dot products of the windowed
//! ZOIs in space, c(d) = Σ_x g_w(x + d) f_w(x), which is exactly what the inverse FFT of
//! G_w conj(F_w) gives at d, without the forward and inverse transforms.

use crate::field::NodeStatus;
pub use crate::image::Image;
use crate::interpolate::{apply, bicubic, bicubic_clamped, identity_plus, Mat2, WarpedBlock};
use crate::peak::quadratic_peak_3x3;
use crate::simd::{dot, F32x4};
use crate::window::modified_hanning_2d;
use fft2d::Complex32;
use fft2d::RealFft2d;

mod flat_side;

/// A ZOI whose grey-level standard deviation is below this (in image counts) is `LowContrast`.
pub const MIN_STD_COUNTS: f32 = 0.5;
/// Sub-pixel iterations stop when the correction is below this (px).
pub const CONVERGED_STEP_PX: f64 = 1e-3;
/// A ZOI whose last correction at the iteration cap is above this (px) is `NotConverged`.
pub const NOT_CONVERGED_STEP_PX: f64 = 0.02;
/// The sub-pixel corrections shrink geometrically (each quadratic peak fit leaves a fixed
/// fraction of the residual, 0.1 to 0.25 of it): once two corrections show a ratio below
/// [`MAX_CONTRACTION`] and the next one is predicted (the last times that ratio) below this
/// (px), the iterations stop. A correction below [`CONVERGED_STEP_PX`] leaves about the same
/// residual (the ratio times it), so the estimate is as converged, one Fourier shift sooner.
pub const PREDICTED_STEP_PX: f64 = 2.5e-4;
/// The largest ratio of two successive corrections that [`PREDICTED_STEP_PX`] trusts.
pub const MAX_CONTRACTION: f64 = 0.5;
/// Cap of the sub-pixel iterations of the IC-GN methods' FFT guess: IC-GN refines every guess,
/// and from the estimate after one Fourier shift it needs as many iterations as from a fully
/// converged one (2.11 per ZOI on DIC Challenge sample 14 at 33 px either way), while each
/// Fourier-shift iteration costs a shift, a window and a peak search. From the first estimate
/// alone (no shift) sample 5's std v rose past its 0.0027 px bound and synthetic speckle took
/// 2.31 IC-GN iterations per ZOI instead of 1.99.
pub const ICGN_GUESS_ITERATIONS: u32 = 2;
/// [`NOT_CONVERGED_STEP_PX`] of the IC-GN methods' guess at its cap: the guess is good enough
/// for IC-GN (which converges from a fraction of a speckle away) when its last correction is
/// below this; above it the Fourier-shift estimate is not settling.
pub const ICGN_GUESS_NOT_CONVERGED_STEP_PX: f64 = 0.2;
/// How far the sub-pixel iterations of one ZOI go: at most `max`, and a ZOI whose last
/// correction at that cap is above `not_converged_step_px` is `NotConverged`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SubpixelIterations {
    pub max: u32,
    pub not_converged_step_px: f64,
}

impl SubpixelIterations {
    /// The paper's: `max` iterations and [`NOT_CONVERGED_STEP_PX`].
    pub fn paper(max: u32) -> Self {
        Self {
            max,
            not_converged_step_px: NOT_CONVERGED_STEP_PX,
        }
    }
}

/// The sub-pixel shift may not wander further than this from the integer position (px).
const MAX_SUBPIXEL_DRIFT_PX: f64 = 2.0;

/// The per-node reference data, cached while the reference is fixed.
pub struct ReferenceSpectra<'a> {
    /// Zero-mean, unit-norm, unwindowed ZOI spectrum (integer step).
    pub plain: &'a [Complex32],
    /// Window-weighted zero-mean, windowed, unit-norm ZOI, row-major n x n (sub-pixel step).
    pub windowed: &'a [f32],
}

/// How a ZOI's rigid displacement estimate responds, to first order, to a displacement gradient
/// G within the ZOI: the estimate is u(centre) + K vec(G), vec(G) = (∂u/∂x, ∂u/∂y, ∂v/∂x,
/// ∂v/∂y), `k[p]` the row of K for component p. A rigid ZOI weighs its speckles unevenly, so
/// under strain it reports the motion of a point off its centre; K is that lever, read from
/// the reference ZOI alone (see [`ZoiEngine::prepare_reference`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GradientSensitivity {
    pub k: [[f32; 4]; 2],
}

impl GradientSensitivity {
    /// The bias K vec(G) (px) for the gradient `g` = [[∂u/∂x, ∂u/∂y], [∂v/∂x, ∂v/∂y]].
    pub fn bias_px(&self, g: [[f64; 2]; 2]) -> (f64, f64) {
        let vec_g = [g[0][0], g[0][1], g[1][0], g[1][1]];
        let row = |r: &[f32; 4]| r.iter().zip(vec_g).map(|(&k, g)| k as f64 * g).sum();
        (row(&self.k[0]), row(&self.k[1]))
    }
}

/// Result of one ZOI: displacement of the ZOI centre (px) against its reference position.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ZoiResult {
    pub u_px: f64,
    pub v_px: f64,
    /// Windowed correlation peak, −1..=1 (how well the match was found; see `verify` for the
    /// check of the match itself).
    pub score: f64,
    pub iterations: u32,
    pub status: NodeStatus,
    /// The displacement gradient the deformed ZOI was sampled through (zero: a rigid ZOI cut
    /// from the pixel grid). The rigid-ZOI bias then only concerns the gradient beyond it.
    pub warp_gradient: Mat2,
}

impl ZoiResult {
    /// A ZOI that was not measured, for `status`, after `iterations` sub-pixel iterations.
    fn with_status(status: NodeStatus, iterations: u32) -> ZoiResult {
        ZoiResult {
            status,
            iterations,
            ..ZoiResult::default()
        }
    }
}

/// What one ZOI is correlated from: the reference ZOI's top-left pixel in the image, the
/// displacement guess (px), the gradient to sample the deformed ZOI through, if any, how far
/// the sub-pixel iterations go, and whether the guess is a prediction from the node's own
/// previous frames (expected within a pixel: see [`ZoiEngine::correlate`]).
#[derive(Clone, Copy, Debug)]
pub struct ZoiSearch {
    pub top_left_px: (usize, usize),
    pub guess_px: (f64, f64),
    pub warp: Option<Mat2>,
    pub iterations: SubpixelIterations,
    pub predicted: bool,
}

/// A predicted guess is trusted without the integer FFT search only when the windowed
/// correlation at the prediction is at least this (and is the largest of its 3x3
/// neighbourhood): matched speckle gives 0.9 and more, a ZOI compared with another area of a
/// random speckle a few hundredths to a tenth. Below it the full search runs, as without a
/// prediction.
pub const PREDICTION_MIN_PEAK: f64 = 0.5;

/// Where the integer step cuts the deformed ZOI: its integer move (px, image axes) and where
/// its centre lands relative to the reference centre (px; in the warped ZOI's axes moved by
/// A, rigid: the integer move itself).
struct Placement {
    ix: i64,
    iy: i64,
    origin_px: (f64, f64),
}

/// Where the sub-pixel iterations got to: the best shift (px, the ZOI's axes), its windowed
/// correlation value, the last correction (px), whether they stopped on their own, and how many
/// ran.
struct SubpixelEstimate {
    shift_px: (f64, f64),
    value: f64,
    last_step_px: f64,
    converged: bool,
    iterations: u32,
}

/// Why the sub-pixel iterations stopped without an estimate.
enum SubpixelStop {
    /// The windowed deformed ZOI went flat after `iterations` sub-pixel iterations.
    Flat { iterations: u32 },
    /// Started from a prediction, the first windowed correlation did not confirm it (its
    /// 3x3 maximum off the prediction, or below [`PREDICTION_MIN_PEAK`]).
    Unconfirmed,
}

/// A gradient smaller than this (its largest entry times the ZOI half-size, px) is not worth
/// a warped extraction: the rigid ZOI and the gradient correction handle it.
pub const MIN_WARP_PX: f64 = 0.25;

/// True when a ZOI of side n under gradient g is worth sampling through the gradient.
pub fn warp_worth_it(g: Mat2, n: usize) -> bool {
    let largest = g.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    largest * n as f64 / 2.0 > MIN_WARP_PX
}

/// Accumulated time split of the engine's work (ns), for the benchmark. Counting is off
/// unless `profile` is set, so the hot loop reads no clock by default.
/// `fft_ns`: the integer step's transforms; `window_ns`: windowing and normalisation;
/// `peak_ns`: the 3x3 windowed correlation values (direct sums) and the quadratic fit;
/// `shift_ns`: the Fourier shift (phase ramp and inverse transform); `other_ns`: extraction
/// (and IC-GN's reference subsets, prepared on first need).
/// IC-GN adds `coefficients_ns` (the frame's B-spline prefilter, counted on the calling
/// thread over the whole pool's run), `iterations_ns` (the Gauss-Newton iterations) and
/// `check_ns` (the final ZNCC checks, every method).
#[derive(Clone, Copy, Debug, Default)]
pub struct TimeSplit {
    pub fft_ns: u64,
    pub window_ns: u64,
    pub peak_ns: u64,
    pub shift_ns: u64,
    pub other_ns: u64,
    pub coefficients_ns: u64,
    pub iterations_ns: u64,
    pub check_ns: u64,
}

impl TimeSplit {
    /// Adds another split (engines of several threads) to this one.
    pub fn add(&mut self, other: &TimeSplit) {
        self.fft_ns += other.fft_ns;
        self.window_ns += other.window_ns;
        self.peak_ns += other.peak_ns;
        self.shift_ns += other.shift_ns;
        self.other_ns += other.other_ns;
        self.coefficients_ns += other.coefficients_ns;
        self.iterations_ns += other.iterations_ns;
        self.check_ns += other.check_ns;
    }
}

/// Length of the cached half spectrum of one ZOI of side n.
pub fn spectrum_len(n: usize) -> usize {
    (n / 2 + 1) * n
}

/// Widest shift (px) at which the windowed correlation is evaluated around zero: the 3x3
/// neighbourhood of a maximum found within ±1 px.
const PAD: usize = 2;

/// Three 4-lane dot products sharing one operand: a_j += Σ_c g_j[c] · f[c] (lane-wise).
struct Mac3 {
    lanes: [F32x4; 3],
}

impl Mac3 {
    fn new() -> Self {
        Mac3 {
            lanes: [F32x4::zero(); 3],
        }
    }

    #[inline]
    fn add_row(&mut self, f: &[[f32; 4]], g: [&[[f32; 4]]; 3]) {
        assert!(g.iter().all(|gj| gj.len() == f.len()));
        let [mut a0, mut a1, mut a2] = self.lanes;
        for (((fc, c0), c1), c2) in f.iter().zip(g[0]).zip(g[1]).zip(g[2]) {
            let fv = F32x4::load(fc);
            a0 = a0.mul_add(F32x4::load(c0), fv);
            a1 = a1.mul_add(F32x4::load(c1), fv);
            a2 = a2.mul_add(F32x4::load(c2), fv);
        }
        self.lanes = [a0, a1, a2];
    }

    fn sums(&self) -> [f32; 3] {
        self.lanes.map(F32x4::sum)
    }
}

pub struct ZoiEngine {
    n: usize,
    fft: RealFft2d,
    window: Vec<f32>,
    /// Row scratch of [`Self::gradient_sensitivity`]: ∂f/∂x, ∂f/∂y, w ∂f_w/∂x, w ∂f_w/∂y
    /// (first and last entries stay 0).
    gradient_rows: [Vec<f32>; 4],
    /// x − centre of each column (px).
    column_offsets: Vec<f32>,
    window_sum: f32,
    /// Zero-mean deformed ZOI (spatial, real).
    g_spatial: Vec<f32>,
    /// Spectrum of `g_spatial` at the integer position.
    g_spectrum: Vec<Complex32>,
    /// Half-spectrum work buffer.
    work: Vec<Complex32>,
    /// Windowed (or normalised) ZOI, real.
    windowed: Vec<f32>,
    /// The windowed ZOI with each row extended by PAD wrapped values on both sides, row
    /// stride n + 2 PAD: a circular shift by |dx| <= PAD is then a contiguous slice.
    extended: Vec<f32>,
    /// Correlation map, real, row-major, unnormalised (times n²).
    corr: Vec<f32>,
    phase_x: Vec<Complex32>,
    phase_y: Vec<Complex32>,
    /// Spectra of a ZOI that is not in the reference cache ([`Self::correlate_uncached`]).
    uncached_plain: Vec<Complex32>,
    uncached_windowed: Vec<f32>,
    /// The sub-pixel sums run on AVX2 + FMA ([`sums_avx2`]): the CPU has them and n is a
    /// multiple of 8.
    avx2: bool,
    pub profile: bool,
    pub split: TimeSplit,
    /// Integer FFT searches this engine ran (a confirmed prediction runs none): a count, not
    /// a time, so tests can tell a shortcut taken from one missed.
    pub searches: u64,
    /// IC-GN: room for one reference subset prepared on the fly (a node's subset in the
    /// origin frame), empty for CORRELI-GD.
    pub subset_scratch: Vec<f32>,
}

/// Laps of the time split: reads the clock only when profiling is on.
pub(crate) struct Timer(Option<std::time::Instant>);

impl Timer {
    #[inline]
    pub(crate) fn start(on: bool) -> Self {
        Timer(on.then(std::time::Instant::now))
    }
    #[inline]
    pub(crate) fn lap(&mut self, into: &mut u64) {
        if let Some(t) = self.0.as_mut() {
            let now = std::time::Instant::now();
            *into += (now - *t).as_nanos() as u64;
            *t = now;
        }
    }
}

impl ZoiEngine {
    pub fn new(n: usize) -> Self {
        let zero = Complex32::new(0.0, 0.0);
        let window = modified_hanning_2d(n);
        let window_sum = window.iter().sum();
        Self {
            n,
            fft: RealFft2d::new(n),
            window,
            gradient_rows: std::array::from_fn(|_| vec![0.0; n]),
            column_offsets: (0..n).map(|x| x as f32 - (n as f32 - 1.0) / 2.0).collect(),
            window_sum,
            g_spatial: vec![0.0; n * n],
            g_spectrum: vec![zero; spectrum_len(n)],
            work: vec![zero; spectrum_len(n)],
            windowed: vec![0.0; n * n],
            extended: vec![0.0; n * (n + 2 * PAD)],
            corr: vec![0.0; n * n],
            phase_x: vec![zero; n],
            phase_y: vec![zero; n],
            uncached_plain: vec![zero; spectrum_len(n)],
            uncached_windowed: vec![0.0; n * n],
            avx2: sums_avx2_available(n),
            profile: false,
            split: TimeSplit::default(),
            searches: 0,
            subset_scratch: Vec::new(),
        }
    }

    /// Fills the two reference spectra of the ZOI with top-left (x0, y0) (inside the image)
    /// and its gradient sensitivity. Returns false when the ZOI has too little contrast to be
    /// correlated.
    pub fn prepare_reference(
        &mut self,
        image: Image,
        x0: usize,
        y0: usize,
        plain: &mut [Complex32],
        windowed: &mut [f32],
        sensitivity: &mut GradientSensitivity,
    ) -> bool {
        let n = self.n;
        assert!(image.contains_block(x0 as i64, y0 as i64, n));
        assert_eq!(plain.len(), spectrum_len(n));
        assert_eq!(windowed.len(), n * n);
        *sensitivity = GradientSensitivity::default();
        let contrast_ok = self.extract_zero_mean(image, x0, y0).is_some();
        if !contrast_ok {
            plain.fill(Complex32::new(0.0, 0.0));
            windowed.fill(0.0);
            return false;
        }
        let norm = self.g_spatial.iter().map(|&g| g * g).sum::<f32>().sqrt();
        for (p, &g) in self.windowed.iter_mut().zip(&self.g_spatial) {
            *p = g / norm;
        }
        self.fft.forward(&self.windowed, plain);
        let ok = self.window_into(windowed).is_some();
        if ok {
            *sensitivity = self.gradient_sensitivity(windowed).unwrap_or_default();
        } else {
            windowed.fill(0.0);
        }
        ok
    }

    /// The windowed ZOI of [`Self::prepare_reference`] alone, into `windowed`; false when the
    /// ZOI has too little contrast (`windowed` then holds nothing of use).
    fn prepare_windowed(
        &mut self,
        image: Image,
        x0: usize,
        y0: usize,
        windowed: &mut [f32],
    ) -> bool {
        assert!(image.contains_block(x0 as i64, y0 as i64, self.n));
        self.extract_zero_mean(image, x0, y0).is_some() && self.window_into(windowed).is_some()
    }

    /// The first-order response of the windowed correlation peak to a displacement gradient,
    /// for the reference ZOI: `g_spatial` holds it zero-mean, `f_w` windowed (w (f − mean_w),
    /// any scale). At the peak, Σ f_w ∇(w g_d) = 0, g_d the deformed ZOI moved back by the
    /// estimate d. For g_d(x) = f(x + δ(x)), δ = e − G r (e = d − u(centre), r = x − centre),
    /// linearising and integrating by parts gives Σ a (∇f · δ) = 0 with
    /// a = w² ∇f + f w ∇w = w ∇f_w, hence A e = B vec(G) with A = Σ a ∇fᵀ and
    /// B[p][2q + s] = Σ a_p ∂_q f r_s: K = A⁻¹ B. Central differences on the interior pixels
    /// (w is 0 on the first row and column and below 1e-6 on the last). None when A is
    /// singular (no texture).
    fn gradient_sensitivity(&mut self, f_w: &[f32]) -> Option<GradientSensitivity> {
        let n = self.n;
        let f = &self.g_spatial;
        let centre = (n as f64 - 1.0) / 2.0;
        let [gx, gy, ax, ay] = &mut self.gradient_rows;
        // Sums of a_p ∂_q f, index 2p + q: over all pixels (A), times r_x, times r_y.
        let mut a_sums = [0.0f64; 4];
        let mut ry_sums = [0.0f64; 4];
        let mut rx_lanes = [F32x4::zero(); 4];
        for y in 1..n - 1 {
            let (row, up, down) = (y * n, (y - 1) * n, (y + 1) * n);
            for x in 1..n - 1 {
                let w = self.window[row + x];
                gx[x] = 0.5 * (f[row + x + 1] - f[row + x - 1]);
                gy[x] = 0.5 * (f[down + x] - f[up + x]);
                ax[x] = 0.5 * w * (f_w[row + x + 1] - f_w[row + x - 1]);
                ay[x] = 0.5 * w * (f_w[down + x] - f_w[up + x]);
            }
            let mut row_lanes = [F32x4::zero(); 4];
            let chunks = ax
                .as_chunks::<4>()
                .0
                .iter()
                .zip(ay.as_chunks::<4>().0)
                .zip(gx.as_chunks::<4>().0)
                .zip(gy.as_chunks::<4>().0)
                .zip(self.column_offsets.as_chunks::<4>().0);
            for ((((ax, ay), gx), gy), rx) in chunks {
                let (ax, ay, gx, gy) = (
                    F32x4::load(ax),
                    F32x4::load(ay),
                    F32x4::load(gx),
                    F32x4::load(gy),
                );
                let rx = F32x4::load(rx);
                let products = [ax.mul(gx), ax.mul(gy), ay.mul(gx), ay.mul(gy)];
                for ((row_lane, rx_lane), product) in
                    row_lanes.iter_mut().zip(&mut rx_lanes).zip(products)
                {
                    *row_lane = row_lane.add(product);
                    *rx_lane = rx_lane.mul_add(product, rx);
                }
            }
            let ry = y as f64 - centre;
            for ((a, b), lane) in a_sums.iter_mut().zip(&mut ry_sums).zip(row_lanes) {
                let row_sum = lane.sum() as f64;
                *a += row_sum;
                *b += ry * row_sum;
            }
        }
        let a = [[a_sums[0], a_sums[1]], [a_sums[2], a_sums[3]]];
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        let scale = a[0][0].abs() + a[1][1].abs();
        if !(det.is_finite() && det.abs() > 1e-9 * scale * scale) {
            return None;
        }
        let inverse = [
            [a[1][1] / det, -a[0][1] / det],
            [-a[1][0] / det, a[0][0] / det],
        ];
        // B[p][2q + s]: s = 0 weighs by r_x, s = 1 by r_y.
        let b = |p: usize, column: usize| {
            let (q, s) = (column / 2, column % 2);
            if s == 0 {
                rx_lanes[2 * p + q].sum() as f64
            } else {
                ry_sums[2 * p + q]
            }
        };
        let mut k = [[0.0f32; 4]; 2];
        for (p, row) in k.iter_mut().enumerate() {
            for (column, value) in row.iter_mut().enumerate() {
                *value = (inverse[p][0] * b(0, column) + inverse[p][1] * b(1, column)) as f32;
            }
        }
        Some(GradientSensitivity { k })
    }

    /// Samples (bicubic) the deformed image through x → x + shift + (a − I)(x − centre) over
    /// the n x n `block` centred on `centre` into `g_spatial`, minus its mean. None when a
    /// sample is more than a pixel past the border (as the rigid ZOI, which is pulled back
    /// inside from there), Some(false) when the samples are flat. Near and past the border the
    /// interpolation repeats the border pixels.
    fn extract_warped(&mut self, image: Image, block: WarpedBlock) -> Option<bool> {
        let n = self.n;
        let WarpedBlock {
            centre_px: centre,
            shift_px: shift,
            a,
            ..
        } = block;
        let sample = if block.inside(image, 1.0, 2.0) {
            bicubic
        } else if block.inside(image, -1.0, -1.0) {
            bicubic_clamped
        } else {
            return None;
        };
        let half = (n as f64 - 1.0) / 2.0;
        let mut sum = 0.0f64;
        for (y, row) in self.g_spatial.chunks_exact_mut(n).enumerate() {
            let start = apply(a, (-half, y as f64 - half));
            let (mut px, mut py) = (centre.0 + shift.0 + start.0, centre.1 + shift.1 + start.1);
            let mut row_sum = 0.0f32;
            for value in row.iter_mut() {
                *value = sample(image, px, py);
                row_sum += *value;
                px += a[0][0];
                py += a[1][0];
            }
            sum += row_sum as f64;
        }
        let mean = F32x4::splat((sum / (n * n) as f64) as f32);
        let mut sum_sq = F32x4::zero();
        for chunk in self.g_spatial.as_chunks_mut::<4>().0 {
            let g = F32x4::load(chunk).sub(mean);
            g.store(chunk);
            sum_sq = sum_sq.mul_add(g, g);
        }
        Some((sum_sq.sum() / (n * n) as f32).sqrt() >= MIN_STD_COUNTS)
    }

    /// Whether the ZOI [`ZoiEngine::prepare_reference`] last read runs off the specimen onto a
    /// flat backdrop along one of its sides (`flat_side`): a reference ZOI must be textured
    /// throughout.
    pub fn reference_has_flat_side(&self) -> bool {
        let n = self.n;
        let std = (self.g_spatial.iter().map(|g| g * g).sum::<f32>() / (n * n) as f32).sqrt();
        flat_side::has_flat_side(&self.g_spatial, n, std)
    }

    /// Copies the n x n block at (x0, y0) into `g_spatial` minus its mean; its standard
    /// deviation, None if flat.
    fn extract_zero_mean(&mut self, image: Image, x0: usize, y0: usize) -> Option<f32> {
        let n = self.n;
        // Exact integer sum of the u16 pixels (n² <= 65536 values: fits in u64 with room).
        let mut sum = 0u64;
        for row in 0..n {
            let start = (y0 + row) * image.width_px + x0;
            let src = &image.pixels[start..start + n];
            let dst = &mut self.g_spatial[row * n..(row + 1) * n];
            let mut row_sum = 0u32;
            for (d, &s) in dst.iter_mut().zip(src) {
                *d = s as f32;
                row_sum += s as u32;
            }
            sum += row_sum as u64;
        }
        let mean = F32x4::splat((sum as f64 / (n * n) as f64) as f32);
        let mut sum_sq = F32x4::zero();
        for chunk in self.g_spatial.as_chunks_mut::<4>().0 {
            let g = F32x4::load(chunk).sub(mean);
            g.store(chunk);
            sum_sq = sum_sq.mul_add(g, g);
        }
        let std = (sum_sq.sum() / (n * n) as f32).sqrt();
        (std >= MIN_STD_COUNTS).then_some(std)
    }

    /// Writes w (g - weighted mean) into `out`, row y at `out[offset + y * stride..][..n]`;
    /// returns the norm of what it wrote, or None when the windowed ZOI is flat.
    fn window_rows(&self, out: &mut [f32], stride: usize, offset: usize) -> Option<f32> {
        let n = self.n;
        assert!(stride >= n && out.len() >= offset + (n - 1) * stride + n);
        let floor = MIN_STD_COUNTS * self.window_sum.sqrt();
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only where sums_avx2::available() returned true.
            let sum_sq = unsafe {
                sums_avx2::window_rows(
                    &self.window,
                    &self.g_spatial,
                    self.window_sum,
                    n,
                    out,
                    stride,
                    offset,
                )
            };
            let norm = sum_sq.sqrt();
            return (norm.is_finite() && norm >= floor).then_some(norm);
        }
        let mean = F32x4::splat(dot(&self.window, &self.g_spatial) / self.window_sum);
        let mut sum_sq = F32x4::zero();
        for (y, (w_row, g_row)) in self
            .window
            .chunks_exact(n)
            .zip(self.g_spatial.chunks_exact(n))
            .enumerate()
        {
            let start = offset + y * stride;
            let o_row = out[start..start + n].as_chunks_mut::<4>().0;
            let (w_row, g_row) = (w_row.as_chunks::<4>().0, g_row.as_chunks::<4>().0);
            for ((o, w), g) in o_row.iter_mut().zip(w_row).zip(g_row) {
                let v = F32x4::load(w).mul(F32x4::load(g).sub(mean));
                sum_sq = sum_sq.mul_add(v, v);
                v.store(o);
            }
        }
        let norm = sum_sq.sum().sqrt();
        (norm.is_finite() && norm >= floor).then_some(norm)
    }

    /// Writes w (g - weighted mean) / norm into `out` (n x n); returns the norm before
    /// normalisation, or None when the windowed ZOI is flat.
    fn window_into(&self, out: &mut [f32]) -> Option<f32> {
        let norm = self.window_rows(out, self.n, 0)?;
        let inv = 1.0 / norm;
        for o in out.iter_mut() {
            *o *= inv;
        }
        Some(norm)
    }

    /// Correlates the deformed image around the reference ZOI at `search.top_left_px`,
    /// starting from the guess. The returned displacement is total (guess included). With a
    /// `warp` gradient G worth it ([`warp_worth_it`]), the deformed ZOI is sampled (bicubic)
    /// through x → x + guess + G (x − c) instead of cut from the pixel grid, so that only the
    /// residual is measured: a ZOI rotated by 170° or stretched by 50 % is correlated against a
    /// deformed ZOI that looks like it.
    ///
    /// A `predicted` guess skips the integer FFT search (paper, section 3.b), whose only task
    /// is to bring the peak within a pixel: the deformed ZOI is cut at the rounded prediction
    /// (sampled at the prediction itself when warped) and the sub-pixel iterations start from
    /// the prediction's fraction (one Fourier shift, which the search's own iterations would
    /// also have made). The first windowed correlation must then confirm the prediction: its
    /// 3x3 maximum at the prediction and at least [`PREDICTION_MIN_PEAK`]. When it does not
    /// (a prediction off by a pixel or more, a decorrelated ZOI), or when the ZOI cannot be cut
    /// there, the full search runs from the same guess, as without a prediction.
    pub fn correlate(
        &mut self,
        reference: &ReferenceSpectra,
        deformed: Image,
        search: ZoiSearch,
    ) -> ZoiResult {
        let mut timer = Timer::start(self.profile);
        let guess_px = search.guess_px;
        if !(guess_px.0.is_finite() && guess_px.1.is_finite()) {
            return ZoiResult::with_status(NodeStatus::NoGuess, 0);
        }
        let warp = self.usable_warp(search.warp);
        let a = warp.map(identity_plus);
        if search.predicted {
            if let Some(result) =
                self.correlate_predicted(reference.windowed, deformed, &search, warp, &mut timer)
            {
                return result;
            }
        }
        self.searches += 1;
        let origin = match self.integer_step(reference.plain, deformed, &search, a, &mut timer) {
            Ok(origin) => origin,
            Err(status) => return ZoiResult::with_status(status, 0),
        };
        let start = (0.0, 0.0);
        let max = search.iterations.max;
        let estimate = match self.subpixel(reference.windowed, start, max, false, &mut timer) {
            Ok(estimate) => estimate,
            Err(SubpixelStop::Flat { iterations }) => {
                return ZoiResult::with_status(NodeStatus::LowContrast, iterations)
            }
            Err(SubpixelStop::Unconfirmed) => unreachable!("only a prediction is confirmed"),
        };
        Self::result(origin, estimate, warp, &search)
    }

    /// The gradient a ZOI is sampled through: `warp` when finite and worth it.
    fn usable_warp(&self, warp: Option<Mat2>) -> Option<Mat2> {
        warp.filter(|&g| g.iter().flatten().all(|v| v.is_finite()) && warp_worth_it(g, self.n))
    }

    /// [`Self::correlate`] from a prediction without the integer search; None when the
    /// prediction is not confirmed or the ZOI cannot be cut there (the full search decides).
    /// It needs the reference's windowed ZOI only (`windowed`).
    fn correlate_predicted(
        &mut self,
        windowed: &[f32],
        deformed: Image,
        search: &ZoiSearch,
        warp: Option<Mat2>,
        timer: &mut Timer,
    ) -> Option<ZoiResult> {
        let guess = search.guess_px;
        let (ix, iy) = (guess.0.round() as i64, guess.1.round() as i64);
        // Warped, the ZOI is sampled at the prediction itself; rigid, cut at its rounding.
        let mut place = Placement {
            ix,
            iy,
            origin_px: if warp.is_some() {
                guess
            } else {
                (ix as f64, iy as f64)
            },
        };
        let a = warp.map(identity_plus);
        self.extract_placed(deformed, search.top_left_px, a, &mut place)
            .ok()?;
        timer.lap(&mut self.split.other_ns);
        // Rigid: the fraction left to the Fourier shift (more than half a pixel when the ZOI
        // was pulled back inside at a border: the full search handles those).
        let start = match a {
            Some(_) => (0.0, 0.0),
            None => (guess.0 - place.origin_px.0, guess.1 - place.origin_px.1),
        };
        if start.0.abs() > 0.5 || start.1.abs() > 0.5 {
            return None;
        }
        self.fft.forward(&self.g_spatial, &mut self.g_spectrum);
        timer.lap(&mut self.split.fft_ns);
        let max = search.iterations.max;
        let estimate = self.subpixel(windowed, start, max, true, timer).ok()?;
        Some(Self::result(place.origin_px, estimate, warp, search))
    }

    /// The node's result from where the deformed ZOI's centre landed (`origin`, px) and the
    /// sub-pixel estimate (the ZOI's axes, warped by `warp`).
    fn result(
        origin: (f64, f64),
        estimate: SubpixelEstimate,
        warp: Option<Mat2>,
        search: &ZoiSearch,
    ) -> ZoiResult {
        let a = warp.map(identity_plus);
        // The sub-pixel estimate is in the ZOI's axes: a step s there is A s in the image.
        let best = estimate.shift_px;
        let step = a.map_or(best, |a| apply(a, best));
        let drifted = best.0.abs() > MAX_SUBPIXEL_DRIFT_PX || best.1.abs() > MAX_SUBPIXEL_DRIFT_PX;
        let settled =
            estimate.converged || estimate.last_step_px < search.iterations.not_converged_step_px;
        ZoiResult {
            u_px: origin.0 + step.0,
            v_px: origin.1 + step.1,
            score: estimate.value.clamp(-1.0, 1.0),
            iterations: estimate.iterations,
            status: if !drifted && settled {
                NodeStatus::Ok
            } else {
                NodeStatus::NotConverged
            },
            warp_gradient: warp.unwrap_or_default(),
        }
    }

    /// The integer step (paper): one unwindowed FFT correlation against the reference
    /// spectrum `plain`, then the deformed ZOI moved by the peak and cut again, its spectrum
    /// left in `g_spectrum`. Warped (`a` = I + G), the move is in the ZOI's own (warped) axes.
    /// Returns where the deformed ZOI's centre lands, relative to the reference centre (px).
    fn integer_step(
        &mut self,
        plain: &[Complex32],
        deformed: Image,
        search: &ZoiSearch,
        a: Option<Mat2>,
        timer: &mut Timer,
    ) -> Result<(f64, f64), NodeStatus> {
        let (ix, iy) = (
            search.guess_px.0.round() as i64,
            search.guess_px.1.round() as i64,
        );
        let mut place = Placement {
            ix,
            iy,
            origin_px: (ix as f64, iy as f64),
        };
        let mut spectrum_valid = false;
        for pass in 0..2 {
            self.extract_placed(deformed, search.top_left_px, a, &mut place)?;
            timer.lap(&mut self.split.other_ns);
            if pass == 1 {
                break;
            }
            self.fft.forward(&self.g_spatial, &mut self.g_spectrum);
            for ((w, &g), &f) in self.work.iter_mut().zip(&self.g_spectrum).zip(plain) {
                *w = g * f.conj();
            }
            self.fft.inverse(&mut self.work, &mut self.corr);
            timer.lap(&mut self.split.fft_ns);
            let (dx, dy) = self.argmax_wrapped();
            timer.lap(&mut self.split.peak_ns);
            if dx == 0 && dy == 0 {
                spectrum_valid = true;
                break;
            }
            place.ix += dx;
            place.iy += dy;
            if let Some(a) = a {
                let step = apply(a, (dx as f64, dy as f64));
                place.origin_px = (place.origin_px.0 + step.0, place.origin_px.1 + step.1);
            }
        }
        if !spectrum_valid {
            self.fft.forward(&self.g_spatial, &mut self.g_spectrum);
            timer.lap(&mut self.split.fft_ns);
        }
        Ok(place.origin_px)
    }

    /// Cuts (rigid) or samples (warped, `a` = I + G) the deformed ZOI at `place` into
    /// `g_spatial`, zero-mean, for the reference ZOI at `top_left`. A rigid ZOI at most one
    /// pixel past the border is pulled back inside (`place` moves with it): the sub-pixel stage
    /// accepts a residual of up to one pixel.
    fn extract_placed(
        &mut self,
        deformed: Image,
        top_left: (usize, usize),
        a: Option<Mat2>,
        place: &mut Placement,
    ) -> Result<(), NodeStatus> {
        let n = self.n;
        if let Some(a) = a {
            let half = (n as f64 - 1.0) / 2.0;
            let block = WarpedBlock {
                centre_px: (top_left.0 as f64 + half, top_left.1 as f64 + half),
                shift_px: place.origin_px,
                a,
                n,
            };
            return match self.extract_warped(deformed, block) {
                None => Err(NodeStatus::OutsideImage),
                Some(false) => Err(NodeStatus::LowContrast),
                Some(true) => Ok(()),
            };
        }
        let (x0, y0) = (top_left.0 as i64, top_left.1 as i64);
        let max_x = deformed.width_px as i64 - n as i64;
        let max_y = deformed.height_px as i64 - n as i64;
        let (gx, gy) = (x0 + place.ix, y0 + place.iy);
        let (cx, cy) = (gx.clamp(0, max_x), gy.clamp(0, max_y));
        if (cx - gx).abs() <= 1 && (cy - gy).abs() <= 1 {
            place.ix += cx - gx;
            place.iy += cy - gy;
        }
        let (gx, gy) = (x0 + place.ix, y0 + place.iy);
        if !deformed.contains_block(gx, gy, n) {
            return Err(NodeStatus::OutsideImage);
        }
        if self
            .extract_zero_mean(deformed, gx as usize, gy as usize)
            .is_none()
        {
            return Err(NodeStatus::LowContrast);
        }
        place.origin_px = (place.ix as f64, place.iy as f64);
        Ok(())
    }

    /// The sub-pixel iterations (at most `max_iterations`) against the reference's windowed
    /// ZOI `windowed`, from the shift `start_px` (the ZOI's axes; the first iteration shifts
    /// there unless it is zero): window, correlate, quadratic peak, Fourier shift, while the
    /// interpolated maximum increases, until a correction below [`CONVERGED_STEP_PX`] or the
    /// next one predicted below [`PREDICTED_STEP_PX`]. `confirm`: the start is a prediction, and the first
    /// windowed correlation must confirm it ([`SubpixelStop::Unconfirmed`] otherwise).
    fn subpixel(
        &mut self,
        windowed: &[f32],
        start_px: (f64, f64),
        max_iterations: u32,
        confirm: bool,
        timer: &mut Timer,
    ) -> Result<SubpixelEstimate, SubpixelStop> {
        let n = self.n;
        let mut estimate = SubpixelEstimate {
            shift_px: start_px,
            value: f64::NEG_INFINITY,
            last_step_px: f64::INFINITY,
            converged: false,
            iterations: 0,
        };
        let mut shift = start_px;
        let mut previous_step_px = f64::INFINITY;
        for iteration in 0..max_iterations {
            if iteration > 0 || shift != (0.0, 0.0) {
                self.shift_into_spatial(shift);
                timer.lap(&mut self.split.shift_ns);
            }
            // Windowed straight into the row-extended layout; the 1/norm goes to the values.
            let mut extended = std::mem::take(&mut self.extended);
            let norm = self.window_rows(&mut extended, n + 2 * PAD, PAD);
            self.extended = extended;
            timer.lap(&mut self.split.window_ns);
            let Some(norm) = norm else {
                return Err(SubpixelStop::Flat {
                    iterations: estimate.iterations,
                });
            };
            self.wrap_rows();
            let (px, py, neighbourhood) = self.peak_neighbourhood(windowed, 1.0 / norm);
            let (fx, fy, value) = quadratic_peak_3x3(&neighbourhood);
            timer.lap(&mut self.split.peak_ns);
            if confirm
                && iteration == 0
                && !((px, py) == (0, 0) && neighbourhood[1][1] as f64 >= PREDICTION_MIN_PEAK)
            {
                return Err(SubpixelStop::Unconfirmed);
            }
            estimate.iterations = iteration + 1;
            if value <= estimate.value {
                estimate.converged = true;
                break;
            }
            estimate.value = value;
            let step = (px as f64 + fx, py as f64 + fy);
            estimate.shift_px = (shift.0 + step.0, shift.1 + step.1);
            let step_px = step.0.abs().max(step.1.abs());
            estimate.last_step_px = step_px;
            shift = estimate.shift_px;
            // No ratio before the second correction (the first one's predecessor is infinite).
            let ratio = step_px / previous_step_px;
            let predicted_small = previous_step_px.is_finite()
                && ratio < MAX_CONTRACTION
                && ratio * step_px < PREDICTED_STEP_PX;
            if step_px < CONVERGED_STEP_PX || predicted_small {
                estimate.converged = true;
                break;
            }
            previous_step_px = step_px;
            if shift.0.abs() > MAX_SUBPIXEL_DRIFT_PX || shift.1.abs() > MAX_SUBPIXEL_DRIFT_PX {
                break;
            }
        }
        Ok(estimate)
    }

    /// [`Self::correlate`] for a ZOI of another image than the cached references (a node's
    /// ZOI in the frame its mesh was defined in): its data are prepared in the engine's own
    /// buffers first, and only those the correlation uses: a prediction the windowed
    /// correlation confirms needs the windowed ZOI alone, not its spectrum nor its gradient
    /// sensitivity. The same result as [`Self::correlate`] with [`Self::prepare_reference`]'s
    /// spectra. `LowContrast` when that ZOI is flat.
    pub fn correlate_uncached(
        &mut self,
        reference: Image,
        deformed: Image,
        mut search: ZoiSearch,
    ) -> ZoiResult {
        let mut plain = std::mem::take(&mut self.uncached_plain);
        let mut windowed = std::mem::take(&mut self.uncached_windowed);
        let (x0, y0) = search.top_left_px;
        let finite = search.guess_px.0.is_finite() && search.guess_px.1.is_finite();
        if search.predicted && finite {
            let mut timer = Timer::start(self.profile);
            let shortcut = if self.prepare_windowed(reference, x0, y0, &mut windowed) {
                timer.lap(&mut self.split.window_ns);
                let warp = self.usable_warp(search.warp);
                self.correlate_predicted(&windowed, deformed, &search, warp, &mut timer)
            } else {
                Some(ZoiResult::with_status(NodeStatus::LowContrast, 0))
            };
            if let Some(result) = shortcut {
                self.uncached_plain = plain;
                self.uncached_windowed = windowed;
                return result;
            }
            // Not confirmed: the full search, as `correlate` runs it after the same attempt.
            search.predicted = false;
        }
        let mut sensitivity = GradientSensitivity::default();
        let result = if self.prepare_reference(
            reference,
            x0,
            y0,
            &mut plain,
            &mut windowed,
            &mut sensitivity,
        ) {
            let spectra = ReferenceSpectra {
                plain: &plain,
                windowed: &windowed,
            };
            self.correlate(&spectra, deformed, search)
        } else {
            ZoiResult::with_status(NodeStatus::LowContrast, 0)
        };
        self.uncached_plain = plain;
        self.uncached_windowed = windowed;
        result
    }

    /// g_spatial = real(IFFT(G · exp(+2πj k·d / n))): the deformed ZOI moved back by d.
    fn shift_into_spatial(&mut self, d: (f64, f64)) {
        let n = self.n;
        // exp(2πj f d / n) for the signed frequencies f: powers of one root computed in f64
        // (error ~1e-16 per step), negative frequencies as conjugates. The 1/n² of the inverse
        // transform is folded into the x factors.
        let scale = 1.0 / (n * n) as f64;
        let fill = |phase: &mut [Complex32], d: f64, scale: f64| {
            let (s, c) = (2.0 * std::f64::consts::PI * d / n as f64).sin_cos();
            let (mut re, mut im) = (scale, 0.0f64);
            for k in 0..n / 2 {
                phase[k] = Complex32::new(re as f32, im as f32);
                if k > 0 {
                    phase[n - k] = Complex32::new(re as f32, -im as f32);
                }
                (re, im) = (re * c - im * s, re * s + im * c);
            }
            // Nyquist bin: +n/2 and -n/2 are the same bin; the symmetric shift factor is their
            // mean, cos(π d), which keeps the shifted ZOI real without favouring a direction.
            phase[n / 2] = Complex32::new((scale * (std::f64::consts::PI * d).cos()) as f32, 0.0);
        };
        fill(&mut self.phase_x, d.0, scale);
        fill(&mut self.phase_y, d.1, 1.0);
        // Half-spectrum layout: index kx * n + ky, kx in 0..=n/2.
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only where sums_avx2::available() returned true.
            unsafe {
                sums_avx2::phase_ramp(
                    &self.g_spectrum,
                    &self.phase_x[..=n / 2],
                    &self.phase_y,
                    &mut self.work,
                )
            };
            self.fft.inverse(&mut self.work, &mut self.g_spatial);
            return;
        }
        for kx in 0..=n / 2 {
            let px = self.phase_x[kx];
            let row = &mut self.work[kx * n..(kx + 1) * n];
            let src = &self.g_spectrum[kx * n..(kx + 1) * n];
            for ((w, &g), &py) in row.iter_mut().zip(src).zip(&self.phase_y) {
                *w = g * (px * py);
            }
        }
        self.fft.inverse(&mut self.work, &mut self.g_spatial);
    }

    /// Integer location of the maximum of the real correlation map, wrapped to [-n/2, n/2).
    fn argmax_wrapped(&self) -> (i64, i64) {
        let n = self.n;
        let mut best = f32::NEG_INFINITY;
        let mut best_index = 0;
        for (i, &c) in self.corr.iter().enumerate() {
            if c > best {
                best = c;
                best_index = i;
            }
        }
        let wrap = |k: usize| {
            if k >= n / 2 {
                k as i64 - n as i64
            } else {
                k as i64
            }
        };
        (wrap(best_index % n), wrap(best_index / n))
    }

    /// Fills the PAD wrapped values on both sides of every row of `extended`.
    fn wrap_rows(&mut self) {
        let n = self.n;
        for row in self.extended.chunks_exact_mut(n + 2 * PAD) {
            row.copy_within(n..n + PAD, 0);
            row.copy_within(PAD..2 * PAD, PAD + n);
        }
    }

    /// The windowed correlation c(dx, dy) = Σ g_w(x + dx, y + dy) f_w(x, y) (circular) at the
    /// 3x3 shifts around `centre` (|centre| < PAD per axis), `[row = dy][col = dx]`, times
    /// `scale`. Per dy, one pass over the rows: each 4-value chunk of the reference row meets
    /// the three shifted chunks of the deformed row.
    fn correlation_3x3(&self, reference: &[f32], centre: (i64, i64), scale: f32) -> [[f32; 3]; 3] {
        let n = self.n;
        let stride = n + 2 * PAD;
        assert!(centre.0.unsigned_abs() < PAD as u64 && centre.1.unsigned_abs() < PAD as u64);
        assert!(n.is_multiple_of(4) && reference.len() == n * n);
        let x0 = (PAD as i64 + centre.0 - 1) as usize;
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            let dy = [centre.1 - 1, centre.1, centre.1 + 1];
            // SAFETY: `avx2` is set only where sums_avx2::available() returned true.
            let sums =
                unsafe { sums_avx2::correlation_3x3(reference, &self.extended, n, stride, x0, dy) };
            return sums.map(|row| row.map(|v| v * scale));
        }
        let mut out = [[0.0f32; 3]; 3];
        for (r, out_row) in out.iter_mut().enumerate() {
            let dy = centre.1 + r as i64 - 1;
            let mut acc = Mac3::new();
            for (y, f_row) in reference.chunks_exact(n).enumerate() {
                let yy = (y as i64 + dy).rem_euclid(n as i64) as usize;
                let row = &self.extended[yy * stride..(yy + 1) * stride];
                acc.add_row(
                    f_row.as_chunks::<4>().0,
                    [
                        row[x0..x0 + n].as_chunks::<4>().0,
                        row[x0 + 1..x0 + 1 + n].as_chunks::<4>().0,
                        row[x0 + 2..x0 + 2 + n].as_chunks::<4>().0,
                    ],
                );
            }
            *out_row = acc.sums().map(|v| v * scale);
        }
        out
    }

    /// The integer maximum of the windowed correlation within ±1 px of zero shift (the integer
    /// step put the peak there) and the 3x3 values around it, `[row = dy][col = dx]`.
    fn peak_neighbourhood(&self, reference: &[f32], scale: f32) -> (i64, i64, [[f32; 3]; 3]) {
        let around_zero = self.correlation_3x3(reference, (0, 0), scale);
        let (mut best, mut at) = (f32::NEG_INFINITY, (0i64, 0i64));
        for (row, values) in around_zero.iter().enumerate() {
            for (col, &v) in values.iter().enumerate() {
                if v > best {
                    best = v;
                    at = (col as i64 - 1, row as i64 - 1);
                }
            }
        }
        if at == (0, 0) {
            (0, 0, around_zero)
        } else {
            (at.0, at.1, self.correlation_3x3(reference, at, scale))
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod sums_avx2;

/// Whether a ZOI of side n runs its sub-pixel sums on AVX2 + FMA.
fn sums_avx2_available(n: usize) -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        n.is_multiple_of(8) && sums_avx2::available()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = n;
        false
    }
}

#[cfg(test)]
mod prediction_tests;

#[cfg(test)]
mod tests {
    use super::*;

    /// A ZOI holding one speckle at r0 from its centre follows that speckle: under a gradient G
    /// it reports u(centre) + G r0, so K = [[r0x, r0y, 0, 0], [0, 0, r0x, r0y]].
    #[test]
    fn a_single_speckle_is_the_lever_of_its_zoi() {
        let n = 32;
        let (width, r0) = (48usize, (5.0f64, -3.0f64));
        let centre = 8.0 + (n as f64 - 1.0) / 2.0;
        let pixels: Vec<u16> = (0..width * width)
            .map(|i| {
                let (x, y) = ((i % width) as f64 - centre, (i / width) as f64 - centre);
                let d2 = (x - r0.0).powi(2) + (y - r0.1).powi(2);
                (1000.0 + 30000.0 * (-d2 / (2.0 * 2.0 * 2.0)).exp()) as u16
            })
            .collect();
        let image = Image {
            pixels: &pixels,
            width_px: width,
            height_px: width,
        };
        let mut engine = ZoiEngine::new(n);
        let mut plain = vec![Complex32::new(0.0, 0.0); spectrum_len(n)];
        let mut windowed = vec![0.0; n * n];
        let mut sensitivity = GradientSensitivity::default();
        assert!(engine.prepare_reference(image, 8, 8, &mut plain, &mut windowed, &mut sensitivity));
        let expected = [[r0.0, r0.1, 0.0, 0.0], [0.0, 0.0, r0.0, r0.1]];
        for (row, expected_row) in sensitivity.k.iter().zip(expected) {
            for (&k, e) in row.iter().zip(expected_row) {
                assert!((k as f64 - e).abs() < 0.1, "{:?}", sensitivity.k);
            }
        }
        // The bias for a 10 % stretch along x is 0.1 r0x along x.
        let (bx, by) = sensitivity.bias_px([[0.1, 0.0], [0.0, 0.0]]);
        assert!((bx - 0.5).abs() < 0.01 && by.abs() < 0.01, "{bx} {by}");
    }

    /// The direct 3x3 values are the inverse FFT of G_w conj(F_w) at those shifts, wrapped.
    #[test]
    fn direct_correlation_matches_the_fft_map() {
        let n = 32;
        let mut engine = ZoiEngine::new(n);
        let texture = |i: usize, a: f32, b: f32| {
            1000.0 * ((i % n) as f32 * a).sin() * ((i / n) as f32 * b + 0.3).cos()
        };
        let reference: Vec<f32> = (0..n * n).map(|i| texture(i, 0.71, 0.43)).collect();
        let deformed: Vec<f32> = (0..n * n)
            .map(|i| texture(i + 1, 0.69, 0.45) + 0.1)
            .collect();
        // Windowed reference, as prepare_reference caches it.
        engine.g_spatial.copy_from_slice(&reference);
        let mut f = vec![0.0f32; n * n];
        engine.window_into(&mut f).unwrap();
        engine.g_spatial.copy_from_slice(&deformed);
        let mut g = vec![0.0f32; n * n];
        engine.window_into(&mut g).unwrap();
        // The correlate path: unnormalised into the extended rows, 1/norm on the values.
        let mut extended = std::mem::take(&mut engine.extended);
        let norm = engine.window_rows(&mut extended, n + 2 * PAD, PAD).unwrap();
        engine.extended = extended;
        engine.wrap_rows();
        let scale = 1.0 / norm;
        // FFT map.
        let zero = Complex32::new(0.0, 0.0);
        let (mut gs, mut fs) = (vec![zero; spectrum_len(n)], vec![zero; spectrum_len(n)]);
        engine.fft.forward(&g, &mut gs);
        engine.fft.forward(&f, &mut fs);
        for (a, b) in gs.iter_mut().zip(&fs) {
            *a *= b.conj();
        }
        let mut map = vec![0.0f32; n * n];
        engine.fft.inverse(&mut gs, &mut map);
        let at = |dx: i64, dy: i64| {
            map[dy.rem_euclid(n as i64) as usize * n + dx.rem_euclid(n as i64) as usize]
                / (n * n) as f32
        };
        for cy in -1i64..=1 {
            for cx in -1i64..=1 {
                let c = engine.correlation_3x3(&f, (cx, cy), scale);
                for (row, values) in c.iter().enumerate() {
                    for (col, v) in values.iter().enumerate() {
                        let (dx, dy) = (cx + col as i64 - 1, cy + row as i64 - 1);
                        assert!(
                            (v - at(dx, dy)).abs() < 1e-5,
                            "({dx}, {dy}): {v} vs {}",
                            at(dx, dy)
                        );
                    }
                }
            }
        }
        let (px, py, c) = engine.peak_neighbourhood(&f, scale);
        for (row, values) in c.iter().enumerate() {
            for (col, v) in values.iter().enumerate() {
                let (dx, dy) = (px + col as i64 - 1, py + row as i64 - 1);
                assert!((v - at(dx, dy)).abs() < 1e-5);
            }
        }
    }
}
