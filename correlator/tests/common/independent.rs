//! An independent speckle generator with exact ground truth, unrelated to the producer's
//! renderer, so that accuracy is not only judged on images made by the project's own model.
//!
//! # Pattern model
//! A Boolean model of hard-edged discs ("spray paint"): disc centres form a homogeneous
//! Poisson point process on the whole (unbounded) reference plane, radii are uniform in
//! [0.7, 1.3] x the mean radius, and a point is painted when any disc covers it. The intensity
//! λ is chosen so that the painted fraction is `coverage` (1 − exp(−λ π E[r²]) = coverage).
//! The process is generated lazily per square cell of side 4 mean radii from a hash of
//! (`seed`, cell indices), so the pattern is a function of `seed` alone: every render of one
//! seed, whatever its map and image size, shows the same material. The cells the map reaches
//! are binned once into a lookup grid (cell side ≈ the mean radius), so evaluating the pattern
//! is O(1) per sample; a point outside that grid falls back to generating its neighbourhood.
//!
//! # Imaging chain (all in the deformed image's frame, as a camera sees it)
//! 1. Area integration: every pixel (centred on integer coordinates, x = column, y = row,
//!    origin at the centre of the top-left pixel) is split into 8 x 8 sub-squares; the centre
//!    of each is mapped through `to_reference` and the sub-square's painted fraction is taken
//!    from the signed distance d to the nearest disc edge there, as clamp(1/2 − d/h, 0, 1)
//!    with h the sub-square's size in the reference frame (the half-plane approximation of
//!    the edge: exact for a straight edge along a side, and binary away from edges). A pixel,
//!    or a quadrant of it, whose footprint is farther than its sub-squares' reach from every
//!    disc edge is set to 0 or 1 directly: the value all its sub-squares would give (checked
//!    equal to the brute-force sum, also for a curved map).
//! 2. Optics: a Gaussian PSF of sigma `blur_sigma_px`, a separable discrete convolution of the
//!    integrated image; the image is rendered with a margin of ceil(4 sigma) pixels so no
//!    border rule is needed.
//! 3. Sensor: grey = background + (dot − background) x painted fraction, plus Gaussian noise
//!    of variance read_noise² + shot_noise x grey (fractions of full scale; `shot_noise` is
//!    1 / full-well electrons), rounded to `bit_depth` bits and clamped to [0, 2^bits − 1].
//!    The noise of a pixel is a hash of (`noise_seed`, pixel index): independent of threads.
//!
//! # Why the truth is exact
//! The deformed image is built by asking, for every sample point x of the camera, which
//! material point X = `to_reference`(x) it sees, then applying the same camera (integration,
//! PSF, sensor) as for the reference image. So the displacement of material point X is
//! exactly φ(X) − X with φ the inverse of `to_reference`, with no interpolation of a
//! reference image anywhere; [`affine_inverse`] and [`displacement`] give both sides of an
//! affine motion.
#![allow(dead_code)]

/// Parameters of the independent generator.
#[derive(Clone, Copy, Debug)]
pub struct IndependentSpeckle {
    /// Mean speckle (dot) diameter, px (e.g. 3 to 10).
    pub dot_diameter_px: f64,
    /// Fraction of the area covered by dots (0.3..0.6).
    pub coverage: f64,
    /// Grey levels of the background and of the dots, as fractions of full scale (contrast =
    /// their difference; dots may be dark on bright or bright on dark).
    pub background: f64,
    pub dot: f64,
    /// Optical blur: Gaussian PSF sigma, px (0 = none).
    pub blur_sigma_px: f64,
    /// Bit depth of the output (8, 10, 12, 16); values are stored in u16 in the low bits.
    pub bit_depth: u32,
    /// Gaussian read noise, fraction of full scale, plus Poisson-like shot noise scaled by
    /// `shot_noise` (0 = none): noise variance = read_noise² + shot_noise x grey.
    pub read_noise: f64,
    pub shot_noise: f64,
    /// Seed of the pattern (the noise has its own seed, see [`render`]).
    pub seed: u64,
}

