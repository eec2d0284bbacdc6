//! The exact motion of simulated frames, compared with what the correlator measured. A frame's
//! ground truth maps the undeformed pattern to the image: x = F (X − c) + c + t. A field's
//! nodes sit in the image of the frame it is measured from (the origin frame); the true
//! displacement of the node at x0 is φ_k(φ_o⁻¹(x0)) − x0, and the true strain comes from the
//! relative gradient F_k F_o⁻¹.

use nalgebra::{Matrix2, SymmetricEigen, Vector2};
use producer::FieldMotion;
use wire::{FieldNode, GroundTruth, NodeStatus};

fn gradient(truth: &GroundTruth) -> Matrix2<f64> {
    let [a, b, c, d] = truth.deformation_gradient;
    Matrix2::new(a, b, c, d)
}

/// x = φ(X).
pub fn forward(truth: &GroundTruth, material_px: Vector2<f64>) -> Vector2<f64> {
    let c = Vector2::from(truth.centre_px);
    gradient(truth) * (material_px - c) + c + Vector2::from(truth.translation_px)
}

/// X = φ⁻¹(x); None when F is singular.
pub fn inverse(truth: &GroundTruth, image_px: Vector2<f64>) -> Option<Vector2<f64>> {
    let c = Vector2::from(truth.centre_px);
    let f_inv = gradient(truth).try_inverse()?;
    Some(f_inv * (image_px - c - Vector2::from(truth.translation_px)) + c)
}

/// Gradient of the motion from the origin frame's image to the current frame's image.
pub fn relative_gradient(current: &GroundTruth, origin: &GroundTruth) -> Option<Matrix2<f64>> {
    Some(gradient(current) * gradient(origin).try_inverse()?)
}

/// Logarithmic (Hencky) strain ½ ln(FᵀF) as (exx, eyy, exy); None when F is singular.
pub fn log_strain(f: &Matrix2<f64>) -> Option<[f64; 3]> {
    let c = f.transpose() * f;
    let eigen = SymmetricEigen::new(c);
    if eigen
        .eigenvalues
        .iter()
        .any(|&v| !(v > 0.0 && v.is_finite()))
    {
        return None;
    }
    let log = eigen.eigenvectors
        * Matrix2::from_diagonal(&eigen.eigenvalues.map(|v| 0.5 * v.ln()))
        * eigen.eigenvectors.transpose();
    Some([log[(0, 0)], log[(1, 1)], log[(0, 1)]])
}

/// Mean and largest displacement error (px) over the valid nodes, and how many there were.
pub fn displacement_error(
    nodes: &[FieldNode],
    current: &GroundTruth,
    origin: &GroundTruth,
    mut each: impl FnMut(f64),
) -> Option<(f64, f64, usize)> {
    let mut errors = ErrorSum::default();
    for node in nodes {
        if node.status != NodeStatus::Ok as u32 {
            continue;
        }
        let x0 = Vector2::new(f64::from(node.x_px), f64::from(node.y_px));
        let material = inverse(origin, x0)?;
        let truth = forward(current, material) - x0;
        each(errors.add(node, truth));
    }
    errors.mean_max_count()
}

/// The running mean and max of the nodes' displacement errors.
#[derive(Default)]
struct ErrorSum {
    sum: f64,
    max: f64,
    count: usize,
}

impl ErrorSum {
    /// Adds the error of `node`'s measured displacement against `truth` (px), and returns it.
    fn add(&mut self, node: &FieldNode, truth: Vector2<f64>) -> f64 {
        let measured = Vector2::new(f64::from(node.u_px), f64::from(node.v_px));
        let error = (measured - truth).norm();
        self.sum += error;
        self.max = self.max.max(error);
        self.count += 1;
        error
    }

    fn mean_max_count(&self) -> Option<(f64, f64, usize)> {
        (self.count > 0).then(|| (self.sum / self.count as f64, self.max, self.count))
    }
}

/// Mean and largest displacement error (px) over the valid nodes against a finite-element
/// field (the specimen as a structure), node by node: the node at x0 in the origin frame's
/// image is the material point X = φ_o⁻¹(x0), which the current frame shows at φ_k(X). A node
/// on no material (the room behind the specimen) has no truth and is not counted. Also the
/// mean relative gradient F_k F_o⁻¹ of the valid nodes `in_gauge` selects (the control
/// gauge's truth).
pub fn field_errors(
    nodes: &[FieldNode],
    current: &FieldMotion,
    origin: &FieldMotion,
    in_gauge: impl Fn(&FieldNode) -> bool,
    mut each: impl FnMut(f64),
) -> Option<FieldErrors> {
    let mut errors = ErrorSum::default();
    let mut gradient_sum = Matrix2::zeros();
    let mut gauge_nodes = 0usize;
    for node in nodes {
        if node.status != NodeStatus::Ok as u32 {
            continue;
        }
        let x0 = [f64::from(node.x_px), f64::from(node.y_px)];
        let Some(material) = origin.inverse(x0) else {
            continue;
        };
        let (Some(x), Some(f_k), Some(f_o)) = (
            current.forward(material),
            current.gradient(material),
            origin.gradient(material),
        ) else {
            continue;
        };
        let truth = Vector2::new(x[0] - x0[0], x[1] - x0[1]);
        each(errors.add(node, truth));
        let f_k = Matrix2::new(f_k[0][0], f_k[0][1], f_k[1][0], f_k[1][1]);
        let f_o = Matrix2::new(f_o[0][0], f_o[0][1], f_o[1][0], f_o[1][1]);
        if in_gauge(node) {
            gradient_sum += f_k * f_o.try_inverse()?;
            gauge_nodes += 1;
        }
    }
    let (mean_px, max_px, count) = errors.mean_max_count()?;
    Some(FieldErrors {
        mean_px,
        max_px,
        nodes: count,
        mean_gradient: (gauge_nodes > 0).then(|| gradient_sum / gauge_nodes as f64),
    })
}

