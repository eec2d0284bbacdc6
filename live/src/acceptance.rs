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

impl CaseComparison {
    /// `uniaxial to λ 1.74: worst stress error 0.57 % at λ 1.37`.
    pub fn describe(&self, name: &str) -> String {
        format!(
            "{name} to λ {:.2}: worst stress error {:.2} % at λ {:.2}",
            self.max_stretch,
            100.0 * self.max_relative_error,
            self.at_stretch
        )
    }

    /// No error yet, up to `max_stretch`.
    pub(crate) fn up_to(max_stretch: f64) -> Self {
        Self {
            max_stretch,
            max_relative_error: 0.0,
            at_stretch: 1.0,
        }
    }

    /// Keeps `error` at `stretch` when it is the largest so far; a non-finite error counts as
    /// infinite and always takes the place.
    pub(crate) fn record(&mut self, error: f64, stretch: f64) {
        if !error.is_finite() || error > self.max_relative_error {
            self.max_relative_error = if error.is_finite() {
                error
            } else {
                f64::INFINITY
            };
            self.at_stretch = stretch;
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Acceptance {
    pub a: Vec<f64>,
    pub b: Vec<f64>,
    pub uniaxial: Option<CaseComparison>,
    pub equibiaxial: Option<CaseComparison>,
    /// A strain-controlled path off those two (pure shear, any ρ but 1): both nominal
    /// stresses along ln λy = ρ ln λx; `max_stretch` and `at_stretch` are of the larger stretch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub strain_path: Option<CaseComparison>,
    /// The strain path's kind (`pure_shear`, `biaxial`, `uniaxial`) and ρ = ln λy / ln λx,
    /// when the acceptance was along a path.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub strain_path_kind: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub strain_path_ratio: Option<f64>,
    pub tolerance: f64,
    pub passed: bool,
}

/// A law can be compared: both series have coefficients, all finite.
fn usable_law(a: &[f64], b: &[f64]) -> bool {
    !a.is_empty() && !b.is_empty() && a.iter().chain(b).all(|c| c.is_finite())
}

fn compare(
    truth: impl Fn(f64) -> f64,
    predicted: impl Fn(f64) -> f64,
    max_stretch: f64,
) -> CaseComparison {
    let mut worst = CaseComparison::up_to(max_stretch);
    for k in 1..=SAMPLES {
        let stretch = 1.0 + (max_stretch - 1.0) * k as f64 / SAMPLES as f64;
        let t = truth(stretch);
        worst.record(((predicted(stretch) - t) / t).abs(), stretch);
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
    let usable = usable_law(a, b);
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
        strain_path: None,
        strain_path_kind: None,
        strain_path_ratio: None,
        tolerance: TOLERANCE,
        passed,
    }
}

/// The stretches (λx, λy) of the path ln λy = ρ ln λx where the larger one is `larger`.
fn path_point(ratio: f64, larger: f64) -> (f64, f64) {
    let e = larger.ln();
    if ratio.abs() <= 1.0 {
        (larger, (ratio * e).exp())
    } else {
        ((e / ratio).exp(), larger)
    }
}

/// Compares the law against `truth` along a strain-controlled path ρ = ln λy / ln λx up to
/// the larger stretch `max_stretch`: the worst relative error of either nominal stress (a
/// stress below 2 % of the larger one, pure shear's lateral near the start, is not a
/// relative comparison). `kind` names the path (`pure_shear`, `biaxial`, ...).
pub fn accept_path(
    truth: &InvariantLaw,
    a: &[f64],
    b: &[f64],
    kind: &str,
    ratio: f64,
    max_stretch: f64,
) -> Acceptance {
    let identified = InvariantLaw {
        f: InvariantFn::ExpPoly(a.to_vec()),
        g: InvariantFn::ExpPoly(b.to_vec()),
    };
    let usable = usable_law(a, b);
    let strain_path = (usable && max_stretch > 1.0).then(|| {
        let mut worst = CaseComparison::up_to(max_stretch);
        for k in 1..=SAMPLES {
            let larger = 1.0 + (max_stretch - 1.0) * k as f64 / SAMPLES as f64;
            let (lx, ly) = path_point(ratio, larger);
            let t = truth.in_plane_stress(lx, ly).nominal_stress_mpa;
            let p = identified.in_plane_stress(lx, ly).nominal_stress_mpa;
            let scale = t[0].abs().max(t[1].abs());
            for i in 0..2 {
                if t[i].abs() < 0.02 * scale {
                    continue;
                }
                worst.record(((p[i] - t[i]) / t[i]).abs(), larger);
            }
        }
        worst
    });
    let passed = strain_path.is_some_and(|c| c.max_relative_error <= TOLERANCE);
    Acceptance {
        a: a.to_vec(),
        b: b.to_vec(),
        uniaxial: None,
        equibiaxial: None,
        strain_path,
        strain_path_kind: Some(kind.to_string()),
        strain_path_ratio: Some(ratio),
        tolerance: TOLERANCE,
        passed,
    }
}

impl Acceptance {
    /// No case was compared: no usable law, or no test stretched the specimen. Such an
    /// acceptance is not passed.
    pub fn tested_nothing(&self) -> bool {
        self.uniaxial.is_none() && self.equibiaxial.is_none() && self.strain_path.is_none()
    }

    /// Why nothing was compared (meaningful when [`Acceptance::tested_nothing`]).
    pub fn why_nothing_tested(&self) -> &'static str {
        let usable = usable_law(&self.a, &self.b);
        if usable {
            "no test stretched the specimen"
        } else {
            "the identified law has no usable coefficients"
        }
    }

    /// One line naming what was compared, its worst error against the limit, and the verdict:
    /// `pure_shear strain path (ρ 0.00) to λ 1.50: worst stress error 0.36 % at λ 1.42 ->
    /// PASSED (limit 3 %)`.
    pub fn verdict_line(&self) -> String {
        let verdict = if self.passed { "PASSED" } else { "NOT PASSED" };
        let limit = format!("limit {:.0} %", 100.0 * self.tolerance);
        if self.tested_nothing() {
            return format!(
                "acceptance tested nothing ({}) -> {verdict} ({limit})",
                self.why_nothing_tested()
            );
        }
        let cases = match (&self.strain_path_kind, self.strain_path) {
            (Some(kind), Some(c)) => c.describe(&format!(
                "{kind} strain path (ρ {:.2})",
                self.strain_path_ratio.unwrap_or(f64::NAN)
            )),
            _ => [
                ("uniaxial", self.uniaxial),
                ("equibiaxial", self.equibiaxial),
            ]
            .into_iter()
            .map(|(name, c)| match c {
                Some(c) => c.describe(name),
                None => format!("{name}: not tested"),
            })
            .collect::<Vec<_>>()
            .join("; "),
        };
        format!("{cases} -> {verdict} ({limit})")
    }
}

/// The specimen's law and its coefficients (ln f, ln g): an identification that found it.
#[cfg(test)]
pub(crate) fn true_law() -> (InvariantLaw, Vec<f64>, Vec<f64>) {
    let truth = InvariantLaw::smactane();
    let (a, b) = (
        truth.f.coefficients().to_vec(),
        truth.g.coefficients().to_vec(),
    );
    (truth, a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_strain_path_is_compared_on_both_stresses_along_its_ratio() {
        let (truth, a, b) = true_law();
        for ratio in [0.0, 0.5, -0.5, 2.0] {
            let ok = accept_path(&truth, &a, &b, "biaxial", ratio, 1.8);
            assert!(ok.passed, "{ok:?}");
            assert!(ok.strain_path.unwrap().max_relative_error < 1e-12);
        }
        assert_eq!(
            path_point(0.5, 1.8),
            (1.8, 1.8f64.ln().mul_add(0.5, 0.0).exp())
        );
        assert_eq!(path_point(2.0, 1.8).1, 1.8);
        // f 10 % stiffer: off by more than the tolerance.
        let mut a_off = a.clone();
        a_off[0] += 0.1f64.ln_1p();
        let bad = accept_path(&truth, &a_off, &b, "biaxial", 0.5, 1.8);
        assert!(!bad.passed);
        assert!(bad.strain_path.unwrap().max_relative_error > TOLERANCE);
        assert!(!accept_path(&truth, &[f64::NAN], &b, "biaxial", 0.5, 1.8).passed);
    }

    #[test]
    fn the_verdict_line_names_what_was_compared_and_the_limit() {
        let (truth, a, b) = true_law();
        // A pure-shear path: named with its ratio, no "not tested" uniaxial/equibiaxial.
        let ok = accept_path(&truth, &a, &b, "pure_shear", 0.0, 1.5);
        let line = ok.verdict_line();
        assert!(
            line.starts_with(
                "pure_shear strain path (ρ 0.00) to λ 1.50: worst stress error 0.00 %"
            ),
            "{line}"
        );
        assert!(line.ends_with("-> PASSED (limit 3 %)"), "{line}");
        assert!(!line.contains("not tested"), "{line}");
        // The path's error decides: f 10 % stiffer fails, and the line says by how much.
        let mut a_off = a.clone();
        a_off[0] += 0.1f64.ln_1p();
        let bad = accept_path(&truth, &a_off, &b, "pure_shear", 0.0, 1.5);
        let error = bad.strain_path.unwrap().max_relative_error;
        assert!(!bad.passed && error > TOLERANCE);
        let line = bad.verdict_line();
        assert!(
            line.contains(&format!("worst stress error {:.2} %", 100.0 * error)),
            "{line}"
        );
        assert!(line.ends_with("-> NOT PASSED (limit 3 %)"), "{line}");
        // The uniaxial and equibiaxial curves: the untested one is said.
        let line = accept(&truth, &a, &b, Some(3.0), None).verdict_line();
        assert!(
            line.starts_with("uniaxial to λ 3.00: worst stress error 0.00 %"),
            "{line}"
        );
        assert!(
            line.contains("; equibiaxial: not tested -> PASSED"),
            "{line}"
        );
        // Nothing compared: said, and not passed.
        for (nothing, why) in [
            (
                accept_path(&truth, &a, &b, "pure_shear", 0.0, 1.0),
                "no test stretched the specimen",
            ),
            (
                accept(&truth, &a, &b, None, None),
                "no test stretched the specimen",
            ),
            (
                accept(&truth, &[], &[], Some(3.0), None),
                "the identified law has no usable coefficients",
            ),
            (
                accept_path(&truth, &[f64::NAN], &b, "biaxial", 0.5, 1.8),
                "the identified law has no usable coefficients",
            ),
        ] {
            assert!(nothing.tested_nothing() && !nothing.passed, "{nothing:?}");
            assert_eq!(
                nothing.verdict_line(),
                format!("acceptance tested nothing ({why}) -> NOT PASSED (limit 3 %)")
            );
        }
    }

    #[test]
    fn the_true_law_passes_and_a_stiffer_one_fails() {
        let (truth, a, b) = true_law();
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
