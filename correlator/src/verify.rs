//! The final check of a node, independent of how its match was found: the zero-normalised
//! cross-correlation (ZNCC) of the reference ZOI with the deformed image sampled where the
//! node's displacement u and local gradient G send it, x → x + u + G (x − c) (c the ZOI
//! centre, bilinear interpolation). A match on the node's own material scores close to 1 (the
//! noise and the interpolation take a little off); a match on other material scores what two
//! unrelated speckle patches score, |ZNCC| < 0.4. The check samples the ZOI every ⌈n / 12⌉
//! px (3 px for a 32 px ZOI: 11 x 11 samples): about 120 samples decide that difference with
//! a wide margin, at a small fraction of the correlation's cost (a 16 x 16 grid cost 13 % of
//! the steady-state frame time).

use crate::interpolate::{apply, identity_plus, Mat2};
use crate::zoi::Image;

/// At most this many samples per side of the check grid.
pub const CHECK_SIDE: usize = 12;
/// The check uses the samples that fall inside the deformed image (the ZOI correlation
/// accepts a ZOI a pixel past the border); with fewer than this fraction inside the node is
/// outside the image.
const MIN_INSIDE_FRACTION: f64 = 0.75;

/// ZNCC in [−1, 1] of the n x n reference block with top-left `top_left` against the
/// deformed image sampled at x + u + G (x − c), over the samples inside the deformed image.
/// None when fewer than [`MIN_INSIDE_FRACTION`] of them are inside; 0 when either side is flat.
pub fn zncc(
    reference: Image,
    top_left: (usize, usize),
    n: usize,
    deformed: Image,
    u: (f64, f64),
    g: Mat2,
) -> Option<f64> {
    let half = (n as f64 - 1.0) / 2.0;
    let centre = (top_left.0 as f64 + half, top_left.1 as f64 + half);
    let a = identity_plus(g);
    if !(u.0.is_finite() && u.1.is_finite() && a.iter().flatten().all(|v| v.is_finite())) {
        return None;
    }
    let stride = n.div_ceil(CHECK_SIDE);
    let first = stride / 2;
    // Sums of (value − offset) in f32 per row (the offset keeps 16-bit squares exact enough),
    // rows added in f64.
    let offset =
        reference.pixels[(top_left.1 + first) * reference.width_px + top_left.0 + first] as f32;
    let grid = Grid {
        top_left,
        n,
        first,
        stride,
        start: (centre.0 + u.0, centre.1 + u.1),
        a,
        offset,
    };
    let (sums, count) = if grid.well_inside(deformed) {
        grid.sums_inside(reference, deformed)
    } else {
        grid.sums_clipped(reference, deformed)
    };
    let [sf, sg, sff, sgg, sfg] = sums;
    let count = count as f64;
    // Samples per side: first, first + stride, ... below n (any n, not only 2^s).
    let side = (n - first).div_ceil(stride);
    if count < MIN_INSIDE_FRACTION * (side * side) as f64 {
        return None;
    }
    let cov = sfg - sf * sg / count;
    let var_f = sff - sf * sf / count;
    let var_g = sgg - sg * sg / count;
    let denominator = (var_f * var_g).sqrt();
    Some(if denominator > 0.0 && denominator.is_finite() {
        (cov / denominator).clamp(-1.0, 1.0)
    } else {
        0.0
    })
}

/// The check's sample grid: reference pixels `first, first + stride, ...` below n on both axes
/// of the n x n block at `top_left`, each sent to `start + a (x − half)` in the deformed image
/// (`start` = centre + u), values less `offset`.
struct Grid {
    top_left: (usize, usize),
    n: usize,
    first: usize,
    stride: usize,
    start: (f64, f64),
    a: Mat2,
    offset: f32,
}

/// How far inside the image (px) every sample of a grid takes [`Grid::sums_inside`]: well
/// above the rounding of the positions' running sums.
const INSIDE_MARGIN_PX: f64 = 0.5;

impl Grid {
    /// The deformed position of the grid's first sample of row `y` and the step along the row.
    fn row_start(&self, y: usize) -> ((f64, f64), (f64, f64)) {
        let half = (self.n as f64 - 1.0) / 2.0;
        let d = apply(self.a, (self.first as f64 - half, y as f64 - half));
        let step = (
            self.a[0][0] * self.stride as f64,
            self.a[1][0] * self.stride as f64,
        );
        ((self.start.0 + d.0, self.start.1 + d.1), step)
    }

