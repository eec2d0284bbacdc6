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

mod describe;
mod fit;
mod raster;
#[cfg(test)]
mod tests;

use describe::*;
use fit::*;
use raster::*;

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
        let resampled = Raster {
            pixels: &self.resampled,
            width_px: frame.w,
            height_px: frame.h,
        };
        gaussian_blur(
            resampled,
            DOG_SIGMA_1,
            &mut self.blur1,
            &mut self.tmp,
            self.threads,
        );
        gaussian_blur(
            resampled,
            DOG_SIGMA_2,
            &mut self.blur2,
            &mut self.tmp,
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

/// A small deterministic generator (xorshift64): the binary test pattern and RANSAC draws.
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
