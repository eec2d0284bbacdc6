//! Quintic B-spline interpolation of an image (Unser, "Splines: a perfect fit for signal and
//! image processing", 1999): the pixels are first turned into B-spline coefficients by the
//! separable recursive prefilter (per axis, a causal and an anticausal first-order pass for
//! each of the two poles, mirror boundary), so that the spline passes through every pixel; a
//! value or a gradient anywhere is then 6 x 6 coefficients times the quintic B-spline weights.
//!
//! Why quintic rather than the usual bicubic B-spline: on the DIC Challenge's sample 5 (a fine
//! 8-bit speckle shifted by 0.1 px) IC-GN with the cubic B-spline is biased by +0.0036 px, with
//! cubic OMOMS (same 4 x 4 cost, fourth order) by +0.0030 px, with the quintic B-spline by
//! +0.0016 px and with a lower standard deviation (0.0026 against 0.0027 px): the interpolation
//! error of the fine speckle content is what biases the match, and the quintic spline's
//! frequency response is the flattest. A Gaussian pre-smoothing also removes that bias (as in
//! Pan 2013) but raises the noise (0.0028 to 0.0034 px). Its derivative is continuous, so the
//! reference gradients IC-GN uses are those of the very model the deformed image is sampled
//! with. The prefilter is four light passes per axis, once per frame, spread over the workers;
//! the 6 x 6 evaluation uses 4-lane vectors.
//!
//! Positions are in px, x = column, y = row, pixel centres on integers. The model is defined
//! on [0, w − 1] x [0, h − 1]: near the border the coefficients are mirrored (c[−k] = c[k],
//! c[N − 1 + k] = c[N − 1 − k]), the boundary condition the prefilter assumed.

use crate::simd::F32x4;

/// Coefficients per axis of one value, from floor(x) − 2 to floor(x) + 3.
pub const TAPS: usize = 6;
const FIRST: i64 = -2;
/// The fast path of [`Coefficients::value_at`] needs MARGIN_LOW <= floor(x) < size −
/// MARGIN_HIGH on both axes.
pub const MARGIN_LOW: usize = 2;
pub const MARGIN_HIGH: usize = 4;
/// The poles of the quintic prefilter and its gain Π (1 − z)(1 − 1/z).
const POLES: [f32; 2] = [-0.430_575_35, -0.043_096_29];
const GAIN: f32 = 120.0;
/// How far past the border a sample may fall (px), as the FFT step accepts a ZOI one pixel
/// past it: the mirror model holds the border pixels' neighbourhood.
pub const BORDER_TOLERANCE_PX: f64 = 1.0;
/// Values read past the last coefficient by the 8-lane row loads of [`Coefficients::value_at`].
const PAD: usize = 8;

/// Rows (or columns) handed to one pool item at a time by the caller.
pub const ROWS_PER_ITEM: usize = 16;
pub const COLUMNS_PER_ITEM: usize = 64;

/// 120 × the weights of the taps at −2, −1, 0, 1 (`LOW`) and 2, 3 (`HIGH`, two zero lanes) as
/// polynomials in the fractional position t: `[power][lane]`.
const LOW: [[f32; 4]; 6] = [
    [1.0, 26.0, 66.0, 26.0],
    [-5.0, -50.0, 0.0, 50.0],
    [10.0, 20.0, -60.0, 20.0],
    [-10.0, 20.0, 0.0, -20.0],
    [5.0, -20.0, 30.0, -20.0],
    [-1.0, 5.0, -10.0, 10.0],
];
const HIGH: [[f32; 4]; 6] = [
    [1.0, 0.0, 0.0, 0.0],
    [5.0, 0.0, 0.0, 0.0],
    [10.0, 0.0, 0.0, 0.0],
    [10.0, 0.0, 0.0, 0.0],
    [5.0, 0.0, 0.0, 0.0],
    [-5.0, 1.0, 0.0, 0.0],
];

/// The weights of the six taps for a fractional position t in [0, 1), as two 4-lane vectors.
#[inline(always)]
fn weight_vectors(t: f32) -> (F32x4, F32x4) {
    let tv = F32x4::splat(t);
    let (mut low, mut high) = (F32x4::load(&LOW[5]), F32x4::load(&HIGH[5]));
    for p in (0..5).rev() {
        low = F32x4::load(&LOW[p]).mul_add(low, tv);
        high = F32x4::load(&HIGH[p]).mul_add(high, tv);
    }
    let scale = F32x4::splat(1.0 / 120.0);
    (low.mul(scale), high.mul(scale))
}

