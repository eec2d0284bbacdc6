//! The shape function's order per node (method `icgn`): when a first-order IC-GN result is
//! worth re-running at second order.
//!
//! **The first order's bias.** Under a displacement with curvature, u = u₀ + ∇u·d +
//! ½ (u_xx dx² + 2 u_xy dx dy + u_yy dy²), the affine least-squares fit of a square subset
//! (speckle: about the same gradient energy at every pixel) finds the centre's displacement off
//! by the subset's mean of the quadratic part, ½ (u_xx + u_yy) ⟨d²⟩ with ⟨d²⟩ = (n² − 1) / 12
//! the mean square offset of a side-n subset's pixels along one axis (the mixed term averages
//! out, and so does every odd one); its gradient is not biased (the slope of the fit of an even
//! function over a symmetric subset is 0). A 33 px subset on the steepest part of a 9 px
//! sigmoid band 32 px wide (u_xx ≈ 8.4e-4 /px) is off by 0.038 px, on one 8 px wide by 0.61 px.
//!
//! **Its estimate.** The neighbours' first-order gradients being unbiased, their differences
//! across the node estimate u_xx, u_yy, v_xx, v_yy with no image sampled ([`Curvature`]).
//!
//! **The second order's cost.** It removes that bias but measures the centre's displacement
//! with more noise: fitted together with the quadratic terms, whose monomials correlate with
//! the constant (over a square, corr(1, dx²) = √5 / 3), the displacement's variance grows by
//! 1 + 2 · (1/9) / (1/5 − 1/9) = 3.5 (uniform gradient energy), r = σ₂ / σ₁ ≈ 1.87; measured
//! on smooth fields of the independent generator at 33 px, 1.76 (translation) and 1.87 (strain)
//! (`tests/suite/steep_band.rs`). The mean square errors are b² + σ₁² (first order) and
//! r² σ₁² (second): the second order wins when |b| > √(r² − 1) σ₁ ≈ 1.5 σ₁.
//!
//! **The noise σ₁** of each node's displacement is the Gauss-Newton covariance s² H⁻¹, s² the
//! residual's variance per pixel. A curved node's own residual holds its misfit, so s² is the
//! field's median of the nodes' residual per pixel in counts ([`residual_counts2`]; most nodes
//! of a field are not steep), and H⁻¹ the node's own (its contrast): [`displacement_noise_px`].

use super::shape::Order;
use super::subset::SubsetStats;

/// A node is re-run at second order when its first-order bias exceeds this many standard
/// deviations of its first-order displacement (in u or in v). The break-even is √(r² − 1) ≈ 1.5
/// (module documentation); the bias estimate carries noise of its own, the neighbours'
/// gradient noise: on a uniform translation at step 8 its standard deviation is 0.7 σ₁
/// (`tests/suite/steep_band.rs`, 33 px), so 2.0 is 2.9 of those above 0, and 0.7 % (translation)
/// to 1.0 % (homogeneous strain) of a smooth field's nodes are re-run, with an RMS error 1.03
/// times `icgn1`'s. Where the true |b| is between 1.5 and 2 σ₁ the first order kept costs
/// little: its error is then at most 1.3 times the second's.
pub const BIAS_TO_NOISE: f64 = 2.0;

/// The second derivatives the first order's bias depends on (1/px): u_xx, u_yy, v_xx, v_yy.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Curvature {
    pub u_xx: f64,
    pub u_yy: f64,
    pub v_xx: f64,
    pub v_yy: f64,
}

/// ⟨d²⟩ of a side-n subset (px²): the mean of dx² over its pixels' offsets from the centre.
pub fn mean_square_offset_px2(n: usize) -> f64 {
    let n = n as f64;
    (n * n - 1.0) / 12.0
}

/// The first-order displacement's bias (u, v) (px) under `curvature`, side-n subset.
pub fn first_order_bias_px(curvature: Curvature, n: usize) -> (f64, f64) {
    let half_mean = 0.5 * mean_square_offset_px2(n);
    (
        half_mean * (curvature.u_xx + curvature.u_yy),
        half_mean * (curvature.v_xx + curvature.v_yy),
    )
}

/// The residual per pixel (counts²) of a first-order result of ZNCC `zncc` on a side-n subset
/// with `stats`: the ZNSSD 2 (1 − ZNCC) of the normalised subsets times f_n² / n².
pub fn residual_counts2(zncc: f64, stats: &SubsetStats, n: usize) -> f64 {
    let norm = stats.norm_counts as f64;
    2.0 * (1.0 - zncc).max(0.0) * norm * norm / (n * n) as f64
}

/// The standard deviations of a first-order subset's displacement (u, v) (px) when its pixels'
/// residual variance is `residual_counts2` (counts²): √(s² H⁻¹) with H⁻¹ of the normalised
/// subset (hence s² / f_n²).
pub fn displacement_noise_px(stats: &SubsetStats, residual_counts2: f64) -> (f64, f64) {
    NoiseScale::of_subset(stats).noise_px(residual_counts2)
}

