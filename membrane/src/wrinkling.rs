//! Tension-field relaxation of the membrane energy (Pipkin's relaxed energy for an isotropic
//! incompressible sheet).
//!
//! Where the full law would give a compressive principal stress, the sheet wrinkles: it
//! contracts freely across the major stretch, so its energy is that of uniaxial tension along
//! the major principal stretch, w = φ(μ1) with μ1 = λ1² the major eigenvalue of C and
//! φ(μ) = W_UT(√μ). The relaxed energy meets the full one with its first derivatives on the
//! taut boundary (σ2 = 0 is the uniaxial state), so the stress is continuous across it.
//! φ'(μ) = σ_UT / (2 λ²) = (1 − μ^(−3/2)) (W1 + W2 μ^(−1/2)) at I1 = μ + 2 μ^(−1/2),
//! I2 = 1/μ + 2 μ^(1/2).

use crate::constitutive::{combine, outer, Jet, Voigt};
use crate::law::{MembraneLaw, SheetLaw};

/// Major eigenvalue μ1 of C as a jet in c = [C11, C22, C12]; `None` at equal eigenvalues.
pub(crate) fn major_eigenvalue_jet(c: &Voigt) -> Option<Jet> {
    let d = 0.5 * (c[0] - c[1]);
    let r = (d * d + c[2] * c[2]).sqrt();
    if r.is_nan() || r <= 0.0 {
        return None;
    }
    let r3 = r * r * r;
    let v = [0.5, -0.5, 0.0];
    let e3 = [0.0, 0.0, 1.0];
    Some(Jet {
        value: 0.5 * (c[0] + c[1]) + r,
        gradient: [0.5 + d / (2.0 * r), 0.5 - d / (2.0 * r), c[2] / r],
        hessian: combine(&[
            (c[2] * c[2] / r3, outer(&v, &v)),
            (-d * c[2] / r3, outer(&v, &e3)),
            (-d * c[2] / r3, outer(&e3, &v)),
            (d * d / r3, outer(&e3, &e3)),
        ]),
    })
}

/// φ'(μ) and φ''(μ) of an invariant law, MPa.
pub(crate) fn invariant_uniaxial_derivatives<L: MembraneLaw + ?Sized>(
    law: &L,
    mu: f64,
) -> Option<(f64, f64)> {
    let root = mu.sqrt();
    let (i1, i2) = (mu + 2.0 / root, 1.0 / mu + 2.0 * root);
    let (w1, w2) = law.first_derivatives_mpa(i1, i2)?;
    let [w11, w12, w22] = law.second_derivatives_mpa(i1, i2)?;
    let m32 = mu.powf(-1.5);
    let a = 1.0 - m32;
    let b = w1 + w2 / root;
    let di1 = 1.0 - m32;
    let di2 = -1.0 / (mu * mu) + 1.0 / root;
    let dw1 = w11 * di1 + w12 * di2;
    let dw2 = w12 * di1 + w22 * di2;
    let db = dw1 + dw2 / root - 0.5 * w2 * m32;
    Some((a * b, 1.5 * mu.powf(-2.5) * b + a * db))
}

/// The relaxed energy's jet in c (gradient and Hessian; the value is not needed).
pub(crate) fn relaxed_energy_jet<L: SheetLaw + ?Sized>(law: &L, c: &Voigt) -> Option<Jet> {
    let mu = major_eigenvalue_jet(c)?;
    let (d1, d2) = law.uniaxial_energy_derivatives_mpa(mu.value)?;
    let g = mu.gradient;
    Some(Jet {
        value: f64::NAN,
        gradient: std::array::from_fn(|k| d1 * g[k]),
        hessian: combine(&[(d2, outer(&g, &g)), (d1, mu.hessian)]),
    })
}
