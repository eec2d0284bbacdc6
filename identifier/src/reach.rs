//! How far a field went: the largest principal stretches of its nodes, and per canonical
//! load case the largest stretch at which it held a state of that case.
//!
//! A node's state (λ1 ≥ λ2, in plane) has the biaxiality m = ln λ2 / ln λ1: −½ in uniaxial
//! tension (λ2 = λ1^−½), 0 in pure shear (λ2 = 1), 1 in equibiaxial tension. A state belongs to
//! a case when its m lies within [`BIAXIALITY_TOLERANCE`] of the case's, and the case's reach
//! is the largest λ1 among its states. A law identified from the field is judged over those
//! reaches: up to them it is interpolated between measured states, beyond them extrapolated.
//! The largest λ1 of any state is not a case's reach: on a bench whose uniaxial strip went to
//! λ 1.8 while the cruciform's pure-shear states stayed below 1.35, pure shear at 1.8 lies
//! beyond every measured (I1, I2) (its I2 exceeds the strip's), where even an exact-data
//! Mooney-Rivlin fit of the paper's Smactane law is 1.7 % off.

use crate::data::LoadCase;
use crate::field_stress::principal_stretches;
use crate::section_cut::FieldGrid;
use serde::{Deserialize, Serialize};

/// How far a state's biaxiality may be from a case's to count as one of its states.
pub const BIAXIALITY_TOLERANCE: f64 = 0.1;
/// Stretches at most this far above 1 carry no biaxiality worth the name (their m is noise):
/// a case reached no further is not reached.
pub const MIN_STRETCH: f64 = 1.005;

/// The reach of a set of nodes' states.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reach {
    /// The largest major and largest minor in-plane principal stretch over the states ([1, 1]
    /// for none).
    pub max_stretches: [f64; 2],
    /// The largest λ1 of a uniaxial state (1 when none).
    pub uniaxial: f64,
    /// The largest λ1 of an equibiaxial state (1 when none).
    pub equibiaxial: f64,
    /// The largest λ1 of a pure-shear state (1 when none).
    pub pure_shear: f64,
}

impl Default for Reach {
    fn default() -> Self {
        Reach {
            max_stretches: [1.0, 1.0],
            uniaxial: 1.0,
            equibiaxial: 1.0,
            pure_shear: 1.0,
        }
    }
}

impl Reach {
    /// The reach of the measured nodes of `grids`.
    pub fn of_grids<'a>(grids: impl IntoIterator<Item = &'a FieldGrid>) -> Reach {
        Reach::of_states(
            grids
                .into_iter()
                .flat_map(|g| g.gradients.iter().flatten())
                .filter_map(principal_stretches),
        )
    }

    /// The reach of in-plane principal stretch pairs [λ1, λ2], λ1 ≥ λ2.
    pub fn of_states(states: impl IntoIterator<Item = [f64; 2]>) -> Reach {
        let mut reach = Reach::default();
        for [major, minor] in states {
            reach.max_stretches[0] = reach.max_stretches[0].max(major);
            reach.max_stretches[1] = reach.max_stretches[1].max(minor);
            if major.is_nan() || major <= MIN_STRETCH {
                continue;
            }
            let m = minor.ln() / major.ln();
            for case in LoadCase::ALL {
                if (m - biaxiality(case)).abs() <= BIAXIALITY_TOLERANCE {
                    let top = reach.case_mut(case);
                    *top = top.max(major);
                }
            }
        }
        reach
    }

    /// The case's reach: the largest stretch of its states, 1 when it held none.
    pub fn case(&self, case: LoadCase) -> f64 {
        match case {
            LoadCase::Uniaxial => self.uniaxial,
            LoadCase::Equibiaxial => self.equibiaxial,
            LoadCase::PureShear => self.pure_shear,
        }
    }

    fn case_mut(&mut self, case: LoadCase) -> &mut f64 {
        match case {
            LoadCase::Uniaxial => &mut self.uniaxial,
            LoadCase::Equibiaxial => &mut self.equibiaxial,
            LoadCase::PureShear => &mut self.pure_shear,
        }
    }
}

/// The case's biaxiality ln λ2 / ln λ1.
pub fn biaxiality(case: LoadCase) -> f64 {
    match case {
        LoadCase::Uniaxial => -0.5,
        LoadCase::Equibiaxial => 1.0,
        LoadCase::PureShear => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_case_reaches_as_far_as_its_own_states() {
        let reach = Reach::of_states([
            [1.8, 1.8_f64.powf(-0.5)],
            [1.3, 1.0],
            [1.14, 1.13],
            // Between pure shear and equibiaxial: none of the three.
            [1.6, 1.6_f64.powf(0.5)],
        ]);
        assert_eq!(reach.max_stretches, [1.8, 1.6_f64.powf(0.5)]);
        assert_eq!(reach.case(LoadCase::Uniaxial), 1.8);
        assert_eq!(reach.case(LoadCase::PureShear), 1.3);
        assert_eq!(reach.case(LoadCase::Equibiaxial), 1.14);
    }

    #[test]
    fn states_near_the_origin_reach_no_case() {
        let reach = Reach::of_states([[1.004, 0.9], [1.0, 1.0]]);
        assert_eq!(reach.case(LoadCase::Uniaxial), 1.0);
        assert_eq!(reach.case(LoadCase::PureShear), 1.0);
        assert_eq!(reach.case(LoadCase::Equibiaxial), 1.0);
        assert_eq!(reach.max_stretches, [1.004, 1.0]);
    }

    #[test]
    fn a_case_state_counts_within_the_tolerance_only() {
        let l = 1.4_f64;
        let inside = l.powf(BIAXIALITY_TOLERANCE * 0.9);
        let outside = l.powf(BIAXIALITY_TOLERANCE * 1.1);
        assert_eq!(Reach::of_states([[l, inside]]).pure_shear, l);
        assert_eq!(Reach::of_states([[l, outside]]).pure_shear, 1.0);
    }

    #[test]
    fn canonical_states_have_their_case_biaxiality() {
        for case in LoadCase::ALL {
            let (l1, l2) = case.in_plane_stretches(1.5);
            let (major, minor) = (l1.max(l2), l1.min(l2));
            assert!(
                (minor.ln() / major.ln() - biaxiality(case)).abs() < 1e-12,
                "{case:?}"
            );
        }
    }
}