    /// Whether every sample lies at least [`INSIDE_MARGIN_PX`] inside [0, w − 2] x [0, h − 2]
    /// (the bilinear 2 x 2 then needs no clamp) of an image whose positions fit in i32: the map
    /// is affine, so its four corners decide.
    fn well_inside(&self, deformed: Image) -> bool {
        let last = self.first + (self.n - 1 - self.first) / self.stride * self.stride;
        let (max_x, max_y) = (
            deformed.width_px as f64 - 2.0 - INSIDE_MARGIN_PX,
            deformed.height_px as f64 - 2.0 - INSIDE_MARGIN_PX,
        );
        let columns = (last - self.first) as f64;
        let small = deformed.width_px.max(deformed.height_px) < i32::MAX as usize;
        small
            && [self.first, last].into_iter().all(|y| {
                let ((x0, y0), step) = self.row_start(y);
                let along = columns / self.stride as f64;
                [(x0, y0), (x0 + along * step.0, y0 + along * step.1)]
                    .into_iter()
                    .all(|(x, y)| {
                        x >= INSIDE_MARGIN_PX && y >= INSIDE_MARGIN_PX && x <= max_x && y <= max_y
                    })
            })
    }

    /// The sums Σ f, Σ g, Σ f², Σ g², Σ f g (f32 per row, f64 over rows) and the sample count
    /// of a grid [`Self::well_inside`] the deformed image: no sample is tested or clamped
    /// (the same values as [`Self::sums_clipped`] gives there, bit for bit).
    fn sums_inside(&self, reference: Image, deformed: Image) -> ([f64; 5], usize) {
        self.sums::<false>(reference, deformed)
    }

    /// [`Self::sums_inside`] over the samples inside [0, w − 1] x [0, h − 1] only, the 2 x 2
    /// clamped into the image at its last row and column.
    fn sums_clipped(&self, reference: Image, deformed: Image) -> ([f64; 5], usize) {
        self.sums::<true>(reference, deformed)
    }

