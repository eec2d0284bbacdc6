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
    let (max_x, max_y) = (
        deformed.width_px as f64 - 1.0,
        deformed.height_px as f64 - 1.0,
    );
    // Sums of (value − offset) in f32 per row (the offset keeps 16-bit squares exact enough),
    // rows added in f64.
    let offset =
        reference.pixels[(top_left.1 + first) * reference.width_px + top_left.0 + first] as f32;
    let (mut sf, mut sg, mut sff, mut sgg, mut sfg) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
    let mut count = 0usize;
    let step = (a[0][0] * stride as f64, a[1][0] * stride as f64);
    let (w, p) = (deformed.width_px, deformed.pixels);
    for y in (first..n).step_by(stride) {
        let row = (top_left.1 + y) * reference.width_px + top_left.0;
        let start = apply(a, (first as f64 - half, y as f64 - half));
        let (mut px, mut py) = (centre.0 + u.0 + start.0, centre.1 + u.1 + start.1);
        let mut sums = [0.0f32; 5];
        for x in (first..n).step_by(stride) {
            let inside = px >= 0.0 && py >= 0.0 && px <= max_x && py <= max_y;
            if inside {
                let ix = (px as usize).min(w - 2);
                let iy = (py as usize).min(deformed.height_px - 2);
                let (fx, fy) = ((px - ix as f64) as f32, (py - iy as f64) as f32);
                let at = iy * w + ix;
                let top = p[at] as f32 + fx * (p[at + 1] as f32 - p[at] as f32);
                let bottom = p[at + w] as f32 + fx * (p[at + w + 1] as f32 - p[at + w] as f32);
                let g = top + fy * (bottom - top) - offset;
                let f = reference.pixels[row + x] as f32 - offset;
                sums[0] += f;
                sums[1] += g;
                sums[2] += f * f;
                sums[3] += g * g;
                sums[4] += f * g;
                count += 1;
            }
            px += step.0;
            py += step.1;
        }
        sf += sums[0] as f64;
        sg += sums[1] as f64;
        sff += sums[2] as f64;
        sgg += sums[3] as f64;
        sfg += sums[4] as f64;
    }
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A smooth analytic texture with speckle-like detail (also IC-GN's test image).
    pub(crate) fn texture(x: f64, y: f64) -> f64 {
        20000.0
            + 8000.0 * (0.9 * x + 0.3 * y).sin() * (0.5 * y - 0.2 * x).cos()
            + 5000.0 * (0.37 * x * x / 40.0 + 0.61 * y).sin()
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
        let (r, d) = (
            Image {
                pixels: &reference,
                width_px: size,
                height_px: size,
            },
            Image {
                pixels: &deformed,
                width_px: size,
                height_px: size,
            },
        );
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
}
