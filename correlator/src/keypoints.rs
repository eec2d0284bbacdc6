//! Whole-image initial guess by keypoints, invariant to rotation, scale and stretch: blobs
//! detected and described in the reference and the deformed image, matched, and filtered by
//! RANSAC to an affine map x' = A x + t (px: x = column, y = row, origin at the centre of the
//! top-left pixel), plus a locally weighted fit at any point for fields that are not affine.
//! It seeds the ZOIs when the cheaper guesses failed; the FFT step then absorbs errors up to
//! about n/4.
//!
//! # Method
//!
//! 1. **Affine normalisation from the pattern's own statistics.** A speckle pattern is
//!    statistically isotropic and stationary, so its gradient structure tensor
//!    M = E[∇I ∇Iᵀ] transforms under x' = F x as M' = F⁻ᵀ M F⁻¹, while the intensity
//!    variance is unchanged. Each image is resampled (bilinear) into its normalised frame
//!    u = κ M^½ / σ_I (x − c); between the two normalised frames the map is then a pure
//!    rotation (N' F N⁻¹ is orthogonal), whatever the scale or stretch (tested to 1.84:1
//!    anisotropy), and the speckle has a fixed size there (σ ≈ 1.5 px for Gaussian spots), so
//!    3-8 px speckles need no scale space. M uses a 5-point derivative (unbiased to a few %
//!    for σ ≥ 1.3 px); σ_I² comes from the structure function at a 24 px lag, so flat
//!    background dilutes it exactly as it dilutes M, and there is no cancellation against the
//!    mean. Magnifications beyond 4x (speckles finer than ~1.5 px, pure noise) give no
//!    keypoints.
//! 2. **Detection**: one difference of Gaussians (σ 1.2 and 2.0 normalised px), 3x3 extrema
//!    above the DoG's RMS, sub-pixel by parabola, bright and dark blobs apart; the strongest per
//!    cell of a 16x16 grid so they spread, at most 2000. Blobs are kept ~20 normalised px from
//!    the region's edge (the description disc and blur support).
//! 3. **Description**: orientation by intensity centroid (disc of radius 9 on the σ 2.0 image,
//!    every second pixel); 256 rotated binary tests (BRIEF-like, pairs Gaussian within radius
//!    12, orientations quantised to 64 bins of 5.6°, nearest-pixel samples of the σ 1.2 image).
//!    Binary rather than gradient histograms: with the affine part normalised away only
//!    rotation remains, and a precomputed table of pixel offsets per orientation bin makes
//!    description ~2 µs per keypoint and matching a few ns per pair (software popcount: the
//!    workspace does not enable the `popcnt` target feature).
//! 4. **Matching**: brute-force Hamming among blobs of the same polarity (halves the work),
//!    mutual nearest neighbours, ratio test 0.85, distance ≤ 96 of 256.
//! 5. **RANSAC** (seeded xorshift, deterministic): affine from 3 matches (thin or implausible
//!    triangles rejected: det A > 0, singular values in [0.2, 5]), inlier threshold 4 px,
//!    adaptive iteration count (≤ 2000), least-squares refinement.
//! 6. **Local consistency for non-affine fields**: from the global inliers, two sweeps keep
//!    every tentative match within 3 px of the Gaussian-weighted affine fit of the current
//!    inliers at the nearest node of a grid (spacing = radius / 2). A moderately non-uniform
//!    field (a bulge of 8 % local strain in the tests) keeps its correct matches far from the
//!    best global affine, and wrong matches (random over the image) are still rejected.
//! 7. **Trust**: None unless ≥ 20 inliers and ≥ 20 % of the tentative matches (unrelated
//!    speckles: 4 inliers of ~110 matches), and the refitted global map is plausible.
//!
//! [`KeypointGuess::local_affine`] fits the inliers around p with Gaussian weights whose
//! radius holds ~25 inliers on average (from the inliers' density, ≥ 8 px): a quadratic fit
//! returned as its linearisation at p (value and gradient unbiased by the field's curvature),
//! else an affine fit, else `global`. O(inliers) per call.
//!
//! # Figures
//!
//! 512² synthetic speckle (4 px FWHM, 35 % cover, 1 % noise; tests below): worst error of
//! `local_affine(p).apply(p)` over a 5x5 grid of the central area 0.04-0.16 px for rotations
//! (5° to 170°), scales 0.7-1.5 and stretches up to 50 % (gradient error < 0.2 %; 0.7 % with
//! a flat background beside the specimen), 0.26 px for 8 px speckle enlarged 1.5x, 0.32 px and
//! 2.6 % on a bulge of 8 % local strain; `global` alone 0.01-0.15 px on affine fields; unrelated
//! patterns, noise and flat images give None.
//!
//! 1024² 16-bit pair (rotation 30°, scale 1.1, 4 px speckle), 2 threads (AMD EPYC 2-vCPU VM),
//! medians: reference side (detect + describe, cached by the caller) 12.5 ms; per frame
//! 16.5 ms = deformed detect + describe 11.3 ms (normalise, resample and blur 5.4, blobs 3.8,
//! describe 2.6) + estimate 5.2 ms (match 3.5, RANSAC 0.14, local consistency 1.9). One thread:
//! 20.3 ms and 27.3 ms.
//!
//! # Integration
//!
//! `region`: the reference ROI for the reference, the whole image for the deformed one; it
//! should be mostly speckled (its statistics set the normalisation). Points are reported in
//! whole-image px. The matcher keeps four f32 buffers of the normalised frame, preallocated
//! in `new` at the image's pixel count (16 MB for 1024²) and reused; they grow if a normalised
//! frame is larger (fine speckle: at most 4x the region). Each call still allocates its keypoint
//! lists, an offsets table (256 kB) and the matching tables (a few 100 kB), acceptable at a new
//! reference or when a cheaper guess failed.
//! Threads are scoped (`std::thread::scope`), split by rows or keypoints.

use crate::zoi::Image;

/// Target standard deviation (px) of a speckle spot in the normalised frame.
const SPECKLE_SIGMA: f64 = 1.5;
/// Inner and outer Gaussian of the difference-of-Gaussians blob detector (normalised px).
const DOG_SIGMA_1: f64 = 1.2;
const DOG_SIGMA_2: f64 = 2.0;
/// Radius (normalised px) of the disc the binary tests are drawn from.
const DESC_RADIUS: f64 = 12.0;
/// Radius (normalised px) of the intensity-centroid orientation disc.
const ORIENT_RADIUS: i32 = 9;
/// Lag (px) of the structure-function variance estimate.
const VAR_LAG: usize = 24;
/// Number of quantised orientations of the test pattern.
const ORIENT_BINS: usize = 64;
/// Number of binary tests (bits) of a descriptor.
const DESC_BITS: usize = 256;
const DESC_WORDS: usize = DESC_BITS / 64;
/// Maximum number of keypoints kept per image, and the bucketing grid.
const MAX_KEYPOINTS: usize = 2000;
const GRID_CELLS: usize = 16;
/// Matching: Lowe ratio on Hamming distances, and absolute distance cap.
const MATCH_RATIO: f64 = 0.85;
const MATCH_MAX_DIST: u32 = 96;
/// RANSAC inlier threshold (deformed px), iterations, and local-consistency threshold.
const RANSAC_THRESHOLD: f64 = 4.0;
const RANSAC_MAX_ITER: usize = 2000;
const LOCAL_THRESHOLD: f64 = 3.0;
/// Acceptance: minimum inlier count and inlier ratio of the tentative matches.
const MIN_INLIERS: usize = 20;
const MIN_INLIER_RATIO: f64 = 0.2;

/// An affine map x' = a x + t (px).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine2 {
    pub a: [[f64; 2]; 2],
    pub t: [f64; 2],
}

impl Affine2 {
    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        [
            self.a[0][0] * p[0] + self.a[0][1] * p[1] + self.t[0],
            self.a[1][0] * p[0] + self.a[1][1] * p[1] + self.t[1],
        ]
    }
}

/// Keypoints and descriptors of one image (the reference's are kept while the reference stays).
pub struct KeypointSet {
    /// Positions in image px, bright blobs first, then dark blobs.
    points: Vec<[f64; 2]>,
    descriptors: Vec<[u64; DESC_WORDS]>,
    /// Number of bright blobs (they come first).
    bright: usize,
}

impl KeypointSet {
    pub fn len(&self) -> usize {
        self.points.len()
    }
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
    fn empty() -> Self {
        KeypointSet {
            points: Vec::new(),
            descriptors: Vec::new(),
            bright: 0,
        }
    }
}

/// The verified correspondences and the map they support.
pub struct KeypointGuess {
    pub global: Affine2,
    /// Inlier pairs (reference point, deformed point), px.
    pub inliers: Vec<([f64; 2], [f64; 2])>,
}

impl KeypointGuess {
    /// The affine map near `p` (reference px): a least-squares fit of the inliers weighted by
    /// distance to p (Gaussian weight with a radius adapted to the inlier density), falling back
    /// to `global` where there are too few.
    pub fn local_affine(&self, p: [f64; 2]) -> Affine2 {
        let radius = density_radius(&self.inliers);
        weighted_quadratic(&self.inliers, p, radius)
            .or_else(|| weighted_affine(&self.inliers, p, radius, None))
            .unwrap_or(self.global)
    }
}

