//! The documented limit on the points a fit uses: above it, the fit runs on a deterministic
//! subsample that keeps every load path's shape: each curve keeps a share of the limit in
//! proportion to its length (at least its two ends), evenly spaced along its rows, in order,
//! first and last point always kept (general biaxial states likewise, two points each). The
//! caller says so (stderr and JSON), never silently.

use crate::data::{BiaxialState, Curve, MIN_POINTS_PER_CURVE};

/// Default largest number of points fitted (over all curves) before subsampling.
pub const DEFAULT_MAX_FIT_POINTS: usize = 200_000;

/// What a subsampling did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Subsample {
    /// Points of the data (every curve).
    pub points_total: usize,
    /// Points fitted.
    pub points_fitted: usize,
    /// The limit that was exceeded.
    pub max_points: usize,
}

/// The curves with at most about `max_points` points in all (never fewer than
/// [`MIN_POINTS_PER_CURVE`] per curve), or `None` when they hold no more than `max_points`.
pub fn subsample(curves: &[Curve], max_points: usize) -> Option<(Vec<Curve>, Subsample)> {
    subsample_data(curves, &[], max_points).map(|(curves, _, s)| (curves, s))
}

/// [`subsample`] of curves and general biaxial states together: a state is two fitted
/// points (P1, P2); the states, in their order, are one more load path sharing the limit.
pub fn subsample_data(
    curves: &[Curve],
    states: &[BiaxialState],
    max_points: usize,
) -> Option<(Vec<Curve>, Vec<BiaxialState>, Subsample)> {
    let total: usize = curves.iter().map(Curve::len).sum::<usize>() + 2 * states.len();
    if total <= max_points {
        return None;
    }
    let share = |len: usize| (max_points as u128 * len as u128 / total as u128) as usize;
    let kept: Vec<Curve> = curves
        .iter()
        .map(|curve| {
            let keep = share(curve.len()).clamp(MIN_POINTS_PER_CURVE, curve.len());
            let rows = evenly_spaced_rows(curve.len(), keep);
            Curve {
                case: curve.case,
                stretch: rows.iter().map(|&i| curve.stretch[i]).collect(),
                nominal_stress_mpa: rows.iter().map(|&i| curve.nominal_stress_mpa[i]).collect(),
                reference_rows_dropped: curve.reference_rows_dropped,
            }
        })
        .collect();
    let kept_states: Vec<BiaxialState> = if states.len() <= MIN_POINTS_PER_CURVE {
        states.to_vec()
    } else {
        let keep = (share(2 * states.len()) / 2).clamp(MIN_POINTS_PER_CURVE, states.len());
        evenly_spaced_rows(states.len(), keep)
            .into_iter()
            .map(|i| states[i])
            .collect()
    };
    let points_fitted = kept.iter().map(Curve::len).sum::<usize>() + 2 * kept_states.len();
    Some((
        kept,
        kept_states,
        Subsample {
            points_total: total,
            points_fitted,
            max_points,
        },
    ))
}

/// `keep` row indices of `0..len`, strictly increasing, evenly spaced, with 0 and len − 1
/// (2 ≤ keep ≤ len).
fn evenly_spaced_rows(len: usize, keep: usize) -> Vec<usize> {
    debug_assert!(2 <= keep && keep <= len);
    let (span, steps) = (len - 1, keep - 1);
    (0..keep).map(|j| (j * span + steps / 2) / steps).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::LoadCase;

    fn curve(case: LoadCase, n: usize) -> Curve {
        let stretch: Vec<f64> = (1..=n).map(|k| 1.0 + k as f64 * 1e-3).collect();
        let stress = stretch.iter().map(|l| (l - 1.0) * 2.0).collect();
        Curve::new(case, stretch, stress).unwrap()
    }

    #[test]
    fn keeps_every_curve_end_order_and_proportion() {
        let curves = [
            curve(LoadCase::Uniaxial, 9_001),
            curve(LoadCase::Equibiaxial, 3_000),
            curve(LoadCase::PureShear, 7),
        ];
        let (kept, report) = subsample(&curves, 1_200).unwrap();
        assert_eq!(report.points_total, 12_008);
        assert_eq!(report.max_points, 1_200);
        assert_eq!(
            report.points_fitted,
            kept.iter().map(Curve::len).sum::<usize>()
        );
        assert!(report.points_fitted <= 1_200 + 2 * curves.len());
        let sizes: Vec<usize> = kept.iter().map(Curve::len).collect();
        assert_eq!(
            sizes,
            [899, 299, 2],
            "shares in proportion, at least the two ends"
        );
        for (k, c) in kept.iter().zip(&curves) {
            assert_eq!(k.case, c.case);
            assert_eq!(k.stretch[0], c.stretch[0], "first point kept");
            assert_eq!(k.stretch.last(), c.stretch.last(), "last point kept");
            assert!(k.stretch.windows(2).all(|w| w[0] < w[1]), "order kept");
            for (l, p) in k.stretch.iter().zip(&k.nominal_stress_mpa) {
                let i = c.stretch.iter().position(|s| s == l).unwrap();
                assert_eq!(c.nominal_stress_mpa[i], *p, "rows kept whole");
            }
            // Evenly along the path: no gap more than twice the mean spacing.
            let mean = (c.len() - 1) as f64 / (k.len() - 1) as f64;
            let index = |l: &f64| c.stretch.iter().position(|s| s == l).unwrap();
            for w in k.stretch.windows(2) {
                assert!(((index(&w[1]) - index(&w[0])) as f64) < 2.0 * mean);
            }
        }
    }

    #[test]
    fn under_the_limit_nothing_changes_and_it_is_deterministic() {
        let curves = [curve(LoadCase::Uniaxial, 500)];
        assert_eq!(subsample(&curves, 500), None);
        let a = subsample(&curves, 100).unwrap();
        let b = subsample(&curves, 100).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.0[0].len(), 100);
    }
}