/// What a first-order result's noise needs of its subset, kept where the subset is not
/// (measurements against the origin prepare theirs on the fly): its residual per pixel
/// (counts²), f_n² (counts²) and the diagonal of its H⁻¹ for u and v.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoiseScale {
    pub residual_counts2: f64,
    norm_counts2: f64,
    inverse_hessian_uv: (f64, f64),
}

impl NoiseScale {
    /// Of a first-order result of ZNCC `zncc` on the side-n subset with `stats`.
    pub fn of(zncc: f64, stats: &SubsetStats, n: usize) -> Self {
        NoiseScale {
            residual_counts2: residual_counts2(zncc, stats, n),
            ..Self::of_subset(stats)
        }
    }

    /// The subset's part alone (no residual).
    fn of_subset(stats: &SubsetStats) -> Self {
        let count = Order::First.parameters();
        let norm = stats.norm_counts as f64;
        NoiseScale {
            residual_counts2: 0.0,
            norm_counts2: norm * norm,
            inverse_hessian_uv: (
                stats.inverse_hessian[0],
                stats.inverse_hessian[3 * count + 3],
            ),
        }
    }

    /// [`displacement_noise_px`] of the subset, for the field's residual `residual_counts2`.
    pub fn noise_px(&self, residual_counts2: f64) -> (f64, f64) {
        let scale = residual_counts2 / self.norm_counts2;
        let sd = |h: f64| (scale * h).max(0.0).sqrt();
        (sd(self.inverse_hessian_uv.0), sd(self.inverse_hessian_uv.1))
    }
}

/// Whether a node whose first-order bias is `bias_px` and noise `noise_px` (u, v) is re-run
/// at second order ([`BIAS_TO_NOISE`]).
pub fn needs_second_order(bias_px: (f64, f64), noise_px: (f64, f64)) -> bool {
    bias_px.0.abs() > BIAS_TO_NOISE * noise_px.0 || bias_px.1.abs() > BIAS_TO_NOISE * noise_px.1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ⟨d²⟩ is the mean square offset of the pixels, counted directly; the bias of a 33 px
    /// subset on the steepest curvature of the 32 px band is the figure of the documentation.
    #[test]
    fn bias_is_half_the_curvature_times_the_mean_square_offset() {
        for n in [9usize, 32, 33] {
            let half = (n as f64 - 1.0) / 2.0;
            let counted = (0..n).map(|i| (i as f64 - half).powi(2)).sum::<f64>() / n as f64;
            assert!((mean_square_offset_px2(n) - counted).abs() < 1e-12, "{n}");
        }
        // u = 9 / (1 + e^(−x/32)): |u''| peaks at 9 / 32² · 0.0962.
        let u_xx = 9.0 / (32.0f64 * 32.0) * 0.0962;
        let curvature = Curvature {
            u_xx,
            ..Curvature::default()
        };
        let (bu, bv) = first_order_bias_px(curvature, 33);
        assert!((bu - 0.0383).abs() < 5e-4 && bv == 0.0, "{bu} {bv}");
        // Opposite curvatures along x and y cancel (a harmonic field has no such bias).
        let saddle = Curvature {
            u_xx,
            u_yy: -u_xx,
            ..Curvature::default()
        };
        assert_eq!(first_order_bias_px(saddle, 33), (0.0, 0.0));
    }

    /// The noise scales with the residual's square root and the subset's H⁻¹, and the choice
    /// compares the bias with BIAS_TO_NOISE of it, in u and in v separately.
    #[test]
    fn second_order_when_the_bias_exceeds_the_noise_threshold() {
        let mut stats = SubsetStats {
            norm_counts: 100.0,
            ..SubsetStats::default()
        };
        stats.inverse_hessian[0] = 4.0e-4; // u
        stats.inverse_hessian[3 * 6 + 3] = 1.0e-4; // v
                                                   // ZNCC 0.995 on 33 px: residual 2 · 0.005 · 100² / 1089 counts².
        let s2 = residual_counts2(0.995, &stats, 33);
        assert!((s2 - 100.0 / 1089.0).abs() < 1e-12, "{s2}");
        let (nu, nv) = displacement_noise_px(&stats, 1.0e4);
        assert!(
            (nu - 0.02).abs() < 1e-12 && (nv - 0.01).abs() < 1e-12,
            "{nu} {nv}"
        );
        let noise = (nu, nv);
        assert!(!needs_second_order((0.039, -0.019), noise));
        assert!(needs_second_order((-0.041, 0.0), noise));
        assert!(needs_second_order((0.0, 0.021), noise));
        // The same noise from what a subset leaves behind.
        let scale = NoiseScale::of(0.995, &stats, 33);
        assert_eq!(scale.residual_counts2, s2);
        let (su, sv) = scale.noise_px(1.0e4);
        assert!(
            (su - nu).abs() < 1e-15 && (sv - nv).abs() < 1e-15,
            "{su} {sv}"
        );
    }
}
