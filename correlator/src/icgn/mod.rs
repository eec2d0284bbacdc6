//! Inverse compositional Gauss-Newton (IC-GN) sub-pixel registration of one subset, with the
//! ZNSSD criterion (Pan, Li, Tong, "Fast, robust and accurate digital image correlation
//! calculation without redundant computations", 2013; the algorithm of OpenCorr's
//! `oc_icgn.cpp`), first-order (6 parameters) or second-order (12) shape function
//! ([`shape`]), quintic B-spline interpolation of the deformed image ([`bspline`], its
//! coefficients computed once per frame), and the reference subset's normalised values,
//! gradients, Hessian and constant sums computed once per reference ([`subset`]).
//!
//! Each iteration samples the deformed subset g through the current warp W(p) and computes,
//! in one pass, Σ g', Σ g'², Σ f̂ g' and Σ J g' (g' = g − f_m, J the steepest-descent images);
//! with g_m and g_n the mean and norm of the samples, ĝ = (g − g_m)/g_n and r = Σ f̂ ĝ their
//! ZNCC, the ZNSSD gradient is b = r Σ J f̂ − Σ J ĝ = r Σ J f̂ − (Σ J g' − g'_m Σ J) / g_n, the
//! update Δp = −H⁻¹ b, and W(p) ← W(p) ∘ W(Δp)⁻¹. Both b and H (see [`subset`]) are those of
//! the ZNSSD itself, whose reference mean and norm also move with Δp: with Σ J f̂ in place of
//! r Σ J f̂ and H = Σ J Jᵀ (the usual simplification, OpenCorr's too) the updates of a small
//! subset's gradient terms are several times too short and the convergence is linear (ratio
//! 0.85 to 0.9 per iteration at 9 px, even without noise; a third of the 9 px subsets then
//! stopped at a 10-iteration cap); with them it takes 2 to 4 iterations. Offset and gain of the deformed image cancel in
//! (g − g_m)/g_n. The iterations stop when the update moves no point of the subset by more
//! than [`CONVERGED_PX`], or, from a guess whose error is noise (a node's prediction from its
//! previous values, [`Stop::WithinNoise`]), when the next update is predicted within a fraction
//! of the subset's own noise ([`PREDICTED_STEP_NOISE`]: the updates shrink by a nearly constant
//! ratio, so that one evaluation suffices from a guess within a few noise deviations); at the
//! cap the subset is `not_converged`. The result's score is the ZNCC of the last samples, 1 −
//! C/2 with C the ZNSSD (after an early stop, less half the last update's predicted decrease:
//! the ZNCC predicted at the final warp).
//!
//! Nothing here allocates: the caller owns every buffer.

pub mod bspline;
#[cfg(target_arch = "x86_64")]
mod evaluate_avx2;
mod first_order_sums;
pub mod order_choice;
pub mod shape;
pub mod subset;

use crate::field::NodeStatus;
use bspline::Coefficients;
use shape::{Order, Warp};
use subset::{SubsetStats, PLANES};

/// The iterations stop when the update moves no point of the subset by more than this (px).
pub const CONVERGED_PX: f64 = 1e-3;
/// The largest ratio of two successive updates the early stop trusts. The updates shrink
/// geometrically by a ratio that does not depend on their size (the reference's gradients,
/// central differences, are not quite the B-spline model's the deformed image is sampled with):
/// 0.017 median, 0.033 p99, 0.050 at most over the 34,600 subsets of `dicstream bench correlate
/// --method icgn1 --zoi 33 --frames 3`, with the first update from 0.008 to 0.035 px (p10 to
/// p99) at the subset's edge.
pub const MAX_CONTRACTION: f64 = 0.1;
/// The iterations also stop when the next update, at most [`MAX_CONTRACTION`] times the last,
/// is predicted below this fraction of the subset's own noise: |Δp| in the metric of H (the
/// update's predicted decrease of the ZNSSD, bᵀ H⁻¹ b) against the covariance the residual
/// leaves the parameters (σ² H⁻¹, σ² the ZNSSD predicted after the update over n² − P). What
/// is left of the update then adds at most a quarter of that noise's variance to the parameters
/// (at the bound's ratio; at the median measured ratio under 1 %); a noise-free subset never
/// stops early. On the bench's
/// frames the first update is 2.6 noise deviations (median; p90 4.2): one evaluation instead of
/// two on nearly every subset.
pub const PREDICTED_STEP_NOISE: f64 = 0.5;
/// A subset whose samples' standard deviation is below this (counts) is `low_contrast`.
const MIN_DEFORMED_STD: f64 = 0.5;

