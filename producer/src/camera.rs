//! The camera model: pattern value p in [0, 1] → photo-electrons → grey levels.
//! N_e = illumination_e p; with shot noise, N_e ~ Normal(N_e, √N_e) (the Gaussian limit of the
//! Poisson law, accurate above ~20 e⁻); DN = offset_dn + gain_dn_per_e N_e + Normal(0,
//! read_noise_dn), rounded, clipped to [0, 2^bit_depth - 1] (saturation). The two normals are
//! drawn as one, of the summed variance gain² N_e + read_noise_dn² (one draw per pixel). Optional Gaussian
//! blur (optics) of the pattern before exposure. Noise is reproducible: one generator per
//! (seed, frame, row), so results do not depend on the thread count.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::error::ProducerError;
use crate::parallel::for_row_bands;

/// Bit depths a camera may have.
pub const BIT_DEPTHS: [u8; 4] = [8, 10, 12, 16];

/// Camera settings.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraModel {
    /// 8, 10, 12 or 16.
    pub bit_depth: u8,
    /// Photo-electrons collected at pattern value 1.
    pub illumination_e: f64,
    /// Grey levels per electron.
    pub gain_dn_per_e: f64,
    /// Black level, DN.
    pub offset_dn: f64,
    /// Read noise standard deviation, DN.
    pub read_noise_dn: f64,
    /// Photon (shot) noise on or off.
    pub shot_noise: bool,
    /// Gaussian blur σ of the optics, px (0: none).
    pub blur_sigma_px: f64,
    /// Noise seed.
    pub seed: u64,
}

impl CameraModel {
    /// A camera of `bit_depth` bits: 10 000 e⁻ at p = 1, black level 5 % and white level 90 %
    /// of full scale, read noise 0.2 % of full scale, shot noise on, no blur.
    pub fn with_bit_depth(bit_depth: u8) -> Self {
        let full_scale_dn = Self::max_dn_of(bit_depth);
        let illumination_e = 10_000.0;
        CameraModel {
            bit_depth,
            illumination_e,
            gain_dn_per_e: 0.85 * full_scale_dn / illumination_e,
            offset_dn: 0.05 * full_scale_dn,
            read_noise_dn: 0.002 * full_scale_dn,
            shot_noise: true,
            blur_sigma_px: 0.0,
            seed: 1,
        }
    }

    /// A noiseless camera (for truth comparisons).
    pub fn noiseless(bit_depth: u8) -> Self {
        CameraModel {
            read_noise_dn: 0.0,
            shot_noise: false,
            ..Self::with_bit_depth(bit_depth)
        }
    }

    /// A 16-bit camera whose only noise is Gaussian read noise of `fraction` of full scale,
    /// seeded: the camera of the accuracy tests and the correlator benchmarks.
    pub fn read_noise_only_16bit(fraction: f64, seed: u64) -> Self {
        CameraModel {
            read_noise_dn: fraction * Self::max_dn_of(16),
            seed,
            ..Self::noiseless(16)
        }
    }

    fn max_dn_of(bit_depth: u8) -> f64 {
        f64::from((1u32 << bit_depth.min(16)) - 1)
    }

    /// Saturation level 2^bit_depth - 1, DN.
    pub fn max_dn(&self) -> u16 {
        Self::max_dn_of(self.bit_depth) as u16
    }

