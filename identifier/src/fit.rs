//! Fitting one model of the catalogue to any combination of load cases and general biaxial
//! states ([`FitData`]), with statistics.
//!
//! Every fitted point is one measured nominal stress along one in-plane direction of an
//! incompressible plane-stress state ([`crate::gradient::Kinematics::in_plane`]): a canonical
//! curve gives one a row (P1), a [`BiaxialState`] two (P1 at (λ1, λ2), P2 at (λ2, λ1)).
//!
//! Parameters in which the stress is linear are solved by linear least squares (SVD); the
//! others by Levenberg-Marquardt from a grid of starts, the linear ones re-solved at each start
//! (variable projection for the starts only). Objective: Σ_cases w_c Σ_points r², with
//! r = P_model − P_data (absolute, MPa) or (P_model − P_data)/|P_data| (relative).

use crate::data::{BiaxialState, Curve, DataGroup, LoadCase};
use crate::gradient::Kinematics;
use crate::identifiability::Identifiability;
use crate::lsq::{self, LsqError};
use crate::models::Model;
use crate::residuals::PointSet;
use crate::stability::{drucker_stability, StabilityRange};
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeMap;

/// How residuals are measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ResidualKind {
    /// P_model − P_data, MPa.
    #[default]
    Absolute,
    /// (P_model − P_data) / |P_data|.
    Relative,
}

/// How the Jacobian of the residuals is obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum JacobianPath {
    /// Analytic gradients, normal equations accumulated point by point ([`crate::residuals`]).
    #[default]
    Analytic,
    /// The straightforward reference: residual vectors and a central finite-difference
    /// Jacobian (n + 1 evaluations of every residual per iteration). Slow; kept to check the
    /// analytic path against.
    FiniteDifference,
}

/// Fit options.
#[derive(Clone, Debug, Default)]
pub struct FitOptions {
    pub residual: ResidualKind,
    /// Per-load-case weights w_c (default 1; general biaxial states weigh 1).
    pub weights: BTreeMap<LoadCase, f64>,
    /// Extra starting points (full parameter vectors) for the nonlinear search.
    pub extra_starts: Vec<Vec<f64>>,
    /// Start the nonlinear search from these parameters alone (a refit after a few more
    /// points: the last solution is next to the new one); the full multi-start search runs
    /// only if that start fails.
    pub warm_start: Option<Vec<f64>>,
    /// Threads sharing the points of each evaluation (0 or 1: the calling thread alone). The
    /// result does not depend on it.
    pub threads: usize,
    pub jacobian: JacobianPath,
}

/// Where a fit is, for a progress display.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FitStage {
    /// Solving the linear parameters at start `start` (1-based) of `starts`.
    Screening { start: usize, starts: usize },
    /// Levenberg-Marquardt from the `start`th best start of `starts`.
    Refining { start: usize, starts: usize },
}

/// Statistics of one group of points (a load case, or the general biaxial states).
#[derive(Clone, Debug, PartialEq)]
pub struct CaseStats {
    pub case: DataGroup,
    pub points: usize,
    /// RMS of P_model − P_data, MPa.
    pub rms_mpa: f64,
    /// 1 − SS_res/SS_tot on the nominal stresses.
    pub r2: f64,
}

/// A fitted model.
#[derive(Clone, Debug)]
pub struct Fit {
    pub model: Model,
    pub param_names: Vec<String>,
    pub params: Vec<f64>,
    /// Standard deviations from s² (JᵀJ)⁻¹; `None` when JᵀJ is singular.
    pub stderr: Vec<Option<f64>>,
    /// RMS of P_model − P_data over every point of every case, MPa.
    pub rms_mpa: f64,
    pub cases: Vec<CaseStats>,
    /// Akaike criterion m ln(S/m) + 2p on the fitted (weighted) objective S.
    pub aic: f64,
    /// Fitted objective S.
    pub objective: f64,
    pub stability: Vec<StabilityRange>,
    /// False if Levenberg-Marquardt hit its iteration cap.
    pub converged: bool,
    /// Whether the data identify the parameters; a fit they do not is not ranked.
    pub identifiability: Identifiability,
}

impl Fit {
    /// Parameter by name.
    pub fn param(&self, name: &str) -> Option<f64> {
        self.param_names
            .iter()
            .position(|n| n == name)
            .map(|i| self.params[i])
    }
}

