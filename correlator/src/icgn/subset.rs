//! What IC-GN needs of a reference subset, computed once per reference: the subset f
//! normalised, f̂ = (f − f_m) / f_n (f_m its mean, f_n = ‖f − f_m‖), its gradient ∇f̂ (sixth-order
//! central differences of the pixels: less noise than the B-spline's own derivative, see
//! [`central_gradient`]), the inverse of the Hessian H = Σ J Jᵀ of the
//! steepest-descent images J = ∇f̂ ∂W/∂p, and the two constant sums of the ZNSSD update, Σ J
//! and Σ J f̂ (see [`super::solve`]). J itself is never stored: it is ∇f̂ times the pixel's
//! offset monomials, rebuilt in the iteration loop from the three planes kept per subset.

use super::bspline::{self, Coefficients};
use super::shape::Order;
use crate::zoi::{Image, MIN_STD_COUNTS};
use nalgebra::SMatrix;

/// Values stored per subset pixel: f̂, ∂f̂/∂x, ∂f̂/∂y (three planes of n² values).
pub const PLANES: usize = 3;

/// The per-subset constants of the ZNSSD update.
#[derive(Clone, Copy, Debug)]
pub struct SubsetStats {
    /// H⁻¹, row-major P x P (P = the order's parameters), in the order of [`steepest_descent`].
    pub inverse_hessian: [f64; 144],
    /// Σ J and Σ J f̂ over the subset.
    pub sum_j: [f64; 12],
    pub sum_jf: [f64; 12],
    /// f_m, subtracted from the deformed samples before their sums (keeps f32 sums exact enough).
    pub mean: f32,
    /// f_n = ‖f − f_m‖ (counts): turns the normalised ZNSSD residual into counts (the noise
    /// estimate of `super::order_choice`).
    pub norm_counts: f32,
}

impl Default for SubsetStats {
    fn default() -> Self {
        Self {
            inverse_hessian: [0.0; 144],
            sum_j: [0.0; 12],
            sum_jf: [0.0; 12],
            mean: 0.0,
            norm_counts: 0.0,
        }
    }
}

/// The steepest-descent image at a pixel: ∇f̂ ∂W/∂p for the parameters of `order`, in the order
/// u, u_x, u_y, (u_xx, u_xy, u_yy,) v, v_x, v_y, (v_xx, v_xy, v_yy).
#[inline]
pub fn steepest_descent(order: Order, fx: f64, fy: f64, dx: f64, dy: f64, out: &mut [f64; 12]) {
    match order {
        Order::First => {
            *out = [
                fx,
                fx * dx,
                fx * dy,
                fy,
                fy * dx,
                fy * dy,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            ];
        }
        Order::Second => {
            let (xx, xy, yy) = (0.5 * dx * dx, dx * dy, 0.5 * dy * dy);
            *out = [
                fx,
                fx * dx,
                fx * dy,
                fx * xx,
                fx * xy,
                fx * yy,
                fy,
                fy * dx,
                fy * dy,
                fy * xx,
                fy * xy,
                fy * yy,
            ];
        }
    }
}

/// Which subset of a reference image: its top-left pixel, its side n (px) and the order of
/// the shape function fitted to it.
#[derive(Clone, Copy, Debug)]
pub struct SubsetSpec {
    pub top_left_px: (usize, usize),
    pub side_px: usize,
    pub order: Order,
}

/// Prepares the subset `spec` of the reference image (`coefficients` are that image's): fills
/// `planes` (3 n² values) and `stats`. False when the subset is flat (standard deviation below
/// [`MIN_STD_COUNTS`]) or its Hessian is singular.
pub fn prepare(
    reference: Image,
    coefficients: &Coefficients,
    spec: SubsetSpec,
    planes: &mut [f32],
    stats: &mut SubsetStats,
) -> bool {
    let (top_left, n) = (spec.top_left_px, spec.side_px);
    let nn = n * n;
    assert_eq!(planes.len(), PLANES * nn);
    assert!(reference.contains_block(top_left.0 as i64, top_left.1 as i64, n));
    *stats = SubsetStats::default();
    let (values, rest) = planes.split_at_mut(nn);
    let (gx, gy) = rest.split_at_mut(nn);
    // The model's values (the pixels themselves: it interpolates) and the image's gradient.
    coefficients.pixel_values_block(top_left, n, &bspline::pixel_weights(), values);
    central_gradient_block(reference, top_left, n, gx, gy);
    let sum: f64 = values.iter().map(|&f| f as f64).sum();
    let mean = sum / nn as f64;
    let norm_sq: f64 = values.iter().map(|&f| (f as f64 - mean).powi(2)).sum();
    if (norm_sq / nn as f64).sqrt() < MIN_STD_COUNTS as f64 {
        return false;
    }
    let inv_norm = 1.0 / norm_sq.sqrt();
    for v in values.iter_mut() {
        *v = ((*v as f64 - mean) * inv_norm) as f32;
    }
    for g in gx.iter_mut().chain(gy.iter_mut()) {
        *g = (*g as f64 * inv_norm) as f32;
    }
    let Some(inverse) = inverse_hessian(spec, [&*values, &*gx, &*gy], stats) else {
        return false;
    };
    stats.inverse_hessian = inverse;
    stats.mean = mean as f32;
    stats.norm_counts = norm_sq.sqrt() as f32;
    true
}

