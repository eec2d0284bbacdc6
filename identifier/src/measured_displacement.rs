//! A measured displacement field on its reference grid, and its value anywhere near its valid
//! nodes: what the finite-element model updating prescribes on the edges of the field of view
//! (`femu`). The value at a point is a local quadratic least-squares fit of the valid nodes
//! within [`FIT_RADII_STEPS`] node steps (the first radius that holds [`MIN_FIT_NODES`] and
//! determines the quadratic): exact for a quadratic field, third order in the step for a
//! smooth one, it smooths the measurement's noise and reaches a point beyond the last valid
//! nodes (an arm's free edge, where the correlator loses the nodes whose window runs off the
//! specimen) without treating a hole as data.

use crate::lsq::linear_least_squares;
use nalgebra::{DMatrix, DVector};

/// Radii of the local fit, in node steps, tried in order.
pub const FIT_RADII_STEPS: [f64; 2] = [2.5, 3.5];
/// Valid nodes a local fit needs (the quadratic has 6 coefficients).
pub const MIN_FIT_NODES: usize = 10;

/// A measured displacement field: node (col, row) at (x0 + col s, y0 + row s) mm in the
/// reference configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct DisplacementGrid {
    pub cols: usize,
    pub rows: usize,
    pub x0_mm: f64,
    pub y0_mm: f64,
    pub step_mm: f64,
    /// Row-major displacements (x, y), mm; `None` where the node has no measurement.
    pub displacements_mm: Vec<Option<[f64; 2]>>,
}

impl DisplacementGrid {
    /// Reference position of node `k` (row-major), mm.
    pub fn node_mm(&self, k: usize) -> [f64; 2] {
        [
            self.x0_mm + (k % self.cols) as f64 * self.step_mm,
            self.y0_mm + (k / self.cols) as f64 * self.step_mm,
        ]
    }

    /// The reference extent of the nodes, [first, last] along x and along y, mm.
    pub fn extent_mm(&self) -> ([f64; 2], [f64; 2]) {
        let s = self.step_mm;
        (
            [self.x0_mm, self.x0_mm + (self.cols.max(1) - 1) as f64 * s],
            [self.y0_mm, self.y0_mm + (self.rows.max(1) - 1) as f64 * s],
        )
    }

    /// The same nodes (size, origin, step) as `other`.
    pub fn same_nodes(&self, other: &DisplacementGrid) -> bool {
        (self.cols, self.rows, self.x0_mm, self.y0_mm, self.step_mm)
            == (
                other.cols,
                other.rows,
                other.x0_mm,
                other.y0_mm,
                other.step_mm,
            )
    }

    /// The valid nodes within `radius_mm` of `x_mm`: (offset from `x_mm` in steps, u mm).
    fn valid_within(&self, x_mm: [f64; 2], radius_mm: f64) -> Vec<([f64; 2], [f64; 2])> {
        let s = self.step_mm;
        let range = |origin: f64, centre: f64, n: usize| {
            let lo = ((centre - radius_mm - origin) / s).ceil().max(0.0) as usize;
            let hi = (((centre + radius_mm - origin) / s).floor().max(-1.0) + 1.0) as usize;
            lo..hi.min(n)
        };
        let mut out = vec![];
        for row in range(self.y0_mm, x_mm[1], self.rows) {
            for col in range(self.x0_mm, x_mm[0], self.cols) {
                let k = row * self.cols + col;
                let Some(u) = self.displacements_mm[k] else {
                    continue;
                };
                let p = self.node_mm(k);
                let d = [(p[0] - x_mm[0]) / s, (p[1] - x_mm[1]) / s];
                if (d[0] * d[0] + d[1] * d[1]).sqrt() * s <= radius_mm {
                    out.push((d, u));
                }
            }
        }
        out
    }

    /// The displacement at `x_mm` (mm) by the local quadratic fit; `None` when no radius holds
    /// [`MIN_FIT_NODES`] valid nodes that determine it.
    pub fn interpolate(&self, x_mm: [f64; 2]) -> Option<[f64; 2]> {
        FIT_RADII_STEPS.iter().find_map(|radius| {
            let nodes = self.valid_within(x_mm, radius * self.step_mm);
            if nodes.len() < MIN_FIT_NODES {
                return None;
            }
            let a = DMatrix::from_fn(nodes.len(), 6, |i, j| {
                let [x, y] = nodes[i].0;
                [1.0, x, y, x * x, x * y, y * y][j]
            });
            let fit = |c: usize| {
                let b = DVector::from_iterator(nodes.len(), nodes.iter().map(|n| n.1[c]));
                linear_least_squares(&a, &b)
                    .ok()
                    .map(|coefficients| coefficients[0])
            };
            Some([fit(0)?, fit(1)?])
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(
        valid: impl Fn([f64; 2]) -> bool,
        u: impl Fn([f64; 2]) -> [f64; 2],
    ) -> DisplacementGrid {
        let (cols, rows, step) = (21, 15, 0.5);
        let mut grid = DisplacementGrid {
            cols,
            rows,
            x0_mm: -5.0,
            y0_mm: -3.0,
            step_mm: step,
            displacements_mm: vec![None; cols * rows],
        };
        for k in 0..cols * rows {
            let p = grid.node_mm(k);
            grid.displacements_mm[k] = valid(p).then(|| u(p));
        }
        grid
    }

    /// A quadratic field comes back exactly, between nodes and beyond the last valid ones; a
    /// point with too few valid nodes around it has no value.
    #[test]
    fn a_quadratic_field_is_exact_near_its_valid_nodes() {
        let u = |p: [f64; 2]| {
            [
                0.1 + 0.02 * p[0] - 0.01 * p[1] + 0.003 * p[0] * p[1],
                -0.2 + 0.05 * p[1] + 0.004 * p[0] * p[0] - 0.002 * p[1] * p[1],
            ]
        };
        // The nodes above y = 2 mm are lost (a free edge).
        let g = grid(|p| p[1] <= 2.0, u);
        for x in [[0.13, -0.77], [2.0, 2.0], [-1.0, 2.6], [4.9, -2.9]] {
            let got = g.interpolate(x).unwrap();
            let want = u(x);
            for c in 0..2 {
                assert!((got[c] - want[c]).abs() < 1e-12, "{x:?}: {got:?} {want:?}");
            }
        }
        // Two steps beyond the smallest radius's reach of any valid node.
        assert_eq!(g.interpolate([0.0, 2.0 + 3.6 * 0.5]), None);
        // A single valid column does not determine a quadratic.
        let column = grid(|p| p[0] == 0.0, u);
        assert_eq!(column.interpolate([0.0, 0.0]), None);
    }
}
