//! Square 2-D FFTs of zones of interest (ZOIs), real-to-complex and complex, planned once on
//! rustfft.
//!
//! A crate of its own for the build's sake: rustfft is generic over its float type, and its
//! planner drags every algorithm it may pick (SSE, AVX and scalar butterflies, Rader, Bluestein,
//! for f32 and f64 alike) into the code generation of whichever crate calls it. Planned inside
//! the correlator, that was a third of the correlator's LLVM IR (414,000 of 1,223,000 lines by
//! `cargo llvm-lines -p correlator --lib --release`), generated twice per build (the library and
//! its unit tests). Here the types below are not generic, so rustfft is instantiated once, in
//! this crate's library; callers link to it. The crate has no unit tests for the same reason:
//! its tests (`tests/`) use the library as callers do.

mod complex;
mod real;

pub use complex::Fft2d;
pub use real::RealFft2d;
/// The complex sample of every spectrum here (rustfft's, i.e. `num_complex`'s).
pub use rustfft::num_complex::Complex32;

use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// A 1-D plan of rustfft's, behind its trait object (nothing generic leaves this crate).
type Plan = Arc<dyn Fft<f32>>;

/// The forward and inverse 1-D plans of length `n`, and a scratch buffer both can use.
fn plan_pair(n: usize) -> (Plan, Plan, Vec<Complex32>) {
    let mut planner = FftPlanner::<f32>::new();
    let forward = planner.plan_fft_forward(n);
    let inverse = planner.plan_fft_inverse(n);
    let scratch_len = forward
        .get_inplace_scratch_len()
        .max(inverse.get_inplace_scratch_len())
        .max(1);
    let scratch = vec![Complex32::new(0.0, 0.0); scratch_len];
    (forward, inverse, scratch)
}
