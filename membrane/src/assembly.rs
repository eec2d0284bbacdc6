//! Total Lagrangian membrane: internal forces and tangent stiffness of the T6 mesh at a
//! displacement, element by element (the solver scatters them).
//!
//! At a Gauss point F = I + Σ u_a ⊗ ∇N_a (in-plane), c = Voigt(FᵀF), S and D from the point
//! law; with B_a the variation of e = [E11, E22, 2E12] with the node's displacement:
//! f_a = ∫ B_aᵀ S h0 dA, K_ab = ∫ (B_aᵀ D B_b + (∇N_a · S ∇N_b) I) h0 dA, in N and N/mm.

use crate::constitutive::{self, MembraneState, PointFailure, StateCount, Voigt, Wrinkling};
use crate::error::GeometryError;
use crate::law::SheetLaw;
use crate::mesh::Mesh;
use crate::t6::{GaussPoint, NODES};

/// Element degrees of freedom.
pub const ELEMENT_DOFS: usize = 2 * NODES;
/// An element stiffness matrix, N/mm.
pub type ElementMatrix = [[f64; ELEMENT_DOFS]; ELEMENT_DOFS];

/// The discretised sheet: mesh, reference thickness, law and its Gauss points.
pub struct Membrane<'a, L: SheetLaw + ?Sized> {
    pub mesh: &'a Mesh,
    pub thickness_mm: f64,
    pub law: &'a L,
    pub wrinkling: Wrinkling,
    points: Vec<[GaussPoint; 6]>,
}

/// Where a point failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FailureAt {
    pub element: usize,
    pub point: usize,
    pub failure: PointFailure,
}

/// Internal forces (all DOFs, N), element tangents if asked, and the states of the points.
pub struct Evaluation {
    pub forces_n: Vec<f64>,
    pub element_tangents: Vec<ElementMatrix>,
    pub states: StateCount,
}

/// The state of one Gauss point, for output and tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointField {
    pub element: usize,
    pub reference_mm: [f64; 2],
    /// In-plane deformation gradient F[i][J].
    pub deformation_gradient: [[f64; 2]; 2],
    pub stress_pk2_mpa: Voigt,
    /// In-plane Cauchy stress F S Fᵀ (λ1 λ2 λ3 = 1), MPa, Voigt.
    pub cauchy_stress_mpa: Voigt,
    pub state: MembraneState,
}

impl<'a, L: SheetLaw + ?Sized> Membrane<'a, L> {
    pub fn new(
        mesh: &'a Mesh,
        thickness_mm: f64,
        law: &'a L,
        wrinkling: Wrinkling,
    ) -> Result<Self, GeometryError> {
        if !(thickness_mm > 0.0 && thickness_mm.is_finite()) {
            return Err(GeometryError::NotPositive {
                name: "thickness",
                value_mm: thickness_mm,
            });
        }
        Ok(Membrane {
            mesh,
            thickness_mm,
            law,
            wrinkling,
            points: mesh.gauss_points()?,
        })
    }

    fn point_response(
        &self,
        element: usize,
        index: usize,
        u: &[f64],
    ) -> Result<([[f64; 2]; 2], constitutive::PointResponse), FailureAt> {
        let f = deformation_gradient(
            &self.mesh.elements[element],
            &self.points[element][index].gradients_per_mm,
            u,
        );
        response_to(self.law, &self.wrinkling, &f)
            .map(|r| (f, r))
            .map_err(|failure| FailureAt {
                element,
                point: index,
                failure,
            })
    }

    /// Internal forces at displacement `u` (mm, two per node), and the element tangents when
    /// `with_tangent`.
    pub fn evaluate(&self, u: &[f64], with_tangent: bool) -> Result<Evaluation, FailureAt> {
        let mut forces_n = vec![0.0; self.mesh.dof_count()];
        let mut element_tangents = Vec::with_capacity(if with_tangent {
            self.mesh.elements.len()
        } else {
            0
        });
        let mut states = StateCount::default();
        for (e, nodes) in self.mesh.elements.iter().enumerate() {
            let mut k = [[0.0; ELEMENT_DOFS]; ELEMENT_DOFS];
            for (index, point) in self.points[e].iter().enumerate() {
                let (f, response) = self.point_response(e, index, u)?;
                states.add(response.state);
                let weight = point.area_mm2 * self.thickness_mm;
                let b = strain_variation(&f, &point.gradients_per_mm);
                let s = response.stress_pk2_mpa;
                for (a, &node) in nodes.iter().enumerate() {
                    for i in 0..2 {
                        let row = &b[2 * a + i];
                        forces_n[2 * node + i] +=
                            weight * (row[0] * s[0] + row[1] * s[1] + row[2] * s[2]);
                    }
                }
                if with_tangent {
                    add_point_tangent(
                        &mut k,
                        &b,
                        &response.tangent_mpa,
                        &s,
                        &point.gradients_per_mm,
                        weight,
                    );
                }
            }
            if with_tangent {
                element_tangents.push(k);
            }
        }
        Ok(Evaluation {
            forces_n,
            element_tangents,
            states,
        })
    }

