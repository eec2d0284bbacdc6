//! Step 2 of CORRELI-GD: one FFT cross-correlation of the ROI gives the mean integer
//! displacement (U0, V0). The correlated square is the largest 2^q square centred in the ROI,
//! capped at `MAX_GLOBAL_PX` so that a 1024² ROI does not cost two 1024² FFTs per frame.

use crate::fft2d::Fft2d;
use crate::settings::Roi;
use crate::zoi::Image;
use rustfft::num_complex::Complex32;

pub const MAX_GLOBAL_PX: usize = 512;

pub struct GlobalCorrelator {
    x0: usize,
    y0: usize,
    m: usize,
    fft: Fft2d,
    reference: Vec<Complex32>,
    work: Vec<Complex32>,
    reference_ok: bool,
}

impl GlobalCorrelator {
    pub fn new(roi: Roi) -> Self {
        let side = roi.width_px.min(roi.height_px);
        let m = if side.is_power_of_two() {
            side
        } else {
            side.next_power_of_two() / 2
        }
        .min(MAX_GLOBAL_PX);
        let x0 = roi.x_px + (roi.width_px - m) / 2;
        let y0 = roi.y_px + (roi.height_px - m) / 2;
        let zero = Complex32::new(0.0, 0.0);
        Self {
            x0,
            y0,
            m,
            fft: Fft2d::new(m),
            reference: vec![zero; m * m],
            work: vec![zero; m * m],
            reference_ok: false,
        }
    }

    fn load(&self, image: Image, out: &mut [Complex32]) -> bool {
        let m = self.m;
        let mut sum = 0.0f64;
        for row in 0..m {
            let start = (self.y0 + row) * image.width_px + self.x0;
            for (o, &p) in out[row * m..(row + 1) * m]
                .iter_mut()
                .zip(&image.pixels[start..start + m])
            {
                *o = Complex32::new(p as f32, 0.0);
                sum += p as f64;
            }
        }
        let mean = (sum / (m * m) as f64) as f32;
        let mut sum_sq = 0.0f64;
        for o in out.iter_mut() {
            o.re -= mean;
            sum_sq += (o.re * o.re) as f64;
        }
        (sum_sq / (m * m) as f64).sqrt() >= crate::zoi::MIN_STD_COUNTS as f64
    }

    pub fn set_reference(&mut self, image: Image) {
        let mut reference = std::mem::take(&mut self.reference);
        self.reference_ok = self.load(image, &mut reference);
        self.fft.forward(&mut reference);
        self.reference = reference;
    }

    /// Integer displacement of `deformed` against the reference, (0, 0) when either is flat.
    pub fn displacement(&mut self, deformed: Image) -> (i64, i64) {
        let mut work = std::mem::take(&mut self.work);
        let ok = self.load(deformed, &mut work);
        if !(ok && self.reference_ok) {
            self.work = work;
            return (0, 0);
        }
        self.fft.forward(&mut work);
        for (w, &r) in work.iter_mut().zip(&self.reference) {
            *w *= r.conj();
        }
        self.fft.inverse(&mut work);
        let mut best = (f32::NEG_INFINITY, 0usize);
        for (i, c) in work.iter().enumerate() {
            if c.re > best.0 {
                best = (c.re, i);
            }
        }
        self.work = work;
        let m = self.m;
        let wrap = |k: usize| {
            if k >= m / 2 {
                k as i64 - m as i64
            } else {
                k as i64
            }
        };
        (wrap(best.1 % m), wrap(best.1 / m))
    }
}
