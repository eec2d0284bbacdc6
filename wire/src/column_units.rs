//! The units of a CSV file's columns, as the `units.json` sidecar of a results folder says them
//! (one entry per kind of file; each column's name, unit and meaning, in the file's order), so
//! that a pandas user reads them beside the data:
//! `pd.DataFrame(json.load(open("units.json"))["files"]["frames.csv"]["columns"])`.

use serde::Serialize;

/// The name of the sidecar, at the top of a results folder.
pub const SIDECAR: &str = "units.json";

/// Dimensionless: a strain, a stretch, a ratio, a count, an id.
pub const ONE: &str = "1";

/// One column: its name as in the header, its unit (`px`, `mm`, `N`, `s`, `1`…) and meaning.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Column {
    pub name: String,
    pub unit: String,
    pub meaning: String,
}

impl Column {
    pub fn new(name: impl Into<String>, unit: &str, meaning: impl Into<String>) -> Column {
        Column {
            name: name.into(),
            unit: unit.to_string(),
            meaning: meaning.into(),
        }
    }
}

/// The units of one kind of CSV file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CsvUnits {
    /// The files it describes, relative to the sidecar (a glob for a series: `fields/field_*.csv`).
    pub files: String,
    /// What holds for the whole file (the strain measure, the scale, the coordinates).
    pub notes: Vec<String>,
    pub columns: Vec<Column>,
}

impl CsvUnits {
    /// The column called `name`.
    pub fn column(&self, name: &str) -> Option<&Column> {
        self.columns.iter().find(|c| c.name == name)
    }

    /// The column names in order, as the file's header.
    pub fn header(&self) -> String {
        let names: Vec<&str> = self.columns.iter().map(|c| c.name.as_str()).collect();
        names.join(",")
    }
}
