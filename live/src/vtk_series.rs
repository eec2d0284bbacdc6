//! `fields/fields.vtk.series`: the run's VTK fields as one time series for ParaView (its JSON
//! "file series" format, read with any reader, legacy `.vtk` included: open the `.series` file
//! and the fields play against the run's time). Rewritten atomically with each VTK file, so a
//! run that is killed still leaves a series of the fields it wrote.

use serde::Serialize;

/// The series' file name, in the fields folder.
pub const FILE_NAME: &str = "fields.vtk.series";

#[derive(Debug, Default, Serialize)]
pub struct VtkSeries {
    #[serde(rename = "file-series-version")]
    version: &'static str,
    files: Vec<SeriesFile>,
}

#[derive(Debug, Serialize)]
struct SeriesFile {
    /// Relative to the series file.
    name: String,
    /// s since the run's start (the frame's capture).
    time: f64,
}

impl VtkSeries {
    pub fn new() -> VtkSeries {
        VtkSeries {
            version: "1.0",
            files: Vec::new(),
        }
    }

    /// Adds the file `name` (in the series' folder) of the frame captured at `time_s`.
    pub fn push(&mut self, name: String, time_s: f64) {
        self.files.push(SeriesFile { name, time: time_s });
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a series serialises")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_series_names_each_file_with_its_time_in_paraviews_format() {
        let mut series = VtkSeries::new();
        series.push("field_000010.vtk".into(), 1.0);
        series.push("field_000020.vtk".into(), 2.0);
        let json: serde_json::Value = serde_json::from_str(&series.to_json()).unwrap();
        assert_eq!(json["file-series-version"], "1.0");
        assert_eq!(json["files"][1]["name"], "field_000020.vtk");
        assert_eq!(json["files"][1]["time"], 2.0);
    }
}
