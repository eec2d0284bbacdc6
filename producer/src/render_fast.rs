//! The `fast` renderer: the pattern is rendered once into an oversampled texture of the
//! reference plane, already integrated over a 1 px x 1 px pixel footprint (Simpson's rule over
//! the texels), then each camera pixel samples it at φ⁻¹(x) with Catmull-Rom bicubic
//! interpolation. The footprint is the undeformed pixel: the error this makes under strain is
//! even (a slight blur difference), not a displacement bias.

use crate::field_motion::{CellRows, FieldMotion, BACKDROP, BLOCK_SPAN_PX};
use crate::motion::{inverse, mul_vec, Affine, Motion};
use crate::parallel::for_row_bands;
use crate::row_inverse::RowInverse;
use crate::speckle::{Speckle, Spot};
use std::ops::Range;

/// Margin of texels kept around the covered area for the filter and the interpolant, px.
const PAD_PX: f64 = 2.0;

/// The oversampled, pixel-integrated texture of a pattern.
#[derive(Debug)]
pub struct FastRenderer {
    /// Texels per px along each axis (even, 2..=8).
    oversample: usize,
    /// Reference coordinates of texel (0, 0), px.
    origin_px: [f64; 2],
    texels_x: usize,
    texture: Vec<f32>,
    /// Texel coordinates from which a 4 x 4 patch would leave the texture: texels - 2.
    end_texel: [f64; 2],
    /// Value outside the texture (the bare background, pixel-integrated).
    background: f32,
    /// Threads used by `render`.
    pub threads: usize,
}

/// The texels of a texture: `oversample` per px along each axis, texel (0, 0) at `origin_px`
/// (reference px), `texels_x` x `texels_y` of them, row-major.
#[derive(Clone, Copy, Debug)]
struct TexelGrid {
    oversample: usize,
    origin_px: [f64; 2],
    texels_x: usize,
    texels_y: usize,
}

impl TexelGrid {
    /// The grid over `[x0, x1] x [y0, y1]` (reference px) with a margin of [`PAD_PX`].
    fn covering(x_range_px: [f64; 2], y_range_px: [f64; 2], oversample: usize) -> TexelGrid {
        let origin_px = [x_range_px[0] - PAD_PX, y_range_px[0] - PAD_PX];
        let texels = |range: [f64; 2]| {
            ((range[1] - range[0] + 2.0 * PAD_PX) * oversample as f64).ceil() as usize + 1
        };
        let (texels_x, texels_y) = (texels(x_range_px), texels(y_range_px));
        assert!(
            texels_x.checked_mul(texels_y).is_some_and(|n| n < 1 << 30),
            "texture of {texels_x} x {texels_y} texels is too large"
        );
        TexelGrid {
            oversample,
            origin_px,
            texels_x,
            texels_y,
        }
    }

    /// Texel size, px.
    fn h(&self) -> f64 {
        1.0 / self.oversample as f64
    }

    /// The spots of `speckle` summed into `band` (the texel rows from `first_row`), then the
    /// pattern's value of each sum.
    fn splat(&self, speckle: &Speckle, first_row: usize, band: &mut [f32]) {
        let (h, origin_px, texels_x) = (self.h(), self.origin_px, self.texels_x);
        let rows = first_row..first_row + band.len() / texels_x;
        let mut gx = Vec::with_capacity(64 * self.oversample);
        let mut dx2 = Vec::with_capacity(64 * self.oversample);
        for spot in speckle.spots() {
            let Some((xs, ys)) = self.spot_texels(spot, &rows) else {
                continue;
            };
            gx.clear();
            dx2.clear();
            for ix in xs.clone() {
                let d = origin_px[0] + ix as f64 * h - spot.centre_px[0];
                dx2.push(d * d);
                gx.push(spot.amplitude * (-d * d * spot.inv_two_sigma2).exp());
            }
            for iy in ys {
                let d = origin_px[1] + iy as f64 * h - spot.centre_px[1];
                let gy = (-d * d * spot.inv_two_sigma2).exp();
                // The texels within the cutoff form one run of the row (dx² is monotone on
                // each side of the centre): found from both ends, then summed without a test.
                let d2 = d * d;
                let within = |k: &usize| dx2[*k] + d2 < spot.cutoff2_px2;
                let Some(first) = (0..dx2.len()).find(within) else {
                    continue;
                };
                let end = (first..dx2.len())
                    .rev()
                    .find(within)
                    .map_or(first, |k| k + 1);
                let row = &mut band[(iy - rows.start) * texels_x..][..texels_x][xs.clone()];
                for (texel, &g) in row[first..end].iter_mut().zip(&gx[first..end]) {
                    *texel += (g * gy) as f32;
                }
            }
        }
        for s in band.iter_mut() {
            *s = speckle.value_from_sum(f64::from(*s)) as f32;
        }
    }

