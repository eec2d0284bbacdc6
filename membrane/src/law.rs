//! The sheet's law as the solver sees it: W1 = ∂W/∂I1 and W2 = ∂W/∂I2 of an incompressible
//! invariant-based potential, and their derivatives W11, W12, W22 for the consistent tangent.
//!
//! One definition per model: `material::InvariantLaw` implements [`MembraneLaw`] with its own
//! analytic f', g'; any other potential (a catalogue model of the identifier with its parameters)
//! is one closure `(I1, I2) -> Option<(W1, W2)>` wrapped in [`InvariantDerivatives`], whose
//! second derivatives are central differences of that same closure (relative step 1e-5: the
//! tangent is then exact to ~1e-10 relative, enough for Newton's quadratic convergence down to
//! the tolerance).

use crate::constitutive::{Matrix3, PointFailure, Voigt};
use material::InvariantLaw;

/// Second derivatives of W, MPa: [W11, W12, W22].
pub type SecondDerivativesMpa = [f64; 3];

/// A hyperelastic incompressible potential W(I1, I2) through its derivatives, stresses in MPa.
pub trait MembraneLaw {
    /// (W1, W2) in MPa at (I1, I2); `None` outside the law's domain.
    fn first_derivatives_mpa(&self, i1: f64, i2: f64) -> Option<(f64, f64)>;

    /// [W11, W12, W22] in MPa; by default central differences of
    /// [`MembraneLaw::first_derivatives_mpa`] (W12 the mean of the two cross differences).
    fn second_derivatives_mpa(&self, i1: f64, i2: f64) -> Option<SecondDerivativesMpa> {
        let h1 = RELATIVE_STEP * i1.abs().max(1.0);
        let h2 = RELATIVE_STEP * i2.abs().max(1.0);
        let (a1p, a2p) = self.first_derivatives_mpa(i1 + h1, i2)?;
        let (a1m, a2m) = self.first_derivatives_mpa(i1 - h1, i2)?;
        let (b1p, b2p) = self.first_derivatives_mpa(i1, i2 + h2)?;
        let (b1m, b2m) = self.first_derivatives_mpa(i1, i2 - h2)?;
        let w11 = (a1p - a1m) / (2.0 * h1);
        let w22 = (b2p - b2m) / (2.0 * h2);
        let w12 = 0.5 * ((b1p - b1m) / (2.0 * h2) + (a2p - a2m) / (2.0 * h1));
        let out = [w11, w12, w22];
        out.iter().all(|v| v.is_finite()).then_some(out)
    }
}

/// The sheet's law at a point, as the element needs it: the reduced energy w(c) of the
/// plane-stress incompressible state, c = [C11, C22, C12], to second order, and the
/// uniaxial energy φ(μ) = W_UT(√μ) that wrinkling relaxes to. Every [`MembraneLaw`] is one
/// (analytic in W1, W2, W11, W12, W22); so is a law given by its principal stresses
/// ([`crate::principal::PrincipalStresses`], e.g. Ogden).
pub trait SheetLaw {
    /// (∂w/∂c, ∂²w/∂c²), MPa.
    fn energy_derivatives(&self, c: &Voigt) -> Result<(Voigt, Matrix3), PointFailure>;
    /// (φ'(μ), φ''(μ)), MPa, μ = λ² of uniaxial tension.
    fn uniaxial_energy_derivatives_mpa(&self, mu: f64) -> Option<(f64, f64)>;
}

impl<T: MembraneLaw + ?Sized> SheetLaw for T {
    fn energy_derivatives(&self, c: &Voigt) -> Result<(Voigt, Matrix3), PointFailure> {
        crate::constitutive::invariant_energy_jet(self, c).map(|jet| (jet.gradient, jet.hessian))
    }

    fn uniaxial_energy_derivatives_mpa(&self, mu: f64) -> Option<(f64, f64)> {
        crate::wrinkling::invariant_uniaxial_derivatives(self, mu)
    }
}

/// Step of the default second derivatives, relative to the invariant.
const RELATIVE_STEP: f64 = 1e-5;

impl MembraneLaw for InvariantLaw {
    fn first_derivatives_mpa(&self, i1: f64, i2: f64) -> Option<(f64, f64)> {
        if !(i1 > 0.0 && i2 > 0.0) {
            return None;
        }
        let pair = (self.f.value_mpa(i1), self.g.value_mpa(i2));
        (pair.0.is_finite() && pair.1.is_finite()).then_some(pair)
    }

    fn second_derivatives_mpa(&self, i1: f64, i2: f64) -> Option<SecondDerivativesMpa> {
        if !(i1 > 0.0 && i2 > 0.0) {
            return None;
        }
        let out = [self.f.derivative_mpa(i1), 0.0, self.g.derivative_mpa(i2)];
        out.iter().all(|v| v.is_finite()).then_some(out)
    }
}

/// Any potential given by its (W1, W2): e.g. an identifier catalogue model and its parameters,
/// `InvariantDerivatives(|i1, i2| model.invariant_derivatives_mpa(&params, i1, i2))`.
#[derive(Clone, Copy, Debug)]
pub struct InvariantDerivatives<F>(pub F);

impl<F: Fn(f64, f64) -> Option<(f64, f64)>> MembraneLaw for InvariantDerivatives<F> {
    fn first_derivatives_mpa(&self, i1: f64, i2: f64) -> Option<(f64, f64)> {
        (self.0)(i1, i2).filter(|(w1, w2)| w1.is_finite() && w2.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_second_derivatives_match_the_analytic_ones() {
        let law = InvariantLaw::smactane();
        let closure = InvariantDerivatives(|i1, i2| law.first_derivatives_mpa(i1, i2));
        for &(i1, i2) in &[(3.0, 3.0), (4.2, 3.7), (9.0, 6.5)] {
            let exact = law.second_derivatives_mpa(i1, i2).unwrap();
            let fd = closure.second_derivatives_mpa(i1, i2).unwrap();
            for k in 0..3 {
                let scale = exact[0].abs().max(exact[2].abs());
                assert!(
                    (exact[k] - fd[k]).abs() < 1e-9 * scale,
                    "{k}: {exact:?} {fd:?}"
                );
            }
        }
    }
}
