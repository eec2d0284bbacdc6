//! FFT timings for scale next to the ZOI figures of the benchmarks: the same 2-D transforms the
//! ZOI loop uses, timed on the calling thread.

use fft2d::Complex32;
use fft2d::Fft2d;
use fft2d::RealFft2d;
use std::time::Instant;

/// Time of one n x n 2-D transform (ns, median over batches).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FftTimings {
    pub n: usize,
    /// Complex-to-complex forward transform (rustfft rows then columns).
    pub complex_forward_ns: f64,
    /// Real-to-complex forward transform (the ZOI loop's, half spectrum).
    pub real_forward_ns: f64,
    /// Half spectrum back to a real image.
    pub real_inverse_ns: f64,
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Times `batches` batches of `repeats` transforms of each kind; returns the median per transform.
pub fn time_ffts(n: usize, repeats: usize, batches: usize) -> FftTimings {
    assert!(n.is_power_of_two() && n >= 4 && repeats >= 1 && batches >= 1);
    let image: Vec<f32> = (0..n * n)
        .map(|i| ((i * 7919) % 251) as f32 - 125.0)
        .collect();
    let mut complex = Fft2d::new(n);
    let mut real = RealFft2d::new(n);
    let source: Vec<Complex32> = image.iter().map(|&v| Complex32::new(v, 0.0)).collect();
    let mut data = source.clone();
    let mut half = vec![Complex32::new(0.0, 0.0); real.spectrum_len()];
    let mut back = vec![0.0f32; n * n];
    let per = |start: Instant| start.elapsed().as_nanos() as f64 / repeats as f64;
    let (mut c, mut f, mut i) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..batches {
        // The complex transform is in place: each one starts from a fresh copy of the input,
        // whose time is measured alone and subtracted.
        let t = Instant::now();
        for _ in 0..repeats {
            data.copy_from_slice(std::hint::black_box(&source));
            std::hint::black_box(&mut data);
        }
        let copy_ns = per(t);
        let t = Instant::now();
        for _ in 0..repeats {
            data.copy_from_slice(std::hint::black_box(&source));
            complex.forward(std::hint::black_box(&mut data));
        }
        c.push((per(t) - copy_ns).max(0.0));
        let t = Instant::now();
        for _ in 0..repeats {
            real.forward(std::hint::black_box(&image), &mut half);
        }
        f.push(per(t));
        let t = Instant::now();
        for _ in 0..repeats {
            real.inverse(std::hint::black_box(&mut half), &mut back);
        }
        i.push(per(t));
    }
    FftTimings {
        n,
        complex_forward_ns: median(&mut c),
        real_forward_ns: median(&mut f),
        real_inverse_ns: median(&mut i),
    }
}