impl Default for IndependentSpeckle {
    fn default() -> Self {
        Self {
            dot_diameter_px: 5.0,
            coverage: 0.5,
            background: 0.8,
            dot: 0.15,
            blur_sigma_px: 0.7,
            bit_depth: 8,
            read_noise: 0.01,
            shot_noise: 0.0,
            seed: 7,
        }
    }
}

impl IndependentSpeckle {
    /// Expected mean grey level (fraction of full scale) of a large image, before
    /// quantisation: background + (dot − background) x coverage.
    pub fn expected_mean(&self) -> f64 {
        self.background + (self.dot - self.background) * self.coverage
    }

    /// Full-scale value, 2^bit_depth − 1.
    pub fn full_scale(&self) -> f64 {
        ((1u32 << self.bit_depth) - 1) as f64
    }
}

/// The varied patterns the accuracy tests share, beside the default (5 px dark dots on a
/// bright background, 8 bit, 1 % read noise).
impl IndependentSpeckle {
    /// 3 px dots, 12 bit, 0.5 % read noise.
    pub fn fine_12_bit() -> Self {
        Self {
            dot_diameter_px: 3.0,
            bit_depth: 12,
            read_noise: 0.005,
            seed: 11,
            ..Self::default()
        }
    }

    /// 9 px dots seen through a 1.2 px blur, 16 bit, shot noise.
    pub fn coarse_16_bit_shot_noise() -> Self {
        Self {
            dot_diameter_px: 9.0,
            bit_depth: 16,
            read_noise: 0.002,
            shot_noise: 1e-4,
            blur_sigma_px: 1.2,
            seed: 12,
            ..Self::default()
        }
    }

    /// 5 px dots, 8 bit, contrast 20 % of full scale, 3 % read noise.
    pub fn low_contrast_8_bit() -> Self {
        Self {
            background: 0.55,
            dot: 0.35,
            read_noise: 0.03,
            seed: 13,
            ..Self::default()
        }
    }

    /// Bright 6 px dots on a dark background (35 % coverage), 10 bit, `read_noise`.
    pub fn bright_on_dark_10_bit(read_noise: f64) -> Self {
        Self {
            dot_diameter_px: 6.0,
            background: 0.1,
            dot: 0.9,
            bit_depth: 10,
            coverage: 0.35,
            read_noise,
            seed: 14,
            ..Self::default()
        }
    }
}

/// Sub-squares per pixel side for the area integration (a power of two).
pub const SUBSAMPLES: usize = 8;
const _: () = assert!(SUBSAMPLES.is_power_of_two());

/// Relative half-width of the radius distribution (radii uniform in mean x [1 − s, 1 + s]).
const RADIUS_SPREAD: f64 = 0.3;

/// Reach (reference px) beyond its edge with which a disc is binned into the lookup grid:
/// bounds the edge-ramp half-width and the radius of the uniform-pixel test.
const RAMP_MARGIN: f64 = 1.5;

/// Renders a width x height image of the pattern seen through `to_reference`, the map from a
/// deformed-image point x (px, x = column, y = row, origin at the centre of the top-left
/// pixel) to the reference (material) point X it shows; the identity gives the reference
/// image. `noise_seed` seeds the noise only (the pattern comes from `params.seed`), so
/// reference and deformed images of one pattern have independent noise. Row-major output,
/// values in the low `bit_depth` bits. The map must be `Sync`: the area integration runs on
/// 2 threads.
pub fn render(
    params: &IndependentSpeckle,
    width: usize,
    height: usize,
    to_reference: &(dyn Fn([f64; 2]) -> [f64; 2] + Sync),
    noise_seed: u64,
) -> Vec<u16> {
    assert!(
        (1..=16).contains(&params.bit_depth),
        "bit depth {} outside 1..=16",
        params.bit_depth
    );
    let painted = painted_fraction(params, width, height, to_reference);
    let sensor = Sensor::new(params);
    painted
        .iter()
        .enumerate()
        .map(|(i, &f)| sensor.expose(f, noise_seed, i as u64))
        .collect()
}

