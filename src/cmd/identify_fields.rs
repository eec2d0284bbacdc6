//! `dicstream identify --fields DIR [--forces rig.csv]`: the field route offline on a run's
//! results folder (`identifier::saved_fields::fit_saved`, the live route's own feed and fit),
//! with the run's camera view and cruciform from its `config.toml`. Prints the ranked fits (or,
//! with `--json`, the JSON alone on stdout); a fit whose parameters the fields do not identify
//! (σ ≥ |value|, or the scaled Jacobian's condition number above 1e8:
//! `identifier::identifiability`) is said on stderr and left unranked, as the gauge route does;
//! a model the states cannot separate at all is refused by the fit with its condition number.

use super::identify::IdentifyArgs;
use anyhow::{bail, Context};
use identifier::field_route::FieldFit;
use identifier::identifiability::Identifiability;
use identifier::models::parse_model_list;
use identifier::saved_fields::{fit_saved, SavedFit};
use serde_json::{json, Value};
use std::io::Write;
use std::path::Path;

/// Fits the saved fields of results folder `dir`; `out` gets the table or the JSON alone.
pub fn run(
    args: &IdentifyArgs,
    dir: &Path,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<()> {
    let others = [
        (args.uniaxial.is_some(), "--uniaxial"),
        (args.biaxial.is_some(), "--biaxial"),
        (args.pure_shear.is_some(), "--pure-shear"),
        (args.biaxial_general.is_some(), "--biaxial-general"),
        (args.gauge_length_mm.is_some(), "--gauge-length-mm"),
        (args.section_mm2.is_some(), "--section-mm2"),
        (args.plot.is_some(), "--plot"),
        (args.cards.is_some(), "--cards"),
    ];
    if let Some((_, flag)) = others.iter().find(|(given, _)| *given) {
        bail!(
            "{flag} does not apply to --fields (a run's saved fields, fitted by the virtual \
             fields method); give it without --fields"
        );
    }
    let config_path = dir.join("config.toml");
    let config = live::RunConfig::read(Some(&config_path))
        .with_context(|| format!("{}: the run's configuration", dir.display()))?;
    let models = match &args.model {
        Some(list) => parse_model_list(list)?,
        None => config.identifier.models.0.clone(),
    };
    let saved = fit_saved(
        dir,
        &config.field_route_settings(),
        &models,
        args.forces.as_deref(),
    )?;
    if !saved.per_grip {
        writeln!(
            err,
            "note: {}/frames.csv has no grip forces of its own (an older run): each axis's mean \
             force taken for both its grips",
            dir.display()
        )?;
    }
    let identifiability: Vec<Identifiability> = saved.fits.fits.iter().map(identify).collect();
    for (fit, id) in saved.fits.fits.iter().zip(&identifiability) {
        if let Some(w) = id.warning() {
            writeln!(err, "{}: {w}", fit.model.name())?;
        }
    }
    for (model, why) in &saved.fits.refused {
        writeln!(err, "not fitted: {model}: {why}")?;
    }
    if args.json {
        let value = saved_json(dir, args.forces.as_deref(), &saved, &identifiability);
        writeln!(out, "{}", serde_json::to_string_pretty(&value)?)?;
    } else {
        print_table(out, &saved, &identifiability)?;
    }
    if saved.fits.fits.is_empty() {
        bail!("no model could be fitted to the fields of {}", dir.display());
    }
    Ok(())
}

/// What the fields say of a fit's parameters (the gauge route's test).
fn identify(fit: &FieldFit) -> Identifiability {
    let sigma: Vec<Option<f64>> = fit
        .fit
        .sigma
        .iter()
        .map(|s| s.is_finite().then_some(*s))
        .collect();
    Identifiability::new(
        &fit.model.param_names(),
        &fit.fit.params,
        &sigma,
        fit.fit.condition,
    )
}

/// The ranks shown: identifiable fits in AIC order, None for the others.
fn ranks(identifiability: &[Identifiability]) -> Vec<Option<usize>> {
    let mut rank = 0;
    identifiability
        .iter()
        .map(|id| {
            id.identifiable().then(|| {
                rank += 1;
                rank
            })
        })
        .collect()
}

fn saved_json(
    dir: &Path,
    forces: Option<&Path>,
    saved: &SavedFit,
    identifiability: &[Identifiability],
) -> Value {
    let mut value = identifier::process::fits_json(&saved.fits);
    if let Some(fits) = value["fits"].as_array_mut() {
        for ((fit, id), rank) in fits.iter_mut().zip(identifiability).zip(ranks(identifiability)) {
            fit["rank"] = json!(rank);
            fit["warning"] = json!(id.warning());
        }
    }
    value["source"] = json!({
        "fields": dir.display().to_string(),
        "forces": forces.map_or_else(|| dir.join("frames.csv").display().to_string(), |p| p.display().to_string()),
        "per_grip_forces": saved.per_grip,
    });
    value["fields_read"] = json!(saved.fields_read);
    value["counters"] = json!(saved.counters);
    value["last_dropped"] = json!(saved.last_dropped);
    value
}

fn print_table(
    out: &mut dyn Write,
    saved: &SavedFit,
    identifiability: &[Identifiability],
) -> std::io::Result<()> {
    let fits = &saved.fits;
    let c = &saved.counters;
    writeln!(
        out,
        "{} frames fitted of {} field files ({} not a new loading state, {} with a grip at rest, \
         {} thinned); {} virtual fields dropped; stretches reached: major {:.3}, minor {:.3}",
        fits.frames,
        saved.fields_read,
        c.not_loading,
        c.grips_unloaded,
        c.thinned,
        c.virtual_fields_dropped,
        fits.max_stretches[0],
        fits.max_stretches[1]
    )?;
    writeln!(
        out,
        "{:>2} {:<22} {:>9} {:>9} {:>9} {:>10}  params ± std",
        "#", "model", "aic", "rms_n", "equations", "condition"
    )?;
    for ((fit, rank), _) in fits.fits.iter().zip(ranks(identifiability)).zip(identifiability) {
        let params: Vec<String> = fit
            .model
            .param_names()
            .iter()
            .zip(&fit.fit.params)
            .zip(&fit.fit.sigma)
            .map(|((n, v), s)| format!("{n}={v:.4e}±{s:.1e}"))
            .collect();
        writeln!(
            out,
            "{:>2} {:<22} {:>9.1} {:>9.3} {:>9} {:>10.2e}  {}",
            rank.map_or("-".to_string(), |r| r.to_string()),
            fit.model.name(),
            fit.aic,
            fit.fit.rms_n,
            fit.fit.equations,
            fit.fit.condition,
            params.join(" ")
        )?;
    }
    writeln!(
        out,
        "(virtual fields method: each equation a virtual field's internal work against its grip's \
         force, N; `-`: parameters not identifiable from these fields, not ranked)"
    )
}