    /// The texel columns and the rows among `rows` within `spot`'s cutoff radius; None when
    /// there are none.
    fn spot_texels(
        &self,
        spot: &Spot,
        rows: &Range<usize>,
    ) -> Option<(Range<usize>, Range<usize>)> {
        let (h, origin_px) = (self.h(), self.origin_px);
        let r = spot.cutoff2_px2.sqrt();
        let ix0 = ((spot.centre_px[0] - r - origin_px[0]) / h).ceil().max(0.0) as usize;
        let ix1 = (((spot.centre_px[0] + r - origin_px[0]) / h)
            .floor()
            .max(-1.0)
            + 1.0) as usize;
        let ix1 = ix1.min(self.texels_x);
        let iy0 = ((spot.centre_px[1] - r - origin_px[1]) / h)
            .ceil()
            .max(rows.start as f64) as usize;
        let iy1 = (((spot.centre_px[1] + r - origin_px[1]) / h)
            .floor()
            .max(-1.0)
            + 1.0) as usize;
        let iy1 = iy1.min(rows.end);
        (ix0 < ix1 && iy0 < iy1).then_some((ix0..ix1, iy0..iy1))
    }

    /// The horizontal pass of the pixel-area integration (Simpson `weights`), in place.
    fn integrate_rows(&self, texture: &mut [f32], weights: &[f64], threads: usize) {
        let (texels_x, half) = (self.texels_x, self.oversample / 2);
        for_row_bands(texture, texels_x, threads, |_, band| {
            let mut scratch = vec![0f32; texels_x];
            for row in band.chunks_exact_mut(texels_x) {
                scratch.copy_from_slice(row);
                let inner = &mut row[half..texels_x - half];
                for (out, window) in inner.iter_mut().zip(scratch.windows(weights.len())) {
                    let mut sum = 0.0f64;
                    for (w, s) in weights.iter().zip(window) {
                        sum += w * f64::from(*s);
                    }
                    *out = sum as f32;
                }
            }
        });
    }

    /// The vertical pass, in place, with a ring of the last `oversample + 1` original rows.
    fn integrate_columns(&self, texture: &mut [f32], weights: &[f64]) {
        let (texels_x, oversample, half) = (self.texels_x, self.oversample, self.oversample / 2);
        let ring_rows = oversample + 1;
        let mut ring = vec![0f32; ring_rows * texels_x];
        for iy in 0..self.texels_y {
            let slot = iy % ring_rows;
            ring[slot * texels_x..][..texels_x]
                .copy_from_slice(&texture[iy * texels_x..][..texels_x]);
            if iy >= oversample {
                let out_row = iy - half;
                let row = &mut texture[out_row * texels_x..][..texels_x];
                row.fill(0.0);
                for (k, w) in weights.iter().enumerate() {
                    let src = &ring[((out_row + k - half) % ring_rows) * texels_x..][..texels_x];
                    for (o, s) in row.iter_mut().zip(src) {
                        *o += (*w as f32) * s;
                    }
                }
            }
        }
    }
}

impl FastRenderer {
    /// Renders the texture of `speckle` over `[x0, x1] x [y0, y1]` (reference px) at
    /// `oversample` texels per px (even, 2..=8; 4 is the default). Done once, at start.
    pub fn new(
        speckle: &Speckle,
        x_range_px: [f64; 2],
        y_range_px: [f64; 2],
        oversample: usize,
        threads: usize,
    ) -> Self {
        assert!(
            (2..=8).contains(&oversample) && oversample.is_multiple_of(2),
            "oversample {oversample} must be even in 2..=8"
        );
        let grid = TexelGrid::covering(x_range_px, y_range_px, oversample);
        let mut texture = vec![0f32; grid.texels_x * grid.texels_y];
        // 1. Spot sums by separable splatting, parallel over bands of texel rows.
        for_row_bands(&mut texture, grid.texels_x, threads, |first_row, band| {
            grid.splat(speckle, first_row, band)
        });
        // 2. Pixel-area integration: Simpson over ±0.5 px (oversample intervals) per axis.
        let weights = simpson_weights(oversample);
        grid.integrate_rows(&mut texture, &weights, threads);
        grid.integrate_columns(&mut texture, &weights);
        let background = speckle.value_from_sum(0.0) as f32;
        FastRenderer {
            oversample,
            origin_px: grid.origin_px,
            texels_x: grid.texels_x,
            texture,
            end_texel: [(grid.texels_x - 2) as f64, (grid.texels_y - 2) as f64],
            background,
            threads,
        }
    }

