//! One ZOI, CORRELI-GD style (paper section 3.b): integer FFT correlation and move, then
//! modified-Hanning windowed correlation, 3x3 quadratic sub-pixel peak and Fourier-shift
//! iterations while the interpolated maximum increases. A `ZoiEngine` owns its FFT plans and
//! buffers (one per worker thread) and never allocates after `new`.

use crate::fft2d::signed_frequency;
use crate::field::NodeStatus;
use crate::peak::quadratic_peak_3x3;
use crate::real_fft2d::RealFft2d;
use crate::window::modified_hanning_2d;
use rustfft::num_complex::Complex32;

/// A ZOI whose grey-level standard deviation is below this (in image counts) is `LowContrast`.
pub const MIN_STD_COUNTS: f32 = 0.5;
/// Sub-pixel iterations stop when the correction is below this (px).
pub const CONVERGED_STEP_PX: f64 = 1e-3;
/// A ZOI whose last correction at the iteration cap is above this (px) is `NotConverged`.
pub const NOT_CONVERGED_STEP_PX: f64 = 0.02;
/// The sub-pixel shift may not wander further than this from the integer position (px).
const MAX_SUBPIXEL_DRIFT_PX: f64 = 2.0;

/// A grey-level image borrowed as row-major u16.
#[derive(Clone, Copy)]
pub struct Image<'a> {
    pub pixels: &'a [u16],
    pub width_px: usize,
    pub height_px: usize,
}

impl Image<'_> {
    /// True when the n x n block with top-left (x0, y0) lies inside the image.
    #[inline]
    pub fn contains_block(&self, x0: i64, y0: i64, n: usize) -> bool {
        x0 >= 0 && y0 >= 0 && x0 as usize + n <= self.width_px && y0 as usize + n <= self.height_px
    }
}

/// The per-node reference data, cached while the reference is fixed.
pub struct ReferenceSpectra<'a> {
    /// Zero-mean, unit-norm, unwindowed ZOI spectrum (integer step).
    pub plain: &'a [Complex32],
    /// Window-weighted zero-mean, windowed, unit-norm spectrum (sub-pixel step).
    pub windowed: &'a [Complex32],
}

/// Result of one ZOI: displacement of the ZOI centre (px) against its reference position.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ZoiResult {
    pub u_px: f64,
    pub v_px: f64,
    pub score: f64,
    pub iterations: u32,
    pub status: NodeStatus,
}

/// Accumulated time split of the engine's work (ns), for the benchmark. Counting is off
/// unless `profile` is set, so the hot loop reads no clock by default.
#[derive(Clone, Copy, Debug, Default)]
pub struct TimeSplit {
    pub fft_ns: u64,
    pub window_ns: u64,
    pub peak_ns: u64,
    pub shift_ns: u64,
    pub other_ns: u64,
}

/// Length of the cached half spectrum of one ZOI of side n.
pub fn spectrum_len(n: usize) -> usize {
    (n / 2 + 1) * n
}

pub struct ZoiEngine {
    n: usize,
    fft: RealFft2d,
    window: Vec<f32>,
    window_sum: f32,
    /// Zero-mean deformed ZOI (spatial, real).
    g_spatial: Vec<f32>,
    /// Spectrum of `g_spatial` at the integer position.
    g_spectrum: Vec<Complex32>,
    /// Half-spectrum work buffer.
    work: Vec<Complex32>,
    /// Windowed (or normalised) ZOI, real.
    windowed: Vec<f32>,
    /// Correlation map, real, row-major, unnormalised (times n²).
    corr: Vec<f32>,
    phase_x: Vec<Complex32>,
    phase_y: Vec<Complex32>,
    pub profile: bool,
    pub split: TimeSplit,
}

struct Timer(Option<std::time::Instant>);

impl Timer {
    #[inline]
    fn start(on: bool) -> Self {
        Timer(on.then(std::time::Instant::now))
    }
    #[inline]
    fn lap(&mut self, into: &mut u64) {
        if let Some(t) = self.0.as_mut() {
            let now = std::time::Instant::now();
            *into += (now - *t).as_nanos() as u64;
            *t = now;
        }
    }
}

