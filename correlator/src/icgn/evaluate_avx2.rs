//! The AVX2 + FMA twin of [`super::evaluate_portable`]: one IC-GN evaluation of the deformed
//! subset (its B-spline samples through the warp and the sums of the ZNSSD update), the whole
//! loop in one `#[target_feature]` function so that every step inlines into it. The caller
//! checks [`available`] (once per evaluation: std caches the CPU's answer in an atomic).
//!
//! The subset's n² samples are taken 8 at a time in row-major order (chunks run across row
//! ends, so that 33 px costs 137 chunks, not 5 per row):
//! - positions in f64 (two 4-lane vectors per coordinate), their floor by truncation (the
//!   positions are checked ≥ 2 first) and fractional parts in f32, the coefficients' index in
//!   32-bit lanes; a chunk with a sample off the coefficients' fast path sends the whole
//!   evaluation back to the portable path (which handles the border and `outside_image`), as
//!   does a subset under 9 px (a chunk then crosses more than one row end);
//! - per sample, the 8-lane weights of the six taps (Horner in 8 lanes, taps in lanes 0..=5,
//!   lanes 6 and 7 zero), six unaligned 8-value coefficient row loads combined by the y weights
//!   (FMA), times the x weights; the 8 samples' vectors are summed across their lanes together
//!   (a tree of `hadd`, about one instruction per sample instead of six);
//! - the sums Σ g', Σ g'², Σ f̂ g' and Σ ∇f̂ g' times the offset monomials accumulate in
//!   8-lane f32 vectors, moved to f64 every [`FLUSH_CHUNKS`] chunks (64 samples: no longer
//!   f32 runs than the portable path's row sums).
//!
//! Only this module's pointer accesses are unsafe: the coefficient row loads, whose bounds
//! follow from the fast-path check (MARGIN_LOW <= floor < size − MARGIN_HIGH on both axes,
//! and the coefficients' 8 values of padding), and the 8-value loads of the reference planes
//! and local arrays, whose bounds are those of the slices they come from.

use super::bspline::{Coefficients, MARGIN_HIGH, MARGIN_LOW, TAPS};
use super::shape::{Order, Warp};
use super::{Subset, Sums};
pub use crate::simd_avx2::available;
use crate::simd_avx2::{load8, store8};
use std::arch::x86_64::{
    __m256, __m256d, _mm256_add_pd, _mm256_add_ps, _mm256_and_pd, _mm256_and_ps,
    _mm256_broadcast_ss, _mm256_castps256_ps128, _mm256_cmp_pd, _mm256_cmp_ps, _mm256_cvtepi32_pd,
    _mm256_cvtpd_ps, _mm256_cvtps_pd, _mm256_cvttpd_epi32, _mm256_extractf128_ps, _mm256_fmadd_pd,
    _mm256_fmadd_ps, _mm256_hadd_ps, _mm256_loadu_ps, _mm256_movemask_pd, _mm256_mul_pd,
    _mm256_mul_ps, _mm256_permute2f128_ps, _mm256_set1_pd, _mm256_set1_ps, _mm256_setr_ps,
    _mm256_setzero_pd, _mm256_setzero_ps, _mm256_storeu_pd, _mm256_sub_pd, _mm256_sub_ps,
    _mm_storeu_ps, _mm_storeu_si128, _CMP_GE_OQ, _CMP_LT_OQ,
};

/// 120 × the weights of the taps −2..=3 (lanes 0..=5; lanes 6 and 7 zero) as polynomials in
/// the fractional position t, `[power][lane]` (the rows of `bspline`'s LOW and HIGH tables
/// side by side). The two factors 1/120 are applied once to the 8 values of a chunk.
const POLY: [[f32; 8]; 6] = [
    [1.0, 26.0, 66.0, 26.0, 1.0, 0.0, 0.0, 0.0],
    [-5.0, -50.0, 0.0, 50.0, 5.0, 0.0, 0.0, 0.0],
    [10.0, 20.0, -60.0, 20.0, 10.0, 0.0, 0.0, 0.0],
    [-10.0, 20.0, 0.0, -20.0, 10.0, 0.0, 0.0, 0.0],
    [5.0, -20.0, 30.0, -20.0, 5.0, 0.0, 0.0, 0.0],
    [-1.0, 5.0, -10.0, 10.0, -5.0, 1.0, 0.0, 0.0],
];
const SCALE: f32 = 1.0 / (120.0 * 120.0);
/// Chunks of 8 samples summed in f32 before the sums move to f64.
pub const FLUSH_CHUNKS: usize = 8;
/// Sums kept: Σ g', Σ g'², Σ f̂ g', then Σ J g' (6 or 12).
const SUMS: usize = 15;