/// Fit errors.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FitError {
    #[error("no data: give at least one load case")]
    NoData,
    #[error("model {model}: {error}")]
    Lsq { model: String, error: LsqError },
    #[error("relative residuals need non-zero stresses: {case} point at stretch {stretch} has zero stress")]
    ZeroStressRelative { case: DataGroup, stretch: f64 },
    #[error("model {model}: undefined at every starting point for these stretches")]
    NoValidStart { model: String },
    #[error("weight of {case} must be finite and > 0, got {weight}")]
    BadWeight { case: LoadCase, weight: f64 },
}

struct Problem<'a> {
    set: PointSet<'a>,
    path: JacobianPath,
}

impl Problem<'_> {
    fn residuals(&self, p: &[f64]) -> Option<DVector<f64>> {
        self.set.residuals(p)
    }

    /// Σ r², `None` where a residual is undefined or not finite.
    fn cost(&mut self, p: &[f64]) -> Option<f64> {
        match self.path {
            JacobianPath::Analytic => lsq::LeastSquares::cost(&mut self.set, p),
            JacobianPath::FiniteDifference => self
                .residuals(p)
                .filter(|r| r.iter().all(|v| v.is_finite()))
                .map(|r| r.norm_squared()),
        }
    }

    fn levenberg_marquardt(&mut self, start: &[f64]) -> Result<lsq::LmResult, LsqError> {
        match self.path {
            JacobianPath::Analytic => lsq::minimise(&mut self.set, start),
            JacobianPath::FiniteDifference => {
                let m = self.set.len();
                lsq::levenberg_marquardt(&|p: &[f64]| self.residuals(p), start, m)
            }
        }
    }

    fn jacobian(&self, p: &[f64]) -> DMatrix<f64> {
        match self.path {
            JacobianPath::Analytic => self.set.jacobian(p),
            JacobianPath::FiniteDifference => {
                lsq::numeric_jacobian(&|q: &[f64]| self.residuals(q), p, self.set.len())
            }
        }
    }

    /// Solves the linear parameters with the nonlinear ones of `p` fixed; returns the full vector.
    fn solve_linear(&mut self, p: &[f64], linear: &[bool]) -> Result<Vec<f64>, LsqError> {
        self.solve_linear_with_cost(p, linear).map(|(p, _)| p)
    }

    /// [`Problem::solve_linear`] and the cost there (`None` if not finite). The analytic path
    /// takes it from the linear system (r = design x − rhs: the stress is linear in those
    /// parameters and their values do not change the model's domain), not from the model.
    fn solve_linear_with_cost(
        &mut self,
        p: &[f64],
        linear: &[bool],
    ) -> Result<(Vec<f64>, Option<f64>), LsqError> {
        let lin_idx: Vec<usize> = (0..p.len()).filter(|&i| linear[i]).collect();
        let mut base = p.to_vec();
        for &i in &lin_idx {
            base[i] = 0.0;
        }
        let (design, rhs) = match self.path {
            JacobianPath::Analytic => self
                .set
                .linear_system(&base, linear)
                .ok_or(LsqError::NonFiniteStart)?,
            JacobianPath::FiniteDifference => {
                let r0 = self.residuals(&base).ok_or(LsqError::NonFiniteStart)?;
                let mut design = DMatrix::zeros(self.set.len(), lin_idx.len());
                for (col, &i) in lin_idx.iter().enumerate() {
                    let mut q = base.clone();
                    q[i] = 1.0;
                    let r1 = self.residuals(&q).ok_or(LsqError::NonFiniteStart)?;
                    design.set_column(col, &(r1 - &r0));
                }
                (design, -r0)
            }
        };
        let x = lsq::linear_least_squares(&design, &rhs)?;
        let mut out = base;
        for (col, &i) in lin_idx.iter().enumerate() {
            out[i] = x[col];
        }
        let cost = match self.path {
            JacobianPath::Analytic => {
                Some((design * x - rhs).norm_squared()).filter(|c| c.is_finite())
            }
            JacobianPath::FiniteDifference => self.cost(&out),
        };
        Ok((out, cost))
    }
}

/// Number of best starts refined by Levenberg-Marquardt.
pub const LM_STARTS_REFINED: usize = 6;