/// The constants of an already prepared subset (`planes`, `prepared` as [`prepare`] left
/// them, whatever its order) for the shape function of `spec.order` into `stats`: the planes
/// do not depend on the order, only H⁻¹, Σ J and Σ J f̂ do. False when that Hessian is
/// singular.
pub fn restate(
    spec: SubsetSpec,
    planes: &[f32],
    prepared: &SubsetStats,
    stats: &mut SubsetStats,
) -> bool {
    let nn = spec.side_px * spec.side_px;
    assert_eq!(planes.len(), PLANES * nn);
    *stats = SubsetStats {
        mean: prepared.mean,
        norm_counts: prepared.norm_counts,
        ..SubsetStats::default()
    };
    let (values, rest) = planes.split_at(nn);
    let (gx, gy) = rest.split_at(nn);
    match inverse_hessian(spec, [values, gx, gy], stats) {
        Some(inverse) => {
            stats.inverse_hessian = inverse;
            true
        }
        None => false,
    }
}

/// H⁻¹ of the normalised subset of `spec` (its planes f̂, ∂f̂/∂x, ∂f̂/∂y), accumulating Σ J and
/// Σ J f̂ into `stats` on the way; None when H is singular.
fn inverse_hessian(
    spec: SubsetSpec,
    planes: [&[f32]; 3],
    stats: &mut SubsetStats,
) -> Option<[f64; 144]> {
    match spec.order {
        Order::First => inverse_hessian_of::<6>(spec, planes, stats),
        Order::Second => inverse_hessian_of::<12>(spec, planes, stats),
    }
}

/// [`inverse_hessian`] for an order of `COUNT` parameters (known at compile time, so that the
/// per-pixel loops over the parameters are unrolled).
fn inverse_hessian_of<const COUNT: usize>(
    spec: SubsetSpec,
    [values, gx, gy]: [&[f32]; 3],
    stats: &mut SubsetStats,
) -> Option<[f64; 144]> {
    let (n, order) = (spec.side_px, spec.order);
    assert_eq!(order.parameters(), COUNT);
    let nn = n * n;
    let (values, gx, gy) = (&values[..nn], &gx[..nn], &gy[..nn]);
    let count = COUNT;
    let mut hessian = if order == Order::First {
        super::first_order_sums::sums(n, [values, gx, gy], &mut stats.sum_j, &mut stats.sum_jf)
    } else {
        steepest_descent_sums::<COUNT>(spec, [values, gx, gy], stats)
    };
    // The Gauss-Newton Hessian of the ZNSSD itself: the reference subset's mean and norm move
    // with Δp too, so its steepest-descent images are K = J − J̄ − f̂ (Σ J f̂) (centred, and
    // without their component along f̂), and Σ K Kᵀ = Σ J Jᵀ − (Σ J)(Σ J)ᵀ / n² − (Σ J f̂)(Σ J f̂)ᵀ.
    // Σ J Jᵀ alone overstates the curvature along the parameters these sums are large for (the
    // gradient terms of a small subset: Σ J f̂ of u_x is about −1/2 whatever the size), which made
    // the updates too short and the convergence linear (ratio 0.85 to 0.9 per iteration at 9 px).
    for a in 0..count {
        for b in a..count {
            hessian[a * count + b] -=
                stats.sum_j[a] * stats.sum_j[b] / nn as f64 + stats.sum_jf[a] * stats.sum_jf[b];
        }
    }
    for a in 0..count {
        for b in 0..a {
            hessian[a * count + b] = hessian[b * count + a];
        }
    }
    invert::<COUNT>(&hessian)
}

/// Σ J Jᵀ (upper triangle, row-major COUNT x COUNT) of the planes, and Σ J, Σ J f̂ into
/// `stats`, from the steepest-descent images pixel by pixel (any order).
fn steepest_descent_sums<const COUNT: usize>(
    spec: SubsetSpec,
    [values, gx, gy]: [&[f32]; 3],
    stats: &mut SubsetStats,
) -> [f64; 144] {
    let (n, order) = (spec.side_px, spec.order);
    let half = (n as f64 - 1.0) / 2.0;
    let mut hessian = [0.0f64; 144];
    let mut j_pixel = [0.0f64; 12];
    for j in 0..n {
        for i in 0..n {
            let k = j * n + i;
            steepest_descent(
                order,
                gx[k] as f64,
                gy[k] as f64,
                i as f64 - half,
                j as f64 - half,
                &mut j_pixel,
            );
            let f = values[k] as f64;
            for a in 0..COUNT {
                stats.sum_j[a] += j_pixel[a];
                stats.sum_jf[a] += j_pixel[a] * f;
                for b in a..COUNT {
                    hessian[a * COUNT + b] += j_pixel[a] * j_pixel[b];
                }
            }
        }
    }
    hessian
}

