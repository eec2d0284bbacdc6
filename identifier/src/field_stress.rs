//! The stress of a measured node, from its in-plane deformation gradient and a law, with no
//! solver (paper section 4.c): an incompressible sheet in plane stress has λ3 = 1/det F, and
//! its in-plane Cauchy stress is the law's principal stresses (σ3 = 0) along the principal
//! directions of B = F Fᵀ. The nominal (first Piola-Kirchhoff) stress is P = σ F⁻ᵀ (J = 1):
//! a force per reference area, what a virtual-work sum over the reference mesh integrates.

use crate::models::Model;

/// A 2x2 matrix, row-major: `m[i][j]`, i the row.
pub type Mat2 = [[f64; 2]; 2];

/// The stress state of one node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeStress {
    /// In-plane principal stretches, λ1 ≥ λ2, and the thickness stretch λ3 = 1/(λ1 λ2).
    pub stretches: [f64; 3],
    /// In-plane Cauchy stress, MPa (current configuration).
    pub cauchy_mpa: Mat2,
    /// In-plane nominal (first Piola-Kirchhoff) stress, MPa: force per reference area,
    /// `nominal_mpa[i][j]` the force along i per reference area normal to j.
    pub nominal_mpa: Mat2,
}

/// Why a node has no stress.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum NodeStressError {
    #[error("deformation gradient {f:?}: not finite")]
    NotFinite { f: Mat2 },
    #[error("deformation gradient {f:?}: det F = {det} (inverted or flattened material)")]
    NotInvertible { f: Mat2, det: f64 },
    #[error("stretches {stretches:?} are outside the model's domain")]
    OutsideDomain { stretches: [f64; 3] },
}

fn det(m: &Mat2) -> f64 {
    m[0][0] * m[1][1] - m[0][1] * m[1][0]
}

fn mul(a: &Mat2, b: &Mat2) -> Mat2 {
    std::array::from_fn(|i| std::array::from_fn(|j| a[i][0] * b[0][j] + a[i][1] * b[1][j]))
}

fn transpose(m: &Mat2) -> Mat2 {
    [[m[0][0], m[1][0]], [m[0][1], m[1][1]]]
}

/// Eigenvalues (descending) and the unit eigenvector of the larger one of a symmetric 2x2.
fn symmetric_eigen(s: &Mat2) -> ([f64; 2], [f64; 2]) {
    let mean = 0.5 * (s[0][0] + s[1][1]);
    let half_diff = 0.5 * (s[0][0] - s[1][1]);
    let radius = half_diff.hypot(s[0][1]);
    // The angle of the first principal direction: tan 2θ = 2 s01 / (s00 − s11).
    let theta = if radius == 0.0 {
        0.0
    } else {
        0.5 * s[0][1].atan2(half_diff)
    };
    ([mean + radius, mean - radius], [theta.cos(), theta.sin()])
}

/// In-plane principal stretches λ1 ≥ λ2 of the deformation gradient `f` (the square roots
/// of the eigenvalues of B = F Fᵀ); None when F is not finite or not invertible.
pub fn principal_stretches(f: &Mat2) -> Option<[f64; 2]> {
    let det_f = det(f);
    if f.iter().flatten().any(|v| !v.is_finite()) || det_f.is_nan() || det_f <= 0.0 {
        return None;
    }
    let ([b1, b2], _) = symmetric_eigen(&mul(f, &transpose(f)));
    Some([b1.sqrt(), b2.max(0.0).sqrt()])
}