/// The painted fraction of every pixel (0 = background, 1 = dot) after area integration and
/// PSF blur, before the grey levels, noise and quantisation: the noise-free image in [0, 1].
pub fn painted_fraction(
    params: &IndependentSpeckle,
    width: usize,
    height: usize,
    to_reference: &(dyn Fn([f64; 2]) -> [f64; 2] + Sync),
) -> Vec<f64> {
    assert!(
        params.dot_diameter_px > 0.0,
        "dot diameter must be positive"
    );
    assert!(
        params.coverage > 0.0 && params.coverage < 1.0,
        "coverage {} outside (0, 1)",
        params.coverage
    );
    if width == 0 || height == 0 {
        return Vec::new();
    }
    let sigma = params.blur_sigma_px.max(0.0);
    let pad = if sigma > 0.0 {
        (4.0 * sigma).ceil() as usize
    } else {
        0
    };
    let (pw, ph) = (width + 2 * pad, height + 2 * pad);
    let origin = -(pad as f64);
    let pattern = Pattern::covering(params, pw, ph, origin, to_reference);

    // Area integration on the padded grid, two row bands on two threads.
    let mut integrated = vec![0f64; pw * ph];
    let split = ph.div_ceil(2) * pw;
    let (top, bottom) = integrated.split_at_mut(split);
    std::thread::scope(|scope| {
        let pattern = &pattern;
        scope.spawn(move || integrate_rows(pattern, to_reference, pw, origin, 0, top));
        integrate_rows(pattern, to_reference, pw, origin, ph.div_ceil(2), bottom);
    });

    if pad == 0 {
        return integrated;
    }
    let kernel = gaussian_kernel(sigma, pad);
    // Rows: padded rows, valid columns only.
    let mut along_x = vec![0f64; ph * width];
    for r in 0..ph {
        let src = &integrated[r * pw..(r + 1) * pw];
        for (c, out) in along_x[r * width..(r + 1) * width].iter_mut().enumerate() {
            *out = kernel.iter().zip(&src[c..]).map(|(k, v)| k * v).sum();
        }
    }
    // Columns: valid rows only.
    let mut out = vec![0f64; width * height];
    for r in 0..height {
        for (k, &w) in kernel.iter().enumerate() {
            let src = &along_x[(r + k) * width..(r + k + 1) * width];
            for (o, v) in out[r * width..(r + 1) * width].iter_mut().zip(src) {
                *o += w * v;
            }
        }
    }
    out
}

/// The map of the motion x = c + F (X − c) + t, inverted: x ↦ X = c + F⁻¹ (x − c − t)
/// (deformed → reference), for [`render`]. `f` is row-major: x₀ = f[0][0] X₀ + f[0][1] X₁.
pub fn affine_inverse(
    f: [[f64; 2]; 2],
    t: [f64; 2],
    centre: [f64; 2],
) -> impl Fn([f64; 2]) -> [f64; 2] + Sync + Send + Copy {
    let det = f[0][0] * f[1][1] - f[0][1] * f[1][0];
    assert!(det.abs() > 1e-12, "singular F");
    let inv = [
        [f[1][1] / det, -f[0][1] / det],
        [-f[1][0] / det, f[0][0] / det],
    ];
    move |x: [f64; 2]| {
        let d = [x[0] - centre[0] - t[0], x[1] - centre[1] - t[1]];
        [
            centre[0] + inv[0][0] * d[0] + inv[0][1] * d[1],
            centre[1] + inv[1][0] * d[0] + inv[1][1] * d[1],
        ]
    }
}

/// The exact displacement u(X) = φ(X) − X = c + F (X − c) + t − X of reference point `x_ref`
/// under the motion of [`affine_inverse`].
pub fn displacement(f: [[f64; 2]; 2], t: [f64; 2], centre: [f64; 2], x_ref: [f64; 2]) -> [f64; 2] {
    let d = [x_ref[0] - centre[0], x_ref[1] - centre[1]];
    [
        centre[0] + f[0][0] * d[0] + f[0][1] * d[1] + t[0] - x_ref[0],
        centre[1] + f[1][0] * d[0] + f[1][1] * d[1] + t[1] - x_ref[1],
    ]
}