/// [`central_gradient`] at every pixel of the n x n block from `top_left` into `gx` and `gy`
/// (row-major), the same sums in the same order; without the clamps where the block is three
/// pixels from every border.
fn central_gradient_block(
    image: Image,
    top_left: (usize, usize),
    n: usize,
    gx: &mut [f32],
    gy: &mut [f32],
) {
    const TAPS: [f32; 3] = [45.0 / 60.0, -9.0 / 60.0, 1.0 / 60.0];
    let (w, h) = (image.width_px, image.height_px);
    let (x0, y0) = top_left;
    if !(x0 >= 3 && y0 >= 3 && x0 + n + 3 <= w && y0 + n + 3 <= h) {
        for j in 0..n {
            for i in 0..n {
                (gx[j * n + i], gy[j * n + i]) = central_gradient(image, (x0 + i, y0 + j));
            }
        }
        return;
    }
    let p = image.pixels;
    for j in 0..n {
        let centre = (y0 + j) * w + x0;
        let (gx_row, gy_row) = (&mut gx[j * n..(j + 1) * n], &mut gy[j * n..(j + 1) * n]);
        for i in 0..n {
            let at = centre + i;
            let (mut dx, mut dy) = (0.0f32, 0.0f32);
            for (k, tap) in TAPS.iter().enumerate() {
                let d = k + 1;
                dx += tap * (p[at + d] as f32 - p[at - d] as f32);
                dy += tap * (p[at + d * w] as f32 - p[at - d * w] as f32);
            }
            gx_row[i] = dx;
            gy_row[i] = dy;
        }
    }
}

