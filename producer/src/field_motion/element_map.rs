//! A six-node triangle's quadratic map written as a polynomial in (ξ, η), for the renderer's
//! inner loop: x = c₀ + c₁ ξ + c₂ η + c₃ ξ² + c₄ ξη + c₅ η² costs a dozen multiply-adds, where
//! the shape functions summed node by node cost several times that. Same map as
//! `membrane::t6::shape` (checked in the tests).

use crate::motion::{Mat2, Vec2};

/// Newton iterations at most (it converges in one or two from a neighbour's coordinates).
const MAX_ITERATIONS: usize = 8;
/// The last step below this (natural coordinates): Newton converging quadratically, the point
/// is off by about its square, 1e-10 (the inverse tests ask for 1e-8 px).
const TOLERANCE: f64 = 1e-5;
/// How far outside [0, 1] a natural coordinate may be and the point still count as inside.
const EDGE_TOLERANCE: f64 = 1e-9;

/// x(ξ, η) of one element, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadraticMap {
    c: [Vec2; 6],
}

impl QuadraticMap {
    /// The map of the element whose six nodes (corners, then midsides 01, 12, 20) are at `p`.
    pub fn of(p: &[[f64; 2]; 6]) -> QuadraticMap {
        // N₀ = 1 − 3ξ − 3η + 2ξ² + 4ξη + 2η², N₁ = −ξ + 2ξ², N₂ = −η + 2η²,
        // N₃ = 4ξ − 4ξ² − 4ξη, N₄ = 4ξη, N₅ = 4η − 4ξη − 4η², gathered by monomial.
        let c = |f: &dyn Fn(usize) -> f64| [f(0), f(1)];
        QuadraticMap {
            c: [
                c(&|i| p[0][i]),
                c(&|i| -3.0 * p[0][i] - p[1][i] + 4.0 * p[3][i]),
                c(&|i| -3.0 * p[0][i] - p[2][i] + 4.0 * p[5][i]),
                c(&|i| 2.0 * p[0][i] + 2.0 * p[1][i] - 4.0 * p[3][i]),
                c(&|i| 4.0 * (p[0][i] - p[3][i] + p[4][i] - p[5][i])),
                c(&|i| 2.0 * p[0][i] + 2.0 * p[2][i] - 4.0 * p[5][i]),
            ],
        }
    }

    /// x(ξ, η).
    #[inline(always)]
    pub fn at(&self, xi: f64, eta: f64) -> Vec2 {
        let c = &self.c;
        let v = |i: usize| {
            c[0][i]
                + xi * (c[1][i] + c[3][i] * xi + c[4][i] * eta)
                + eta * (c[2][i] + c[5][i] * eta)
        };
        [v(0), v(1)]
    }

    /// ∂x_i/∂(ξ, η)_a, row i.
    #[inline(always)]
    pub fn jacobian(&self, xi: f64, eta: f64) -> Mat2 {
        let c = &self.c;
        let row = |i: usize| {
            [
                c[1][i] + 2.0 * c[3][i] * xi + c[4][i] * eta,
                c[2][i] + c[4][i] * xi + 2.0 * c[5][i] * eta,
            ]
        };
        [row(0), row(1)]
    }

    /// (ξ, η) of `x` by Newton from `start` when it lies in the element; None outside (or when
    /// Newton does not settle, or the map folds there).
    #[inline]
    pub fn natural(&self, x: Vec2, start: (f64, f64)) -> Option<(f64, f64)> {
        let (mut xi, mut eta) = start;
        for _ in 0..MAX_ITERATIONS {
            let p = self.at(xi, eta);
            let j = self.jacobian(xi, eta);
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if !(det > 0.0 && det.is_finite()) {
                return None;
            }
            let r = [x[0] - p[0], x[1] - p[1]];
            let d_xi = (j[1][1] * r[0] - j[0][1] * r[1]) / det;
            let d_eta = (-j[1][0] * r[0] + j[0][0] * r[1]) / det;
            xi += d_xi;
            eta += d_eta;
            if d_xi.abs().max(d_eta.abs()) < TOLERANCE {
                let inside = xi >= -EDGE_TOLERANCE
                    && eta >= -EDGE_TOLERANCE
                    && 1.0 - xi - eta >= -EDGE_TOLERANCE;
                return inside.then_some((xi, eta));
            }
            // Clearly outside and settling there (the map is nearly affine: two steps put
            // a point close to where it is): not this element.
            let outside_by = (-xi).max(-eta).max(xi + eta - 1.0);
            if xi.abs() > 10.0
                || eta.abs() > 10.0
                || (outside_by > 0.05 && d_xi.abs().max(d_eta.abs()) < 0.01)
            {
                return None;
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use membrane::t6;

    /// A curved element: midside nodes off the straight edges.
    const NODES: [[f64; 2]; 6] = [
        [0.0, 0.0],
        [10.0, 1.0],
        [2.0, 9.0],
        [5.2, 0.1],
        [6.5, 5.4],
        [0.8, 4.3],
    ];

    #[test]
    fn the_polynomial_is_the_shape_functions_map_and_newton_inverts_it() {
        let map = QuadraticMap::of(&NODES);
        for (xi, eta) in [(0.0, 0.0), (0.2, 0.3), (1.0, 0.0), (0.05, 0.9), (0.4, 0.4)] {
            let n = t6::shape(xi, eta);
            let dn = t6::shape_gradients(xi, eta);
            let mut want = [0.0; 2];
            let mut jac = [[0.0; 2]; 2];
            for k in 0..6 {
                for i in 0..2 {
                    want[i] += n[k] * NODES[k][i];
                    for a in 0..2 {
                        jac[i][a] += dn[k][a] * NODES[k][i];
                    }
                }
            }
            let got = map.at(xi, eta);
            let j = map.jacobian(xi, eta);
            for i in 0..2 {
                assert!((got[i] - want[i]).abs() < 1e-12, "{xi} {eta}");
                for a in 0..2 {
                    assert!((j[i][a] - jac[i][a]).abs() < 1e-12, "{xi} {eta}");
                }
            }
            let (bx, be) = map.natural(got, (1.0 / 3.0, 1.0 / 3.0)).unwrap();
            assert!((bx - xi).abs() < 1e-12 && (be - eta).abs() < 1e-12);
        }
        // Outside the element: refused.
        assert!(map.natural([-1.0, -1.0], (0.3, 0.3)).is_none());
        assert!(map.natural([9.0, 9.0], (0.3, 0.3)).is_none());
    }
}