/// F of a rotation by `deg` degrees (counter-clockwise in x-right, y-up axes; clockwise on
/// screen since y points down).
pub fn rotation(deg: f64) -> [[f64; 2]; 2] {
    let (s, c) = deg.to_radians().sin_cos();
    [[c, -s], [s, c]]
}

/// The identity map, for the reference image.
pub fn identity(x: [f64; 2]) -> [f64; 2] {
    x
}

// ---------------------------------------------------------------------------------------
// Pattern: the Boolean model of discs.

#[derive(Clone, Copy, Debug)]
struct Disc {
    c: [f64; 2],
    r: f64,
}

struct Pattern {
    seed: u64,
    /// Mean number of discs per generation cell.
    cell_mean: f64,
    /// Side of a generation cell, px.
    gen_cell: f64,
    mean_r: f64,
    /// Lookup grid: origin, cell side, size, and per-cell lists (CSR).
    origin: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    discs: Vec<Disc>,
}

impl Pattern {
    /// The pattern with a lookup grid covering everything `to_reference` reaches from the
    /// pw x ph pixel grid whose first pixel centre is at (origin, origin).
    fn covering(
        params: &IndependentSpeckle,
        pw: usize,
        ph: usize,
        origin: f64,
        to_reference: &dyn Fn([f64; 2]) -> [f64; 2],
    ) -> Self {
        let mean_r = 0.5 * params.dot_diameter_px;
        let mean_r2 = mean_r * mean_r * (1.0 + RADIUS_SPREAD * RADIUS_SPREAD / 3.0);
        let lambda = -(1.0 - params.coverage).ln() / (std::f64::consts::PI * mean_r2);
        let gen_cell = 4.0 * mean_r;
        let mut p = Pattern {
            seed: params.seed,
            cell_mean: lambda * gen_cell * gen_cell,
            gen_cell,
            mean_r,
            origin: [0.0; 2],
            cell: mean_r.max(0.5),
            nx: 0,
            ny: 0,
            start: vec![0],
            discs: Vec::new(),
        };

        // Bounding box of the reference points reached: the border of the pixel area densely,
        // its interior on a coarse grid (exact for affine maps; the fallback covers the rest).
        let (x0, x1) = (origin - 0.5, origin + pw as f64 - 0.5);
        let (y0, y1) = (origin - 0.5, origin + ph as f64 - 0.5);
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        let mut add = |x: [f64; 2]| {
            let q = to_reference(x);
            for k in 0..2 {
                if q[k].is_finite() {
                    lo[k] = lo[k].min(q[k]);
                    hi[k] = hi[k].max(q[k]);
                }
            }
        };
        let steps =
            |a: f64, b: f64, n: usize| (0..=n).map(move |i| a + (b - a) * i as f64 / n as f64);
        for x in steps(x0, x1, 2 * pw) {
            add([x, y0]);
            add([x, y1]);
        }
        for y in steps(y0, y1, 2 * ph) {
            add([x0, y]);
            add([x1, y]);
        }
        for y in steps(y0, y1, ph.div_ceil(8)) {
            for x in steps(x0, x1, pw.div_ceil(8)) {
                add([x, y]);
            }
        }
        if !(lo[0].is_finite() && lo[1].is_finite() && hi[0].is_finite() && hi[1].is_finite()) {
            return p; // empty grid: everything goes through the fallback
        }
        let margin = 2.0;
        p.origin = [lo[0] - margin, lo[1] - margin];
        p.nx = (((hi[0] - lo[0] + 2.0 * margin) / p.cell).ceil() as usize).max(1);
        p.ny = (((hi[1] - lo[1] + 2.0 * margin) / p.cell).ceil() as usize).max(1);
        assert!(
            p.nx.saturating_mul(p.ny) < 200_000_000,
            "map reaches a reference region too large to bin"
        );

        // Every disc that can reach the grid, binned into each lookup cell its inflated
        // bounding box overlaps (two passes: counts, then fill).
        let reach = (1.0 + RADIUS_SPREAD) * mean_r + RAMP_MARGIN;
        let gx0 = ((p.origin[0] - reach) / gen_cell).floor() as i64;
        let gx1 = ((p.origin[0] + p.nx as f64 * p.cell + reach) / gen_cell).floor() as i64;
        let gy0 = ((p.origin[1] - reach) / gen_cell).floor() as i64;
        let gy1 = ((p.origin[1] + p.ny as f64 * p.cell + reach) / gen_cell).floor() as i64;
        let mut all = Vec::new();
        for gy in gy0..=gy1 {
            for gx in gx0..=gx1 {
                p.generate(gx, gy, &mut all);
            }
        }
        let range = |d: &Disc, p: &Pattern| {
            let e = d.r + RAMP_MARGIN;
            let clampi = |v: f64, n: usize| (v.floor().max(0.0) as usize).min(n - 1);
            let (a0, a1) = (
                (d.c[0] - e - p.origin[0]) / p.cell,
                (d.c[0] + e - p.origin[0]) / p.cell,
            );
            let (b0, b1) = (
                (d.c[1] - e - p.origin[1]) / p.cell,
                (d.c[1] + e - p.origin[1]) / p.cell,
            );
            if a1 < 0.0 || b1 < 0.0 || a0 >= p.nx as f64 || b0 >= p.ny as f64 {
                None
            } else {
                Some((
                    clampi(a0, p.nx),
                    clampi(a1, p.nx),
                    clampi(b0, p.ny),
                    clampi(b1, p.ny),
                ))
            }
        };
        let mut count = vec![0u32; p.nx * p.ny + 1];
        for d in &all {
            if let Some((i0, i1, j0, j1)) = range(d, &p) {
                for j in j0..=j1 {
                    for c in &mut count[j * p.nx + i0..=j * p.nx + i1] {
                        *c += 1;
                    }
                }
            }
        }
        let mut start = vec![0u32; p.nx * p.ny + 1];
        for k in 0..p.nx * p.ny {
            start[k + 1] = start[k] + count[k];
        }
        let mut fill: Vec<u32> = start[..p.nx * p.ny].to_vec();
        let mut discs = vec![
            Disc {
                c: [0.0; 2],
                r: 0.0
            };
            start[p.nx * p.ny] as usize
        ];
        for d in &all {
            if let Some((i0, i1, j0, j1)) = range(d, &p) {
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        let slot = &mut fill[j * p.nx + i];
                        discs[*slot as usize] = *d;
                        *slot += 1;
                    }
                }
            }
        }
        p.start = start;
        p.discs = discs;
        p
    }

    /// Appends the discs whose centres lie in generation cell (gx, gy).
    fn generate(&self, gx: i64, gy: i64, out: &mut Vec<Disc>) {
        let mut rng = SplitMix(mix(self.seed
            ^ mix((gx as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15))
            ^ mix((gy as u64)
                .wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
                .rotate_left(17))));
        // Poisson count (Knuth; the mean is a few units).
        let limit = (-self.cell_mean).exp();
        let mut n = 0usize;
        let mut prod = rng.uniform();
        while prod > limit {
            n += 1;
            prod *= rng.uniform();
        }
        for _ in 0..n {
            let c = [
                (gx as f64 + rng.uniform()) * self.gen_cell,
                (gy as f64 + rng.uniform()) * self.gen_cell,
            ];
            let r = self.mean_r * (1.0 + RADIUS_SPREAD * (2.0 * rng.uniform() - 1.0));
            out.push(Disc { c, r });
        }
    }

    /// Some(0 or 1) when no disc edge passes within `rho` (≤ RAMP_MARGIN) of `x` inside the
    /// lookup grid, so a pixel footprint of that radius is uniformly background or dot.
    #[inline]
    fn uniform(&self, x: [f64; 2], rho: f64) -> Option<f64> {
        let fx = (x[0] - self.origin[0]) / self.cell;
        let fy = (x[1] - self.origin[1]) / self.cell;
        if !(rho <= RAMP_MARGIN && fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        let (i, j) = (fx as usize, fy as usize);
        if i >= self.nx || j >= self.ny {
            return None;
        }
        let k = j * self.nx + i;
        for d in &self.discs[self.start[k] as usize..self.start[k + 1] as usize] {
            let dx = x[0] - d.c[0];
            let dy = x[1] - d.c[1];
            let q = dx * dx + dy * dy;
            let inner = d.r - rho;
            if inner > 0.0 && q <= inner * inner {
                return Some(1.0);
            }
            let outer = d.r + rho;
            if q < outer * outer {
                return None;
            }
        }
        Some(0.0)
    }

    /// Painted fraction of a sub-square of size h (reference px) centred at `x`.
    #[inline]
    fn coverage(&self, x: [f64; 2], h: f64, scratch: &mut Vec<Disc>) -> f64 {
        let fx = (x[0] - self.origin[0]) / self.cell;
        let fy = (x[1] - self.origin[1]) / self.cell;
        let list: &[Disc] =
            if fx >= 0.0 && fy >= 0.0 && (fx as usize) < self.nx && (fy as usize) < self.ny {
                let k = fy as usize * self.nx + fx as usize;
                &self.discs[self.start[k] as usize..self.start[k + 1] as usize]
            } else if x[0].is_finite() && x[1].is_finite() {
                // Fallback outside the lookup grid: the 3 x 3 generation cells around x hold every
                // disc that can reach it (reach < gen_cell).
                scratch.clear();
                let gx = (x[0] / self.gen_cell).floor() as i64;
                let gy = (x[1] / self.gen_cell).floor() as i64;
                for j in gy - 1..=gy + 1 {
                    for i in gx - 1..=gx + 1 {
                        self.generate(i, j, scratch);
                    }
                }
                scratch
            } else {
                return 0.0;
            };
        let half = 0.5 * h;
        // Signed distance to the union's edge, clipped to [-half, half].
        let mut sd = half;
        for d in list {
            let dx = x[0] - d.c[0];
            let dy = x[1] - d.c[1];
            let q = dx * dx + dy * dy;
            let inner = d.r - half;
            if inner > 0.0 && q <= inner * inner {
                return 1.0;
            }
            let outer = d.r + half;
            if q < outer * outer {
                sd = sd.min(q.sqrt() - d.r);
            }
        }
        (0.5 - sd / h).clamp(0.0, 1.0)
    }
}

