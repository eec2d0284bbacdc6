//! A law given by its in-plane principal Cauchy stresses σ1, σ2 (σ3 = 0, λ3 = 1/(λ1 λ2)), for
//! potentials that are not invariant-based (Ogden): one closure, e.g. a catalogue model's
//! `|l1, l2| model.in_plane_cauchy_stress_mpa(&params, l1, l2)`.
//!
//! With μ_k = λ_k² the eigenvalues of C, w = ψ(μ1, μ2) and ψ_k = ∂ψ/∂μ_k = σ_k / (2 μ_k).
//! In c: ∂w/∂c = ψ_1 ∇μ1 + ψ_2 ∇μ2 (μ1,2 = t/2 ± r), and
//! ∂²w/∂c² = Σ ψ_kl ∇μk ∇μlᵀ + (ψ_1 − ψ_2) ∂²r/∂c², ψ_kl by central differences of the
//! closure (relative step 1e-5). At equal stretches (r → 0, the undeformed state) the last
//! term's limit is used: 2(ψ11 + ψ12) g gᵀ + 2(ψ11 − ψ12)(v vᵀ + e3 e3ᵀ), g = ∇t/2.

use crate::constitutive::{combine, outer, Matrix3, PointFailure, Voigt};
use crate::law::SheetLaw;

/// A law from its principal in-plane Cauchy stresses, MPa; `None` outside its domain.
#[derive(Clone, Copy, Debug)]
pub struct PrincipalStresses<F>(pub F);

/// Relative step of the differences.
const RELATIVE_STEP: f64 = 1e-5;
/// Below this r / tr C the stretches count as equal (the tangent's limit is used).
const EQUAL_STRETCHES: f64 = 1e-6;

impl<F: Fn(f64, f64) -> Option<[f64; 2]>> PrincipalStresses<F> {
    /// [ψ_1, ψ_2] at (μ1, μ2).
    fn first(&self, mu1: f64, mu2: f64) -> Option<[f64; 2]> {
        if !(mu1 > 0.0 && mu2 > 0.0) {
            return None;
        }
        let s = (self.0)(mu1.sqrt(), mu2.sqrt())?;
        let out = [0.5 * s[0] / mu1, 0.5 * s[1] / mu2];
        out.iter().all(|v| v.is_finite()).then_some(out)
    }

    /// [ψ11, ψ12, ψ22] at (μ1, μ2).
    fn second(&self, mu1: f64, mu2: f64) -> Option<[f64; 3]> {
        let (h1, h2) = (RELATIVE_STEP * mu1, RELATIVE_STEP * mu2);
        let (p1, m1) = (self.first(mu1 + h1, mu2)?, self.first(mu1 - h1, mu2)?);
        let (p2, m2) = (self.first(mu1, mu2 + h2)?, self.first(mu1, mu2 - h2)?);
        let d1 = [(p1[0] - m1[0]) / (2.0 * h1), (p1[1] - m1[1]) / (2.0 * h1)];
        let d2 = [(p2[0] - m2[0]) / (2.0 * h2), (p2[1] - m2[1]) / (2.0 * h2)];
        Some([d1[0], 0.5 * (d2[0] + d1[1]), d2[1]])
    }
}

impl<F: Fn(f64, f64) -> Option<[f64; 2]>> SheetLaw for PrincipalStresses<F> {
    fn energy_derivatives(&self, c: &Voigt) -> Result<(Voigt, Matrix3), PointFailure> {
        let det_c = c[0] * c[1] - c[2] * c[2];
        if det_c.is_nan() || det_c <= 0.0 {
            return Err(PointFailure::Inverted { det_c });
        }
        let t = c[0] + c[1];
        let d = 0.5 * (c[0] - c[1]);
        let r = (d * d + c[2] * c[2]).sqrt();
        let (mu1, mu2) = (0.5 * t + r, 0.5 * t - r);
        let outside = PointFailure::OutsideDomain {
            i1: t + 1.0 / det_c,
            i2: t / det_c + det_c,
        };
        let psi = self.first(mu1, mu2).ok_or(outside)?;
        let [a11, a12, a22] = self.second(mu1, mu2).ok_or(outside)?;
        let g = [0.5, 0.5, 0.0];
        let v = [0.5, -0.5, 0.0];
        let e3 = [0.0, 0.0, 1.0];
        let grad_r = if r > 0.0 {
            [d / (2.0 * r), -d / (2.0 * r), c[2] / r]
        } else {
            [0.0; 3]
        };
        let gradient =
            std::array::from_fn(|k| (psi[0] + psi[1]) * g[k] + (psi[0] - psi[1]) * grad_r[k]);
        let hessian = if r > EQUAL_STRETCHES * t {
            let g1: Voigt = std::array::from_fn(|k| g[k] + grad_r[k]);
            let g2: Voigt = std::array::from_fn(|k| g[k] - grad_r[k]);
            let r3 = r * r * r;
            combine(&[
                (a11, outer(&g1, &g1)),
                (a12, outer(&g1, &g2)),
                (a12, outer(&g2, &g1)),
                (a22, outer(&g2, &g2)),
                ((psi[0] - psi[1]) * c[2] * c[2] / r3, outer(&v, &v)),
                (-(psi[0] - psi[1]) * d * c[2] / r3, outer(&v, &e3)),
                (-(psi[0] - psi[1]) * d * c[2] / r3, outer(&e3, &v)),
                ((psi[0] - psi[1]) * d * d / r3, outer(&e3, &e3)),
            ])
        } else {
            let (a, b) = (0.5 * (a11 + a22), a12);
            combine(&[
                (2.0 * (a + b), outer(&g, &g)),
                (2.0 * (a - b), outer(&v, &v)),
                (2.0 * (a - b), outer(&e3, &e3)),
            ])
        };
        Ok((gradient, hessian))
    }

    fn uniaxial_energy_derivatives_mpa(&self, mu: f64) -> Option<(f64, f64)> {
        let slope = |m: f64| -> Option<f64> {
            let stretch = m.sqrt();
            let sigma = (self.0)(stretch, 1.0 / stretch.sqrt())?[0];
            let out = 0.5 * sigma / m;
            out.is_finite().then_some(out)
        };
        let h = RELATIVE_STEP * mu;
        let second = (slope(mu + h)? - slope(mu - h)?) / (2.0 * h);
        Some((slope(mu)?, second))
    }
}
