//! The virtual fields method over section cuts and tapered ramps (`tapered_ramp`, which reach
//! the centre of a cruciform): every virtual field of every frame is one equation,
//! the force its band carries under the law (`section_cut`) against the arm's measured grip
//! force. All frames of a test are fitted together: by linear least squares when the model's
//! stress is linear in all its parameters (a cut's force is then the same combination of the
//! forces of the unit parameter vectors), by Levenberg-Marquardt otherwise. The condition
//! number of the equations' Jacobian says whether the states the field reached separate the
//! parameters; beyond [`MAX_CONDITION`] the fit is refused rather than reported.

use crate::field_stress::NodeStressError;
use crate::lsq::{inverse_normal_matrix, levenberg_marquardt, linear_least_squares, LsqError};
use crate::models::Model;
use crate::section_cut::{cut_force, cut_weights, CutError, FieldGrid, SectionCut};
use crate::tapered_ramp::{RampError, RampQuadrature};
use crate::virtual_work::{EquationInput, Equations, NodeFailure, WeightedNode};
use nalgebra::{DMatrix, DVector};

/// Condition number of the scaled Jacobian beyond which the parameters are not told apart:
/// the gauge route's limit ([`crate::identifiability::MAX_CONDITION_NUMBER`]), one definition.
pub const MAX_CONDITION: f64 = crate::identifiability::MAX_CONDITION_NUMBER;

/// A virtual field whose work balances one arm's grip force.
#[derive(Clone, Copy, Debug)]
pub enum VirtualField<'a> {
    /// The paper's section cut across the arm.
    Cut(SectionCut),
    /// A ramp tapered across, which may reach the centre, by its quadrature over the frame.
    Ramp(&'a RampQuadrature),
}

impl VirtualField<'_> {
    /// The force the field's internal virtual work balances, evaluated directly.
    pub fn force_n(
        &self,
        grid: &FieldGrid,
        model: &Model,
        p: &[f64],
        thickness_mm: f64,
    ) -> Result<f64, VfmError> {
        Ok(match self {
            VirtualField::Cut(cut) => cut_force(grid, cut, model, p, thickness_mm)?.force_n,
            VirtualField::Ramp(quadrature) => quadrature.force_n(grid, model, p, thickness_mm)?,
        })
    }

    /// The nodes the field weighs over `grid`, for compiled equations.
    pub fn weighted_nodes(&self, grid: &FieldGrid) -> Result<Vec<WeightedNode>, VfmError> {
        Ok(match self {
            VirtualField::Cut(cut) => cut_weights(grid, cut)?.0,
            VirtualField::Ramp(quadrature) => quadrature.weighted_nodes(grid)?,
        })
    }
}

/// One equation: a frame's field, a virtual field, and the measured force of the arm it
/// balances.
#[derive(Clone, Copy, Debug)]
pub struct CutObservation<'a> {
    pub grid: &'a FieldGrid,
    pub cut: VirtualField<'a>,
    /// Reference thickness of the sheet, mm.
    pub thickness_mm: f64,
    /// The arm's grip force at the frame, N.
    pub force_n: f64,
}

/// A law identified from the cuts.
#[derive(Clone, Debug, PartialEq)]
pub struct VfmFit {
    pub params: Vec<f64>,
    /// Standard deviations of the parameters (from the residual variance).
    pub sigma: Vec<f64>,
    /// Root mean square of measured minus computed force, N.
    pub rms_n: f64,
    pub equations: usize,
    /// Condition number of the column-scaled Jacobian at the solution.
    pub condition: f64,
}