/// Integrates rows `first_row..` of the padded grid (row length pw, first pixel centre at
/// (origin, origin)) into `out`.
fn integrate_rows(
    pattern: &Pattern,
    to_reference: &(dyn Fn([f64; 2]) -> [f64; 2] + Sync),
    pw: usize,
    origin: f64,
    first_row: usize,
    out: &mut [f64],
) {
    let step = 1.0 / SUBSAMPLES as f64;
    let norm = step * step;
    let mut scratch = Vec::new();
    for (r, row) in out.chunks_mut(pw).enumerate() {
        let y = origin + (first_row + r) as f64;
        for (c, out) in row.iter_mut().enumerate() {
            let x = origin + c as f64;
            // The pixel's footprint in the reference frame: centre, corners, and from them the
            // sub-square size h and the footprint radius (10 % slack for curved maps).
            let o = to_reference([x, y]);
            let a = to_reference([x - 0.5, y - 0.5]);
            let b = to_reference([x + 0.5, y - 0.5]);
            let d = to_reference([x - 0.5, y + 0.5]);
            let e = to_reference([x + 0.5, y + 0.5]);
            let det = ((b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0])).abs();
            let h = (det.sqrt() * step).clamp(1e-9, 2.0 * RAMP_MARGIN);
            let radius = 1.1
                * [a, b, d, e]
                    .iter()
                    .map(|p| (p[0] - o[0]).hypot(p[1] - o[1]))
                    .fold(0.0, f64::max);
            let mut square = Square {
                pattern,
                to_reference,
                h,
                radius,
                scratch: &mut scratch,
            };
            *out = square.sum([x, y], o, 1.0) * norm;
        }
    }
}

