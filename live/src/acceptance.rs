//! Does the identified law give back the specimen's? The run's acceptance: the stresses the
//! identified f and g predict in uniaxial and equibiaxial tension stay within a tolerance of
//! the true law's over the stretch range each test covered.

use identifier::law::{InvariantFn, InvariantLaw};
use serde::Serialize;

/// Relative stress tolerance of the acceptance (3 %).
pub const TOLERANCE: f64 = 0.03;
/// Stretches sampled per range.
const SAMPLES: usize = 200;

/// The comparison over one load case.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CaseComparison {
    pub max_stretch: f64,
    /// Largest |predicted − true| / true nominal stress over (1, max_stretch].
    pub max_relative_error: f64,
    /// Where it occurs.
    pub at_stretch: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Acceptance {
    pub a: Vec<f64>,
    pub b: Vec<f64>,
    pub uniaxial: Option<CaseComparison>,
    pub equibiaxial: Option<CaseComparison>,
    pub tolerance: f64,
    pub passed: bool,
}

fn compare(
    truth: impl Fn(f64) -> f64,
    predicted: impl Fn(f64) -> f64,
    max_stretch: f64,
) -> CaseComparison {
    let mut worst = CaseComparison {
        max_stretch,
        max_relative_error: 0.0,
        at_stretch: 1.0,
    };
    for k in 1..=SAMPLES {
        let stretch = 1.0 + (max_stretch - 1.0) * k as f64 / SAMPLES as f64;
        let t = truth(stretch);
        let error = ((predicted(stretch) - t) / t).abs();
        if !error.is_finite() || error > worst.max_relative_error {
            worst.max_relative_error = if error.is_finite() {
                error
            } else {
                f64::INFINITY
            };
            worst.at_stretch = stretch;
        }
    }
    worst
}

/// Compares the law with ln f = Σ a_i (I1 − 3)^i, ln g = Σ b_i (I2 − 3)^i against `truth`
/// over the tested ranges (None: that case was not tested).
pub fn accept(
    truth: &InvariantLaw,
    a: &[f64],
    b: &[f64],
    uniaxial_max_stretch: Option<f64>,
    equibiaxial_max_stretch: Option<f64>,
) -> Acceptance {
    let identified = InvariantLaw {
        f: InvariantFn::ExpPoly(a.to_vec()),
        g: InvariantFn::ExpPoly(b.to_vec()),
    };
    let usable = !a.is_empty() && !b.is_empty() && a.iter().chain(b).all(|c| c.is_finite());
    let uniaxial = uniaxial_max_stretch.filter(|_| usable).map(|max| {
        compare(
            |l| truth.uniaxial_nominal_stress_mpa(l),
            |l| identified.uniaxial_nominal_stress_mpa(l),
            max,
        )
    });
    let equibiaxial = equibiaxial_max_stretch.filter(|_| usable).map(|max| {
        compare(
            |l| truth.equibiaxial_nominal_stress_mpa(l),
            |l| identified.equibiaxial_nominal_stress_mpa(l),
            max,
        )
    });
    let within = |c: Option<CaseComparison>| c.is_some_and(|c| c.max_relative_error <= TOLERANCE);
    let passed = usable
        && (uniaxial_max_stretch.is_none() || within(uniaxial))
        && (equibiaxial_max_stretch.is_none() || within(equibiaxial))
        && (uniaxial.is_some() || equibiaxial.is_some());
    Acceptance {
        a: a.to_vec(),
        b: b.to_vec(),
        uniaxial,
        equibiaxial,
        tolerance: TOLERANCE,
        passed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_true_law_passes_and_a_stiffer_one_fails() {
        let truth = InvariantLaw::smactane();
        let a = truth.f.coefficients().to_vec();
        let b = truth.g.coefficients().to_vec();
        let ok = accept(&truth, &a, &b, Some(3.0), Some(2.0));
        assert!(ok.passed, "{ok:?}");
        assert!(ok.uniaxial.unwrap().max_relative_error < 1e-12);
        // f 5 % stiffer: exp(a0 + ln 1.05).
        let mut stiffer = a.clone();
        stiffer[0] += 1.05f64.ln();
        let bad = accept(&truth, &stiffer, &b, Some(3.0), Some(2.0));
        assert!(!bad.passed);
        assert!(bad.uniaxial.unwrap().max_relative_error > 0.03);
        // Nothing identified: not passed.
        assert!(!accept(&truth, &[], &[], Some(3.0), None).passed);
        assert!(!accept(&truth, &a, &b, None, None).passed);
    }
}
