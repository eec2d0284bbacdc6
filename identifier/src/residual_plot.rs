//! `residuals.png`: the best-ranked fit's residuals P_model − P_data (MPa) against the loaded
//! stretch, one coloured line per load case or the general biaxial states (points in stretch
//! order; [`chart`] draws marker series all black, so cases would not be told apart), and a
//! zero line: a trend along the stretch says the model misses a feature of the data that the
//! RMS hides.

use crate::fit::{Fit, FitData};
use crate::plot::{chart, PlotError, Series};
use std::path::Path;

/// Writes the residual plot of `fit` against `data` at `path`.
pub fn write_residual_plot(path: &Path, data: FitData, fit: &Fit) -> Result<(), PlotError> {
    let points = data.points();
    let mut series: Vec<Series> = Vec::new();
    for group in data.groups() {
        let mut residuals: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.0 == group)
            .filter_map(|(_, k, stretch, stress)| {
                let model = fit.model.nominal_stress_at(&fit.params, k, None)?;
                Some((*stretch, model - stress))
            })
            .collect();
        residuals.sort_by(|a, b| a.0.total_cmp(&b.0));
        series.push(Series {
            label: format!("{group} ({} points)", residuals.len()),
            points: residuals,
            markers: false,
        });
    }
    let max_stretch = data.max_stretch();
    series.push(Series {
        label: "zero".into(),
        points: vec![(1.0, 0.0), (max_stretch, 0.0)],
        markers: false,
    });
    chart(
        path,
        &format!(
            "residuals of {} (RMS {:.3e} MPa)",
            fit.model.name(),
            fit.rms_mpa
        ),
        "loaded stretch",
        "P_model - P_data (MPa)",
        &series,
    )
}
