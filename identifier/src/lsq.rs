//! Least squares: linear (SVD with a rank check) and a small bounded Levenberg-Marquardt.
//!
//! Written with nalgebra rather than a crate (`levenberg-marquardt` is the candidate) so that
//! steps giving non-finite residuals (Gent's and Arruda-Boyce's limiting chains) are simply
//! rejected, the iteration count is bounded, and nothing panics on a singular JᵀJ.

use nalgebra::{DMatrix, DVector};

/// Relative singular value below which a design matrix is declared rank deficient.
pub const RANK_TOLERANCE: f64 = 1e-10;
/// Maximum Levenberg-Marquardt iterations.
pub const LM_MAX_ITERATIONS: usize = 300;

#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LsqError {
    /// Fewer residuals than parameters (+1 for the residual variance).
    #[error("too few points: {points} data points for {params} parameters, need at least {}", .params + 1)]
    TooFewPoints { points: usize, params: usize },
    /// Parameters not identifiable from the data (rank of the design < number of parameters).
    #[error("parameters not identifiable from these load cases: design rank {rank} < {params} parameters")]
    RankDeficient { rank: usize, params: usize },
    /// Non-finite residuals at the starting point.
    #[error("model not defined at the starting parameters")]
    NonFiniteStart,
}

/// Rows per column above which [`linear_least_squares`] first reduces a tall system by QR.
pub const QR_REDUCTION_ROWS_PER_COLUMN: usize = 16;

/// Solves min ||A x − b|| by SVD; errors when A is rank deficient. A tall system (many points,
/// few parameters) is first reduced by a Householder QR of [A b] = Q [R c; 0 d]: the SVD of R
/// has A's singular values and column norms, and min ||R x − c|| has A's solution, at a small
/// fraction of the cost of A's own SVD.
pub fn linear_least_squares(a: &DMatrix<f64>, b: &DVector<f64>) -> Result<DVector<f64>, LsqError> {
    let (m, n) = a.shape();
    assert_eq!(m, b.len(), "design rows and right-hand side must match");
    if m < n {
        return Err(LsqError::TooFewPoints {
            points: m,
            params: n,
        });
    }
    if n == 0 {
        return Ok(DVector::zeros(0));
    }
    if m > QR_REDUCTION_ROWS_PER_COLUMN * (n + 1) {
        let mut augmented = DMatrix::zeros(m, n + 1);
        augmented.columns_mut(0, n).copy_from(a);
        augmented.set_column(n, b);
        let r = augmented.qr().r();
        let reduced = r.view((0, 0), (n, n)).into_owned();
        let rhs = r.view((0, n), (n, 1)).column(0).into_owned();
        return solve_by_svd(&reduced, &rhs);
    }
    solve_by_svd(a, b)
}

/// The SVD solve of [`linear_least_squares`] (column scaling, rank check).
fn solve_by_svd(a: &DMatrix<f64>, b: &DVector<f64>) -> Result<DVector<f64>, LsqError> {
    let n = a.ncols();
    // Column scaling so that the rank test is not fooled by units.
    let scales: Vec<f64> = (0..n).map(|j| a.column(j).norm()).collect();
    if scales.iter().any(|s| !s.is_finite()) {
        return Err(LsqError::NonFiniteStart);
    }
    let mut scaled = a.clone();
    for (j, &s) in scales.iter().enumerate() {
        if s > 0.0 {
            scaled.column_mut(j).scale_mut(1.0 / s);
        }
    }
    let svd = scaled.svd(true, true);
    let s_max = svd.singular_values.max();
    let rank = svd
        .singular_values
        .iter()
        .filter(|&&s| s > RANK_TOLERANCE * s_max.max(f64::MIN_POSITIVE))
        .count();
    if rank < n || scales.contains(&0.0) {
        return Err(LsqError::RankDeficient { rank, params: n });
    }
    let y = svd
        .solve(b, RANK_TOLERANCE * s_max)
        .map_err(|_| LsqError::RankDeficient { rank, params: n })?;
    Ok(DVector::from_iterator(
        n,
        y.iter().zip(&scales).map(|(v, s)| v / s),
    ))
}

