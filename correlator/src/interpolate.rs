//! Sub-pixel sampling of a u16 image for the warped ZOI: Keys bicubic with a = −0.5
//! (third-order accurate, exact on linear ramps, four taps per axis; the final check in
//! `verify` does its own bilinear sampling inline, where speed matters more than a slight
//! smoothing), and the small affine helpers both use. Positions are in px, x = column,
//! y = row, pixel centres on integers.

use crate::image::Image;

/// A 2x2 matrix, row-major: `[[a11, a12], [a21, a22]]`.
pub type Mat2 = [[f64; 2]; 2];

/// I + G for a displacement gradient G.
pub fn identity_plus(g: Mat2) -> Mat2 {
    [[1.0 + g[0][0], g[0][1]], [g[1][0], 1.0 + g[1][1]]]
}

/// m v.
#[inline]
pub fn apply(m: Mat2, v: (f64, f64)) -> (f64, f64) {
    (m[0][0] * v.0 + m[0][1] * v.1, m[1][0] * v.0 + m[1][1] * v.1)
}

/// The n x n block with centre `centre_px` (px), mapped by
/// x → centre + shift + a (x − centre).
#[derive(Clone, Copy, Debug)]
pub struct WarpedBlock {
    pub centre_px: (f64, f64),
    pub shift_px: (f64, f64),
    pub a: Mat2,
    pub n: usize,
}

impl WarpedBlock {
    /// Where the block lands in `image`: true when all four corners (hence, the map being
    /// affine, every sample) lie within `[lo_px, size − 1 − hi_px]` on both axes.
    pub fn inside(&self, image: Image, lo_px: f64, hi_px: f64) -> bool {
        let (centre, shift, a) = (self.centre_px, self.shift_px, self.a);
        let half = (self.n as f64 - 1.0) / 2.0;
        let (max_x, max_y) = (
            image.width_px as f64 - 1.0 - hi_px,
            image.height_px as f64 - 1.0 - hi_px,
        );
        [(-half, -half), (half, -half), (-half, half), (half, half)]
            .into_iter()
            .all(|r| {
                let d = apply(a, r);
                let (x, y) = (centre.0 + shift.0 + d.0, centre.1 + shift.1 + d.1);
                x >= lo_px && y >= lo_px && x <= max_x && y <= max_y
            })
    }
}

/// Keys cubic convolution weights (a = −0.5) of the four samples at −1, 0, 1, 2 for a
/// fractional position t in [0, 1).
#[inline]
fn keys_weights(t: f32) -> [f32; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    [
        -0.5 * t3 + t2 - 0.5 * t,
        1.5 * t3 - 2.5 * t2 + 1.0,
        -1.5 * t3 + 2.0 * t2 + 0.5 * t,
        0.5 * t3 - 0.5 * t2,
    ]
}

/// Keys bicubic value at (x, y), which must lie in [1, w − 3] x [1, h − 3] (the 4x4
/// neighbourhood inside the image).
#[inline]
pub fn bicubic(image: Image, x: f64, y: f64) -> f32 {
    let w = image.width_px;
    let (fx, fy) = (x.floor(), y.floor());
    let (ix, iy) = (fx as usize, fy as usize);
    let wx = keys_weights((x - fx) as f32);
    let wy = keys_weights((y - fy) as f32);
    let p = image.pixels;
    let mut sum = 0.0f32;
    for (row, &wy) in wy.iter().enumerate() {
        let start = (iy + row - 1) * w + ix - 1;
        let r = &p[start..start + 4];
        let v =
            wx[0] * r[0] as f32 + wx[1] * r[1] as f32 + wx[2] * r[2] as f32 + wx[3] * r[3] as f32;
        sum += wy * v;
    }
    sum
}

/// [`bicubic`] anywhere in [0, w − 1] x [0, h − 1]: the 4x4 neighbourhood is clamped into the
/// image (the border pixels repeated), for ZOIs that touch the border.
pub fn bicubic_clamped(image: Image, x: f64, y: f64) -> f32 {
    let (w, h) = (image.width_px as i64, image.height_px as i64);
    let (fx, fy) = (x.floor(), y.floor());
    let (ix, iy) = (fx as i64, fy as i64);
    let wx = keys_weights((x - fx) as f32);
    let wy = keys_weights((y - fy) as f32);
    let mut sum = 0.0f32;
    for (row, &wy) in wy.iter().enumerate() {
        let yy = (iy + row as i64 - 1).clamp(0, h - 1) as usize;
        let mut v = 0.0f32;
        for (col, &wx) in wx.iter().enumerate() {
            let xx = (ix + col as i64 - 1).clamp(0, w - 1) as usize;
            v += wx * image.pixels[yy * image.width_px + xx] as f32;
        }
        sum += wy * v;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    const IDENTITY: Mat2 = [[1.0, 0.0], [0.0, 1.0]];

    #[test]
    fn bicubic_is_exact_on_a_ramp_and_at_pixels() {
        let (w, h) = (12usize, 9usize);
        let pixels: Vec<u16> = (0..w * h)
            .map(|i| (100 + 7 * (i % w) + 3 * (i / w)) as u16)
            .collect();
        let image = Image {
            pixels: &pixels,
            width_px: w,
            height_px: h,
        };
        let ramp = |x: f64, y: f64| 100.0 + 7.0 * x + 3.0 * y;
        for (x, y) in [(1.0, 1.0), (2.25, 3.5), (5.9, 4.1), (8.0, 5.999)] {
            assert!((bicubic(image, x, y) as f64 - ramp(x, y)).abs() < 1e-3);
        }
        assert_eq!(bicubic(image, 3.0, 4.0), pixels[4 * w + 3] as f32);
        for (x, y) in [(2.25, 3.5), (5.9, 4.1)] {
            assert_eq!(bicubic_clamped(image, x, y), bicubic(image, x, y));
        }
        // At the border, pixels and the samples next to them are still right.
        assert!((bicubic_clamped(image, 0.0, 0.0) - 100.0).abs() < 1e-3);
        assert!((bicubic_clamped(image, 11.0, 8.0) as f64 - ramp(11.0, 8.0)).abs() < 1e-3);
    }

    #[test]
    fn corners_decide_whether_a_warped_block_is_inside() {
        let pixels = vec![0u16; 64 * 64];
        let image = Image {
            pixels: &pixels,
            width_px: 64,
            height_px: 64,
        };
        let block = |shift_px, a, n| WarpedBlock {
            centre_px: (31.5, 31.5),
            shift_px,
            a,
            n,
        };
        assert!(block((0.0, 0.0), IDENTITY, 64).inside(image, 0.0, 0.0));
        assert!(!block((0.5, 0.0), IDENTITY, 64).inside(image, 0.0, 0.0));
        let (s, co) = 0.3f64.sin_cos();
        let rotation = [[co, -s], [s, co]];
        assert!(!block((0.0, 0.0), rotation, 64).inside(image, 0.0, 0.0));
        assert!(block((0.0, 0.0), rotation, 32).inside(image, 1.0, 2.0));
    }
}
