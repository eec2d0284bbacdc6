//! Shape functions of IC-GN: where a reference subset point at (dx, dy) from the subset centre
//! lands in the deformed image, relative to that centre,
//!
//! x' = dx + u + u_x dx + u_y dy + ½ u_xx dx² + u_xy dx dy + ½ u_yy dy²  (and y' with v),
//!
//! first order (6 parameters: the second-order terms stay 0) or second order (12). The
//! parameters are the displacement of the subset centre and its derivatives there. Composition
//! and inversion go through the 6 x 6 matrix that maps (dx², dx dy, dy², dx, dy, 1) to the same
//! monomials of (x', y') truncated to second order (Gao, Cheng, Su, Xu, "High-efficiency and
//! high-accuracy digital image correlation for three-dimensional measurement", 2015): exact for
//! the first order (an affine map), the standard approximation for the second.

use nalgebra::SMatrix;

type M6 = SMatrix<f64, 6, 6>;

/// Parameters of a shape function, in the order of the steepest-descent images:
/// u, u_x, u_y, u_xx, u_xy, u_yy, v, v_x, v_y, v_xx, v_xy, v_yy.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Warp {
    pub p: [f64; 12],
}

/// Index of each parameter in [`Warp::p`].
pub const U: usize = 0;
pub const U_X: usize = 1;
pub const U_Y: usize = 2;
pub const V: usize = 6;
pub const V_X: usize = 7;
pub const V_Y: usize = 8;

/// Which shape function.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    First,
    Second,
}

impl Order {
    /// Parameters of the shape function (6 or 12).
    pub fn parameters(self) -> usize {
        match self {
            Order::First => 6,
            Order::Second => 12,
        }
    }

    /// Index in [`Warp::p`] of the i-th parameter of this order.
    #[inline]
    pub fn index(self, i: usize) -> usize {
        match self {
            Order::First => [U, U_X, U_Y, V, V_X, V_Y][i],
            Order::Second => i,
        }
    }
}

impl Warp {
    /// The warp of a displacement (u, v) and gradient g = [[u_x, u_y], [v_x, v_y]].
    pub fn affine(u: (f64, f64), g: [[f64; 2]; 2]) -> Warp {
        let mut p = [0.0; 12];
        p[U] = u.0;
        p[U_X] = g[0][0];
        p[U_Y] = g[0][1];
        p[V] = u.1;
        p[V_X] = g[1][0];
        p[V_Y] = g[1][1];
        Warp { p }
    }

    pub fn displacement(&self) -> (f64, f64) {
        (self.p[U], self.p[V])
    }

    pub fn gradient(&self) -> [[f64; 2]; 2] {
        [[self.p[U_X], self.p[U_Y]], [self.p[V_X], self.p[V_Y]]]
    }