/// The Jacobian with each column scaled to unit norm (the parameters' units out of the way)
/// and the scales; `None` when a column is zero or not finite.
fn column_scaled(jacobian: &DMatrix<f64>) -> Option<(DMatrix<f64>, Vec<f64>)> {
    let n = jacobian.ncols();
    let scales: Vec<f64> = (0..n).map(|j| jacobian.column(j).norm()).collect();
    if scales.iter().any(|&s| s == 0.0 || !s.is_finite()) {
        return None;
    }
    let mut scaled = jacobian.clone();
    for (j, &s) in scales.iter().enumerate() {
        scaled.column_mut(j).scale_mut(1.0 / s);
    }
    Some((scaled, scales))
}

/// Condition number (largest over smallest singular value) of the column-scaled Jacobian:
/// how nearly the parameters' effects on the residuals are dependent, whatever their units;
/// infinite when a parameter has no effect.
pub fn scaled_condition_number(jacobian: &DMatrix<f64>) -> f64 {
    let Some((scaled, _)) = column_scaled(jacobian) else {
        return f64::INFINITY;
    };
    let values = scaled.singular_values();
    let (max, min) = (values.max(), values.min());
    if min > 0.0 {
        max / min
    } else {
        f64::INFINITY
    }
}

/// Covariance (JᵀJ)⁻¹ by SVD; `None` when JᵀJ is numerically singular.
pub fn inverse_normal_matrix(jacobian: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = jacobian.ncols();
    let (scaled, scales) = column_scaled(jacobian)?;
    let svd = scaled.svd(false, true);
    let s_max = svd.singular_values.max();
    if svd.singular_values.iter().any(|&s| s <= 1e-12 * s_max) {
        return None;
    }
    let v_t = svd.v_t?;
    let mut inv = DMatrix::zeros(n, n);
    for k in 0..n {
        let s2 = svd.singular_values[k] * svd.singular_values[k];
        let v = v_t.row(k).transpose();
        inv += &v * v.transpose() / s2;
    }
    for i in 0..n {
        for j in 0..n {
            inv[(i, j)] /= scales[i] * scales[j];
        }
    }
    Some(inv)
}

/// Central finite-difference Jacobian of `residuals` at `p`.
pub fn numeric_jacobian<F>(residuals: &F, p: &[f64], m: usize) -> DMatrix<f64>
where
    F: Fn(&[f64]) -> Option<DVector<f64>>,
{
    let n = p.len();
    let mut jac = DMatrix::zeros(m, n);
    let mut q = p.to_vec();
    for j in 0..n {
        let h = 1e-6 * p[j].abs().max(1e-6);
        q[j] = p[j] + h;
        let plus = residuals(&q);
        q[j] = p[j] - h;
        let minus = residuals(&q);
        q[j] = p[j];
        let column = match (plus, minus) {
            (Some(a), Some(b)) => (a - b) / (2.0 * h),
            (Some(a), None) => (a - residuals(p).expect("residuals finite at p")) / h,
            (None, Some(b)) => (residuals(p).expect("residuals finite at p") - b) / h,
            (None, None) => DVector::zeros(m),
        };
        jac.set_column(j, &column);
    }
    jac
}

/// A least-squares problem as Levenberg-Marquardt sees it: the cost ||r(p)||² and the normal
/// equations JᵀJ, Jᵀr at a point. The fitting's fast path builds both in one pass over the
/// points ([`crate::residuals`]); [`ResidualVector`] is the straightforward reference (a
/// residual vector and a central finite-difference Jacobian).
pub trait LeastSquares {
    /// Number of residuals m.
    fn points(&self) -> usize;
    /// ||r(p)||², `None` where the model is undefined or a residual is not finite.
    fn cost(&mut self, p: &[f64]) -> Option<f64>;
    /// JᵀJ (n × n) and Jᵀr (n) at `p`, where `cost(p)` is defined.
    fn normal_equations(&mut self, p: &[f64], jtj: &mut DMatrix<f64>, jtr: &mut DVector<f64>);
}

