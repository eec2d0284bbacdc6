//! The paper's identification route (section 4, eqs 20-25) and its inverse-analysis refinement.
//!
//! 1. f(I1) from uniaxial data by eq. 20 (g neglected), fitted as ln f = Σ a_i (I1−3)^i.
//! 2. g(I2) from equibiaxial data by eq. 23 with that f, fitted as Σ c_i / I2^i (eq. 24) and as
//!    ln g = Σ b_i (I2−3)^i (eq. 25).
//! 3. f again from uniaxial data, now with the g correction of eq. 19; then g again
//!    (bounded: [`ROUTE_PASSES`] passes).
//! 4. Levenberg-Marquardt refinement of all a_i, b_i against the measured stresses of every load
//!    case at once (model `lambert-diani-rey`).
//!
//! Eqs. 20 and 23 divide the stress by a term that vanishes at λ = 1: the few points within
//! [`ROUTE_MIN_STRETCH`] of the unstretched state turn load-cell noise into arbitrary (even
//! negative) f and g values, so steps 1-3 leave them out (the refinement of step 4 uses every
//! point).

use crate::data::{Curve, LoadCase};
use crate::law::{InvariantFn, InvariantLaw};
use crate::lsq::{linear_least_squares, LsqError};
use nalgebra::{DMatrix, DVector};

/// Passes of the f ↔ g correction.
pub const ROUTE_PASSES: usize = 5;

/// Smallest stretch whose data enter eqs. 20 and 23.
pub const ROUTE_MIN_STRETCH: f64 = 1.02;

/// The part of `curve` at or beyond [`ROUTE_MIN_STRETCH`].
fn route_part(curve: &Curve) -> Curve {
    let keep: Vec<usize> = (0..curve.stretch.len())
        .filter(|&i| curve.stretch[i] >= ROUTE_MIN_STRETCH)
        .collect();
    Curve {
        case: curve.case,
        stretch: keep.iter().map(|&i| curve.stretch[i]).collect(),
        nominal_stress_mpa: keep.iter().map(|&i| curve.nominal_stress_mpa[i]).collect(),
        reference_rows_dropped: curve.reference_rows_dropped,
    }
}

/// Experimental invariant-derivative points (eq. 20 or 23): (invariant, value in MPa).
pub type InvariantPoints = Vec<(f64, f64)>;

/// The route's outcome.
#[derive(Clone, Debug)]
pub struct RouteResult {
    /// a_0..a_n of ln f (eq. 22).
    pub a: Vec<f64>,
    /// b_0..b_n of ln g (eq. 25).
    pub b: Vec<f64>,
    /// c_0..c_n of g = Σ c_i / I2^i (eq. 24), fitted to the same g points.
    pub c: Vec<f64>,
    /// Experimental f points after the last pass (uniaxial, with the g correction).
    pub f_points: InvariantPoints,
    /// Experimental f points of eq. 20 (no g correction), as in the paper's Fig. 8.
    pub f_points_uncorrected: InvariantPoints,
    /// Experimental g points of eq. 23 (last pass), as in the paper's Fig. 14.
    pub g_points: InvariantPoints,
}

impl RouteResult {
    /// a then b: the parameter vector of `Model::LambertDianiRey`.
    pub fn coefficients(&self) -> Vec<f64> {
        self.a.iter().chain(&self.b).copied().collect()
    }

    /// The law with exponential g (eq. 25).
    pub fn law_exp(&self) -> InvariantLaw {
        InvariantLaw {
            f: InvariantFn::ExpPoly(self.a.clone()),
            g: InvariantFn::ExpPoly(self.b.clone()),
        }
    }
}

/// Route errors.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RouteError {
    #[error("the paper's route needs {0} data")]
    MissingCase(LoadCase),
    #[error("{what} = {value} MPa at invariant {invariant} is not positive: its logarithm cannot be fitted")]
    NonPositive {
        what: &'static str,
        invariant: f64,
        value: f64,
    },
    #[error("fitting {what}: {error}")]
    Lsq { what: &'static str, error: LsqError },
}