/// One reference subset as [`subset::prepare`] left it.
#[derive(Clone, Copy)]
pub struct Subset<'a> {
    pub planes: &'a [f32],
    pub stats: &'a SubsetStats,
    /// Side (px) and centre of the subset in the reference image (px).
    pub n: usize,
    pub centre_px: (f64, f64),
}

/// What IC-GN found for a subset.
#[derive(Clone, Copy, Debug)]
pub struct Outcome {
    pub warp: Warp,
    pub iterations: u32,
    /// ZNCC of the last samples with the reference subset.
    pub zncc: f64,
    pub status: NodeStatus,
}

/// The sums of one evaluation of the deformed subset (see the module documentation).
#[derive(Default, Debug, Clone, Copy)]
struct Sums {
    g: f64,
    gg: f64,
    fg: f64,
    jg: [f64; 12],
}

/// One row's sums, in f32: Σ g', Σ g'², Σ f̂ g', Σ ∂f̂/∂x g' times 1, dx, dx² and the same
/// with ∂f̂/∂y (the dx² sums for the second order only).
#[derive(Default)]
struct RowSums {
    g: f32,
    gg: f32,
    fg: f32,
    x: f32,
    xd: f32,
    xdd: f32,
    y: f32,
    yd: f32,
    ydd: f32,
}

impl RowSums {
    #[inline(always)]
    fn add<const SECOND: bool>(&mut self, f: f32, fx: f32, fy: f32, g: f32, dx: f32) {
        let (fx, fy) = (fx * g, fy * g);
        self.g += g;
        self.gg += g * g;
        self.fg += f * g;
        self.x += fx;
        self.xd += fx * dx;
        self.y += fy;
        self.yd += fy * dx;
        if SECOND {
            self.xdd += fx * dx * dx;
            self.ydd += fy * dx * dx;
        }
    }
}

/// The deformed image's value at (x, y) (B-spline), None outside [0, w − 1] x [0, h − 1].
#[inline(always)]
fn sample(c: &Coefficients, x: f64, y: f64) -> Option<f32> {
    let low = bspline::MARGIN_LOW as f64;
    if x >= low
        && y >= low
        && x < (c.width_px - bspline::MARGIN_HIGH) as f64
        && y < (c.height_px - bspline::MARGIN_HIGH) as f64
    {
        let (ix, iy) = (x as usize, y as usize);
        Some(c.value_at(ix, iy, (x - ix as f64) as f32, (y - iy as f64) as f32))
    } else {
        c.value_gradient(x, y).map(|(v, _, _)| v)
    }
}

/// Samples the deformed subset through `warp` and accumulates the sums; None when a sample
/// falls outside the image. The AVX2 + FMA kernel ([`evaluate_avx2`]) where the CPU has them
/// and every sample is on the coefficients' fast path, else [`evaluate_portable`]; both give
/// the same sums within f32 rounding (tested).
#[inline]
fn evaluate(
    subset: &Subset,
    order: Order,
    coefficients: &Coefficients,
    warp: &Warp,
) -> Option<Sums> {
    #[cfg(target_arch = "x86_64")]
    if evaluate_avx2::available() {
        // SAFETY: the CPU has AVX2 and FMA (checked just above).
        if let Some(sums) = unsafe { evaluate_avx2::evaluate(subset, order, coefficients, warp) } {
            return Some(sums);
        }
    }
    evaluate_portable(subset, order, coefficients, warp)
}