/// The quintic B-spline at x, and its derivative.
fn basis(x: f32) -> (f32, f32) {
    let a = x.abs();
    let sign = if x < 0.0 { -1.0 } else { 1.0 };
    let a2 = a * a;
    if a < 1.0 {
        (
            (66.0 - 60.0 * a2 + 30.0 * a2 * a2 - 10.0 * a2 * a2 * a) / 120.0,
            sign * (-120.0 * a + 120.0 * a2 * a - 50.0 * a2 * a2) / 120.0,
        )
    } else if a < 2.0 {
        (
            (51.0 + 75.0 * a - 210.0 * a2 + 150.0 * a2 * a - 45.0 * a2 * a2 + 5.0 * a2 * a2 * a)
                / 120.0,
            sign * (75.0 - 420.0 * a + 450.0 * a2 - 180.0 * a2 * a + 25.0 * a2 * a2) / 120.0,
        )
    } else if a < 3.0 {
        let b = 3.0 - a;
        let b2 = b * b;
        (b2 * b2 * b / 120.0, sign * -5.0 * b2 * b2 / 120.0)
    } else {
        (0.0, 0.0)
    }
}

/// Value and derivative weights of the six taps for a fractional position t in [0, 1).
fn weights_and_derivatives(t: f32) -> ([f32; TAPS], [f32; TAPS]) {
    let mut value = [0.0; TAPS];
    let mut derivative = [0.0; TAPS];
    for k in 0..TAPS {
        (value[k], derivative[k]) = basis(t - (FIRST + k as i64) as f32);
    }
    (value, derivative)
}

/// Value and derivative weights at a pixel (t = 0) over the five coefficients −2..=2 (the
/// sixth is zero there).
pub type PixelWeights = ([f32; 5], [f32; 5]);

pub fn pixel_weights() -> PixelWeights {
    let (value, derivative) = weights_and_derivatives(0.0);
    (
        value[..5].try_into().expect("five taps"),
        derivative[..5].try_into().expect("five taps"),
    )
}

/// Index i mirrored into 0..n (n >= 2), the prefilter's boundary.
#[inline]
fn mirror(i: i64, n: usize) -> usize {
    let n = n as i64;
    let period = 2 * (n - 1);
    let m = i.rem_euclid(period);
    (if m < n { m } else { period - m }) as usize
}

/// Terms of the truncated sum that starts the causal pass: |z|^k < 1e-7.
fn horizon(z: f32) -> usize {
    (1e-7f32.ln() / z.abs().ln()).ceil() as usize
}

/// Rows of the image prefiltered together by [`filter_rows`].
const INTERLEAVED_ROWS: usize = 8;

/// The prefilter of up to [`INTERLEAVED_ROWS`] rows of `n` values each (`rows` holds them one
/// after the other), in place, gain included: [`filter_line`]'s operations on each row in the
/// same order (the same f32 results), the rows' recursions interleaved. One row's recursion is
/// a chain of dependent multiply-adds, each waiting on the last; several rows' chains are
/// independent, so that the processor overlaps them (the row pass took three quarters of the
/// prefilter's time, the column pass already running 64 columns' recursions side by side).
fn filter_rows(rows: &mut [f32], n: usize) {
    if n < 2 {
        return;
    }
    let count = rows.len() / n;
    assert!(count <= INTERLEAVED_ROWS && rows.len() == count * n);
    for v in rows.iter_mut() {
        *v *= GAIN;
    }
    let mut previous = [0.0f32; INTERLEAVED_ROWS];
    let previous = &mut previous[..count];
    for z in POLES {
        for (line, p) in rows.chunks_exact_mut(n).zip(previous.iter_mut()) {
            // Causal start: Σ z^k s[k], the mirror boundary's sum truncated.
            let mut sum = line[0];
            let mut zk = z;
            for &value in &line[1..horizon(z).min(n)] {
                sum += zk * value;
                zk *= z;
            }
            line[0] = sum;
            *p = sum;
        }
        for k in 1..n {
            for (r, p) in previous.iter_mut().enumerate() {
                let v = &mut rows[r * n + k];
                *v += z * *p;
                *p = *v;
            }
        }
        for (line, p) in rows.chunks_exact_mut(n).zip(previous.iter_mut()) {
            line[n - 1] = (z / (z * z - 1.0)) * (line[n - 1] + z * line[n - 2]);
            *p = line[n - 1];
        }
        for k in (0..n - 1).rev() {
            for (r, p) in previous.iter_mut().enumerate() {
                let v = &mut rows[r * n + k];
                *v = z * (*p - *v);
                *p = *v;
            }
        }
    }
}

