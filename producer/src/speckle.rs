//! The speckle pattern: an analytic, random, isotropic sum of Gaussian spots, reproducible from
//! a seed. Value at a reference point X (px):
//! p(X) = (1 - c) / 2 + c (1 - exp(-S(X))), S(X) = Σ a_k exp(-|X - X_k|² / (2 σ_k²)),
//! with contrast c; each spot is cut at |X - X_k| = 5 σ_k (a tail below 4e-6 of its peak).
//! p is in [0, 1]; the camera maps it to grey levels.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::ProducerError;
use crate::motion::Vec2;

/// Spot cut-off radius, in units of the spot's σ.
pub const CUTOFF_SIGMAS: f64 = 5.0;
/// FWHM of a Gaussian in units of σ: 2 sqrt(2 ln 2).
const FWHM_PER_SIGMA: f64 = 2.354_820_045_030_949;

/// Tunable pattern parameters.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeckleParams {
    /// Mean speckle size (spot full width at half maximum), px. Spots vary ±20 % around it.
    pub size_px: f64,
    /// Mean number of spots per spot area (π (size/2)²); about the covered fraction.
    pub density: f64,
    /// Contrast c in (0, 1]: p spans [(1 - c) / 2, (1 + c) / 2].
    pub contrast: f64,
    /// Seed of the spot positions, sizes and amplitudes.
    pub seed: u64,
}

impl Default for SpeckleParams {
    fn default() -> Self {
        SpeckleParams {
            size_px: 4.0,
            density: 0.35,
            contrast: 0.9,
            seed: 1,
        }
    }
}

impl SpeckleParams {
    /// Checks the ranges; errors name the parameter.
    pub fn validate(&self) -> Result<(), ProducerError> {
        let bad = |name: &str, value: f64, expected: &str| {
            Err(ProducerError::InvalidParameter {
                name: name.to_owned(),
                value: value.to_string(),
                expected: expected.to_owned(),
            })
        };
        if !(self.size_px >= 1.0 && self.size_px <= 64.0) {
            return bad("speckle size_px", self.size_px, "a size in [1, 64] px");
        }
        if !(self.density > 0.0 && self.density <= 5.0) {
            return bad("speckle density", self.density, "a density in (0, 5]");
        }
        if !(self.contrast > 0.0 && self.contrast <= 1.0) {
            return bad("speckle contrast", self.contrast, "a contrast in (0, 1]");
        }
        Ok(())
    }
}

/// One Gaussian spot.
#[derive(Clone, Copy, Debug)]
pub struct Spot {
    /// Centre, px.
    pub centre_px: Vec2,
    /// 1 / (2 σ²), px⁻².
    pub inv_two_sigma2: f64,
    /// Cut-off radius squared, px².
    pub cutoff2_px2: f64,
    /// Amplitude a.
    pub amplitude: f64,
}

/// The pattern over a rectangle of the reference plane, with a uniform grid of cells for
/// evaluation at any point (each cell lists the spots whose cut-off disc meets it).
#[derive(Debug)]
pub struct Speckle {
    params: SpeckleParams,
    spots: Vec<Spot>,
    /// Spots live in [origin, origin + extent]; outside, S = 0 but for tails.
    origin_px: Vec2,
    cell_px: f64,
    cells_x: usize,
    cells_y: usize,
    cell_start: Vec<u32>,
    cell_spots: Vec<u32>,
    max_cutoff_px: f64,
}

