//! Models the field's forces do not tell apart (issue 25: "refuse to rank models it cannot
//! tell apart"). The field route ranks its identifiable fits by BIC; a fit whose BIC is within
//! [`TOLD_APART_BIC`] of the lowest is not told apart from it. Among those, the one with the
//! fewest parameters goes first (then the lowest BIC): more parameters must earn their place
//! with very strong evidence, Occam's window. The window is reported with how far its laws'
//! nominal stresses spread over the states the field reached, the uncertainty the choice
//! leaves.
//!
//! Why: on the live bench's equibiaxial cruciform test (`tests/field_route.rs`), Hart-Smith
//! came within −7.5 to +6.5 of Mooney-Rivlin's BIC over 10 runs and ranked first in 5 of them,
//! 10-16 % off Smactane's uniaxial stress at λ 1.35: their forces differ by less than the load
//! cells' noise (σ 2 N; noise-free, on the same grid, Mooney-Rivlin leads by 50 to 100,
//! `identifier/tests/suite/field_resolution.rs`), and the states where their laws part are a
//! few fillet nodes. Kass and Raftery's scale (J. Am. Stat. Assoc. 90, 1995): a BIC difference
//! above 10 is very strong evidence, 6 to 10 strong; the route's equations are not independent
//! (`field_route::information_criteria`), so it asks for the former.

use crate::data::LoadCase;
use crate::models::Model;
use crate::reach::Reach;

/// A BIC within this of the lowest is not told apart from it.
pub const TOLD_APART_BIC: f64 = 10.0;
/// Stretches sampled per case for the spread.
const SAMPLES: usize = 100;

/// The ranked models not told apart from the lowest BIC (more than one), the first the one
/// chosen, and their nominal stresses' spread.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ModelWindow {
    /// Names, the chosen one first, then by BIC.
    pub models: Vec<String>,
    /// Each one's BIC minus the lowest.
    pub delta_bic: Vec<f64>,
    pub bic_window: f64,
    /// Largest (max − min) / |mean| of their nominal stresses over the reach, uniaxial and
    /// pure shear to the largest major stretch, equibiaxial to the largest minor one (None: a
    /// case not reached or a law without a stress there).
    pub spread_uniaxial: Option<f64>,
    pub spread_equibiaxial: Option<f64>,
    pub spread_pure_shear: Option<f64>,
}

impl ModelWindow {
    /// One line for the logs and the tables.
    pub fn describe(&self) -> String {
        format!(
            "{} not told apart by the forces (BIC within {} of the lowest: {}); {} has the \
             fewest parameters and goes first; their nominal stresses differ by up to {} over \
             the states reached",
            self.models.join(", "),
            self.bic_window,
            self.delta_bic
                .iter()
                .map(|d| format!("{d:+.1}"))
                .collect::<Vec<_>>()
                .join(", "),
            self.models[0],
            self.spreads()
        )
    }

    /// The chosen model's line: `the forces do not tell it apart from hart-smith: stresses
    /// differ by up to 8.1 % uniaxial, … pure shear; it has the fewest parameters`.
    pub fn versus_chosen(&self) -> String {
        format!(
            "the forces do not tell it apart from {}: stresses differ by up to {}; it has the \
             fewest parameters",
            self.models[1..].join(", "),
            self.spreads()
        )
    }

    /// `8.1 % uniaxial, 0.4 % equibiaxial, - pure shear` (`-`: not reached).
    fn spreads(&self) -> String {
        let spread = |s: Option<f64>| s.map_or("-".to_string(), |s| format!("{:.1} %", 100.0 * s));
        format!(
            "{} uniaxial, {} equibiaxial, {} pure shear",
            spread(self.spread_uniaxial),
            spread(self.spread_equibiaxial),
            spread(self.spread_pure_shear)
        )
    }
}

/// One ranked candidate: its model, parameters and BIC.
pub struct Candidate<'a> {
    pub model: &'a Model,
    pub params: &'a [f64],
    pub bic: f64,
}

/// The order of `candidates` (indices): by BIC, except that among those within
/// [`TOLD_APART_BIC`] of the lowest the one with the fewest parameters comes first; and the
/// window when it holds more than one; the spreads over each case's `reach`.
pub fn rank(candidates: &[Candidate], reach: &Reach) -> (Vec<usize>, Option<ModelWindow>) {
    let mut order: Vec<usize> = (0..candidates.len()).collect();
    order.sort_by(|&a, &b| candidates[a].bic.total_cmp(&candidates[b].bic));
    let Some(&best) = order.first() else {
        return (order, None);
    };
    let lowest = candidates[best].bic;
    let within = order
        .iter()
        .take_while(|&&i| candidates[i].bic <= lowest + TOLD_APART_BIC)
        .count();
    let parameters = |i: usize| candidates[i].params.len();
    if let Some(pos) = (0..within).min_by_key(|&p| (parameters(order[p]), p)) {
        let chosen = order.remove(pos);
        order.insert(0, chosen);
    }
    if within < 2 {
        return (order, None);
    }
    let members = &order[..within];
    let spread = |case: LoadCase| spread(candidates, members, case, reach.case(case));
    let window = ModelWindow {
        models: members
            .iter()
            .map(|&i| candidates[i].model.name())
            .collect(),
        delta_bic: members
            .iter()
            .map(|&i| candidates[i].bic - lowest)
            .collect(),
        bic_window: TOLD_APART_BIC,
        spread_uniaxial: spread(LoadCase::Uniaxial),
        spread_equibiaxial: spread(LoadCase::Equibiaxial),
        spread_pure_shear: spread(LoadCase::PureShear),
    };
    (order, Some(window))
}

