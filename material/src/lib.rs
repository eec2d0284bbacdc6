//! Incompressible invariant-based hyperelastic law W(I1, I2) of the paper (section 4, eqs 18-25).
//!
//! ∂W/∂I1 = f(I1) and ∂W/∂I2 = g(I2) are uncoupled (eq. 18). Each is an [`InvariantFn`]:
//! either the Lambert-Diani & Rey exponential form exp Σ a_i (I − 3)^i (eqs 22, 25) or the
//! Hart-Smith inverse-power form Σ c_i / I^i (eq. 24). Stresses are in MPa (the units of the
//! coefficients), stretches are dimensionless, sections are in mm², forces in N.
//!
//! The material is incompressible: λ1 λ2 λ3 = 1. Cauchy stress (eqs 16-17), principal axes:
//! σ_i = 2 f λ_i² − 2 g λ_i⁻² − p, with p fixed by the free surface σ3 = 0.

#![forbid(unsafe_code)]

/// One of the two invariant derivatives f(I1) or g(I2).
#[derive(Clone, Debug, PartialEq)]
pub enum InvariantFn {
    /// exp(Σ_{i=0..n} coeffs[i] (I − 3)^i), eqs 22 and 25 (dimensionless exponent, value in MPa).
    ExpPoly(Vec<f64>),
    /// Σ_{i=0..n} coeffs[i] / I^i, eq. 24 (coefficients in MPa).
    InversePower(Vec<f64>),
}

impl InvariantFn {
    /// Value in MPa at invariant `invariant` (I1 or I2, ≥ 3 for an incompressible material).
    pub fn value_mpa(&self, invariant: f64) -> f64 {
        assert!(
            invariant.is_finite() && invariant > 0.0,
            "invariant must be positive, got {invariant}"
        );
        match self {
            InvariantFn::ExpPoly(a) => poly(a, invariant - 3.0).exp(),
            InvariantFn::InversePower(c) => poly(c, 1.0 / invariant),
        }
    }

    /// Derivative with respect to the invariant, in MPa.
    pub fn derivative_mpa(&self, invariant: f64) -> f64 {
        assert!(
            invariant.is_finite() && invariant > 0.0,
            "invariant must be positive, got {invariant}"
        );
        match self {
            InvariantFn::ExpPoly(a) => {
                let x = invariant - 3.0;
                poly_derivative(a, x) * poly(a, x).exp()
            }
            InvariantFn::InversePower(c) => {
                let y = 1.0 / invariant;
                // d/dI Σ c_i y^i = Σ i c_i y^(i−1) · (−y²)
                -poly_derivative(c, y) * y * y
            }
        }
    }

    /// The coefficients (a_i, b_i or c_i), lowest order first.
    pub fn coefficients(&self) -> &[f64] {
        match self {
            InvariantFn::ExpPoly(a) | InvariantFn::InversePower(a) => a,
        }
    }
}

/// Σ coeffs[i] x^i (Horner).
fn poly(coeffs: &[f64], x: f64) -> f64 {
    coeffs.iter().rev().fold(0.0, |acc, &c| acc * x + c)
}

/// d/dx Σ coeffs[i] x^i.
fn poly_derivative(coeffs: &[f64], x: f64) -> f64 {
    coeffs
        .iter()
        .enumerate()
        .skip(1)
        .rev()
        .fold(0.0, |acc, (i, &c)| acc * x + i as f64 * c)
}

/// Invariants (I1, I2) of an incompressible state given its three principal stretches.
pub fn invariants(stretches: [f64; 3]) -> (f64, f64) {
    let i1 = stretches.iter().map(|l| l * l).sum();
    let i2 = stretches.iter().map(|l| 1.0 / (l * l)).sum();
    (i1, i2)
}

/// Principal Cauchy and nominal stresses of a plane-stress (σ3 = 0) in-plane state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InPlaneStress {
    /// Cauchy (true) stresses σ1, σ2 along the in-plane principal stretches, MPa.
    pub cauchy_stress_mpa: [f64; 2],
    /// Nominal (first Piola-Kirchhoff) stresses P_i = σ_i / λ_i, MPa (force / reference section).
    pub nominal_stress_mpa: [f64; 2],
    /// Through-thickness stretch λ3 = 1 / (λ1 λ2).
    pub stretch3: f64,
}

/// Why coefficients do not make a law ([`InvariantLaw::exp_poly`]).
#[derive(Clone, Debug, PartialEq)]
pub enum LawError {
    /// The coefficients of `which` (f or g) are empty or not finite.
    Coefficients {
        which: &'static str,
        coefficients: Vec<f64>,
    },
    /// The law's small-strain Young's modulus is not positive.
    Stiffness { young_mpa: f64 },
}

impl std::fmt::Display for LawError {
    fn fmt(&self, out: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LawError::Coefficients {
                which,
                coefficients,
            } => write!(
                out,
                "{which} coefficients {coefficients:?}: expected one or more finite numbers"
            ),
            LawError::Stiffness { young_mpa } => write!(
                out,
                "the law has a small-strain Young's modulus of {young_mpa} MPa: expected a positive stiffness"
            ),
        }
    }
}