/// Weighted least-squares quadratic fit of `pairs` around `p` (Gaussian radius `radius`),
/// returned as its linearisation at p (value and gradient there), which has no bias from the
/// curvature of the field. None when the support is too thin or degenerate.
fn weighted_quadratic(pairs: &[([f64; 2], [f64; 2])], p: [f64; 2], radius: f64) -> Option<Affine2> {
    let inv2 = 1.0 / (2.0 * radius * radius);
    let mut s = [[0.0f64; 6]; 6];
    let mut b = [[0.0f64; 6]; 2];
    let (mut sw, mut sw2) = (0.0, 0.0);
    for (r, d) in pairs {
        let dx = r[0] - p[0];
        let dy = r[1] - p[1];
        let q = (dx * dx + dy * dy) * inv2;
        if q > 12.0 {
            continue;
        }
        let w = (-q).exp();
        let (x, y) = (dx / radius, dy / radius);
        let v = [1.0, x, y, x * x, x * y, y * y];
        for i in 0..6 {
            for j in 0..6 {
                s[i][j] += w * v[i] * v[j];
            }
            b[0][i] += w * v[i] * d[0];
            b[1][i] += w * v[i] * d[1];
        }
        sw += w;
        sw2 += w * w;
    }
    if sw <= 0.0 || sw * sw / sw2 < 25.0 {
        return None;
    }
    let cx = solve_n(s, b[0])?;
    let cy = solve_n(s, b[1])?;
    let a = [
        [cx[1] / radius, cx[2] / radius],
        [cy[1] / radius, cy[2] / radius],
    ];
    let t = [
        cx[0] - a[0][0] * p[0] - a[0][1] * p[1],
        cy[0] - a[1][0] * p[0] - a[1][1] * p[1],
    ];
    Some(Affine2 { a, t })
}