/// [`evaluate`] without SIMD beyond the baseline's 4 lanes, one sample at a time (and the
/// border's mirrored coefficients).
fn evaluate_portable(
    subset: &Subset,
    order: Order,
    coefficients: &Coefficients,
    warp: &Warp,
) -> Option<Sums> {
    let n = subset.n;
    let nn = n * n;
    let half = (n as f64 - 1.0) / 2.0;
    let (values, rest) = subset.planes.split_at(nn);
    let (gx, gy) = rest.split_at(nn);
    let mean = subset.stats.mean;
    let p = &warp.p;
    let (cx, cy) = subset.centre_px;
    let mut sums = Sums::default();
    for j in 0..n {
        let dy = j as f64 - half;
        let row = j * n..(j + 1) * n;
        let (f_row, gx_row, gy_row) = (&values[row.clone()], &gx[row.clone()], &gy[row]);
        let mut r = RowSums::default();
        match order {
            Order::First => {
                // Affine: the samples of a row are evenly spaced.
                let (mut x, mut y) = (
                    cx + p[0] + (1.0 + p[1]) * -half + p[2] * dy,
                    cy + p[6] + p[7] * -half + (1.0 + p[8]) * dy,
                );
                let (step_x, step_y) = (1.0 + p[1], p[7]);
                for i in 0..n {
                    let g = sample(coefficients, x, y)? - mean;
                    r.add::<false>(f_row[i], gx_row[i], gy_row[i], g, i as f32 - half as f32);
                    x += step_x;
                    y += step_y;
                }
            }
            Order::Second => {
                for i in 0..n {
                    let dx = i as f64 - half;
                    let (wx, wy) = warp.apply(dx, dy);
                    let g = sample(coefficients, cx + wx, cy + wy)? - mean;
                    r.add::<true>(f_row[i], gx_row[i], gy_row[i], g, dx as f32);
                }
            }
        }
        sums.g += r.g as f64;
        sums.gg += r.gg as f64;
        sums.fg += r.fg as f64;
        let (ax, axd, axdd, ay, ayd, aydd) = (
            r.x as f64,
            r.xd as f64,
            r.xdd as f64,
            r.y as f64,
            r.yd as f64,
            r.ydd as f64,
        );
        // Σ J g' in the order of `subset::steepest_descent`.
        // Per gradient component: the first-order terms (1, dx, dy) and the second-order ones
        // (dx²/2, dx dy, dy²/2).
        let first = |a: f64, ad: f64| [a, ad, dy * a];
        let second = |a: f64, ad: f64, add: f64| [0.5 * add, dy * ad, 0.5 * dy * dy * a];
        let terms: &[[f64; 3]] = match order {
            Order::First => &[first(ax, axd), first(ay, ayd)],
            Order::Second => &[
                first(ax, axd),
                second(ax, axd, axdd),
                first(ay, ayd),
                second(ay, ayd, aydd),
            ],
        };
        for (jg, term) in sums.jg.chunks_exact_mut(3).zip(terms) {
            for (j, t) in jg.iter_mut().zip(term) {
                *j += t;
            }
        }
    }
    Some(sums)
}

/// Whether the update after one whose predicted decrease of the ZNSSD is `decrease` (from
/// `znssd`, the residual of the evaluation it came from, of a subset with `dof` degrees of
/// freedom, n² − P) is predicted below [`PREDICTED_STEP_NOISE`] of the noise (see there):
/// (MAX_CONTRACTION |Δp|_H)² < PREDICTED_STEP_NOISE² σ² with σ² = (znssd − decrease) / dof.
fn next_update_within_noise(decrease: f64, znssd: f64, dof: f64) -> bool {
    let residual = znssd - decrease;
    residual > 0.0
        && MAX_CONTRACTION * MAX_CONTRACTION * decrease * dof
            < PREDICTED_STEP_NOISE * PREDICTED_STEP_NOISE * residual
}

/// When [`solve`] stops (besides `max_iterations`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// When the update moves no subset point by more than [`CONVERGED_PX`].
    Converged,
    /// Also when the next update is predicted within the subset's noise
    /// ([`PREDICTED_STEP_NOISE`]): for a guess whose error is the noise of the frames it was
    /// predicted from (a node's prediction from its previous values). Not for a guess whose
    /// error is systematic (the FFT guess's sub-pixel estimate has a bias: on DIC Challenge
    /// sample 5 a one-evaluation result kept enough of it to move `icgn1`'s bias from +0.00085,
    /// +0.00099 to +0.00101, +0.00114 px and its std v from 0.00270 to 0.00272 px), nor where
    /// the updates may not shrink (from a first-order result to the second order).
    WithinNoise,
}

