//! How much each measured state (a node of a kept frame) contributes to a field-route fit
//! (issue 25 deliverable 3: the states used, coloured by how much each contributes). Pure.
//!
//! Definition. Each virtual-work equation i is F_i(θ) = Σ_n c_in · s_n(θ) over its nodes n
//! (`virtual_work::Equations`: c = h0 (K1:W, K2:W), s_n the node's principal Cauchy stresses
//! under the law). Node n moves equation i, when parameter θ_k moves, by
//! J_ink = c_in · ∂s_n/∂θ_k (N per unit of θ_k; J_ik = Σ_n J_ink is the fit's Jacobian).
//! The node's sensitivity to θ_k is S_nk = Σ_i |J_ink| over the virtual fields of its frame,
//! its share of that parameter is S_nk / Σ_m S_mk, and its contribution is the mean of its
//! shares over the K parameters:
//!
//!   contribution_n = (1/K) Σ_k S_nk / Σ_m S_mk,
//!
//! so that every parameter's shares sum to 1 over the states of the fit, and the
//! contributions too.
//!
//! Why this one. A user reads it as "this state carries x of the fit's sensitivity": a node
//! outside every virtual field's support, or where ∇u* = 0, moves no equation and contributes
//! exactly 0; a node at rest (every law's stress is 0 there) contributes 0. Dividing each
//! parameter by its own total makes parameters of different units (C10 in MPa, Gent's Jm a
//! number) commensurate, and gives each the same weight 1/K: a stiff, well-determined
//! parameter does not drown the others. The alternatives weigh parameters unevenly or not at
//! all: scaling |J_ink| by σ_k (the N a node moves under a 1σ change of θ_k) is 0/0 on
//! noise-free fields (σ = 0) and infinite when the normal matrix is singular, and scaling by
//! √(JᵀJ)_kk (the fit's column scaling) leaves a parameter whose sensitivity is spread over
//! many equations with a larger total than one concentrated in few. Absolute values, because a
//! node that pushes one equation up and another down still informs both. The per-parameter
//! shares are kept ([`StateContribution::shares`]): a state may inform one parameter and not
//! another.
//!
//! ∂s_n/∂θ_k is a central difference of the law's principal stresses at the node's stretches,
//! with the step of the fit's own Jacobian (`vfm::difference_step`); exact for a model linear
//! in its parameters up to rounding.

use crate::field_route::{FieldFits, FieldRoute};
use crate::field_stress::{principal_stretches, NodeStressError};
use crate::models::Model;
use crate::section_cut::FieldGrid;
use crate::virtual_work::Equations;
use std::collections::HashMap;

/// One frame of a fit: its measured field and the equations of its virtual fields, compiled
/// from this frame alone (as `FieldRoute` keeps them).
#[derive(Clone, Copy, Debug)]
pub struct FrameStates<'a> {
    pub frame_id: u64,
    pub grid: &'a FieldGrid,
    pub equations: &'a Equations,
}

impl<'a> FrameStates<'a> {
    /// The route's kept frames.
    pub fn of_route(route: &'a FieldRoute) -> Vec<Self> {
        route
            .frames()
            .iter()
            .map(|f| FrameStates {
                frame_id: f.frame_id,
                grid: &f.grid,
                equations: &f.equations,
            })
            .collect()
    }
}

/// One state: a node of a frame, its principal stretches and its contribution.
#[derive(Clone, Debug, PartialEq)]
pub struct StateContribution {
    pub frame_id: u64,
    /// The node (col, row) of its grid.
    pub at: (usize, usize),
    /// Its reference position, mm.
    pub position_mm: [f64; 2],
    /// In-plane principal stretches, λ1 ≥ λ2.
    pub stretches: [f64; 2],
    /// Its value was interpolated across a hole (a section cut's filled node), not measured.
    pub filled: bool,
    /// Its share of the fit's sensitivity, averaged over the parameters (all states sum to 1).
    pub contribution: f64,
    /// Its share of each parameter's sensitivity (each parameter's sum to 1 over the states).
    pub shares: Vec<f64>,
}

