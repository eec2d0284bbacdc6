//! The run's PNG figures, drawn at the end from what the run wrote: the stress-stretch curves
//! of both tests with the fitted models and the paper's f(I1) and g(I2) plots (Figs. 7, 8, 13,
//! 14, from the identifier's journal), the strain map of the last field over the reference
//! image (Fig. 12d), and the latency distribution.

use crate::latency::Latency;
use anyhow::Context;
use identifier::data::Curve;
use identifier::fit::{fit_ranked, FitOptions};
use identifier::plot::{chart, Series};
use std::path::{Path, PathBuf};
use wire::colour_map::ColourScale;
use wire::colour_range::RangeChoice;

/// The load path of the journal as curves (canonical cases with enough points).
pub fn journal_curves(journal: &Path) -> anyhow::Result<Vec<Curve>> {
    let states: Vec<_> = identifier::journal::read(journal)?
        .iter()
        .map(|p| p.state)
        .collect();
    let tolerance = identifier::online::OnlineConfig::default().classify_tolerance;
    Ok(identifier::data::canonical_curves(&states, tolerance))
}

/// Stress-stretch per case with the ranked fits, f(I1) and g(I2) with the paper's route, into
/// `dir`. Returns the files written, and why f(I1) and g(I2) have no data points when the
/// route could not run (their titles say it too).
pub fn identification_figures(
    dir: &Path,
    journal: &Path,
    models: &[identifier::models::Model],
    options: identifier::plot::PlotOptions,
) -> anyhow::Result<(Vec<PathBuf>, Option<String>)> {
    let curves = journal_curves(journal)?;
    if curves.is_empty() {
        return Ok((Vec::new(), None));
    }
    let (fits, _failures) = fit_ranked(models, &curves, &FitOptions::default());
    // Without both cases the route cannot run: the f(I1) and g(I2) plots show the identified
    // law and say why they have no points.
    let route = identifier::route::paper_route(&curves, 2, 2).map_err(|e| e.to_string());
    let written = identifier::plot::write_plots(
        dir,
        &curves,
        &fits,
        route.as_ref().map_err(String::as_str),
        options,
    )?;
    Ok((written, route.err()))
}

/// The colour map of a field's exx over its origin image, with its title (the strain measure,
/// the frame) and a colour bar of its range in %, as PNG at `path`; returns the colour scale
/// (`range`: `wire::colour_range`'s choice; the automatic one's floor is the field's own
/// strain noise, measured past the strains' window, `strain_window_nodes`).
pub fn strain_map(
    path: &Path,
    grey: &[u16],
    width: usize,
    field: &correlator::Field,
    title: &str,
    range: RangeChoice,
    strain_window_nodes: usize,
) -> anyhow::Result<ColourScale> {
    let exx = |n: &correlator::Node| n.exx;
    let lag = wire::colour_range::strain_noise_lag_nodes(strain_window_nodes);
    let scale = correlator::output::field_colour_scale(field, exx, true, lag, range);
    let rgb = correlator::output::colour_map_rgb(grey, width, field, exx, &scale);
    let label = |v: f64| format!("{:+.3} %", 100.0 * v);
    identifier::map_figure::write(
        path,
        &identifier::map_figure::MapFigure {
            rgb: &rgb,
            width_px: width,
            height_px: grey.len() / width,
            title,
            scale,
            label: &label,
            bar_title: None,
        },
    )
    .with_context(|| path.display().to_string())?;
    Ok(scale)
}

/// Latency (ms) against log10 of 1/(1 − percentile), the usual HdrHistogram plot.
pub fn latency_png(path: &Path, curves: &[(&str, &Latency)]) -> anyhow::Result<()> {
    let series: Vec<Series> = curves
        .iter()
        .filter(|(_, l)| l.count() > 0)
        .map(|(label, latency)| Series {
            label: format!("{label} ({} samples)", latency.count()),
            points: latency
                .distribution()
                .into_iter()
                .filter(|&(_, q)| q < 1.0)
                .map(|(ms, q)| ((1.0 / (1.0 - q)).log10(), ms))
                .collect(),
            markers: false,
        })
        .collect();
    if series.is_empty() {
        return Ok(());
    }
    Ok(chart(
        path,
        "latency from capture",
        "percentile (log10 1/(1-p): 1 = 90 %, 2 = 99 %, 3 = 99.9 %)",
        "latency (ms)",
        &series,
    )?)
}
