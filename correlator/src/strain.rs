//! Strains from the displacement gradient (paper section 3.c): F = 1 + ∇u from a least-squares
//! affine fit of (u, v) over a window of valid nodes; infinitesimal strain sym(∇u) and the
//! Lagrangian family E_m = (C^m − 1)/2m (m = 1 Green-Lagrange, m = 1/2 nominal) and
//! E_0 = ln(C)/2 (logarithmic), eq. (13), via the eigen-decomposition of C = FᵀF.
//!
//! Gauge (CORRELI-GAUGE): the paper averages the strain of an interpolated (B-spline) field over
//! the ROI. Here the average gradient is the least-squares affine fit u = a + ∇u·x over all valid
//! nodes, which equals the ROI average of the gradient for an affine field and weighs every node
//! equally otherwise; the four measures are then computed from that one F.

use crate::field::{Node, NodeStatus, Strain2};
use crate::settings::StrainMeasure;
use nalgebra::{Matrix2, Matrix3, SymmetricEigen, Vector3};

/// Running sums of the normal equations of u = a + b·dx + c·dy (and the same for v).
#[derive(Default, Clone, Copy)]
pub struct AffineSums {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    sxy: f64,
    syy: f64,
    su: f64,
    sxu: f64,
    syu: f64,
    sv: f64,
    sxv: f64,
    syv: f64,
}

impl AffineSums {
    #[inline]
    pub fn add(&mut self, dx: f64, dy: f64, u: f64, v: f64) {
        self.n += 1.0;
        self.sx += dx;
        self.sy += dy;
        self.sxx += dx * dx;
        self.sxy += dx * dy;
        self.syy += dy * dy;
        self.su += u;
        self.sxu += dx * u;
        self.syu += dy * u;
        self.sv += v;
        self.sxv += dx * v;
        self.syv += dy * v;
    }

    /// ∇u = [[du/dx, du/dy], [dv/dx, dv/dy]], or None when the points are fewer than 3 or collinear.
    pub fn gradient(&self) -> Option<Matrix2<f64>> {
        self.fit().map(|(_, grad)| grad)
    }

    /// The whole affine fit: (u, v) at dx = dy = 0, and ∇u; None when the points are fewer
    /// than 3 or collinear.
    pub fn fit(&self) -> Option<((f64, f64), Matrix2<f64>)> {
        if self.n < 3.0 {
            return None;
        }
        let a = Matrix3::new(
            self.n, self.sx, self.sy, //
            self.sx, self.sxx, self.sxy, //
            self.sy, self.sxy, self.syy,
        );
        let scale = self.sxx.max(self.syy).max(1e-300);
        let det = a.determinant();
        if det.abs() <= 1e-9 * self.n * scale * scale {
            return None;
        }
        let inv = a.try_inverse()?;
        let cu = inv * Vector3::new(self.su, self.sxu, self.syu);
        let cv = inv * Vector3::new(self.sv, self.sxv, self.syv);
        Some(((cu[0], cv[0]), Matrix2::new(cu[1], cu[2], cv[1], cv[2])))
    }
}

/// Strain of one measure from the displacement gradient ∇u (F = 1 + ∇u).
/// A non-invertible F (det F ≤ 0) gives None.
pub fn strain_from_gradient(grad: &Matrix2<f64>, measure: StrainMeasure) -> Option<Strain2> {
    let f = Matrix2::identity() + grad;
    if f.determinant() <= 0.0 {
        return None;
    }
    let tensor = match measure {
        StrainMeasure::Small => (grad + grad.transpose()) * 0.5,
        StrainMeasure::Green => lagrangian(&f, 1.0),
        StrainMeasure::Nominal => lagrangian(&f, 0.5),
        StrainMeasure::Log => lagrangian(&f, 0.0),
    };
    Some(Strain2 {
        exx: tensor[(0, 0)],
        eyy: tensor[(1, 1)],
        exy: tensor[(0, 1)],
    })
}

/// E_m of eq. (13) for C = FᵀF.
fn lagrangian(f: &Matrix2<f64>, m: f64) -> Matrix2<f64> {
    let c = f.transpose() * f;
    let eigen = SymmetricEigen::new(c);
    let q = eigen.eigenvectors;
    let map = |lambda: f64| {
        let lambda = lambda.max(1e-300);
        if m == 0.0 {
            0.5 * lambda.ln()
        } else {
            (lambda.powf(m) - 1.0) / (2.0 * m)
        }
    };
    let d = Matrix2::new(
        map(eigen.eigenvalues[0]),
        0.0,
        0.0,
        map(eigen.eigenvalues[1]),
    );
    q * d * q.transpose()
}

