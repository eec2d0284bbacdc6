//! Nodal values for output (`dicstream specimen`'s VTK and CSV): the in-plane F at each node of
//! each element (the element's own quadratic interpolation at the node's natural coordinates),
//! averaged over the elements that share the node, then the law's response to that F:
//! stretches, Cauchy stress and the tension-field state. The Gauss points stay what the solver
//! uses; these values are for people and the camera's truth.

use crate::assembly::{
    deformation_gradient, push_forward, response_to, right_cauchy_green, Membrane,
};
use crate::constitutive::{principal_values, MembraneState, PointFailure, Voigt};
use crate::law::SheetLaw;
use crate::t6::{gradients_at, NODE_COORDINATES};

/// The state of one node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodalField {
    pub reference_mm: [f64; 2],
    pub displacement_mm: [f64; 2],
    /// In-plane deformation gradient F[i][J], averaged over the elements sharing the node.
    pub deformation_gradient: [[f64; 2]; 2],
    /// Principal in-plane stretches λ1 ≥ λ2, and the thickness stretch λ3 = 1 / (λ1 λ2).
    pub stretches: [f64; 3],
    /// In-plane Cauchy stress (MPa, Voigt [σxx, σyy, σxy]) of the relaxed law.
    pub cauchy_stress_mpa: Voigt,
    pub state: MembraneState,
}

/// A node whose averaged F has no response: inverted, or outside the law's domain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeFailure {
    pub node: usize,
    pub failure: PointFailure,
}

impl<L: SheetLaw + ?Sized> Membrane<'_, L> {
    /// Every node's kinematics and stress at displacement `u` (mm, two per node); the first
    /// node whose F is inverted or outside the law's domain is an error naming it.
    pub fn nodal_fields(&self, u: &[f64]) -> Result<Vec<NodalField>, NodeFailure> {
        let mesh = self.mesh;
        let nodes = mesh.nodes_mm.len();
        let mut sum = vec![[[0.0; 2]; 2]; nodes];
        let mut count = vec![0u32; nodes];
        for (e, element) in mesh.elements.iter().enumerate() {
            let nodes_mm = mesh.element_nodes_mm(e);
            for (&node, &(xi, eta)) in element.iter().zip(NODE_COORDINATES.iter()) {
                let gradients = gradients_at(&nodes_mm, xi, eta).map_err(|det| NodeFailure {
                    node,
                    failure: PointFailure::Inverted { det_c: det },
                })?;
                let f = deformation_gradient(element, &gradients.0, u);
                for i in 0..2 {
                    for j in 0..2 {
                        sum[node][i][j] += f[i][j];
                    }
                }
                count[node] += 1;
            }
        }
        (0..nodes)
            .map(|n| {
                let f = sum[n].map(|row| row.map(|v| v / f64::from(count[n].max(1))));
                self.nodal_response(f, [u[2 * n], u[2 * n + 1]], mesh.nodes_mm[n])
                    .map_err(|failure| NodeFailure { node: n, failure })
            })
            .collect()
    }

    fn nodal_response(
        &self,
        f: [[f64; 2]; 2],
        displacement_mm: [f64; 2],
        reference_mm: [f64; 2],
    ) -> Result<NodalField, PointFailure> {
        let response = response_to(self.law, &self.wrinkling, &f)?;
        let det_f = f[0][0] * f[1][1] - f[0][1] * f[1][0];
        let (c_major, c_minor) = principal_values(&right_cauchy_green(&f));
        let (l1, l2) = (c_major.sqrt(), c_minor.max(0.0).sqrt());
        Ok(NodalField {
            reference_mm,
            displacement_mm,
            deformation_gradient: f,
            stretches: [l1, l2, 1.0 / det_f],
            cauchy_stress_mpa: push_forward(&f, &response.stress_pk2_mpa),
            state: response.state,
        })
    }
}
