//! The followed mesh: at a reference update every node's new base is its total displacement
//! (a node that failed or whose material left the image is carried by the affine fit of its
//! never-lost neighbours, so it stays out and comes back on its own material), the gradients at
//! the new bases, and the affine fits of neighbouring nodes that place, carry and check nodes.

use super::{
    to_mat2, AffineFit, Correlator, OriginBases, Support, CARRY_RINGS, EXTRAPOLATION_RINGS,
    MIN_EXTRAPOLATION_NODES,
};
use crate::field::NodeStatus;
use crate::interpolate::Mat2;
use crate::settings::ReferenceMode;
use crate::strain::AffineSums;
use crate::zoi::Image;

impl Correlator {
    /// Least-squares gradient of the bases of the nodes around k (3x3), zero when none.
    pub(super) fn base_fit_gradient(&self, k: usize) -> Mat2 {
        let (nx, ny) = (self.mesh.nx, self.mesh.ny);
        let (i, j) = (k % nx, k / nx);
        let mut sums = AffineSums::default();
        for jj in j.saturating_sub(1)..=(j + 1).min(ny - 1) {
            for ii in i.saturating_sub(1)..=(i + 1).min(nx - 1) {
                let m = jj * nx + ii;
                let (a, b) = (&self.field.nodes[m], &self.field.nodes[k]);
                let base = self.reference.nodes[m].base_px;
                sums.add(a.x_px - b.x_px, a.y_px - b.y_px, base.0, base.1);
            }
        }
        sums.gradient().map_or([[0.0; 2]; 2], to_mat2)
    }

    /// Whether the frame just assembled is to become the reference (`Field::reference_updated`,
    /// see `renewal.rs`); the renewal itself is [`Self::renew`].
    pub(super) fn decide_renewal(&mut self) {
        self.reference.frames_since += 1;
        let renew = match self.settings.reference {
            ReferenceMode::Fixed => false,
            ReferenceMode::Incremental => true,
            ReferenceMode::Auto {
                max_deformation_px,
                min_mean_score,
            } => self
                .renewal_signals()
                .call_for_renewal(max_deformation_px, min_mean_score),
        };
        self.field.reference_updated = renew && self.field.valid > 0;
    }

    /// The frame just assembled (`pixels`) becomes the reference. `origin`: when its bases are
    /// measured against the origin (see [`OriginBases`]).
    pub(super) fn renew(&mut self, pixels: &[u16], origin: OriginBases) {
        // New base = total displacement. A node that failed (typically one whose followed point
        // left the image) gets the displacement the affine fit of its valid neighbours
        // extrapolates to it: its followed point keeps moving with the material, so it stays
        // outside while the material is outside and comes back where that material is. A
        // neighbour mean would pull it back inside the image onto another material point,
        // which then correlates as a false "ok". The fit uses the never-lost nodes (within
        // CARRY_RINGS, else the whole mesh): nodes that came back carry their extrapolation
        // error, and fitting the next ones on them would compound it ring by ring as material
        // returns (unloading from a large stretch).
        let (nx, ny) = (self.mesh.nx, self.mesh.ny);
        let whole_mesh = self.affine_fit(None, 0, None, Support::NeverLost);
        let whole_mesh_valid = self.affine_fit_around(None, 0);
        for k in 0..nx * ny {
            let node = self.field.nodes[k];
            self.scratch.pairs[k] = if node.status == NodeStatus::Ok {
                (node.u_px, node.v_px)
            } else {
                self.affine_fit(Some(k), CARRY_RINGS, None, Support::NeverLost)
                    .or(whole_mesh)
                    .or_else(|| self.affine_fit_around(Some(k), EXTRAPOLATION_RINGS))
                    .or(whole_mesh_valid)
                    .map_or((self.field.u_mean_px, self.field.v_mean_px), |fit| {
                        self.extrapolate(k, fit)
                    })
            };
        }
        match origin {
            OriginBases::Now => {
                self.reference.origin_pending.clear();
                self.bases_from_origin(Image {
                    pixels,
                    width_px: self.width_px,
                    height_px: self.height_px,
                });
            }
            OriginBases::Deferred => self.defer_bases_from_origin(),
        }

        for (r, &base) in self.reference.nodes.iter_mut().zip(&self.scratch.pairs) {
            r.base_px = base;
        }
        for k in 0..nx * ny {
            self.reference.nodes[k].base_gradient = if self.field.nodes[k].status == NodeStatus::Ok
            {
                self.field.gradients[k]
            } else {
                self.base_fit_gradient(k)
            };
        }
        self.take_reference(pixels, self.settings.method.is_icgn());
        self.reference.is_origin = false;
    }

    /// Least-squares affine fit of the total displacement of the valid nodes within `rings`
    /// of node `centre` (all valid nodes when `centre` is None): the origin of the fit, (u, v)
    /// there, and ∇u; None with fewer than [`MIN_EXTRAPOLATION_NODES`] valid nodes or collinear.
    pub(super) fn affine_fit_around(
        &self,
        centre: Option<usize>,
        rings: usize,
    ) -> Option<AffineFit> {
        self.affine_fit(centre, rings, None, Support::Valid)
    }

    /// [`Self::affine_fit_around`] over the nodes of `support`, leaving node `exclude` out.
    pub(super) fn affine_fit(
        &self,
        centre: Option<usize>,
        rings: usize,
        exclude: Option<usize>,
        support: Support,
    ) -> Option<AffineFit> {
        let (nx, ny) = (self.mesh.nx, self.mesh.ny);
        let (i_range, j_range, origin) = match centre {
            Some(k) => {
                let (i, j) = (k % nx, k / nx);
                let node = &self.field.nodes[k];
                (
                    i.saturating_sub(rings)..=(i + rings).min(nx - 1),
                    j.saturating_sub(rings)..=(j + rings).min(ny - 1),
                    (node.x_px, node.y_px),
                )
            }
            None => (
                0..=nx - 1,
                0..=ny - 1,
                (
                    0.5 * (self.field.nodes[0].x_px + self.field.nodes[nx * ny - 1].x_px),
                    0.5 * (self.field.nodes[0].y_px + self.field.nodes[nx * ny - 1].y_px),
                ),
            ),
        };
        let mut sums = AffineSums::default();
        let mut count = 0;
        for j in j_range {
            for i in i_range.clone() {
                let m = j * nx + i;
                let node = &self.field.nodes[m];
                let supported = match support {
                    Support::Valid => true,
                    Support::NeverLost => self.history.never_lost[m],
                };
                if node.status == NodeStatus::Ok && supported && exclude != Some(m) {
                    sums.add(
                        node.x_px - origin.0,
                        node.y_px - origin.1,
                        node.u_px,
                        node.v_px,
                    );
                    count += 1;
                }
            }
        }
        if count < MIN_EXTRAPOLATION_NODES {
            return None;
        }
        sums.fit().map(|(at_origin_px, gradient)| AffineFit {
            origin_px: origin,
            at_origin_px,
            gradient,
        })
    }

    /// The displacement an affine fit (from [`Self::affine_fit_around`]) gives at node k.
    pub(super) fn extrapolate(
        &self,
        k: usize,
        AffineFit {
            origin_px: origin,
            at_origin_px: (u0, v0),
            gradient: g,
        }: AffineFit,
    ) -> (f64, f64) {
        let node = &self.field.nodes[k];
        let (dx, dy) = (node.x_px - origin.0, node.y_px - origin.1);
        (
            u0 + g[(0, 0)] * dx + g[(0, 1)] * dy,
            v0 + g[(1, 0)] * dx + g[(1, 1)] * dy,
        )
    }
}