/// The data of a fit: canonical curves (P1 along the loaded direction) and general biaxial
/// states (P1 and P2). Either may be empty.
#[derive(Clone, Copy, Debug, Default)]
pub struct FitData<'a> {
    pub curves: &'a [Curve],
    pub states: &'a [BiaxialState],
}

impl<'a> FitData<'a> {
    pub fn curves(curves: &'a [Curve]) -> Self {
        FitData {
            curves,
            states: &[],
        }
    }

    pub fn is_empty(&self) -> bool {
        self.curves.iter().all(|c| c.is_empty()) && self.states.is_empty()
    }

    /// Every measured point, by group: (group, kinematics of its direction, its loaded
    /// stretch, nominal stress MPa). The one place data become fitted points.
    pub fn points(&self) -> Vec<(DataGroup, Kinematics, f64, f64)> {
        let mut points = Vec::new();
        for curve in self.curves {
            for (&stretch, &stress) in curve.stretch.iter().zip(&curve.nominal_stress_mpa) {
                let k = Kinematics::of(curve.case, stretch);
                points.push((DataGroup::Case(curve.case), k, stretch, stress));
            }
        }
        for s in self.states {
            for (l, other, stress) in [
                (s.stretch1, s.stretch2, s.nominal_stress1_mpa),
                (s.stretch2, s.stretch1, s.nominal_stress2_mpa),
            ] {
                let k = Kinematics::in_plane(l, other);
                points.push((DataGroup::BiaxialGeneral, k, l, stress));
            }
        }
        points
    }

    /// The groups present, in [`FitData::points`] order.
    pub fn groups(&self) -> Vec<DataGroup> {
        let mut groups: Vec<DataGroup> = self
            .curves
            .iter()
            .map(|c| DataGroup::Case(c.case))
            .collect();
        if !self.states.is_empty() {
            groups.push(DataGroup::BiaxialGeneral);
        }
        groups
    }

    /// The largest in-plane stretch of the data (1 if none).
    pub fn max_stretch(&self) -> f64 {
        self.curves
            .iter()
            .flat_map(|c| c.stretch.iter().copied())
            .chain(self.states.iter().map(BiaxialState::max_stretch))
            .fold(1.0, f64::max)
    }
}

/// Fits `model` to `curves`.
pub fn fit_model(model: &Model, curves: &[Curve], options: &FitOptions) -> Result<Fit, FitError> {
    fit_data(model, FitData::curves(curves), options, &mut |_| {})
}

/// [`fit_model`], telling `progress` where it is (at every start of the nonlinear search).
pub fn fit_model_with_progress(
    model: &Model,
    curves: &[Curve],
    options: &FitOptions,
    progress: &mut dyn FnMut(FitStage),
) -> Result<Fit, FitError> {
    fit_data(model, FitData::curves(curves), options, progress)
}

/// Fits `model` to curves and general biaxial states at once, telling `progress` where it is.
pub fn fit_data(
    model: &Model,
    data: FitData,
    options: &FitOptions,
    progress: &mut dyn FnMut(FitStage),
) -> Result<Fit, FitError> {
    if data.is_empty() {
        return Err(FitError::NoData);
    }
    let points = weighted_points(&data, options)?;
    let (m, n) = (points.len(), model.param_names().len());
    if m < n + 1 {
        return Err(FitError::Lsq {
            model: model.name(),
            error: LsqError::TooFewPoints {
                points: m,
                params: n,
            },
        });
    }
    let mut problem = Problem {
        set: PointSet::new(model, &points, options.threads),
        path: options.jacobian,
    };
    let (params, converged) = solve(&mut problem, model, &data, options, progress)?;
    fit_at(&problem, model, &data, params, converged, m)
}

/// Each point's kinematics, stress and residual factor (√weight / scale); a bad weight or a
/// zero stress under relative residuals refused.
fn weighted_points(
    data: &FitData,
    options: &FitOptions,
) -> Result<Vec<(Kinematics, f64, f64)>, FitError> {
    let all = data.points();
    let mut points = Vec::with_capacity(all.len());
    for &(group, kinematics, stretch, stress) in &all {
        let weight = match group {
            DataGroup::Case(case) => {
                let weight = options.weights.get(&case).copied().unwrap_or(1.0);
                if !(weight.is_finite() && weight > 0.0) {
                    return Err(FitError::BadWeight { case, weight });
                }
                weight
            }
            DataGroup::BiaxialGeneral => 1.0,
        };
        let scale = match options.residual {
            ResidualKind::Absolute => 1.0,
            ResidualKind::Relative => {
                if stress == 0.0 {
                    return Err(FitError::ZeroStressRelative {
                        case: group,
                        stretch,
                    });
                }
                stress.abs()
            }
        };
        points.push((kinematics, stress, weight.sqrt() / scale));
    }
    Ok(points)
}

