//! The mesh of ZOI centres in the ROI, which of them are in the region, and its
//! centre-outwards ring order.

use crate::region::ResolvedRegion;
use crate::settings::Roi;

pub struct Mesh {
    pub nx: usize,
    pub ny: usize,
    /// ZOI top-left corners in the first reference image (px), row-major, x fastest.
    pub top_left: Vec<(usize, usize)>,
    /// Node indices sorted by ring (Chebyshev distance to the centre node).
    pub ring_order: Vec<usize>,
    /// `ring_order[ring_starts[k]..ring_starts[k + 1]]` is ring k.
    pub ring_starts: Vec<usize>,
    pub ring_of: Vec<usize>,
    /// Whether node k's ZOI lies wholly inside the region (the others are `outside_region`).
    pub in_region: Vec<bool>,
}

impl Mesh {
    /// ZOIs of `zoi_px` every `step_px` inside the ROI, the mesh centred in the ROI.
    pub fn new(roi: Roi, zoi_px: usize, step_px: usize) -> Self {
        assert!(zoi_px <= roi.width_px && zoi_px <= roi.height_px && step_px >= 1);
        let count = |extent: usize| (extent - zoi_px) / step_px + 1;
        let (nx, ny) = (count(roi.width_px), count(roi.height_px));
        let margin_x = (roi.width_px - zoi_px - (nx - 1) * step_px) / 2;
        let margin_y = (roi.height_px - zoi_px - (ny - 1) * step_px) / 2;
        let mut top_left = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                top_left.push((
                    roi.x_px + margin_x + i * step_px,
                    roi.y_px + margin_y + j * step_px,
                ));
            }
        }
        let (ci, cj) = (nx / 2, ny / 2);
        let ring_of: Vec<usize> = (0..nx * ny)
            .map(|k| (k % nx).abs_diff(ci).max((k / nx).abs_diff(cj)))
            .collect();
        let mut ring_order: Vec<usize> = (0..nx * ny).collect();
        ring_order.sort_by_key(|&k| ring_of[k]);
        let rings = ring_of.iter().max().copied().unwrap_or(0) + 1;
        let mut ring_starts = vec![0; rings + 1];
        for &k in &ring_order {
            ring_starts[ring_of[k] + 1] += 1;
        }
        for r in 0..rings {
            ring_starts[r + 1] += ring_starts[r];
        }
        Self {
            nx,
            ny,
            top_left,
            ring_order,
            ring_starts,
            ring_of,
            in_region: vec![true; nx * ny],
        }
    }

    /// The mesh over the region's rectangle, its nodes whose ZOI leaves the region marked.
    pub fn of_region(region: &ResolvedRegion, zoi_px: usize, step_px: usize) -> Self {
        let mut mesh = Mesh::new(region.mesh_rect, zoi_px, step_px);
        for (inside, &top_left) in mesh.in_region.iter_mut().zip(&mesh.top_left) {
            *inside = region.contains_block(top_left, zoi_px);
        }
        mesh
    }

    /// Nodes whose ZOI lies inside the region.
    pub fn measured(&self) -> usize {
        self.in_region.iter().filter(|&&inside| inside).count()
    }

    pub fn len(&self) -> usize {
        self.nx * self.ny
    }

    pub fn rings(&self) -> usize {
        self.ring_starts.len() - 1
    }

    /// Centre of ZOI `k` in the first reference image (px).
    pub fn centre_px(&self, k: usize, zoi_px: usize) -> (f64, f64) {
        let (x0, y0) = self.top_left[k];
        let half = (zoi_px as f64 - 1.0) / 2.0;
        (x0 as f64 + half, y0 as f64 + half)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mesh_1024() {
        let roi = Roi {
            x_px: 0,
            y_px: 0,
            width_px: 1024,
            height_px: 1024,
        };
        let mesh = Mesh::new(roi, 32, 16);
        assert_eq!(mesh.len(), 3969);
        assert_eq!(mesh.ring_starts[1], 1);
        assert_eq!(*mesh.ring_starts.last().unwrap(), 3969);
        assert_eq!(mesh.ring_order[0], 31 * 63 + 31);
    }
}
