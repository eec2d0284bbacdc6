//! Step 2 of CORRELI-GD: one FFT cross-correlation of the ROI gives the mean integer
//! displacement (U0, V0). The correlated square is the largest 2^q square centred in the ROI,
//! capped at `MAX_GLOBAL_PX` so that a 1024² ROI does not cost two 1024² FFTs per frame.
//!
//! Beyond the paper, the peak is kept only when it is significant: its height at least
//! [`SIGNIFICANCE_RATIO`] times the highest value outside its neighbourhood (a correlation of
//! unrelated speckle has many peaks of about equal height; a true match stands out). When it
//! does not, the next smaller centred square is tried (down to [`MIN_GLOBAL_PX`]): under a
//! rotation or a strain the centre of the ROI stays correlated longer than its border (5° of
//! rotation moves a 512² square's corners by 31 px against each other, a 128² square's by 8).
//! When no square has a significant peak, there is no guess, never a wrong one.

use crate::settings::Roi;
use crate::zoi::Image;
use fft2d::Complex32;
use fft2d::Fft2d;

pub const MAX_GLOBAL_PX: usize = 512;
/// Smallest square tried.
pub const MIN_GLOBAL_PX: usize = 64;
/// A peak counts when it is this many times the highest value outside its neighbourhood.
pub const SIGNIFICANCE_RATIO: f32 = 1.5;
/// The peak's neighbourhood (Chebyshev radius, px) left out when looking for the second peak:
/// the correlation peak of a speckle is a few pixels wide.
const PEAK_RADIUS_PX: usize = 4;

/// One centred square and its reference spectrum.
struct Level {
    x0: usize,
    y0: usize,
    m: usize,
    fft: Fft2d,
    reference: Vec<Complex32>,
    reference_ok: bool,
}

pub struct GlobalCorrelator {
    levels: Vec<Level>,
    work: Vec<Complex32>,
}

/// Why the global correlation gave no displacement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GlobalMiss {
    /// The reference or the deformed square has no texture: nothing can match there.
    Flat,
    /// No square had a significant peak.
    NotSignificant,
}

/// What the global correlation found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlobalPeak {
    /// Integer displacement (px).
    pub displacement_px: (i64, i64),
    /// Peak height over the highest value outside its neighbourhood.
    pub ratio: f32,
    /// Side of the square it was found on (px).
    pub square_px: usize,
}

impl GlobalCorrelator {
    pub fn new(roi: Roi) -> Self {
        let side = roi.width_px.min(roi.height_px);
        let largest = if side.is_power_of_two() {
            side
        } else {
            side.next_power_of_two() / 2
        }
        .min(MAX_GLOBAL_PX);
        let mut levels = Vec::new();
        let mut m = largest;
        loop {
            levels.push(Level {
                x0: roi.x_px + (roi.width_px - m) / 2,
                y0: roi.y_px + (roi.height_px - m) / 2,
                m,
                fft: Fft2d::new(m),
                reference: vec![Complex32::new(0.0, 0.0); m * m],
                reference_ok: false,
            });
            if m / 2 < MIN_GLOBAL_PX {
                break;
            }
            m /= 2;
        }
        Self {
            levels,
            work: vec![Complex32::new(0.0, 0.0); largest * largest],
        }
    }

    pub fn set_reference(&mut self, image: Image) {
        for level in &mut self.levels {
            let mut reference = std::mem::take(&mut level.reference);
            level.reference_ok = level.load(image, &mut reference);
            level.fft.forward(&mut reference);
            level.reference = reference;
        }
    }

    /// Integer displacement of `deformed` against the reference on the largest square whose
    /// peak is significant; [`GlobalMiss`] says why there is none.
    pub fn displacement(&mut self, deformed: Image) -> Result<GlobalPeak, GlobalMiss> {
        let mut work = std::mem::take(&mut self.work);
        let mut miss = GlobalMiss::NotSignificant;
        let mut found = None;
        for level in &mut self.levels {
            match level.peak(deformed, &mut work[..level.m * level.m]) {
                Ok(peak) => {
                    found = Some(peak);
                    break;
                }
                Err(GlobalMiss::Flat) => {
                    miss = GlobalMiss::Flat;
                    break;
                }
                Err(GlobalMiss::NotSignificant) => {}
            }
        }
        self.work = work;
        found.ok_or(miss)
    }
}

impl Level {
    /// Loads the square, zero-mean; false when it is flat.
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

    fn peak(&mut self, deformed: Image, work: &mut [Complex32]) -> Result<GlobalPeak, GlobalMiss> {
        if !(self.load(deformed, work) && self.reference_ok) {
            return Err(GlobalMiss::Flat);
        }
        self.fft.forward(work);
        for (w, &r) in work.iter_mut().zip(&self.reference) {
            *w *= r.conj();
        }
        self.fft.inverse(work);
        let m = self.m;
        let (best, at) = work
            .iter()
            .enumerate()
            .fold((f32::NEG_INFINITY, 0), |(b, at), (i, c)| {
                if c.re > b {
                    (c.re, i)
                } else {
                    (b, at)
                }
            });
        let (px, py) = (at % m, at / m);
        // Circular distance to the peak, per axis.
        let near = |a: usize, b: usize| {
            let d = a.abs_diff(b);
            d.min(m - d) <= PEAK_RADIUS_PX
        };
        let second = work
            .iter()
            .enumerate()
            .filter(|(i, _)| !(near(i % m, px) && near(i / m, py)))
            .fold(f32::NEG_INFINITY, |s, (_, c)| s.max(c.re));
        let ratio = if second > 0.0 {
            best / second
        } else {
            f32::INFINITY
        };
        if !(best > 0.0 && ratio >= SIGNIFICANCE_RATIO) {
            return Err(GlobalMiss::NotSignificant);
        }
        let wrap = |k: usize| {
            if k >= m / 2 {
                k as i64 - m as i64
            } else {
                k as i64
            }
        };
        Ok(GlobalPeak {
            displacement_px: (wrap(px), wrap(py)),
            ratio,
            square_px: m,
        })
    }
}