/// What a node's stress owes to its kinematics alone: its stretches and, per in-plane
/// principal direction n_α of B = F Fᵀ, the tensor K_α = (n_α ⊗ n_α) F⁻ᵀ, so that the nominal
/// stress under any law is P = s1 K1 + s2 K2 with s1, s2 the law's principal Cauchy stresses
/// (J = 1). A fit that tries many laws on one field computes this once per node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeKinematics {
    /// In-plane principal stretches, λ1 ≥ λ2, and the thickness stretch λ3 = 1/(λ1 λ2).
    pub stretches: [f64; 3],
    /// Unit principal directions n1, n2 (current configuration), n2 ⟂ n1.
    pub directions: [[f64; 2]; 2],
    /// K1, K2: the nominal stress per unit principal Cauchy stress.
    pub nominal_per_cauchy: [Mat2; 2],
}

/// The kinematics of a node whose in-plane deformation gradient is `f` (F = I + ∇u, reference
/// to current).
pub fn node_kinematics(f: &Mat2) -> Result<NodeKinematics, NodeStressError> {
    if f.iter().flatten().any(|v| !v.is_finite()) {
        return Err(NodeStressError::NotFinite { f: *f });
    }
    let det_f = det(f);
    if det_f.is_nan() || det_f <= 0.0 {
        return Err(NodeStressError::NotInvertible { f: *f, det: det_f });
    }
    let b = mul(f, &transpose(f));
    let ([b1, b2], n1) = symmetric_eigen(&b);
    let n2 = [-n1[1], n1[0]];
    // F⁻ᵀ = cof(F) / det F.
    let inverse_transpose = [
        [f[1][1] / det_f, -f[1][0] / det_f],
        [-f[0][1] / det_f, f[0][0] / det_f],
    ];
    let dyad = |n: [f64; 2]| std::array::from_fn(|i| std::array::from_fn(|j| n[i] * n[j]));
    Ok(NodeKinematics {
        stretches: [b1.sqrt(), b2.max(0.0).sqrt(), 1.0 / det_f],
        directions: [n1, n2],
        nominal_per_cauchy: [n1, n2].map(|n| mul(&dyad(n), &inverse_transpose)),
    })
}

impl NodeKinematics {
    /// The law's in-plane principal Cauchy stresses s1, s2 (MPa) at the node's stretches.
    pub fn principal_cauchy_mpa(&self, model: &Model, p: &[f64]) -> Option<[f64; 2]> {
        model.in_plane_cauchy_stress_mpa(p, self.stretches[0], self.stretches[1])
    }
}

