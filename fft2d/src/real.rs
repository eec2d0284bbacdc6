//! Square 2-D real-to-complex FFT on rustfft alone: two real rows are packed into one complex
//! FFT (z = a + j b) and separated by Hermitian symmetry, then only the n/2 + 1 non-redundant
//! columns are transformed. About half the work of a complex 2-D FFT, which matters because the
//! ZOI loop is FFT-bound; the `realfft` crate would do the same (one n/2 complex FFT per row)
//! at the cost of one more dependency.
//!
//! Half-spectrum layout: `spectrum[kx * n + ky]`, kx in 0..=n/2, ky in 0..n.

use crate::Complex32;
use crate::Plan;

pub struct RealFft2d {
    n: usize,
    forward: Plan,
    inverse: Plan,
    scratch: Vec<Complex32>,
    /// n/2 packed row pairs of n complex values.
    rows: Vec<Complex32>,
}

impl RealFft2d {
    pub fn new(n: usize) -> Self {
        assert!(n.is_power_of_two() && n >= 4);
        let (forward, inverse, scratch) = crate::plan_pair(n);
        let zero = Complex32::new(0.0, 0.0);
        Self {
            n,
            forward,
            inverse,
            scratch,
            rows: vec![zero; n * n / 2],
        }
    }

    /// Length of a half spectrum, (n/2 + 1) n.
    pub fn spectrum_len(&self) -> usize {
        (self.n / 2 + 1) * self.n
    }

    /// Row-major real n x n image in, half spectrum out.
    pub fn forward(&mut self, input: &[f32], spectrum: &mut [Complex32]) {
        let n = self.n;
        assert_eq!(input.len(), n * n);
        assert_eq!(spectrum.len(), self.spectrum_len());
        for (p, pair) in self.rows.chunks_exact_mut(n).enumerate() {
            let (a, b) = (
                &input[2 * p * n..(2 * p + 1) * n],
                &input[(2 * p + 1) * n..(2 * p + 2) * n],
            );
            for ((z, &ra), &rb) in pair.iter_mut().zip(a).zip(b) {
                *z = Complex32::new(ra, rb);
            }
        }
        self.forward
            .process_with_scratch(&mut self.rows, &mut self.scratch);
        // Separate the two rows of each pair, column kx at a time: the writes run along
        // spectrum[kx * n..] (rows 2p, 2p + 1 side by side), the reads are two per pair.
        for (k, column) in spectrum.chunks_exact_mut(n).enumerate() {
            let kc = (n - k) & (n - 1);
            for (ab, pair) in column.chunks_exact_mut(2).zip(self.rows.chunks_exact(n)) {
                let z = pair[k];
                let zc = pair[kc].conj();
                let d = (z - zc) * 0.5;
                ab[0] = (z + zc) * 0.5;
                ab[1] = Complex32::new(d.im, -d.re); // d / j
            }
        }
        self.forward
            .process_with_scratch(spectrum, &mut self.scratch);
    }

    /// Half spectrum in (overwritten), real image out, unnormalised (times n²). Imaginary parts
    /// of the kx = 0 and kx = n/2 columns that break Hermitian symmetry are dropped, i.e. the
    /// result is the real part of the full complex inverse.
    pub fn inverse(&mut self, spectrum: &mut [Complex32], output: &mut [f32]) {
        let n = self.n;
        assert_eq!(output.len(), n * n);
        assert_eq!(spectrum.len(), self.spectrum_len());
        self.inverse
            .process_with_scratch(spectrum, &mut self.scratch);
        // spectrum is now [kx][y]: half spectra of the rows y along x. Pack rows 2p, 2p + 1
        // as a + j b, column kx at a time (reads along spectrum[kx * n..]); the columns
        // n - kx are the conjugates. Columns 0 and n/2 keep only their real parts' symmetry.
        let half = n / 2;
        for (k, column) in spectrum.chunks_exact(n).enumerate() {
            let edge = k == 0 || k == half;
            for (ab, pair) in column.chunks_exact(2).zip(self.rows.chunks_exact_mut(n)) {
                let (mut a, mut b) = (ab[0], ab[1]);
                if edge {
                    a.im = 0.0;
                    b.im = 0.0;
                } else {
                    pair[n - k] = Complex32::new(a.re + b.im, b.re - a.im); // conj(a) + j conj(b)
                }
                pair[k] = Complex32::new(a.re - b.im, a.im + b.re); // a + j b
            }
        }
        self.inverse
            .process_with_scratch(&mut self.rows, &mut self.scratch);
        for (p, pair) in self.rows.chunks_exact(n).enumerate() {
            let (ya, yb) = (2 * p, 2 * p + 1);
            for (x, z) in pair.iter().enumerate() {
                output[ya * n + x] = z.re;
                output[yb * n + x] = z.im;
            }
        }
    }
}