/// What [`field_errors`] finds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldErrors {
    pub mean_px: f64,
    pub max_px: f64,
    /// Valid nodes on material, compared.
    pub nodes: usize,
    /// The mean relative gradient F_k F_o⁻¹ (image to image) of those in the gauge; None
    /// when none is.
    pub mean_gradient: Option<Matrix2<f64>>,
}

/// Every node's displacement error of a run (px), for its percentiles.
#[derive(Debug)]
pub struct NodeErrors {
    /// In µpx, 3 significant digits, up to 1000 px (a larger error counts as 1000 px).
    histogram: hdrhistogram::Histogram<u64>,
}

const MICRO_PX_MAX: u64 = 1_000_000_000;

impl Default for NodeErrors {
    fn default() -> Self {
        NodeErrors {
            histogram: hdrhistogram::Histogram::new_with_bounds(1, MICRO_PX_MAX, 3)
                .expect("valid histogram bounds"),
        }
    }
}

impl NodeErrors {
    pub fn record(&mut self, error_px: f64) {
        let micro = (error_px * 1e6).round().clamp(1.0, MICRO_PX_MAX as f64) as u64;
        self.histogram.saturating_record(micro);
    }

    pub fn count(&self) -> u64 {
        self.histogram.len()
    }

    /// The error below which a share `quantile` of the nodes lie (px); None before any.
    pub fn quantile_px(&self, quantile: f64) -> Option<f64> {
        (self.count() > 0).then(|| self.histogram.value_at_quantile(quantile) as f64 * 1e-6)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stretch(lx: f64, ly: f64, centre: [f64; 2]) -> GroundTruth {
        GroundTruth {
            deformation_gradient: [lx, 0.0, 0.0, ly],
            translation_px: [0.0, 0.0],
            centre_px: centre,
            ..GroundTruth::IDENTITY
        }
    }

    #[test]
    fn maps_invert_and_compose() {
        let a = 0.3f64;
        let t = GroundTruth {
            deformation_gradient: [1.2 * a.cos(), -a.sin(), 1.2 * a.sin(), a.cos()],
            translation_px: [3.0, -2.0],
            centre_px: [50.0, 40.0],
            ..GroundTruth::IDENTITY
        };
        let p = Vector2::new(10.0, 70.0);
        let back = inverse(&t, forward(&t, p)).unwrap();
        assert!((back - p).norm() < 1e-12);
        // A rotation has zero log strain; a stretch has ln λ.
        let rotation = Matrix2::new(a.cos(), -a.sin(), a.sin(), a.cos());
        let e = log_strain(&rotation).unwrap();
        assert!(e.iter().all(|v| v.abs() < 1e-12), "{e:?}");
        let e = log_strain(&Matrix2::new(2.0, 0.0, 0.0, 0.5)).unwrap();
        assert!((e[0] - 2f64.ln()).abs() < 1e-12 && (e[1] - 0.5f64.ln()).abs() < 1e-12);
        // Relative gradient from λ 1.5 to λ 3 is 2.
        let g =
            relative_gradient(&stretch(3.0, 1.0, [0.0; 2]), &stretch(1.5, 1.0, [0.0; 2])).unwrap();
        assert!((g[(0, 0)] - 2.0).abs() < 1e-12);
    }

    #[test]
    fn displacement_error_of_an_exact_field_is_zero() {
        let origin = stretch(1.1, 1.0, [100.0, 100.0]);
        let current = stretch(1.32, 1.0, [100.0, 100.0]);
        let mut nodes = Vec::new();
        for (x, y) in [(20.0f32, 30.0f32), (150.0, 100.0), (100.0, 180.0)] {
            // Reference image point x0 = φ_o(P); P = (x0 - c)/1.1 + c; now at c + 1.32 (P - c).
            let u = (x - 100.0) * (1.32 / 1.1 - 1.0);
            nodes.push(FieldNode {
                x_px: x,
                y_px: y,
                u_px: u,
                v_px: 0.0,
                status: NodeStatus::Ok as u32,
                ..FieldNode::default()
            });
        }
        nodes.push(FieldNode {
            u_px: 99.0,
            status: NodeStatus::OutsideImage as u32,
            ..FieldNode::default()
        });
        let (mean, max, count) = displacement_error(&nodes, &current, &origin, |_| {}).unwrap();
        assert_eq!(count, 3);
        assert!(mean < 1e-4 && max < 1e-4, "{mean} {max}");
        nodes[0].v_px = 0.5;
        let (_, max, _) = displacement_error(&nodes, &current, &origin, |_| {}).unwrap();
        assert!((max - 0.5).abs() < 1e-4);
    }
}