/// The gradient of `image` at pixel `p` by sixth-order central differences, (−f₋₃ + 9 f₋₂ −
/// 45 f₋₁ + 45 f₁ − 9 f₂ + f₃) / 60 along each axis (rows and columns clamped at the border).
/// Not the quintic B-spline's own derivative: that one passes white noise with a gain of
/// 1.89 σ² (from its frequency response), this one 1.17 σ², and the noise of the reference's
/// gradient inflates the Hessian, which shortens every update: on low-contrast images with 3 %
/// noise IC-GN then converged linearly and left a fifth to a third of the 33 px subsets at the
/// cap. The sixth order keeps the fine speckle's gradient (DIC Challenge sample 5: bias
/// +0.0009 px instead of +0.0016 px, same std); the fourth order (gain 0.90 σ²) lost some of it
/// (std v 0.00272 px instead of 0.00268 px).
#[inline]
fn central_gradient(image: Image, p: (usize, usize)) -> (f32, f32) {
    const TAPS: [f32; 3] = [45.0 / 60.0, -9.0 / 60.0, 1.0 / 60.0];
    let (w, h) = (image.width_px as i64, image.height_px as i64);
    let at =
        |x: i64, y: i64| image.pixels[(y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize] as f32;
    let (x, y) = (p.0 as i64, p.1 as i64);
    let (mut dx, mut dy) = (0.0, 0.0);
    for (k, tap) in TAPS.iter().enumerate() {
        let d = k as i64 + 1;
        dx += tap * (at(x + d, y) - at(x - d, y));
        dy += tap * (at(x, y + d) - at(x, y - d));
    }
    (dx, dy)
}

/// Inverse of the symmetric positive definite P x P matrix in the first P² values (Cholesky);
/// None when it is not positive definite.
fn invert<const P: usize>(h: &[f64; 144]) -> Option<[f64; 144]> {
    let m = SMatrix::<f64, P, P>::from_fn(|r, c| h[r * P + c]);
    let inverse = m.cholesky()?.inverse();
    let mut out = [0.0; 144];
    for r in 0..P {
        for c in 0..P {
            out[r * P + c] = inverse[(r, c)];
        }
    }
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// For the IC-GN tests: images of one size with their B-spline coefficients, and reference
/// subsets prepared from them.
#[cfg(test)]
pub(crate) mod test_support {
    use super::*;
    use crate::icgn::Subset;

    /// The B-spline coefficients of a `size` x `size` image.
    pub fn coefficients(pixels: &[u16], size: usize) -> Coefficients {
        let mut c = Coefficients::new(size, size);
        c.prefilter(pixels);
        c
    }

    /// A reference and a deformed `size` x `size` image: the reference as an image, and both
    /// images' B-spline coefficients.
    pub fn pair<'a>(
        reference: &'a [u16],
        deformed: &[u16],
        size: usize,
    ) -> (Image<'a>, Coefficients, Coefficients) {
        let image = Image {
            pixels: reference,
            width_px: size,
            height_px: size,
        };
        let coefficients_of = |pixels| coefficients(pixels, size);
        (image, coefficients_of(reference), coefficients_of(deformed))
    }

    /// A reference subset's planes and statistics, owned.
    pub struct Prepared {
        planes: Vec<f32>,
        stats: SubsetStats,
        n: usize,
        centre_px: (f64, f64),
    }

    impl Prepared {
        /// The subset of side `n` at `top_left` of `reference`; panics if it cannot be prepared.
        pub fn new(
            reference: Image,
            coefficients: &Coefficients,
            top_left: (usize, usize),
            n: usize,
            order: Order,
        ) -> Self {
            let mut planes = vec![0.0; PLANES * n * n];
            let mut stats = SubsetStats::default();
            let spec = SubsetSpec {
                top_left_px: top_left,
                side_px: n,
                order,
            };
            assert!(prepare(
                reference,
                coefficients,
                spec,
                &mut planes,
                &mut stats
            ));
            let half = (n as f64 - 1.0) / 2.0;
            Self {
                planes,
                stats,
                n,
                centre_px: (top_left.0 as f64 + half, top_left.1 as f64 + half),
            }
        }

        pub fn subset(&self) -> Subset<'_> {
            Subset {
                planes: &self.planes,
                stats: &self.stats,
                n: self.n,
                centre_px: self.centre_px,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first order's row sums give the pixel-by-pixel sums within f32 rounding of the rows,
    /// at odd and even sizes.
    #[test]
    fn first_order_row_sums_are_the_pixel_sums() {
        for n in [9usize, 24, 33] {
            let nn = n * n;
            let plane = |a: f64, b: f64| -> Vec<f32> {
                (0..nn)
                    .map(|k| ((a * k as f64).sin() * 0.03 + b * (k % n) as f64 * 1e-3) as f32)
                    .collect()
            };
            let (values, gx, gy) = (plane(0.71, 0.2), plane(1.37, -0.5), plane(0.29, 0.8));
            let spec = SubsetSpec {
                top_left_px: (0, 0),
                side_px: n,
                order: Order::First,
            };
            let mut pixelwise = SubsetStats::default();
            let expected = steepest_descent_sums::<6>(spec, [&values, &gx, &gy], &mut pixelwise);
            let mut rows = SubsetStats::default();
            let found = super::super::first_order_sums::sums(
                n,
                [&values, &gx, &gy],
                &mut rows.sum_j,
                &mut rows.sum_jf,
            );
            let scale = expected.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for a in 0..6 {
                for b in a..6 {
                    let (e, f) = (expected[a * 6 + b], found[a * 6 + b]);
                    assert!(
                        (e - f).abs() <= 1e-5 * scale,
                        "n {n} H[{a}][{b}]: {f} vs {e}"
                    );
                }
                let sums = [
                    (pixelwise.sum_j[a], rows.sum_j[a]),
                    (pixelwise.sum_jf[a], rows.sum_jf[a]),
                ];
                for (e, f) in sums {
                    assert!(
                        (e - f).abs() <= 1e-5 * (e.abs() + 1e-3),
                        "n {n} {a}: {f} vs {e}"
                    );
                }
            }
            assert!(scale > 0.0);
        }
    }

    /// The block gradient is the per-pixel one, bit for bit, inside and at the borders.
    #[test]
    fn block_gradient_is_the_pixel_gradient() {
        let (w, h) = (40usize, 30usize);
        let pixels: Vec<u16> = (0..w * h)
            .map(|i| ((i * 7919) % 4093 + 100 * (i % w)) as u16)
            .collect();
        let image = Image {
            pixels: &pixels,
            width_px: w,
            height_px: h,
        };
        let n = 9;
        for top_left in [
            (10, 8),
            (0, 0),
            (w - n, h - n),
            (2, 3),
            (w - n - 3, h - n - 2),
        ] {
            let (mut gx, mut gy) = (vec![0.0; n * n], vec![0.0; n * n]);
            central_gradient_block(image, top_left, n, &mut gx, &mut gy);
            for j in 0..n {
                for i in 0..n {
                    let (dx, dy) = central_gradient(image, (top_left.0 + i, top_left.1 + j));
                    assert_eq!(gx[j * n + i].to_bits(), dx.to_bits(), "{top_left:?}");
                    assert_eq!(gy[j * n + i].to_bits(), dy.to_bits(), "{top_left:?}");
                }
            }
        }
    }
}
