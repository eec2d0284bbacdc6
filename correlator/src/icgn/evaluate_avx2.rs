//! The AVX2 + FMA twin of [`super::evaluate_portable`]: one IC-GN evaluation of the deformed
//! subset (its B-spline samples through the warp and the sums of the ZNSSD update), the whole
//! loop in one `#[target_feature]` function so that every step inlines into it. The caller
//! checks [`available`] (once per evaluation: std caches the CPU's answer in an atomic).
//!
//! The subset's samples are taken 8 at a time along each row (chunks of 8 consecutive pixels
//! of one row, the last one of a row partial, its missing lanes masked):
//! - positions in f64 (two 4-lane vectors per coordinate), their floor by truncation (the
//!   positions are checked ≥ 2 first) and fractional parts in f32, the coefficients' index in
//!   32-bit lanes; a chunk with a sample off the coefficients' fast path sends the whole
//!   evaluation back to the portable path (which handles the border and `outside_image`);
//! - **samples in lanes** ([`taps_in_lanes`]) when the chunk's floors are lane 0's plus the
//!   lane index, give or take one pixel on each axis (on a near-translation warp, every chunk
//!   but the few where a row's fractional positions wrap; any warp whose gradient is below
//!   1/7): the 8 samples' weights of each tap as one 8-lane vector (Horner per tap), and each
//!   tap's 8 coefficients are one unaligned load, contiguous in the row; 6 x 6 taps, or 7 on
//!   an axis whose floors differ by one across the chunk (a lane one pixel on takes the
//!   weights shifted by one tap). About 170 instructions per chunk instead of 40 per sample;
//! - otherwise, and for chunks of fewer than [`MIN_LANES`] samples, **taps in lanes**
//!   ([`sample_by_sample`]): per sample, the 8-lane weights of the six taps (taps in lanes
//!   0..=5, lanes 6 and 7 zero), six unaligned 8-value coefficient row loads combined by the
//!   y weights (FMA), times the x weights; the chunk's vectors summed across their lanes
//!   together (a tree of `hadd`);
//! - the sums Σ g', Σ g'², Σ f̂ g' and Σ ∇f̂ g' times the offset monomials accumulate in
//!   8-lane f32 vectors, moved to f64 every [`FLUSH_CHUNKS`] chunks (at most 64 samples: no
//!   longer f32 runs than the portable path's row sums).
//!
//! Only this module's pointer accesses are unsafe: the coefficient loads, whose bounds follow
//! from the fast-path check (MARGIN_LOW <= floor < size − MARGIN_HIGH on both axes, and the
//! coefficients' 8 values of padding) or, with samples in lanes, from an explicit check of the
//! chunk's first and last load, and the 8-value loads of the reference planes and local
//! arrays, whose bounds are those of the slices they come from.