/// Why the cuts identify nothing.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum VfmError {
    #[error("{equations} cut equations for {params} parameters: need at least {}", .params + 1)]
    TooFewEquations { equations: usize, params: usize },
    #[error(transparent)]
    Cut(#[from] CutError),
    #[error(transparent)]
    Ramp(#[from] RampError),
    #[error(transparent)]
    Lsq(#[from] LsqError),
    #[error(
        "the states the field reached do not separate the {params} parameters of {model}: \
         condition number {condition:.3e} > {MAX_CONDITION:e}"
    )]
    NotIdentifiable {
        model: String,
        params: usize,
        condition: f64,
    },
    #[error("the law is not defined at the starting parameters {start:?}")]
    UndefinedStart { start: Vec<f64> },
    #[error("node (col {}, row {}): {}", .0.at.0, .0.at.1, .0.reason)]
    Node(NodeFailure),
    #[error("the law at the fitted parameters: {0}")]
    Stress(#[from] NodeStressError),
}

/// The observations' equations, compiled once for every trial law of a fit (nodes of one
/// field grid that several virtual fields weigh are evaluated once).
pub fn compile(obs: &[CutObservation]) -> Result<Equations, VfmError> {
    let (equations, failures) = compile_each(obs);
    match failures.into_iter().flatten().next() {
        Some(failure) => Err(failure),
        None => Ok(equations),
    }
}

/// [`compile`], leaving out each observation that has no equation (a hole in its virtual
/// field, a node without kinematics), its error given in its place (`None`: compiled). Each
/// node's kinematics are computed once.
pub fn compile_each(obs: &[CutObservation]) -> (Equations, Vec<Option<VfmError>>) {
    let mut frames: Vec<*const FieldGrid> = vec![];
    let nodes: Vec<Result<Vec<WeightedNode>, VfmError>> =
        obs.iter().map(|o| o.cut.weighted_nodes(o.grid)).collect();
    let inputs: Vec<EquationInput> = obs
        .iter()
        .zip(&nodes)
        .filter_map(|(o, nodes)| Some((o, nodes.as_ref().ok()?)))
        .map(|(o, nodes)| {
            let key: *const FieldGrid = o.grid;
            let frame = frames.iter().position(|&g| g == key).unwrap_or_else(|| {
                frames.push(key);
                frames.len() - 1
            });
            EquationInput {
                frame,
                nodes,
                thickness_mm: o.thickness_mm,
                measured_n: o.force_n,
            }
        })
        .collect();
    let (equations, mut compiled) = Equations::compile_each(&inputs);
    compiled.reverse();
    let failures = nodes
        .into_iter()
        .map(|n| match n {
            Err(e) => Some(e),
            Ok(_) => compiled.pop().flatten().map(VfmError::Node),
        })
        .collect();
    (equations, failures)
}

/// Condition number of `j` with its columns scaled to unit norm.
fn condition(j: &DMatrix<f64>) -> f64 {
    let mut scaled = j.clone();
    for mut column in scaled.column_iter_mut() {
        let norm = column.norm();
        if norm > 0.0 {
            column /= norm;
        }
    }
    let singular = scaled.singular_values();
    let (max, min) = singular
        .iter()
        .fold((0.0_f64, f64::INFINITY), |(a, b), &s| (a.max(s), b.min(s)));
    if min > 0.0 {
        max / min
    } else {
        f64::INFINITY
    }
}

/// The central-difference step of a parameter of value `p_k`: relative, floored at 1e-9 (the
/// fit's Jacobian and `state_contributions`'s node sensitivities alike).
pub(crate) fn difference_step(p_k: f64) -> f64 {
    1e-6 * p_k.abs().max(1e-3)
}

/// Jacobian of the computed forces by central differences (relative step).
fn jacobian(model: &Model, equations: &Equations, p: &[f64]) -> Result<DMatrix<f64>, VfmError> {
    let mut j = DMatrix::zeros(equations.len(), p.len());
    for k in 0..p.len() {
        let h = difference_step(p[k]);
        let mut plus = p.to_vec();
        let mut minus = p.to_vec();
        plus[k] += h;
        minus[k] -= h;
        let (fp, fm) = (
            equations.forces_n(model, &plus)?,
            equations.forces_n(model, &minus)?,
        );
        for i in 0..equations.len() {
            j[(i, k)] = (fp[i] - fm[i]) / (2.0 * h);
        }
    }
    Ok(j)
}

/// Fits `model`'s parameters to the cut equations, starting from `start` (used only by the
/// nonlinear fit).
pub fn fit(model: &Model, obs: &[CutObservation], start: &[f64]) -> Result<VfmFit, VfmError> {
    if obs.len() <= start.len() {
        return Err(VfmError::TooFewEquations {
            equations: obs.len(),
            params: start.len(),
        });
    }
    fit_equations(model, &compile(obs)?, start)
}

/// Fits `model`'s parameters to compiled equations (see [`fit`]).
pub fn fit_equations(
    model: &Model,
    equations: &Equations,
    start: &[f64],
) -> Result<VfmFit, VfmError> {
    let n = start.len();
    let m = equations.len();
    if m <= n {
        return Err(VfmError::TooFewEquations {
            equations: m,
            params: n,
        });
    }
    let measured = DVector::from_column_slice(equations.measured_n());
    let params = if model.linear_params().iter().all(|&l| l) {
        let mut a = DMatrix::zeros(m, n);
        for k in 0..n {
            let unit: Vec<f64> = (0..n).map(|i| f64::from(u8::from(i == k))).collect();
            let column = equations.forces_n(model, &unit)?;
            a.set_column(k, &DVector::from_vec(column));
        }
        // States that cannot separate the parameters: refused with the design's condition
        // number (infinite when a column is a combination of the others), not solved.
        let design = condition(&a);
        if design.is_nan() || design > MAX_CONDITION {
            return Err(VfmError::NotIdentifiable {
                model: model.name(),
                params: n,
                condition: design,
            });
        }
        linear_least_squares(&a, &measured)?
            .iter()
            .copied()
            .collect()
    } else {
        if equations.forces_n(model, start).is_err() {
            return Err(VfmError::UndefinedStart {
                start: start.to_vec(),
            });
        }
        let residuals = |p: &[f64]| {
            let forces = equations.forces_n(model, p).ok()?;
            Some(DVector::from_iterator(
                m,
                forces
                    .iter()
                    .zip(equations.measured_n())
                    .map(|(f, o)| f - o),
            ))
        };
        levenberg_marquardt(&residuals, start, m)?.params
    };
    let j = jacobian(model, equations, &params)?;
    let condition = condition(&j);
    if condition > MAX_CONDITION {
        return Err(VfmError::NotIdentifiable {
            model: model.name(),
            params: n,
            condition,
        });
    }
    let forces = equations.forces_n(model, &params)?;
    let rss: f64 = forces
        .iter()
        .zip(equations.measured_n())
        .map(|(f, o)| (f - o).powi(2))
        .sum();
    let variance = rss / (m - n) as f64;
    let sigma = match inverse_normal_matrix(&j) {
        Some(cov) => (0..n).map(|k| (cov[(k, k)] * variance).sqrt()).collect(),
        None => vec![f64::INFINITY; n],
    };
    Ok(VfmFit {
        params,
        sigma,
        rms_n: (rss / m as f64).sqrt(),
        equations: m,
        condition,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::LoadCase;
    use crate::section_cut::ArmAxis;

    /// A homogeneous arm field (21 x 21 nodes, 0.5 mm) of a canonical state along x.
    fn arm(case: LoadCase, stretch: f64) -> FieldGrid {
        let (l1, l2) = case.in_plane_stretches(stretch);
        FieldGrid {
            cols: 21,
            rows: 21,
            x0_mm: 0.0,
            y0_mm: 0.0,
            step_mm: 0.5,
            gradients: vec![Some([[l1, 0.0], [0.0, l2]]); 21 * 21],
        }
    }

    const CUT: SectionCut = SectionCut {
        axis: ArmAxis::X,
        from_mm: 2.25,
        to_mm: 7.75,
        across_from_mm: -0.25,
        across_to_mm: 10.25,
    };

    /// Frames of a test whose field reaches uniaxial and equibiaxial states (as a cruciform's
    /// arms and centre do).
    fn frames(cases: &[LoadCase]) -> Vec<FieldGrid> {
        cases
            .iter()
            .flat_map(|&case| [1.2, 1.5, 1.9, 2.4].map(|s| arm(case, s)))
            .collect()
    }

    fn observations<'a>(
        model: &Model,
        truth: &[f64],
        grids: &'a [FieldGrid],
    ) -> Vec<CutObservation<'a>> {
        grids
            .iter()
            .map(|grid| CutObservation {
                grid,
                cut: VirtualField::Cut(CUT),
                thickness_mm: 2.0,
                force_n: cut_force(grid, &CUT, model, truth, 2.0).unwrap().force_n,
            })
            .collect()
    }

    #[test]
    fn noise_free_cuts_give_back_a_linear_and_a_nonlinear_law() {
        let both = [LoadCase::Uniaxial, LoadCase::Equibiaxial];
        for (model, truth, start) in [
            (Model::Mooney, vec![0.3, 0.05], vec![0.0, 0.0]),
            (Model::Yeoh, vec![0.3, -0.01, 0.002], vec![0.0; 3]),
            (Model::Gent, vec![0.4, 40.0], vec![0.3, 60.0]),
        ] {
            let grids = frames(&both);
            let obs = observations(&model, &truth, &grids);
            let fit = fit(&model, &obs, &start).unwrap();
            for (got, want) in fit.params.iter().zip(&truth) {
                assert!((got - want).abs() <= 1e-6 * want.abs(), "{model}: {fit:?}");
            }
            assert!(fit.rms_n < 1e-6, "{fit:?}");
            assert!(fit.condition < MAX_CONDITION);
        }
    }

    #[test]
    fn states_that_cannot_separate_the_parameters_are_refused() {
        // Mooney-Rivlin from one stretch of one case: two parameters, one distinct state.
        let model = Model::Mooney;
        let truth = [0.3, 0.05];
        let grids: Vec<FieldGrid> = (0..6).map(|_| arm(LoadCase::Uniaxial, 1.5)).collect();
        let obs = observations(&model, &truth, &grids);
        let error = fit(&model, &obs, &[0.0, 0.0]).unwrap_err();
        assert!(
            matches!(error, VfmError::Lsq(LsqError::RankDeficient { .. }))
                || matches!(error, VfmError::NotIdentifiable { .. }),
            "{error}"
        );
        let too_few = fit(&model, &obs[..2], &[0.0, 0.0]).unwrap_err();
        assert!(too_few.to_string().contains("need at least 3"), "{too_few}");
    }
}
