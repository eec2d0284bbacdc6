//! The finite-element field at any reference point, not only at the nodes: which element
//! holds the point and where in it (the inverse of the element's quadratic map, by Newton),
//! then the displacement Σ Nᵢ uᵢ and the deformation gradient F = I + Σ uᵢ ⊗ ∂Nᵢ/∂X there.
//! What a camera filming the specimen and a virtual-fields sum over a measurement grid need.
//!
//! Elements are found through a uniform grid of buckets over the mesh's bounding box, each
//! bucket listing the elements whose bounding box (of all six nodes: a curved edge stays
//! inside it for the meshes' gentle curvature) meets it.

use crate::assembly::deformation_gradient;
use crate::mesh::Mesh;
use crate::t6::{self, NODES};

/// Newton iterations of the inverse map at most; it converges in 2-4 on straight elements.
const INVERSE_MAX_ITERATIONS: usize = 25;
/// Convergence of the inverse map, in natural coordinates: the last Newton step is below it,
/// so (quadratic convergence) the point found is off by about its square, far below 1e-12.
const INVERSE_TOLERANCE: f64 = 1e-7;
/// How far outside [0, 1] a natural coordinate may be and the point still count as inside
/// (a point on an edge between two elements).
const EDGE_TOLERANCE: f64 = 1e-9;
/// Buckets per element on average.
const BUCKETS_PER_ELEMENT: f64 = 1.0;

/// A point of the reference configuration in an element: the element and (ξ, η).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Location {
    pub element: usize,
    pub xi: f64,
    pub eta: f64,
}

/// The field at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointSample {
    pub location: Location,
    pub displacement_mm: [f64; 2],
    /// In-plane deformation gradient, row-major.
    pub f: [[f64; 2]; 2],
}

/// A uniform grid of buckets over a mesh's bounding box, each listing the elements whose
/// bounding box meets it. Owns no mesh: build it from one and locate points in the same one
/// (its nodes may have moved since only if the grid is rebuilt).
#[derive(Clone, Debug)]
pub struct ElementGrid {
    /// Each element's bounding box (of its six nodes), [low, high]: a cheap refusal before
    /// Newton.
    boxes: Vec<[[f64; 2]; 2]>,
    origin_mm: [f64; 2],
    bucket_mm: f64,
    columns: usize,
    rows: usize,
    buckets: Vec<Vec<usize>>,
}

impl ElementGrid {
    pub fn new(mesh: &Mesh) -> ElementGrid {
        let boxes: Vec<[[f64; 2]; 2]> = (0..mesh.elements.len())
            .map(|e| bounding_box(&mesh.element_nodes_mm(e)))
            .collect();
        let (low, high) = boxes.iter().fold(
            ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
            |(low, high), b| {
                (
                    [low[0].min(b[0][0]), low[1].min(b[0][1])],
                    [high[0].max(b[1][0]), high[1].max(b[1][1])],
                )
            },
        );
        let size = [(high[0] - low[0]).max(1e-9), (high[1] - low[1]).max(1e-9)];
        let buckets_wanted = (mesh.elements.len() as f64 * BUCKETS_PER_ELEMENT).max(1.0);
        let bucket_mm = (size[0] * size[1] / buckets_wanted).sqrt().max(1e-9);
        let columns = ((size[0] / bucket_mm).ceil() as usize).max(1);
        let rows = ((size[1] / bucket_mm).ceil() as usize).max(1);
        let mut grid = ElementGrid {
            boxes: Vec::new(),
            origin_mm: low,
            bucket_mm,
            columns,
            rows,
            buckets: vec![Vec::new(); columns * rows],
        };
        for (e, b) in boxes.iter().enumerate() {
            let (c0, r0) = grid.cell(b[0]);
            let (c1, r1) = grid.cell(b[1]);
            for r in r0..=r1 {
                for c in c0..=c1 {
                    grid.buckets[r * columns + c].push(e);
                }
            }
        }
        grid.boxes = boxes;
        grid
    }

    /// The bucket of a point, clamped into the grid.
    fn cell(&self, x_mm: [f64; 2]) -> (usize, usize) {
        let at = |v: f64, origin: f64, count: usize| {
            (((v - origin) / self.bucket_mm).floor().max(0.0) as usize).min(count - 1)
        };
        (
            at(x_mm[0], self.origin_mm[0], self.columns),
            at(x_mm[1], self.origin_mm[1], self.rows),
        )
    }

