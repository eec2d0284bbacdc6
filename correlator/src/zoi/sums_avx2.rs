//! The AVX2 + FMA twins of the sub-pixel iterations' sums in [`super::ZoiEngine`]: the 3x3
//! windowed correlation values, the windowing of the deformed ZOI and the Fourier shift's
//! phase ramp (four complex products per instruction sequence). The portable (SSE) sums
//! run each value in one chain of dependent adds, so they wait on the add latency (a 3x3 at
//! 32 px, 9216 products, took about 0.9 µs); here the nine values of a 3x3 accumulate in nine
//! independent 8-lane FMA chains in one pass over the rows, and the windowing's sums in two
//! chains each. The same sums in another order and with fused multiply-adds: the values differ
//! from the portable ones by rounding only (within 1e-6 of them at unit norm, tests).
//!
//! The caller checks [`available`] (std caches the CPU's answer) and a ZOI side that is a
//! multiple of 8. Only the 8-value loads and stores are unsafe, each on a slice of at least 8
//! values, and the views of complex slices as their f32 pairs.

pub use crate::simd_avx2::available;
use crate::simd_avx2::{load8, store8};
use fft2d::Complex32;
use std::arch::x86_64::{
    __m256, _mm256_fmadd_ps, _mm256_fmaddsub_ps, _mm256_movehdup_ps, _mm256_moveldup_ps,
    _mm256_mul_ps, _mm256_permute_ps, _mm256_set1_ps, _mm256_setr_ps, _mm256_setzero_ps,
    _mm256_sub_ps,
};

/// Four complex products a b, each complex number two lanes (re, im).
#[target_feature(enable = "avx2,fma")]
#[inline]
fn complex_mul(a: __m256, b: __m256) -> __m256 {
    let swapped = _mm256_permute_ps(a, 0xB1);
    // Even lanes a.re b.re − a.im b.im, odd lanes a.im b.re + a.re b.im.
    _mm256_fmaddsub_ps(
        a,
        _mm256_moveldup_ps(b),
        _mm256_mul_ps(swapped, _mm256_movehdup_ps(b)),
    )
}

/// The values of a complex slice as re, im pairs.
fn as_floats(values: &[Complex32]) -> &[f32] {
    // SAFETY: Complex32 is `repr(C)` { re: f32, im: f32 }: 2 len f32 values, same alignment.
    unsafe { std::slice::from_raw_parts(values.as_ptr().cast::<f32>(), 2 * values.len()) }
}

/// [`as_floats`] for a mutable slice.
fn as_floats_mut(values: &mut [Complex32]) -> &mut [f32] {
    // SAFETY: as in `as_floats`, and the borrow is exclusive.
    unsafe { std::slice::from_raw_parts_mut(values.as_mut_ptr().cast::<f32>(), 2 * values.len()) }
}

/// The Fourier shift's phase ramp on the half spectrum `g` (rows of n, `phase_x.len()` of
/// them): `work[kx n + ky]` = g[kx n + ky] (phase_x[kx] phase_y[ky]), the products of
/// `ZoiEngine::shift_into_spatial` four bins at a time.
///
/// # Safety
/// [`available`] returned true.
#[target_feature(enable = "avx2,fma")]
pub unsafe fn phase_ramp(
    g: &[Complex32],
    phase_x: &[Complex32],
    phase_y: &[Complex32],
    work: &mut [Complex32],
) {
    let n = phase_y.len();
    assert!(n.is_multiple_of(4) && g.len() == work.len() && g.len() >= phase_x.len() * n);
    let (py, g) = (as_floats(phase_y), as_floats(g));
    let work = as_floats_mut(work);
    for (kx, px) in phase_x.iter().enumerate() {
        let px = _mm256_setr_ps(px.re, px.im, px.re, px.im, px.re, px.im, px.re, px.im);
        let row = 2 * kx * n;
        let mut c = 0;
        while c < 2 * n {
            let pxy = complex_mul(px, load8(&py[c..]));
            store8(complex_mul(load8(&g[row + c..]), pxy), &mut work[row + c..]);
            c += 8;
        }
    }
}

/// The sum of the 8 lanes.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn lane_sum(v: __m256) -> f32 {
    let mut a = [0.0f32; 8];
    store8(v, &mut a);
    ((a[0] + a[4]) + (a[2] + a[6])) + ((a[1] + a[5]) + (a[3] + a[7]))
}