impl ZoiEngine {
    pub fn new(n: usize) -> Self {
        let zero = Complex32::new(0.0, 0.0);
        let window = modified_hanning_2d(n);
        let window_sum = window.iter().sum();
        Self {
            n,
            fft: RealFft2d::new(n),
            window,
            window_sum,
            g_spatial: vec![0.0; n * n],
            g_spectrum: vec![zero; spectrum_len(n)],
            work: vec![zero; spectrum_len(n)],
            windowed: vec![0.0; n * n],
            corr: vec![0.0; n * n],
            phase_x: vec![zero; n],
            phase_y: vec![zero; n],
            profile: false,
            split: TimeSplit::default(),
        }
    }

    /// Fills the two reference spectra of the ZOI with top-left (x0, y0) (inside the image).
    /// Returns false when the ZOI has too little contrast to be correlated.
    pub fn prepare_reference(
        &mut self,
        image: Image,
        x0: usize,
        y0: usize,
        plain: &mut [Complex32],
        windowed: &mut [Complex32],
    ) -> bool {
        let n = self.n;
        assert!(image.contains_block(x0 as i64, y0 as i64, n));
        assert_eq!(plain.len(), spectrum_len(n));
        assert_eq!(windowed.len(), spectrum_len(n));
        let contrast_ok = self.extract_zero_mean(image, x0, y0);
        if !contrast_ok {
            plain.fill(Complex32::new(0.0, 0.0));
            windowed.fill(Complex32::new(0.0, 0.0));
            return false;
        }
        let norm = self.g_spatial.iter().map(|&g| g * g).sum::<f32>().sqrt();
        for (p, &g) in self.windowed.iter_mut().zip(&self.g_spatial) {
            *p = g / norm;
        }
        self.fft.forward(&self.windowed, plain);
        let mut real = std::mem::take(&mut self.windowed);
        let ok = self.window_into(&mut real).is_some();
        if ok {
            self.fft.forward(&real, windowed);
        }
        self.windowed = real;
        ok
    }

    /// Copies the n x n block at (x0, y0) into `g_spatial` minus its mean; false if flat.
    fn extract_zero_mean(&mut self, image: Image, x0: usize, y0: usize) -> bool {
        let n = self.n;
        let mut sum = 0.0f64;
        for row in 0..n {
            let start = (y0 + row) * image.width_px + x0;
            let src = &image.pixels[start..start + n];
            let dst = &mut self.g_spatial[row * n..(row + 1) * n];
            for (d, &s) in dst.iter_mut().zip(src) {
                *d = s as f32;
                sum += s as f64;
            }
        }
        let mean = (sum / (n * n) as f64) as f32;
        let mut sum_sq = 0.0f32;
        for g in self.g_spatial.iter_mut() {
            *g -= mean;
            sum_sq += *g * *g;
        }
        let std = (sum_sq / (n * n) as f32).sqrt();
        std >= MIN_STD_COUNTS
    }

    /// Writes w (g - weighted mean) / norm into `out` (real parts); returns the norm before
    /// normalisation, or None when the windowed ZOI is flat.
    fn window_into(&self, out: &mut [f32]) -> Option<f32> {
        let mut weighted = 0.0f32;
        for (&w, &g) in self.window.iter().zip(&self.g_spatial) {
            weighted += w * g;
        }
        let mean = weighted / self.window_sum;
        let mut sum_sq = 0.0f32;
        for ((o, &w), &g) in out.iter_mut().zip(&self.window).zip(&self.g_spatial) {
            let v = w * (g - mean);
            sum_sq += v * v;
            *o = v;
        }
        let norm = sum_sq.sqrt();
        let floor = MIN_STD_COUNTS * (self.window_sum).sqrt();
        if norm.is_finite() && norm >= floor {
            let inv = 1.0 / norm;
            for o in out.iter_mut() {
                *o *= inv;
            }
            Some(norm)
        } else {
            None
        }
    }