    /// Texels per px.
    pub fn oversample(&self) -> usize {
        self.oversample
    }

    /// Texture size in bytes.
    pub fn texture_bytes(&self) -> usize {
        self.texture.len() * std::mem::size_of::<f32>()
    }

    /// The pixel-integrated pattern at reference point X, Catmull-Rom interpolated.
    #[inline]
    pub fn sample(&self, p: [f64; 2]) -> f32 {
        let os = self.oversample as f64;
        self.sample_texels(
            (p[0] - self.origin_px[0]) * os,
            (p[1] - self.origin_px[1]) * os,
        )
    }

    /// The pattern at texel coordinates (`fx`, `fy`), Catmull-Rom interpolated; the background
    /// where the 4 x 4 texels would leave the texture.
    #[inline(always)]
    fn sample_texels(&self, fx: f64, fy: f64) -> f32 {
        // The texture edge is at least PAD_PX * oversample texels beyond the filtered area.
        // Truncation is the floor here: a point left of texel 1 is outside either way.
        if !(fx >= 1.0 && fy >= 1.0 && fx < self.end_texel[0] && fy < self.end_texel[1]) {
            return self.background;
        }
        // Signed conversions: one instruction each on x86-64 (unsigned ones take five).
        let (ix, iy) = (fx as i64, fy as i64);
        let wx = catmull_rom((fx - ix as f64) as f32);
        let wy = catmull_rom((fy - iy as f64) as f32);
        let tx = self.texels_x;
        let first = (iy as usize - 1) * tx + ix as usize - 1;
        let patch = &self.texture[first..first + 3 * tx + 4];
        // Vertical pass on the four columns at once (4-wide SIMD), then the horizontal one.
        let row =
            |j: usize| -> &[f32; 4] { patch[j * tx..j * tx + 4].try_into().expect("four texels") };
        let mut columns = scaled(wy[0], row(0));
        for (j, &wyj) in wy.iter().enumerate().skip(1) {
            columns = add_scaled(columns, wyj, row(j));
        }
        wx[0] * columns[0] + wx[1] * columns[1] + wx[2] * columns[2] + wx[3] * columns[3]
    }

    /// Renders p over the `width` x rows camera frame `out` under `motion` (values in [0, 1]).
    pub fn render(&self, motion: &Motion, width: usize, out: &mut [f32]) {
        for_row_bands(out, width, self.threads, |first_row, band| {
            for (r, row) in band.chunks_exact_mut(width).enumerate() {
                self.render_row(motion, first_row + r, row);
            }
        });
    }

    /// Renders p over the `width` x rows camera frame `out` under a finite-element field,
    /// [`BACKDROP`] where the camera sees no material. See [`Self::render_field_row`].
    pub fn render_field(&self, field: &FieldMotion, width: usize, out: &mut [f32]) {
        for_row_bands(out, width, self.threads, |first_row, band| {
            let mut cells = CellRows::new(width);
            for (r, row) in band.chunks_exact_mut(width).enumerate() {
                self.render_field_row(field, &mut cells, first_row + r, row);
            }
        });
    }

    /// Row `y` under a finite-element field, block by block ([`CellRows`]: exact points on
    /// every eighth row at the ends of each block, interpolated between them inside one
    /// element); `cells` is the walk of the rows before (rows in increasing order are cheapest).
    pub fn render_field_row(
        &self,
        field: &FieldMotion,
        cells: &mut CellRows,
        y: usize,
        row: &mut [f32],
    ) {
        let os = self.oversample as f64;
        let width = row.len();
        cells.walk_row(field, y, |first_col, points| {
            let block = &mut row[first_col..(first_col + BLOCK_PX).min(width)];
            let (mut fx, mut fy) = ([f64::NAN; BLOCK_PX], [f64::NAN; BLOCK_PX]);
            for (k, p) in points.iter().enumerate() {
                if let Some(p) = p {
                    fx[k] = (p[0] - self.origin_px[0]) * os;
                    fy[k] = (p[1] - self.origin_px[1]) * os;
                }
            }
            self.sample_positions(&fx, &fy, block);
            for (value, p) in block.iter_mut().zip(points) {
                if p.is_none() {
                    *value = BACKDROP;
                }
            }
        });
    }