    /// The elements whose bounding box holds `x_mm` (candidates for holding it); none outside
    /// the grid.
    pub fn candidates(&self, x_mm: [f64; 2]) -> impl Iterator<Item = usize> + '_ {
        let outside = |v: f64, low: f64, count: usize| {
            v < low - self.bucket_mm * 1e-9
                || v > low + self.bucket_mm * count as f64 + self.bucket_mm * 1e-9
        };
        let beyond = outside(x_mm[0], self.origin_mm[0], self.columns)
            || outside(x_mm[1], self.origin_mm[1], self.rows)
            || !(x_mm[0].is_finite() && x_mm[1].is_finite());
        let bucket: &[usize] = if beyond {
            &[]
        } else {
            let (c, r) = self.cell(x_mm);
            &self.buckets[r * self.columns + c]
        };
        let slack = self.bucket_mm * 1e-9;
        bucket.iter().copied().filter(move |&e| {
            let [low, high] = self.boxes[e];
            x_mm[0] >= low[0] - slack
                && x_mm[0] <= high[0] + slack
                && x_mm[1] >= low[1] - slack
                && x_mm[1] <= high[1] + slack
        })
    }

    /// Whether any element's bounding box meets the rectangle [low, high] (mm): when none
    /// does, no point of it is in the mesh.
    pub fn any_element_meets(&self, low: [f64; 2], high: [f64; 2]) -> bool {
        let grid_high = [
            self.origin_mm[0] + self.bucket_mm * self.columns as f64,
            self.origin_mm[1] + self.bucket_mm * self.rows as f64,
        ];
        if high[0] < self.origin_mm[0]
            || high[1] < self.origin_mm[1]
            || low[0] > grid_high[0]
            || low[1] > grid_high[1]
        {
            return false;
        }
        let (c0, r0) = self.cell(low);
        let (c1, r1) = self.cell(high);
        (r0..=r1).any(|r| {
            (c0..=c1).any(|c| {
                self.buckets[r * self.columns + c].iter().any(|&e| {
                    let [lo, hi] = self.boxes[e];
                    lo[0] <= high[0] && hi[0] >= low[0] && lo[1] <= high[1] && hi[1] >= low[1]
                })
            })
        })
    }

    /// The element of `mesh` (the one the grid was built from) holding `x_mm` and where in
    /// it; None outside the mesh.
    pub fn locate(&self, mesh: &Mesh, x_mm: [f64; 2]) -> Option<Location> {
        self.candidates(x_mm).find_map(|e| {
            natural_coordinates(&mesh.element_nodes_mm(e), x_mm, CENTROID).map(|(xi, eta)| {
                Location {
                    element: e,
                    xi,
                    eta,
                }
            })
        })
    }

    /// [`Self::locate`], trying first the element of `near` from its natural coordinates
    /// (a neighbouring point's location: one or two Newton steps when it is the same
    /// element, as for the next pixel of a row).
    pub fn locate_near(&self, mesh: &Mesh, x_mm: [f64; 2], near: Location) -> Option<Location> {
        natural_coordinates(
            &mesh.element_nodes_mm(near.element),
            x_mm,
            (near.xi, near.eta),
        )
        .map(|(xi, eta)| Location {
            element: near.element,
            xi,
            eta,
        })
        .or_else(|| self.locate(mesh, x_mm))
    }
}

/// Finds points in a mesh and samples a displacement field there.
#[derive(Clone, Debug)]
pub struct Probe<'m> {
    mesh: &'m Mesh,
    grid: ElementGrid,
}

