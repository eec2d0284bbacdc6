//! What a node's neighbours say its displacement since the current reference is, for the
//! outlier check (`assemble.rs`, `refuse_inconsistent`): the least-squares affine surface
//! through the valid nodes of the nearest ring ([`LOCAL_RINGS`]), or within
//! [`EXTRAPOLATION_RINGS`] where it holds fewer than [`MIN_EXTRAPOLATION_NODES`] (the node left
//! out).
//!
//! The check compares increments since the reference, not total displacements: a false match
//! jumps in both, but the total displacement of a heterogeneous field carries its curvature
//! (on the cruciform at a grip stretch of 1.5, step 16 px, the fillets' nodes sat 1 px or more
//! off their neighbours' plane, twice the check's floor, and the arms' roots lost them all),
//! while the increment since a reference taken at most `max_deformation_px` ago is nearly
//! affine over two rings. A quadratic surface instead also followed the curvature, but it fits
//! noise too: on DIC Challenge sample 14 (ZOI 16 px) it let a 0.56 px false match through.
//! Even the increment is not affine over two rings beside the cruciform's fillets late in a
//! reference's life: there the plane through two rings refused good nodes, whose bases the
//! next renewal then extrapolated (`tests/suite/structure.rs`: the nearest ring instead took
//! correli's node error p99 from 0.109 to 0.093 px with the bases' gradient of `reanchor.rs`
//! unchanged).

use super::{Correlator, EXTRAPOLATION_RINGS, LOCAL_RINGS, MIN_EXTRAPOLATION_NODES};
use crate::field::NodeStatus;
use nalgebra::{SMatrix, SVector};

type Basis = SVector<f64, 3>;

/// 1, x, y at (x, y) in node steps.
fn basis(x: f64, y: f64) -> Basis {
    Basis::from([1.0, x, y])
}

impl Correlator {
    /// Node k's displacement since the current reference (px), and what its valid neighbours
    /// predict for it; None when too few neighbours.
    pub(super) fn increment_and_prediction(&self, k: usize) -> Option<((f64, f64), (f64, f64))> {
        self.increment_and_prediction_within(k, LOCAL_RINGS)
            .or_else(|| self.increment_and_prediction_within(k, EXTRAPOLATION_RINGS))
    }

    /// [`Self::increment_and_prediction`] from the valid nodes within `rings`.
    fn increment_and_prediction_within(
        &self,
        k: usize,
        rings: usize,
    ) -> Option<((f64, f64), (f64, f64))> {
        let (nx, ny) = (self.mesh.nx, self.mesh.ny);
        let (i, j) = (k % nx, k / nx);
        let increment = |m: usize| {
            let node = &self.field.nodes[m];
            let base = self.reference.nodes[m].base_px;
            (node.u_px - base.0, node.v_px - base.1)
        };
        let centre = &self.field.nodes[k];
        let step = self.settings.step_px.max(1) as f64;
        let mut normal = SMatrix::<f64, 3, 3>::zeros();
        let mut rhs_u = Basis::zeros();
        let mut rhs_v = Basis::zeros();
        let mut count = 0;
        for jj in j.saturating_sub(rings)..=(j + rings).min(ny - 1) {
            for ii in i.saturating_sub(rings)..=(i + rings).min(nx - 1) {
                let m = jj * nx + ii;
                let node = &self.field.nodes[m];
                if m == k || node.status != NodeStatus::Ok {
                    continue;
                }
                let x = (node.x_px - centre.x_px) / step;
                let y = (node.y_px - centre.y_px) / step;
                let b = basis(x, y);
                let (du, dv) = increment(m);
                normal += b * b.transpose();
                rhs_u += b * du;
                rhs_v += b * dv;
                count += 1;
            }
        }
        if count < MIN_EXTRAPOLATION_NODES {
            return None;
        }
        let cholesky = normal.cholesky()?;
        // At the node itself (x = y = 0) the surface is its constant term.
        let prediction = (cholesky.solve(&rhs_u)[0], cholesky.solve(&rhs_v)[0]);
        Some((increment(k), prediction))
    }
}

#[cfg(test)]
mod tests {
    use super::basis;
    use nalgebra::{SMatrix, SVector};

    /// The normal equations of the 5 x 5 neighbourhood without its centre give an affine
    /// field back exactly at the centre (the check's residual is then noise alone).
    #[test]
    fn an_affine_field_is_predicted_exactly() {
        let field = |x: f64, y: f64| 0.3 + 1.2 * x - 0.4 * y;
        let mut normal = SMatrix::<f64, 3, 3>::zeros();
        let mut rhs = SVector::<f64, 3>::zeros();
        for j in -2..=2 {
            for i in -2..=2 {
                if (i, j) == (0, 0) {
                    continue;
                }
                let b = basis(f64::from(i), f64::from(j));
                normal += b * b.transpose();
                rhs += b * field(f64::from(i), f64::from(j));
            }
        }
        let solution = normal.cholesky().unwrap().solve(&rhs);
        assert!((solution[0] - field(0.0, 0.0)).abs() < 1e-12);
    }
}