/// The sums of one evaluation, or None when a sample falls off the coefficients' fast path
/// (the caller then runs the portable evaluation, which handles the border).
///
/// # Safety
/// [`available`] returned true.
#[target_feature(enable = "avx2,fma")]
pub unsafe fn evaluate(
    subset: &Subset,
    order: Order,
    coefficients: &Coefficients,
    warp: &Warp,
) -> Option<Sums> {
    match order {
        Order::First => run::<false>(subset, coefficients, warp),
        Order::Second => run::<true>(subset, coefficients, warp),
    }
}

/// The weights (× 120) of the six taps at t, lanes 0..=5.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn weights(t: __m256) -> __m256 {
    let row = |p: usize| load8(&POLY[p]);
    // Written out: an iterator adapter is not inlined into a target-feature function.
    let mut w = _mm256_fmadd_ps(row(5), t, row(4));
    w = _mm256_fmadd_ps(w, t, row(3));
    w = _mm256_fmadd_ps(w, t, row(2));
    w = _mm256_fmadd_ps(w, t, row(1));
    _mm256_fmadd_ps(w, t, row(0))
}

/// The lane sums of eight vectors, in order.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn lane_sums(v: &[__m256; 8]) -> __m256 {
    let t0 = _mm256_hadd_ps(v[0], v[1]);
    let t1 = _mm256_hadd_ps(v[2], v[3]);
    let t2 = _mm256_hadd_ps(v[4], v[5]);
    let t3 = _mm256_hadd_ps(v[6], v[7]);
    // Per 128-bit half: the partial sums of vectors 0..=3 (u0) and 4..=7 (u1).
    let u0 = _mm256_hadd_ps(t0, t1);
    let u1 = _mm256_hadd_ps(t2, t3);
    _mm256_add_ps(
        _mm256_permute2f128_ps(u0, u1, 0x20),
        _mm256_permute2f128_ps(u0, u1, 0x31),
    )
}

/// The two f64 halves of 8 f32 lanes.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn widen(v: __m256) -> (__m256d, __m256d) {
    (
        _mm256_cvtps_pd(_mm256_castps256_ps128(v)),
        _mm256_cvtps_pd(_mm256_extractf128_ps(v, 1)),
    )
}

/// acc[0] += a, acc[1 + m] += a monomials[m].
#[target_feature(enable = "avx2,fma")]
#[inline]
fn accumulate<const M: usize>(acc: &mut [__m256], a: __m256, monomials: &[__m256; M]) {
    let acc = &mut acc[..M + 1];
    acc[0] = _mm256_add_ps(acc[0], a);
    for m in 0..M {
        acc[1 + m] = _mm256_fmadd_ps(a, monomials[m], acc[1 + m]);
    }
}