    /// Checks the settings; errors name the parameter and the valid range.
    pub fn validate(&self) -> Result<(), ProducerError> {
        let bad = |name: &str, value: String, expected: &str| {
            Err(ProducerError::InvalidParameter {
                name: name.to_owned(),
                value,
                expected: expected.to_owned(),
            })
        };
        if !BIT_DEPTHS.contains(&self.bit_depth) {
            return bad("bit_depth", self.bit_depth.to_string(), "8, 10, 12 or 16");
        }
        let checks = [
            (
                "illumination_e",
                self.illumination_e,
                self.illumination_e > 0.0,
            ),
            (
                "gain_dn_per_e",
                self.gain_dn_per_e,
                self.gain_dn_per_e > 0.0,
            ),
            ("offset_dn", self.offset_dn, self.offset_dn.is_finite()),
            (
                "read_noise_dn",
                self.read_noise_dn,
                self.read_noise_dn >= 0.0,
            ),
            (
                "blur_sigma_px",
                self.blur_sigma_px,
                (0.0..=16.0).contains(&self.blur_sigma_px),
            ),
        ];
        for (name, value, ok) in checks {
            if !(ok && value.is_finite()) {
                return bad(name, value.to_string(), "a finite value in range");
            }
        }
        Ok(())
    }

    /// Exposes the pattern values `pattern` (rows of `width`) of frame `frame_index` into `out`.
    /// [`Self::expose`] into a new frame.
    pub fn exposed(
        &self,
        frame_index: u64,
        pattern: &[f32],
        width: usize,
        threads: usize,
    ) -> Vec<u16> {
        let mut out = vec![0u16; pattern.len()];
        self.expose(frame_index, pattern, width, &mut out, threads);
        out
    }

    pub fn expose(
        &self,
        frame_index: u64,
        pattern: &[f32],
        width: usize,
        out: &mut [u16],
        threads: usize,
    ) {
        assert_eq!(pattern.len(), out.len(), "pattern and frame sizes differ");
        for_row_bands(out, width, threads, |first_row, band| {
            for (r, row) in band.chunks_exact_mut(width).enumerate() {
                let y = first_row + r;
                self.expose_row(frame_index, y, &pattern[y * width..][..width], row);
            }
        });
    }

    /// Exposes the pattern values `pattern_row` of row `y` of frame `frame_index` into `out`:
    /// the same grey levels as that row of [`Self::expose`] (one noise stream per row).
    pub fn expose_row(&self, frame_index: u64, y: usize, pattern_row: &[f32], out: &mut [u16]) {
        assert_eq!(pattern_row.len(), out.len(), "pattern and row sizes differ");
        let grey = self.grey_map();
        let mut rng = ChaCha8Rng::seed_from_u64(mix(self.seed, frame_index, y as u64));
        // A chunk's normal draws first (the generator's loop, with the ziggurat's rare slow
        // paths), then its grey levels in a loop free of branches, which the compiler runs in
        // vector lanes.
        let mut z = [0.0f64; EXPOSE_CHUNK_PX];
        for (out, pattern) in out
            .chunks_mut(EXPOSE_CHUNK_PX)
            .zip(pattern_row.chunks(EXPOSE_CHUNK_PX))
        {
            let z = &mut z[..out.len()];
            if grey.noisy {
                z.iter_mut()
                    .for_each(|z| *z = StandardNormal.sample(&mut rng));
            }
            for ((o, &p), &z) in out.iter_mut().zip(pattern).zip(z.iter()) {
                let p = f64::from(p).max(0.0);
                let dn = grey.offset_dn + grey.dn_per_p * p + z * grey.sigma_dn(p);
                *o = quantise(dn, grey.max_dn);
            }
        }
    }

    /// The pattern value's grey level and noise, in the pattern's units (made once per row).
    fn grey_map(&self) -> GreyMap {
        let gain = self.gain_dn_per_e;
        // Shot noise in DN has variance gain² N_e = gain² illumination p; the read noise's adds
        // to it: one normal draw per pixel carries both (their sum is normal with the summed
        // variance).
        let shot_var_dn2_per_p = if self.shot_noise {
            gain * gain * self.illumination_e
        } else {
            0.0
        };
        GreyMap {
            offset_dn: self.offset_dn,
            dn_per_p: gain * self.illumination_e,
            shot_var_dn2_per_p,
            read_var_dn2: self.read_noise_dn * self.read_noise_dn,
            noisy: self.shot_noise || self.read_noise_dn > 0.0,
            max_dn: f64::from(self.max_dn()),
        }
    }
}