    /// Renders row `y` (pixel row index) of the frame into `row` (values in [0, 1]).
    pub fn render_row(&self, motion: &Motion, y: usize, row: &mut [f32]) {
        let y = y as f64;
        match motion {
            Motion::Affine(a) => self.render_affine_row(a, y, row),
            other => {
                let mut inverse = RowInverse::new(other, y);
                for (col, value) in row.iter_mut().enumerate() {
                    *value = self.sample(inverse.next(col as f64));
                }
            }
        }
    }

    /// Row `y` of an affine motion: X = c + F⁻¹ (x - c - t) is affine in the column, so the
    /// texel coordinates of column k are start + k step, each computed from the row's start (no
    /// accumulated round-off).
    fn render_affine_row(&self, a: &Affine, y: f64, row: &mut [f32]) {
        let inv = inverse(&a.f);
        let os = self.oversample as f64;
        let step = mul_vec(&inv, [os, 0.0]);
        let d = mul_vec(
            &inv,
            [
                -a.centre_px[0] - a.translation_px[0],
                y - a.centre_px[1] - a.translation_px[1],
            ],
        );
        let start = [
            (a.centre_px[0] + d[0] - self.origin_px[0]) * os,
            (a.centre_px[1] + d[1] - self.origin_px[1]) * os,
        ];
        for (b, block) in row.chunks_mut(BLOCK_PX).enumerate() {
            let first_col = (b * BLOCK_PX) as f64;
            let (mut fx, mut fy) = ([0.0f64; BLOCK_PX], [0.0f64; BLOCK_PX]);
            for k in 0..BLOCK_PX {
                let col = first_col + k as f64;
                fx[k] = start[0] + col * step[0];
                fy[k] = start[1] + col * step[1];
            }
            self.sample_positions(&fx, &fy, block);
        }
    }

    /// The pattern at the texel coordinates of a block (up to [`BLOCK_PX`] pixels): lane by
    /// lane when all of them lie inside the texture, else one by one (the background outside).
    #[inline(always)]
    fn sample_positions(&self, fx: &[f64; BLOCK_PX], fy: &[f64; BLOCK_PX], block: &mut [f32]) {
        let inside = |k: usize| {
            fx[k] >= 1.0 && fy[k] >= 1.0 && fx[k] < self.end_texel[0] && fy[k] < self.end_texel[1]
        };
        if block.len() == BLOCK_PX && (0..BLOCK_PX).all(inside) {
            self.sample_block(fx, fy, block);
        } else {
            for (k, value) in block.iter_mut().enumerate() {
                *value = self.sample_texels(fx[k], fy[k]);
            }
        }
    }

    /// [`Self::sample_texels`] of a block of points all inside the texture, lane by lane
    /// (weights computed 4 or 8 wide; each point's vertical pass on its patch's four columns
    /// at once, 4-wide, as `sample_texels`; then the horizontal passes of the whole block, 4 or
    /// 8 wide).
    #[inline(always)]
    fn sample_block(&self, fx: &[f64; BLOCK_PX], fy: &[f64; BLOCK_PX], out: &mut [f32]) {
        let (mut ix, mut iy) = ([0i32; BLOCK_PX], [0i32; BLOCK_PX]);
        let (mut tx, mut ty) = ([0.0f32; BLOCK_PX], [0.0f32; BLOCK_PX]);
        for k in 0..BLOCK_PX {
            ix[k] = fx[k] as i32;
            iy[k] = fy[k] as i32;
            tx[k] = (fx[k] - f64::from(ix[k])) as f32;
            ty[k] = (fy[k] - f64::from(iy[k])) as f32;
        }
        let wx = catmull_rom_lanes(&tx);
        let wy = catmull_rom_lanes(&ty);
        let stride = self.texels_x;
        // columns[i][k]: column i of point k's patch, weighted down the rows.
        let mut columns = [[0.0f32; BLOCK_PX]; 4];
        for k in 0..BLOCK_PX {
            let first = (iy[k] as usize - 1) * stride + ix[k] as usize - 1;
            let patch = &self.texture[first..first + 3 * stride + 4];
            let row = |j: usize| -> &[f32; 4] {
                patch[j * stride..j * stride + 4]
                    .try_into()
                    .expect("four texels")
            };
            let mut column = scaled(wy[0][k], row(0));
            for (j, wyj) in wy.iter().enumerate().skip(1) {
                column = add_scaled(column, wyj[k], row(j));
            }
            for (i, c) in column.iter().enumerate() {
                columns[i][k] = *c;
            }
        }
        for (k, value) in out.iter_mut().enumerate() {
            *value = wx[0][k] * columns[0][k]
                + wx[1][k] * columns[1][k]
                + wx[2][k] * columns[2][k]
                + wx[3][k] * columns[3][k];
        }
    }
}