    /// The 6 x 6 matrix of the warp on (dx², dx dy, dy², dx, dy, 1).
    fn matrix(&self) -> M6 {
        let p = &self.p;
        let a = [0.5 * p[3], p[4], 0.5 * p[5], 1.0 + p[1], p[2], p[0]];
        let b = [0.5 * p[9], p[10], 0.5 * p[11], p[7], 1.0 + p[8], p[6]];
        let square = |a: &[f64; 6]| {
            [
                a[3] * a[3] + 2.0 * a[0] * a[5],
                2.0 * a[3] * a[4] + 2.0 * a[1] * a[5],
                a[4] * a[4] + 2.0 * a[2] * a[5],
                2.0 * a[3] * a[5],
                2.0 * a[4] * a[5],
                a[5] * a[5],
            ]
        };
        let cross = [
            a[3] * b[3] + a[0] * b[5] + a[5] * b[0],
            a[3] * b[4] + a[4] * b[3] + a[1] * b[5] + a[5] * b[1],
            a[4] * b[4] + a[2] * b[5] + a[5] * b[2],
            a[3] * b[5] + a[5] * b[3],
            a[4] * b[5] + a[5] * b[4],
            a[5] * b[5],
        ];
        let rows = [
            square(&a),
            cross,
            square(&b),
            a,
            b,
            [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        ];
        M6::from_fn(|r, c| rows[r][c])
    }

    fn from_matrix(m: &M6) -> Warp {
        let mut p = [0.0; 12];
        p[3] = 2.0 * m[(3, 0)];
        p[4] = m[(3, 1)];
        p[5] = 2.0 * m[(3, 2)];
        p[1] = m[(3, 3)] - 1.0;
        p[2] = m[(3, 4)];
        p[0] = m[(3, 5)];
        p[9] = 2.0 * m[(4, 0)];
        p[10] = m[(4, 1)];
        p[11] = 2.0 * m[(4, 2)];
        p[7] = m[(4, 3)];
        p[8] = m[(4, 4)] - 1.0;
        p[6] = m[(4, 5)];
        Warp { p }
    }

    /// The inverse-compositional update W(p) ∘ W(Δp)⁻¹; None when W(Δp) is not invertible.
    pub fn compose_inverse(&self, delta: &Warp) -> Option<Warp> {
        let inverse = delta.matrix().try_inverse()?;
        let w = Self::from_matrix(&(self.matrix() * inverse));
        w.p.iter().all(|v| v.is_finite()).then_some(w)
    }

    /// Where the point (dx, dy) from the subset centre lands, relative to that centre.
    #[inline]
    pub fn apply(&self, dx: f64, dy: f64) -> (f64, f64) {
        let p = &self.p;
        let quadratic =
            |a: f64, b: f64, c: f64| 0.5 * a * dx * dx + b * dx * dy + 0.5 * c * dy * dy;
        (
            dx + p[0] + p[1] * dx + p[2] * dy + quadratic(p[3], p[4], p[5]),
            dy + p[6] + p[7] * dx + p[8] * dy + quadratic(p[9], p[10], p[11]),
        )
    }

    /// The largest motion the warp gives a point within `radius_px` of the centre (first and
    /// second order terms bounded separately): the size of an update.
    pub fn reach_px(&self, radius_px: f64) -> f64 {
        let p = &self.p;
        let r = radius_px;
        let first = (p[0] * p[0]
            + p[6] * p[6]
            + r * r * (p[1] * p[1] + p[2] * p[2] + p[7] * p[7] + p[8] * p[8]))
            .sqrt();
        let second = 0.5
            * r
            * r
            * (p[3] * p[3]
                + p[4] * p[4]
                + p[5] * p[5]
                + p[9] * p[9]
                + p[10] * p[10]
                + p[11] * p[11])
                .sqrt();
        first + second
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn composing_with_the_inverse_of_itself_is_the_identity() {
        let w = Warp {
            p: [
                0.3, 0.02, -0.01, 0.001, 0.0005, -0.002, -1.2, 0.015, 0.03, -0.001, 0.0, 0.0007,
            ],
        };
        let id = w.compose_inverse(&w).unwrap();
        for v in id.p {
            assert!(v.abs() < 1e-5, "{:?}", id.p);
        }
    }

    #[test]
    fn affine_composition_is_exact() {
        // W(p) ∘ W(d)⁻¹ applied to W(d)(x) gives W(p)(x).
        let p = Warp::affine((1.5, -0.7), [[0.1, -0.05], [0.08, 0.2]]);
        let d = Warp::affine((0.2, 0.1), [[0.01, 0.02], [-0.03, 0.015]]);
        let c = p.compose_inverse(&d).unwrap();
        for (x, y) in [(3.0, -4.0), (-10.0, 7.5), (0.0, 0.0)] {
            let (ax, ay) = d.apply(x, y);
            let via = c.apply(ax, ay);
            let direct = p.apply(x, y);
            assert!((via.0 - direct.0).abs() < 1e-12 && (via.1 - direct.1).abs() < 1e-12);
        }
    }
}