impl<'m> Probe<'m> {
    pub fn new(mesh: &'m Mesh) -> Probe<'m> {
        Probe {
            mesh,
            grid: ElementGrid::new(mesh),
        }
    }

    /// The element holding the reference point `x_mm` and where in it; None outside the
    /// mesh.
    pub fn locate(&self, x_mm: [f64; 2]) -> Option<Location> {
        self.grid.locate(self.mesh, x_mm)
    }

    /// The field of the nodal displacements `u` (two per node, mm) at the reference point
    /// `x_mm`; None outside the mesh.
    pub fn sample(&self, u: &[f64], x_mm: [f64; 2]) -> Option<PointSample> {
        let location = self.locate(x_mm)?;
        sample_at(self.mesh, u, location)
    }
}

/// The field of the nodal displacements `u` (two per node, mm) of `mesh` at `location`; None
/// where the element's Jacobian is not positive.
pub fn sample_at(mesh: &Mesh, u: &[f64], location: Location) -> Option<PointSample> {
    let element = &mesh.elements[location.element];
    let nodes_mm = mesh.element_nodes_mm(location.element);
    let (gradients, _) = t6::gradients_at(&nodes_mm, location.xi, location.eta).ok()?;
    let shape = t6::shape(location.xi, location.eta);
    let mut displacement_mm = [0.0; 2];
    for (&node, n) in element.iter().zip(shape.iter()) {
        displacement_mm[0] += n * u[2 * node];
        displacement_mm[1] += n * u[2 * node + 1];
    }
    Some(PointSample {
        location,
        displacement_mm,
        f: deformation_gradient(element, &gradients, u),
    })
}

/// The point of `mesh` at `location`: Σ Nᵢ(ξ, η) Xᵢ, mm.
pub fn point_at(mesh: &Mesh, location: Location) -> [f64; 2] {
    let shape = t6::shape(location.xi, location.eta);
    let mut x = [0.0; 2];
    for (&node, n) in mesh.elements[location.element].iter().zip(shape.iter()) {
        x[0] += n * mesh.nodes_mm[node][0];
        x[1] += n * mesh.nodes_mm[node][1];
    }
    x
}

fn bounding_box(nodes_mm: &[[f64; 2]; NODES]) -> [[f64; 2]; 2] {
    nodes_mm.iter().fold(
        [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]],
        |[low, high], p| {
            [
                [low[0].min(p[0]), low[1].min(p[1])],
                [high[0].max(p[0]), high[1].max(p[1])],
            ]
        },
    )
}

/// The element's centroid in natural coordinates, where Newton starts without a better guess.
const CENTROID: (f64, f64) = (1.0 / 3.0, 1.0 / 3.0);