/// The states of a fit with their contributions.
#[derive(Clone, Debug, PartialEq)]
pub struct StateContributions {
    /// The model fitted and its parameters' names (the order of [`StateContribution::shares`]).
    pub model: String,
    pub parameters: Vec<String>,
    /// Every measured node of every frame (row-major per frame, frames in the order given),
    /// then each frame's filled nodes.
    pub states: Vec<StateContribution>,
}

/// Why contributions cannot be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ContributionError {
    #[error("{model} takes {expected} parameters, {got} given")]
    Parameters {
        model: String,
        expected: usize,
        got: usize,
    },
    #[error(
        "frame {frame_id}: its equations hold nodes of several frames (compile each frame alone)"
    )]
    SeveralFrames { frame_id: u64 },
    #[error("frame {frame_id}: the law at the fitted parameters: {reason}")]
    Stress {
        frame_id: u64,
        reason: NodeStressError,
    },
    #[error(
        "no state moves the equations when {parameter} moves: its shares are undefined \
         (no equations, or a parameter the fit does not use)"
    )]
    Insensitive { parameter: String },
}

/// A filled node of a frame: its node, stretches and summed sensitivities S_nk.
type FilledNode = ((usize, usize), [f64; 2], Vec<f64>);

/// ∂s/∂θ_k of the principal Cauchy stresses at stretches (λ1, λ2), k = 0..K, MPa per unit.
fn stress_derivatives(
    model: &Model,
    p: &[f64],
    [l1, l2]: [f64; 2],
) -> Result<Vec<[f64; 2]>, NodeStressError> {
    let outside = NodeStressError::OutsideDomain {
        stretches: [l1, l2, 1.0 / (l1 * l2)],
    };
    let mut trial = p.to_vec();
    (0..p.len())
        .map(|k| {
            let h = crate::vfm::difference_step(p[k]);
            trial[k] = p[k] + h;
            let plus = model.in_plane_cauchy_stress_mpa(&trial, l1, l2);
            trial[k] = p[k] - h;
            let minus = model.in_plane_cauchy_stress_mpa(&trial, l1, l2);
            trial[k] = p[k];
            let (plus, minus) = plus.zip(minus).ok_or(outside)?;
            Ok([
                (plus[0] - minus[0]) / (2.0 * h),
                (plus[1] - minus[1]) / (2.0 * h),
            ])
        })
        .collect()
}

