//! Four-lane f32 vectors for the ZOI loop's sums: SSE on x86-64 (part of its baseline, so
//! always available, no runtime detection), plain arrays elsewhere. The compiler's own
//! vectoriser turns these loops into shuffle-heavy code (lane reductions and overlapping shifted
//! loads), about twice the instructions; with explicit lanes each 4 values cost one load and
//! one arithmetic instruction per operation. All unsafe code of the module is the two pointer
//! accesses, each reading or writing exactly the 16 bytes of a `[f32; 4]` reference, and
//! calls of SSE intrinsics, which need an unsafe block although SSE is enabled on every x86-64
//! target (`#[target_feature]` functions).

#[cfg(target_arch = "x86_64")]
mod imp {
    use std::arch::x86_64::{
        __m128, _mm_add_ps, _mm_loadu_ps, _mm_mul_ps, _mm_set1_ps, _mm_setzero_ps, _mm_storeu_ps,
        _mm_sub_ps,
    };

    #[derive(Clone, Copy)]
    pub struct F32x4(__m128);

    impl F32x4 {
        #[inline(always)]
        pub fn zero() -> Self {
            F32x4(unsafe { _mm_setzero_ps() })
        }
        #[inline(always)]
        pub fn splat(v: f32) -> Self {
            F32x4(unsafe { _mm_set1_ps(v) })
        }
        #[inline(always)]
        pub fn load(a: &[f32; 4]) -> Self {
            // SAFETY: reads the 16 bytes of a [f32; 4]; unaligned load.
            F32x4(unsafe { _mm_loadu_ps(a.as_ptr()) })
        }
        #[inline(always)]
        pub fn store(self, out: &mut [f32; 4]) {
            // SAFETY: writes the 16 bytes of a [f32; 4]; unaligned store.
            unsafe { _mm_storeu_ps(out.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        pub fn add(self, b: Self) -> Self {
            F32x4(unsafe { _mm_add_ps(self.0, b.0) })
        }
        #[inline(always)]
        pub fn sub(self, b: Self) -> Self {
            F32x4(unsafe { _mm_sub_ps(self.0, b.0) })
        }
        #[inline(always)]
        pub fn mul(self, b: Self) -> Self {
            F32x4(unsafe { _mm_mul_ps(self.0, b.0) })
        }
    }
}

#[cfg(not(target_arch = "x86_64"))]
mod imp {
    #[derive(Clone, Copy)]
    pub struct F32x4([f32; 4]);

    impl F32x4 {
        #[inline(always)]
        pub fn zero() -> Self {
            F32x4([0.0; 4])
        }
        #[inline(always)]
        pub fn splat(v: f32) -> Self {
            F32x4([v; 4])
        }
        #[inline(always)]
        pub fn load(a: &[f32; 4]) -> Self {
            F32x4(*a)
        }
        #[inline(always)]
        pub fn store(self, out: &mut [f32; 4]) {
            *out = self.0;
        }
        #[inline(always)]
        pub fn add(self, b: Self) -> Self {
            F32x4(std::array::from_fn(|i| self.0[i] + b.0[i]))
        }
        #[inline(always)]
        pub fn sub(self, b: Self) -> Self {
            F32x4(std::array::from_fn(|i| self.0[i] - b.0[i]))
        }
        #[inline(always)]
        pub fn mul(self, b: Self) -> Self {
            F32x4(std::array::from_fn(|i| self.0[i] * b.0[i]))
        }
    }
}

pub use imp::F32x4;

impl F32x4 {
    /// Sum of the four lanes, ((a0 + a2) + (a1 + a3)).
    #[inline(always)]
    pub fn sum(self) -> f32 {
        let mut a = [0.0f32; 4];
        self.store(&mut a);
        (a[0] + a[2]) + (a[1] + a[3])
    }

    /// self + a b.
    #[inline(always)]
    pub fn mul_add(self, a: Self, b: Self) -> Self {
        self.add(a.mul(b))
    }
}

/// Σ a[i] b[i] over slices of equal length, a multiple of 4, in two 4-lane accumulators.
#[inline]
pub fn dot(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    let (a, rest_a) = a.as_chunks::<4>();
    let (b, _) = b.as_chunks::<4>();
    assert!(rest_a.is_empty(), "length must be a multiple of 4");
    let (mut s0, mut s1) = (F32x4::zero(), F32x4::zero());
    let mut pairs = a.chunks_exact(2).zip(b.chunks_exact(2));
    for (x, y) in &mut pairs {
        s0 = s0.mul_add(F32x4::load(&x[0]), F32x4::load(&y[0]));
        s1 = s1.mul_add(F32x4::load(&x[1]), F32x4::load(&y[1]));
    }
    if a.len() % 2 == 1 {
        let last = a.len() - 1;
        s0 = s0.mul_add(F32x4::load(&a[last]), F32x4::load(&b[last]));
    }
    s0.add(s1).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dot_matches_a_plain_sum() {
        for len in [4usize, 8, 12, 32, 1024] {
            let a: Vec<f32> = (0..len).map(|i| (i as f32 * 0.37).sin()).collect();
            let b: Vec<f32> = (0..len).map(|i| (i as f32 * 0.11).cos()).collect();
            let plain: f64 = a.iter().zip(&b).map(|(x, y)| (x * y) as f64).sum();
            assert!((dot(&a, &b) as f64 - plain).abs() < 1e-4, "{len}");
        }
        let mut v = F32x4::splat(2.0)
            .sub(F32x4::splat(0.5))
            .mul(F32x4::splat(2.0));
        v = v.add(F32x4::zero());
        assert_eq!(v.sum(), 12.0);
    }
}
