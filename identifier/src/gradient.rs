//! Analytic gradients of the nominal stress with respect to a model's parameters, for the
//! fitting's Jacobian (one pass over the points, no finite differences).
//!
//! The nominal stress along the loaded direction is P = σ1/λ1 with, for invariant models,
//! σ1 = 2 W1 (λ1² − λ3²) − 2 W2 (λ1⁻² − λ3⁻²), so ∂P/∂p = a ∂W1/∂p − b ∂W2/∂p with
//! a = 2 (λ1² − λ3²)/λ1, b = 2 (λ1⁻² − λ3⁻²)/λ1; for Ogden σ1 = Σ μ_k (λ1^α_k − λ3^α_k).
//! [`Model::nominal_stress_mpa`] is this module's value without the gradient. Ogden powers are
//! exp(α ln λ) with ln λ computed once per point ([`Kinematics`]).

pub use crate::kinematics::Kinematics;
use crate::models::{inverse_langevin, Model};

/// Below this |β| the Langevin slope L'(β) = 1/β² − 1/sinh²β is taken from its series
/// 1/3 − β²/15 + 2β⁴/189 (the closed form cancels catastrophically there).
const LANGEVIN_SERIES_BELOW: f64 = 1e-2;

/// L'(β), the slope of the Langevin function.
fn langevin_slope(beta: f64) -> f64 {
    if beta.abs() < LANGEVIN_SERIES_BELOW {
        let b2 = beta * beta;
        1.0 / 3.0 - b2 / 15.0 + 2.0 * b2 * b2 / 189.0
    } else {
        let s = beta.sinh();
        1.0 / (beta * beta) - 1.0 / (s * s)
    }
}

impl Model {
    /// Nominal stress along the loaded direction (MPa, what [`Model::nominal_stress_mpa`]
    /// gives) at a point, and, when `gradient` is given (length = number of parameters), its
    /// gradient ∂P/∂p. `None` outside the model's domain.
    pub fn nominal_stress_at(
        &self,
        p: &[f64],
        point: &Kinematics,
        gradient: Option<&mut [f64]>,
    ) -> Option<f64> {
        let Kinematics {
            stretch1: l1,
            stretch3: l3,
            ..
        } = *point;
        if let Model::Ogden(n) = self {
            let (mu, alpha) = p.split_at(*n);
            let (ln1, ln3) = (point.ln_stretch1, point.ln_stretch3);
            let mut sigma1 = 0.0;
            match gradient {
                None => {
                    for k in 0..*n {
                        sigma1 += mu[k] * ((alpha[k] * ln1).exp() - (alpha[k] * ln3).exp());
                    }
                }
                Some(gradient) => {
                    debug_assert_eq!(gradient.len(), p.len());
                    for k in 0..*n {
                        let (pow1, pow3) = ((alpha[k] * ln1).exp(), (alpha[k] * ln3).exp());
                        sigma1 += mu[k] * (pow1 - pow3);
                        gradient[k] = (pow1 - pow3) / l1;
                        gradient[n + k] = mu[k] * (ln1 * pow1 - ln3 * pow3) / l1;
                    }
                }
            }
            return sigma1.is_finite().then_some(sigma1 / l1);
        }
        let (i1, i2) = (point.i1, point.i2);
        let (w1, w2) = self.invariant_derivatives_mpa(p, i1, i2)?;
        let l3_sq = l3 * l3;
        let sigma1 = 2.0 * w1 * (l1 * l1 - l3_sq) - 2.0 * w2 * (1.0 / (l1 * l1) - 1.0 / l3_sq);
        if !sigma1.is_finite() {
            return None;
        }
        if let Some(gradient) = gradient {
            debug_assert_eq!(gradient.len(), p.len());
            let a = 2.0 * (l1 * l1 - l3_sq) / l1;
            let b = 2.0 * (1.0 / (l1 * l1) - 1.0 / l3_sq) / l1;
            self.invariant_gradient(p, i1, i2, (w1, w2), (a, b), gradient);
        }
        Some(sigma1 / l1)
    }

