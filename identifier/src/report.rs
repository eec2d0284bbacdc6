//! JSON form of fits: `{"model", "params", "stderr", "rms_mpa", "rms_by_case_mpa", "r2",
//! "aic", "stable_up_to", "unstable_from", "converged", "initial_shear_modulus_mpa",
//! "identifiable", "condition_number", "warning", "fe_cards": {"abaqus", "ansys"}}`;
//! non-finite numbers become null.

use crate::fe_cards::fe_cards;
use crate::fit::Fit;
use crate::initial_modulus::initial_shear_modulus_mpa;
use serde_json::{json, Map, Value};

fn finite(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// One fit as JSON.
pub fn fit_json(fit: &Fit) -> Value {
    let mut params = Map::new();
    let mut stderr = Map::new();
    for ((name, value), std) in fit.param_names.iter().zip(&fit.params).zip(&fit.stderr) {
        params.insert(name.clone(), finite(*value));
        stderr.insert(name.clone(), std.map_or(Value::Null, finite));
    }
    let mut r2 = Map::new();
    let mut rms = Map::new();
    for c in &fit.cases {
        r2.insert(c.case.name().into(), finite(c.r2));
        rms.insert(c.case.name().into(), finite(c.rms_mpa));
    }
    let mu0 = initial_shear_modulus_mpa(&fit.model, &fit.params);
    let cards = fe_cards(fit, mu0);
    let mut stable = Map::new();
    let mut unstable = Map::new();
    for s in &fit.stability {
        stable.insert(s.case.name().into(), finite(s.stable_up_to));
        unstable.insert(
            s.case.name().into(),
            s.unstable_from.map_or(Value::Null, finite),
        );
    }
    json!({
        "model": fit.model.name(),
        "params": params,
        "stderr": stderr,
        "rms_mpa": finite(fit.rms_mpa),
        "rms_by_case_mpa": rms,
        "r2": r2,
        "aic": finite(fit.aic),
        "stable_up_to": stable,
        "unstable_from": unstable,
        "converged": fit.converged,
        "initial_shear_modulus_mpa": mu0.map_or(Value::Null, finite),
        "identifiable": fit.identifiability.identifiable(),
        "condition_number": finite(fit.identifiability.condition_number),
        "warning": fit.identifiability.warning(),
        "fe_cards": {"abaqus": cards.abaqus, "ansys": cards.ansys},
    })
}