/// (ξ, η) of `x_mm` in the element of `nodes_mm` when it lies inside (Newton on the quadratic
/// map from `start`); None outside or when Newton does not converge.
fn natural_coordinates(
    nodes_mm: &[[f64; 2]; NODES],
    x_mm: [f64; 2],
    start: (f64, f64),
) -> Option<(f64, f64)> {
    let (mut xi, mut eta) = start;
    for _ in 0..INVERSE_MAX_ITERATIONS {
        let shape = t6::shape(xi, eta);
        let dn = t6::shape_gradients(xi, eta);
        let mut x = [0.0; 2];
        let mut jac = [[0.0; 2]; 2]; // ∂X_i/∂ξ_k
        for k in 0..NODES {
            for i in 0..2 {
                x[i] += shape[k] * nodes_mm[k][i];
                jac[i][0] += dn[k][0] * nodes_mm[k][i];
                jac[i][1] += dn[k][1] * nodes_mm[k][i];
            }
        }
        let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
        if !(det.is_finite() && det > 0.0) {
            return None;
        }
        let r = [x_mm[0] - x[0], x_mm[1] - x[1]];
        let d_xi = (jac[1][1] * r[0] - jac[0][1] * r[1]) / det;
        let d_eta = (-jac[1][0] * r[0] + jac[0][0] * r[1]) / det;
        xi += d_xi;
        eta += d_eta;
        if d_xi.abs().max(d_eta.abs()) < INVERSE_TOLERANCE {
            let inside = xi >= -EDGE_TOLERANCE
                && eta >= -EDGE_TOLERANCE
                && 1.0 - xi - eta >= -EDGE_TOLERANCE;
            return inside.then_some((xi, eta));
        }
        // Far outside: not this element (Newton may wander on a curved map there).
        if xi.abs() > 10.0 || eta.abs() > 10.0 {
            return None;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::MeshBuilder;

    /// A 10 × 6 mm parallelogram of 5 × 3 cells, its nodes 1 mm apart along X, sheared by
    /// 0.1 (straight-sided elements: a quadratic field is then exact in them).
    fn rectangle() -> Mesh {
        let mut builder = MeshBuilder::new(1e-9);
        builder.add_patch(5, 3, |i, j| [i as f64 + 0.1 * j as f64, j as f64]);
        builder.finish().unwrap()
    }

    #[test]
    fn a_homogeneous_field_is_found_exactly_anywhere_and_nothing_outside() {
        let mesh = rectangle();
        let probe = Probe::new(&mesh);
        // x = F X + t with F = [[1.3, 0.2], [-0.1, 0.8]], t = (0.5, -0.25) mm.
        let f = [[1.3, 0.2], [-0.1, 0.8]];
        let t = [0.5, -0.25];
        let u: Vec<f64> = mesh
            .nodes_mm
            .iter()
            .flat_map(|x| {
                [
                    f[0][0] * x[0] + f[0][1] * x[1] + t[0] - x[0],
                    f[1][0] * x[0] + f[1][1] * x[1] + t[1] - x[1],
                ]
            })
            .collect();
        for x in [
            [0.0, 0.0],
            [3.3, 1.7],
            [9.99, 5.99],
            [10.0, 6.0],
            [5.0, 3.0],
            [7.25, 0.5],
        ] {
            let s = probe
                .sample(&u, x)
                .unwrap_or_else(|| panic!("{x:?} not found"));
            let want = [
                f[0][0] * x[0] + f[0][1] * x[1] + t[0] - x[0],
                f[1][0] * x[0] + f[1][1] * x[1] + t[1] - x[1],
            ];
            for i in 0..2 {
                assert!(
                    (s.displacement_mm[i] - want[i]).abs() < 1e-12,
                    "{x:?} {s:?}"
                );
                for (got, want) in s.f[i].iter().zip(f[i].iter()) {
                    assert!((got - want).abs() < 1e-12, "{x:?} {s:?}");
                }
            }
        }
        for x in [
            [-0.01, 0.5],
            [10.1, 0.5],
            [0.1, 5.0],
            [5.0, 6.5],
            [f64::NAN, 1.0],
        ] {
            assert!(probe.locate(x).is_none(), "{x:?}");
        }
    }

    #[test]
    fn a_quadratic_field_is_interpolated_exactly_inside_each_element() {
        let mesh = rectangle();
        let probe = Probe::new(&mesh);
        // u = (0.01 X², 0.02 X Y): quadratic, which T6 represents exactly.
        let u: Vec<f64> = mesh
            .nodes_mm
            .iter()
            .flat_map(|x| [0.01 * x[0] * x[0], 0.02 * x[0] * x[1]])
            .collect();
        let x = [6.3, 2.2];
        let s = probe.sample(&u, x).unwrap();
        assert!((s.displacement_mm[0] - 0.01 * 6.3 * 6.3).abs() < 1e-12);
        assert!((s.displacement_mm[1] - 0.02 * 6.3 * 2.2).abs() < 1e-12);
        assert!((s.f[0][0] - (1.0 + 0.02 * 6.3)).abs() < 1e-12);
        assert!((s.f[1][0] - 0.02 * 2.2).abs() < 1e-12);
        assert!((s.f[1][1] - (1.0 + 0.02 * 6.3)).abs() < 1e-12);
    }

    #[test]
    fn every_node_and_element_centre_of_the_cruciform_is_found_with_its_curved_fillets() {
        let specimen = crate::specimens::cruciform::CruciformGeometry::default()
            .mesh()
            .unwrap();
        let mesh = &specimen.mesh;
        let probe = Probe::new(mesh);
        // A smooth field with every node's value: sampled at a node it is that node's value.
        let field = |x: [f64; 2]| {
            [
                0.01 * x[0] + 1e-4 * x[1] * x[1],
                -0.02 * x[1] + 1e-4 * x[0] * x[1],
            ]
        };
        let u: Vec<f64> = mesh.nodes_mm.iter().flat_map(|&x| field(x)).collect();
        for (n, &x) in mesh.nodes_mm.iter().enumerate() {
            let s = probe
                .sample(&u, x)
                .unwrap_or_else(|| panic!("node {n} at {x:?} not found"));
            for i in 0..2 {
                assert!(
                    (s.displacement_mm[i] - u[2 * n + i]).abs() < 1e-9,
                    "node {n}: {s:?}"
                );
            }
        }
        // Each element's centroid lies in that element (and in no other).
        for e in 0..mesh.elements.len() {
            let nodes = mesh.element_nodes_mm(e);
            let shape = t6::shape(1.0 / 3.0, 1.0 / 3.0);
            let mut centre = [0.0; 2];
            for (p, w) in nodes.iter().zip(shape.iter()) {
                centre[0] += w * p[0];
                centre[1] += w * p[1];
            }
            let at = probe.locate(centre).unwrap();
            assert_eq!(at.element, e, "{centre:?}");
            assert!((at.xi - 1.0 / 3.0).abs() < 1e-9 && (at.eta - 1.0 / 3.0).abs() < 1e-9);
        }
        // The corner between two arms is not material.
        let corner = [0.95 * 100.0, 0.95 * 100.0];
        assert!(probe.locate(corner).is_none());
    }
}
