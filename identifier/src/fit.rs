//! Fitting one model of the catalogue to any combination of load cases, with statistics.
//!
//! Parameters in which the stress is linear are solved by linear least squares (SVD); the
//! others by Levenberg-Marquardt from a grid of starts, the linear ones re-solved at each start
//! (variable projection for the starts only). Objective: Σ_cases w_c Σ_points r², with
//! r = P_model − P_data (absolute, MPa) or (P_model − P_data)/|P_data| (relative).

use crate::data::{Curve, LoadCase};
use crate::lsq::{self, LsqError};
use crate::models::Model;
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

/// Fit options.
#[derive(Clone, Debug, Default)]
pub struct FitOptions {
    pub residual: ResidualKind,
    /// Per-load-case weights w_c (default 1).
    pub weights: BTreeMap<LoadCase, f64>,
    /// Extra starting points (full parameter vectors) for the nonlinear search.
    pub extra_starts: Vec<Vec<f64>>,
    /// Start the nonlinear search from these parameters alone (a refit after a few more
    /// points: the last solution is next to the new one); the full multi-start search runs
    /// only if that start fails.
    pub warm_start: Option<Vec<f64>>,
}

/// Statistics of one load case.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseStats {
    pub case: LoadCase,
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
#[derive(Clone, Debug, PartialEq)]
pub enum FitError {
    NoData,
    Lsq { model: String, error: LsqError },
    ZeroStressRelative { case: LoadCase, stretch: f64 },
    NoValidStart { model: String },
    BadWeight { case: LoadCase, weight: f64 },
}

impl std::fmt::Display for FitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FitError::NoData => write!(f, "no data: give at least one load case"),
            FitError::Lsq { model, error } => write!(f, "model {model}: {error}"),
            FitError::ZeroStressRelative { case, stretch } => write!(
                f,
                "relative residuals need non-zero stresses: {case} point at stretch {stretch} has zero stress"
            ),
            FitError::NoValidStart { model } => {
                write!(f, "model {model}: undefined at every starting point for these stretches")
            }
            FitError::BadWeight { case, weight } => {
                write!(f, "weight of {case} must be finite and > 0, got {weight}")
            }
        }
    }
}

impl std::error::Error for FitError {}

struct Problem<'a> {
    model: &'a Model,
    points: Vec<(LoadCase, f64, f64)>,
    /// sqrt(w_c) / scale_i per point.
    factors: Vec<f64>,
}

impl Problem<'_> {
    fn residuals(&self, p: &[f64]) -> Option<DVector<f64>> {
        let mut r = DVector::zeros(self.points.len());
        for (k, &(case, stretch, stress)) in self.points.iter().enumerate() {
            let model = self.model.nominal_stress_mpa(p, case, stretch)?;
            r[k] = (model - stress) * self.factors[k];
        }
        Some(r)
    }

    /// Solves the linear parameters with the nonlinear ones of `p` fixed; returns the full vector.
    fn solve_linear(&self, p: &[f64], linear: &[bool]) -> Result<Vec<f64>, LsqError> {
        let lin_idx: Vec<usize> = (0..p.len()).filter(|&i| linear[i]).collect();
        let m = self.points.len();
        let mut base = p.to_vec();
        for &i in &lin_idx {
            base[i] = 0.0;
        }
        let r0 = self.residuals(&base).ok_or(LsqError::NonFiniteStart)?;
        let mut design = DMatrix::zeros(m, lin_idx.len());
        for (col, &i) in lin_idx.iter().enumerate() {
            let mut q = base.clone();
            q[i] = 1.0;
            let r1 = self.residuals(&q).ok_or(LsqError::NonFiniteStart)?;
            design.set_column(col, &(r1 - &r0));
        }
        let x = lsq::linear_least_squares(&design, &(-r0))?;
        let mut out = base;
        for (col, &i) in lin_idx.iter().enumerate() {
            out[i] = x[col];
        }
        Ok(out)
    }
}

/// Number of best starts refined by Levenberg-Marquardt.
pub const LM_STARTS_REFINED: usize = 6;