#[target_feature(enable = "avx2,fma")]
#[inline]
fn run<const SECOND: bool>(subset: &Subset, c: &Coefficients, warp: &Warp) -> Option<Sums> {
    let n = subset.n;
    let nn = n * n;
    let (values, rest) = subset.planes.split_at(nn);
    let (gx, gy) = rest.split_at(nn);
    let p = &warp.p;
    let half = (n as f64 - 1.0) / 2.0;
    let (cx, cy) = subset.centre_px;
    let (w, h) = (c.width_px, c.height_px);
    let data = &c.data[..];
    // Floors in 32-bit lanes; chunks cross at most one row end.
    let small = w <= MARGIN_LOW + MARGIN_HIGH || h <= MARGIN_LOW + MARGIN_HIGH;
    if n < 9 || small || w.max(h) >= i32::MAX as usize {
        return None;
    }
    // The fast path: MARGIN_LOW <= x < w − MARGIN_HIGH, the same for y; every row load then
    // reads data[(iy − 2) w + ix − 2 + r w .. + 8], r < 6, inside the buffer (w h + 8 values).
    assert!(data.len() >= w * h + 8);
    let (x_low, x_high) = (
        _mm256_set1_pd(MARGIN_LOW as f64),
        _mm256_set1_pd((w - MARGIN_HIGH) as f64),
    );
    let y_high = _mm256_set1_pd((h - MARGIN_HIGH) as f64);
    let pd = |v: f64| _mm256_set1_pd(v);
    // x = cx + dx + u + u_x dx + u_y dy (+ ½ u_xx dx² + u_xy dx dy + ½ u_yy dy²), the same for y.
    let (x0, x_dx, x_dy) = (pd(cx + p[0]), pd(1.0 + p[1]), pd(p[2]));
    let (y0, y_dx, y_dy) = (pd(cy + p[6]), pd(p[7]), pd(1.0 + p[8]));
    let (x_xx, x_xy, x_yy) = (pd(0.5 * p[3]), pd(p[4]), pd(0.5 * p[5]));
    let (y_xx, y_xy, y_yy) = (pd(0.5 * p[9]), pd(p[10]), pd(0.5 * p[11]));
    let mean = _mm256_set1_ps(subset.stats.mean);
    let scale = _mm256_set1_ps(SCALE);
    let base = data.as_ptr();

    let mut acc = [_mm256_setzero_ps(); SUMS];
    let mut total = [[_mm256_setzero_pd(); 2]; SUMS];
    let terms = if SECOND { 15 } else { 9 };
    // Column, row and row-major index of each lane's sample (exact in f32 below 2^24);
    // lanes past n² are masked (zero bits) and sit at the subset centre.
    let ps = |v: f32| _mm256_set1_ps(v);
    let (n_v, nn_v, half_v, eight) = (ps(n as f32), ps(nn as f32), ps(half as f32), ps(8.0));
    let mut column = _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0);
    let mut row = _mm256_setzero_ps();
    let mut index = column;
    let chunks = nn.div_ceil(8);
    for chunk in 0..chunks {
        let k = 8 * chunk;
        let count = (nn - k).min(8);
        let valid = _mm256_cmp_ps::<_CMP_LT_OQ>(index, nn_v);
        let dxv = _mm256_and_ps(_mm256_sub_ps(column, half_v), valid);
        let dyv = _mm256_and_ps(_mm256_sub_ps(row, half_v), valid);
        // The next chunk: 8 samples on, at most one row end crossed (n >= 9).
        index = _mm256_add_ps(index, eight);
        column = _mm256_add_ps(column, eight);
        let wrap = _mm256_cmp_ps::<_CMP_GE_OQ>(column, n_v);
        column = _mm256_sub_ps(column, _mm256_and_ps(wrap, n_v));
        row = _mm256_add_ps(row, _mm256_and_ps(wrap, ps(1.0)));
        let ((dx0, dx1), (dy0, dy1)) = (widen(dxv), widen(dyv));
        let mut ix = [0i32; 8];
        let mut iy = [0i32; 8];
        let mut tx = [0.0f32; 8];
        let mut ty = [0.0f32; 8];
        for half_index in 0..2 {
            let (a, b) = if half_index == 0 {
                (dx0, dy0)
            } else {
                (dx1, dy1)
            };
            let mut x = _mm256_fmadd_pd(x_dy, b, _mm256_fmadd_pd(x_dx, a, x0));
            let mut y = _mm256_fmadd_pd(y_dy, b, _mm256_fmadd_pd(y_dx, a, y0));
            if SECOND {
                let (aa, ab, bb) = (
                    _mm256_mul_pd(a, a),
                    _mm256_mul_pd(a, b),
                    _mm256_mul_pd(b, b),
                );
                x = _mm256_fmadd_pd(
                    x_xx,
                    aa,
                    _mm256_fmadd_pd(x_xy, ab, _mm256_fmadd_pd(x_yy, bb, x)),
                );
                y = _mm256_fmadd_pd(
                    y_xx,
                    aa,
                    _mm256_fmadd_pd(y_xy, ab, _mm256_fmadd_pd(y_yy, bb, y)),
                );
            }
            let inside = _mm256_and_pd(
                _mm256_and_pd(
                    _mm256_cmp_pd::<_CMP_GE_OQ>(x, x_low),
                    _mm256_cmp_pd::<_CMP_LT_OQ>(x, x_high),
                ),
                _mm256_and_pd(
                    _mm256_cmp_pd::<_CMP_GE_OQ>(y, x_low),
                    _mm256_cmp_pd::<_CMP_LT_OQ>(y, y_high),
                ),
            );
            if _mm256_movemask_pd(inside) != 0b1111 {
                return None;
            }
            // Positive positions: truncation is the floor.
            let (fx, fy) = (_mm256_cvttpd_epi32(x), _mm256_cvttpd_epi32(y));
            let (fracx, fracy) = (
                _mm256_cvtpd_ps(_mm256_sub_pd(x, _mm256_cvtepi32_pd(fx))),
                _mm256_cvtpd_ps(_mm256_sub_pd(y, _mm256_cvtepi32_pd(fy))),
            );
            let at = 4 * half_index;
            // SAFETY: each store writes 16 bytes into a 4-element range of an 8-element local
            // array (at ∈ {0, 4}).
            unsafe {
                _mm_storeu_si128(ix[at..at + 4].as_mut_ptr().cast(), fx);
                _mm_storeu_si128(iy[at..at + 4].as_mut_ptr().cast(), fy);
                _mm_storeu_ps(tx[at..at + 4].as_mut_ptr(), fracx);
                _mm_storeu_ps(ty[at..at + 4].as_mut_ptr(), fracy);
            }
        }
        let mut partial = [_mm256_setzero_ps(); 8];
        for l in 0..8 {
            let wx = weights(_mm256_broadcast_ss(&tx[l]));
            let mut wy = [0.0f32; 8];
            store8(weights(_mm256_broadcast_ss(&ty[l])), &mut wy);
            // The fast-path check above: 2 <= ix < w − 4 and 2 <= iy < h − 4.
            let start = (iy[l] as usize - MARGIN_LOW) * w + ix[l] as usize - MARGIN_LOW;
            debug_assert!(start + (TAPS - 1) * w + 8 <= data.len());
            // SAFETY: start + r w + 8 <= (h − 7) w + w − 7 + 5 w + 8 <= w h + 8 <= data.len()
            // for r < TAPS (the fast-path check and the asserts before the loop).
            let row_at = |r: usize| unsafe { _mm256_loadu_ps(base.add(start + r * w)) };
            // Written out: an iterator adapter is not inlined into a target-feature function.
            let mut sum = _mm256_mul_ps(_mm256_broadcast_ss(&wy[0]), row_at(0));
            sum = _mm256_fmadd_ps(_mm256_broadcast_ss(&wy[1]), row_at(1), sum);
            sum = _mm256_fmadd_ps(_mm256_broadcast_ss(&wy[2]), row_at(2), sum);
            sum = _mm256_fmadd_ps(_mm256_broadcast_ss(&wy[3]), row_at(3), sum);
            sum = _mm256_fmadd_ps(_mm256_broadcast_ss(&wy[4]), row_at(4), sum);
            sum = _mm256_fmadd_ps(_mm256_broadcast_ss(&wy[TAPS - 1]), row_at(TAPS - 1), sum);
            partial[l] = _mm256_mul_ps(sum, wx);
        }
        // g' = g − f_m, zero in the lanes past n².
        let g = _mm256_and_ps(
            _mm256_sub_ps(_mm256_mul_ps(lane_sums(&partial), scale), mean),
            valid,
        );
        let (f, fx, fy) = if count == 8 {
            (load8(&values[k..]), load8(&gx[k..]), load8(&gy[k..]))
        } else {
            let pad = |plane: &[f32]| {
                let mut lanes = [0.0f32; 8];
                lanes[..count].copy_from_slice(&plane[k..k + count]);
                load8(&lanes)
            };
            (pad(values), pad(gx), pad(gy))
        };
        acc[0] = _mm256_add_ps(acc[0], g);
        acc[1] = _mm256_fmadd_ps(g, g, acc[1]);
        acc[2] = _mm256_fmadd_ps(f, g, acc[2]);
        let (ax, ay) = (_mm256_mul_ps(fx, g), _mm256_mul_ps(fy, g));
        if SECOND {
            let half_v = _mm256_set1_ps(0.5);
            let xx = _mm256_mul_ps(_mm256_mul_ps(dxv, dxv), half_v);
            let xy = _mm256_mul_ps(dxv, dyv);
            let yy = _mm256_mul_ps(_mm256_mul_ps(dyv, dyv), half_v);
            let monomials = [dxv, dyv, xx, xy, yy];
            accumulate(&mut acc[3..9], ax, &monomials);
            accumulate(&mut acc[9..15], ay, &monomials);
        } else {
            let monomials = [dxv, dyv];
            accumulate(&mut acc[3..6], ax, &monomials);
            accumulate(&mut acc[6..9], ay, &monomials);
        }
        if (chunk + 1) % FLUSH_CHUNKS == 0 || chunk + 1 == chunks {
            for t in 0..terms {
                let (low, high) = widen(acc[t]);
                total[t][0] = _mm256_add_pd(total[t][0], low);
                total[t][1] = _mm256_add_pd(total[t][1], high);
                acc[t] = _mm256_setzero_ps();
            }
        }
    }
    let mut sums = [0.0f64; SUMS];
    for (s, t) in sums.iter_mut().zip(&total).take(terms) {
        let mut lanes = [0.0f64; 4];
        // SAFETY: writes the 32 bytes of a local [f64; 4].
        unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), _mm256_add_pd(t[0], t[1])) };
        *s = (lanes[0] + lanes[2]) + (lanes[1] + lanes[3]);
    }
    let mut out = Sums {
        g: sums[0],
        gg: sums[1],
        fg: sums[2],
        jg: [0.0; 12],
    };
    out.jg[..terms - 3].copy_from_slice(&sums[3..terms]);
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::super::subset::test_support::{coefficients, Prepared};
    use super::super::{evaluate_portable, Sums};
    use super::*;
    use crate::verify::tests::texture;
    use crate::zoi::Image;

    /// The largest difference between two evaluations' sums, relative to the scale of each
    /// kind of sum (Σ g'² for Σ g' and Σ g'², and its square root for the sums with f̂, whose
    /// norm is 1).
    fn difference(a: &Sums, b: &Sums) -> f64 {
        let scale_g = b.gg.abs().max(1.0);
        let scale_j = scale_g.sqrt();
        let mut worst = ((a.g - b.g).abs() / scale_g).max((a.gg - b.gg).abs() / scale_g);
        worst = worst.max((a.fg - b.fg).abs() / scale_j);
        for (x, y) in a.jg.iter().zip(&b.jg) {
            worst = worst.max((x - y).abs() / scale_j);
        }
        worst
    }

    /// On this CPU (when it has AVX2 and FMA) the kernel gives the portable path's sums
    /// within f32 rounding, for both orders, odd and even sizes (chunks of 8 across row ends
    /// and a partial last chunk), arbitrary warps; off the fast path it declines, and the
    /// portable path takes over.
    #[test]
    fn the_kernel_matches_the_portable_path() {
        if !available() {
            println!("no AVX2 + FMA: nothing to compare");
            return;
        }
        let size = 120usize;
        let reference: Vec<u16> = (0..size * size)
            .map(|i| texture((i % size) as f64, (i / size) as f64) as u16)
            .collect();
        let deformed: Vec<u16> = (0..size * size)
            .map(|i| {
                (0.9 * texture((i % size) as f64 - 0.37, (i / size) as f64 + 0.21) + 700.0) as u16
            })
            .collect();
        let (cr, cd) = (
            coefficients(&reference, size),
            coefficients(&deformed, size),
        );
        let image = Image {
            pixels: &reference,
            width_px: size,
            height_px: size,
        };
        let mut worst = 0.0f64;
        let mut compared = 0;
        for order in [Order::First, Order::Second] {
            for n in [9usize, 10, 24, 33, 41] {
                let top_left = (40usize, 37usize);
                let prepared = Prepared::new(image, &cr, top_left, n, order);
                let subset = prepared.subset();
                for case in 0..12 {
                    let s = case as f64;
                    let mut warp = Warp::affine(
                        (0.37 + 0.731 * s - 4.0, -0.21 - 0.577 * s + 3.0),
                        [
                            [0.01 * (s - 5.0), -0.007 * s],
                            [0.004 * s, -0.02 + 0.003 * s],
                        ],
                    );
                    if order == Order::Second {
                        for (i, q) in [3usize, 4, 5, 9, 10, 11].into_iter().enumerate() {
                            warp.p[q] = 1e-3 * ((i as f64 + s) * 1.7).sin();
                        }
                    }
                    let portable = evaluate_portable(&subset, order, &cd, &warp).unwrap();
                    // SAFETY: `available` returned true above.
                    let fast = unsafe { evaluate(&subset, order, &cd, &warp) }
                        .expect("the subset lies on the fast path");
                    let d = difference(&fast, &portable);
                    assert!(
                        d < 2e-5,
                        "{order:?} n {n} case {case}: {d}\n{fast:?}\n{portable:?}"
                    );
                    worst = worst.max(d);
                    compared += 1;
                }
                // Near the border: the kernel declines, the portable path still samples.
                let border = Warp::affine((1.5 - top_left.0 as f64, 0.0), [[0.0; 2]; 2]);
                // SAFETY: as above.
                assert!(unsafe { evaluate(&subset, order, &cd, &border) }.is_none());
                assert!(evaluate_portable(&subset, order, &cd, &border).is_some());
                let outside = Warp::affine((f64::NAN, 0.0), [[0.0; 2]; 2]);
                // SAFETY: as above.
                assert!(unsafe { evaluate(&subset, order, &cd, &outside) }.is_none());
            }
        }
        println!("{compared} evaluations, largest relative difference {worst:.2e}");
    }
}