/// IC-GN from `guess` until the update is below [`CONVERGED_PX`], or the next is predicted
/// within the noise (`stop`), or `max_iterations`.
pub fn solve(
    subset: &Subset,
    order: Order,
    coefficients: &Coefficients,
    guess: Warp,
    max_iterations: u32,
    stop: Stop,
) -> Outcome {
    assert_eq!(subset.planes.len(), PLANES * subset.n * subset.n);
    let count = order.parameters();
    let nn = (subset.n * subset.n) as f64;
    let radius_px = (subset.n as f64 - 1.0) / 2.0;
    let stats = subset.stats;
    let mut outcome = Outcome {
        warp: guess,
        iterations: 0,
        zncc: 0.0,
        status: NodeStatus::NotConverged,
    };
    for iteration in 1..=max_iterations {
        outcome.iterations = iteration;
        let Some(sums) = evaluate(subset, order, coefficients, &outcome.warp) else {
            outcome.status = NodeStatus::OutsideImage;
            return outcome;
        };
        let g_mean = sums.g / nn;
        let g_norm_sq = sums.gg - sums.g * g_mean;
        if !(g_norm_sq.is_finite() && g_norm_sq > MIN_DEFORMED_STD * MIN_DEFORMED_STD * nn) {
            outcome.status = NodeStatus::LowContrast;
            return outcome;
        }
        let g_norm = g_norm_sq.sqrt();
        let zncc = sums.fg / g_norm;
        outcome.zncc = zncc.clamp(-1.0, 1.0);
        let mut b = [0.0f64; 12];
        for (a, value) in b.iter_mut().enumerate().take(count) {
            *value = zncc * stats.sum_jf[a] - (sums.jg[a] - g_mean * stats.sum_j[a]) / g_norm;
        }
        let mut delta = Warp::default();
        for a in 0..count {
            let row = &stats.inverse_hessian[a * count..(a + 1) * count];
            let dot: f64 = row.iter().zip(&b).map(|(h, b)| h * b).sum();
            delta.p[order.index(a)] = -dot;
        }
        let Some(next) = outcome.warp.compose_inverse(&delta) else {
            return outcome;
        };
        outcome.warp = next;
        // bᵀ H⁻¹ b: the ZNSSD's predicted decrease, from C = 2 (1 − r) to C − decrease.
        let decrease = -(0..count)
            .map(|a| b[a] * delta.p[order.index(a)])
            .sum::<f64>();
        if delta.reach_px(radius_px) < CONVERGED_PX {
            outcome.status = NodeStatus::Ok;
            return outcome;
        }
        if stop == Stop::WithinNoise
            && next_update_within_noise(decrease, 2.0 * (1.0 - zncc), nn - count as f64)
        {
            // The ZNCC predicted at the final warp (the last samples are an update away).
            outcome.zncc = (zncc + 0.5 * decrease).clamp(-1.0, 1.0);
            outcome.status = NodeStatus::Ok;
            return outcome;
        }
        // A subset sent further than half its size from its guess has lost its match.
        let (du, dv) = (
            next.p[shape::U] - guess.p[shape::U],
            next.p[shape::V] - guess.p[shape::V],
        );
        if du.hypot(dv) > radius_px {
            return outcome;
        }
    }
    outcome
}

#[cfg(test)]
mod tests {
    use super::*;
    use subset::test_support::{pair, Prepared};

    use crate::verify::tests::texture;

