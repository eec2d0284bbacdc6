//! The six-node quadratic triangle (T6): shape functions on the reference triangle and a
//! six-point Gauss rule exact to degree 4 (Dunavant), enough for the quadratic element's
//! stiffness without spurious modes. Node order: corners 0, 1, 2, then midsides 01, 12, 20.

/// Nodes per element.
pub const NODES: usize = 6;

/// (ξ, η, weight) of the six-point rule on the reference triangle (weights sum to 1/2).
pub const GAUSS_POINTS: [(f64, f64, f64); 6] = {
    const A: f64 = 0.445_948_490_915_965;
    const WA: f64 = 0.223_381_589_678_011 / 2.0;
    const B: f64 = 0.091_576_213_509_771;
    const WB: f64 = 0.109_951_743_655_322 / 2.0;
    [
        (A, A, WA),
        (1.0 - 2.0 * A, A, WA),
        (A, 1.0 - 2.0 * A, WA),
        (B, B, WB),
        (1.0 - 2.0 * B, B, WB),
        (B, 1.0 - 2.0 * B, WB),
    ]
};

/// Shape function values at (ξ, η).
pub fn shape(xi: f64, eta: f64) -> [f64; NODES] {
    let l = [1.0 - xi - eta, xi, eta];
    [
        l[0] * (2.0 * l[0] - 1.0),
        l[1] * (2.0 * l[1] - 1.0),
        l[2] * (2.0 * l[2] - 1.0),
        4.0 * l[0] * l[1],
        4.0 * l[1] * l[2],
        4.0 * l[2] * l[0],
    ]
}

/// Derivatives [∂N/∂ξ, ∂N/∂η] of the shape functions at (ξ, η).
pub fn shape_gradients(xi: f64, eta: f64) -> [[f64; 2]; NODES] {
    let l0 = 1.0 - xi - eta;
    [
        [1.0 - 4.0 * l0, 1.0 - 4.0 * l0],
        [4.0 * xi - 1.0, 0.0],
        [0.0, 4.0 * eta - 1.0],
        [4.0 * (l0 - xi), -4.0 * xi],
        [4.0 * eta, 4.0 * xi],
        [-4.0 * eta, 4.0 * (l0 - eta)],
    ]
}

/// Reference-configuration data of one Gauss point: ∂N/∂X (mm⁻¹) and the area weight (mm²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussPoint {
    pub gradients_per_mm: [[f64; 2]; NODES],
    pub area_mm2: f64,
}

/// Natural coordinates (ξ, η) of the six nodes, in node order.
pub const NODE_COORDINATES: [(f64, f64); NODES] = [
    (0.0, 0.0),
    (1.0, 0.0),
    (0.0, 1.0),
    (0.5, 0.0),
    (0.5, 0.5),
    (0.0, 0.5),
];

/// ∂N/∂X (mm⁻¹) at (ξ, η) of an element with reference node positions `nodes_mm`, and the
/// Jacobian determinant (mm²); `Err(det)` where it is not positive.
pub fn gradients_at(
    nodes_mm: &[[f64; 2]; NODES],
    xi: f64,
    eta: f64,
) -> Result<([[f64; 2]; NODES], f64), f64> {
    let dn = shape_gradients(xi, eta);
    let mut jac = [[0.0; 2]; 2]; // jac[i][k] = ∂X_i/∂ξ_k
    for (x, d) in nodes_mm.iter().zip(dn.iter()) {
        for i in 0..2 {
            for k in 0..2 {
                jac[i][k] += x[i] * d[k];
            }
        }
    }
    let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
    if det.is_nan() || det <= 0.0 {
        return Err(det);
    }
    // ∂N/∂X = J⁻ᵀ ∂N/∂ξ
    let inv = [
        [jac[1][1] / det, -jac[0][1] / det],
        [-jac[1][0] / det, jac[0][0] / det],
    ];
    let gradients = dn.map(|d| {
        [
            inv[0][0] * d[0] + inv[1][0] * d[1],
            inv[0][1] * d[0] + inv[1][1] * d[1],
        ]
    });
    Ok((gradients, det))
}

/// The Gauss points of an element with reference node positions `nodes_mm`; `Err(det)` with the
/// Jacobian determinant (mm²) of the first point where it is not positive.
pub fn gauss_points(nodes_mm: &[[f64; 2]; NODES]) -> Result<[GaussPoint; 6], f64> {
    let mut out = [GaussPoint {
        gradients_per_mm: [[0.0; 2]; NODES],
        area_mm2: 0.0,
    }; 6];
    for (point, &(xi, eta, weight)) in out.iter_mut().zip(GAUSS_POINTS.iter()) {
        let (gradients, det) = gradients_at(nodes_mm, xi, eta)?;
        point.gradients_per_mm = gradients;
        point.area_mm2 = det * weight;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_of_unity_and_rule_integrates_quartics() {
        for &(xi, eta, _) in &GAUSS_POINTS {
            let n = shape(xi, eta);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            let g = shape_gradients(xi, eta);
            assert!(g.iter().map(|d| d[0]).sum::<f64>().abs() < 1e-13);
            assert!(g.iter().map(|d| d[1]).sum::<f64>().abs() < 1e-13);
        }
        // ∫ ξ² η² over the reference triangle = 2! 2! / 6! = 1/180.
        let integral: f64 = GAUSS_POINTS
            .iter()
            .map(|&(x, y, w)| w * x * x * y * y)
            .sum();
        assert!((integral - 1.0 / 180.0).abs() < 1e-14, "{integral}");
    }

    #[test]
    fn shape_gradients_match_finite_differences() {
        let (xi, eta, h) = (0.23, 0.41, 1e-6);
        let g = shape_gradients(xi, eta);
        let (px, mx) = (shape(xi + h, eta), shape(xi - h, eta));
        let (py, my) = (shape(xi, eta + h), shape(xi, eta - h));
        for a in 0..NODES {
            assert!(((px[a] - mx[a]) / (2.0 * h) - g[a][0]).abs() < 1e-8);
            assert!(((py[a] - my[a]) / (2.0 * h) - g[a][1]).abs() < 1e-8);
        }
    }
}