/// The prefilter of one line of `n` values with stride `stride`, in place, gain included
/// (the reference [`filter_rows`] is tested against).
#[cfg(test)]
fn filter_line(line: &mut [f32], n: usize, stride: usize) {
    let at = |k: usize| k * stride;
    if n < 2 {
        return;
    }
    for k in 0..n {
        line[at(k)] *= GAIN;
    }
    for z in POLES {
        // Causal start: Σ z^k s[k], the mirror boundary's sum truncated.
        let mut sum = line[at(0)];
        let mut zk = z;
        for k in 1..horizon(z).min(n) {
            sum += zk * line[at(k)];
            zk *= z;
        }
        line[at(0)] = sum;
        for k in 1..n {
            line[at(k)] += z * line[at(k - 1)];
        }
        line[at(n - 1)] = (z / (z * z - 1.0)) * (line[at(n - 1)] + z * line[at(n - 2)]);
        for k in (0..n - 1).rev() {
            line[at(k)] = z * (line[at(k + 1)] - line[at(k)]);
        }
    }
}

/// B-spline coefficients of one image, row-major (plus [`PAD`] zeros).
pub struct Coefficients {
    pub width_px: usize,
    pub height_px: usize,
    pub data: Vec<f32>,
}

impl Coefficients {
    pub fn new(width_px: usize, height_px: usize) -> Self {
        Self {
            width_px,
            height_px,
            data: vec![0.0; width_px * height_px + PAD],
        }
    }

    /// Pool items of [`Self::prefilter_rows`] and [`Self::prefilter_columns`].
    pub fn row_items(&self) -> usize {
        self.height_px.div_ceil(ROWS_PER_ITEM)
    }

    pub fn column_items(&self) -> usize {
        self.width_px.div_ceil(COLUMNS_PER_ITEM)
    }

    /// First pass: rows `first_row..` of `pixels` converted and filtered along x into `rows`
    /// (those rows of `data`).
    pub fn prefilter_rows(pixels: &[u16], width_px: usize, first_row: usize, rows: &mut [f32]) {
        let start = first_row * width_px;
        let pixels = &pixels[start..start + rows.len()];
        for (o, &p) in rows.iter_mut().zip(pixels) {
            *o = p as f32;
        }
        for group in rows.chunks_mut(INTERLEAVED_ROWS * width_px) {
            filter_rows(group, width_px);
        }
    }

    /// Second pass, item `item`: columns `item * COLUMNS_PER_ITEM..` filtered along y in
    /// place, row by row over all those columns at once (cache friendly).
    ///
    /// # Safety
    /// `data` must point to `width_px * height_px` values, and no other thread may access the
    /// columns of this item during the call.
    pub unsafe fn prefilter_columns(
        data: *mut f32,
        width_px: usize,
        height_px: usize,
        item: usize,
    ) {
        let x0 = item * COLUMNS_PER_ITEM;
        let x1 = (x0 + COLUMNS_PER_ITEM).min(width_px);
        let n = height_px;
        if n < 2 || x0 >= x1 {
            return;
        }
        let cols = x1 - x0;
        // SAFETY: rows of this item's columns only (the caller's contract); at most two rows
        // are borrowed at a time, and they are different rows.
        let row =
            |y: usize| unsafe { std::slice::from_raw_parts_mut(data.add(y * width_px + x0), cols) };
        for y in 0..n {
            for v in row(y).iter_mut() {
                *v *= GAIN;
            }
        }
        for z in POLES {
            let mut zk = z;
            for k in 1..horizon(z).min(n) {
                let (first, other) = (row(0), row(k));
                for (a, &b) in first.iter_mut().zip(other.iter()) {
                    *a += zk * b;
                }
                zk *= z;
            }
            for y in 1..n {
                let (previous, current) = (row(y - 1), row(y));
                for (c, &p) in current.iter_mut().zip(previous.iter()) {
                    *c += z * p;
                }
            }
            let (last, before) = (row(n - 1), row(n - 2));
            for (l, &b) in last.iter_mut().zip(before.iter()) {
                *l = (z / (z * z - 1.0)) * (*l + z * b);
            }
            for y in (0..n - 1).rev() {
                let (current, next) = (row(y), row(y + 1));
                for (c, &nx) in current.iter_mut().zip(next.iter()) {
                    *c = z * (nx - *c);
                }
            }
        }
    }