/// Gaussian elimination with partial pivoting; None when (nearly) singular.
fn solve_n<const K: usize>(mut m: [[f64; K]; K], mut b: [f64; K]) -> Option<[f64; K]> {
    let scale = m.iter().flatten().fold(0.0f64, |acc, v| acc.max(v.abs()));
    if scale.is_nan() || scale <= 0.0 {
        return None;
    }
    for col in 0..K {
        let mut piv = col;
        for r in col + 1..K {
            if m[r][col].abs() > m[piv][col].abs() {
                piv = r;
            }
        }
        if m[piv][col].is_nan() || m[piv][col].abs() <= 1e-9 * scale {
            return None;
        }
        m.swap(col, piv);
        b.swap(col, piv);
        for r in col + 1..K {
            let f = m[r][col] / m[col][col];
            let pivot_row = m[col];
            for (v, p) in m[r][col..].iter_mut().zip(&pivot_row[col..]) {
                *v -= f * p;
            }
            b[r] -= f * b[col];
        }
    }
    let mut x = [0.0; K];
    for r in (0..K).rev() {
        let mut acc = b[r];
        for c in r + 1..K {
            acc -= m[r][c] * x[c];
        }
        x[r] = acc / m[r][r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Gaussian radius such that about 25 inliers fall within one radius on average.
fn density_radius(pairs: &[([f64; 2], [f64; 2])]) -> f64 {
    if pairs.is_empty() {
        return 1.0;
    }
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    for (r, _) in pairs {
        for k in 0..2 {
            lo[k] = lo[k].min(r[k]);
            hi[k] = hi[k].max(r[k]);
        }
    }
    let area = ((hi[0] - lo[0]) * (hi[1] - lo[1])).max(1.0);
    (25.0 * area / (std::f64::consts::PI * pairs.len() as f64))
        .sqrt()
        .max(8.0)
}

/// Weighted least-squares affine fit of `pairs` around `p` with Gaussian radius `radius`,
/// skipping index `skip`. None when the support is too thin or degenerate.
fn weighted_affine(
    pairs: &[([f64; 2], [f64; 2])],
    p: [f64; 2],
    radius: f64,
    skip: Option<usize>,
) -> Option<Affine2> {
    let inv2 = 1.0 / (2.0 * radius * radius);
    let mut s = [[0.0f64; 3]; 3];
    let mut bx = [0.0f64; 3];
    let mut by = [0.0f64; 3];
    let (mut sw, mut sw2) = (0.0, 0.0);
    for (i, (r, d)) in pairs.iter().enumerate() {
        if Some(i) == skip {
            continue;
        }
        let dx = r[0] - p[0];
        let dy = r[1] - p[1];
        let q = (dx * dx + dy * dy) * inv2;
        if q > 4.5 {
            continue;
        }
        let w = (-q).exp();
        let v = [1.0, dx / radius, dy / radius];
        for a in 0..3 {
            for b in 0..3 {
                s[a][b] += w * v[a] * v[b];
            }
            bx[a] += w * v[a] * d[0];
            by[a] += w * v[a] * d[1];
        }
        sw += w;
        sw2 += w * w;
    }
    // Effective number of points and conditioning of the spatial spread.
    if sw <= 0.0 || sw * sw / sw2 < 10.0 {
        return None;
    }
    let cxx = s[1][1] / sw - (s[0][1] / sw).powi(2);
    let cyy = s[2][2] / sw - (s[0][2] / sw).powi(2);
    let cxy = s[1][2] / sw - s[0][1] * s[0][2] / (sw * sw);
    let det = cxx * cyy - cxy * cxy;
    if det < 0.01 {
        return None;
    }
    let cx = solve3(&s, &bx)?;
    let cy = solve3(&s, &by)?;
    let a = [
        [cx[1] / radius, cx[2] / radius],
        [cy[1] / radius, cy[2] / radius],
    ];
    let t = [
        cx[0] - a[0][0] * p[0] - a[0][1] * p[1],
        cy[0] - a[1][0] * p[0] - a[1][1] * p[1],
    ];
    Some(Affine2 { a, t })
}

/// Solves a 3x3 linear system by Cramer's rule.
fn solve3(m: &[[f64; 3]; 3], b: &[f64; 3]) -> Option<[f64; 3]> {
    let det3 = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(m);
    let scale = m.iter().flatten().fold(0.0f64, |acc, v| acc.max(v.abs()));
    if !d.is_finite() || d.abs() <= 1e-12 * scale.powi(3) {
        return None;
    }
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let mut mk = *m;
        for r in 0..3 {
            mk[r][k] = b[r];
        }
        *o = det3(&mk) / d;
    }
    Some(out)
}

/// The map between image px x and normalised px u: u = n (x - c) + off.
#[derive(Clone, Copy, Debug)]
struct Frame {
    inv: [[f64; 2]; 2],
    c: [f64; 2],
    off: [f64; 2],
    w: usize,
    h: usize,
}

impl Frame {
    fn image_point(&self, u: [f64; 2]) -> [f64; 2] {
        let a = u[0] - self.off[0];
        let b = u[1] - self.off[1];
        [
            self.inv[0][0] * a + self.inv[0][1] * b + self.c[0],
            self.inv[1][0] * a + self.inv[1][1] * b + self.c[1],
        ]
    }
}

pub struct KeypointMatcher {
    threads: usize,
    resampled: Vec<f32>,
    blur1: Vec<f32>,
    blur2: Vec<f32>,
    tmp: Vec<f32>,
    pattern: Vec<[f32; 4]>,
}

impl KeypointMatcher {
    pub fn new(width_px: usize, height_px: usize, threads: usize) -> Self {
        let n = width_px.saturating_mul(height_px).min(1 << 26);
        KeypointMatcher {
            threads: threads.max(1),
            resampled: Vec::with_capacity(n),
            blur1: Vec::with_capacity(n),
            blur2: Vec::with_capacity(n),
            tmp: Vec::with_capacity(n),
            pattern: brief_pattern(),
        }
    }

    /// Detects and describes keypoints inside the rectangle `region` = (x, y, w, h) px of the
    /// image (the whole image is fine too).
    pub fn detect(&mut self, image: Image, region: (usize, usize, usize, usize)) -> KeypointSet {
        let (iw, ih) = (image.width_px, image.height_px);
        if iw == 0 || ih == 0 || image.pixels.len() < iw.saturating_mul(ih) {
            return KeypointSet::empty();
        }
        let x0 = region.0.min(iw);
        let y0 = region.1.min(ih);
        let x1 = region.0.saturating_add(region.2).min(iw);
        let y1 = region.1.saturating_add(region.3).min(ih);
        if x1 < x0 + 48 || y1 < y0 + 48 {
            return KeypointSet::empty();
        }
        let rect = (x0, y0, x1, y1);
        let Some(frame) = self.normalising_frame(image, rect) else {
            return KeypointSet::empty();
        };
        resample(&mut self.resampled, image, rect, &frame, self.threads);
        gaussian_blur(
            &self.resampled,
            &mut self.blur1,
            &mut self.tmp,
            frame.w,
            frame.h,
            DOG_SIGMA_1,
            self.threads,
        );
        gaussian_blur(
            &self.resampled,
            &mut self.blur2,
            &mut self.tmp,
            frame.w,
            frame.h,
            DOG_SIGMA_2,
            self.threads,
        );
        let cands = self.find_blobs(&frame, rect);
        self.describe(&frame, &cands)
    }

    /// Gradient structure tensor and intensity variance of the region give the normalising
    /// frame: u = kappa sqrt(M) / std(I) (x - c).
    fn normalising_frame(&self, image: Image, rect: (usize, usize, usize, usize)) -> Option<Frame> {
        let (x0, y0, x1, y1) = rect;
        let w = image.width_px;
        let px = image.pixels;
        // Every second to fourth row is plenty for these statistics. The pattern variance is estimated
        // from differences at a lag beyond the speckle correlation length (structure function
        // E[(I(x + L) - I(x))^2] = 2 var): flat background then dilutes it exactly as it dilutes
        // the gradient tensor, illumination gradients hardly matter, and there is no
        // cancellation against a large mean.
        let step = ((y1 - y0) / 256).clamp(2, 4);
        let rows = (y1 - y0 - 4) / step;
        let parts = par_map(rows, self.threads, |r0, r1| {
            let mut acc = [0.0f64; 7];
            for y in (r0..r1).map(|r| y0 + 2 + step * r) {
                let row = &px[y * w..(y + 1) * w];
                let (mut s, mut gxx, mut gyy, mut gxy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
                for x in (x0 + 2)..(x1 - 2) {
                    let v = row[x] as f32;
                    let gx = (row[x - 2] as f32 - row[x + 2] as f32)
                        + 8.0 * (row[x + 1] as f32 - row[x - 1] as f32);
                    let gy = (px[(y - 2) * w + x] as f32 - px[(y + 2) * w + x] as f32)
                        + 8.0 * (px[(y + 1) * w + x] as f32 - px[(y - 1) * w + x] as f32);
                    s += v;
                    gxx += gx * gx;
                    gyy += gy * gy;
                    gxy += gx * gy;
                }
                let mut sx = 0.0f32;
                for (a, b) in row[x0 + 2..x1 - 2]
                    .iter()
                    .zip(&row[x0 + 2 + VAR_LAG..x1 - 2])
                {
                    let d = *b as f32 - *a as f32;
                    sx += d * d;
                }
                if y + VAR_LAG < y1 {
                    let below = &px[(y + VAR_LAG) * w..(y + VAR_LAG + 1) * w];
                    let mut sy = 0.0f32;
                    for (a, b) in row[x0 + 2..x1 - 2].iter().zip(&below[x0 + 2..x1 - 2]) {
                        let d = *b as f32 - *a as f32;
                        sy += d * d;
                    }
                    acc[6] += sy as f64;
                    acc[5] += 1.0;
                }
                acc[0] += s as f64;
                acc[1] += sx as f64;
                acc[2] += gxx as f64;
                acc[3] += gyy as f64;
                acc[4] += gxy as f64;
            }
            acc
        });
        let mut acc = [0.0f64; 7];
        for p in parts {
            for (a, v) in acc.iter_mut().zip(p) {
                *a += v;
            }
        }
        let count = (rows * (x1 - x0 - 4)) as f64;
        let count_x = (rows * (x1 - x0 - 4 - VAR_LAG)) as f64;
        let count_y = acc[5] * (x1 - x0 - 4) as f64;
        if count_y < 1.0 {
            return None;
        }
        let mean = acc[0] / count;
        let var = 0.25 * (acc[1] / count_x + acc[6] / count_y);
        let g = 1.0 / (144.0 * count);
        let (mxx, myy, mxy) = (acc[2] * g, acc[3] * g, acc[4] * g);
        let det = mxx * myy - mxy * mxy;
        // Flat or structureless: no keypoints (also guards the square roots below).
        if !(var > 1e-6 && det > 0.0 && det.is_finite()) || var < 1e-4 * mean.abs().max(1.0) {
            return None;
        }
        let sd = det.sqrt();
        let tn = (mxx + myy + 2.0 * sd).sqrt();
        let kappa = SPECKLE_SIGMA * std::f64::consts::SQRT_2 / var.sqrt();
        let n = [
            [kappa * (mxx + sd) / tn, kappa * mxy / tn],
            [kappa * mxy / tn, kappa * (myy + sd) / tn],
        ];
        let dn = n[0][0] * n[1][1] - n[0][1] * n[1][0];
        if !(dn > 0.0 && dn.is_finite()) {
            return None;
        }
        let inv = [[n[1][1] / dn, -n[0][1] / dn], [-n[1][0] / dn, n[0][0] / dn]];
        let c = [(x0 + x1 - 1) as f64 * 0.5, (y0 + y1 - 1) as f64 * 0.5];
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        for (cx, cy) in [
            (x0 as f64, y0 as f64),
            ((x1 - 1) as f64, y0 as f64),
            (x0 as f64, (y1 - 1) as f64),
            ((x1 - 1) as f64, (y1 - 1) as f64),
        ] {
            let d = [cx - c[0], cy - c[1]];
            let u = [
                n[0][0] * d[0] + n[0][1] * d[1],
                n[1][0] * d[0] + n[1][1] * d[1],
            ];
            for k in 0..2 {
                lo[k] = lo[k].min(u[k]);
                hi[k] = hi[k].max(u[k]);
            }
        }
        let fw = (hi[0] - lo[0]).ceil() + 1.0;
        let fh = (hi[1] - lo[1]).ceil() + 1.0;
        // Refuse large magnifications (speckles finer than ~1.5 px FWHM, or pure noise): the
        // normalised frame may hold at most 4x the region's pixels.
        let limit = 4.0 * ((x1 - x0) * (y1 - y0)) as f64;
        if (fw * fh).is_nan() || fw * fh > limit || fw < 32.0 || fh < 32.0 {
            return None;
        }
        Some(Frame {
            inv,
            c,
            off: [-lo[0], -lo[1]],
            w: fw as usize,
            h: fh as usize,
        })
    }

    /// Local extrema of the DoG, bucketed over a grid, strongest first.
    fn find_blobs(&mut self, frame: &Frame, rect: (usize, usize, usize, usize)) -> Vec<Blob> {
        let (w, h) = (frame.w, frame.h);
        // The DoG image, into the (free) scratch buffer.
        {
            let (b1, b2) = (&self.blur1, &self.blur2);
            par_rows(&mut self.tmp, w, self.threads, |y, row| {
                let r1 = &b1[y * w..(y + 1) * w];
                let r2 = &b2[y * w..(y + 1) * w];
                for ((o, a), b) in row.iter_mut().zip(r1).zip(r2) {
                    *o = a - b;
                }
            });
        }
        let dog = &self.tmp;
        // Margin in image px that keeps the description disc (plus blur support) inside the
        // region: the spectral norm of inv times the normalised margin.
        let margin_u = DESC_RADIUS + 3.0 * DOG_SIGMA_2 + 2.0;
        let spec = spectral_norm(&frame.inv);
        let margin = margin_u * spec;
        let (x0, y0, x1, y1) = (
            rect.0 as f64 + margin,
            rect.1 as f64 + margin,
            (rect.2 - 1) as f64 - margin,
            (rect.3 - 1) as f64 - margin,
        );
        if x1 <= x0 || y1 <= y0 {
            return Vec::new();
        }
        let mu = margin_u.ceil() as usize + 1;
        if w <= 2 * mu + 2 || h <= 2 * mu + 2 {
            return Vec::new();
        }
        let rows = h - 2 * mu;
        let d = |i: usize| dog[i];
        // RMS of the DoG over the interior, for a relative threshold.
        let sums = par_map(rows, self.threads, |r0, r1| {
            let mut s = 0.0f64;
            for y in ((mu + r0)..(mu + r1)).step_by(4) {
                let mut sr = 0.0f32;
                for i in (y * w + mu)..(y * w + w - mu) {
                    let v = d(i);
                    sr += v * v;
                }
                s += sr as f64;
            }
            s
        });
        let sampled = (0..rows).step_by(4).count().max(1);
        let rms = (sums.iter().sum::<f64>() / (sampled * (w - 2 * mu)) as f64).sqrt() as f32;
        if rms.is_nan() || rms <= 0.0 {
            return Vec::new();
        }
        let thr = rms;
        let found = par_map(rows, self.threads, |r0, r1| {
            let mut out = Vec::new();
            for y in (mu + r0)..(mu + r1) {
                for x in mu..(w - mu) {
                    let i = y * w + x;
                    let v = d(i);
                    if v.abs() <= thr {
                        continue;
                    }
                    let mut is_ext = true;
                    for j in [
                        i - w - 1,
                        i - w,
                        i - w + 1,
                        i - 1,
                        i + 1,
                        i + w - 1,
                        i + w,
                        i + w + 1,
                    ] {
                        let dj = d(j);
                        if (v > 0.0 && dj >= v) || (v < 0.0 && dj <= v) {
                            is_ext = false;
                            break;
                        }
                    }
                    if !is_ext {
                        continue;
                    }
                    let (l, r, t, b) = (d(i - 1), d(i + 1), d(i - w), d(i + w));
                    let sub = |m: f32, c: f32, p: f32| {
                        let den = m - 2.0 * c + p;
                        if den.abs() > 1e-12 {
                            (0.5 * (m - p) / den).clamp(-0.5, 0.5)
                        } else {
                            0.0
                        }
                    };
                    let u = [
                        x as f64 + sub(l, v, r) as f64,
                        y as f64 + sub(t, v, b) as f64,
                    ];
                    let xi = frame.image_point(u);
                    if xi[0] < x0 || xi[0] > x1 || xi[1] < y0 || xi[1] > y1 {
                        continue;
                    }
                    out.push(Blob {
                        u,
                        x: xi,
                        strength: v.abs(),
                        bright: v > 0.0,
                    });
                }
            }
            out
        });
        let all: Vec<Blob> = found.into_iter().flatten().collect();
        bucket(all, w, h)
    }

    /// Orientation by intensity centroid, rotated binary tests on the smoothed image.
    fn describe(&self, frame: &Frame, blobs: &[Blob]) -> KeypointSet {
        let w = frame.w;
        let b1 = &self.blur1;
        let b2 = &self.blur2;
        let pattern = &self.pattern;
        // Orientation disc sampled every second pixel (B2 is smooth at that step).
        let disc: Vec<(isize, f32, f32)> = {
            let r = ORIENT_RADIUS;
            let mut v = Vec::new();
            for dy in (-r..=r).step_by(2) {
                for dx in (-r..=r).step_by(2) {
                    if dx * dx + dy * dy <= r * r {
                        v.push((dy as isize * w as isize + dx as isize, dx as f32, dy as f32));
                    }
                }
            }
            v
        };
        // Pixel offsets of the test pairs for every orientation bin.
        let offsets: Vec<(isize, isize)> = (0..ORIENT_BINS)
            .flat_map(|bin| {
                let t = bin as f32 * std::f32::consts::TAU / ORIENT_BINS as f32;
                let (sn, cs) = t.sin_cos();
                pattern.iter().map(move |p| {
                    let o = |px: f32, py: f32| {
                        let x = (cs * px - sn * py).round() as isize;
                        let y = (sn * px + cs * py).round() as isize;
                        y * w as isize + x
                    };
                    (o(p[0], p[1]), o(p[2], p[3]))
                })
            })
            .collect();
        let offsets = &offsets;
        let descs = par_map(blobs.len(), self.threads, |k0, k1| {
            let mut out = Vec::with_capacity(k1 - k0);
            for blob in &blobs[k0..k1] {
                // Blobs are at least DESC_RADIUS + 2 px inside the frame: the offsets below
                // stay in bounds (indexing still checks).
                let cx = (blob.u[0] + 0.5) as isize;
                let cy = (blob.u[1] + 0.5) as isize;
                let ci = cy * w as isize + cx;
                let (mut mx, mut my) = (0.0f32, 0.0f32);
                for &(o, dx, dy) in &disc {
                    let v = b2[(ci + o) as usize];
                    mx += v * dx;
                    my += v * dy;
                }
                let norm = (mx * mx + my * my).sqrt();
                let (cs, sn) = if norm > 0.0 {
                    (mx / norm, my / norm)
                } else {
                    (1.0, 0.0)
                };
                // Nearest-pixel sampling of the smoothed image at the test points rotated to the
                // nearest of ORIENT_BINS orientations (precomputed pixel offsets).
                let angle = sn.atan2(cs).rem_euclid(std::f32::consts::TAU);
                let bin = ((angle / std::f32::consts::TAU * ORIENT_BINS as f32).round() as usize)
                    % ORIENT_BINS;
                let offs = &offsets[bin * DESC_BITS..(bin + 1) * DESC_BITS];
                let ci = ci as usize;
                let mut desc = [0u64; DESC_WORDS];
                for (bit, &(a, b)) in offs.iter().enumerate() {
                    let va = b1[ci.wrapping_add_signed(a)];
                    let vb = b1[ci.wrapping_add_signed(b)];
                    if va < vb {
                        desc[bit / 64] |= 1u64 << (bit % 64);
                    }
                }
                out.push(desc);
            }
            out
        });
        let descs: Vec<[u64; DESC_WORDS]> = descs.into_iter().flatten().collect();
        let mut set = KeypointSet::empty();
        for bright in [true, false] {
            for (b, d) in blobs.iter().zip(&descs) {
                if b.bright == bright {
                    set.points.push(b.x);
                    set.descriptors.push(*d);
                }
            }
            if bright {
                set.bright = set.points.len();
            }
        }
        set
    }

    /// Matches reference against deformed keypoints and fits the affine map by RANSAC; None
    /// when the match is not trustworthy.
    pub fn estimate(
        &mut self,
        reference: &KeypointSet,
        deformed: &KeypointSet,
    ) -> Option<KeypointGuess> {
        let matches = match_sets(reference, deformed, self.threads);
        if matches.len() < MIN_INLIERS {
            return None;
        }
        let pairs: Vec<([f64; 2], [f64; 2])> = matches
            .iter()
            .map(|&(r, d)| (reference.points[r], deformed.points[d]))
            .collect();
        let (global, _count) = ransac(&pairs)?;
        let inliers = local_consistency(&pairs, &global, self.threads);
        if inliers.len() < MIN_INLIERS
            || (inliers.len() as f64) < MIN_INLIER_RATIO * pairs.len() as f64
        {
            return None;
        }
        let global = fit_affine(&inliers).unwrap_or(global);
        if !plausible(&global) {
            return None;
        }
        Some(KeypointGuess { global, inliers })
    }
}

#[derive(Clone, Copy, Debug)]
struct Blob {
    u: [f64; 2],
    x: [f64; 2],
    strength: f32,
    bright: bool,
}

/// Keeps the strongest blobs per cell of a GRID_CELLS² grid (in the normalised frame) so the
/// keypoints spread over the image, then at most MAX_KEYPOINTS overall.
fn bucket(mut all: Vec<Blob>, w: usize, h: usize) -> Vec<Blob> {
    all.sort_by(|a, b| b.strength.total_cmp(&a.strength));
    let cells = GRID_CELLS * GRID_CELLS;
    let mut per_cell = vec![0usize; cells];
    let mut occupied = 0usize;
    let cell_of = |b: &Blob| {
        let cx = ((b.u[0] / w as f64 * GRID_CELLS as f64) as usize).min(GRID_CELLS - 1);
        let cy = ((b.u[1] / h as f64 * GRID_CELLS as f64) as usize).min(GRID_CELLS - 1);
        cy * GRID_CELLS + cx
    };
    for b in &all {
        let c = cell_of(b);
        if per_cell[c] == 0 {
            occupied += 1;
        }
        per_cell[c] += 1;
    }
    if occupied == 0 {
        return Vec::new();
    }
    let cap = MAX_KEYPOINTS.div_ceil(occupied);
    per_cell.iter_mut().for_each(|c| *c = 0);
    let mut out = Vec::with_capacity(MAX_KEYPOINTS);
    for b in all {
        let c = cell_of(&b);
        if per_cell[c] < cap {
            per_cell[c] += 1;
            out.push(b);
        }
    }
    out.truncate(MAX_KEYPOINTS);
    out
}

fn spectral_norm(m: &[[f64; 2]; 2]) -> f64 {
    let a = m[0][0] * m[0][0] + m[1][0] * m[1][0];
    let b = m[0][0] * m[0][1] + m[1][0] * m[1][1];
    let c = m[0][1] * m[0][1] + m[1][1] * m[1][1];
    let tr = a + c;
    let disc = ((a - c) * (a - c) + 4.0 * b * b).sqrt();
    (0.5 * (tr + disc)).sqrt()
}

/// Deterministic test pairs: both points Gaussian (sigma = 0.4 R) clipped to the disc.
fn brief_pattern() -> Vec<[f32; 4]> {
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
    let sigma = 0.4 * DESC_RADIUS;
    let point = |rng: &mut XorShift| loop {
        let (a, b) = rng.gauss_pair();
        let (x, y) = (a * sigma, b * sigma);
        if x * x + y * y <= DESC_RADIUS * DESC_RADIUS {
            return [x as f32, y as f32];
        }
    };
    (0..DESC_BITS)
        .map(|_| {
            let p = point(&mut rng);
            let q = point(&mut rng);
            [p[0], p[1], q[0], q[1]]
        })
        .collect()
}

struct XorShift(u64);

impl XorShift {
    fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn below(&mut self, n: usize) -> usize {
        ((self.next_u64() >> 33) as usize) % n.max(1)
    }
    fn gauss_pair(&mut self) -> (f64, f64) {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        let r = (-2.0 * u1.ln()).sqrt();
        let t = 2.0 * std::f64::consts::PI * u2;
        (r * t.cos(), r * t.sin())
    }
}

/// Splits 0..n into `threads` contiguous ranges and maps them in parallel.
fn par_map<T: Send, F: Fn(usize, usize) -> T + Sync>(n: usize, threads: usize, f: F) -> Vec<T> {
    let t = threads.max(1).min(n.max(1));
    if t <= 1 {
        return vec![f(0, n)];
    }
    let per = n.div_ceil(t);
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..t)
            .map(|k| {
                let f = &f;
                let (a, b) = ((k * per).min(n), ((k + 1) * per).min(n));
                s.spawn(move || f(a, b))
            })
            .collect();
        handles
            .into_iter()
            .map(|h| match h.join() {
                Ok(v) => v,
                Err(e) => std::panic::resume_unwind(e),
            })
            .collect()
    })
}