use super::bspline::{Coefficients, MARGIN_HIGH, MARGIN_LOW, TAPS};
use super::shape::{Order, Warp};
use super::{Subset, Sums};
pub use crate::simd_avx2::available;
use crate::simd_avx2::{load8, store8};
use std::arch::x86_64::{
    __m256, __m256d, __m256i, _mm256_add_pd, _mm256_add_ps, _mm256_and_pd, _mm256_and_ps,
    _mm256_blendv_ps, _mm256_broadcast_ss, _mm256_castps256_ps128, _mm256_castps_si256,
    _mm256_castsi256_ps, _mm256_castsi256_si128, _mm256_cmp_pd, _mm256_cmp_ps, _mm256_cmpgt_epi32,
    _mm256_cvtepi32_pd, _mm256_cvtpd_ps, _mm256_cvtps_pd, _mm256_cvttpd_epi32,
    _mm256_extractf128_ps, _mm256_extracti128_si256, _mm256_fmadd_pd, _mm256_fmadd_ps,
    _mm256_hadd_ps, _mm256_loadu_ps, _mm256_movemask_pd, _mm256_mul_pd, _mm256_mul_ps,
    _mm256_permute2f128_ps, _mm256_permutevar8x32_epi32, _mm256_set1_epi32, _mm256_set1_pd,
    _mm256_set1_ps, _mm256_set_m128, _mm256_set_m128i, _mm256_setr_epi32, _mm256_setr_ps,
    _mm256_setzero_pd, _mm256_setzero_ps, _mm256_setzero_si256, _mm256_storeu_pd,
    _mm256_storeu_si256, _mm256_sub_epi32, _mm256_sub_pd, _mm256_sub_ps, _mm_cvtsi128_si32,
    _mm_max_epi32, _mm_min_epi32, _mm_shuffle_epi32, _CMP_GE_OQ, _CMP_LT_OQ,
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
/// Chunks of up to 8 samples summed in f32 before the sums move to f64.
pub const FLUSH_CHUNKS: usize = 8;
/// Sums kept: Σ g', Σ g'², Σ f̂ g', then Σ J g' (6 or 12).
const SUMS: usize = 15;
/// A chunk of fewer samples (a row's last) is evaluated sample by sample: samples in lanes
/// cost the same for 1 sample as for 8.
pub const MIN_LANES: usize = 4;
/// Taps per axis with samples in lanes when the chunk's floors differ by one on that axis.
const WIDE: usize = TAPS + 1;

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

/// The smallest and largest of 8 i32 lanes.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn lane_range(v: __m256i) -> (i32, i32) {
    let (low, high) = (_mm256_castsi256_si128(v), _mm256_extracti128_si256::<1>(v));
    let (mut min, mut max) = (_mm_min_epi32(low, high), _mm_max_epi32(low, high));
    min = _mm_min_epi32(min, _mm_shuffle_epi32::<0b01_00_11_10>(min));
    max = _mm_max_epi32(max, _mm_shuffle_epi32::<0b01_00_11_10>(max));
    min = _mm_min_epi32(min, _mm_shuffle_epi32::<0b10_11_00_01>(min));
    max = _mm_max_epi32(max, _mm_shuffle_epi32::<0b10_11_00_01>(max));
    (_mm_cvtsi128_si32(min), _mm_cvtsi128_si32(max))
}

/// The weights (× 120) of the six taps for the fractional positions `t` of 8 samples, one
/// vector per tap, and a seventh (zero) for [`WIDE`]: the polynomials of [`POLY`] by Horner,
/// per tap (the same operations as [`weights`], so the same f32 values).
#[target_feature(enable = "avx2,fma")]
#[inline]
#[allow(clippy::needless_range_loop)]
fn tap_weights(t: __m256) -> [__m256; WIDE] {
    let mut w = [_mm256_setzero_ps(); WIDE];
    // Plain index loops: an iterator adapter is not inlined into a target-feature function.
    for tap in 0..TAPS {
        let c = |p: usize| _mm256_set1_ps(POLY[p][tap]);
        let mut v = _mm256_fmadd_ps(c(5), t, c(4));
        v = _mm256_fmadd_ps(v, t, c(3));
        v = _mm256_fmadd_ps(v, t, c(2));
        v = _mm256_fmadd_ps(v, t, c(1));
        w[tap] = _mm256_fmadd_ps(v, t, c(0));
    }
    w
}

/// [`tap_weights`] of a [`WIDE`] axis: where `one_on` is set (the lane's floor is one past
/// the chunk's), tap k takes the weight of tap k − 1.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn widen_taps(w: [__m256; WIDE], one_on: __m256) -> [__m256; WIDE] {
    let mut out = w;
    for k in 0..WIDE {
        let before = if k == 0 {
            _mm256_setzero_ps()
        } else {
            w[k - 1]
        };
        out[k] = _mm256_blendv_ps(w[k], before, one_on);
    }
    out
}

/// Σ_r wy[r] Σ_c wx[c] (the 8 coefficients from `start` + r w + c), TX x TY taps.
///
/// # Safety
/// Every load reads inside `data`: start + (TY − 1) w + TX − 1 + 8 <= data.len().
#[target_feature(enable = "avx2,fma")]
#[inline]
#[allow(clippy::needless_range_loop)]
unsafe fn tap_sum<const TX: usize, const TY: usize>(
    data: &[f32],
    start: usize,
    w: usize,
    wx: &[__m256; WIDE],
    wy: &[__m256; WIDE],
) -> __m256 {
    let base = data.as_ptr();
    let mut value = _mm256_setzero_ps();
    // Plain index loops: an iterator adapter is not inlined into a target-feature function.
    for r in 0..TY {
        // SAFETY: the caller's bound.
        let at = |c: usize| unsafe { _mm256_loadu_ps(base.add(start + r * w + c)) };
        let mut row = _mm256_mul_ps(wx[0], at(0));
        for c in 1..TX {
            row = _mm256_fmadd_ps(wx[c], at(c), row);
        }
        value = _mm256_fmadd_ps(wy[r], row, value);
    }
    value
}