/// Pixels whose normal draws are made together before their grey levels.
const EXPOSE_CHUNK_PX: usize = 64;

/// Pattern value p ≥ 0 to grey level: mean offset + dn_per_p p, standard deviation
/// √(shot_var_dn2_per_p p + read_var_dn2).
#[derive(Clone, Copy, Debug)]
struct GreyMap {
    offset_dn: f64,
    dn_per_p: f64,
    shot_var_dn2_per_p: f64,
    read_var_dn2: f64,
    noisy: bool,
    max_dn: f64,
}

impl GreyMap {
    #[inline(always)]
    fn sigma_dn(&self, p: f64) -> f64 {
        (self.shot_var_dn2_per_p * p + self.read_var_dn2).sqrt()
    }
}

/// `dn` rounded to the nearest level and clipped to [0, `max_dn`] (saturation). Rounds half
/// up (`f64::round` is a library call on the baseline x86-64 target; this is two
/// instructions). The clipped value is within i32, whose conversion has a vector instruction
/// (a cast straight to u16 would saturate again).
#[inline(always)]
fn quantise(dn: f64, max_dn: f64) -> u16 {
    (dn.clamp(0.0, max_dn) + 0.5) as i32 as u16
}

/// SplitMix64 of the three, for independent per-row streams.
fn mix(seed: u64, frame: u64, row: u64) -> u64 {
    let mut z =
        seed ^ frame.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ row.wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A separable Gaussian blur with its kernel and scratch made once.
#[derive(Debug)]
pub struct Blur {
    kernel: Vec<f32>,
    scratch: Vec<f32>,
}

impl Blur {
    /// A blur of `sigma_px` (> 0) for frames of `len_px` pixels; kernel radius ⌈3σ⌉.
    pub fn new(sigma_px: f64, len_px: usize) -> Self {
        assert!(sigma_px > 0.0 && sigma_px <= 16.0, "blur sigma {sigma_px}");
        let radius = (3.0 * sigma_px).ceil() as isize;
        let mut kernel: Vec<f32> = (-radius..=radius)
            .map(|k| (-(k * k) as f64 / (2.0 * sigma_px * sigma_px)).exp() as f32)
            .collect();
        let total: f32 = kernel.iter().sum();
        kernel.iter_mut().for_each(|k| *k /= total);
        Blur {
            kernel,
            scratch: vec![0.0; len_px],
        }
    }

    /// Blurs `image` (rows of `width`) in place; edges are clamped.
    pub fn apply(&mut self, image: &mut [f32], width: usize, threads: usize) {
        assert_eq!(
            image.len(),
            self.scratch.len(),
            "blur made for another size"
        );
        let height = image.len() / width;
        let kernel = &self.kernel;
        let radius = (kernel.len() / 2) as isize;
        let src: &[f32] = image;
        for_row_bands(&mut self.scratch, width, threads, |first_row, band| {
            for (r, row) in band.chunks_exact_mut(width).enumerate() {
                let line = &src[(first_row + r) * width..][..width];
                for (x, o) in row.iter_mut().enumerate() {
                    let mut sum = 0.0;
                    for (k, w) in kernel.iter().enumerate() {
                        let xi = (x as isize + k as isize - radius).clamp(0, width as isize - 1);
                        sum += w * line[xi as usize];
                    }
                    *o = sum;
                }
            }
        });
        let scratch: &[f32] = &self.scratch;
        for_row_bands(image, width, threads, |first_row, band| {
            for (r, row) in band.chunks_exact_mut(width).enumerate() {
                let y = (first_row + r) as isize;
                row.fill(0.0);
                for (k, w) in kernel.iter().enumerate() {
                    let yi = (y + k as isize - radius).clamp(0, height as isize - 1) as usize;
                    for (o, s) in row.iter_mut().zip(&scratch[yi * width..][..width]) {
                        *o += w * s;
                    }
                }
            }
        });
    }
}
