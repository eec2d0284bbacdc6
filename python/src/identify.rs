//! `identify_json(...)`: `dicstream identify` on arrays: the load cases' curves and the general
//! biaxial states checked by the CSV reader's own rules, every model fitted and ranked
//! (`identifier::ranking`), the JSON of `identify --json`.

use identifier::data::{BiaxialState, Curve, LoadCase};
use identifier::fit::{FitOptions, ResidualKind};
use identifier::models::parse_model_list;
use identifier::ranking::{identify, outcome_json};
use identifier::subsample::DEFAULT_MAX_FIT_POINTS;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// A load case's (stretch, nominal stress in MPa) columns.
type Columns = (Vec<f64>, Vec<f64>);

/// The fits of `models` (`"all"` or NAME[,NAME...]) to the curves given (each a pair of
/// equal-length sequences: stretch, nominal stress in MPa) and the general biaxial states
/// (rows λ1, λ2, P1, P2 in MPa), as the JSON text of `dicstream identify --json`. The GIL is
/// released while it fits.
#[pyfunction]
#[pyo3(signature = (
    *, uniaxial=None, biaxial=None, pure_shear=None, biaxial_general=vec![], model=None,
    residual=None, max_fit_points=None, threads=None
))]
#[allow(clippy::too_many_arguments)]
pub fn identify_json(
    py: Python<'_>,
    uniaxial: Option<Columns>,
    biaxial: Option<Columns>,
    pure_shear: Option<Columns>,
    biaxial_general: Vec<[f64; 4]>,
    model: Option<&str>,
    residual: Option<&str>,
    max_fit_points: Option<usize>,
    threads: Option<usize>,
) -> PyResult<String> {
    let value_error = |e: String| PyValueError::new_err(e);
    let mut curves = Vec::new();
    for (columns, case) in [
        (uniaxial, LoadCase::Uniaxial),
        (biaxial, LoadCase::Equibiaxial),
        (pure_shear, LoadCase::PureShear),
    ] {
        if let Some((stretch, stress)) = columns {
            curves.push(
                Curve::new(case, stretch, stress)
                    .map_err(|e| value_error(format!("reading {case} data: {e}")))?,
            );
        }
    }
    let mut states = Vec::with_capacity(biaxial_general.len());
    for (row, [l1, l2, p1, p2]) in biaxial_general.into_iter().enumerate() {
        let state = BiaxialState {
            stretch1: l1,
            stretch2: l2,
            nominal_stress1_mpa: p1,
            nominal_stress2_mpa: p2,
        };
        state.check().map_err(|e| {
            value_error(format!(
                "reading general biaxial data: row {}: {e}",
                row + 1
            ))
        })?;
        states.push(state);
    }
    if curves.is_empty() && states.is_empty() {
        return Err(value_error(
            "no data: give at least one of uniaxial, biaxial, pure_shear, biaxial_general".into(),
        ));
    }
    let models =
        parse_model_list(model.unwrap_or("all")).map_err(|e| value_error(e.to_string()))?;
    let residual = match residual.unwrap_or("absolute") {
        "absolute" => ResidualKind::Absolute,
        "relative" => ResidualKind::Relative,
        other => {
            return Err(value_error(format!(
                "residual {other:?}: expected absolute or relative"
            )))
        }
    };
    let options = FitOptions {
        residual,
        threads: threads.unwrap_or(1),
        ..FitOptions::default()
    };
    let max_fit_points = max_fit_points.unwrap_or(DEFAULT_MAX_FIT_POINTS);
    if max_fit_points < 2 {
        return Err(value_error("max_fit_points must be at least 2".into()));
    }
    let outcome = py.detach(|| {
        identify(
            &models,
            &curves,
            &states,
            &options,
            max_fit_points,
            &mut |_, _| {},
        )
    });
    if outcome.fits.is_empty() {
        return Err(value_error("no model could be fitted".into()));
    }
    Ok(outcome_json(&outcome).to_string())
}