/// One chunk's floors and fractional positions, per lane (lanes past the chunk's samples: 0).
struct Lanes {
    ix: __m256i,
    iy: __m256i,
    tx: __m256,
    ty: __m256,
}

/// The values (× 120²) of the chunk's samples with the samples in lanes (module
/// documentation), or None when its floors are not lane 0's plus the lane index within one
/// pixel per axis, or a load would leave the coefficients.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn taps_in_lanes(data: &[f32], w: usize, lanes: &Lanes, valid: __m256) -> Option<__m256> {
    let index = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    // The lanes past the chunk's samples take lane 0's floors.
    let keep = |v: __m256i| {
        let lane0 = _mm256_castsi256_ps(_mm256_permutevar8x32_epi32(v, _mm256_setzero_si256()));
        _mm256_castps_si256(_mm256_blendv_ps(lane0, _mm256_castsi256_ps(v), valid))
    };
    let rel_x = keep(_mm256_sub_epi32(lanes.ix, index));
    let rel_y = keep(lanes.iy);
    let ((x0, x1), (y0, y1)) = (lane_range(rel_x), lane_range(rel_y));
    if x1 - x0 > 1 || y1 - y0 > 1 || x0 < MARGIN_LOW as i32 || y0 < MARGIN_LOW as i32 {
        return None;
    }
    let (wide_x, wide_y) = (x1 > x0, y1 > y0);
    let start = (y0 as usize - MARGIN_LOW) * w + x0 as usize - MARGIN_LOW;
    // The last load: row WIDE − 1, tap WIDE − 1, 8 values.
    if start + (WIDE - 1) * w + WIDE - 1 + 8 > data.len() {
        return None;
    }
    let one_on = |rel: __m256i, low: i32| {
        _mm256_castsi256_ps(_mm256_cmpgt_epi32(rel, _mm256_set1_epi32(low)))
    };
    let mut wx = tap_weights(lanes.tx);
    let mut wy = tap_weights(lanes.ty);
    if wide_x {
        wx = widen_taps(wx, one_on(rel_x, x0));
    }
    if wide_y {
        wy = widen_taps(wy, one_on(rel_y, y0));
    }
    // SAFETY: the loads of the widest case end at the bound checked above.
    Some(unsafe {
        match (wide_x, wide_y) {
            (false, false) => tap_sum::<TAPS, TAPS>(data, start, w, &wx, &wy),
            (true, false) => tap_sum::<WIDE, TAPS>(data, start, w, &wx, &wy),
            (false, true) => tap_sum::<TAPS, WIDE>(data, start, w, &wx, &wy),
            (true, true) => tap_sum::<WIDE, WIDE>(data, start, w, &wx, &wy),
        }
    })
}

/// The values (× 120²) of the chunk's first `count` samples one by one (module
/// documentation), zero in the other lanes. Every one of them is on the fast path.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn sample_by_sample(data: &[f32], w: usize, lanes: &Lanes, count: usize) -> __m256 {
    let mut ix = [0i32; 8];
    let mut iy = [0i32; 8];
    let mut tx = [0.0f32; 8];
    let mut ty = [0.0f32; 8];
    // SAFETY: each store writes the 32 bytes of a local 8-element array.
    unsafe {
        _mm256_storeu_si256(ix.as_mut_ptr().cast(), lanes.ix);
        _mm256_storeu_si256(iy.as_mut_ptr().cast(), lanes.iy);
    }
    store8(lanes.tx, &mut tx);
    store8(lanes.ty, &mut ty);
    let base = data.as_ptr();
    let mut partial = [_mm256_setzero_ps(); 8];
    for l in 0..count {
        let wx = weights(_mm256_broadcast_ss(&tx[l]));
        let mut wy = [0.0f32; 8];
        store8(weights(_mm256_broadcast_ss(&ty[l])), &mut wy);
        // The fast-path check: 2 <= ix < w − 4 and 2 <= iy < h − 4.
        let start = (iy[l] as usize - MARGIN_LOW) * w + ix[l] as usize - MARGIN_LOW;
        debug_assert!(start + (TAPS - 1) * w + 8 <= data.len());
        // SAFETY: start + r w + 8 <= (h − 7) w + w − 7 + 5 w + 8 <= w h + 8 <= data.len()
        // for r < TAPS (the fast-path check and the asserts of `run`).
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
    lane_sums(&partial)
}