/// The fitted parameters and whether the search converged: linear least squares for an
/// all-linear model, else from the warm start when it succeeds, else from the best starts.
fn solve(
    problem: &mut Problem,
    model: &Model,
    data: &FitData,
    options: &FitOptions,
    progress: &mut dyn FnMut(FitStage),
) -> Result<(Vec<f64>, bool), FitError> {
    let n = model.param_names().len();
    let linear = model.linear_params();
    if linear.iter().all(|&l| l) {
        let params = problem
            .solve_linear(&vec![0.0; n], &linear)
            .map_err(|error| FitError::Lsq {
                model: model.name(),
                error,
            })?;
        return Ok((params, true));
    }
    let warm = options.warm_start.as_ref().filter(|w| w.len() == n);
    if let Some(warm) = warm.and_then(|w| warm_start(problem, w, &linear)) {
        return Ok((warm.params, warm.converged));
    }
    let starts: Vec<Vec<f64>> = nonlinear_starts(model, data)
        .into_iter()
        .chain(options.extra_starts.iter().cloned())
        .collect();
    let candidates = screen_starts(problem, model, starts, &linear, progress)?;
    let best = refine_best(problem, &candidates, progress).ok_or(FitError::NoValidStart {
        model: model.name(),
    })?;
    Ok((best.params, best.converged))
}

/// Levenberg-Marquardt from a warm start (its linear parameters solved first).
fn warm_start(problem: &mut Problem, start: &[f64], linear: &[bool]) -> Option<lsq::LmResult> {
    let start = if linear.iter().any(|&l| l) {
        problem.solve_linear(start, linear).ok()?
    } else {
        start.to_vec()
    };
    problem.levenberg_marquardt(&start).ok()
}