    /// Correlates the deformed image around the reference ZOI at (x0, y0), starting from the
    /// guess (px). The returned displacement is total (guess included).
    pub fn correlate(
        &mut self,
        reference: &ReferenceSpectra,
        deformed: Image,
        x0: usize,
        y0: usize,
        guess_px: (f64, f64),
        max_iterations: u32,
    ) -> ZoiResult {
        let n = self.n;
        let mut timer = Timer::start(self.profile);
        let mut result = ZoiResult {
            status: NodeStatus::NotConverged,
            ..ZoiResult::default()
        };
        if !(guess_px.0.is_finite() && guess_px.1.is_finite()) {
            return result;
        }
        // Integer step (paper): one unwindowed FFT correlation, then move the deformed ZOI.
        let mut ix = guess_px.0.round() as i64;
        let mut iy = guess_px.1.round() as i64;
        let mut spectrum_valid = false;
        for pass in 0..2 {
            // A ZOI at most one pixel past the border is pulled back inside: the sub-pixel
            // stage accepts a residual of up to one pixel.
            let max_x = deformed.width_px as i64 - n as i64;
            let max_y = deformed.height_px as i64 - n as i64;
            let (gx, gy) = (x0 as i64 + ix, y0 as i64 + iy);
            let (cx, cy) = (gx.clamp(0, max_x), gy.clamp(0, max_y));
            if (cx - gx).abs() <= 1 && (cy - gy).abs() <= 1 {
                ix += cx - gx;
                iy += cy - gy;
            }
            let (gx, gy) = (x0 as i64 + ix, y0 as i64 + iy);
            if !deformed.contains_block(gx, gy, n) {
                result.status = NodeStatus::OutsideImage;
                return result;
            }
            if !self.extract_zero_mean(deformed, gx as usize, gy as usize) {
                result.status = NodeStatus::LowContrast;
                return result;
            }
            timer.lap(&mut self.split.other_ns);
            if pass == 1 {
                break;
            }
            self.fft.forward(&self.g_spatial, &mut self.g_spectrum);
            for ((w, &g), &f) in self
                .work
                .iter_mut()
                .zip(&self.g_spectrum)
                .zip(reference.plain)
            {
                *w = g * f.conj();
            }
            self.fft.inverse(&mut self.work, &mut self.corr);
            timer.lap(&mut self.split.fft_ns);
            let (dx, dy) = self.argmax_wrapped();
            timer.lap(&mut self.split.peak_ns);
            if dx == 0 && dy == 0 {
                spectrum_valid = true;
                break;
            }
            ix += dx;
            iy += dy;
        }
        if !spectrum_valid {
            self.fft.forward(&self.g_spatial, &mut self.g_spectrum);
            timer.lap(&mut self.split.fft_ns);
        }
        // Sub-pixel iterations: window, correlate, quadratic peak, Fourier shift.
        let scale = 1.0 / (n * n) as f32;
        let mut shift = (0.0f64, 0.0f64);
        let mut best_value = f64::NEG_INFINITY;
        let mut best_estimate = (0.0f64, 0.0f64);
        let mut last_step = f64::INFINITY;
        let mut converged = false;
        for iteration in 0..max_iterations {
            if iteration > 0 {
                self.shift_into_spatial(shift);
                timer.lap(&mut self.split.shift_ns);
            }
            let mut real = std::mem::take(&mut self.windowed);
            let windowed = self.window_into(&mut real);
            self.windowed = real;
            timer.lap(&mut self.split.window_ns);
            if windowed.is_none() {
                result.status = NodeStatus::LowContrast;
                return result;
            }
            self.fft.forward(&self.windowed, &mut self.work);
            for (w, &f) in self.work.iter_mut().zip(reference.windowed) {
                *w *= f.conj();
            }
            self.fft.inverse(&mut self.work, &mut self.corr);
            timer.lap(&mut self.split.fft_ns);
            let (px, py) = self.argmax_near_zero();
            let neighbourhood = self.neighbourhood(px, py, scale);
            let (fx, fy, value) = quadratic_peak_3x3(&neighbourhood);
            timer.lap(&mut self.split.peak_ns);
            result.iterations = iteration + 1;
            if value <= best_value {
                converged = true;
                break;
            }
            best_value = value;
            let step = (px as f64 + fx, py as f64 + fy);
            best_estimate = (shift.0 + step.0, shift.1 + step.1);
            last_step = step.0.abs().max(step.1.abs());
            shift = best_estimate;
            if last_step < CONVERGED_STEP_PX {
                converged = true;
                break;
            }
            if shift.0.abs() > MAX_SUBPIXEL_DRIFT_PX || shift.1.abs() > MAX_SUBPIXEL_DRIFT_PX {
                break;
            }
        }
        result.u_px = ix as f64 + best_estimate.0;
        result.v_px = iy as f64 + best_estimate.1;
        result.score = best_value.clamp(-1.0, 1.0);
        let drifted = best_estimate.0.abs() > MAX_SUBPIXEL_DRIFT_PX
            || best_estimate.1.abs() > MAX_SUBPIXEL_DRIFT_PX;
        result.status = if !drifted && (converged || last_step < NOT_CONVERGED_STEP_PX) {
            NodeStatus::Ok
        } else {
            NodeStatus::NotConverged
        };
        result
    }