/// The reference form of a problem: a residual vector and [`numeric_jacobian`].
pub struct ResidualVector<'a, F> {
    pub residuals: &'a F,
    pub points: usize,
}

impl<F> LeastSquares for ResidualVector<'_, F>
where
    F: Fn(&[f64]) -> Option<DVector<f64>>,
{
    fn points(&self) -> usize {
        self.points
    }

    fn cost(&mut self, p: &[f64]) -> Option<f64> {
        let r = (self.residuals)(p).filter(|r| r.iter().all(|v| v.is_finite()))?;
        assert_eq!(
            r.len(),
            self.points,
            "residual length must match the declared point count"
        );
        Some(r.norm_squared())
    }

    fn normal_equations(&mut self, p: &[f64], jtj: &mut DMatrix<f64>, jtr: &mut DVector<f64>) {
        let jac = numeric_jacobian(self.residuals, p, self.points);
        let r = (self.residuals)(p).expect("residuals finite at p");
        *jtj = jac.transpose() * &jac;
        *jtr = jac.transpose() * &r;
    }
}

/// Outcome of a Levenberg-Marquardt run.
#[derive(Clone, Debug)]
pub struct LmResult {
    pub params: Vec<f64>,
    pub cost: f64,
    pub iterations: usize,
    pub converged: bool,
}

/// Minimises ||r(p)||² from `start`. `residuals` returns `None` where the model is undefined.
pub fn levenberg_marquardt<F>(residuals: &F, start: &[f64], m: usize) -> Result<LmResult, LsqError>
where
    F: Fn(&[f64]) -> Option<DVector<f64>>,
{
    minimise(
        &mut ResidualVector {
            residuals,
            points: m,
        },
        start,
    )
}

/// When a Levenberg-Marquardt run stops: the gauge and virtual-fields fits run to the
/// precision of their closed-form residuals (the defaults); a costly problem whose residuals
/// are themselves converged iterates (finite-element model updating) stops at their precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LmStop {
    pub max_iterations: usize,
    /// An accepted step that lowers the cost by less than this fraction ends the run.
    pub min_relative_decrease: f64,
    /// Rejected trial steps (each with 4 times the damping) before the run ends at a point
    /// no step lowers.
    pub max_rejected: usize,
}

impl Default for LmStop {
    fn default() -> Self {
        LmStop {
            max_iterations: LM_MAX_ITERATIONS,
            min_relative_decrease: 1e-14,
            max_rejected: 40,
        }
    }
}

/// Levenberg-Marquardt on any [`LeastSquares`] problem from `start`.
pub fn minimise<P: LeastSquares>(problem: &mut P, start: &[f64]) -> Result<LmResult, LsqError> {
    minimise_until(problem, start, LmStop::default())
}