/// The floors and fractional positions of the 8 lanes at offsets (dx, dy) from the subset
/// centre through the warp; None when a lane of `valid_lanes` (a bit per lane) is off the
/// coefficients' fast path.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn positions<const SECOND: bool>(
    warp: &LaneWarp,
    dx: (__m256d, __m256d),
    dy: __m256d,
    valid_lanes: i32,
) -> Option<Lanes> {
    let mut floors = [[_mm256_castsi256_si128(_mm256_setzero_si256()); 2]; 2];
    let mut fractions = [[_mm256_castps256_ps128(_mm256_setzero_ps()); 2]; 2];
    for half_index in 0..2 {
        let (a, b) = (if half_index == 0 { dx.0 } else { dx.1 }, dy);
        let mut x = _mm256_fmadd_pd(warp.x_dy, b, _mm256_fmadd_pd(warp.x_dx, a, warp.x0));
        let mut y = _mm256_fmadd_pd(warp.y_dy, b, _mm256_fmadd_pd(warp.y_dx, a, warp.y0));
        if SECOND {
            let (aa, ab, bb) = (
                _mm256_mul_pd(a, a),
                _mm256_mul_pd(a, b),
                _mm256_mul_pd(b, b),
            );
            x = _mm256_fmadd_pd(
                warp.x_xx,
                aa,
                _mm256_fmadd_pd(warp.x_xy, ab, _mm256_fmadd_pd(warp.x_yy, bb, x)),
            );
            y = _mm256_fmadd_pd(
                warp.y_xx,
                aa,
                _mm256_fmadd_pd(warp.y_xy, ab, _mm256_fmadd_pd(warp.y_yy, bb, y)),
            );
        }
        let inside = _mm256_and_pd(
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GE_OQ>(x, warp.low),
                _mm256_cmp_pd::<_CMP_LT_OQ>(x, warp.x_high),
            ),
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GE_OQ>(y, warp.low),
                _mm256_cmp_pd::<_CMP_LT_OQ>(y, warp.y_high),
            ),
        );
        let required = (valid_lanes >> (4 * half_index)) & 0b1111;
        if _mm256_movemask_pd(inside) & required != required {
            return None;
        }
        // Positive positions: truncation is the floor (in the lanes checked).
        let (fx, fy) = (_mm256_cvttpd_epi32(x), _mm256_cvttpd_epi32(y));
        floors[0][half_index] = fx;
        floors[1][half_index] = fy;
        fractions[0][half_index] = _mm256_cvtpd_ps(_mm256_sub_pd(x, _mm256_cvtepi32_pd(fx)));
        fractions[1][half_index] = _mm256_cvtpd_ps(_mm256_sub_pd(y, _mm256_cvtepi32_pd(fy)));
    }
    Some(Lanes {
        ix: _mm256_set_m128i(floors[0][1], floors[0][0]),
        iy: _mm256_set_m128i(floors[1][1], floors[1][0]),
        tx: _mm256_set_m128(fractions[0][1], fractions[0][0]),
        ty: _mm256_set_m128(fractions[1][1], fractions[1][0]),
    })
}