    /// g_spatial = real(IFFT(G · exp(+2πj k·d / n))): the deformed ZOI moved back by d.
    fn shift_into_spatial(&mut self, d: (f64, f64)) {
        let n = self.n;
        let two_pi_over_n = 2.0 * std::f64::consts::PI / n as f64;
        for k in 0..n {
            let f = signed_frequency(k, n) as f64;
            let (sx, cx) = (two_pi_over_n * f * d.0).sin_cos();
            let (sy, cy) = (two_pi_over_n * f * d.1).sin_cos();
            self.phase_x[k] = Complex32::new(cx as f32, sx as f32);
            self.phase_y[k] = Complex32::new(cy as f32, sy as f32);
        }
        // Nyquist bins: +n/2 and -n/2 are the same bin; the symmetric shift factor is their
        // mean, cos(π d), which keeps the shifted ZOI real without favouring a direction.
        self.phase_x[n / 2] = Complex32::new((std::f64::consts::PI * d.0).cos() as f32, 0.0);
        self.phase_y[n / 2] = Complex32::new((std::f64::consts::PI * d.1).cos() as f32, 0.0);
        // Half-spectrum layout: index kx * n + ky, kx in 0..=n/2.
        for kx in 0..=n / 2 {
            let px = self.phase_x[kx];
            let row = &mut self.work[kx * n..(kx + 1) * n];
            let src = &self.g_spectrum[kx * n..(kx + 1) * n];
            for ((w, &g), &py) in row.iter_mut().zip(src).zip(&self.phase_y) {
                *w = g * (px * py);
            }
        }
        self.fft.inverse(&mut self.work, &mut self.g_spatial);
        let scale = 1.0 / (n * n) as f32;
        for g in self.g_spatial.iter_mut() {
            *g *= scale;
        }
    }

    /// Integer location of the maximum of the real correlation map, wrapped to [-n/2, n/2).
    fn argmax_wrapped(&self) -> (i64, i64) {
        let n = self.n;
        let mut best = f32::NEG_INFINITY;
        let mut best_index = 0;
        for (i, &c) in self.corr.iter().enumerate() {
            if c > best {
                best = c;
                best_index = i;
            }
        }
        let wrap = |k: usize| {
            if k >= n / 2 {
                k as i64 - n as i64
            } else {
                k as i64
            }
        };
        (wrap(best_index % n), wrap(best_index / n))
    }

    /// Integer maximum within ±1 px of zero shift (the integer step put the peak there).
    fn argmax_near_zero(&self) -> (i64, i64) {
        let mut best = f32::NEG_INFINITY;
        let mut at = (0, 0);
        for dy in -1i64..=1 {
            for dx in -1i64..=1 {
                let v = self.corr[self.wrap_index(dx, dy)];
                if v > best {
                    best = v;
                    at = (dx, dy);
                }
            }
        }
        at
    }

    #[inline]
    fn wrap_index(&self, dx: i64, dy: i64) -> usize {
        let n = self.n as i64;
        let x = dx.rem_euclid(n) as usize;
        let y = dy.rem_euclid(n) as usize;
        y * self.n + x
    }

    fn neighbourhood(&self, px: i64, py: i64, scale: f32) -> [[f32; 3]; 3] {
        let mut c = [[0.0f32; 3]; 3];
        for (row, values) in c.iter_mut().enumerate() {
            for (col, v) in values.iter_mut().enumerate() {
                let idx = self.wrap_index(px + col as i64 - 1, py + row as i64 - 1);
                *v = self.corr[idx] * scale;
            }
        }
        c
    }
}