    /// gradient_k = a ∂W1/∂p_k − b ∂W2/∂p_k at (I1, I2), given W1 and W2 there.
    fn invariant_gradient(
        &self,
        p: &[f64],
        i1: f64,
        i2: f64,
        (w1, w2): (f64, f64),
        (a, b): (f64, f64),
        gradient: &mut [f64],
    ) {
        let x = i1 - 3.0;
        let y = i2 - 3.0;
        match self {
            Model::NeoHookean => gradient[0] = a,
            Model::Mooney => gradient.copy_from_slice(&[a, -b]),
            Model::Rivlin(terms) => {
                for (g, &(i, j)) in gradient.iter_mut().zip(terms) {
                    let mut d = 0.0;
                    if i > 0 {
                        d += a * i as f64 * x.powi(i as i32 - 1) * y.powi(j as i32);
                    }
                    if j > 0 {
                        d -= b * j as f64 * x.powi(i as i32) * y.powi(j as i32 - 1);
                    }
                    *g = d;
                }
            }
            Model::Isihara => gradient.copy_from_slice(&[a, -b * 2.0 * y, -b]),
            Model::RivlinSaunders => {
                gradient.copy_from_slice(&[a, -b, -b * 2.0 * y, -b * 3.0 * y * y])
            }
            Model::GentThomas => gradient.copy_from_slice(&[a, -b / i2]),
            Model::Biderman => gradient.copy_from_slice(&[a, a * 2.0 * x, a * 3.0 * x * x, -b]),
            Model::Yeoh => gradient.copy_from_slice(&[a, a * 2.0 * x, a * 3.0 * x * x]),
            Model::HartSmith => {
                let e = (p[1] * x * x).exp();
                gradient.copy_from_slice(&[
                    a * e - b * p[2] / i2,
                    a * p[0] * x * x * e,
                    -b * p[0] / i2,
                ]);
            }
            Model::Alexander => {
                let e = (p[1] * x * x).exp();
                let d = y + p[3];
                gradient.copy_from_slice(&[
                    a * e,
                    a * p[0] * x * x * e,
                    -b / d,
                    b * p[2] / (d * d),
                    -b,
                ]);
            }
            Model::Gent => {
                let jm = p[1];
                gradient.copy_from_slice(&[
                    a * 0.5 / (1.0 - x / jm),
                    -a * 0.5 * p[0] * x / ((jm - x) * (jm - x)),
                ]);
            }
            Model::ArrudaBoyce => {
                let n = p[1];
                let sqrt_n = n.sqrt();
                let chain_stretch = (i1 / 3.0).sqrt();
                let ratio = chain_stretch / sqrt_n;
                // Defined here: W1 was.
                let beta = inverse_langevin(ratio).unwrap_or(f64::NAN);
                let dbeta_dratio = 1.0 / langevin_slope(beta);
                gradient.copy_from_slice(&[
                    a * sqrt_n * beta / (6.0 * chain_stretch),
                    a * p[0] / (6.0 * chain_stretch) / (2.0 * sqrt_n)
                        * (beta - ratio * dbeta_dratio),
                ]);
            }
            Model::LambertDianiRey { f_degree, .. } => {
                let (ga, gb) = gradient.split_at_mut(f_degree + 1);
                let mut power = 1.0;
                for g in ga.iter_mut() {
                    *g = a * w1 * power;
                    power *= x;
                }
                power = 1.0;
                for g in gb.iter_mut() {
                    *g = -b * w2 * power;
                    power *= y;
                }
            }
            Model::Ogden(_) => unreachable!("Ogden is not an invariant model"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::LoadCase;

    /// Every model's analytic gradient against central differences of the stress itself.
    #[test]
    fn analytic_gradients_match_central_differences() {
        let cases: Vec<(Model, Vec<f64>)> = vec![
            (Model::NeoHookean, vec![0.2]),
            (Model::Mooney, vec![0.2, 0.05]),
            (
                Model::Rivlin(vec![(1, 0), (0, 1), (2, 0), (1, 1), (0, 2)]),
                vec![0.2, 0.05, 0.01, -0.003, 0.002],
            ),
            (Model::Isihara, vec![0.2, 0.01, 0.05]),
            (Model::RivlinSaunders, vec![0.2, 0.05, -0.002, 1e-4]),
            (Model::GentThomas, vec![0.2, 0.1]),
            (Model::Biderman, vec![0.2, -0.002, 5e-5, 0.01]),
            (Model::HartSmith, vec![0.2, 3e-4, 0.5]),
            (Model::Alexander, vec![0.2, 3e-4, 0.1, 2.0, 0.01]),
            (Model::Yeoh, vec![0.2, -0.002, 5e-5]),
            (Model::Ogden(3), vec![0.63, 0.0012, -0.01, 1.3, 5.0, -2.0]),
            (Model::Gent, vec![0.3, 90.0]),
            (Model::ArrudaBoyce, vec![0.3, 30.0]),
            (
                Model::LambertDianiRey {
                    f_degree: 2,
                    g_degree: 2,
                },
                vec![-1.5, -0.01, 2e-4, -3.0, -0.05, 1e-3],
            ),
        ];
        for (model, p) in &cases {
            for case in LoadCase::ALL {
                for stretch in [1.001, 1.3, 2.5, 5.0] {
                    let mut g = vec![0.0; p.len()];
                    let point = Kinematics::of(case, stretch);
                    let value = model.nominal_stress_at(p, &point, Some(&mut g)).unwrap();
                    let reference = model.nominal_stress_mpa(p, case, stretch).unwrap();
                    assert_eq!(
                        value.to_bits(),
                        reference.to_bits(),
                        "{model} {case} {stretch}"
                    );
                    // The plane-stress Cauchy stress (powf for Ogden) agrees to rounding.
                    let (l1, l2) = case.in_plane_stretches(stretch);
                    let cauchy = model.in_plane_cauchy_stress_mpa(p, l1, l2).unwrap()[0] / l1;
                    assert!(
                        (cauchy - value).abs() <= 1e-13 * value.abs(),
                        "{model} {case}"
                    );
                    for k in 0..p.len() {
                        let h = 1e-6 * p[k].abs().max(1e-6);
                        let at = |v: f64| {
                            let mut q = p.clone();
                            q[k] = v;
                            model.nominal_stress_mpa(&q, case, stretch).unwrap()
                        };
                        let fd = (at(p[k] + h) - at(p[k] - h)) / (2.0 * h);
                        // Truncation (relative) and the difference's rounding (ε |P| / h).
                        let tolerance =
                            1e-5 * fd.abs().max(g[k].abs()) + 1e-14 * (1.0 + reference.abs()) / h;
                        assert!(
                            (fd - g[k]).abs() <= tolerance,
                            "{model} {case} λ={stretch} ∂P/∂p{k}: analytic {} vs difference {fd}",
                            g[k]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn langevin_slope_series_joins_the_closed_form() {
        let b = LANGEVIN_SERIES_BELOW;
        let s = b.sinh();
        let closed = 1.0 / (b * b) - 1.0 / (s * s);
        assert!((langevin_slope(b * (1.0 - 1e-12)) - closed).abs() < 1e-9);
    }
}