/// The area integration of one pixel, by quadrants: a square of side `side` (px) whose
/// footprint has no disc edge within reach is uniform, so its sub-squares need not be
/// evaluated; the result is the same as evaluating all SUBSAMPLES² of them.
struct Square<'a> {
    pattern: &'a Pattern,
    to_reference: &'a (dyn Fn([f64; 2]) -> [f64; 2] + Sync),
    /// Sub-square size in the reference frame.
    h: f64,
    /// Footprint radius of the whole pixel in the reference frame.
    radius: f64,
    scratch: &'a mut Vec<Disc>,
}

impl Square<'_> {
    /// Sum of the painted fractions of the sub-squares of the square of side `side` centred
    /// at `x` (deformed frame), whose centre maps to `o`.
    fn sum(&mut self, x: [f64; 2], o: [f64; 2], side: f64) -> f64 {
        let count = side * side * (SUBSAMPLES * SUBSAMPLES) as f64;
        if count <= 1.0 {
            return self.pattern.coverage(o, self.h, self.scratch);
        }
        if let Some(v) = self.pattern.uniform(o, self.radius * side + 0.5 * self.h) {
            return v * count;
        }
        let q = 0.25 * side;
        let mut total = 0.0;
        for (dx, dy) in [(-q, -q), (q, -q), (-q, q), (q, q)] {
            let c = [x[0] + dx, x[1] + dy];
            total += self.sum(c, (self.to_reference)(c), 0.5 * side);
        }
        total
    }
}