    /// Every Gauss point's kinematics and stresses at displacement `u`.
    pub fn point_fields(&self, u: &[f64]) -> Result<Vec<PointField>, FailureAt> {
        let mut out = Vec::with_capacity(6 * self.mesh.elements.len());
        for e in 0..self.mesh.elements.len() {
            let nodes = self.mesh.element_nodes_mm(e);
            for (index, &(xi, eta, _)) in crate::t6::GAUSS_POINTS.iter().enumerate() {
                let (f, response) = self.point_response(e, index, u)?;
                let n = crate::t6::shape(xi, eta);
                let reference_mm = [0, 1].map(|i| (0..NODES).map(|a| n[a] * nodes[a][i]).sum());
                out.push(PointField {
                    element: e,
                    reference_mm,
                    deformation_gradient: f,
                    stress_pk2_mpa: response.stress_pk2_mpa,
                    cauchy_stress_mpa: push_forward(&f, &response.stress_pk2_mpa),
                    state: response.state,
                });
            }
        }
        Ok(out)
    }
}

/// The in-plane F[i][J] = δiJ + Σ u_a,i ∂N_a/∂X_J of an element with nodes `element_nodes`
/// and shape-function gradients `gradients_per_mm` at a point, under displacement `u` (mm).
pub(crate) fn deformation_gradient(
    element_nodes: &[usize; NODES],
    gradients_per_mm: &[[f64; 2]; NODES],
    u: &[f64],
) -> [[f64; 2]; 2] {
    let mut f = [[1.0, 0.0], [0.0, 1.0]];
    for (&node, g) in element_nodes.iter().zip(gradients_per_mm.iter()) {
        for i in 0..2 {
            for j in 0..2 {
                f[i][j] += u[2 * node + i] * g[j];
            }
        }
    }
    f
}

/// C = Fᵀ F of an in-plane F, Voigt [C11, C22, C12].
pub(crate) fn right_cauchy_green(f: &[[f64; 2]; 2]) -> Voigt {
    [
        f[0][0] * f[0][0] + f[1][0] * f[1][0],
        f[0][1] * f[0][1] + f[1][1] * f[1][1],
        f[0][0] * f[0][1] + f[1][0] * f[1][1],
    ]
}

/// The law's response (with tension-field relaxation) to an in-plane F; an inverted F (det F
/// ≤ 0 or not a number) has none.
pub(crate) fn response_to<L: SheetLaw + ?Sized>(
    law: &L,
    wrinkling: &Wrinkling,
    f: &[[f64; 2]; 2],
) -> Result<constitutive::PointResponse, PointFailure> {
    let det_f = f[0][0] * f[1][1] - f[0][1] * f[1][0];
    if det_f.is_nan() || det_f <= 0.0 {
        return Err(PointFailure::Inverted {
            det_c: det_f * det_f.abs(),
        });
    }
    constitutive::response(law, &right_cauchy_green(f), wrinkling)
}

/// σ = F S Fᵀ (Voigt in and out).
pub fn push_forward(f: &[[f64; 2]; 2], s: &Voigt) -> Voigt {
    let sm = [[s[0], s[2]], [s[2], s[1]]];
    let mut out = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            for k in 0..2 {
                for l in 0..2 {
                    out[i][j] += f[i][k] * sm[k][l] * f[j][l];
                }
            }
        }
    }
    [out[0][0], out[1][1], out[0][1]]
}

/// Rows 2a+i: ∂e/∂u_ai (three Voigt components) at a point.
fn strain_variation(f: &[[f64; 2]; 2], gradients: &[[f64; 2]; NODES]) -> [Voigt; ELEMENT_DOFS] {
    let mut b = [[0.0; 3]; ELEMENT_DOFS];
    for (a, g) in gradients.iter().enumerate() {
        for i in 0..2 {
            b[2 * a + i] = [
                f[i][0] * g[0],
                f[i][1] * g[1],
                f[i][0] * g[1] + f[i][1] * g[0],
            ];
        }
    }
    b
}

/// K += (Bᵀ D B + geometric) · weight.
fn add_point_tangent(
    k: &mut ElementMatrix,
    b: &[Voigt; ELEMENT_DOFS],
    d: &[[f64; 3]; 3],
    s: &Voigt,
    gradients: &[[f64; 2]; NODES],
    weight: f64,
) {
    let db: Vec<Voigt> = b
        .iter()
        .map(|row| std::array::from_fn(|p| (0..3).map(|q| d[p][q] * row[q]).sum()))
        .collect();
    for r in 0..ELEMENT_DOFS {
        for c in 0..ELEMENT_DOFS {
            k[r][c] += weight * (0..3).map(|p| b[r][p] * db[c][p]).sum::<f64>();
        }
    }
    for (a, ga) in gradients.iter().enumerate() {
        for (bn, gb) in gradients.iter().enumerate() {
            let geometric =
                ga[0] * (s[0] * gb[0] + s[2] * gb[1]) + ga[1] * (s[2] * gb[0] + s[1] * gb[1]);
            for i in 0..2 {
                k[2 * a + i][2 * bn + i] += weight * geometric;
            }
        }
    }
}