/// Fits `model` to `curves`.
pub fn fit_model(model: &Model, curves: &[Curve], options: &FitOptions) -> Result<Fit, FitError> {
    let name = model.name();
    if curves.iter().all(|c| c.is_empty()) {
        return Err(FitError::NoData);
    }
    let mut points = Vec::new();
    let mut factors = Vec::new();
    for curve in curves {
        let weight = options.weights.get(&curve.case).copied().unwrap_or(1.0);
        if !(weight.is_finite() && weight > 0.0) {
            return Err(FitError::BadWeight {
                case: curve.case,
                weight,
            });
        }
        for (&stretch, &stress) in curve.stretch.iter().zip(&curve.nominal_stress_mpa) {
            let scale = match options.residual {
                ResidualKind::Absolute => 1.0,
                ResidualKind::Relative => {
                    if stress == 0.0 {
                        return Err(FitError::ZeroStressRelative {
                            case: curve.case,
                            stretch,
                        });
                    }
                    stress.abs()
                }
            };
            points.push((curve.case, stretch, stress));
            factors.push(weight.sqrt() / scale);
        }
    }
    let m = points.len();
    let n = model.param_names().len();
    if m < n + 1 {
        return Err(FitError::Lsq {
            model: name,
            error: LsqError::TooFewPoints {
                points: m,
                params: n,
            },
        });
    }
    let problem = Problem {
        model,
        points,
        factors,
    };
    let linear = model.linear_params();
    let lsq_err = |error| FitError::Lsq {
        model: name.clone(),
        error,
    };

    let (params, converged) = if linear.iter().all(|&l| l) {
        (
            problem
                .solve_linear(&vec![0.0; n], &linear)
                .map_err(lsq_err)?,
            true,
        )
    } else if let Some(warm) = options
        .warm_start
        .as_ref()
        .filter(|w| w.len() == n)
        .and_then(|w| {
            let start = if linear.iter().any(|&l| l) {
                problem.solve_linear(w, &linear).ok()?
            } else {
                w.clone()
            };
            lsq::levenberg_marquardt(&|p: &[f64]| problem.residuals(p), &start, m).ok()
        })
    {
        (warm.params, warm.converged)
    } else {
        let mut candidates: Vec<(f64, Vec<f64>)> = Vec::new();
        let mut last_error = None;
        let starts = nonlinear_starts(model, curves)
            .into_iter()
            .chain(options.extra_starts.iter().cloned());
        for start in starts {
            assert_eq!(
                start.len(),
                n,
                "start length must match the parameter count"
            );
            let has_linear = linear.iter().any(|&l| l);
            let full = if has_linear {
                problem.solve_linear(&start, &linear)
            } else {
                Ok(start)
            };
            match full {
                Ok(p) => {
                    if let Some(r) = problem
                        .residuals(&p)
                        .filter(|r| r.iter().all(|v| v.is_finite()))
                    {
                        candidates.push((r.norm_squared(), p));
                    }
                }
                Err(e) => last_error = Some(e),
            }
        }
        if candidates.is_empty() {
            return Err(match last_error {
                Some(LsqError::TooFewPoints { .. }) | Some(LsqError::RankDeficient { .. }) => {
                    lsq_err(last_error.unwrap())
                }
                _ => FitError::NoValidStart { model: name },
            });
        }
        candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best: Option<lsq::LmResult> = None;
        for (_, start) in candidates.iter().take(LM_STARTS_REFINED) {
            let res = lsq::levenberg_marquardt(&|p: &[f64]| problem.residuals(p), start, m);
            if let Ok(res) = res {
                if best.as_ref().is_none_or(|b| res.cost < b.cost) {
                    best = Some(res);
                }
            }
        }
        let best = best.ok_or(FitError::NoValidStart {
            model: name.clone(),
        })?;
        (best.params, best.converged)
    };

    let r = problem.residuals(&params).ok_or(FitError::NoValidStart {
        model: name.clone(),
    })?;
    let objective = r.norm_squared();
    let jac = lsq::numeric_jacobian(&|p: &[f64]| problem.residuals(p), &params, m);
    let variance = objective / (m - n) as f64;
    let stderr = match lsq::inverse_normal_matrix(&jac) {
        Some(cov) => (0..n)
            .map(|i| Some((variance * cov[(i, i)]).max(0.0).sqrt()))
            .collect(),
        None => vec![None; n],
    };
    let mut cases = Vec::new();
    let mut total_sq = 0.0;
    for curve in curves {
        let predicted: Vec<f64> = curve
            .stretch
            .iter()
            .map(|&l| {
                model
                    .nominal_stress_mpa(&params, curve.case, l)
                    .unwrap_or(f64::NAN)
            })
            .collect();
        let ss_res: f64 = predicted
            .iter()
            .zip(&curve.nominal_stress_mpa)
            .map(|(p, d)| (p - d).powi(2))
            .sum();
        let mean = curve.nominal_stress_mpa.iter().sum::<f64>() / curve.len() as f64;
        let ss_tot: f64 = curve
            .nominal_stress_mpa
            .iter()
            .map(|d| (d - mean).powi(2))
            .sum();
        total_sq += ss_res;
        cases.push(CaseStats {
            case: curve.case,
            points: curve.len(),
            rms_mpa: (ss_res / curve.len() as f64).sqrt(),
            r2: 1.0 - ss_res / ss_tot,
        });
    }
    let max_stretch = curves
        .iter()
        .flat_map(|c| c.stretch.iter().copied())
        .fold(1.0, f64::max);
    let stability = LoadCase::ALL
        .iter()
        .map(|&case| drucker_stability(model, &params, case, max_stretch))
        .collect();
    Ok(Fit {
        model: model.clone(),
        param_names: model.param_names(),
        params,
        stderr,
        rms_mpa: (total_sq / m as f64).sqrt(),
        cases,
        aic: m as f64 * (objective.max(f64::MIN_POSITIVE) / m as f64).ln() + 2.0 * n as f64,
        objective,
        stability,
        converged,
    })
}