    /// Uniform noise in [−amplitude, amplitude) for pixel i, from `seed` (splitmix64).
    fn noise(i: usize, seed: u64, amplitude: f64) -> f64 {
        let mut z = (i as u64 ^ seed.wrapping_mul(0x9e37_79b9_7f4a_7c15)).wrapping_add(1);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        amplitude * ((z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0)
    }

    /// A noisy pair (the texture translated, each image with its own noise): from a guess a few
    /// thousandths of a pixel off, IC-GN stops after one evaluation (the next update is predicted
    /// within the noise) where it lands within a small fraction of the noise of what it
    /// converges to from 0.4 px away in several; the same pair without noise is never stopped
    /// early, nor is a solve asked to converge.
    #[test]
    fn a_guess_within_the_noise_takes_one_evaluation_and_keeps_the_converged_result() {
        let (size, n, top_left) = (96usize, 33usize, (30usize, 32usize));
        let t = (2.37, -1.21);
        let render = |amplitude: f64| {
            let pixels = |shift: (f64, f64), seed: u64| -> Vec<u16> {
                (0..size * size)
                    .map(|i| {
                        let (x, y) = ((i % size) as f64 - shift.0, (i / size) as f64 - shift.1);
                        (texture(x, y) + noise(i, seed, amplitude)) as u16
                    })
                    .collect()
            };
            (pixels((0.0, 0.0), 1), pixels(t, 2))
        };
        let solve_from = |amplitude: f64, guess: (f64, f64), gradient: [[f64; 2]; 2], stop| {
            let (reference, deformed) = render(amplitude);
            let (image, cr, cd) = pair(&reference, &deformed, size);
            let prepared = Prepared::new(image, &cr, top_left, n, Order::First);
            let outcome = solve(
                &prepared.subset(),
                Order::First,
                &cd,
                Warp::affine(guess, gradient),
                30,
                stop,
            );
            assert_eq!(outcome.status, NodeStatus::Ok, "{outcome:?}");
            outcome
        };
        // About 1 % noise (uniform, ±300 counts on a 20,000-count texture).
        let far = solve_from(
            300.0,
            (t.0 + 0.4, t.1 - 0.3),
            [[0.0; 2]; 2],
            Stop::WithinNoise,
        );
        assert!(far.iterations >= 2, "{far:?}");
        let (u, v) = far.warp.displacement();
        let near_guess = (u + 0.004, v - 0.003);
        let near = solve_from(300.0, near_guess, far.warp.gradient(), Stop::WithinNoise);
        assert_eq!(near.iterations, 1, "{near:?}");
        let (nu, nv) = near.warp.displacement();
        assert!(
            (nu - u).abs() < 3e-4 && (nv - v).abs() < 3e-4,
            "one evaluation: {nu} {nv}, converged: {u} {v}"
        );
        assert!((near.zncc - far.zncc).abs() < 1e-4, "{near:?} {far:?}");
        let exact = solve_from(0.0, near_guess, far.warp.gradient(), Stop::WithinNoise);
        assert!(exact.iterations >= 2, "{exact:?}");
        let full = solve_from(300.0, near_guess, far.warp.gradient(), Stop::Converged);
        assert!(full.iterations >= 2, "{full:?}");
    }

    /// A deformed image of the analytic texture under a known affine map: IC-GN recovers the
    /// displacement and gradient at the subset centre from a guess 0.6 px away and no gradient,
    /// with either order, and is insensitive to the deformed image's offset and gain.
    #[test]
    fn recovers_an_affine_motion_with_offset_and_gain() {
        let size = 96usize;
        let (t, g) = ((3.3, -2.45), [[0.03, -0.02], [0.015, -0.01]]);
        let det = (1.0 + g[0][0]) * (1.0 + g[1][1]) - g[0][1] * g[1][0];
        let reference: Vec<u16> = (0..size * size)
            .map(|i| texture((i % size) as f64, (i / size) as f64) as u16)
            .collect();
        let deformed: Vec<u16> = (0..size * size)
            .map(|i| {
                let (x, y) = ((i % size) as f64 - t.0, (i / size) as f64 - t.1);
                let (px, py) = (
                    ((1.0 + g[1][1]) * x - g[0][1] * y) / det,
                    (-g[1][0] * x + (1.0 + g[0][0]) * y) / det,
                );
                (0.8 * texture(px, py) + 1500.0) as u16
            })
            .collect();
        let (reference_image, cr, cd) = pair(&reference, &deformed, size);
        for (order, n) in [
            (Order::First, 33usize),
            (Order::Second, 33),
            (Order::First, 24),
        ] {
            let top_left = (30usize, 32usize);
            let prepared = Prepared::new(reference_image, &cr, top_left, n, order);
            let subset = prepared.subset();
            let half = (n as f64 - 1.0) / 2.0;
            let centre = subset.centre_px;
            let truth = (
                t.0 + g[0][0] * centre.0 + g[0][1] * centre.1,
                t.1 + g[1][0] * centre.0 + g[1][1] * centre.1,
            );
            let guess = Warp::affine(
                (truth.0.round() + 0.4, truth.1.round() - 0.2),
                [[0.0; 2]; 2],
            );
            let outcome = solve(&subset, order, &cd, guess, 30, Stop::Converged);
            assert_eq!(outcome.status, NodeStatus::Ok, "{order:?} {n}: {outcome:?}");
            let (u, v) = outcome.warp.displacement();
            assert!(
                (u - truth.0).abs() < 0.01 && (v - truth.1).abs() < 0.01,
                "{order:?} {n}: {u} {v} vs {truth:?}"
            );
            let found = outcome.warp.gradient();
            for r in 0..2 {
                for c in 0..2 {
                    assert!((found[r][c] - g[r][c]).abs() < 2e-3, "{order:?}: {found:?}");
                }
            }
            assert!(outcome.zncc > 0.99, "{}", outcome.zncc);
            // Sent past the border, the subset is outside the image, whatever the order.
            let past = Warp::affine((size as f64 - centre.0 - half + 0.5, 0.0), [[0.0; 2]; 2]);
            let outside = solve(&subset, order, &cd, past, 30, Stop::WithinNoise);
            assert_eq!(outside.status, NodeStatus::OutsideImage, "{outside:?}");
        }
    }
}