    /// Single-threaded prefilter of a whole image (tests; the correlator spreads the items over
    /// its pool).
    #[cfg(test)]
    pub fn prefilter(&mut self, pixels: &[u16]) {
        let (w, h) = (self.width_px, self.height_px);
        assert_eq!(pixels.len(), w * h);
        Self::prefilter_rows(pixels, w, 0, &mut self.data[..w * h]);
        for item in 0..self.column_items() {
            // SAFETY: one item at a time on the whole buffer.
            unsafe { Self::prefilter_columns(self.data.as_mut_ptr(), w, h, item) };
        }
    }

    /// The interpolated value at (ix + tx, iy + ty), tx and ty in [0, 1), on the fast path:
    /// MARGIN_LOW <= ix < w − MARGIN_HIGH, the same for iy.
    #[inline(always)]
    pub fn value_at(&self, ix: usize, iy: usize, tx: f32, ty: f32) -> f32 {
        let (wx_low, wx_high) = weight_vectors(tx);
        let (wy_low, wy_high) = weight_vectors(ty);
        let mut wy = [0.0f32; 8];
        let (a, b) = wy.split_at_mut(4);
        wy_low.store(a.try_into().expect("4 lanes"));
        wy_high.store(b.try_into().expect("4 lanes"));
        let w = self.width_px;
        let start = (iy - MARGIN_LOW) * w + ix - MARGIN_LOW;
        let rows = &self.data[start..start + (TAPS - 1) * w + 8];
        let (mut low, mut high) = (F32x4::zero(), F32x4::zero());
        for (r, &weight) in wy.iter().take(TAPS).enumerate() {
            let row = &rows[r * w..r * w + 8];
            let s = F32x4::splat(weight);
            low = low.mul_add(s, F32x4::load(row[..4].try_into().expect("4 values")));
            high = high.mul_add(s, F32x4::load(row[4..].try_into().expect("4 values")));
        }
        low.mul(wx_low).add(high.mul(wx_high)).sum()
    }

    /// Value and gradient (∂/∂x, ∂/∂y) of the model at the pixel (ix, iy) with `weights` from
    /// [`pixel_weights`] (mirrored coefficients near the border).
    #[cfg(test)]
    pub fn pixel_value_gradient(
        &self,
        (ix, iy): (usize, usize),
        (value, derivative): &PixelWeights,
    ) -> (f32, f32, f32) {
        let (w, h) = (self.width_px, self.height_px);
        let (mut v, mut gx, mut gy) = (0.0f32, 0.0f32, 0.0f32);
        for r in 0..5 {
            let yy = mirror(iy as i64 + r as i64 - 2, h);
            let (mut sv, mut sd) = (0.0f32, 0.0f32);
            for c in 0..5 {
                let coefficient = self.data[yy * w + mirror(ix as i64 + c as i64 - 2, w)];
                sv += value[c] * coefficient;
                sd += derivative[c] * coefficient;
            }
            v += value[r] * sv;
            gx += value[r] * sd;
            gy += derivative[r] * sv;
        }
        (v, gx, gy)
    }