/// Runs `f(row_index, row)` over the rows of `out` in parallel.
fn par_rows<F: Fn(usize, &mut [f32]) + Sync>(out: &mut [f32], width: usize, threads: usize, f: F) {
    if width == 0 || out.is_empty() {
        return;
    }
    let rows = out.len() / width;
    let t = threads.max(1).min(rows.max(1));
    let per = rows.div_ceil(t);
    if t <= 1 {
        for (y, row) in out.chunks_mut(width).enumerate() {
            f(y, row);
        }
        return;
    }
    std::thread::scope(|s| {
        for (ci, chunk) in out.chunks_mut(per * width).enumerate() {
            let f = &f;
            s.spawn(move || {
                for (k, row) in chunk.chunks_mut(width).enumerate() {
                    f(ci * per + k, row);
                }
            });
        }
    });
}

/// Resamples the region into the normalised frame (bilinear); outside the region the value is
/// the region mean.
fn resample(
    out: &mut Vec<f32>,
    image: Image,
    rect: (usize, usize, usize, usize),
    frame: &Frame,
    threads: usize,
) {
    let (x0, y0, x1, y1) = rect;
    let iw = image.width_px;
    let px = image.pixels;
    let mut sum = 0.0f64;
    for y in y0..y1 {
        sum += px[y * iw + x0..y * iw + x1]
            .iter()
            .map(|&v| v as u64)
            .sum::<u64>() as f64;
    }
    let mean = (sum / ((x1 - x0) * (y1 - y0)) as f64) as f32;
    out.clear();
    out.resize(frame.w * frame.h, 0.0);
    let (xmax, ymax) = ((x1 - 1) as f64, (y1 - 1) as f64);
    par_rows(out, frame.w, threads, |j, row| {
        let start = frame.image_point([0.0, j as f64]);
        let (sx, sy) = (frame.inv[0][0], frame.inv[1][0]);
        for (i, o) in row.iter_mut().enumerate() {
            let x = start[0] + sx * i as f64;
            let y = start[1] + sy * i as f64;
            if x < x0 as f64 || y < y0 as f64 || x >= xmax || y >= ymax {
                *o = mean;
                continue;
            }
            // x, y >= 0 here: truncation is floor.
            let (xi, yi) = (x as usize, y as usize);
            let fx = (x - xi as f64) as f32;
            let fy = (y - yi as f64) as f32;
            let k = yi * iw + xi;
            let (a, b) = (px[k] as f32, px[k + 1] as f32);
            let (c, d) = (px[k + iw] as f32, px[k + iw + 1] as f32);
            let top = a + fx * (b - a);
            let bot = c + fx * (d - c);
            *o = top + fy * (bot - top);
        }
    });
}