/// [`minimise`] with its stopping rule.
pub fn minimise_until<P: LeastSquares>(
    problem: &mut P,
    start: &[f64],
    stop: LmStop,
) -> Result<LmResult, LsqError> {
    let n = start.len();
    let m = problem.points();
    if m < n {
        return Err(LsqError::TooFewPoints {
            points: m,
            params: n,
        });
    }
    let mut p = start.to_vec();
    let mut cost = problem.cost(&p).ok_or(LsqError::NonFiniteStart)?;
    let mut jtj = DMatrix::zeros(n, n);
    let mut jtr = DVector::zeros(n);
    let mut lhs = DMatrix::zeros(n, n);
    let mut trial = vec![0.0; n];
    let mut damping = 1e-3;
    let mut converged = false;
    let mut iterations = 0;
    while iterations < stop.max_iterations && !converged {
        iterations += 1;
        problem.normal_equations(&p, &mut jtj, &mut jtr);
        if jtr.amax() <= 1e-15 * (1.0 + cost) {
            converged = true;
            break;
        }
        let mut accepted = false;
        for _ in 0..stop.max_rejected {
            lhs.copy_from(&jtj);
            for k in 0..n {
                lhs[(k, k)] += damping * jtj[(k, k)].max(1e-12);
            }
            let step = match lhs.clone().cholesky() {
                Some(ch) => ch.solve(&(-&jtr)),
                None => {
                    damping *= 10.0;
                    continue;
                }
            };
            for ((t, a), d) in trial.iter_mut().zip(&p).zip(step.iter()) {
                *t = a + d;
            }
            match problem.cost(&trial) {
                Some(new_cost) if new_cost < cost => {
                    let relative_decrease = (cost - new_cost) / cost.max(f64::MIN_POSITIVE);
                    let step_small = step
                        .iter()
                        .zip(&p)
                        .all(|(d, a)| d.abs() <= 1e-12 * (a.abs() + 1e-12));
                    p.copy_from_slice(&trial);
                    cost = new_cost;
                    damping = (damping / 3.0).max(1e-12);
                    accepted = true;
                    if relative_decrease < stop.min_relative_decrease || step_small {
                        converged = true;
                    }
                    break;
                }
                _ => damping *= 4.0,
            }
            if damping > 1e16 {
                break;
            }
        }
        if !accepted {
            // No descent possible: a (local) minimum to the precision of the Jacobian.
            converged = true;
        }
    }
    Ok(LmResult {
        params: p,
        cost,
        iterations,
        converged,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rank_deficient_design_is_an_error_not_a_panic() {
        let a = DMatrix::from_row_slice(3, 2, &[1.0, 2.0, 2.0, 4.0, 3.0, 6.0]);
        let b = DVector::from_vec(vec![1.0, 2.0, 3.0]);
        assert!(matches!(
            linear_least_squares(&a, &b),
            Err(LsqError::RankDeficient { .. })
        ));
        let a = DMatrix::from_row_slice(1, 2, &[1.0, 2.0]);
        assert!(matches!(
            linear_least_squares(&a, &b.rows(0, 1).into()),
            Err(LsqError::TooFewPoints { .. })
        ));
    }

    #[test]
    fn tall_systems_reduced_by_qr_solve_as_the_plain_svd() {
        let m = 2000;
        let a = DMatrix::from_fn(m, 3, |i, j| {
            let t = 1.0 + i as f64 / m as f64;
            t.powi(j as i32 + 1) * [1.0, 1e-3, 1e3][j]
        });
        let b = DVector::from_fn(m, |i, _| {
            (1.0 + i as f64 / m as f64).ln() + 0.01 * (i % 7) as f64
        });
        assert!(m > QR_REDUCTION_ROWS_PER_COLUMN * 4, "the reduction runs");
        let reduced = linear_least_squares(&a, &b).unwrap();
        let plain = solve_by_svd(&a, &b).unwrap();
        for (x, y) in reduced.iter().zip(plain.iter()) {
            assert!((x - y).abs() <= 1e-9 * y.abs(), "{reduced} vs {plain}");
        }
        let mut dependent = a.clone();
        let column = a.column(0) * 2.0;
        dependent.set_column(2, &column);
        assert!(matches!(
            linear_least_squares(&dependent, &b),
            Err(LsqError::RankDeficient { .. })
        ));
    }

    #[test]
    fn lm_fits_an_exponential() {
        let xs: Vec<f64> = (0..20).map(|i| i as f64 * 0.1).collect();
        let ys: Vec<f64> = xs.iter().map(|x| 2.0 * (-1.3 * x).exp()).collect();
        let res = |p: &[f64]| {
            Some(DVector::from_iterator(
                20,
                xs.iter().zip(&ys).map(|(x, y)| p[0] * (p[1] * x).exp() - y),
            ))
        };
        let out = levenberg_marquardt(&res, &[1.0, 0.0], 20).unwrap();
        assert!(
            (out.params[0] - 2.0).abs() < 1e-6 && (out.params[1] + 1.3).abs() < 1e-6,
            "{out:?}"
        );
    }
}
