//! The tangent stiffness of a converged equilibrium condensed on its grips' axial motions: what
//! a grip's force does, to first order, when the grips move a little and the sheet follows in
//! equilibrium. Each grip is a rigid motion of its nodes; its generalised coordinate q_g is
//! the translation along its own axis (its nodes' other motions held). With T the map from q
//! to the clamped DOFs,
//!
//!   K_c = Tᵀ (K_pp − K_pf K_ff⁻¹ K_fp) T   (N/mm),
//!
//! the Schur complement of the free-free block, from one sparse Cholesky factorisation of K_ff
//! at the equilibrium and one solve per grip. Each solve also gives the grip's displacement
//! mode (the whole sheet's displacement per mm of that grip), from which anything linear in
//! the displacement (a region's mean F, say) follows the grips between two solves.

use crate::assembly::Membrane;
use crate::boundary::Clamp;
use crate::error::SolveError;
use crate::law::SheetLaw;
use crate::solver::{factorise, Analysis, Equilibrium, FreeDofs};
use crate::specimens::Grip;
use faer::linalg::solvers::Solve;
use faer::sparse::Triplet;
use faer::Mat;

/// The tangent of an equilibrium condensed on the grips' axial translations.
#[derive(Clone, Debug, PartialEq)]
pub struct Condensed {
    /// stiffness_n_per_mm[a][b]: change of grip a's axial force (N, positive when it pulls) per
    /// mm of grip b's outward axial translation, the sheet in equilibrium. Symmetric.
    pub stiffness_n_per_mm: Vec<Vec<f64>>,
    /// modes[b]: the nodal displacement (mm, two per node) per mm of grip b's translation.
    pub modes: Vec<Vec<f64>>,
}

/// Condenses the tangent at `equilibrium` (a converged solve of `clamps`) on the axial
/// translations of `grips` (whose nodes `clamps` hold). The tangent must be positive definite
/// there: an unstable state is a [`SolveError::Unstable`] at load factor 1. `analysis`: the
/// symbolic factorisation of the solves of the same clamped nodes, reused or made and kept.
pub fn condense<L: SheetLaw + ?Sized>(
    membrane: &Membrane<'_, L>,
    clamps: &[Clamp],
    equilibrium: &Equilibrium,
    grips: &[Grip],
    analysis: &mut Analysis,
) -> Result<Condensed, SolveError> {
    let dofs = FreeDofs::of(membrane, clamps)?;
    let u = &equilibrium.displacement_mm;
    if u.len() != dofs.free.len() {
        return Err(SolveError::StartLength {
            values: u.len(),
            dofs: dofs.free.len(),
        });
    }
    let at_end = |failure: crate::solver::Failure| failure.into_error(1.0, 1.0);
    let evaluation = membrane
        .evaluate(u, true)
        .map_err(|f| at_end(crate::solver::Failure::Point(f)))?;
    let elements = &membrane.mesh.elements;
    let element_dofs = |e: usize| -> [usize; 12] {
        let element = &elements[e];
        std::array::from_fn(|r| 2 * element[r / 2] + r % 2)
    };
    let mut triplets = Vec::with_capacity(elements.len() * 78);
    for (e, k) in evaluation.element_tangents.iter().enumerate() {
        let dofs_e = element_dofs(e);
        for (r, &gr) in dofs_e.iter().enumerate() {
            let Some(fr) = dofs.free[gr] else { continue };
            for (c, &gc) in dofs_e.iter().enumerate() {
                if let Some(fc) = dofs.free[gc] {
                    if fr >= fc {
                        triplets.push(Triplet::new(fr, fc, k[r][c]));
                    }
                }
            }
        }
    }
    let mut symbolic = analysis.take_for(&dofs.free);
    let llt = factorise(dofs.count, &triplets, &mut symbolic);
    analysis.keep(&dofs.free, symbolic);
    let llt = llt.map_err(at_end)?;
    // K d over every DOF, element by element.
    let product = |d: &[f64]| -> Vec<f64> {
        let mut y = vec![0.0; d.len()];
        for (e, k) in evaluation.element_tangents.iter().enumerate() {
            let dofs_e = element_dofs(e);
            for (r, &gr) in dofs_e.iter().enumerate() {
                y[gr] += dofs_e
                    .iter()
                    .enumerate()
                    .map(|(c, &gc)| k[r][c] * d[gc])
                    .sum::<f64>();
            }
        }
        y
    };
    let axial = |grip: &Grip, y: &[f64]| -> f64 {
        grip.nodes
            .iter()
            .map(|&n| grip.axis[0] * y[2 * n] + grip.axis[1] * y[2 * n + 1])
            .sum()
    };
    let mut modes = Vec::with_capacity(grips.len());
    let mut stiffness_n_per_mm = vec![vec![0.0; grips.len()]; grips.len()];
    for (b, grip) in grips.iter().enumerate() {
        // The grip's unit translation on the clamped DOFs, the free ones at rest.
        let mut d = vec![0.0; u.len()];
        for &n in &grip.nodes {
            d[2 * n] = grip.axis[0];
            d[2 * n + 1] = grip.axis[1];
        }
        // The free DOFs' response: K_ff d_f = −K_fp d_p.
        let coupling = product(&d);
        let mut x = Mat::from_fn(dofs.count, 1, |_, _| 0.0);
        for (dof, slot) in dofs.free.iter().enumerate() {
            if let Some(i) = slot {
                x[(*i, 0)] = -coupling[dof];
            }
        }
        llt.solve_in_place(x.as_mut());
        for (dof, slot) in dofs.free.iter().enumerate() {
            if let Some(i) = slot {
                d[dof] = x[(*i, 0)];
            }
        }
        let y = product(&d);
        for (a, other) in grips.iter().enumerate() {
            stiffness_n_per_mm[a][b] = axial(other, &y);
        }
        modes.push(d);
    }
    Ok(Condensed {
        stiffness_n_per_mm,
        modes,
    })
}