/// The circular windowed correlation `[r][k]` = Σ_y Σ_x f(x, y) g(x0 − PAD + k + x, y + dy[r])
/// of the n x n `reference` f against the row-extended deformed ZOI g (`extended`, row stride
/// `stride`, each row wrapped on both sides so that columns `x0..x0 + n + 2` are in it), the
/// rows taken modulo n: the unscaled 3x3 of `ZoiEngine::correlation_3x3`.
///
/// # Safety
/// [`available`] returned true.
#[target_feature(enable = "avx2,fma")]
pub unsafe fn correlation_3x3(
    reference: &[f32],
    extended: &[f32],
    n: usize,
    stride: usize,
    x0: usize,
    dy: [i64; 3],
) -> [[f32; 3]; 3] {
    assert!(n.is_multiple_of(8) && reference.len() == n * n);
    assert!(extended.len() == n * stride && x0 + 2 + n <= stride);
    let zero = _mm256_setzero_ps();
    let (mut a00, mut a01, mut a02) = (zero, zero, zero);
    let (mut a10, mut a11, mut a12) = (zero, zero, zero);
    let (mut a20, mut a21, mut a22) = (zero, zero, zero);
    let row = |y: usize, dy: i64| {
        let yy = (y as i64 + dy).rem_euclid(n as i64) as usize;
        &extended[yy * stride + x0..yy * stride + x0 + n + 2]
    };
    for y in 0..n {
        let f_row = &reference[y * n..(y + 1) * n];
        let (g0, g1, g2) = (row(y, dy[0]), row(y, dy[1]), row(y, dy[2]));
        let mut c = 0;
        while c < n {
            let f = load8(&f_row[c..]);
            a00 = _mm256_fmadd_ps(f, load8(&g0[c..]), a00);
            a01 = _mm256_fmadd_ps(f, load8(&g0[c + 1..]), a01);
            a02 = _mm256_fmadd_ps(f, load8(&g0[c + 2..]), a02);
            a10 = _mm256_fmadd_ps(f, load8(&g1[c..]), a10);
            a11 = _mm256_fmadd_ps(f, load8(&g1[c + 1..]), a11);
            a12 = _mm256_fmadd_ps(f, load8(&g1[c + 2..]), a12);
            a20 = _mm256_fmadd_ps(f, load8(&g2[c..]), a20);
            a21 = _mm256_fmadd_ps(f, load8(&g2[c + 1..]), a21);
            a22 = _mm256_fmadd_ps(f, load8(&g2[c + 2..]), a22);
            c += 8;
        }
    }
    [
        [lane_sum(a00), lane_sum(a01), lane_sum(a02)],
        [lane_sum(a10), lane_sum(a11), lane_sum(a12)],
        [lane_sum(a20), lane_sum(a21), lane_sum(a22)],
    ]
}

/// Writes w (g − mean_w) for the n x n ZOI g into `out`, row y at `out[offset + y * stride..][..n]`, mean_w the
/// window-weighted mean of g (`window_sum` = Σ w); returns Σ (w (g − mean_w))². The sums of
/// `ZoiEngine::window_rows`.
///
/// # Safety
/// [`available`] returned true.
#[target_feature(enable = "avx2,fma")]
pub unsafe fn window_rows(
    window: &[f32],
    g: &[f32],
    window_sum: f32,
    n: usize,
    out: &mut [f32],
    stride: usize,
    offset: usize,
) -> f32 {
    let n2 = n * n;
    assert!(n.is_multiple_of(8) && window.len() == n2 && g.len() == n2 && stride >= n);
    assert!(out.len() >= offset + (n - 1) * stride + n);
    let (mut d0, mut d1) = (_mm256_setzero_ps(), _mm256_setzero_ps());
    let mut i = 0;
    while i < n2 {
        let product = (load8(&window[i..]), load8(&g[i..]));
        if (i / 8).is_multiple_of(2) {
            d0 = _mm256_fmadd_ps(product.0, product.1, d0);
        } else {
            d1 = _mm256_fmadd_ps(product.0, product.1, d1);
        }
        i += 8;
    }
    let mean = _mm256_set1_ps((lane_sum(d0) + lane_sum(d1)) / window_sum);
    let (mut s0, mut s1) = (_mm256_setzero_ps(), _mm256_setzero_ps());
    for y in 0..n {
        let (w_row, g_row) = (&window[y * n..(y + 1) * n], &g[y * n..(y + 1) * n]);
        let o_row = &mut out[offset + y * stride..offset + y * stride + n];
        let mut x = 0;
        while x < n {
            let v = _mm256_mul_ps(load8(&w_row[x..]), _mm256_sub_ps(load8(&g_row[x..]), mean));
            if (x / 8).is_multiple_of(2) {
                s0 = _mm256_fmadd_ps(v, v, s0);
            } else {
                s1 = _mm256_fmadd_ps(v, v, s1);
            }
            store8(v, &mut o_row[x..]);
            x += 8;
        }
    }
    lane_sum(s0) + lane_sum(s1)
}