/// Normalised sampled Gaussian of sigma `sigma`, 2 radius + 1 taps.
fn gaussian_kernel(sigma: f64, radius: usize) -> Vec<f64> {
    let k: Vec<f64> = (0..=2 * radius)
        .map(|i| {
            let d = i as f64 - radius as f64;
            (-0.5 * d * d / (sigma * sigma)).exp()
        })
        .collect();
    let s: f64 = k.iter().sum();
    k.into_iter().map(|v| v / s).collect()
}

// ---------------------------------------------------------------------------------------
// Sensor and PRNG.

struct Sensor {
    background: f64,
    contrast: f64,
    read2: f64,
    shot: f64,
    full: f64,
}

impl Sensor {
    fn new(p: &IndependentSpeckle) -> Self {
        Sensor {
            background: p.background,
            contrast: p.dot - p.background,
            read2: p.read_noise * p.read_noise,
            shot: p.shot_noise.max(0.0),
            full: p.full_scale(),
        }
    }

    fn expose(&self, painted: f64, noise_seed: u64, index: u64) -> u16 {
        let mut g = self.background + self.contrast * painted;
        let var = self.read2 + self.shot * g.max(0.0);
        if var > 0.0 {
            let mut rng = SplitMix(mix(
                noise_seed ^ mix(index.wrapping_add(0x5851_F42D_4C95_7F2D))
            ));
            g += var.sqrt() * rng.normal();
        }
        (g * self.full).round().clamp(0.0, self.full) as u16
    }
}

fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// splitmix64.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix(self.0)
    }

    /// Uniform in (0, 1).
    fn uniform(&mut self) -> f64 {
        ((self.next() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal (Box-Muller).
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// `pixels` plus white Gaussian noise of standard deviation `sigma_counts`, rounded and clipped
/// to `0..=full_scale`: the noise of this generator, for images it did not render.
pub fn with_white_noise(pixels: &[u16], sigma_counts: f64, full_scale: u16, seed: u64) -> Vec<u16> {
    pixels
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let mut rng = SplitMix(mix(seed ^ mix(i as u64)));
            let g = p as f64 + sigma_counts * rng.normal();
            g.round().clamp(0.0, full_scale as f64) as u16
        })
        .collect()
}
