//! The reference mesh: node positions (mm) and T6 connectivity, built from structured patches
//! whose shared nodes are merged by position (`MeshBuilder`).

use crate::error::GeometryError;
use crate::t6::{self, GaussPoint, NODES};
use std::collections::HashMap;

/// Nodes and six-node triangles (corners counter-clockwise, then midsides 01, 12, 20).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub nodes_mm: Vec<[f64; 2]>,
    pub elements: Vec<[usize; NODES]>,
}

impl Mesh {
    /// Reference positions of an element's nodes.
    pub fn element_nodes_mm(&self, element: usize) -> [[f64; 2]; NODES] {
        self.elements[element].map(|n| self.nodes_mm[n])
    }

    /// Gauss points of every element, or the first element whose Jacobian is not positive.
    pub fn gauss_points(&self) -> Result<Vec<[GaussPoint; 6]>, GeometryError> {
        (0..self.elements.len())
            .map(|e| {
                t6::gauss_points(&self.element_nodes_mm(e)).map_err(|jacobian_mm2| {
                    GeometryError::InvertedElement {
                        element: e,
                        jacobian_mm2,
                    }
                })
            })
            .collect()
    }

    /// Reference area, mm² (exact for the mesh's quadratic geometry).
    pub fn area_mm2(&self) -> Result<f64, GeometryError> {
        Ok(self
            .gauss_points()?
            .iter()
            .flat_map(|points| points.iter().map(|p| p.area_mm2))
            .sum())
    }

    /// Nodes whose reference position satisfies `keep`.
    pub fn nodes_where(&self, keep: impl Fn([f64; 2]) -> bool) -> Vec<usize> {
        (0..self.nodes_mm.len())
            .filter(|&n| keep(self.nodes_mm[n]))
            .collect()
    }

    /// Degrees of freedom (two per node).
    pub fn dof_count(&self) -> usize {
        2 * self.nodes_mm.len()
    }
}

/// Builds a mesh from structured patches, merging nodes that coincide (within `tolerance_mm`).
pub struct MeshBuilder {
    mesh: Mesh,
    index: HashMap<(i64, i64), usize>,
    tolerance_mm: f64,
}

impl MeshBuilder {
    pub fn new(tolerance_mm: f64) -> Self {
        MeshBuilder {
            mesh: Mesh::default(),
            index: HashMap::new(),
            tolerance_mm,
        }
    }

    /// The node at `p_mm`, created unless one is already there.
    fn node(&mut self, p_mm: [f64; 2]) -> usize {
        let key = (
            (p_mm[0] / self.tolerance_mm).round() as i64,
            (p_mm[1] / self.tolerance_mm).round() as i64,
        );
        let nodes = &mut self.mesh.nodes_mm;
        *self.index.entry(key).or_insert_with(|| {
            nodes.push(p_mm);
            nodes.len() - 1
        })
    }

    /// A patch of `cells_x` × `cells_y` cells, each split into two T6 (diagonals alternating),
    /// from the positions of its (2 cells_x + 1) × (2 cells_y + 1) nodes: `position(i, j)`, i
    /// along the first direction, j along the second, (i, j) right-handed.
    pub fn add_patch(
        &mut self,
        cells_x: usize,
        cells_y: usize,
        position: impl Fn(usize, usize) -> [f64; 2],
    ) {
        self.add_cut_patch(cells_x, cells_y, position, |_, _| false);
    }

    /// [`MeshBuilder::add_patch`] with cuts: a node (i, j) with `cut(i, j)` (j even, a cell
    /// boundary) is doubled, the cells above it getting their own copy (a slit).
    pub fn add_cut_patch(
        &mut self,
        cells_x: usize,
        cells_y: usize,
        position: impl Fn(usize, usize) -> [f64; 2],
        cut: impl Fn(usize, usize) -> bool,
    ) {
        let columns = 2 * cells_y + 1;
        let ids: Vec<usize> = (0..=2 * cells_x)
            .flat_map(|i| (0..columns).map(move |j| (i, j)))
            .map(|(i, j)| self.node(position(i, j)))
            .collect();
        let upper: Vec<usize> = (0..ids.len())
            .map(|k| {
                let (i, j) = (k / columns, k % columns);
                if cut(i, j) {
                    self.mesh.nodes_mm.push(position(i, j));
                    self.mesh.nodes_mm.len() - 1
                } else {
                    ids[k]
                }
            })
            .collect();
        for cx in 0..cells_x {
            for cy in 0..cells_y {
                let p = |di: usize, dj: usize| {
                    let k = (2 * cx + di) * columns + 2 * cy + dj;
                    if dj == 0 {
                        upper[k]
                    } else {
                        ids[k]
                    }
                };
                let triangles = if (cx + cy) % 2 == 0 {
                    [
                        [p(0, 0), p(2, 0), p(2, 2), p(1, 0), p(2, 1), p(1, 1)],
                        [p(0, 0), p(2, 2), p(0, 2), p(1, 1), p(1, 2), p(0, 1)],
                    ]
                } else {
                    [
                        [p(0, 0), p(2, 0), p(0, 2), p(1, 0), p(1, 1), p(0, 1)],
                        [p(2, 0), p(2, 2), p(0, 2), p(2, 1), p(1, 2), p(1, 1)],
                    ]
                };
                self.mesh.elements.extend(triangles);
            }
        }
    }

    /// The mesh, checked: every element's Jacobian positive at every Gauss point.
    pub fn finish(self) -> Result<Mesh, GeometryError> {
        self.mesh.gauss_points()?;
        Ok(self.mesh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patches_share_their_common_nodes() {
        let mut builder = MeshBuilder::new(1e-7);
        builder.add_patch(2, 1, |i, j| [i as f64 * 0.5, j as f64 * 0.5]);
        builder.add_patch(2, 1, |i, j| [2.0 + i as f64 * 0.5, j as f64 * 0.5]);
        let mesh = builder.finish().unwrap();
        assert_eq!(mesh.elements.len(), 8);
        assert_eq!(mesh.nodes_mm.len(), 9 * 3);
        assert!((mesh.area_mm2().unwrap() - 4.0).abs() < 1e-12);
    }
}