#[cfg(test)]
mod tests {
    use super::super::{spectrum_len, ZoiEngine, PAD};
    use fft2d::Complex32;

    /// The phase ramp gives the portable products g (px py) to rounding.
    #[test]
    fn the_avx2_phase_ramp_is_the_portable_one() {
        if !super::available() {
            return;
        }
        for n in [8usize, 16, 32] {
            let unit = |a: f32| Complex32::new(a.cos(), a.sin());
            let g: Vec<Complex32> = (0..spectrum_len(n))
                .map(|i| Complex32::new((i as f32 * 0.7).sin() * 50.0, (i as f32 * 0.3).cos()))
                .collect();
            let phase_x: Vec<Complex32> =
                (0..=n / 2).map(|k| unit(k as f32 * 0.37) * 0.01).collect();
            let phase_y: Vec<Complex32> = (0..n).map(|k| unit(k as f32 * -0.81)).collect();
            let mut work = vec![Complex32::new(0.0, 0.0); spectrum_len(n)];
            // SAFETY: available() returned true.
            unsafe { super::phase_ramp(&g, &phase_x, &phase_y, &mut work) };
            for (kx, px) in phase_x.iter().enumerate() {
                for (ky, py) in phase_y.iter().enumerate() {
                    let i = kx * n + ky;
                    let expected = g[i] * (px * py);
                    assert!(
                        (work[i] - expected).norm() <= 1e-6 * g[i].norm().max(1.0),
                        "{n} {i}"
                    );
                }
            }
        }
    }

    /// A speckle-like ZOI: sums of sines, any scale.
    fn texture(n: usize, phase: f32) -> Vec<f32> {
        (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f32, (i / n) as f32);
                300.0 * (0.71 * x + phase).sin() * (0.43 * y + 0.3).cos()
                    + 200.0 * (1.37 * x - 0.91 * y + 2.0 * phase).sin()
                    + 7.0
            })
            .collect()
    }

    /// The AVX2 sums give the portable path's windowed ZOI, norm and 3x3 values to rounding,
    /// at every centre the sub-pixel iterations use, for the ZOI sides a power of two allows.
    #[test]
    fn the_avx2_sums_are_the_portable_sums() {
        if !super::available() {
            eprintln!("no AVX2 + FMA on this CPU: nothing to compare");
            return;
        }
        for n in [8usize, 16, 32, 64] {
            let stride = n + 2 * PAD;
            let mut engines = [ZoiEngine::new(n), ZoiEngine::new(n)];
            engines[0].avx2 = false;
            assert!(engines[1].avx2);
            let mut reference = [vec![0.0f32; n * n], vec![0.0f32; n * n]];
            let mut norms = [0.0f32; 2];
            for (engine, (f, norm)) in engines
                .iter_mut()
                .zip(reference.iter_mut().zip(norms.iter_mut()))
            {
                engine.g_spatial = texture(n, 0.2);
                engine.window_into(f).unwrap();
                engine.g_spatial = texture(n, 0.5);
                let mut extended = std::mem::take(&mut engine.extended);
                *norm = engine.window_rows(&mut extended, stride, PAD).unwrap();
                engine.extended = extended;
                engine.wrap_rows();
            }
            assert!(
                (norms[0] - norms[1]).abs() <= 1e-5 * norms[0],
                "{n}: {norms:?}"
            );
            for (a, b) in reference[0].iter().zip(&reference[1]) {
                assert!((a - b).abs() <= 1e-6, "{n}: {a} {b}");
            }
            for (a, b) in engines[0].extended.iter().zip(&engines[1].extended) {
                assert!((a - b).abs() <= 1e-5 * a.abs().max(1.0), "{n}: {a} {b}");
            }
            for cy in -1i64..=1 {
                for cx in -1i64..=1 {
                    let scale = 1.0 / norms[0];
                    let [portable, avx2] =
                        [0, 1].map(|e| engines[e].correlation_3x3(&reference[0], (cx, cy), scale));
                    for (p, a) in portable.iter().flatten().zip(avx2.iter().flatten()) {
                        assert!((p - a).abs() <= 1e-6, "{n} ({cx}, {cy}): {p} {a}");
                    }
                }
            }
        }
    }
}
