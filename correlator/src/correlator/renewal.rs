//! When the automatic reference is renewed: when the correlation against it degrades, not when
//! the material has merely moved. A renewal costs several frames' worth of work (the new bases
//! measured against the origin, spread over the next frames on the live path, and every node's
//! reference prepared), and each reference adds the
//! noise of one more image to the total displacement; a rigid motion, however large, costs the
//! correlation nothing, since each ZOI is placed at its prediction (the previous frames) before
//! it is correlated. What does degrade a match against an old reference:
//!
//! - **the deformation of the ZOI since the reference**: a rigid `correli` ZOI (or the FFT guess
//!   of an IC-GN subset) compares a square with a deformed one; the correlation peak widens and
//!   its bias grows beyond the first-order gradient correction as the corners move against the
//!   centre. Measured as how far the deformation since the reference, (I + ∇u)(I + ∇u_base)⁻¹ − I,
//!   moves a ZOI's corner relative to its centre (px), the 90th percentile over the valid nodes
//!   (a few noisy gradients at the border do not decide);
//! - **the score**: the mean correlation score of the valid nodes below the bar;
//! - **nodes refused**: more nodes the reference can correlate refused (neither `ok` nor outside
//!   the image) than in the first frame against it, by [`MAX_NEW_REFUSED_FRACTION`] of the
//!   nodes: matches lost to decorrelation, which a new reference gives back (a node refused from
//!   the start, a dirty patch say, is not counted again at every frame).

use super::{identity_plus, Correlator};
use crate::field::NodeStatus;
use crate::interpolate::Mat2;

/// Nodes newly refused against a reference, as a fraction of the mesh, that call for a new one.
pub const MAX_NEW_REFUSED_FRACTION: f64 = 0.05;

/// Quantile of the nodes' deformation that is compared with the limit.
const DEFORMATION_QUANTILE: f64 = 0.9;

/// What the last frame says of the current reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenewalSignals {
    /// The ZOIs' deformation since the reference (px at a corner, see the module documentation).
    pub deformation_px: f64,
    /// Mean correlation score of the valid nodes.
    pub mean_score: f64,
    /// Nodes refused now and in the first frame against this reference.
    pub refused: usize,
    pub refused_first: usize,
    pub nodes: usize,
}

impl RenewalSignals {
    /// Whether these signals call for a new reference, with the automatic mode's thresholds.
    pub fn call_for_renewal(&self, max_deformation_px: f64, min_mean_score: f64) -> bool {
        let newly_refused = self.refused.saturating_sub(self.refused_first) as f64;
        self.deformation_px > max_deformation_px
            || self.mean_score < min_mean_score
            || newly_refused > MAX_NEW_REFUSED_FRACTION * self.nodes as f64
    }
}

/// How far the deformation `g` (∇u since the reference) moves a corner of a ZOI of half-size
/// `half_px` relative to its centre (px): the larger of the two diagonals.
pub fn corner_deformation_px(g: Mat2, half_px: f64) -> f64 {
    let along = |s: f64| {
        let dx = g[0][0] + s * g[0][1];
        let dy = g[1][0] + s * g[1][1];
        dx.hypot(dy)
    };
    half_px * along(1.0).max(along(-1.0))
}

/// (I + a)(I + b)⁻¹ − I: the gradient since a reference whose own gradient (against the same
/// origin) is `b`, of a total gradient `a`; None when I + b is singular.
pub fn gradient_since(a: Mat2, b: Mat2) -> Option<Mat2> {
    let (fa, fb) = (identity_plus(a), identity_plus(b));
    let det = fb[0][0] * fb[1][1] - fb[0][1] * fb[1][0];
    if det.abs() < 1e-12 || !det.is_finite() {
        return None;
    }
    let inv = [
        [fb[1][1] / det, -fb[0][1] / det],
        [-fb[1][0] / det, fb[0][0] / det],
    ];
    let mut out = [[0.0; 2]; 2];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, value) in row.iter_mut().enumerate() {
            *value = fa[r][0] * inv[0][c] + fa[r][1] * inv[1][c] - if r == c { 1.0 } else { 0.0 };
        }
    }
    Some(out)
}

