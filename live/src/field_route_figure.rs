//! The field route's figures (issue 25, deliverable 3): `field_route_law.png`, the law it
//! identified against the specimen's true one in uniaxial, equibiaxial and pure-shear nominal
//! stress over the stretches the field reached (what [`crate::field_acceptance`] judges, so a
//! user sees where along each curve it departs), and `force_balance.png`, each grip's measured
//! force against the force its virtual fields compute from the field under that law, over the
//! test's time (paper section 4.c).

use crate::field_acceptance::{reach, FieldAcceptance, CASES};
use identifier::law::InvariantLaw;
use identifier::models::Model;
use identifier::plot::{chart_paired, Series};
use serde_json::Value;
use std::path::Path;

/// Stretches per true curve (a line).
const LINE_SAMPLES: usize = 100;
/// Stretches per identified curve (markers, sparse enough to see the line under them).
const MARKER_SAMPLES: usize = 20;

/// Stretches 1..=max in `samples` steps.
fn stretches(max: f64, samples: usize) -> impl Iterator<Item = f64> {
    (0..=samples).map(move |k| 1.0 + (max - 1.0) * k as f64 / samples as f64)
}

/// The figure's series: per case the field reached, the true law (line) and the identified
/// one (markers, in the line's colour); empty when the route identified no law or reached no stretch.
pub fn series(truth: &InvariantLaw, acceptance: &FieldAcceptance) -> Vec<Series> {
    let (Some(name), Some(reached)) = (&acceptance.model, &acceptance.reach) else {
        return Vec::new();
    };
    let Ok(model) = Model::parse(name) else {
        return Vec::new();
    };
    let p = &acceptance.params;
    let mut out = Vec::new();
    for (case_name, case, true_curve) in CASES {
        // As the acceptance compares them: each case up to its own states' reach.
        let Some(max) = reach(case, reached) else {
            continue;
        };
        out.push(Series {
            label: format!("{case_name}: true law"),
            points: stretches(max, LINE_SAMPLES)
                .map(|l| (l, true_curve(truth, l)))
                .collect(),
            markers: false,
        });
        out.push(Series {
            label: format!("{case_name}: field route ({name})"),
            points: stretches(max, MARKER_SAMPLES)
                .filter_map(|l| Some((l, model.nominal_stress_mpa(p, case, l)?)))
                .filter(|(_, s)| s.is_finite())
                .collect(),
            markers: true,
        });
    }
    out
}

/// Writes `field_route_law.png`; false (no file) when the route identified no law.
pub fn field_route_law_png(
    path: &Path,
    truth: &InvariantLaw,
    acceptance: &FieldAcceptance,
) -> anyhow::Result<bool> {
    let series = series(truth, acceptance);
    if series.is_empty() {
        return Ok(false);
    }
    let frames = acceptance.frames.unwrap_or(0);
    chart_paired(
        path,
        &format!("field route's law against the true one ({frames} frames)"),
        "stretch λ",
        "nominal stress (MPa)",
        &series,
        true,
    )?;
    Ok(true)
}

/// Each frame's capture time (s since the run started) from `frames.csv`'s text.
fn capture_times_s(frames_csv: &str) -> anyhow::Result<std::collections::HashMap<u64, f64>> {
    use crate::mechanics_figures::{column, header};
    let (names, lines) = header(frames_csv, "frames.csv")?;
    let (id, t) = (
        column(&names, "frame_id", "frames.csv")?,
        column(&names, "t_capture_s", "frames.csv")?,
    );
    Ok(lines
        .filter_map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            Some((cells.get(id)?.parse().ok()?, cells.get(t)?.parse().ok()?))
        })
        .collect())
}

/// The series of `force_balance.png` (N against s): per grip, its measured force (line) and
/// the computed one (markers), from the route's `force_balance` and `frames.csv`'s text.
pub fn force_balance_series(balance: &Value, frames_csv: &str) -> anyhow::Result<Vec<Series>> {
    let times = capture_times_s(frames_csv)?;
    let mut out = Vec::new();
    for grip in identifier::field_layout::GRIPS {
        let rows: Vec<(f64, f64, f64)> = balance
            .as_array()
            .into_iter()
            .flatten()
            .filter(|row| row["grip"] == grip)
            .filter_map(|row| {
                let t = *times.get(&row["frame_id"].as_u64()?)?;
                Some((t, row["measured_n"].as_f64()?, row["computed_n"].as_f64()?))
            })
            .collect();
        if rows.is_empty() {
            continue;
        }
        let series = |label: String, pick: fn(&(f64, f64, f64)) -> f64, markers| Series {
            label,
            points: rows.iter().map(|r| (r.0, pick(r))).collect(),
            markers,
        };
        out.push(series(format!("{grip}: measured"), |r| r.1, false));
        out.push(series(format!("{grip}: from the field"), |r| r.2, true));
    }
    Ok(out)
}

