//! The internal virtual work of a virtual field over a measured field, in the one form both
//! the direct evaluation and a fit's compiled equations use: per node, the nominal stress P
//! weighed by the integral of ∇u* over the node's share of the reference area
//! (`WeightedNode::weight_mm2`), work = h0 Σ P : W.
//!
//! A fit tries many laws on the same frames. Its equations are compiled once
//! ([`Equations::compile`]): P = s1 K1 + s2 K2 (`field_stress::NodeKinematics`), so each
//! equation is h0 Σ (s1 K1:W + s2 K2:W) over its nodes, and a trial law only evaluates its
//! principal Cauchy stresses s1, s2 once per distinct node (a node that several virtual fields
//! of its frame weigh is evaluated once), then a sparse sum. No eigen-decomposition, no
//! quadrature, no allocation per node per trial.

use crate::field_stress::{node_kinematics, node_stress, Mat2, NodeStressError};
use crate::models::Model;
use std::collections::HashMap;

/// One node's share of a virtual field's work.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightedNode {
    /// The node (col, row) of its grid.
    pub at: (usize, usize),
    /// Its value was interpolated across a hole (not the node's own measurement).
    pub filled: bool,
    /// The in-plane deformation gradient used there.
    pub gradient: Mat2,
    /// ∫ ∇u* dA0 over the node's share, mm²: the work is P : W.
    pub weight_mm2: Mat2,
}

impl WeightedNode {
    /// A node's own measurement (not filled).
    pub fn measured(at: (usize, usize), gradient: Mat2, weight_mm2: Mat2) -> Self {
        Self {
            at,
            filled: false,
            gradient,
            weight_mm2,
        }
    }
}

/// A node whose stress is not defined, and why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeFailure {
    pub at: (usize, usize),
    pub reason: NodeStressError,
}

fn contract(a: &Mat2, b: &Mat2) -> f64 {
    a[0][0] * b[0][0] + a[0][1] * b[0][1] + a[1][0] * b[1][0] + a[1][1] * b[1][1]
}

/// h0 Σ P : W over `nodes` under `model` at `p`: the force (N) the virtual field balances.
pub fn work_n(
    nodes: &[WeightedNode],
    model: &Model,
    p: &[f64],
    thickness_mm: f64,
) -> Result<f64, NodeFailure> {
    let mut work = 0.0;
    for node in nodes {
        let stress = node_stress(model, p, &node.gradient).map_err(|reason| NodeFailure {
            at: node.at,
            reason,
        })?;
        work += contract(&stress.nominal_mpa, &node.weight_mm2);
    }
    Ok(thickness_mm * work)
}

/// A node of a frame: (frame, (col, row)).
type NodeKey = (usize, (usize, usize));

/// One equation before compilation: the weighted nodes of a virtual field over one frame, the
/// frame's identity (nodes of one frame that several fields weigh are evaluated once), the
/// sheet's thickness and the measured force.
#[derive(Clone, Copy, Debug)]
pub struct EquationInput<'a> {
    pub frame: usize,
    pub nodes: &'a [WeightedNode],
    pub thickness_mm: f64,
    pub measured_n: f64,
}

/// Where a distinct node of compiled equations comes from: its frame (the index the inputs
/// gave; [`Equations::append`] shifts the appended frames past the others), its grid node, and
/// whether its value was filled across a hole (then it is its equation's alone).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeOrigin {
    pub frame: usize,
    pub at: (usize, usize),
    pub filled: bool,
}

/// A set of virtual-work equations, compiled for many trial laws.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Equations {
    /// (λ1, λ2) of each distinct node.
    stretches: Vec<[f64; 2]>,
    /// Where each distinct node comes from.
    origins: Vec<NodeOrigin>,
    /// Frames the inputs named (one past the largest index).
    frames: usize,
    /// Equation i's terms are `terms[row_start[i]..row_start[i + 1]]`.
    row_start: Vec<usize>,
    /// (distinct node, h0 K1:W, h0 K2:W), mm³.
    terms: Vec<(u32, [f64; 2])>,
    measured_n: Vec<f64>,
}

impl Equations {
    /// Compiles `inputs`; a node whose kinematics are not defined (not finite, inverted) is an
    /// error naming it.
    pub fn compile(inputs: &[EquationInput]) -> Result<Self, NodeFailure> {
        let (equations, failures) = Self::compile_each(inputs);
        match failures.into_iter().flatten().next() {
            Some(failure) => Err(failure),
            None => Ok(equations),
        }
    }

