//! Means over a region of the reference sheet (what a camera films: the cruciform's central
//! square, the middle of a strip): the mean deformation gradient ∫F dA / A and the mean
//! displacement ∫u dA / A, by the elements' Gauss points. Both are linear in the nodal
//! displacements, so they follow a grip's displacement mode exactly.

use crate::error::GeometryError;
use crate::mesh::Mesh;
use crate::t6::{self, NODES};

/// One Gauss point of the region.
#[derive(Clone, Debug, PartialEq)]
struct Point {
    nodes: [usize; NODES],
    gradients_per_mm: [[f64; 2]; NODES],
    shape: [f64; NODES],
    area_mm2: f64,
}

/// The elements of a mesh whose centroid lies in a region.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    points: Vec<Point>,
    area_mm2: f64,
}

impl Region {
    /// The elements whose reference centroid satisfies `inside`; an empty region is refused
    /// (`GeometryError::EmptyRegion`).
    pub fn new(mesh: &Mesh, inside: impl Fn([f64; 2]) -> bool) -> Result<Region, GeometryError> {
        let gauss = mesh.gauss_points()?;
        let mut points = Vec::new();
        for (e, element_points) in gauss.iter().enumerate() {
            let nodes_mm = mesh.element_nodes_mm(e);
            let centroid = [0, 1].map(|i| nodes_mm[..3].iter().map(|p| p[i]).sum::<f64>() / 3.0);
            if !inside(centroid) {
                continue;
            }
            for (p, &(xi, eta, _)) in element_points.iter().zip(t6::GAUSS_POINTS.iter()) {
                points.push(Point {
                    nodes: mesh.elements[e],
                    gradients_per_mm: p.gradients_per_mm,
                    shape: t6::shape(xi, eta),
                    area_mm2: p.area_mm2,
                });
            }
        }
        let area_mm2: f64 = points.iter().map(|p| p.area_mm2).sum();
        if points.is_empty() || area_mm2 <= 0.0 {
            return Err(GeometryError::EmptyRegion);
        }
        Ok(Region { points, area_mm2 })
    }

    /// Reference area of the region's elements, mm².
    pub fn area_mm2(&self) -> f64 {
        self.area_mm2
    }

    /// Mean displacement gradient ∫∇u dA / A under the nodal displacements `u` (mm, two per
    /// node), row-major [i][J]: the mean F less the identity (linear in `u`).
    pub fn mean_displacement_gradient(&self, u: &[f64]) -> [[f64; 2]; 2] {
        let mut h = [[0.0; 2]; 2];
        for p in &self.points {
            for (&node, g) in p.nodes.iter().zip(&p.gradients_per_mm) {
                for i in 0..2 {
                    for j in 0..2 {
                        h[i][j] += p.area_mm2 * u[2 * node + i] * g[j];
                    }
                }
            }
        }
        h.map(|row| row.map(|v| v / self.area_mm2))
    }

    /// Mean deformation gradient ∫F dA / A, row-major [i][J].
    pub fn mean_deformation_gradient(&self, u: &[f64]) -> [[f64; 2]; 2] {
        let h = self.mean_displacement_gradient(u);
        [[1.0 + h[0][0], h[0][1]], [h[1][0], 1.0 + h[1][1]]]
    }

    /// Mean displacement ∫u dA / A, mm.
    pub fn mean_displacement_mm(&self, u: &[f64]) -> [f64; 2] {
        let mut m = [0.0; 2];
        for p in &self.points {
            for (&node, n) in p.nodes.iter().zip(&p.shape) {
                m[0] += p.area_mm2 * n * u[2 * node];
                m[1] += p.area_mm2 * n * u[2 * node + 1];
            }
        }
        m.map(|v| v / self.area_mm2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::specimens::SpecimenChoice;

    #[test]
    fn an_affine_field_has_its_own_gradient_as_mean_and_its_centre_value_as_mean_displacement() {
        let specimen = SpecimenChoice::default().mesh().unwrap();
        let mesh = &specimen.mesh;
        let region = Region::new(mesh, |p| p[0].abs() < 50.0 && p[1].abs() < 50.0).unwrap();
        assert!((region.area_mm2() - 100.0 * 100.0).abs() < 1e-6);
        let h = [[0.3, -0.1], [0.05, 0.2]];
        let c = [1.5, -2.0];
        let u: Vec<f64> = mesh
            .nodes_mm
            .iter()
            .flat_map(|x| [0, 1].map(|i| c[i] + h[i][0] * x[0] + h[i][1] * x[1]))
            .collect();
        let mean = region.mean_displacement_gradient(&u);
        for i in 0..2 {
            for j in 0..2 {
                assert!((mean[i][j] - h[i][j]).abs() < 1e-12, "{mean:?}");
            }
        }
        let m = region.mean_displacement_mm(&u);
        assert!(
            (m[0] - c[0]).abs() < 1e-12 && (m[1] - c[1]).abs() < 1e-12,
            "{m:?}"
        );
        assert_eq!(
            Region::new(mesh, |p| p[0] > 1e6),
            Err(GeometryError::EmptyRegion)
        );
    }
}