/// Fits Σ coeffs_i t^i (i = 0..=degree) to (t, y) points.
pub fn fit_polynomial(points: &[(f64, f64)], degree: usize) -> Result<Vec<f64>, LsqError> {
    let m = points.len();
    if m < degree + 2 {
        return Err(LsqError::TooFewPoints {
            points: m,
            params: degree + 1,
        });
    }
    let design = DMatrix::from_fn(m, degree + 1, |r, c| points[r].0.powi(c as i32));
    let rhs = DVector::from_iterator(m, points.iter().map(|p| p.1));
    Ok(linear_least_squares(&design, &rhs)?
        .iter()
        .copied()
        .collect())
}

/// Fits ln y = Σ coeffs_i (I − 3)^i.
pub fn fit_log_polynomial(
    points: &[(f64, f64)],
    degree: usize,
    what: &'static str,
) -> Result<Vec<f64>, RouteError> {
    let mut logs = Vec::with_capacity(points.len());
    for &(invariant, value) in points {
        if value.is_nan() || value <= 0.0 {
            return Err(RouteError::NonPositive {
                what,
                invariant,
                value,
            });
        }
        logs.push((invariant - 3.0, value.ln()));
    }
    fit_polynomial(&logs, degree).map_err(|error| RouteError::Lsq { what, error })
}

/// f points from uniaxial data, eq. 19 solved for f given g (g = 0 gives eq. 20).
pub fn f_points(uniaxial: &Curve, g: Option<&InvariantFn>) -> InvariantPoints {
    assert_eq!(uniaxial.case, LoadCase::Uniaxial);
    uniaxial
        .stretch
        .iter()
        .zip(uniaxial.cauchy_stress_mpa())
        .map(|(&l, sigma)| {
            let (i1, i2) = LoadCase::Uniaxial.invariants(l);
            let g_value = g.map_or(0.0, |g| g.value_mpa(i2));
            (
                i1,
                (sigma + 2.0 * g_value * (1.0 / (l * l) - l)) / (2.0 * (l * l - 1.0 / l)),
            )
        })
        .collect()
}

/// g points from equibiaxial data, eq. 23.
pub fn g_points(equibiaxial: &Curve, f: &InvariantFn) -> InvariantPoints {
    assert_eq!(equibiaxial.case, LoadCase::Equibiaxial);
    equibiaxial
        .stretch
        .iter()
        .zip(equibiaxial.cauchy_stress_mpa())
        .map(|(&l, sigma)| {
            let (i1, i2) = LoadCase::Equibiaxial.invariants(l);
            let l2 = l * l;
            (
                i2,
                (sigma - 2.0 * f.value_mpa(i1) * (l2 - 1.0 / (l2 * l2)))
                    / (2.0 * (l2 * l2 - 1.0 / l2)),
            )
        })
        .collect()
}

/// Runs steps 1-3 of the route with polynomial degrees `f_degree` (Table 3's n) and
/// `g_degree` (Table 4's n).
pub fn paper_route(
    curves: &[Curve],
    f_degree: usize,
    g_degree: usize,
) -> Result<RouteResult, RouteError> {
    let part = |case| {
        curves
            .iter()
            .find(|c| c.case == case)
            .map(route_part)
            .ok_or(RouteError::MissingCase(case))
    };
    let (uniaxial, equibiaxial) = (&part(LoadCase::Uniaxial)?, &part(LoadCase::Equibiaxial)?);
    let f_points_uncorrected = f_points(uniaxial, None);
    let mut a = fit_log_polynomial(&f_points_uncorrected, f_degree, "f(I1) from eq. 20")?;
    let mut b = Vec::new();
    let mut gp = Vec::new();
    let mut fp = f_points_uncorrected.clone();
    for pass in 0..ROUTE_PASSES {
        gp = g_points(equibiaxial, &InvariantFn::ExpPoly(a.clone()));
        b = fit_log_polynomial(&gp, g_degree, "g(I2) from eq. 23")?;
        if pass + 1 == ROUTE_PASSES {
            break;
        }
        fp = f_points(uniaxial, Some(&InvariantFn::ExpPoly(b.clone())));
        a = fit_log_polynomial(&fp, f_degree, "f(I1) with the g correction")?;
    }
    let inverse: Vec<(f64, f64)> = gp.iter().map(|&(i2, g)| (1.0 / i2, g)).collect();
    let c = fit_polynomial(&inverse, g_degree).map_err(|error| RouteError::Lsq {
        what: "g(I2) eq. 24",
        error,
    })?;
    Ok(RouteResult {
        a,
        b,
        c,
        f_points: fp,
        f_points_uncorrected,
        g_points: gp,
    })
}