/// The stress of a node whose in-plane deformation gradient is `f` (F = I + ∇u, reference to
/// current), under `model` with parameters `p` (MPa).
pub fn node_stress(model: &Model, p: &[f64], f: &Mat2) -> Result<NodeStress, NodeStressError> {
    let k = node_kinematics(f)?;
    let stretches = k.stretches;
    let [s1, s2] = k
        .principal_cauchy_mpa(model, p)
        .ok_or(NodeStressError::OutsideDomain { stretches })?;
    let [n1, n2] = k.directions;
    // σ = s1 n1⊗n1 + s2 n2⊗n2; P = J σ F⁻ᵀ = s1 K1 + s2 K2.
    let cauchy_mpa: Mat2 =
        std::array::from_fn(|i| std::array::from_fn(|j| s1 * n1[i] * n1[j] + s2 * n2[i] * n2[j]));
    let [k1, k2] = k.nominal_per_cauchy;
    let nominal_mpa: Mat2 =
        std::array::from_fn(|i| std::array::from_fn(|j| s1 * k1[i][j] + s2 * k2[i][j]));
    Ok(NodeStress {
        stretches,
        cauchy_mpa,
        nominal_mpa,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::LoadCase;

    fn rotation(angle: f64) -> Mat2 {
        [[angle.cos(), -angle.sin()], [angle.sin(), angle.cos()]]
    }

    fn models() -> Vec<(Model, Vec<f64>)> {
        vec![
            (Model::NeoHookean, vec![0.4]),
            (Model::Mooney, vec![0.3, 0.05]),
            (Model::Yeoh, vec![0.3, -0.01, 0.002]),
            (Model::Ogden(3), vec![0.63, 0.0012, -0.01, 1.3, 5.0, -2.0]),
            (Model::Gent, vec![0.4, 40.0]),
        ]
    }

    /// A canonical load case along x gives the catalogue's own nominal stress along x, and
    /// zero shear.
    #[test]
    fn canonical_states_give_the_models_nominal_stress() {
        for (model, p) in models() {
            for case in LoadCase::ALL {
                for stretch in [1.1, 1.6, 2.5] {
                    let (l1, l2) = case.in_plane_stretches(stretch);
                    let s = node_stress(&model, &p, &[[l1, 0.0], [0.0, l2]]).unwrap();
                    let expected = model.nominal_stress_mpa(&p, case, stretch).unwrap();
                    let scale = expected.abs().max(1e-6);
                    assert!(
                        (s.nominal_mpa[0][0] - expected).abs() < 1e-9 * scale,
                        "{model} {case:?} λ {stretch}: {} vs {expected}",
                        s.nominal_mpa[0][0]
                    );
                    assert_eq!(s.nominal_mpa[0][1], 0.0);
                    assert!((s.stretches[2] - 1.0 / (l1 * l2)).abs() < 1e-12);
                }
            }
        }
    }

    /// Frame indifference: rotating the current configuration (F → R F) rotates the Cauchy
    /// stress (σ → R σ Rᵀ) and the nominal stress (P → R P); rotating the reference (F → F Q)
    /// leaves σ unchanged.
    #[test]
    fn rotations_of_either_configuration_act_as_they_must() {
        let f = [[1.7, 0.25], [-0.1, 0.8]];
        for (model, p) in models() {
            let s = node_stress(&model, &p, &f).unwrap();
            let r = rotation(0.7);
            let turned = node_stress(&model, &p, &mul(&r, &f)).unwrap();
            let expected_sigma = mul(&mul(&r, &s.cauchy_mpa), &transpose(&r));
            let expected_p = mul(&r, &s.nominal_mpa);
            let q = rotation(-1.2);
            let reference_turned = node_stress(&model, &p, &mul(&f, &q)).unwrap();
            for i in 0..2 {
                for j in 0..2 {
                    let scale = s.cauchy_mpa[0][0].abs().max(1.0);
                    assert!((turned.cauchy_mpa[i][j] - expected_sigma[i][j]).abs() < 1e-9 * scale);
                    assert!((turned.nominal_mpa[i][j] - expected_p[i][j]).abs() < 1e-9 * scale);
                    assert!(
                        (reference_turned.cauchy_mpa[i][j] - s.cauchy_mpa[i][j]).abs()
                            < 1e-9 * scale
                    );
                }
            }
            // σ is symmetric, P Fᵀ = σ (balance of angular momentum).
            assert!((s.cauchy_mpa[0][1] - s.cauchy_mpa[1][0]).abs() < 1e-12);
            let back = mul(&s.nominal_mpa, &transpose(&f));
            let gap = (0..4).map(|k| (back[k / 2][k % 2] - s.cauchy_mpa[k / 2][k % 2]).abs());
            assert!(gap.fold(0.0, f64::max) < 1e-9);
        }
    }

    #[test]
    fn a_bad_gradient_is_refused_with_the_reason() {
        let model = Model::NeoHookean;
        let p = [0.4];
        assert!(matches!(
            node_stress(&model, &p, &[[f64::NAN, 0.0], [0.0, 1.0]]),
            Err(NodeStressError::NotFinite { .. })
        ));
        let error = node_stress(&model, &p, &[[1.0, 2.0], [1.0, 2.0]]).unwrap_err();
        assert!(error.to_string().contains("det F = 0"), "{error}");
        assert!(matches!(
            node_stress(&Model::Gent, &[0.4, 2.0], &[[3.0, 0.0], [0.0, 1.0]]),
            Err(NodeStressError::OutsideDomain { .. })
        ));
    }
}
