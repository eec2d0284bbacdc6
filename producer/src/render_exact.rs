//! The `exact` renderer: the analytic pattern evaluated at φ⁻¹(x) and integrated over each
//! camera pixel's area with an n x n Gauss-Legendre rule. Slow; the ground truth.

use crate::camera::CameraModel;
use crate::field_motion::{FieldMotion, BACKDROP};
use crate::motion::Motion;
use crate::parallel::for_row_bands;
use crate::speckle::{Speckle, SpeckleParams};

/// The accuracy tests' frame: the default speckle (seed 1) covering the image plus `margin_px`
/// on every side, moved by `motion`, rendered exactly (Gauss order 3) and exposed by
/// [`CameraModel::read_noise_only_16bit`] with read noise `noise` (fraction of full scale)
/// and noise seed `seed`, on 2 threads.
pub fn exact_test_frame(
    width: usize,
    height: usize,
    margin_px: f64,
    motion: &Motion,
    noise: f64,
    seed: u64,
) -> Vec<u16> {
    let speckle = Speckle::new(
        SpeckleParams::default(),
        [-margin_px, width as f64 + margin_px],
        [-margin_px, height as f64 + margin_px],
    );
    let mut pattern = vec![0f32; width * height];
    ExactRenderer {
        gauss_order: 3,
        threads: 2,
    }
    .render(&speckle, motion, width, &mut pattern);
    CameraModel::read_noise_only_16bit(noise, seed).exposed(seed, &pattern, width, 2)
}

/// Largest Gauss-Legendre order supported per axis.
pub const MAX_GAUSS_ORDER: usize = 6;

/// Gauss-Legendre nodes and weights on [-1, 1] for n = 1..=6.
pub fn gauss_legendre(n: usize) -> (&'static [f64], &'static [f64]) {
    const N1: [f64; 1] = [0.0];
    const W1: [f64; 1] = [2.0];
    const N2: [f64; 2] = [-0.577_350_269_189_625_8, 0.577_350_269_189_625_8];
    const W2: [f64; 2] = [1.0, 1.0];
    const N3: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
    const W3: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    const N4: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const W4: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    const N5: [f64; 5] = [
        -0.906_179_845_938_664,
        -0.538_469_310_105_683_1,
        0.0,
        0.538_469_310_105_683_1,
        0.906_179_845_938_664,
    ];
    const W5: [f64; 5] = [
        0.236_926_885_056_189_1,
        0.478_628_670_499_366_5,
        0.568_888_888_888_888_9,
        0.478_628_670_499_366_5,
        0.236_926_885_056_189_1,
    ];
    const N6: [f64; 6] = [
        -0.932_469_514_203_152,
        -0.661_209_386_466_264_5,
        -0.238_619_186_083_196_9,
        0.238_619_186_083_196_9,
        0.661_209_386_466_264_5,
        0.932_469_514_203_152,
    ];
    const W6: [f64; 6] = [
        0.171_324_492_379_170_3,
        0.360_761_573_048_138_6,
        0.467_913_934_572_691,
        0.467_913_934_572_691,
        0.360_761_573_048_138_6,
        0.171_324_492_379_170_3,
    ];
    match n {
        1 => (&N1, &W1),
        2 => (&N2, &W2),
        3 => (&N3, &W3),
        4 => (&N4, &W4),
        5 => (&N5, &W5),
        6 => (&N6, &W6),
        _ => panic!("Gauss-Legendre order {n} outside 1..={MAX_GAUSS_ORDER}"),
    }
}

/// Exact renderer settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExactRenderer {
    /// Gauss-Legendre points per axis per pixel (1..=6; 4 is ample for speckles >= 2 px).
    pub gauss_order: usize,
    /// Threads.
    pub threads: usize,
}

impl Default for ExactRenderer {
    fn default() -> Self {
        ExactRenderer {
            gauss_order: 4,
            threads: crate::parallel::default_threads(),
        }
    }
}

impl ExactRenderer {
    /// Renders the mean of p(φ⁻¹(x)) over each pixel of a `width` x rows frame into `out`
    /// (row-major, values in [0, 1]).
    pub fn render(&self, speckle: &Speckle, motion: &Motion, width: usize, out: &mut [f32]) {
        self.render_inverse(speckle, width, out, |x| Some(motion.inverse(x)));
    }

    /// [`Self::render`] under a finite-element field: a point of a pixel that shows no
    /// material counts as [`BACKDROP`], so a pixel on the specimen's edge is the mean of both.
    pub fn render_field(
        &self,
        speckle: &Speckle,
        field: &FieldMotion,
        width: usize,
        out: &mut [f32],
    ) {
        self.render_inverse(speckle, width, out, |x| field.inverse(x));
    }

    /// The mean over each pixel of p(X) where `inverse` gives X = φ⁻¹(x), [`BACKDROP`] where it
    /// gives none.
    fn render_inverse(
        &self,
        speckle: &Speckle,
        width: usize,
        out: &mut [f32],
        inverse: impl Fn([f64; 2]) -> Option<[f64; 2]> + Sync,
    ) {
        let (nodes, weights) = gauss_legendre(self.gauss_order);
        for_row_bands(out, width, self.threads, |first_row, band| {
            for (r, row) in band.chunks_exact_mut(width).enumerate() {
                let y = (first_row + r) as f64;
                for (col, value) in row.iter_mut().enumerate() {
                    let x = col as f64;
                    let mut sum = 0.0;
                    for (ny, wy) in nodes.iter().zip(weights) {
                        for (nx, wx) in nodes.iter().zip(weights) {
                            let point = match inverse([x + 0.5 * nx, y + 0.5 * ny]) {
                                Some(p) => speckle.value(p),
                                None => f64::from(BACKDROP),
                            };
                            sum += wx * wy * point;
                        }
                    }
                    *value = (0.25 * sum) as f32;
                }
            }
        });
    }
}