/// Writes `force_balance.png`; false (no file) when the route balanced no frame.
pub fn force_balance_png(
    path: &Path,
    acceptance: &FieldAcceptance,
    frames_csv: &Path,
) -> anyhow::Result<bool> {
    if acceptance.model.is_none() {
        return Ok(false);
    }
    let text = std::fs::read_to_string(frames_csv)
        .map_err(|e| anyhow::anyhow!("{}: {e}", frames_csv.display()))?;
    let series = force_balance_series(&acceptance.force_balance, &text)?;
    if series.is_empty() {
        return Ok(false);
    }
    let model = acceptance.model.as_deref().unwrap_or_default();
    chart_paired(
        path,
        &format!("grip forces: measured, and from the field under {model}"),
        "time (s)",
        "force (N)",
        &series,
        true,
    )?;
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field_acceptance::judge_route;
    use serde_json::json;

    /// Each case reached to its stretch.
    fn acceptance([uniaxial, equibiaxial, pure_shear]: [f64; 3]) -> FieldAcceptance {
        judge_route(
            &InvariantLaw::smactane(),
            &json!({
                "frames": 12,
                "reach": {"max_stretches": [uniaxial, equibiaxial], "uniaxial": uniaxial,
                          "equibiaxial": equibiaxial, "pure_shear": pure_shear},
                "fits": [{"model": "mooney", "params": {"C10": 0.3, "C01": 0.05}}],
            }),
        )
    }

    #[test]
    fn each_case_reached_has_its_true_line_and_the_identified_markers() {
        let truth = InvariantLaw::smactane();
        let series = series(&truth, &acceptance([1.6, 1.3, 1.2]));
        let labels: Vec<&str> = series.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(
            labels,
            [
                "uniaxial: true law",
                "uniaxial: field route (mooney)",
                "equibiaxial: true law",
                "equibiaxial: field route (mooney)",
                "pure shear: true law",
                "pure shear: field route (mooney)",
            ]
        );
        // Each over the stretches the acceptance compares: each case to its own reach.
        let last_x = |s: &Series| s.points.last().unwrap().0;
        assert!((last_x(&series[0]) - 1.6).abs() < 1e-12);
        assert!((last_x(&series[3]) - 1.3).abs() < 1e-12);
        assert!((last_x(&series[4]) - 1.2).abs() < 1e-12);
        assert!(series[1].markers && !series[0].markers);
        // The true line is the law's: at λ 1.6 in uniaxial tension.
        let (l, s) = *series[0].points.last().unwrap();
        assert!((s - truth.uniaxial_nominal_stress_mpa(l)).abs() < 1e-12);
    }

    #[test]
    fn the_png_is_written_and_nothing_identified_writes_none() {
        let dir = std::env::temp_dir().join(format!("field_route_law_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let png = dir.join("field_route_law.png");
        let truth = InvariantLaw::smactane();
        assert!(field_route_law_png(&png, &truth, &acceptance([1.6, 1.3, 1.2])).unwrap());
        assert!(std::fs::metadata(&png).unwrap().len() > 1000);
        std::fs::remove_file(&png).unwrap();
        let nothing = judge_route(&truth, &json!({"error": "crosses no arm", "fits": null}));
        assert!(!field_route_law_png(&png, &truth, &nothing).unwrap());
        assert!(!png.exists());
        // At rest: no stretch reached, no figure.
        assert!(!field_route_law_png(&png, &truth, &acceptance([1.0, 1.0, 1.0])).unwrap());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_force_balance_is_each_grips_measured_line_and_computed_markers_over_time() {
        let balance = json!([
            {"frame_id": 10, "grip": "x+", "measured_n": 100.0, "computed_n": 98.0, "fields": 2},
            {"frame_id": 10, "grip": "y+", "measured_n": 90.0, "computed_n": 91.0, "fields": 2},
            {"frame_id": 20, "grip": "x+", "measured_n": 200.0, "computed_n": 203.0, "fields": 2},
            {"frame_id": 99, "grip": "x+", "measured_n": 1.0, "computed_n": 1.0, "fields": 2},
        ]);
        let frames_csv = "frame_id,reference_frame_id,t_capture_s\n10,0,1.5\n20,0,2.5\n";
        let series = force_balance_series(&balance, frames_csv).unwrap();
        let labels: Vec<&str> = series.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(
            labels,
            [
                "x+: measured",
                "x+: from the field",
                "y+: measured",
                "y+: from the field"
            ]
        );
        // N against the frames' capture times; a frame frames.csv does not hold is left out.
        assert_eq!(series[0].points, vec![(1.5, 100.0), (2.5, 200.0)]);
        assert_eq!(series[1].points, vec![(1.5, 98.0), (2.5, 203.0)]);
        assert!(series[1].markers && !series[0].markers);
        let error = force_balance_series(&balance, "frame_id,x\n")
            .err()
            .unwrap();
        assert_eq!(error.to_string(), "frames.csv has no column t_capture_s");
    }
}