impl Correlator {
    /// The signals of the frame just assembled against the current reference. Counts the first
    /// frame's refusals on the way (`reference.refused_first`).
    pub(super) fn renewal_signals(&mut self) -> RenewalSignals {
        let half_px = (self.settings.zoi_px as f64 - 1.0) / 2.0;
        let (mut score_sum, mut count, mut refused) = (0.0, 0usize, 0usize);
        self.scratch.scores.clear();
        for (k, node) in self.field.nodes.iter().enumerate() {
            match node.status {
                NodeStatus::Ok => {
                    score_sum += self.frame.results[k].score;
                    count += 1;
                    let base = self.reference.nodes[k].base_gradient;
                    if let Some(g) = gradient_since(self.field.gradients[k], base) {
                        self.scratch.scores.push(corner_deformation_px(g, half_px));
                    }
                }
                NodeStatus::OutsideImage => {}
                _ if self.reference.nodes[k].status == NodeStatus::Ok => refused += 1,
                _ => {}
            }
        }
        let deformation_px = if self.scratch.scores.is_empty() {
            0.0
        } else {
            let at = ((self.scratch.scores.len() - 1) as f64 * DEFORMATION_QUANTILE).round();
            *self
                .scratch
                .scores
                .select_nth_unstable_by(at as usize, f64::total_cmp)
                .1
        };
        let refused_first = *self.reference.refused_first.get_or_insert(refused);
        RenewalSignals {
            deformation_px,
            mean_score: if count > 0 {
                score_sum / count as f64
            } else {
                0.0
            },
            refused,
            refused_first,
            nodes: self.field.nodes.len(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signals(deformation_px: f64, mean_score: f64, refused: usize) -> RenewalSignals {
        RenewalSignals {
            deformation_px,
            mean_score,
            refused,
            refused_first: 10,
            nodes: 1000,
        }
    }

    /// A correlation that holds keeps its reference, whatever the motion was; each degradation
    /// alone renews it.
    #[test]
    fn renews_when_the_correlation_degrades_not_when_it_holds() {
        let holds = signals(0.4, 0.95, 12);
        assert!(!holds.call_for_renewal(1.0, 0.5));
        assert!(signals(1.2, 0.95, 12).call_for_renewal(1.0, 0.5));
        assert!(signals(0.4, 0.45, 12).call_for_renewal(1.0, 0.5));
        // 10 refused from the start: 50 more is 5 % of the mesh, 61 more is beyond.
        assert!(!signals(0.4, 0.95, 60).call_for_renewal(1.0, 0.5));
        assert!(signals(0.4, 0.95, 71).call_for_renewal(1.0, 0.5));
    }

    #[test]
    fn corner_deformation_of_a_stretch_a_shear_and_a_rotation() {
        // 10 % along x on a 32 px ZOI (half 15.5 px): the corner moves 1.55 px along x.
        let stretch = [[0.1, 0.0], [0.0, 0.0]];
        assert!((corner_deformation_px(stretch, 15.5) - 1.55).abs() < 1e-12);
        // Simple shear 0.1: the diagonals move by 0.1 × 15.5 px along x.
        let shear = [[0.0, 0.1], [0.0, 0.0]];
        assert!((corner_deformation_px(shear, 15.5) - 1.55).abs() < 1e-12);
        // A rotation by θ moves a corner by 2 sin(θ/2) × its distance √2 half.
        let t: f64 = 0.05;
        let rotation = [[t.cos() - 1.0, -t.sin()], [t.sin(), t.cos() - 1.0]];
        let expected = 2.0 * (t / 2.0).sin() * 15.5 * 2f64.sqrt();
        assert!((corner_deformation_px(rotation, 15.5) - expected).abs() < 1e-9);
    }

    /// The gradient since a reference composes back into the total one.
    #[test]
    fn gradient_since_the_reference_composes_back() {
        let (a, b) = ([[0.3, 0.05], [-0.02, -0.12]], [[0.25, 0.01], [0.0, -0.1]]);
        let since = gradient_since(a, b).unwrap();
        let back = super::super::compose_gradients(since, b);
        for r in 0..2 {
            for c in 0..2 {
                assert!((back[r][c] - a[r][c]).abs() < 1e-12);
            }
        }
        let none = gradient_since(a, a).unwrap();
        assert!(none.iter().flatten().all(|v| v.abs() < 1e-12), "{none:?}");
        assert!(gradient_since(a, [[-1.0, 0.0], [0.0, 0.0]]).is_none());
    }
}