/// Separable Gaussian blur with clamped borders.
fn gaussian_blur(
    src: &[f32],
    dst: &mut Vec<f32>,
    tmp: &mut Vec<f32>,
    w: usize,
    h: usize,
    sigma: f64,
    threads: usize,
) {
    let r = (3.0 * sigma).ceil() as usize;
    let mut k: Vec<f32> = (0..=2 * r)
        .map(|i| {
            let d = i as f64 - r as f64;
            (-d * d / (2.0 * sigma * sigma)).exp() as f32
        })
        .collect();
    let s: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= s);
    tmp.clear();
    tmp.resize(w * h, 0.0);
    dst.clear();
    dst.resize(w * h, 0.0);
    let k = &k;
    par_rows(tmp, w, threads, |y, row| {
        let srow = &src[y * w..(y + 1) * w];
        row.iter_mut().for_each(|v| *v = 0.0);
        if w > 2 * r {
            // Interior: accumulate tap by tap over the row (vectorises).
            for (i, kv) in k.iter().enumerate() {
                for (o, sv) in row[r..w - r].iter_mut().zip(&srow[i..w - 2 * r + i]) {
                    *o += kv * sv;
                }
            }
        }
        for x in (0..r.min(w)).chain(w.saturating_sub(r).max(r.min(w))..w) {
            let mut acc = 0.0f32;
            for (i, kv) in k.iter().enumerate() {
                let xx = (x + i).saturating_sub(r).min(w - 1);
                acc += kv * srow[xx];
            }
            row[x] = acc;
        }
    });
    let tmp = &*tmp;
    par_rows(dst, w, threads, |y, row| {
        row.iter_mut().for_each(|v| *v = 0.0);
        for (i, kv) in k.iter().enumerate() {
            let yy = (y + i).saturating_sub(r).min(h - 1);
            let srow = &tmp[yy * w..(yy + 1) * w];
            for (o, sv) in row.iter_mut().zip(srow) {
                *o += kv * sv;
            }
        }
    });
}

#[inline]
fn hamming(a: &[u64; DESC_WORDS], b: &[u64; DESC_WORDS]) -> u32 {
    let mut s = 0;
    for k in 0..DESC_WORDS {
        s += (a[k] ^ b[k]).count_ones();
    }
    s
}

/// Mutual nearest neighbours passing the ratio test, among blobs of the same polarity.
/// Returns (reference index, deformed index).
fn match_sets(
    reference: &KeypointSet,
    deformed: &KeypointSet,
    threads: usize,
) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let groups = [
        (0..reference.bright, 0..deformed.bright),
        (
            reference.bright..reference.len(),
            deformed.bright..deformed.len(),
        ),
    ];
    for (rr, dr) in groups {
        let (rn, dn) = (rr.len(), dr.len());
        if rn < 2 || dn < 2 {
            continue;
        }
        let rd = &reference.descriptors[rr.clone()];
        let dd = &deformed.descriptors[dr.clone()];
        // Per deformed keypoint: best reference index, best and second distances;
        // per thread: best deformed index for every reference keypoint.
        let parts = par_map(dn, threads, |a, b| {
            let mut rows = Vec::with_capacity(b - a);
            let mut col = vec![(u32::MAX, usize::MAX); rn];
            for (di, d) in dd[a..b].iter().enumerate() {
                let (mut b1, mut b2, mut bi) = (u32::MAX, u32::MAX, 0usize);
                for (ri, r) in rd.iter().enumerate() {
                    let h = hamming(d, r);
                    if h < b2 {
                        if h < b1 {
                            b2 = b1;
                            b1 = h;
                            bi = ri;
                        } else {
                            b2 = h;
                        }
                    }
                    let c = &mut col[ri];
                    if h < c.0 {
                        *c = (h, a + di);
                    }
                }
                rows.push((b1, b2, bi));
            }
            (a, rows, col)
        });
        let mut col = vec![(u32::MAX, usize::MAX); rn];
        for (_, _, c) in &parts {
            for (m, v) in col.iter_mut().zip(c) {
                if v.0 < m.0 {
                    *m = *v;
                }
            }
        }
        for (a, rows, _) in &parts {
            for (k, &(b1, b2, bi)) in rows.iter().enumerate() {
                let di = a + k;
                if b1 <= MATCH_MAX_DIST && (b1 as f64) < MATCH_RATIO * b2 as f64 && col[bi].1 == di
                {
                    out.push((rr.start + bi, dr.start + di));
                }
            }
        }
    }
    out
}

/// Exact affine map through three correspondences.
fn affine_from3(p: [([f64; 2], [f64; 2]); 3]) -> Option<Affine2> {
    let (a, b, c) = (p[0], p[1], p[2]);
    let u = [b.0[0] - a.0[0], b.0[1] - a.0[1]];
    let v = [c.0[0] - a.0[0], c.0[1] - a.0[1]];
    let det = u[0] * v[1] - u[1] * v[0];
    // Reject thin triangles (area below ~50 px² or very flat).
    let lu = (u[0] * u[0] + u[1] * u[1]).sqrt();
    let lv = (v[0] * v[0] + v[1] * v[1]).sqrt();
    if det.abs() < 100.0 || det.abs() < 0.1 * lu * lv {
        return None;
    }
    let up = [b.1[0] - a.1[0], b.1[1] - a.1[1]];
    let vp = [c.1[0] - a.1[0], c.1[1] - a.1[1]];
    // A [u v] = [up vp]  =>  A = [up vp] [u v]^-1
    let inv = [[v[1] / det, -v[0] / det], [-u[1] / det, u[0] / det]];
    let m = [[up[0], vp[0]], [up[1], vp[1]]];
    let am = [
        [
            m[0][0] * inv[0][0] + m[0][1] * inv[1][0],
            m[0][0] * inv[0][1] + m[0][1] * inv[1][1],
        ],
        [
            m[1][0] * inv[0][0] + m[1][1] * inv[1][0],
            m[1][0] * inv[0][1] + m[1][1] * inv[1][1],
        ],
    ];
    let t = [
        a.1[0] - am[0][0] * a.0[0] - am[0][1] * a.0[1],
        a.1[1] - am[1][0] * a.0[0] - am[1][1] * a.0[1],
    ];
    Some(Affine2 { a: am, t })
}

/// Determinant positive and singular values within [0.2, 5].
fn plausible(m: &Affine2) -> bool {
    let det = m.a[0][0] * m.a[1][1] - m.a[0][1] * m.a[1][0];
    if det.is_nan() || det <= 0.0 || !m.t[0].is_finite() || !m.t[1].is_finite() {
        return false;
    }
    let smax = spectral_norm(&m.a);
    let smin = det / smax;
    smin > 0.2 && smax < 5.0
}