/// The warp's terms in 4 f64 lanes: x = x0 + x_dx dx + x_dy dy (+ x_xx dx² + x_xy dx dy +
/// x_yy dy²), the same for y; and the fast path's bounds.
struct LaneWarp {
    x0: __m256d,
    x_dx: __m256d,
    x_dy: __m256d,
    y0: __m256d,
    y_dx: __m256d,
    y_dy: __m256d,
    x_xx: __m256d,
    x_xy: __m256d,
    x_yy: __m256d,
    y_xx: __m256d,
    y_xy: __m256d,
    y_yy: __m256d,
    low: __m256d,
    x_high: __m256d,
    y_high: __m256d,
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
    // Floors in 32-bit lanes.
    let small = w <= MARGIN_LOW + MARGIN_HIGH || h <= MARGIN_LOW + MARGIN_HIGH;
    if small || w.max(h) >= i32::MAX as usize {
        return None;
    }
    // The fast path: MARGIN_LOW <= x < w − MARGIN_HIGH, the same for y; every row load of
    // `sample_by_sample` then reads data[(iy − 2) w + ix − 2 + r w .. + 8], r < 6, inside the
    // buffer (w h + 8 values).
    assert!(data.len() >= w * h + 8);
    let pd = |v: f64| _mm256_set1_pd(v);
    let lane_warp = LaneWarp {
        x0: pd(cx + p[0]),
        x_dx: pd(1.0 + p[1]),
        x_dy: pd(p[2]),
        y0: pd(cy + p[6]),
        y_dx: pd(p[7]),
        y_dy: pd(1.0 + p[8]),
        x_xx: pd(0.5 * p[3]),
        x_xy: pd(p[4]),
        x_yy: pd(0.5 * p[5]),
        y_xx: pd(0.5 * p[9]),
        y_xy: pd(p[10]),
        y_yy: pd(0.5 * p[11]),
        low: pd(MARGIN_LOW as f64),
        x_high: pd((w - MARGIN_HIGH) as f64),
        y_high: pd((h - MARGIN_HIGH) as f64),
    };
    let mean = _mm256_set1_ps(subset.stats.mean);
    let scale = _mm256_set1_ps(SCALE);