/// Least-squares gradient of the valid nodes in the (2h+1) x (2h+1) window around node (i, j)
/// (None when that node is not valid or the fit is impossible).
fn window_gradient(
    nodes: &[Node],
    (nx, ny): (usize, usize),
    half_window: usize,
    (i, j): (usize, usize),
) -> Option<Matrix2<f64>> {
    let centre = nodes[j * nx + i];
    if centre.status != NodeStatus::Ok {
        return None;
    }
    let mut sums = AffineSums::default();
    let (j0, j1) = (j.saturating_sub(half_window), (j + half_window).min(ny - 1));
    let (i0, i1) = (i.saturating_sub(half_window), (i + half_window).min(nx - 1));
    for jj in j0..=j1 {
        for ii in i0..=i1 {
            let node = &nodes[jj * nx + ii];
            if node.status == NodeStatus::Ok {
                sums.add(
                    node.x_px - centre.x_px,
                    node.y_px - centre.y_px,
                    node.u_px,
                    node.v_px,
                );
            }
        }
    }
    sums.gradient()
}

fn set_strain(node: &mut Node, gradient: Option<Matrix2<f64>>, measure: StrainMeasure) {
    let strain = gradient
        .and_then(|g| strain_from_gradient(&g, measure))
        .unwrap_or_default();
    node.exx = strain.exx;
    node.eyy = strain.eyy;
    node.exy = strain.exy;
}

/// Fills exx, eyy, exy of every node from a least-squares gradient over the
/// (2h+1) x (2h+1) window of valid nodes around it (zeros where the fit is impossible).
pub fn node_strains(
    nodes: &mut [Node],
    nx: usize,
    ny: usize,
    half_window: usize,
    measure: StrainMeasure,
) {
    assert_eq!(nodes.len(), nx * ny);
    for k in 0..nx * ny {
        let g = window_gradient(nodes, (nx, ny), half_window, (k % nx, k / nx));
        set_strain(&mut nodes[k], g, measure);
    }
}

/// [`node_strains`], also writing each node's least-squares gradient ([[∂u/∂x, ∂u/∂y],
/// [∂v/∂x, ∂v/∂y]], zero where there is none) into `gradients`.
pub fn node_strains_and_gradients(
    nodes: &mut [Node],
    (nx, ny): (usize, usize),
    half_window: usize,
    measure: StrainMeasure,
    gradients: &mut [[[f64; 2]; 2]],
) {
    assert_eq!(nodes.len(), nx * ny);
    assert_eq!(gradients.len(), nx * ny);
    for k in 0..nx * ny {
        let g = window_gradient(nodes, (nx, ny), half_window, (k % nx, k / nx));
        gradients[k] = g.map_or([[0.0; 2]; 2], |g| {
            [[g[(0, 0)], g[(0, 1)]], [g[(1, 0)], g[(1, 1)]]]
        });
        set_strain(&mut nodes[k], g, measure);
    }
}

/// Fills exx, eyy, exy of every valid node from its own displacement gradient (IC-GN's),
/// zeros elsewhere.
pub fn strains_from_gradients(
    nodes: &mut [Node],
    gradients: &[[[f64; 2]; 2]],
    measure: StrainMeasure,
) {
    assert_eq!(nodes.len(), gradients.len());
    for (node, g) in nodes.iter_mut().zip(gradients) {
        let gradient = (node.status == NodeStatus::Ok)
            .then(|| Matrix2::new(g[0][0], g[0][1], g[1][0], g[1][1]));
        set_strain(node, gradient, measure);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_has_zero_lagrangian_strain() {
        let t = 5f64.to_radians();
        let grad = Matrix2::new(t.cos() - 1.0, -t.sin(), t.sin(), t.cos() - 1.0);
        let small = strain_from_gradient(&grad, StrainMeasure::Small).unwrap();
        assert!((small.exx - (t.cos() - 1.0)).abs() < 1e-12);
        for m in [
            StrainMeasure::Green,
            StrainMeasure::Nominal,
            StrainMeasure::Log,
        ] {
            let e = strain_from_gradient(&grad, m).unwrap();
            assert!(
                e.exx.abs() < 1e-12 && e.eyy.abs() < 1e-12 && e.exy.abs() < 1e-12,
                "{m:?} {e:?}"
            );
        }
    }

    #[test]
    fn equibiaxial_stretch_measures() {
        let grad = Matrix2::new(0.07, 0.0, 0.0, 0.07);
        let lambda: f64 = 1.07;
        let expect = [
            (StrainMeasure::Small, 0.07),
            (StrainMeasure::Green, 0.5 * (lambda * lambda - 1.0)),
            (StrainMeasure::Nominal, lambda - 1.0),
            (StrainMeasure::Log, lambda.ln()),
        ];
        for (m, e) in expect {
            let s = strain_from_gradient(&grad, m).unwrap();
            assert!((s.exx - e).abs() < 1e-12 && (s.eyy - e).abs() < 1e-12 && s.exy.abs() < 1e-12);
        }
    }
}
