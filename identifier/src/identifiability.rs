//! Whether a fit's parameters are identifiable from the data: each parameter's standard
//! deviation below its magnitude (σ < |value|: the data tell it from zero), and the
//! column-scaled Jacobian's condition number below [`MAX_CONDITION_NUMBER`] (the parameters'
//! effects on the residuals are not nearly dependent). Ogden with three terms on uniaxial
//! data alone fails both: several (μ, α) pairs give the same curve. A fit that fails is
//! reported with its reasons and not ranked by AIC (its AIC says how well it fits, not which
//! parameters the material has).

/// Largest condition number of the column-scaled Jacobian of an identifiable fit: a relative
/// change of 1e-8 in the residuals may then move the parameters by their own size.
pub const MAX_CONDITION_NUMBER: f64 = 1e8;

/// What the data say of a fit's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Identifiability {
    /// Condition number of the column-scaled Jacobian at the fitted parameters (∞ when a
    /// parameter has no effect).
    pub condition_number: f64,
    /// The parameters whose σ (times `sigmas`) is not below |value| (or unknown: JᵀJ
    /// singular).
    pub loose_params: Vec<String>,
    /// Standard deviations |value| must exceed (1 for the gauge route).
    pub sigmas: f64,
}

/// The ranks shown for fits in their ranked order: the identifiable ones numbered from 1, None
/// for the others (listed, not ranked). `identify --json`'s and `identify --fields`'s.
pub fn ranks<'a>(fits: impl IntoIterator<Item = &'a Identifiability>) -> Vec<Option<usize>> {
    let mut rank = 0;
    fits.into_iter()
        .map(|id| {
            id.identifiable().then(|| {
                rank += 1;
                rank
            })
        })
        .collect()
}

impl Identifiability {
    /// From the fit's names, values, standard deviations and scaled condition number.
    pub fn new(
        names: &[String],
        values: &[f64],
        stderr: &[Option<f64>],
        condition_number: f64,
    ) -> Identifiability {
        Self::with_sigmas(names, values, stderr, condition_number, 1.0)
    }

    /// As [`Identifiability::new`], a parameter identified only when `sigmas` standard
    /// deviations stay below its magnitude (the field route asks for 2: see
    /// `field_route::SIGMAS_PER_VALUE`).
    pub fn with_sigmas(
        names: &[String],
        values: &[f64],
        stderr: &[Option<f64>],
        condition_number: f64,
        sigmas: f64,
    ) -> Identifiability {
        let loose_params = names
            .iter()
            .zip(values.iter().zip(stderr))
            .filter(|(_, (v, s))| s.is_none_or(|s| s.is_nan() || sigmas * s >= v.abs()))
            .map(|(n, _)| n.clone())
            .collect();
        Identifiability {
            condition_number,
            loose_params,
            sigmas,
        }
    }

    pub fn identifiable(&self) -> bool {
        self.loose_params.is_empty() && self.condition_number <= MAX_CONDITION_NUMBER
    }

    /// Why the parameters are not identifiable (`None` when they are).
    pub fn warning(&self) -> Option<String> {
        if self.identifiable() {
            return None;
        }
        let mut why = Vec::new();
        if !self.loose_params.is_empty() {
            let sigma = match self.sigmas {
                1.0 => "σ".to_string(),
                k => format!("{k}σ"),
            };
            why.push(format!(
                "{sigma} ≥ |value| for {}",
                self.loose_params.join(", ")
            ));
        }
        if self.condition_number.is_nan() || self.condition_number > MAX_CONDITION_NUMBER {
            why.push(format!(
                "condition number {:.1e} of the scaled Jacobian above {MAX_CONDITION_NUMBER:.0e}",
                self.condition_number
            ));
        }
        Some(format!(
            "parameters not identifiable from these data ({}): not ranked; add load cases or take a model with fewer parameters",
            why.join("; ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_loose_parameter_or_a_large_condition_number_is_a_warning() {
        let names = vec!["mu1".to_string(), "alpha1".to_string()];
        let tight = Identifiability::new(&names, &[0.3, 2.0], &[Some(0.01), Some(0.1)], 50.0);
        assert!(tight.identifiable() && tight.warning().is_none());
        let loose = Identifiability::new(&names, &[0.3, -2.0], &[Some(0.01), Some(2.5)], 50.0);
        assert_eq!(loose.loose_params, ["alpha1"]);
        assert!(loose.warning().unwrap().contains("σ ≥ |value| for alpha1"));
        let unknown = Identifiability::new(&names, &[0.3, 2.0], &[Some(0.01), None], 50.0);
        assert!(!unknown.identifiable());
        let ill = Identifiability::new(&names, &[0.3, 2.0], &[Some(0.01), Some(0.1)], 3e9);
        let w = ill.warning().unwrap();
        assert!(w.contains("condition number 3.0e9"), "{w}");
    }
}