    /// Compiles every input whose nodes all have kinematics, each node's once (a node that
    /// several inputs of its frame weigh, valid or not, is computed once); an input holding a
    /// node that has none is left out, its failure given in its place (`None`: compiled).
    pub fn compile_each(inputs: &[EquationInput]) -> (Self, Vec<Option<NodeFailure>>) {
        let mut out = Equations {
            row_start: vec![0],
            ..Self::default()
        };
        // (frame, node) → its kinematics ((λ1, λ2), K1, K2) or why it has none.
        type Kinematics = Result<([f64; 2], [Mat2; 2]), NodeFailure>;
        let kinematics_of = |node: &WeightedNode| -> Kinematics {
            let k = node_kinematics(&node.gradient).map_err(|reason| NodeFailure {
                at: node.at,
                reason,
            })?;
            let [l1, l2, _] = k.stretches;
            Ok(([l1, l2], k.nominal_per_cauchy))
        };
        let mut computed: HashMap<NodeKey, Kinematics> = HashMap::new();
        // (frame, node) → its distinct node, once an equation uses it.
        let mut index: HashMap<NodeKey, u32> = HashMap::new();
        let mut failures = Vec::with_capacity(inputs.len());
        let mut resolved: Vec<(Option<NodeKey>, [f64; 2], [Mat2; 2])> = vec![];
        for input in inputs {
            resolved.clear();
            let mut failure = None;
            for node in input.nodes {
                let key = (input.frame, node.at);
                // A filled value is not the node's own: computed for its equation alone.
                let k = if node.filled {
                    kinematics_of(node)
                } else {
                    *computed.entry(key).or_insert_with(|| kinematics_of(node))
                };
                match k {
                    Ok((stretches, k)) => {
                        resolved.push(((!node.filled).then_some(key), stretches, k))
                    }
                    Err(e) => {
                        failure = Some(e);
                        break;
                    }
                }
            }
            if failure.is_some() {
                failures.push(failure);
                continue;
            }
            for (node, &(key, stretches, k)) in input.nodes.iter().zip(&resolved) {
                let known = key.and_then(|key| index.get(&key).copied());
                let distinct = known.unwrap_or_else(|| {
                    out.stretches.push(stretches);
                    out.origins.push(NodeOrigin {
                        frame: input.frame,
                        at: node.at,
                        filled: node.filled,
                    });
                    let new = (out.stretches.len() - 1) as u32;
                    if let Some(key) = key {
                        index.insert(key, new);
                    }
                    new
                });
                let h = input.thickness_mm;
                out.terms.push((
                    distinct,
                    [
                        h * contract(&k[0], &node.weight_mm2),
                        h * contract(&k[1], &node.weight_mm2),
                    ],
                ));
            }
            out.row_start.push(out.terms.len());
            out.measured_n.push(input.measured_n);
            out.frames = out.frames.max(input.frame + 1);
            failures.push(None);
        }
        (out, failures)
    }

    /// Appends `other`'s equations (their nodes stay theirs).
    pub fn append(&mut self, other: &Equations) {
        if self.row_start.is_empty() {
            self.row_start.push(0);
        }
        let offset = self.stretches.len() as u32;
        self.stretches.extend_from_slice(&other.stretches);
        let frames = self.frames;
        self.origins
            .extend(other.origins.iter().map(|o| NodeOrigin {
                frame: o.frame + frames,
                ..*o
            }));
        self.frames += other.frames;
        let base = self.terms.len();
        self.terms
            .extend(other.terms.iter().map(|&(node, c)| (node + offset, c)));
        self.row_start
            .extend(other.row_start.iter().skip(1).map(|&end| base + end));
        self.measured_n.extend_from_slice(&other.measured_n);
    }

    pub fn len(&self) -> usize {
        self.measured_n.len()
    }

    pub fn is_empty(&self) -> bool {
        self.measured_n.is_empty()
    }

    /// Distinct nodes the equations weigh.
    pub fn nodes(&self) -> usize {
        self.stretches.len()
    }

    pub fn measured_n(&self) -> &[f64] {
        &self.measured_n
    }

    /// The (λ1, λ2) of every distinct node.
    pub fn stretches(&self) -> &[[f64; 2]] {
        &self.stretches
    }

    /// Where every distinct node comes from, in the order of [`Self::stretches`].
    pub fn origins(&self) -> &[NodeOrigin] {
        &self.origins
    }

