//! The files a run writes at its end from what it recorded: the latency histograms (also
//! rewritten during the run), `latency.png`, the identification figures, `strain_map.png` (on
//! the camera's host: drawn over the field's origin image),
//! `forces.png` and `stretch_states.png` (coloured by the identifier's `states.csv`); once the field route is judged,
//! `field_route_law.png` and `force_balance.png`.
//! A file that cannot be written is a note, never the end of the others.

use super::StrainMapInfo;
use crate::config::RunConfig;
use crate::latency::Latency;
use crate::recorder::Recorder;
use crate::results::ResultsDir;
use wire::files::FileError;

/// What the end of the run wrote: what `strain_map.png` shows, and the files that could not
/// be written, each with why.
pub(super) struct Outputs {
    pub(super) strain_map: Option<StrainMapInfo>,
    pub(super) notes: Vec<String>,
}

/// The latency histograms' files and what each holds.
fn histograms(recorder: &Recorder) -> [(&'static str, &Latency); 2] {
    [
        ("latency.hgrm", &recorder.latency_field),
        (
            "latency_identification.hgrm",
            &recorder.latency_identification,
        ),
    ]
}

fn write_histogram(results: &ResultsDir, name: &str, latency: &Latency) -> Result<(), FileError> {
    wire::files::write_atomic(&results.path(name), latency.hgrm().as_bytes())
}

/// `latency.hgrm` (capture to field) and `latency_identification.hgrm`.
pub(super) fn write_histograms(results: &ResultsDir, recorder: &Recorder) -> Result<(), FileError> {
    histograms(recorder)
        .into_iter()
        .try_for_each(|(name, latency)| write_histogram(results, name, latency))
}

/// Writes every file of the end of the run.
pub(super) fn write(config: &RunConfig, results: &ResultsDir, recorder: &Recorder) -> Outputs {
    let mut notes = Vec::new();
    let mut keep = |what: &str, result: anyhow::Result<()>| {
        if let Err(e) = result {
            notes.push(format!("{what}: {e:#}"));
        }
    };
    for (name, latency) in histograms(recorder) {
        keep(
            name,
            write_histogram(results, name, latency).map_err(Into::into),
        );
    }
    let curves = [
        ("capture to field", &recorder.latency_field),
        (
            "capture to identification",
            &recorder.latency_identification,
        ),
    ];
    keep(
        "latency.png",
        crate::figures::latency_png(&results.path("latency.png"), &curves),
    );
    let models = &config.identifier.models.0;
    let options = identifier::plot::PlotOptions {
        all_models: config.identifier.plot_all_models,
    };
    let figures =
        crate::figures::identification_figures(&results.root, &results.journal(), models, options);
    if let Ok((_, Some(why))) = &figures {
        // Written, without points: not a missing file, said on stderr and in their titles.
        eprintln!("f_I1.png, g_I2.png: no data points, the paper's route did not run: {why}");
    }
    keep("identification figures", figures.map(|_| ()));
    keep(
        "forces.png",
        crate::mechanics_figures::forces_png(&results.rig_csv(), &results.path("forces.png"))
            .map(|_| ()),
    );
    let model = best_field_model(&results.identification_json());
    keep(
        "stretch_states.png",
        crate::mechanics_figures::stretch_states_png(
            &results.fields(),
            Some(&results.states_csv()),
            model.as_deref(),
            &results.path("stretch_states.png"),
        )
        .map(|_| ()),
    );
    // Drawn over the field's origin image: a host without the camera (`[run] processes`) has
    // the fields, not the frames; the camera's host draws it.
    if !config.runs(crate::config::BenchProcess::Producer) {
        return Outputs {
            strain_map: None,
            notes,
        };
    }
    let strain_map = strain_map(results, recorder, config.run.map_range);
    let strain_map = strain_map.unwrap_or_else(|e| {
        keep("strain_map.png", Err(e));
        None
    });
    Outputs { strain_map, notes }
}

/// The field route's best fit in `identification.json` (its first identifiable one: the fit
/// `states.csv`'s contributions are to), if any.
fn best_field_model(identification_json: &std::path::Path) -> Option<String> {
    let text = std::fs::read_to_string(identification_json).ok()?;
    let json: serde_json::Value = serde_json::from_str(&text).ok()?;
    json["field_route"]["fits"]
        .as_array()?
        .iter()
        .find(|fit| fit["identifiable"] == true)
        .and_then(|fit| Some(fit["model"].as_str()?.to_string()))
}

/// `field_route_law.png` and `force_balance.png` when the field route identified a law and
/// the run has its truth (`field`: the route's acceptance); what could not be written goes to
/// `notes`, each with why.
pub(super) fn field_route_figures(
    config: &RunConfig,
    results: &ResultsDir,
    field: Option<&crate::field_acceptance::FieldAcceptance>,
    notes: &mut Vec<String>,
) {
    let (Some(field), Ok(truth)) = (field, config.law()) else {
        return;
    };
    use crate::field_route_figure::{field_route_law_png, force_balance_png};
    let law = field_route_law_png(&results.path("field_route_law.png"), &truth, field);
    let balance = force_balance_png(
        &results.path("force_balance.png"),
        field,
        &results.frames_csv(),
    );
    for (name, result) in [("field_route_law.png", law), ("force_balance.png", balance)] {
        if let Err(e) = result {
            notes.push(format!("{name}: {e:#}"));
        }
    }
}

/// The most strained field of the last test over the image its mesh is defined in (its origin
/// frame), as `strain_map.png`; none without a field, an error saying why without the image.
fn strain_map(
    results: &ResultsDir,
    recorder: &Recorder,
    range: wire::colour_range::RangeChoice,
) -> anyhow::Result<Option<StrainMapInfo>> {
    let Some((header, nodes)) = &recorder.peak_field else {
        return Ok(None);
    };
    let (frame, pixels) = recorder
        .origin_frames
        .get(header.origin_frame_id)
        .map_err(|why| {
            anyhow::anyhow!(
                "the field of frame {} cannot be drawn: {why}",
                header.frame_id
            )
        })?;
    let field = crate::recorder::to_correlator_field(header, nodes);
    let path = results.path("strain_map.png");
    let measure = wire::StrainMeasure::from_code(header.strain_measure).map_or("?", |m| m.name());
    let title = format!(
        "exx ({measure} strain), frame {} from frame {}",
        header.frame_id, header.origin_frame_id
    );
    // The run's correlator computes its strains on the library's window.
    let window = correlator::CorrelatorSettings::default().strain_window_nodes;
    let scale = crate::figures::strain_map(
        &path,
        pixels,
        frame.width_px as usize,
        &field,
        &title,
        range,
        window,
    )?;
    Ok(Some(StrainMapInfo {
        frame_id: header.frame_id,
        origin_frame_id: header.origin_frame_id,
        measure,
        exx_colours: scale,
    }))
}
