//! `units.json` at the top of a run's results folder: the unit and meaning of every column of
//! the CSV files the run writes (`frames.csv` with the user's gauges, `rig.csv`,
//! `fields/field_*.csv`), their strain measure and the fields' scale, for a pandas user:
//! `pd.DataFrame(json.load(open("units.json"))["files"]["frames.csv"]["columns"])`.
//! A column's unit follows its name's suffix (`_s`, `_ms`, `_n`, `_mpa`, `_mm`, `_px`,
//! `_deg`); what has none is dimensionless (strains, stretches, invariants, ids, counts).

use crate::field_scale::FieldScale;
use wire::column_units::{Column, CsvUnits, ONE};
use wire::StrainMeasure;

/// The sidecar's JSON for a run writing `frames_header` (the `frames.csv` header, gauges
/// included), fields in `strain` at `scale`.
pub fn units_json(frames_header: &str, strain: StrainMeasure, scale: &FieldScale) -> String {
    let mut fields =
        correlator::output::field_csv_units("fields/field_*.csv", strain, scale.of_field(None));
    if let Some(note) = fields.notes.last_mut() {
        *note = scale.note();
    }
    let units = serde_json::json!({
        "about": "units of the columns of this run's CSV files (dicstream run); forces in N \
                  everywhere",
        "files": {
            "frames.csv": frames_csv_units(frames_header),
            "rig.csv": rig_csv_units(&rig::log::csv_header()),
            "fields/field_*.csv": fields,
        },
    });
    serde_json::to_string_pretty(&units).expect("units serialise")
}

/// `frames.csv`'s columns.
pub fn frames_csv_units(header: &str) -> CsvUnits {
    CsvUnits {
        files: "frames.csv".into(),
        notes: vec![
            "one row per correlated frame; strains of the control gauge in the four measures \
             (small, green: Green-Lagrange, nominal, log), each exy the tensor component, half \
             the engineering shear"
                .into(),
            "t_sim_s: the test's (rig's) time; t_capture_s: since the run started".into(),
        ],
        columns: header.split(',').map(frames_column).collect(),
    }
}

/// `rig.csv`'s columns.
pub fn rig_csv_units(header: &str) -> CsvUnits {
    CsvUnits {
        files: "rig.csv".into(),
        notes: vec![
            "the rig's log, one row per logged sample; actuators X+, X-, Y+, Y-, Z+, Z-, \
                     axes x, y, z"
                .into(),
        ],
        columns: header.split(',').map(rig_column).collect(),
    }
}

/// The unit a column's name says by its suffix, if any.
fn suffix_unit(name: &str) -> Option<&'static str> {
    [
        ("_ms", "ms"),
        ("_s", "s"),
        ("_n", "N"),
        ("_mpa", "MPa"),
        ("_mm", "mm"),
        ("_px", "px"),
        ("_deg", "deg"),
    ]
    .into_iter()
    .find(|(suffix, _)| name.ends_with(suffix))
    .map(|(_, unit)| unit)
}

fn frames_column(name: &str) -> Column {
    let strain = |measure: &str| {
        let tensor = if name.ends_with("exy") {
            ", tensor component (gamma_xy / 2)"
        } else {
            ""
        };
        Column::new(name, ONE, format!("{measure} strain{tensor}"))
    };
    if let Some(gauge) = name.strip_prefix("gauge_") {
        return match gauge.strip_suffix("_nodes") {
            Some(g) => Column::new(name, ONE, format!("valid nodes in gauge {g}")),
            None => strain("user gauge's mean log"),
        };
    }
    if let Some(ext) = name.strip_prefix("ext_") {
        return match ext.strip_suffix("_nominal_strain") {
            Some(e) => Column::new(
                name,
                ONE,
                format!("extensometer {e}'s nominal strain (elongation / initial length)"),
            ),
            None => match ext.ends_with("_elongation_mm") {
                true => Column::new(name, "mm", "extensometer's elongation (the field's scale)"),
                false => Column::new(name, "px", "extensometer's elongation"),
            },
        };
    }
    for measure in ["small", "green", "nominal", "log", "target_log"] {
        if name.starts_with(&format!("{measure}_e")) {
            return strain(measure);
        }
    }
    if name.ends_with("_error") {
        return Column::new(name, ONE, "measured minus true gauge log strain");
    }
    match suffix_unit(name) {
        Some(unit) => Column::new(name, unit, "as named"),
        None => Column::new(
            name,
            ONE,
            "dimensionless: an id, a count, a code, a stretch or an invariant",
        ),
    }
}

fn rig_column(name: &str) -> Column {
    if name.ends_with("_command") || name.ends_with("_error") {
        return Column::new(
            name,
            "mm or N",
            "position (mm) in displacement control, force (N) in force control; the error is \
             the command minus its feedback",
        );
    }
    if name.ends_with("_valve") {
        return Column::new(name, ONE, "servo-valve command in [-1, 1]");
    }
    if name == "control" {
        return Column::new(name, "", "displacement, strain or held");
    }
    if name.starts_with("target_log_") {
        return Column::new(name, ONE, "the strain loop's target log strain");
    }
    match suffix_unit(name) {
        Some(unit) => Column::new(name, unit, "as named"),
        None => Column::new(name, ONE, "dimensionless: a code, a flag or a stretch"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_column_of_the_runs_files_has_its_unit_in_header_order() {
        let gauges = ",gauge_mid_log_exx,gauge_mid_log_eyy,gauge_mid_log_exy,gauge_mid_nodes\
                      ,ext_arm_elongation_px,ext_arm_elongation_mm,ext_arm_nominal_strain";
        let header = crate::frames::csv_header_with(true, gauges);
        let scale = FieldScale::User(wire::scale::MmPerPx::new(0.1).unwrap());
        let json: serde_json::Value =
            serde_json::from_str(&units_json(&header, StrainMeasure::Log, &scale)).unwrap();
        let files = &json["files"];
        let names = |file: &str| -> Vec<String> {
            files[file]["columns"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| c["name"].as_str().unwrap().to_string())
                .collect()
        };
        assert_eq!(names("frames.csv").join(","), header);
        assert_eq!(names("rig.csv").join(","), rig::log::csv_header());
        let unit = |file: &str, name: &str| {
            let columns = files[file]["columns"].as_array().unwrap();
            let c = columns.iter().find(|c| c["name"] == name).unwrap();
            c["unit"].as_str().unwrap().to_string()
        };
        assert_eq!(unit("frames.csv", "force_x_n"), "N");
        assert_eq!(unit("frames.csv", "t_sim_s"), "s");
        assert_eq!(unit("frames.csv", "latency_field_ms"), "ms");
        assert_eq!(unit("frames.csv", "cauchy_x_mpa"), "MPa");
        assert_eq!(unit("frames.csv", "log_exy"), "1");
        assert_eq!(unit("frames.csv", "ext_arm_elongation_px"), "px");
        assert_eq!(unit("frames.csv", "ext_arm_elongation_mm"), "mm");
        assert_eq!(unit("rig.csv", "X+_force_n"), "N");
        assert_eq!(unit("rig.csv", "X+_position_mm"), "mm");
        assert_eq!(unit("fields/field_*.csv", "u_mm"), "mm");
        let exy = &files["frames.csv"]["columns"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["name"] == "log_exy")
            .unwrap()["meaning"];
        assert!(exy.as_str().unwrap().contains("tensor component"));
        let notes = files["fields/field_*.csv"]["notes"].to_string();
        assert!(notes.contains("strain measure: log") && notes.contains("0.1 mm per px"));
    }
}
