//! A strip between two clamps along x: the uniaxial strip (long and narrow) and the paper's
//! "plane strain" strip (Fig. 9: wide, short between the clamps) are the same mesh with
//! different proportions. Reference frame: centred, x ∈ [−L/2, L/2], y ∈ [−w/2, w/2].

use super::{cells, check_size, positive, tolerance_mm, Grip, Specimen};
use crate::error::GeometryError;
use crate::mesh::MeshBuilder;

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StripGeometry {
    /// Free length between the clamps (along x, the pull).
    pub length_mm: f64,
    /// Width (along y).
    pub width_mm: f64,
    pub thickness_mm: f64,
    /// Target element edge.
    pub element_size_mm: f64,
}

impl StripGeometry {
    /// A uniaxial strip 100 × 20 × 2 mm (the rig's uniaxial specimen), 2.5 mm elements.
    pub fn uniaxial() -> Self {
        StripGeometry {
            length_mm: 100.0,
            width_mm: 20.0,
            thickness_mm: 2.0,
            element_size_mm: 2.5,
        }
    }

    /// The plane-strain strip of Fig. 9: 20 mm between clamps, 200 mm wide, 2.5 mm elements.
    pub fn plane_strain() -> Self {
        StripGeometry {
            length_mm: 20.0,
            width_mm: 200.0,
            thickness_mm: 2.0,
            element_size_mm: 2.5,
        }
    }

    /// The meshed strip with grips "x-" and "x+" on its two ends.
    pub fn mesh(&self) -> Result<Specimen, GeometryError> {
        let length = positive("length", self.length_mm)?;
        let width = positive("width", self.width_mm)?;
        let thickness_mm = positive("thickness", self.thickness_mm)?;
        let size = positive("element size", self.element_size_mm)?;
        let (nx, ny) = (cells(length, size, 1), cells(width, size, 1));
        check_size(2 * nx.saturating_mul(ny))?;
        let tolerance = tolerance_mm(length.max(width));
        let mut builder = MeshBuilder::new(tolerance);
        builder.add_patch(nx, ny, |i, j| {
            [
                length * (i as f64 / (2 * nx) as f64 - 0.5),
                width * (j as f64 / (2 * ny) as f64 - 0.5),
            ]
        });
        let mesh = builder.finish()?;
        let grips = [("x-", -1.0), ("x+", 1.0)]
            .map(|(name, side)| Grip {
                name,
                nodes: mesh.nodes_where(|p| (p[0] - side * 0.5 * length).abs() < tolerance),
                centre_mm: [side * 0.5 * length, 0.0],
                axis: [side, 0.0],
            })
            .to_vec();
        Ok(Specimen {
            mesh,
            thickness_mm,
            grips,
        })
    }
}