impl Speckle {
    /// A pattern covering `[x0, x1] x [y0, y1]` (px, reference coordinates).
    pub fn new(params: SpeckleParams, x_range_px: [f64; 2], y_range_px: [f64; 2]) -> Self {
        params
            .validate()
            .expect("speckle params validated by the caller");
        let (x0, x1, y0, y1) = (x_range_px[0], x_range_px[1], y_range_px[0], y_range_px[1]);
        assert!(x1 > x0 && y1 > y0, "empty speckle area");
        let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
        let sigma_px = params.size_px / FWHM_PER_SIGMA;
        let spot_area_px2 = std::f64::consts::PI * (params.size_px / 2.0).powi(2);
        let area_px2 = (x1 - x0) * (y1 - y0);
        let count = (params.density * area_px2 / spot_area_px2).round() as usize;
        assert!(count < 200_000_000, "too many spots: {count}");
        let mut spots = Vec::with_capacity(count);
        let mut max_cutoff_px: f64 = 0.0;
        for _ in 0..count {
            let s = sigma_px * rng.random_range(0.8..1.2);
            let cutoff = CUTOFF_SIGMAS * s;
            max_cutoff_px = max_cutoff_px.max(cutoff);
            spots.push(Spot {
                centre_px: [rng.random_range(x0..x1), rng.random_range(y0..y1)],
                inv_two_sigma2: 1.0 / (2.0 * s * s),
                cutoff2_px2: cutoff * cutoff,
                amplitude: rng.random_range(1.0..2.0),
            });
        }
        // Grid over the area grown by the largest cut-off, cells of that size.
        let cell_px = max_cutoff_px.max(1.0);
        let origin_px = [x0 - cell_px, y0 - cell_px];
        let cells_x = ((x1 - x0) / cell_px).ceil() as usize + 3;
        let cells_y = ((y1 - y0) / cell_px).ceil() as usize + 3;
        let mut counts = vec![0u32; cells_x * cells_y + 1];
        let cell_range = |spot: &Spot, axis: usize, cells: usize| {
            let r = spot.cutoff2_px2.sqrt();
            let lo = ((spot.centre_px[axis] - r - origin_px[axis]) / cell_px).floor();
            let hi = ((spot.centre_px[axis] + r - origin_px[axis]) / cell_px).floor();
            (lo.max(0.0) as usize, (hi.max(0.0) as usize).min(cells - 1))
        };
        for pass in 0..2 {
            let mut fill = counts.clone();
            let mut cell_spots = vec![
                0u32;
                if pass == 1 {
                    counts[cells_x * cells_y] as usize
                } else {
                    0
                }
            ];
            for (k, spot) in spots.iter().enumerate() {
                let (ix0, ix1) = cell_range(spot, 0, cells_x);
                let (iy0, iy1) = cell_range(spot, 1, cells_y);
                for iy in iy0..=iy1 {
                    for ix in ix0..=ix1 {
                        let cell = iy * cells_x + ix;
                        if pass == 0 {
                            counts[cell + 1] += 1;
                        } else {
                            cell_spots[fill[cell] as usize] = k as u32;
                            fill[cell] += 1;
                        }
                    }
                }
            }
            if pass == 0 {
                for i in 0..cells_x * cells_y {
                    counts[i + 1] += counts[i];
                }
            } else {
                return Speckle {
                    params,
                    spots,
                    origin_px,
                    cell_px,
                    cells_x,
                    cells_y,
                    cell_start: counts,
                    cell_spots,
                    max_cutoff_px,
                };
            }
        }
        unreachable!("two passes build the grid")
    }

    /// The parameters.
    pub fn params(&self) -> &SpeckleParams {
        &self.params
    }

    /// All spots.
    pub fn spots(&self) -> &[Spot] {
        &self.spots
    }

    /// Largest spot cut-off radius, px.
    pub fn max_cutoff_px(&self) -> f64 {
        self.max_cutoff_px
    }

    /// The spot sum S(X).
    pub fn spot_sum(&self, p: Vec2) -> f64 {
        let fx = (p[0] - self.origin_px[0]) / self.cell_px;
        let fy = (p[1] - self.origin_px[1]) / self.cell_px;
        if !(fx >= 0.0 && fy >= 0.0) {
            return 0.0;
        }
        let (ix, iy) = (fx as usize, fy as usize);
        if ix >= self.cells_x || iy >= self.cells_y {
            return 0.0;
        }
        let cell = iy * self.cells_x + ix;
        let (start, end) = (
            self.cell_start[cell] as usize,
            self.cell_start[cell + 1] as usize,
        );
        let mut sum = 0.0;
        for &k in &self.cell_spots[start..end] {
            let spot = &self.spots[k as usize];
            let dx = p[0] - spot.centre_px[0];
            let dy = p[1] - spot.centre_px[1];
            let r2 = dx * dx + dy * dy;
            if r2 < spot.cutoff2_px2 {
                sum += spot.amplitude * (-r2 * spot.inv_two_sigma2).exp();
            }
        }
        sum
    }

    /// Maps a spot sum S to the pattern value p in [0, 1].
    pub fn value_from_sum(&self, sum: f64) -> f64 {
        let c = self.params.contrast;
        0.5 * (1.0 - c) + c * (1.0 - (-sum).exp())
    }

    /// The pattern value p(X) in [0, 1].
    pub fn value(&self, p: Vec2) -> f64 {
        self.value_from_sum(self.spot_sum(p))
    }
}
