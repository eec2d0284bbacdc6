//! The offline identification as `dicstream identify` runs it on data in memory: every model
//! fitted (on a load-path-preserving subsample above the limit of fitted points; RMS and R²
//! then over every point), ranked by AIC, with the paper's route, and the JSON of the outcome
//! (`identify --json`, and the Python module's `identify`): one definition for both.

use crate::data::{BiaxialState, Curve};
use crate::fit::{evaluate_data, fit_ranked_data, Fit, FitData, FitError, FitOptions, FitStage};
use crate::identifiability::ranks;
use crate::models::Model;
use crate::report::fit_json;
use crate::route::{paper_route, RouteResult};
use crate::subsample::{subsample_data, Subsample};
use serde_json::{json, Value};

/// What the fits gave: the ranked fits, the models that failed, the paper's route (if it
/// could run) and the subsample fitted (if the data were too many).
pub struct Outcome {
    pub fits: Vec<Fit>,
    pub failures: Vec<(Model, FitError)>,
    pub route: Result<RouteResult, String>,
    pub subsample: Option<Subsample>,
}

/// Fits `models` to `curves` and `states` (to their subsample above `max_fit_points`), ranked
/// by AIC; `progress` hears each model's index and stage.
pub fn identify(
    models: &[Model],
    curves: &[Curve],
    states: &[BiaxialState],
    options: &FitOptions,
    max_fit_points: usize,
    progress: &mut dyn FnMut(usize, Option<FitStage>),
) -> Outcome {
    let all = FitData { curves, states };
    let subsampled = subsample_data(curves, states, max_fit_points);
    let fitted = subsampled.as_ref().map_or(all, |(c, s, _)| FitData {
        curves: c,
        states: s,
    });
    let (mut fits, failures) = fit_ranked_data(models, fitted, options, progress);
    if subsampled.is_some() {
        for fit in &mut fits {
            (fit.rms_mpa, fit.cases) = evaluate_data(&fit.model, &fit.params, all);
        }
    }
    Outcome {
        fits,
        failures,
        route: paper_route(curves, 2, 2).map_err(|e| e.to_string()),
        subsample: subsampled.map(|(_, _, s)| s),
    }
}

/// The outcome as one object: the fits (each with its rank among the identifiable ones, null
/// for the others), the failures, the paper's route and the subsample.
pub fn outcome_json(outcome: &Outcome) -> Value {
    let ranks = ranks(outcome.fits.iter().map(|fit| &fit.identifiability));
    let fits_json: Vec<Value> = outcome
        .fits
        .iter()
        .zip(ranks)
        .map(|(fit, rank)| {
            let mut value = fit_json(fit);
            value["rank"] = json!(rank);
            value
        })
        .collect();
    let failures_json: Vec<Value> = outcome
        .failures
        .iter()
        .map(|(m, e)| json!({"model": m.name(), "error": e.to_string()}))
        .collect();
    let mut json_out = json!({"fits": fits_json, "failures": failures_json});
    if let Ok(r) = &outcome.route {
        json_out["paper_route"] = json!({"a": r.a, "b": r.b, "c": r.c});
    }
    if let Some(s) = &outcome.subsample {
        json_out["subsample"] = subsample_json(s);
    }
    json_out
}

/// The JSON note of a subsampled fit.
fn subsample_json(s: &Subsample) -> Value {
    json!({
        "points_total": s.points_total,
        "points_fitted": s.points_fitted,
        "max_fit_points": s.max_points,
        "note": "parameters, stderr, objective and aic from the fitted subsample (each curve's ends and shape kept); rms and r2 over every point",
    })
}