/// Largest (max − min) / |mean| over (1, top] of the members' nominal stresses in `case`.
fn spread(candidates: &[Candidate], members: &[usize], case: LoadCase, top: f64) -> Option<f64> {
    if top <= 1.0 {
        return None;
    }
    let mut worst = 0.0_f64;
    for k in 1..=SAMPLES {
        let stretch = 1.0 + (top - 1.0) * k as f64 / SAMPLES as f64;
        let stresses = members
            .iter()
            .map(|&i| {
                let c = &candidates[i];
                c.model.nominal_stress_mpa(c.params, case, stretch)
            })
            .collect::<Option<Vec<f64>>>()?;
        let (lo, hi) = stresses
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &s| {
                (lo.min(s), hi.max(s))
            });
        let mean = stresses.iter().sum::<f64>() / stresses.len() as f64;
        if mean != 0.0 {
            worst = worst.max((hi - lo) / mean.abs());
        }
    }
    Some(worst)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn candidate<'a>(model: &'a Model, params: &'a [f64], bic: f64) -> Candidate<'a> {
        Candidate { model, params, bic }
    }

    /// A reach: uniaxial and pure shear to `major`, equibiaxial to `minor`.
    fn reach(major: f64, minor: f64) -> Reach {
        Reach {
            max_stretches: [major, minor],
            uniaxial: major,
            equibiaxial: minor,
            pure_shear: major,
        }
    }

    #[test]
    fn the_fewest_parameters_lead_a_window_and_strong_evidence_still_wins() {
        let (mooney, hart_smith, neo) = (Model::Mooney, Model::HartSmith, Model::NeoHookean);
        let (pm, ph, pn) = ([0.26, 0.39], [0.23, 2.7, 5.3], [0.6]);
        // Hart-Smith 7.5 below Mooney-Rivlin: not told apart; neo-Hookean far behind.
        let fits = [
            candidate(&neo, &pn, 300.0),
            candidate(&hart_smith, &ph, 258.9),
            candidate(&mooney, &pm, 266.4),
        ];
        let (order, window) = rank(&fits, &reach(1.35, 1.08));
        assert_eq!(order, vec![2, 1, 0]);
        let window = window.unwrap();
        assert_eq!(window.models, vec!["mooney", "hart-smith"]);
        assert!((window.delta_bic[0] - 7.5).abs() < 1e-9 && window.delta_bic[1] == 0.0);
        // The two laws part at the largest stretches: a spread of several per cent.
        let uniaxial = window.spread_uniaxial.unwrap();
        assert!(uniaxial > 0.03 && uniaxial < 0.5, "{uniaxial}");
        assert!(window.describe().contains("mooney, hart-smith"));
        // Very strong evidence (more than the window) for more parameters: by BIC.
        let fits = [
            candidate(&mooney, &pm, 266.4),
            candidate(&hart_smith, &ph, 250.0),
        ];
        let (order, window) = rank(&fits, &reach(1.35, 1.08));
        assert_eq!((order, window), (vec![1, 0], None));
        // A lone fit, and none.
        assert_eq!(rank(&fits[..1], &reach(1.35, 1.08)), (vec![0], None));
        assert_eq!(rank(&[], &reach(1.35, 1.08)), (vec![], None));
    }

    #[test]
    fn equal_parameters_in_the_window_keep_the_bic_order() {
        let (mooney, neo) = (Model::Mooney, Model::NeoHookean);
        let ogden = Model::Ogden(1);
        let fits = [
            candidate(&mooney, &[0.26, 0.39], 100.0),
            candidate(&ogden, &[1.2, 2.0], 95.0),
            candidate(&neo, &[0.6], 120.0),
        ];
        let (order, window) = rank(&fits, &reach(1.3, 1.0));
        assert_eq!(order, vec![1, 0, 2]);
        let window = window.unwrap();
        // Equibiaxial not reached (λ2 1.0): no spread there.
        assert_eq!(window.spread_equibiaxial, None);
        assert!(window.spread_uniaxial.unwrap() > 0.0);
    }
}