    /// The model's values at the n x n pixels from `top_left` into `out` (row-major), with
    /// `weights` from [`pixel_weights`]: the value of `pixel_value_gradient` (the tests' reference) at each
    /// pixel, summed in the same order (the same f32 results), without its gradient, and with
    /// the mirrored indices computed once per row and column instead of per tap.
    pub fn pixel_values_block(
        &self,
        top_left: (usize, usize),
        n: usize,
        (value, _): &PixelWeights,
        out: &mut [f32],
    ) {
        let (w, h) = (self.width_px, self.height_px);
        assert!(top_left.0 + n <= w && top_left.1 + n <= h && out.len() == n * n);
        // The columns' first tap: the block's columns −2..n + 2 mirrored, kept when they are
        // contiguous (the block is two pixels from the left and right borders).
        let interior_x = top_left.0 >= 2 && top_left.0 + n + 2 <= w;
        for (j, out_row) in out.chunks_exact_mut(n).enumerate() {
            out_row.fill(0.0);
            for (r, &weight_r) in value.iter().enumerate() {
                let yy = mirror((top_left.1 + j) as i64 + r as i64 - 2, h);
                let row = &self.data[yy * w..(yy + 1) * w];
                if interior_x {
                    let taps = &row[top_left.0 - 2..top_left.0 + n + 2];
                    for (i, v) in out_row.iter_mut().enumerate() {
                        let mut sv = 0.0f32;
                        for (c, &weight_c) in value.iter().enumerate() {
                            sv += weight_c * taps[i + c];
                        }
                        *v += weight_r * sv;
                    }
                } else {
                    for (i, v) in out_row.iter_mut().enumerate() {
                        let mut sv = 0.0f32;
                        for (c, &weight_c) in value.iter().enumerate() {
                            let xx = mirror((top_left.0 + i) as i64 + c as i64 - 2, w);
                            sv += weight_c * row[xx];
                        }
                        *v += weight_r * sv;
                    }
                }
            }
        }
    }

    /// Value and gradient (∂/∂x, ∂/∂y) at any (x, y) inside the image or at most
    /// [`BORDER_TOLERANCE_PX`] past its border (mirrored coefficients near the border, the
    /// prefilter's boundary model); None further out.
    pub fn value_gradient(&self, x: f64, y: f64) -> Option<(f32, f32, f32)> {
        let t = BORDER_TOLERANCE_PX;
        let inside = x >= -t
            && y >= -t
            && x <= (self.width_px - 1) as f64 + t
            && y <= (self.height_px - 1) as f64 + t;
        if !inside {
            return None;
        }
        let (fx, fy) = (x.floor(), y.floor());
        let (wx, dx) = weights_and_derivatives((x - fx) as f32);
        let (wy, dy) = weights_and_derivatives((y - fy) as f32);
        let (ix, iy) = (fx as i64, fy as i64);
        let (mut v, mut gx, mut gy) = (0.0f32, 0.0f32, 0.0f32);
        for r in 0..TAPS {
            let yy = mirror(iy + r as i64 + FIRST, self.height_px);
            let (mut sv, mut sd) = (0.0f32, 0.0f32);
            for c in 0..TAPS {
                let xx = mirror(ix + c as i64 + FIRST, self.width_px);
                let coefficient = self.data[yy * self.width_px + xx];
                sv += wx[c] * coefficient;
                sd += dx[c] * coefficient;
            }
            v += wy[r] * sv;
            gx += wy[r] * sd;
            gy += dy[r] * sv;
        }
        Some((v, gx, gy))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: usize, h: usize, f: impl Fn(f64, f64) -> f64) -> Vec<u16> {
        (0..w * h)
            .map(|i| f((i % w) as f64, (i / w) as f64).round() as u16)
            .collect()
    }

