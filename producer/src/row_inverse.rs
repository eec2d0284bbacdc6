//! φ⁻¹ along a row of pixels for any motion that gives φ and its gradient F at a point: the
//! general path of the renderers, the one a heterogeneous (finite-element) field takes, where
//! there is no closed-form inverse per pixel.
//!
//! The row's first pixel is inverted by the motion itself ([`Motion::inverse`]); each next
//! pixel starts from the previous pixel's X advanced by F⁻¹ (1, 0) (the first-order predictor,
//! exact for an affine map) and is corrected by 2-D Newton, X ← X − F(X)⁻¹ (φ(X) − x), until the
//! step is below [`NEWTON_TOLERANCE_PX`]: as exact as the motion's own inverse, at one or two
//! evaluations of φ and F per pixel. A pixel whose Newton does not converge within
//! [`NEWTON_MAX_ITERATIONS`] (a predictor too far off on a steep field) is inverted by the
//! motion itself, so the result never depends on the predictor.

use crate::motion::{
    inverse, mul_vec, Mat2, Motion, Vec2, NEWTON_MAX_ITERATIONS, NEWTON_TOLERANCE_PX,
};

/// The inverse of one row of pixels, column by column from 0.
#[derive(Debug)]
pub struct RowInverse<'a> {
    motion: &'a Motion,
    y_px: f64,
    /// X of the previous column and F⁻¹ there.
    previous: Option<(Vec2, Mat2)>,
    /// Newton steps taken so far (the predictor's quality, for tests).
    pub newton_steps: u64,
    /// Pixels inverted by the motion itself after Newton failed to converge.
    pub fallbacks: u64,
}

impl<'a> RowInverse<'a> {
    /// The inverse along row `y_px` of `motion`.
    pub fn new(motion: &'a Motion, y_px: f64) -> Self {
        RowInverse {
            motion,
            y_px,
            previous: None,
            newton_steps: 0,
            fallbacks: 0,
        }
    }

    /// X = φ⁻¹(x, y) of the next column `x_px` (columns in increasing order, 1 px apart).
    pub fn next(&mut self, x_px: f64) -> Vec2 {
        let target = [x_px, self.y_px];
        let p = match self.previous {
            None => self.motion.inverse(target),
            Some((p, f_inv)) => {
                let step = mul_vec(&f_inv, [1.0, 0.0]);
                let guess = [p[0] + step[0], p[1] + step[1]];
                self.newton(guess, target).unwrap_or_else(|| {
                    self.fallbacks += 1;
                    self.motion.inverse(target)
                })
            }
        };
        self.previous = Some((p, inverse(&self.motion.gradient(p))));
        p
    }

    /// Newton from `guess` to φ(X) = `target`; None when it does not converge.
    fn newton(&mut self, guess: Vec2, target: Vec2) -> Option<Vec2> {
        let mut p = guess;
        for _ in 0..NEWTON_MAX_ITERATIONS {
            let x = self.motion.forward(p);
            let f = self.motion.gradient(p);
            // A fold (or NaN) is no place to continue from.
            if crate::motion::det(&f).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return None;
            }
            let step = mul_vec(&inverse(&f), [x[0] - target[0], x[1] - target[1]]);
            p = [p[0] - step[0], p[1] - step[1]];
            self.newton_steps += 1;
            if step[0].abs().max(step[1].abs()) < NEWTON_TOLERANCE_PX {
                return Some(p);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::{Affine, Bulge, Chirp};

    fn motions() -> Vec<Motion> {
        vec![
            Motion::Chirp(Chirp {
                amplitude_px: 0.5,
                start_px: 20.0,
                length_px: 200.0,
                periods: 4.0,
            }),
            Motion::Bulge(Bulge {
                strain: 0.3,
                width_px: 40.0,
                centre_px: [100.0, 80.0],
            }),
            Motion::Affine(Affine {
                f: [[1.4, 0.1], [-0.05, 0.8]],
                translation_px: [2.5, -3.0],
                centre_px: [100.0, 80.0],
            }),
        ]
    }

    /// Row by row, the warm-started inverse is the motion's own Newton (or closed-form)
    /// inverse to 1e-9 px, without falling back, in at most 3.5 Newton steps per pixel (the
    /// last one the check).
    #[test]
    fn row_inverse_equals_the_motions_inverse() {
        for motion in motions() {
            let (mut worst, mut steps, mut pixels) = (0.0f64, 0u64, 0u64);
            for y in (0..160).step_by(7) {
                let mut row = RowInverse::new(&motion, y as f64);
                for x in 0..200 {
                    let got = row.next(x as f64);
                    let expected = motion.inverse([x as f64, y as f64]);
                    worst = worst.max(
                        (got[0] - expected[0])
                            .abs()
                            .max((got[1] - expected[1]).abs()),
                    );
                    // And it is an inverse: φ(X) = x.
                    let back = motion.forward(got);
                    assert!((back[0] - x as f64).abs() < 1e-9 && (back[1] - y as f64).abs() < 1e-9);
                }
                assert_eq!(row.fallbacks, 0, "{motion:?}");
                steps += row.newton_steps;
                pixels += 199;
            }
            eprintln!(
                "{motion:?}: worst {worst:.1e} px, {:.2} Newton steps per pixel",
                steps as f64 / pixels as f64
            );
            assert!(worst < 1e-9, "{motion:?}: {worst} px");
            assert!(
                2 * steps <= 7 * pixels,
                "{motion:?}: {steps} steps for {pixels} pixels"
            );
        }
    }
}
