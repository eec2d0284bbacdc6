//! Square 2-D complex FFT built from rustfft 1-D plans, planned once, with owned scratch.
//!
//! Forward output is stored transposed (`spectrum[kx * n + ky]`), which saves two transposes
//! per forward/inverse pair; the inverse takes that layout and returns row-major `[y * n + x]`.
//! Products of spectra are element-wise, so the layout never matters to callers that only
//! multiply spectra of the same `Fft2d` and use `frequency_index` for phase ramps.

use crate::Complex32;
use crate::Plan;

pub struct Fft2d {
    n: usize,
    forward: Plan,
    inverse: Plan,
    scratch: Vec<Complex32>,
    transposed: Vec<Complex32>,
}

impl Fft2d {
    pub fn new(n: usize) -> Self {
        assert!(n.is_power_of_two() && n >= 2);
        let (forward, inverse, scratch) = crate::plan_pair(n);
        Self {
            n,
            forward,
            inverse,
            scratch,
            transposed: vec![Complex32::new(0.0, 0.0); n * n],
        }
    }

    /// Row-major image in, transposed spectrum out (in place).
    pub fn forward(&mut self, data: &mut [Complex32]) {
        let (scratch, transposed) = (&mut self.scratch, &mut self.transposed);
        rows_then_columns(&self.forward, data, scratch, transposed, self.n);
    }

    /// Transposed spectrum in, row-major image out (in place), unnormalised (times n²).
    pub fn inverse(&mut self, data: &mut [Complex32]) {
        let (scratch, transposed) = (&mut self.scratch, &mut self.transposed);
        rows_then_columns(&self.inverse, data, scratch, transposed, self.n);
    }
}

/// One 1-D plan along the rows, a transpose, the plan along the rows again (the columns), in
/// place: both directions are this with their own plan.
fn rows_then_columns(
    plan: &Plan,
    data: &mut [Complex32],
    scratch: &mut [Complex32],
    transposed: &mut [Complex32],
    n: usize,
) {
    assert_eq!(data.len(), n * n);
    plan.process_with_scratch(data, scratch);
    transpose(data, transposed, n);
    plan.process_with_scratch(transposed, scratch);
    data.copy_from_slice(transposed);
}

fn transpose(src: &[Complex32], dst: &mut [Complex32], n: usize) {
    const BLOCK: usize = 8;
    for by in (0..n).step_by(BLOCK) {
        for bx in (0..n).step_by(BLOCK) {
            for y in by..(by + BLOCK).min(n) {
                for x in bx..(bx + BLOCK).min(n) {
                    dst[x * n + y] = src[y * n + x];
                }
            }
        }
    }
}