    /// Each equation's terms: (distinct node, h0 K1:W, h0 K2:W), mm³, so that its force is
    /// Σ c1 s1 + c2 s2 over them with s1, s2 the node's principal Cauchy stresses, MPa.
    pub fn rows(&self) -> impl Iterator<Item = &[(u32, [f64; 2])]> + '_ {
        self.row_start
            .windows(2)
            .map(|range| &self.terms[range[0]..range[1]])
    }

    /// Each equation's force under `model` at `p`, N; an error where the law is not defined
    /// at a node's stretches.
    pub fn forces_n(&self, model: &Model, p: &[f64]) -> Result<Vec<f64>, NodeStressError> {
        let stresses = self
            .stretches
            .iter()
            .map(|&[l1, l2]| {
                model
                    .in_plane_cauchy_stress_mpa(p, l1, l2)
                    .ok_or(NodeStressError::OutsideDomain {
                        stretches: [l1, l2, 1.0 / (l1 * l2)],
                    })
            })
            .collect::<Result<Vec<[f64; 2]>, _>>()?;
        Ok(self
            .row_start
            .windows(2)
            .map(|range| {
                self.terms[range[0]..range[1]]
                    .iter()
                    .map(|&(node, c)| {
                        let s = stresses[node as usize];
                        c[0] * s[0] + c[1] * s[1]
                    })
                    .sum()
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn models() -> Vec<(Model, Vec<f64>)> {
        vec![
            (Model::Mooney, vec![0.3, 0.05]),
            (Model::Ogden(2), vec![0.6, 0.01, 1.5, -2.0]),
            (Model::Gent, vec![0.4, 40.0]),
        ]
    }

    fn node(col: usize, gradient: Mat2, weight_mm2: Mat2) -> WeightedNode {
        WeightedNode::measured((col, 0), gradient, weight_mm2)
    }

    /// The compiled equations give the direct evaluation's forces, for nodes shared between
    /// equations of one frame, the same node in two frames and a filled value.
    #[test]
    fn compiled_equations_give_the_direct_work() {
        let f = [[1.6, 0.2], [-0.15, 0.8]];
        let g = [[1.2, -0.05], [0.1, 1.3]];
        let a = [
            node(0, f, [[0.7, 0.2], [0.0, 0.0]]),
            node(1, g, [[0.3, -0.1], [0.05, 0.4]]),
        ];
        let b = [
            node(1, g, [[0.0, 0.0], [0.2, 0.9]]),
            WeightedNode {
                filled: true,
                ..node(1, f, [[0.1, 0.0], [0.0, 0.1]])
            },
        ];
        let inputs = [
            EquationInput {
                frame: 0,
                nodes: &a,
                thickness_mm: 2.0,
                measured_n: 1.0,
            },
            EquationInput {
                frame: 0,
                nodes: &b,
                thickness_mm: 2.0,
                measured_n: 2.0,
            },
            EquationInput {
                frame: 1,
                nodes: &b,
                thickness_mm: 1.5,
                measured_n: 3.0,
            },
        ];
        let equations = Equations::compile(&inputs).unwrap();
        // Frame 0: nodes 0 and 1, and the filled value; frame 1: node 1 and the filled value.
        assert_eq!(equations.nodes(), 5);
        assert_eq!(equations.measured_n(), &[1.0, 2.0, 3.0]);
        for (model, p) in models() {
            let compiled = equations.forces_n(&model, &p).unwrap();
            for (input, got) in inputs.iter().zip(&compiled) {
                let direct = work_n(input.nodes, &model, &p, input.thickness_mm).unwrap();
                assert!(
                    (got - direct).abs() <= 1e-12 * direct.abs().max(1.0),
                    "{model}: {got} vs {direct}"
                );
            }
        }
    }

    #[test]
    fn an_undefined_node_is_named() {
        let inverted = [node(3, [[1.0, 2.0], [1.0, 2.0]], [[1.0, 0.0], [0.0, 0.0]])];
        let error = Equations::compile(&[EquationInput {
            frame: 0,
            nodes: &inverted,
            thickness_mm: 1.0,
            measured_n: 0.0,
        }])
        .unwrap_err();
        assert_eq!(error.at, (3, 0));
        assert!(matches!(
            error.reason,
            NodeStressError::NotInvertible { .. }
        ));
        // Gent's stress is not defined beyond its limit: the trial law says so.
        let stretched = [node(0, [[3.0, 0.0], [0.0, 1.0]], [[1.0, 0.0], [0.0, 0.0]])];
        let equations = Equations::compile(&[EquationInput {
            frame: 0,
            nodes: &stretched,
            thickness_mm: 1.0,
            measured_n: 0.0,
        }])
        .unwrap();
        assert!(matches!(
            equations.forces_n(&Model::Gent, &[0.4, 2.0]),
            Err(NodeStressError::OutsideDomain { .. })
        ));
    }
}
