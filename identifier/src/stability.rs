//! Drucker stability: d σ : d ε > 0 for every in-plane log-strain increment of a plane-stress
//! incompressible state (dσ3 = 0, the pressure is eliminated by σ3 = 0), i.e. the symmetric part
//! of the 2×2 tangent D_ij = ∂σ_i/∂ε_j is positive definite. Checked along each load case's
//! tension path from λ = 1 to the largest stretch of the data (compression is not checked).

use crate::data::LoadCase;
use crate::models::Model;

/// Number of stretches checked along a path.
pub const STABILITY_STEPS: usize = 200;

/// Stability of one load-case path.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityRange {
    pub case: LoadCase,
    /// Largest stretch checked.
    pub checked_up_to: f64,
    /// Largest stretch up to which every checked point is stable (= `checked_up_to` if stable).
    pub stable_up_to: f64,
    /// First checked stretch where the Drucker condition fails (or the model is undefined).
    pub unstable_from: Option<f64>,
}

/// True if the model is Drucker-stable at in-plane stretches (λ1, λ2).
pub fn drucker_stable_at(model: &Model, params: &[f64], stretch1: f64, stretch2: f64) -> bool {
    const H: f64 = 1e-5; // log-strain step
    let stress = |e1: f64, e2: f64| {
        model.in_plane_cauchy_stress_mpa(params, stretch1 * e1.exp(), stretch2 * e2.exp())
    };
    let (Some(p1), Some(m1), Some(p2), Some(m2)) = (
        stress(H, 0.0),
        stress(-H, 0.0),
        stress(0.0, H),
        stress(0.0, -H),
    ) else {
        return false;
    };
    let d11 = (p1[0] - m1[0]) / (2.0 * H);
    let d21 = (p1[1] - m1[1]) / (2.0 * H);
    let d12 = (p2[0] - m2[0]) / (2.0 * H);
    let d22 = (p2[1] - m2[1]) / (2.0 * H);
    let off = 0.5 * (d12 + d21);
    d11 > 0.0 && d22 > 0.0 && d11 * d22 - off * off > 0.0
}

/// Scans the tension path of `case` from just above 1 to `max_stretch`.
pub fn drucker_stability(
    model: &Model,
    params: &[f64],
    case: LoadCase,
    max_stretch: f64,
) -> StabilityRange {
    assert!(
        max_stretch >= 1.0,
        "max stretch must be >= 1, got {max_stretch}"
    );
    let checked_up_to = max_stretch.max(1.0 + 1e-3);
    let mut stable_up_to = 1.0;
    for k in 1..=STABILITY_STEPS {
        let stretch = 1.0 + (checked_up_to - 1.0) * k as f64 / STABILITY_STEPS as f64;
        let (l1, l2) = case.in_plane_stretches(stretch);
        if !drucker_stable_at(model, params, l1, l2) {
            return StabilityRange {
                case,
                checked_up_to,
                stable_up_to,
                unstable_from: Some(stretch),
            };
        }
        stable_up_to = stretch;
    }
    StabilityRange {
        case,
        checked_up_to,
        stable_up_to,
        unstable_from: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neo_hookean_is_stable_and_negative_modulus_is_not() {
        let ok = drucker_stability(&Model::NeoHookean, &[0.2], LoadCase::Uniaxial, 5.0);
        assert_eq!(ok.unstable_from, None);
        assert_eq!(ok.stable_up_to, 5.0);
        let bad = drucker_stability(&Model::NeoHookean, &[-0.2], LoadCase::Equibiaxial, 5.0);
        assert!(bad.unstable_from.is_some() && bad.stable_up_to == 1.0);
        // Mooney with a negative C01 loses stability in equibiaxial tension at large stretch.
        let m = drucker_stability(&Model::Mooney, &[0.2, -0.05], LoadCase::Equibiaxial, 5.0);
        assert!(m.unstable_from.is_some(), "{m:?}");
    }
}
