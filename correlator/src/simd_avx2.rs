//! The AVX2 + FMA lane helpers shared by the correlator's kernels (`zoi/sums_avx2.rs`,
//! `icgn/evaluate_avx2.rs`): whether the CPU runs them, and 8-lane loads and stores from and to
//! slices. Each helper is a `#[target_feature]` function, inlined into its callers' own
//! target-feature functions; only the loads and stores are unsafe, each on a slice of at
//! least 8 values.

use std::arch::x86_64::{__m256, _mm256_loadu_ps, _mm256_storeu_ps};

/// Whether this CPU has AVX2 and FMA (std caches the answer in an atomic).
#[inline]
pub fn available() -> bool {
    is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")
}

/// 8 lanes from the first 8 values of `values`.
#[target_feature(enable = "avx2,fma")]
#[inline]
pub fn load8(values: &[f32]) -> __m256 {
    let values = &values[..8];
    // SAFETY: reads the 8 values of `values`.
    unsafe { _mm256_loadu_ps(values.as_ptr()) }
}

/// Writes 8 lanes to the first 8 values of `out`.
#[target_feature(enable = "avx2,fma")]
#[inline]
pub fn store8(v: __m256, out: &mut [f32]) {
    let out = &mut out[..8];
    // SAFETY: writes the 8 values of `out`.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), v) }
}