/// Every start with its linear parameters solved, and its cost, best first; refused when
/// none has a cost.
fn screen_starts(
    problem: &mut Problem,
    model: &Model,
    starts: Vec<Vec<f64>>,
    linear: &[bool],
    progress: &mut dyn FnMut(FitStage),
) -> Result<Vec<(f64, Vec<f64>)>, FitError> {
    let n = linear.len();
    let mut candidates: Vec<(f64, Vec<f64>)> = Vec::new();
    let mut last_error = None;
    let start_count = starts.len();
    for (k, start) in starts.into_iter().enumerate() {
        progress(FitStage::Screening {
            start: k + 1,
            starts: start_count,
        });
        assert_eq!(
            start.len(),
            n,
            "start length must match the parameter count"
        );
        let full = if linear.iter().any(|&l| l) {
            problem.solve_linear_with_cost(&start, linear)
        } else {
            let cost = problem.cost(&start);
            Ok((start, cost))
        };
        match full {
            Ok((p, Some(cost))) => candidates.push((cost, p)),
            Ok((_, None)) => {}
            Err(e) => last_error = Some(e),
        }
    }
    if candidates.is_empty() {
        return Err(match last_error {
            Some(error @ (LsqError::TooFewPoints { .. } | LsqError::RankDeficient { .. })) => {
                FitError::Lsq {
                    model: model.name(),
                    error,
                }
            }
            _ => FitError::NoValidStart {
                model: model.name(),
            },
        });
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(candidates)
}

/// Levenberg-Marquardt from the [`LM_STARTS_REFINED`] best candidates: the lowest cost.
fn refine_best(
    problem: &mut Problem,
    candidates: &[(f64, Vec<f64>)],
    progress: &mut dyn FnMut(FitStage),
) -> Option<lsq::LmResult> {
    let mut best: Option<lsq::LmResult> = None;
    let refined = candidates.len().min(LM_STARTS_REFINED);
    for (k, (_, start)) in candidates.iter().take(refined).enumerate() {
        progress(FitStage::Refining {
            start: k + 1,
            starts: refined,
        });
        if let Ok(res) = problem.levenberg_marquardt(start) {
            if best.as_ref().is_none_or(|b| res.cost < b.cost) {
                best = Some(res);
            }
        }
    }
    best
}

/// The fit at `params`: standard deviations, per-group statistics, AIC, stability.
fn fit_at(
    problem: &Problem,
    model: &Model,
    data: &FitData,
    params: Vec<f64>,
    converged: bool,
    m: usize,
) -> Result<Fit, FitError> {
    let n = params.len();
    let r = problem.residuals(&params).ok_or(FitError::NoValidStart {
        model: model.name(),
    })?;
    let objective = r.norm_squared();
    let jac = problem.jacobian(&params);
    let variance = objective / (m - n) as f64;
    let stderr = match lsq::inverse_normal_matrix(&jac) {
        Some(cov) => (0..n)
            .map(|i| Some((variance * cov[(i, i)]).max(0.0).sqrt()))
            .collect(),
        None => vec![None; n],
    };
    let identifiability = Identifiability::new(
        &model.param_names(),
        &params,
        &stderr,
        lsq::scaled_condition_number(&jac),
    );
    let (rms_mpa, cases) = group_stats(model, &params, data);
    let max_stretch = data.max_stretch();
    let stability = LoadCase::ALL
        .iter()
        .map(|&case| drucker_stability(model, &params, case, max_stretch))
        .collect();
    Ok(Fit {
        model: model.clone(),
        param_names: model.param_names(),
        params,
        stderr,
        rms_mpa,
        cases,
        aic: gaussian_fit_term(m, objective) + 2.0 * n as f64,
        objective,
        stability,
        converged,
        identifiability,
    })
}

/// Σ (P_model − P_data)² over `points` (unweighted, MPa²).
/// m ln(RSS/m): the residuals' part of an information criterion over m Gaussian residuals
/// (AIC adds 2 per parameter, BIC ln m: the field route's `information_criteria`).
pub(crate) fn gaussian_fit_term(m: usize, rss: f64) -> f64 {
    m as f64 * (rss.max(f64::MIN_POSITIVE) / m as f64).ln()
}

fn r_abs_sq(model: &Model, params: &[f64], points: &[(DataGroup, Kinematics, f64, f64)]) -> f64 {
    points
        .iter()
        .map(|(_, k, _, d)| {
            (model.nominal_stress_at(params, k, None).unwrap_or(f64::NAN) - d).powi(2)
        })
        .sum()
}

/// (overall RMS, per group) of a model with given parameters against `data`.
fn group_stats(model: &Model, params: &[f64], data: &FitData) -> (f64, Vec<CaseStats>) {
    let points = data.points();
    let mut cases = Vec::new();
    for group in data.groups() {
        let mine: Vec<_> = points.iter().filter(|p| p.0 == group).copied().collect();
        let ss = r_abs_sq(model, params, &mine);
        let mean = mine.iter().map(|p| p.3).sum::<f64>() / mine.len() as f64;
        let ss_tot: f64 = mine.iter().map(|p| (p.3 - mean).powi(2)).sum();
        cases.push(CaseStats {
            case: group,
            points: mine.len(),
            rms_mpa: (ss / mine.len() as f64).sqrt(),
            r2: 1.0 - ss / ss_tot,
        });
    }
    let total = r_abs_sq(model, params, &points);
    ((total / points.len().max(1) as f64).sqrt(), cases)
}

/// Evaluates a model with given parameters against curves (no fitting): (overall RMS, per case).
pub fn evaluate(model: &Model, params: &[f64], curves: &[Curve]) -> (f64, Vec<CaseStats>) {
    group_stats(model, params, &FitData::curves(curves))
}

/// [`evaluate`] against curves and general biaxial states.
pub fn evaluate_data(model: &Model, params: &[f64], data: FitData) -> (f64, Vec<CaseStats>) {
    group_stats(model, params, &data)
}

/// Fits several models; successful fits sorted by AIC (best first), those whose parameters the
/// data do not identify after them (unranked, [`crate::identifiability`]), failures apart.
pub fn fit_ranked(
    models: &[Model],
    curves: &[Curve],
    options: &FitOptions,
) -> (Vec<Fit>, Vec<(Model, FitError)>) {
    fit_ranked_with_progress(models, curves, options, &mut |_, _| {})
}

/// [`fit_ranked`], telling `progress` which model (index into `models`) is where.
pub fn fit_ranked_with_progress(
    models: &[Model],
    curves: &[Curve],
    options: &FitOptions,
    progress: &mut dyn FnMut(usize, Option<FitStage>),
) -> (Vec<Fit>, Vec<(Model, FitError)>) {
    fit_ranked_data(models, FitData::curves(curves), options, progress)
}

/// [`fit_ranked_with_progress`] on curves and general biaxial states.
pub fn fit_ranked_data(
    models: &[Model],
    data: FitData,
    options: &FitOptions,
    progress: &mut dyn FnMut(usize, Option<FitStage>),
) -> (Vec<Fit>, Vec<(Model, FitError)>) {
    let mut fits = Vec::new();
    let mut failures = Vec::new();
    for (index, model) in models.iter().enumerate() {
        progress(index, None);
        let result = fit_data(model, data, options, &mut |stage| {
            progress(index, Some(stage))
        });
        match result {
            Ok(fit) => fits.push(fit),
            Err(e) => failures.push((model.clone(), e)),
        }
    }
    fits.sort_by(|a, b| {
        let loose = |f: &Fit| !f.identifiability.identifiable();
        loose(a).cmp(&loose(b)).then(a.aic.total_cmp(&b.aic))
    });
    (fits, failures)
}

/// Starting values (full vectors; linear entries are re-solved) for the nonlinear parameters.
fn nonlinear_starts(model: &Model, data: &FitData) -> Vec<Vec<f64>> {
    let max_i1_minus_3: f64 = data
        .points()
        .iter()
        .map(|p| p.1.i1 - 3.0)
        .fold(0.0, f64::max);
    let max_chain_stretch_sq = (max_i1_minus_3 + 3.0) / 3.0;
    let mut starts = Vec::new();
    match model {
        Model::HartSmith => {
            for k1 in [0.0, 1e-5, 1e-4, 1e-3, 1e-2] {
                for k2 in [0.0, 0.1, 1.0, 5.0] {
                    starts.push(vec![0.0, k1, k2]);
                }
            }
        }
        Model::Alexander => {
            for k in [0.0, 1e-5, 1e-4, 1e-3, 1e-2] {
                for gamma in [0.1, 1.0, 10.0] {
                    starts.push(vec![0.0, k, 0.0, gamma, 0.0]);
                }
            }
        }
        Model::Gent => {
            for f in [1.01, 1.1, 1.5, 3.0, 10.0] {
                starts.push(vec![0.0, (max_i1_minus_3 * f).max(1.0)]);
            }
        }
        Model::ArrudaBoyce => {
            for f in [1.01, 1.1, 1.5, 3.0, 10.0] {
                starts.push(vec![0.0, (max_chain_stretch_sq * f).max(1.1)]);
            }
        }
        Model::Ogden(n) => {
            const ALPHAS: [f64; 13] = [
                -4.0, -2.0, -1.0, -0.5, 0.5, 1.0, 1.3, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0,
            ];
            let mut idx: Vec<usize> = (0..*n).collect();
            // All increasing index tuples (bounded: C(13, 6) = 1716 at most).
            loop {
                let mut s = vec![0.0; *n];
                s.extend(idx.iter().map(|&i| ALPHAS[i]));
                starts.push(s);
                let mut k = *n;
                let mut advanced = false;
                while k > 0 {
                    k -= 1;
                    if idx[k] < ALPHAS.len() - (*n - k) {
                        idx[k] += 1;
                        for j in k + 1..*n {
                            idx[j] = idx[j - 1] + 1;
                        }
                        advanced = true;
                        break;
                    }
                }
                if !advanced {
                    break;
                }
            }
        }
        Model::LambertDianiRey { f_degree, g_degree } => {
            for a0 in [0.05_f64, 0.2, 0.5] {
                for b0 in [0.01_f64, 0.1, 0.4] {
                    let mut s = vec![0.0; f_degree + g_degree + 2];
                    s[0] = a0.ln();
                    s[f_degree + 1] = b0.ln();
                    starts.push(s);
                }
            }
            if let Ok(route) = crate::route::paper_route(data.curves, *f_degree, *g_degree) {
                starts.push(route.coefficients());
            }
        }
        _ => {}
    }
    starts
}