impl std::error::Error for LawError {}

/// The invariant-based law: ∂W/∂I1 = f(I1), ∂W/∂I2 = g(I2).
#[derive(Clone, Debug, PartialEq)]
pub struct InvariantLaw {
    pub f: InvariantFn,
    pub g: InvariantFn,
}

impl InvariantLaw {
    /// Smactane™ of the paper: f from Table 3 (n = 2), g from Table 4 exponential form (ii) n = 2.
    /// Small-strain Young's modulus 6 (f(3) + g(3)) ≈ 3.85 MPa.
    pub fn smactane() -> Self {
        InvariantLaw {
            f: InvariantFn::ExpPoly(vec![-1.27, -2.52e-2, 1.40e-3]),
            g: InvariantFn::ExpPoly(vec![-1.02, -3.92e-3, -5.30e-4]),
        }
    }

    /// The law ln f = Σ a_i (I1 − 3)^i, ln g = Σ b_i (I2 − 3)^i from its coefficients, checked:
    /// each list non-empty and finite, and a positive small-strain stiffness. The error says
    /// which part is wrong (`f`, `g`, or the stiffness) for the caller to name its own input.
    pub fn exp_poly(a: &[f64], b: &[f64]) -> Result<InvariantLaw, LawError> {
        for (which, coefficients) in [("f", a), ("g", b)] {
            if coefficients.is_empty() || coefficients.iter().any(|c| !c.is_finite()) {
                return Err(LawError::Coefficients {
                    which,
                    coefficients: coefficients.to_vec(),
                });
            }
        }
        let law = InvariantLaw {
            f: InvariantFn::ExpPoly(a.to_vec()),
            g: InvariantFn::ExpPoly(b.to_vec()),
        };
        let young_mpa = law.small_strain_young_modulus_mpa();
        if !(young_mpa.is_finite() && young_mpa > 0.0) {
            return Err(LawError::Stiffness { young_mpa });
        }
        Ok(law)
    }

    /// Small-strain Young's modulus E = 6 (f(3) + g(3)), MPa.
    pub fn small_strain_young_modulus_mpa(&self) -> f64 {
        6.0 * (self.f.value_mpa(3.0) + self.g.value_mpa(3.0))
    }

    /// General in-plane state: principal stretches λ1, λ2 (> 0), λ3 = 1/(λ1 λ2), σ3 = 0:
    /// σ_k = 2 f (λ_k² − λ3²) − 2 g (λ_k⁻² − λ3⁻²), k = 1, 2.
    pub fn in_plane_stress(&self, stretch1: f64, stretch2: f64) -> InPlaneStress {
        assert!(
            stretch1 > 0.0 && stretch1.is_finite(),
            "stretch1 must be positive, got {stretch1}"
        );
        assert!(
            stretch2 > 0.0 && stretch2.is_finite(),
            "stretch2 must be positive, got {stretch2}"
        );
        let stretch3 = 1.0 / (stretch1 * stretch2);
        let (i1, i2) = invariants([stretch1, stretch2, stretch3]);
        let f = self.f.value_mpa(i1);
        let g = self.g.value_mpa(i2);
        let l3_sq = stretch3 * stretch3;
        let sigma = |l: f64| 2.0 * f * (l * l - l3_sq) - 2.0 * g * (1.0 / (l * l) - 1.0 / l3_sq);
        let cauchy = [sigma(stretch1), sigma(stretch2)];
        InPlaneStress {
            cauchy_stress_mpa: cauchy,
            nominal_stress_mpa: [cauchy[0] / stretch1, cauchy[1] / stretch2],
            stretch3,
        }
    }

    /// Uniaxial tension Cauchy stress σ_UT of eq. 19, MPa.
    pub fn uniaxial_cauchy_stress_mpa(&self, stretch: f64) -> f64 {
        assert!(
            stretch > 0.0 && stretch.is_finite(),
            "stretch must be positive, got {stretch}"
        );
        let i1 = stretch * stretch + 2.0 / stretch;
        let i2 = 1.0 / (stretch * stretch) + 2.0 * stretch;
        2.0 * self.f.value_mpa(i1) * (stretch * stretch - 1.0 / stretch)
            - 2.0 * self.g.value_mpa(i2) * (1.0 / (stretch * stretch) - stretch)
    }

    /// Equibiaxial tension Cauchy stress σ_BT of eq. 19, MPa.
    pub fn equibiaxial_cauchy_stress_mpa(&self, stretch: f64) -> f64 {
        assert!(
            stretch > 0.0 && stretch.is_finite(),
            "stretch must be positive, got {stretch}"
        );
        let l2 = stretch * stretch;
        let i1 = 2.0 * l2 + 1.0 / (l2 * l2);
        let i2 = 2.0 / l2 + l2 * l2;
        2.0 * self.f.value_mpa(i1) * (l2 - 1.0 / (l2 * l2))
            - 2.0 * self.g.value_mpa(i2) * (1.0 / l2 - l2 * l2)
    }