/// Pixels per block of the row loops (the finite-element path's span between exact points).
const BLOCK_PX: usize = BLOCK_SPAN_PX;

/// The Catmull-Rom weights of a block of `t`: `w[k][lane]` (Horner, lane by lane).
#[inline(always)]
fn catmull_rom_lanes(t: &[f32; BLOCK_PX]) -> [[f32; BLOCK_PX]; 4] {
    let [a, b, c, d] = CATMULL_ROM;
    let mut w = [[0.0f32; BLOCK_PX]; 4];
    for (k, wk) in w.iter_mut().enumerate() {
        for (lane, &t) in wk.iter_mut().zip(t) {
            *lane = ((a[k] * t + b[k]) * t + c[k]) * t + d[k];
        }
    }
    w
}

/// Composite Simpson weights over `n` (even) intervals spanning 1 px, summing to 1.
fn simpson_weights(n: usize) -> Vec<f64> {
    assert!(n >= 2 && n.is_multiple_of(2));
    (0..=n)
        .map(|k| {
            let m = if k == 0 || k == n {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            m / (3.0 * n as f64)
        })
        .collect()
}

/// w r, lane by lane.
#[inline(always)]
fn scaled(w: f32, r: &[f32; 4]) -> [f32; 4] {
    [w * r[0], w * r[1], w * r[2], w * r[3]]
}

/// acc + w r, lane by lane.
#[inline(always)]
fn add_scaled(acc: [f32; 4], w: f32, r: &[f32; 4]) -> [f32; 4] {
    [
        acc[0] + w * r[0],
        acc[1] + w * r[1],
        acc[2] + w * r[2],
        acc[3] + w * r[3],
    ]
}

/// Catmull-Rom weights w_k(t) = ((a_k t + b_k) t + c_k) t + d_k of the texels at -1, 0, 1, 2:
/// rows a, b, c, d.
const CATMULL_ROM: [[f32; 4]; 4] = [
    [-0.5, 1.5, -1.5, 0.5],
    [1.0, -2.5, 2.0, -0.5],
    [-0.5, 0.0, 0.5, 0.0],
    [0.0, 1.0, 0.0, 0.0],
];

/// The four Catmull-Rom weights at `t` in [0, 1) (Horner, 4-wide).
#[inline(always)]
fn catmull_rom(t: f32) -> [f32; 4] {
    let [a, b, c, d] = CATMULL_ROM;
    std::array::from_fn(|k| ((a[k] * t + b[k]) * t + c[k]) * t + d[k])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::{mul_mat, rotation};
    use crate::speckle::SpeckleParams;

    /// The row-incremental affine path samples where the per-pixel analytic inverse φ⁻¹ lands:
    /// same values to f32 round-off (a position difference of 1e-9 px changes a value by far
    /// less than 1e-6 of the range).
    #[test]
    fn affine_rows_sample_at_the_analytic_inverse() {
        let (w, h) = (96usize, 64usize);
        let x_range = [-40.0, w as f64 + 40.0];
        let y_range = [-40.0, h as f64 + 40.0];
        let speckle = Speckle::new(SpeckleParams::default(), x_range, y_range);
        let fast = FastRenderer::new(&speckle, x_range, y_range, 4, 1);
        let motion = Motion::Affine(Affine {
            f: mul_mat(&rotation(0.3), &[[1.7, 0.05], [-0.02, 0.8]]),
            translation_px: [3.25, -1.5],
            centre_px: [47.5, 31.5],
        });
        let mut rows = vec![0f32; w * h];
        fast.render(&motion, w, &mut rows);
        for y in 0..h {
            for x in 0..w {
                let expected = fast.sample(motion.inverse([x as f64, y as f64]));
                let got = rows[y * w + x];
                assert!(
                    (got - expected).abs() < 1e-6,
                    "({x}, {y}): {got} vs {expected}"
                );
            }
        }
    }
}
