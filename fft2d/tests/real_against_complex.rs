//! The real 2-D transform against the complex one, and its round trip.

use fft2d::{Complex32, Fft2d, RealFft2d};

#[test]
fn matches_complex_fft_and_round_trips() {
    let n = 16;
    let input: Vec<f32> = (0..n * n)
        .map(|i| ((i * 7919) % 97) as f32 - 40.0)
        .collect();
    let mut real = RealFft2d::new(n);
    let mut half = vec![Complex32::new(0.0, 0.0); real.spectrum_len()];
    real.forward(&input, &mut half);
    let mut full: Vec<Complex32> = input.iter().map(|&v| Complex32::new(v, 0.0)).collect();
    Fft2d::new(n).forward(&mut full);
    for kx in 0..=n / 2 {
        for ky in 0..n {
            let (h, f) = (half[kx * n + ky], full[kx * n + ky]);
            assert!((h - f).norm() < 1e-2, "kx {kx} ky {ky}: {h} vs {f}");
        }
    }
    let mut back = vec![0.0f32; n * n];
    real.inverse(&mut half, &mut back);
    for (b, i) in back.iter().zip(&input) {
        assert!((b / (n * n) as f32 - i).abs() < 1e-3);
    }
}