/// Evaluates a model with given parameters against curves (no fitting): (overall RMS, per case).
pub fn evaluate(model: &Model, params: &[f64], curves: &[Curve]) -> (f64, Vec<CaseStats>) {
    let mut cases = Vec::new();
    let mut total_sq = 0.0;
    let mut m = 0;
    for curve in curves {
        let ss: f64 = curve
            .stretch
            .iter()
            .zip(&curve.nominal_stress_mpa)
            .map(|(&l, d)| {
                (model
                    .nominal_stress_mpa(params, curve.case, l)
                    .unwrap_or(f64::NAN)
                    - d)
                    .powi(2)
            })
            .sum();
        let mean = curve.nominal_stress_mpa.iter().sum::<f64>() / curve.len() as f64;
        let ss_tot: f64 = curve
            .nominal_stress_mpa
            .iter()
            .map(|d| (d - mean).powi(2))
            .sum();
        total_sq += ss;
        m += curve.len();
        cases.push(CaseStats {
            case: curve.case,
            points: curve.len(),
            rms_mpa: (ss / curve.len() as f64).sqrt(),
            r2: 1.0 - ss / ss_tot,
        });
    }
    ((total_sq / m.max(1) as f64).sqrt(), cases)
}

/// Fits several models; successful fits sorted by AIC (best first), failures listed apart.
pub fn fit_ranked(
    models: &[Model],
    curves: &[Curve],
    options: &FitOptions,
) -> (Vec<Fit>, Vec<(Model, FitError)>) {
    let mut fits = Vec::new();
    let mut failures = Vec::new();
    for model in models {
        match fit_model(model, curves, options) {
            Ok(fit) => fits.push(fit),
            Err(e) => failures.push((model.clone(), e)),
        }
    }
    fits.sort_by(|a, b| a.aic.total_cmp(&b.aic));
    (fits, failures)
}

/// Starting values (full vectors; linear entries are re-solved) for the nonlinear parameters.
fn nonlinear_starts(model: &Model, curves: &[Curve]) -> Vec<Vec<f64>> {
    let mut max_i1_minus_3: f64 = 0.0;
    for c in curves {
        for &l in &c.stretch {
            max_i1_minus_3 = max_i1_minus_3.max(c.case.invariants(l).0 - 3.0);
        }
    }
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
            if let Ok(route) = crate::route::paper_route(curves, *f_degree, *g_degree) {
                starts.push(route.coefficients());
            }
        }
        _ => {}
    }
    starts
}