    #[test]
    fn the_spline_passes_through_every_pixel_and_follows_a_ramp() {
        let (w, h) = (23, 17);
        let pixels = image(w, h, |x, y| {
            1000.0 + 500.0 * (0.9 * x).sin() * (0.7 * y + 0.2).cos() + 3.0 * x
        });
        let mut c = Coefficients::new(w, h);
        c.prefilter(&pixels);
        let weights = pixel_weights();
        for y in 0..h {
            for x in 0..w {
                let (v, _, _) = c.value_gradient(x as f64, y as f64).unwrap();
                let (p, _, _) = c.pixel_value_gradient((x, y), &weights);
                assert!(
                    (v - pixels[y * w + x] as f32).abs() < 0.05,
                    "({x}, {y}): {v}"
                );
                assert!((p - v).abs() < 1e-3);
            }
        }
        let ramp = image(w, h, |x, y| 100.0 + 7.0 * x + 3.0 * y);
        c.prefilter(&ramp);
        // Away from the border (the mirror boundary bends a ramp within a few px of it).
        for (x, y) in [(8.25, 7.5), (12.9, 8.1), (10.0, 9.0)] {
            let (v, gx, gy) = c.value_gradient(x, y).unwrap();
            assert!(
                (v as f64 - (100.0 + 7.0 * x + 3.0 * y)).abs() < 0.02,
                "({x}, {y}): {v}"
            );
            assert!(
                (gx - 7.0).abs() < 0.01 && (gy - 3.0).abs() < 0.01,
                "{gx} {gy}"
            );
            let (ix, iy) = (x.floor(), y.floor());
            let fast = c.value_at(ix as usize, iy as usize, (x - ix) as f32, (y - iy) as f32);
            assert!((fast - v).abs() < 1e-3, "{fast} vs {v}");
        }
        assert!(c.value_gradient(-0.9, 3.0).is_some());
        assert!(c.value_gradient(-1.1, 3.0).is_none());
        assert!(c.value_gradient(3.0, 17.01).is_none());
    }

    /// The threaded layout (row items, then column items) gives the same coefficients.
    /// The block values are the per-pixel values, bit for bit, inside and at the borders.
    #[test]
    fn block_values_are_the_pixel_values() {
        let (w, h) = (40usize, 30usize);
        let pixels = image(w, h, |x, y| {
            1000.0 + 500.0 * (0.7 * x).sin() * (0.45 * y + 0.2).cos()
        });
        let mut c = Coefficients::new(w, h);
        c.prefilter(&pixels);
        let weights = pixel_weights();
        let n = 9;
        for top_left in [
            (10, 8),
            (0, 0),
            (w - n, h - n),
            (1, h - n - 1),
            (w - n - 1, 3),
        ] {
            let mut block = vec![0.0; n * n];
            c.pixel_values_block(top_left, n, &weights, &mut block);
            for j in 0..n {
                for i in 0..n {
                    let (v, _, _) =
                        c.pixel_value_gradient((top_left.0 + i, top_left.1 + j), &weights);
                    assert_eq!(
                        block[j * n + i].to_bits(),
                        v.to_bits(),
                        "{top_left:?} ({i}, {j})"
                    );
                }
            }
        }
    }

    /// Rows filtered together are each row filtered alone, bit for bit, for widths shorter and
    /// longer than the causal start's horizon and any number of rows up to the group.
    #[test]
    fn interleaved_rows_are_single_lines() {
        for n in [2usize, 3, 7, 20, 131] {
            for count in [1usize, 3, INTERLEAVED_ROWS] {
                let values: Vec<f32> = (0..n * count)
                    .map(|i| (1000.0 + 700.0 * (0.37 * i as f64).sin()).round() as f32)
                    .collect();
                let mut together = values.clone();
                filter_rows(&mut together, n);
                let mut alone = values;
                for line in alone.chunks_exact_mut(n) {
                    filter_line(line, n, 1);
                }
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&together), bits(&alone), "n {n}, {count} rows");
                assert_ne!(together[n / 2], 0.0);
            }
        }
    }

    #[test]
    fn row_and_column_items_equal_the_whole_prefilter() {
        let (w, h) = (150, 41);
        let pixels = image(w, h, |x, y| 2000.0 + 900.0 * (0.3 * x + 0.5 * y).sin());
        let mut whole = Coefficients::new(w, h);
        whole.prefilter(&pixels);
        let mut items = Coefficients::new(w, h);
        for item in 0..items.row_items() {
            let first = item * ROWS_PER_ITEM;
            let last = (first + ROWS_PER_ITEM).min(h);
            Coefficients::prefilter_rows(&pixels, w, first, &mut items.data[first * w..last * w]);
        }
        for item in (0..items.column_items()).rev() {
            // SAFETY: `items.data` holds w * h values and this thread alone touches it.
            unsafe { Coefficients::prefilter_columns(items.data.as_mut_ptr(), w, h, item) };
        }
        assert_eq!(whole.data, items.data);
    }
}
