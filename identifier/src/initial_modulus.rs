//! The initial shear modulus μ0 of a fitted model: the slope of the shear stress against the
//! amount of shear at the undeformed state (small-strain uniaxial tension gives E = 3 μ0).
//!
//! - A model W(I1, I2) (every one but Ogden): μ0 = 2 (W1 + W2) at I1 = I2 = 3. So
//!   neo-Hookean 2 C10; Mooney-Rivlin and every Rivlin polynomial 2 (C10 + C01); Yeoh and
//!   Biderman 2 (C10 + C01); Isihara 2 (C1 + C3); Rivlin-Saunders 2 (C1 + C2); Gent-Thomas
//!   2 (C1 + C2 / 3); Hart-Smith 2 G (1 + k2 / 3); Alexander 2 (C1 + C2 / γ + C3); Gent μ;
//!   Arruda-Boyce μ √N L⁻¹(1/√N) / 3 ≈ μ (1 + 3/(5N)); Lambert-Diani-Rey 2 (e^a0 + e^b0).
//! - Ogden, W = Σ μp/αp (λ1^αp + λ2^αp + λ3^αp − 3) (the identifier's form, σ_k = Σ μp
//!   (λk^αp − λ3^αp)): μ0 = ½ Σ μp αp.

use crate::models::Model;

/// μ0 in MPa; `None` when the model is not defined at the undeformed state with these
/// parameters.
pub fn initial_shear_modulus_mpa(model: &Model, params: &[f64]) -> Option<f64> {
    let mu0 = match model {
        Model::Ogden(n) => {
            let (mu, alpha) = params.split_at(*n);
            0.5 * mu.iter().zip(alpha).map(|(m, a)| m * a).sum::<f64>()
        }
        _ => {
            let (w1, w2) = model.invariant_derivatives_mpa(params, 3.0, 3.0)?;
            2.0 * (w1 + w2)
        }
    };
    mu0.is_finite().then_some(mu0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::LoadCase;

    /// μ0 from the uniaxial nominal stress's slope at λ = 1: dP/dλ = 3 μ0.
    fn slope_mu0(model: &Model, p: &[f64]) -> f64 {
        let eps = 1e-7;
        model
            .nominal_stress_mpa(p, LoadCase::Uniaxial, 1.0 + eps)
            .unwrap()
            / eps
            / 3.0
    }

    #[test]
    fn the_formula_is_the_small_strain_slope_of_every_model() {
        let cases: Vec<(Model, Vec<f64>)> = vec![
            (Model::NeoHookean, vec![0.2]),
            (Model::Mooney, vec![0.2, 0.05]),
            (Model::Yeoh, vec![0.2, -0.01, 0.001]),
            (Model::Isihara, vec![0.2, 0.01, 0.03]),
            (Model::GentThomas, vec![0.2, 0.3]),
            (Model::HartSmith, vec![0.2, 0.001, 0.5]),
            (Model::Alexander, vec![0.2, 0.001, 0.1, 2.0, 0.02]),
            (Model::Gent, vec![0.4, 50.0]),
            (Model::ArrudaBoyce, vec![0.4, 8.0]),
            (Model::Ogden(3), vec![0.63, 0.0012, -0.01, 1.3, 5.0, -2.0]),
            (
                Model::LambertDianiRey {
                    f_degree: 1,
                    g_degree: 1,
                },
                vec![-1.5, 0.01, -3.0, -0.1],
            ),
        ];
        for (model, p) in cases {
            let mu0 = initial_shear_modulus_mpa(&model, &p).unwrap();
            let slope = slope_mu0(&model, &p);
            assert!(
                (mu0 - slope).abs() < 1e-5 * mu0.abs().max(1e-3),
                "{model}: μ0 {mu0} against the slope {slope}"
            );
        }
        // Ogden's reference values (Ogden 1972 on Treloar): ½ Σ μ α ≈ 0.4.
        let mu0 =
            initial_shear_modulus_mpa(&Model::Ogden(3), &[0.63, 0.0012, -0.01, 1.3, 5.0, -2.0]);
        assert!((mu0.unwrap() - 0.4225).abs() < 1e-12);
    }
}