    /// Uniaxial nominal stress P = σ_UT / λ, MPa.
    pub fn uniaxial_nominal_stress_mpa(&self, stretch: f64) -> f64 {
        self.uniaxial_cauchy_stress_mpa(stretch) / stretch
    }

    /// Equibiaxial nominal stress P = σ_BT / λ, MPa.
    pub fn equibiaxial_nominal_stress_mpa(&self, stretch: f64) -> f64 {
        self.equibiaxial_cauchy_stress_mpa(stretch) / stretch
    }

    /// Pure shear (planar tension, λ2 = 1) nominal stress along λ, MPa.
    pub fn pure_shear_nominal_stress_mpa(&self, stretch: f64) -> f64 {
        self.in_plane_stress(stretch, 1.0).nominal_stress_mpa[0]
    }
}

/// Force in N carried by a face of current section `current_section_mm2` under Cauchy stress
/// `cauchy_stress_mpa` (MPa · mm² = N). Equivalently nominal stress × reference section.
pub fn force_n(cauchy_stress_mpa: f64, current_section_mm2: f64) -> f64 {
    assert!(
        current_section_mm2 >= 0.0,
        "section must be non-negative, got {current_section_mm2}"
    );
    cauchy_stress_mpa * current_section_mm2
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coefficients_are_checked() {
        let smactane = InvariantLaw::smactane();
        let (a, b) = (smactane.f.coefficients(), smactane.g.coefficients());
        assert_eq!(InvariantLaw::exp_poly(a, b), Ok(smactane.clone()));
        assert!(matches!(
            InvariantLaw::exp_poly(&[f64::NAN, 1.0], b),
            Err(LawError::Coefficients { which: "f", .. })
        ));
        assert!(matches!(
            InvariantLaw::exp_poly(a, &[]),
            Err(LawError::Coefficients { which: "g", .. })
        ));
        // ln f = 800: f overflows to infinity, no stiffness.
        assert!(matches!(
            InvariantLaw::exp_poly(&[800.0], b),
            Err(LawError::Stiffness { .. })
        ));
    }

    #[test]
    fn small_strain_limit_gives_young_modulus() {
        let law = InvariantLaw::smactane();
        let e_mpa = law.small_strain_young_modulus_mpa();
        assert!((e_mpa - 3.85).abs() < 0.01, "E = {e_mpa}");
        let eps = 1e-6;
        let slope = law.uniaxial_cauchy_stress_mpa(1.0 + eps) / eps;
        assert!(
            (slope - e_mpa).abs() < 1e-4 * e_mpa,
            "slope {slope} vs E {e_mpa}"
        );
        // Equibiaxial initial slope is 2E for an incompressible material.
        let slope_bt = law.equibiaxial_cauchy_stress_mpa(1.0 + eps) / eps;
        assert!(
            (slope_bt - 2.0 * e_mpa).abs() < 1e-4 * e_mpa,
            "slope {slope_bt}"
        );
    }

    #[test]
    fn eq19_matches_general_in_plane_state() {
        let law = InvariantLaw::smactane();
        for k in 0..50 {
            let l = 1.0 + 0.05 * k as f64;
            let ut = law.in_plane_stress(l, 1.0 / l.sqrt());
            assert!((ut.cauchy_stress_mpa[0] - law.uniaxial_cauchy_stress_mpa(l)).abs() < 1e-10);
            assert!(
                ut.cauchy_stress_mpa[1].abs() < 1e-10,
                "lateral stress must vanish"
            );
            let bt = law.in_plane_stress(l, l);
            assert!((bt.cauchy_stress_mpa[0] - law.equibiaxial_cauchy_stress_mpa(l)).abs() < 1e-10);
            assert!((bt.cauchy_stress_mpa[1] - bt.cauchy_stress_mpa[0]).abs() < 1e-12);
            assert!((bt.stretch3 * l * l - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let fns = [
            InvariantFn::ExpPoly(vec![-1.27, -2.52e-2, 1.40e-3]),
            InvariantFn::InversePower(vec![-9.53e-3, 2.89, -4.39]),
        ];
        for func in &fns {
            for &i in &[3.0, 4.5, 10.0] {
                let h = 1e-6;
                let fd = (func.value_mpa(i + h) - func.value_mpa(i - h)) / (2.0 * h);
                assert!(
                    (fd - func.derivative_mpa(i)).abs() < 1e-6,
                    "{func:?} at {i}"
                );
            }
        }
    }

    #[test]
    fn force_is_nominal_times_reference_section() {
        let law = InvariantLaw::smactane();
        let (l1, l2) = (1.4, 1.1);
        let s = law.in_plane_stress(l1, l2);
        let (width0_mm, thickness0_mm) = (10.0, 2.0);
        let current_section_mm2 = width0_mm * l2 * thickness0_mm * s.stretch3;
        let f_current = force_n(s.cauchy_stress_mpa[0], current_section_mm2);
        let f_nominal = s.nominal_stress_mpa[0] * width0_mm * thickness0_mm;
        assert!((f_current - f_nominal).abs() < 1e-9);
    }
}