    /// The sums of both: `CLIPPED` tests and clamps every sample.
    #[inline(always)]
    fn sums<const CLIPPED: bool>(&self, reference: Image, deformed: Image) -> ([f64; 5], usize) {
        let (w, h, p) = (deformed.width_px, deformed.height_px, deformed.pixels);
        let (max_x, max_y) = (w as f64 - 1.0, h as f64 - 1.0);
        let mut total = [0.0f64; 5];
        let mut count = 0;
        for y in (self.first..self.n).step_by(self.stride) {
            let row = (self.top_left.1 + y) * reference.width_px + self.top_left.0;
            let f_row = &reference.pixels[row..row + self.n];
            let ((mut px, mut py), step) = self.row_start(y);
            let mut sums = [0.0f32; 5];
            for &f in f_row[self.first..].iter().step_by(self.stride) {
                let (x, y) = (px, py);
                px += step.0;
                py += step.1;
                if CLIPPED && !(x >= 0.0 && y >= 0.0 && x <= max_x && y <= max_y) {
                    continue;
                }
                // Inside, positive positions well inside: truncation to i32 is the floor (and
                // cheaper than a conversion to usize, which saturates).
                let (ix, iy) = if CLIPPED {
                    ((x as usize).min(w - 2), (y as usize).min(h - 2))
                } else {
                    (x as i32 as usize, y as i32 as usize)
                };
                let (fx, fy) = ((x - ix as f64) as f32, (y - iy as f64) as f32);
                let at = iy * w + ix;
                let block = &p[at..at + w + 2];
                let (t0, t1) = (block[0] as f32, block[1] as f32);
                let (b0, b1) = (block[w] as f32, block[w + 1] as f32);
                let top = t0 + fx * (t1 - t0);
                let bottom = b0 + fx * (b1 - b0);
                let g = top + fy * (bottom - top) - self.offset;
                let f = f as f32 - self.offset;
                sums[0] += f;
                sums[1] += g;
                sums[2] += f * f;
                sums[3] += g * g;
                sums[4] += f * g;
                count += 1;
            }
            for (t, s) in total.iter_mut().zip(sums) {
                *t += s as f64;
            }
        }
        (total, count)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A smooth analytic texture with speckle-like detail (also IC-GN's test image).
    pub(crate) fn texture(x: f64, y: f64) -> f64 {
        20000.0
            + 8000.0 * (0.9 * x + 0.3 * y).sin() * (0.5 * y - 0.2 * x).cos()
            + 5000.0 * (0.37 * x * x / 40.0 + 0.61 * y).sin()
    }

    /// A square image of side `size` over `pixels`.
    fn square(pixels: &[u16], size: usize) -> Image<'_> {
        Image {
            pixels,
            width_px: size,
            height_px: size,
        }
    }

    fn image(size: usize, map: impl Fn(f64, f64) -> (f64, f64)) -> Vec<u16> {
        (0..size * size)
            .map(|i| {
                let (x, y) = map((i % size) as f64, (i / size) as f64);
                texture(x, y) as u16
            })
            .collect()
    }

    #[test]
    fn the_right_displacement_and_gradient_score_high_and_a_wrong_one_low() {
        let size = 96;
        let reference = image(size, |x, y| (x, y));
        // Deformed: material point X shows at x = X + (3.4, −2.2) + G X with G a 4 % stretch
        // and a small rotation, i.e. X = (I + G)⁻¹ (x − t).
        let g = [[0.04, -0.02], [0.02, 0.0]];
        let a = identity_plus(g);
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        let deformed = image(size, |x, y| {
            let (dx, dy) = (x - 3.4, y + 2.2);
            (
                (a[1][1] * dx - a[0][1] * dy) / det,
                (-a[1][0] * dx + a[0][0] * dy) / det,
            )
        });
        let (r, d) = (square(&reference, size), square(&deformed, size));
        let top_left = (30, 34);
        let c = (30.0 + 15.5, 34.0 + 15.5);
        let u = (
            3.4 + g[0][0] * c.0 + g[0][1] * c.1,
            -2.2 + g[1][0] * c.0 + g[1][1] * c.1,
        );
        let right = zncc(r, top_left, 32, d, u, g).unwrap();
        assert!(right > 0.99, "{right}");
        let rigid = zncc(r, top_left, 32, d, u, [[0.0; 2]; 2]).unwrap();
        assert!(rigid < right, "{rigid} vs {right}");
        let wrong = zncc(r, top_left, 32, d, (u.0 + 7.0, u.1 - 5.0), g).unwrap();
        assert!(wrong < 0.5, "{wrong}");
        assert_eq!(zncc(r, top_left, 32, d, (60.0, 0.0), g), None);
        assert_eq!(zncc(r, top_left, 32, d, (f64::NAN, 0.0), g), None);
    }

    /// Inside the image, the unclamped sums are the clamped ones bit for bit; at the border
    /// the grid is not well inside and the clamped path decides.
    #[test]
    fn the_inside_sums_are_the_clipped_ones() {
        let size = 80;
        let reference = image(size, |x, y| (x, y));
        let deformed = image(size, |x, y| (1.1 * x + 0.3, 0.95 * y - 0.2 * x));
        let (r, d) = (square(&reference, size), square(&deformed, size));
        let mut compared = 0;
        for case in 0..40 {
            let s = case as f64;
            let n = [32usize, 33, 24, 12][case % 4];
            let stride = n.div_ceil(CHECK_SIDE);
            let grid = Grid {
                top_left: (10 + case % 7, 12 + case % 5),
                n,
                first: stride / 2,
                stride,
                start: (30.0 + 1.37 * s - 20.0, 28.0 - 0.91 * s + 10.0),
                a: identity_plus([[0.01 * (s - 20.0), -0.004 * s], [0.003 * s, 0.02]]),
                offset: 1000.0,
            };
            if !grid.well_inside(d) {
                continue;
            }
            assert_eq!(
                grid.sums_inside(r, d),
                grid.sums_clipped(r, d),
                "case {case}"
            );
            compared += 1;
        }
        assert!(compared > 20, "{compared}");
        let border = Grid {
            top_left: (0, 0),
            n: 32,
            first: 1,
            stride: 3,
            start: (15.5 - 16.0, 15.5),
            a: identity_plus([[0.0; 2]; 2]),
            offset: 0.0,
        };
        assert!(!border.well_inside(d));
    }
}