/// The contributions of every state of `frames` to the fit of `model` at `params`.
pub fn state_contributions(
    model: &Model,
    params: &[f64],
    frames: &[FrameStates],
) -> Result<StateContributions, ContributionError> {
    let parameters = model.param_names();
    if parameters.len() != params.len() {
        return Err(ContributionError::Parameters {
            model: model.name(),
            expected: parameters.len(),
            got: params.len(),
        });
    }
    let k_count = params.len();
    // Per frame, per distinct node: S_nk.
    let mut sensitivities: Vec<Vec<Vec<f64>>> = Vec::with_capacity(frames.len());
    let mut totals = vec![0.0; k_count];
    for frame in frames {
        let origins = frame.equations.origins();
        if origins.windows(2).any(|w| w[0].frame != w[1].frame) {
            return Err(ContributionError::SeveralFrames {
                frame_id: frame.frame_id,
            });
        }
        let derivatives = frame
            .equations
            .stretches()
            .iter()
            .map(|&l| stress_derivatives(model, params, l))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|reason| ContributionError::Stress {
                frame_id: frame.frame_id,
                reason,
            })?;
        let mut s = vec![vec![0.0; k_count]; origins.len()];
        for row in frame.equations.rows() {
            for &(node, c) in row {
                let node = node as usize;
                for (k, d) in derivatives[node].iter().enumerate() {
                    let moved = (c[0] * d[0] + c[1] * d[1]).abs();
                    s[node][k] += moved;
                    totals[k] += moved;
                }
            }
        }
        sensitivities.push(s);
    }
    if let Some(k) = totals.iter().position(|t| !(t.is_finite() && *t > 0.0)) {
        return Err(ContributionError::Insensitive {
            parameter: parameters[k].clone(),
        });
    }
    let shares_of = |s: &[f64]| -> Vec<f64> { s.iter().zip(&totals).map(|(s, t)| s / t).collect() };
    let mut states = Vec::new();
    for (frame, s) in frames.iter().zip(&sensitivities) {
        let grid = frame.grid;
        let position = |(col, row): (usize, usize)| {
            [
                grid.x0_mm + col as f64 * grid.step_mm,
                grid.y0_mm + row as f64 * grid.step_mm,
            ]
        };
        // The measured nodes the equations weigh, and the filled ones (by node, summed).
        let mut measured: HashMap<(usize, usize), usize> = HashMap::new();
        let mut filled: Vec<FilledNode> = vec![];
        for (d, origin) in frame.equations.origins().iter().enumerate() {
            if !origin.filled {
                measured.insert(origin.at, d);
            } else if let Some(f) = filled.iter_mut().find(|f| f.0 == origin.at) {
                f.2.iter_mut().zip(&s[d]).for_each(|(a, b)| *a += b);
            } else {
                let stretches = frame.equations.stretches()[d];
                filled.push((origin.at, stretches, s[d].clone()));
            }
        }
        for (index, gradient) in grid.gradients.iter().enumerate() {
            let at = (index % grid.cols, index / grid.cols);
            let Some(stretches) = gradient.as_ref().and_then(principal_stretches) else {
                continue;
            };
            let shares = measured
                .get(&at)
                .map_or_else(|| vec![0.0; k_count], |&d| shares_of(&s[d]));
            states.push(state(
                frame.frame_id,
                at,
                position(at),
                stretches,
                false,
                shares,
            ));
        }
        for (at, stretches, s) in filled {
            let shares = shares_of(&s);
            states.push(state(
                frame.frame_id,
                at,
                position(at),
                stretches,
                true,
                shares,
            ));
        }
    }
    Ok(StateContributions {
        model: model.name(),
        parameters,
        states,
    })
}

fn state(
    frame_id: u64,
    at: (usize, usize),
    position_mm: [f64; 2],
    stretches: [f64; 2],
    filled: bool,
    shares: Vec<f64>,
) -> StateContribution {
    StateContribution {
        frame_id,
        at,
        position_mm,
        stretches,
        filled,
        contribution: shares.iter().sum::<f64>() / shares.len().max(1) as f64,
        shares,
    }
}

/// The contributions of the route's kept frames to its best fit (the first ranked, as the
/// force balance's); None when no fit is ranked.
pub fn of_best_fit(
    route: &FieldRoute,
    fits: &FieldFits,
) -> Option<Result<StateContributions, ContributionError>> {
    let best = fits.fits.iter().find(|fit| fit.ranked())?;
    let frames = FrameStates::of_route(route);
    Some(state_contributions(&best.model, &best.fit.params, &frames))
}

/// `states.csv`'s header before the per-parameter shares: units by the names' suffixes as in
/// the run's other CSVs (`_mm`; none: dimensionless).
pub const STATES_CSV_HEADER: &str =
    "frame_id,col,row,x_mm,y_mm,lambda1,lambda2,filled,contribution";

/// `states.csv`: one row per state, its node, reference position (mm), principal stretches,
/// whether it was filled, its contribution and its share of each parameter (`share_<name>`).
pub fn states_csv(contributions: &StateContributions) -> String {
    let mut out = String::from(STATES_CSV_HEADER);
    for name in &contributions.parameters {
        out.push_str(",share_");
        out.push_str(name);
    }
    out.push('\n');
    for s in &contributions.states {
        out.push_str(&format!(
            "{},{},{},{},{},{},{},{},{:e}",
            s.frame_id,
            s.at.0,
            s.at.1,
            s.position_mm[0],
            s.position_mm[1],
            s.stretches[0],
            s.stretches[1],
            u8::from(s.filled),
            s.contribution
        ));
        for share in &s.shares {
            out.push_str(&format!(",{share:e}"));
        }
        out.push('\n');
    }
    out
}