    let mut acc = [_mm256_setzero_ps(); SUMS];
    let mut total = [[_mm256_setzero_pd(); 2]; SUMS];
    let terms = if SECOND { 15 } else { 9 };
    let ps = |v: f32| _mm256_set1_ps(v);
    let lane_index = _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0);
    let chunks = n * n.div_ceil(8);
    let mut chunk = 0;
    for j in 0..n {
        let dy = j as f64 - half;
        let dy_lanes = pd(dy);
        // A plain loop: an iterator adapter is not inlined into a target-feature function.
        let mut i0 = 0;
        while i0 < n {
            let k = j * n + i0;
            let count = (n - i0).min(8);
            let valid = _mm256_cmp_ps::<_CMP_LT_OQ>(lane_index, ps(count as f32));
            // Offsets from the subset centre (exact in f32: half-integers below 2^23); the
            // lanes past the row's end continue it, their samples unused.
            let dx_lanes = _mm256_add_ps(lane_index, ps((i0 as f64 - half) as f32));
            let lanes =
                positions::<SECOND>(&lane_warp, widen(dx_lanes), dy_lanes, (1 << count) - 1)?;
            let lanes = Lanes {
                tx: _mm256_and_ps(lanes.tx, valid),
                ty: _mm256_and_ps(lanes.ty, valid),
                ..lanes
            };
            let sampled = if count >= MIN_LANES {
                taps_in_lanes(data, w, &lanes, valid)
            } else {
                None
            };
            let sampled = sampled.unwrap_or_else(|| sample_by_sample(data, w, &lanes, count));
            // g' = g − f_m, zero in the lanes past the row.
            let g = _mm256_and_ps(_mm256_sub_ps(_mm256_mul_ps(sampled, scale), mean), valid);
            let (dxv, dyv) = (
                _mm256_and_ps(dx_lanes, valid),
                _mm256_and_ps(ps(dy as f32), valid),
            );
            let (f, fx, fy) = if k + 8 <= nn {
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
            chunk += 1;
            i0 += 8;
            if chunk % FLUSH_CHUNKS == 0 || chunk == chunks {
                for t in 0..terms {
                    let (low, high) = widen(acc[t]);
                    total[t][0] = _mm256_add_pd(total[t][0], low);
                    total[t][1] = _mm256_add_pd(total[t][1], high);
                    acc[t] = _mm256_setzero_ps();
                }
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
    use super::super::subset::test_support::{pair, Prepared};
    use super::super::{evaluate_portable, Sums};
    use super::*;
    use crate::verify::tests::texture;
    use std::arch::x86_64::_mm256_loadu_si256;

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
        let (image, cr, cd) = pair(&reference, &deformed, size);
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

    /// Samples in lanes give the sample-by-sample values within f32 rounding on chunks whose
    /// floors differ from lane 0's plus the lane index by 0 or 1 on either axis (the four
    /// tap counts), and decline a chunk whose floors spread further.
    #[test]
    fn samples_in_lanes_are_the_samples_one_by_one() {
        if !available() {
            println!("no AVX2 + FMA: nothing to compare");
            return;
        }
        let (w, h) = (64usize, 48usize);
        let pixels: Vec<u16> = (0..w * h)
            .map(|i| texture((i % w) as f64, (i / w) as f64) as u16)
            .collect();
        let mut c = Coefficients::new(w, h);
        c.prefilter(&pixels);
        let mut taken = [0usize; 4];
        for case in 0..400 {
            let s = case as f64;
            // Lane k at (x0 + k (1 + gx), y0 + k gy): gradients up to ±0.14 (spreads of 0 or
            // 1 px over the chunk) and, one case in ten, 0.4 (declined).
            let (gx, gy) = if case % 10 == 9 {
                (0.4, -0.4)
            } else {
                (0.14 * (0.37 * s).sin(), 0.14 * (0.53 * s).cos())
            };
            let (x0, y0) = (10.0 + (s * 0.731) % 30.0, 8.0 + (s * 0.577) % 25.0);
            let mut x = [0.0f32; 8];
            let mut ix = [0i32; 8];
            let mut y = [0.0f32; 8];
            let mut iy = [0i32; 8];
            for k in 0..8 {
                let (px, py) = (x0 + k as f64 * (1.0 + gx), y0 + k as f64 * gy);
                (ix[k], iy[k]) = (px.floor() as i32, py.floor() as i32);
                (x[k], y[k]) = ((px - px.floor()) as f32, (py - py.floor()) as f32);
            }
            // SAFETY: `available` returned true above.
            let (fast, slow) = unsafe {
                let lanes = Lanes {
                    ix: _mm256_loadu_si256(ix.as_ptr().cast()),
                    iy: _mm256_loadu_si256(iy.as_ptr().cast()),
                    tx: _mm256_loadu_ps(x.as_ptr()),
                    ty: _mm256_loadu_ps(y.as_ptr()),
                };
                let valid = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
                (
                    taps_in_lanes(&c.data, w, &lanes, valid),
                    sample_by_sample(&c.data, w, &lanes, 8),
                )
            };
            let spread = |f: &[i32; 8], step: i32| {
                let rel: Vec<i32> = (0..8).map(|k| f[k] - step * k as i32).collect();
                rel.iter().max().unwrap() - rel.iter().min().unwrap()
            };
            let (sx, sy) = (spread(&ix, 1), spread(&iy, 0));
            let Some(fast) = fast else {
                assert!(
                    sx > 1 || sy > 1,
                    "case {case}: declined at spreads {sx} {sy}"
                );
                continue;
            };
            assert!(sx <= 1 && sy <= 1, "case {case}");
            taken[(sx * 2 + sy) as usize] += 1;
            let (mut a, mut b) = ([0.0f32; 8], [0.0f32; 8]);
            // SAFETY: `available` returned true above.
            unsafe {
                store8(fast, &mut a);
                store8(slow, &mut b);
            }
            for k in 0..8 {
                let scale = b[k].abs().max(1.0);
                assert!(
                    (a[k] - b[k]).abs() <= 2e-6 * scale,
                    "case {case} lane {k}: {} vs {}",
                    a[k],
                    b[k]
                );
            }
        }
        println!("tap counts 6x6, 6x7, 7x6, 7x7 taken: {taken:?}");
        assert!(taken.iter().all(|&t| t > 0), "{taken:?}");
    }
}