fn residual(m: &Affine2, p: &([f64; 2], [f64; 2])) -> f64 {
    let q = m.apply(p.0);
    ((q[0] - p.1[0]).powi(2) + (q[1] - p.1[1]).powi(2)).sqrt()
}

/// Unweighted least-squares affine fit (coordinates centred and scaled for conditioning).
fn fit_affine(pairs: &[([f64; 2], [f64; 2])]) -> Option<Affine2> {
    if pairs.len() < 3 {
        return None;
    }
    let n = pairs.len() as f64;
    let mut c = [0.0; 2];
    for (r, _) in pairs {
        c[0] += r[0] / n;
        c[1] += r[1] / n;
    }
    let spread = (pairs
        .iter()
        .map(|(r, _)| (r[0] - c[0]).powi(2) + (r[1] - c[1]).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    if spread.is_nan() || spread < 1.0 {
        return None;
    }
    let mut s = [[0.0f64; 3]; 3];
    let mut bx = [0.0f64; 3];
    let mut by = [0.0f64; 3];
    for (r, d) in pairs {
        let v = [1.0, (r[0] - c[0]) / spread, (r[1] - c[1]) / spread];
        for a in 0..3 {
            for b in 0..3 {
                s[a][b] += v[a] * v[b];
            }
            bx[a] += v[a] * d[0];
            by[a] += v[a] * d[1];
        }
    }
    // Nearly collinear points: no affine map.
    let det = (s[1][1] * s[2][2] - s[1][2] * s[1][2]) / (n * n);
    if det < 1e-4 {
        return None;
    }
    let cx = solve3(&s, &bx)?;
    let cy = solve3(&s, &by)?;
    let a = [
        [cx[1] / spread, cx[2] / spread],
        [cy[1] / spread, cy[2] / spread],
    ];
    let t = [
        cx[0] - a[0][0] * c[0] - a[0][1] * c[1],
        cy[0] - a[1][0] * c[0] - a[1][1] * c[1],
    ];
    Some(Affine2 { a, t })
}

/// Seeded RANSAC for the affine map; returns the refined model and its inlier count.
fn ransac(pairs: &[([f64; 2], [f64; 2])]) -> Option<(Affine2, usize)> {
    let n = pairs.len();
    if n < 3 {
        return None;
    }
    let mut rng = XorShift(0x2545_F491_4F6C_DD1D);
    let mut best: Option<(Affine2, usize)> = None;
    let mut needed = RANSAC_MAX_ITER;
    let mut it = 0;
    while it < needed.min(RANSAC_MAX_ITER) {
        it += 1;
        let i = rng.below(n);
        let j = rng.below(n);
        let k = rng.below(n);
        if i == j || j == k || i == k {
            continue;
        }
        let Some(m) = affine_from3([pairs[i], pairs[j], pairs[k]]) else {
            continue;
        };
        if !plausible(&m) {
            continue;
        }
        let count = pairs
            .iter()
            .filter(|p| residual(&m, p) < RANSAC_THRESHOLD)
            .count();
        if best.as_ref().is_none_or(|b| count > b.1) {
            best = Some((m, count));
            let w = count as f64 / n as f64;
            let p_fail = 1.0 - w * w * w;
            if p_fail <= 0.0 {
                needed = it;
            } else if p_fail < 1.0 {
                needed = ((1e-4f64).ln() / p_fail.ln()).ceil().max(50.0) as usize;
            }
        }
    }
    let (mut model, mut count) = best?;
    // Refine by least squares on the inliers (twice).
    for _ in 0..2 {
        let inl: Vec<_> = pairs
            .iter()
            .filter(|p| residual(&model, p) < RANSAC_THRESHOLD)
            .copied()
            .collect();
        let Some(m) = fit_affine(&inl) else { break };
        let c = pairs
            .iter()
            .filter(|p| residual(&m, p) < RANSAC_THRESHOLD)
            .count();
        if c >= count {
            model = m;
            count = c;
        } else {
            break;
        }
    }
    Some((model, count))
}

/// Second pass for non-affine fields: starting from the global RANSAC inliers, keeps every
/// tentative match that agrees within LOCAL_THRESHOLD with the locally weighted affine fit of the
/// current inliers, evaluated at the nearest node of a grid (spacing radius / 2). Two sweeps.
fn local_consistency(
    pairs: &[([f64; 2], [f64; 2])],
    global: &Affine2,
    threads: usize,
) -> Vec<([f64; 2], [f64; 2])> {
    let mut inl: Vec<([f64; 2], [f64; 2])> = pairs
        .iter()
        .filter(|p| residual(global, p) < RANSAC_THRESHOLD)
        .copied()
        .collect();
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    for (r, _) in pairs {
        for k in 0..2 {
            lo[k] = lo[k].min(r[k]);
            hi[k] = hi[k].max(r[k]);
        }
    }
    for _ in 0..2 {
        if inl.len() < MIN_INLIERS {
            break;
        }
        let radius = density_radius(&inl);
        let step = 0.5 * radius;
        let nx = (((hi[0] - lo[0]) / step).ceil() as usize + 1).min(64);
        let ny = (((hi[1] - lo[1]) / step).ceil() as usize + 1).min(64);
        let sx = (hi[0] - lo[0]) / (nx.max(2) - 1) as f64;
        let sy = (hi[1] - lo[1]) / (ny.max(2) - 1) as f64;
        let node = |i: usize| [lo[0] + sx * (i % nx) as f64, lo[1] + sy * (i / nx) as f64];
        let fits: Vec<Affine2> = par_map(nx * ny, threads, |a, b| {
            (a..b)
                .map(|i| weighted_affine(&inl, node(i), radius, None).unwrap_or(*global))
                .collect::<Vec<_>>()
        })
        .into_iter()
        .flatten()
        .collect();
        let nearest = |r: [f64; 2]| {
            let ix = if sx > 0.0 {
                ((r[0] - lo[0]) / sx).round() as usize
            } else {
                0
            };
            let iy = if sy > 0.0 {
                ((r[1] - lo[1]) / sy).round() as usize
            } else {
                0
            };
            iy.min(ny - 1) * nx + ix.min(nx - 1)
        };
        inl = pairs
            .iter()
            .filter(|p| residual(&fits[nearest(p.0)], p) < LOCAL_THRESHOLD)
            .copied()
            .collect();
    }
    inl
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Test speckle renderer: Gaussian spots (random amplitude) on a bright background,
    /// evaluated analytically at the pre-image of each of 3x3 sub-samples per pixel.
    pub(super) struct Speckle {
        spots: Vec<[f64; 3]>,
        cells: Vec<Vec<u32>>,
        cell: f64,
        lo: [f64; 2],
        nx: usize,
        ny: usize,
        sigma: f64,
        contrast: f64,
        /// Flat background (value 0.15) where X < flat_left_of.
        flat_left_of: f64,
    }

    impl Speckle {
        /// Spots of `fwhm` px covering ~35 % of the box [lo, hi].
        pub(super) fn new(seed: u64, fwhm: f64, contrast: f64, lo: [f64; 2], hi: [f64; 2]) -> Self {
            let sigma = fwhm / 2.3548;
            let density = -(0.65f64).ln() / (std::f64::consts::PI * (fwhm / 2.0).powi(2));
            let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
            let count = (density * area) as usize;
            let mut rng = XorShift(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
            let cell = 4.0 * sigma;
            let nx = ((hi[0] - lo[0]) / cell).ceil() as usize + 1;
            let ny = ((hi[1] - lo[1]) / cell).ceil() as usize + 1;
            let mut cells = vec![Vec::new(); nx * ny];
            let mut spots = Vec::with_capacity(count);
            for k in 0..count {
                let x = lo[0] + rng.uniform() * (hi[0] - lo[0]);
                let y = lo[1] + rng.uniform() * (hi[1] - lo[1]);
                let a = 0.7 + 0.6 * rng.uniform();
                spots.push([x, y, a]);
                let cx = ((x - lo[0]) / cell) as usize;
                let cy = ((y - lo[1]) / cell) as usize;
                cells[cy * nx + cx].push(k as u32);
            }
            Speckle {
                spots,
                cells,
                cell,
                lo,
                nx,
                ny,
                sigma,
                contrast,
                flat_left_of: f64::NEG_INFINITY,
            }
        }

        /// Intensity in [0, 1] at reference point X.
        pub(super) fn value(&self, p: [f64; 2]) -> f64 {
            if p[0] < self.flat_left_of {
                return 0.15;
            }
            let cx = ((p[0] - self.lo[0]) / self.cell).floor() as isize;
            let cy = ((p[1] - self.lo[1]) / self.cell).floor() as isize;
            let inv = 1.0 / (2.0 * self.sigma * self.sigma);
            let mut v = 0.0;
            for yy in cy - 1..=cy + 1 {
                for xx in cx - 1..=cx + 1 {
                    if xx < 0 || yy < 0 || xx as usize >= self.nx || yy as usize >= self.ny {
                        continue;
                    }
                    for &k in &self.cells[yy as usize * self.nx + xx as usize] {
                        let s = self.spots[k as usize];
                        let d2 = (p[0] - s[0]).powi(2) + (p[1] - s[1]).powi(2);
                        if d2 < 16.0 * self.sigma * self.sigma {
                            v += s[2] * (-d2 * inv).exp();
                        }
                    }
                }
            }
            0.5 + 0.5 * self.contrast * (2.0 * (-2.5 * v).exp() - 1.0)
        }

        /// Renders a w x h image whose pixel x shows the pattern at `pre(x)`, with 3x3
        /// sub-samples, Gaussian noise (`noise` of full scale) and `bits` depth.
        pub(super) fn render(
            &self,
            w: usize,
            h: usize,
            pre: &dyn Fn([f64; 2]) -> [f64; 2],
            noise: f64,
            bits: u32,
            seed: u64,
        ) -> Vec<u16> {
            let full = ((1u32 << bits) - 1) as f64;
            let mut rng = XorShift(seed.wrapping_mul(0xD134_2543_DE82_EF95) | 1);
            let mut out = Vec::with_capacity(w * h);
            for y in 0..h {
                for x in 0..w {
                    let mut s = 0.0;
                    for sy in [-1.0, 0.0, 1.0] {
                        for sx in [-1.0, 0.0, 1.0] {
                            let q = pre([x as f64 + sx / 3.0, y as f64 + sy / 3.0]);
                            s += self.value(q);
                        }
                    }
                    let v = s / 9.0 + noise * rng.gauss_pair().0;
                    out.push((v * full).round().clamp(0.0, full) as u16);
                }
            }
            out
        }
    }

    const N: usize = 512;

    /// A deformation phi(X) = c + F (X - c) + t (+ optional radial bulge), with its inverse.
    #[derive(Clone, Copy)]
    struct Warp {
        f: [[f64; 2]; 2],
        t: [f64; 2],
        bulge: f64,
    }

    impl Warp {
        fn c() -> [f64; 2] {
            [(N as f64 - 1.0) * 0.5; 2]
        }
        fn phi(&self, x: [f64; 2]) -> [f64; 2] {
            let c = Self::c();
            let d = [x[0] - c[0], x[1] - c[1]];
            let g = self.bulge * (-(d[0] * d[0] + d[1] * d[1]) / (2.0 * 100.0f64.powi(2))).exp();
            let e = [d[0] * (1.0 + g), d[1] * (1.0 + g)];
            [
                c[0] + self.f[0][0] * e[0] + self.f[0][1] * e[1] + self.t[0],
                c[1] + self.f[1][0] * e[0] + self.f[1][1] * e[1] + self.t[1],
            ]
        }
        fn inverse(&self, x: [f64; 2]) -> [f64; 2] {
            let c = Self::c();
            let det = self.f[0][0] * self.f[1][1] - self.f[0][1] * self.f[1][0];
            let y = [x[0] - c[0] - self.t[0], x[1] - c[1] - self.t[1]];
            let e = [
                (self.f[1][1] * y[0] - self.f[0][1] * y[1]) / det,
                (-self.f[1][0] * y[0] + self.f[0][0] * y[1]) / det,
            ];
            // d (1 + g(|d|)) = e, by fixed point.
            let mut d = e;
            for _ in 0..50 {
                let g =
                    self.bulge * (-(d[0] * d[0] + d[1] * d[1]) / (2.0 * 100.0f64.powi(2))).exp();
                d = [e[0] / (1.0 + g), e[1] / (1.0 + g)];
            }
            [c[0] + d[0], c[1] + d[1]]
        }
    }

    fn rot(deg: f64, s: f64) -> [[f64; 2]; 2] {
        let (sn, cs) = deg.to_radians().sin_cos();
        [[s * cs, -s * sn], [s * sn, s * cs]]
    }

    struct Opts {
        fwhm: f64,
        contrast: f64,
        bits: u32,
        seed_def: u64,
        /// Specimen edge: flat background left of this reference abscissa.
        edge: f64,
        /// Lighting change of the deformed image: v -> 0.1 full scale + gain v.
        gain: f64,
    }

    const STD: Opts = Opts {
        fwhm: 4.0,
        contrast: 0.9,
        bits: 16,
        seed_def: 1,
        edge: f64::NEG_INFINITY,
        gain: 1.0,
    };

    fn images(warp: &Warp, o: &Opts) -> (Vec<u16>, Vec<u16>) {
        // Pattern box: the reference image and the pre-image of the deformed one, + margin.
        let (mut lo, mut hi) = ([-10.0f64, -10.0], [N as f64 + 10.0; 2]);
        for y in (0..=N).step_by(16) {
            for x in (0..=N).step_by(16) {
                let q = warp.inverse([x as f64, y as f64]);
                for k in 0..2 {
                    lo[k] = lo[k].min(q[k] - 10.0);
                    hi[k] = hi[k].max(q[k] + 10.0);
                }
            }
        }
        let mut sp = Speckle::new(7, o.fwhm, o.contrast, lo, hi);
        sp.flat_left_of = o.edge;
        let r = sp.render(N, N, &|x| x, 0.01, o.bits, 11);
        let sp_def = if o.seed_def == 1 {
            sp
        } else {
            Speckle::new(o.seed_def, o.fwhm, o.contrast, lo, hi)
        };
        let d = sp_def.render(N, N, &|x| warp.inverse(x), 0.01, o.bits, 13);
        let full = ((1u32 << o.bits) - 1) as f64;
        let d = if o.gain == 1.0 {
            d
        } else {
            d.iter()
                .map(|&v| (0.1 * full + o.gain * v as f64).round().min(full) as u16)
                .collect()
        };
        (r, d)
    }

    /// Returns the maximal guess error over a grid of the central area, or None.
    fn run(warp: Warp, o: &Opts) -> Option<f64> {
        let (r, d) = images(&warp, o);
        let mut m = KeypointMatcher::new(N, N, 2);
        fn img(p: &[u16]) -> Image<'_> {
            Image {
                pixels: p,
                width_px: N,
                height_px: N,
            }
        }
        let t0 = std::time::Instant::now();
        let ks_r = m.detect(img(&r), (0, 0, N, N));
        let ks_d = m.detect(img(&d), (0, 0, N, N));
        let guess = m.estimate(&ks_r, &ks_d);
        let el = t0.elapsed();
        let Some(g) = guess else {
            eprintln!("kp {} / {}: no guess ({el:?})", ks_r.len(), ks_d.len());
            return None;
        };
        let mut worst = 0.0f64;
        let mut worst_grad = 0.0f64;
        let mut worst_global = 0.0f64;
        for gy in 0..5 {
            for gx in 0..5 {
                let p = [176.0 + 40.0 * gx as f64, 176.0 + 40.0 * gy as f64];
                // Only points whose image lies inside the deformed image.
                let truth = warp.phi(p);
                if truth[0] < 24.0
                    || truth[1] < 24.0
                    || truth[0] > N as f64 - 24.0
                    || truth[1] > N as f64 - 24.0
                {
                    continue;
                }
                if warp.bulge == 0.0 {
                    let q = g.global.apply(p);
                    let e = ((q[0] - truth[0]).powi(2) + (q[1] - truth[1]).powi(2)).sqrt();
                    worst_global = worst_global.max(e);
                }
                let la = g.local_affine(p);
                let q = la.apply(p);
                let e = ((q[0] - truth[0]).powi(2) + (q[1] - truth[1]).powi(2)).sqrt();
                worst = worst.max(e);
                // Gradient: central differences of phi.
                let h = 0.5;
                for k in 0..2 {
                    let mut a = p;
                    let mut b = p;
                    a[k] -= h;
                    b[k] += h;
                    let (pa, pb) = (warp.phi(a), warp.phi(b));
                    for r in 0..2 {
                        let j = (pb[r] - pa[r]) / (2.0 * h);
                        worst_grad = worst_grad.max((la.a[r][k] - j).abs());
                    }
                }
            }
        }
        eprintln!(
            "kp {} / {}, inliers {}, worst error {worst:.3} px, gradient {worst_grad:.4}, global {worst_global:.3} px ({el:?})",
            ks_r.len(),
            ks_d.len(),
            g.inliers.len()
        );
        assert!(worst_grad < 0.03, "gradient error {worst_grad}");
        assert!(worst_global < 1.0, "global map error {worst_global}");
        Some(worst)
    }

    fn check(name: &str, f: [[f64; 2]; 2], t: [f64; 2], o: &Opts) {
        eprint!("{name}: ");
        let e = run(Warp { f, t, bulge: 0.0 }, o);
        assert!(matches!(e, Some(e) if e < 1.0), "{name}: {e:?}");
    }

    #[test]
    fn rotation_5() {
        check("rot 5", rot(5.0, 1.0), [12.0, -7.0], &STD);
    }
    #[test]
    fn rotation_30() {
        check("rot 30", rot(30.0, 1.0), [-20.0, 15.0], &STD);
    }
    #[test]
    fn rotation_90() {
        check("rot 90", rot(90.0, 1.0), [25.0, 30.0], &STD);
    }
    #[test]
    fn rotation_170() {
        check("rot 170", rot(170.0, 1.0), [-33.0, 21.0], &STD);
    }
    #[test]
    fn rotation_minus_120() {
        check("rot -120", rot(-120.0, 1.0), [40.0, -18.0], &STD);
    }
    #[test]
    fn scale_0_7() {
        check("scale 0.7", rot(0.0, 0.7), [15.0, 10.0], &STD);
    }
    #[test]
    fn scale_1_5() {
        check("scale 1.5", rot(0.0, 1.5), [-12.0, 20.0], &STD);
    }
    #[test]
    fn scale_1_5_rot_40() {
        check("scale 1.5 rot 40", rot(40.0, 1.5), [10.0, 5.0], &STD);
    }
    fn poisson(e: f64) -> [[f64; 2]; 2] {
        [[1.0 + e, 0.0], [0.0, 1.0 - 0.3 * e]]
    }
    fn incompressible(l: f64) -> [[f64; 2]; 2] {
        [[l, 0.0], [0.0, 1.0 / l.sqrt()]]
    }
    #[test]
    fn stretch_10() {
        check("stretch 10%", poisson(0.1), [20.0, -10.0], &STD);
    }
    #[test]
    fn stretch_30() {
        check("stretch 30%", poisson(0.3), [-15.0, 12.0], &STD);
    }
    #[test]
    fn stretch_50() {
        check("stretch 50%", poisson(0.5), [10.0, 30.0], &STD);
    }
    #[test]
    fn incompressible_10() {
        check(
            "incompressible 1.1",
            incompressible(1.1),
            [20.0, -10.0],
            &STD,
        );
    }
    #[test]
    fn incompressible_30() {
        check(
            "incompressible 1.3",
            incompressible(1.3),
            [-15.0, 12.0],
            &STD,
        );
    }
    #[test]
    fn incompressible_50() {
        check(
            "incompressible 1.5",
            incompressible(1.5),
            [10.0, 30.0],
            &STD,
        );
    }
    #[test]
    fn stretch_30_rotated_60() {
        let r = rot(60.0, 1.0);
        let s = poisson(0.3);
        let f = [
            [
                r[0][0] * s[0][0] + r[0][1] * s[1][0],
                r[0][0] * s[0][1] + r[0][1] * s[1][1],
            ],
            [
                r[1][0] * s[0][0] + r[1][1] * s[1][0],
                r[1][0] * s[0][1] + r[1][1] * s[1][1],
            ],
        ];
        check("stretch 30% rot 60", f, [18.0, -25.0], &STD);
    }
    #[test]
    fn eight_bit() {
        let o = Opts { bits: 8, ..STD };
        check("8-bit rot 30", rot(30.0, 1.0), [-20.0, 15.0], &o);
    }
    #[test]
    fn speckle_7px() {
        let o = Opts { fwhm: 7.0, ..STD };
        check("7 px rot 90 scale 1.2", rot(90.0, 1.2), [20.0, 15.0], &o);
    }
    #[test]
    fn speckle_3px_shrunk() {
        let o = Opts { fwhm: 3.0, ..STD };
        check(
            "3 px scale 0.75 rot -30",
            rot(-30.0, 0.75),
            [10.0, -12.0],
            &o,
        );
    }
    #[test]
    fn speckle_8px_enlarged() {
        let o = Opts { fwhm: 8.0, ..STD };
        check("8 px scale 1.5 rot 120", rot(120.0, 1.5), [-14.0, 9.0], &o);
    }
    #[test]
    fn background_left() {
        // A third of the reference is flat background; the specimen is enlarged, so its share
        // differs in the deformed image.
        let o = Opts { edge: 170.0, ..STD };
        check(
            "background scale 1.3 rot 20",
            rot(20.0, 1.3),
            [30.0, 0.0],
            &o,
        );
    }
    #[test]
    fn lighting_change() {
        let o = Opts { gain: 0.55, ..STD };
        check(
            "lighting gain 0.55 rot 45",
            rot(45.0, 1.0),
            [-9.0, 14.0],
            &o,
        );
    }
    #[test]
    fn low_contrast() {
        let o = Opts {
            contrast: 0.3,
            ..STD
        };
        check("contrast 0.3 rot 170", rot(170.0, 1.0), [-33.0, 21.0], &o);
    }
    #[test]
    fn bulge() {
        eprint!("bulge: ");
        let w = Warp {
            f: rot(20.0, 1.0),
            t: [10.0, -5.0],
            bulge: 0.08,
        };
        let e = run(w, &STD);
        assert!(matches!(e, Some(e) if e < 1.0), "bulge: {e:?}");
    }
    #[test]
    fn region_subset() {
        // Keypoints from sub-rectangles, reported in whole-image px.
        let warp = Warp {
            f: rot(-60.0, 1.2),
            t: [8.0, -6.0],
            bulge: 0.0,
        };
        let (r, d) = images(&warp, &STD);
        let mut m = KeypointMatcher::new(N, N, 2);
        let img = |p| Image {
            pixels: p,
            width_px: N,
            height_px: N,
        };
        let ks_r = m.detect(img(&r), (100, 80, 320, 360));
        let ks_d = m.detect(img(&d), (60, 60, 400, 400));
        let g = m.estimate(&ks_r, &ks_d).expect("guess");
        let p = [250.0, 260.0];
        let (q, t) = (g.local_affine(p).apply(p), warp.phi(p));
        let e = ((q[0] - t[0]).powi(2) + (q[1] - t[1]).powi(2)).sqrt();
        eprintln!(
            "region subset: inliers {}, error {e:.3} px",
            g.inliers.len()
        );
        assert!(e < 1.0);
        for (a, _) in &g.inliers {
            assert!(a[0] >= 100.0 && a[0] < 420.0 && a[1] >= 80.0 && a[1] < 440.0);
        }
    }

    #[test]
    fn small_reference_roi() {
        // The correlator's use: reference keypoints from its ROI only, deformed from the whole
        // image (most deformed keypoints then have no partner).
        let warp = Warp {
            f: rot(35.0, 1.1),
            t: [15.0, -10.0],
            bulge: 0.0,
        };
        let (r, d) = images(&warp, &STD);
        let mut m = KeypointMatcher::new(N, N, 2);
        let img = |p| Image {
            pixels: p,
            width_px: N,
            height_px: N,
        };
        let ks_r = m.detect(img(&r), (156, 156, 200, 200));
        let ks_d = m.detect(img(&d), (0, 0, N, N));
        let g = m.estimate(&ks_r, &ks_d).expect("guess");
        let mut worst = 0.0f64;
        for p in [
            [180.0, 180.0],
            [256.0, 256.0],
            [330.0, 200.0],
            [200.0, 330.0],
        ] {
            let (q, t) = (g.local_affine(p).apply(p), warp.phi(p));
            worst = worst.max(((q[0] - t[0]).powi(2) + (q[1] - t[1]).powi(2)).sqrt());
        }
        eprintln!(
            "small reference ROI: kp {} / {}, inliers {}, worst error {worst:.3} px",
            ks_r.len(),
            ks_d.len(),
            g.inliers.len()
        );
        assert!(worst < 1.0);
    }

    #[test]
    fn unrelated_gives_none() {
        for seed in [2, 3, 4] {
            eprint!("unrelated seed {seed}: ");
            let o = Opts {
                seed_def: seed,
                ..STD
            };
            assert!(run(
                Warp {
                    f: rot(0.0, 1.0),
                    t: [0.0, 0.0],
                    bulge: 0.0
                },
                &o
            )
            .is_none());
        }
    }
    #[test]
    fn flat_and_tiny_give_empty() {
        let flat = vec![1000u16; N * N];
        let mut m = KeypointMatcher::new(N, N, 2);
        let img = Image {
            pixels: &flat,
            width_px: N,
            height_px: N,
        };
        let k = m.detect(img, (0, 0, N, N));
        assert!(k.is_empty());
        assert!(m.estimate(&k, &k).is_none());
        let tiny = [5u16; 9];
        let img = Image {
            pixels: &tiny,
            width_px: 3,
            height_px: 3,
        };
        assert!(m.detect(img, (0, 0, 3, 3)).is_empty());
        let img = Image {
            pixels: &tiny,
            width_px: 100,
            height_px: 100,
        };
        assert!(m.detect(img, (0, 0, 100, 100)).is_empty());
        // Pure noise (no pattern) in both images: whatever is detected must not match.
        let mut rng = XorShift(99);
        let mut noise = || -> Vec<u16> {
            (0..N * N)
                .map(|_| (30000.0 + 650.0 * rng.gauss_pair().0) as u16)
                .collect()
        };
        let (n1, n2) = (noise(), noise());
        let im = |p| Image {
            pixels: p,
            width_px: N,
            height_px: N,
        };
        let k1 = m.detect(im(&n1), (0, 0, N, N));
        let k2 = m.detect(im(&n2), (0, 0, N, N));
        eprintln!("noise: {} / {} keypoints", k1.len(), k2.len());
        assert!(m.estimate(&k1, &k2).is_none());
        // Regions outside the image or too small.
        assert!(m.detect(im(&n1), (600, 0, 50, 50)).is_empty());
        assert!(m.detect(im(&n1), (0, 0, 20, 500)).is_empty());
        let zero = Image {
            pixels: &[],
            width_px: 0,
            height_px: 0,
        };
        assert!(m.detect(zero, (0, 0, 10, 10)).is_empty());
    }
}
