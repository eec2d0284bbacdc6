//! Which columns of a machine's CSV hold time, forces and displacements, in which units: the
//! header names them (`Time (s)`, `Fx [kN]` or plain `Time`), the configuration may state
//! the units; every value is converted to s, N and mm.

use super::malformed::{excerpt, RowError};
use wire::delimited::{parse_decimal, split_unit};

use wire::names::Named;

/// Why a follow cannot start (or go on).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CsvError {
    #[error("column {name:?} is not in the header {header:?}")]
    MissingColumn { name: String, header: String },
    #[error("column {name:?} appears {count} times in the header {header:?}")]
    AmbiguousColumn {
        name: String,
        count: usize,
        header: String,
    },
    #[error("the unit of {what} is not stated: name it in the header (`{name} (UNIT)`) or in the configuration ({expected})")]
    NoUnit {
        what: &'static str,
        name: String,
        expected: String,
    },
    #[error("unknown unit {unit:?} for {what}: expected {expected}")]
    UnknownUnit {
        what: &'static str,
        unit: String,
        expected: String,
    },
    #[error("{what}: the header says {header_unit:?}, the configuration {config_unit:?}")]
    UnitDisagrees {
        what: String,
        header_unit: String,
        config_unit: String,
    },
    /// The first line cannot be split into cells (the header is an excerpt).
    #[error("the header {header:?} cannot be read: {why}")]
    BadHeader { header: String, why: RowError },
    #[error("{0}")]
    Spec(String),
}

pub use wire::units::{ForceUnit, LengthUnit, TimeUnit};

/// One configured column: the name as in the header, without its unit.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColumnSpec {
    pub name: String,
    /// The unit the configuration states (None: the header must).
    pub unit: Option<String>,
}

impl ColumnSpec {
    pub fn new(name: &str, unit: Option<&str>) -> ColumnSpec {
        ColumnSpec {
            name: name.to_string(),
            unit: unit.map(str::to_string),
        }
    }
}

/// The columns to follow: time, force per axis X, Y, Z and, if logged, displacement per axis.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CsvColumns {
    pub time: ColumnSpec,
    pub force: [Option<ColumnSpec>; 3],
    pub displacement: [Option<ColumnSpec>; 3],
    /// Units the configuration states (None: each column's header must state it).
    pub time_unit: Option<TimeUnit>,
    pub force_unit: Option<ForceUnit>,
    pub displacement_unit: Option<LengthUnit>,
    /// `,`, `;` or a tab. A comma inside a cell is a decimal comma (with `,` the cell is
    /// quoted, `"4,5"`).
    pub delimiter: char,
}

impl CsvColumns {
    pub fn validate(&self) -> Result<(), CsvError> {
        if self.time.name.trim().is_empty() {
            return Err(CsvError::Spec("the time column is not named".into()));
        }
        if self.force.iter().all(Option::is_none) {
            return Err(CsvError::Spec(
                "no force column is named: name at least one axis's".into(),
            ));
        }
        if ![',', ';', '\t'].contains(&self.delimiter) {
            return Err(CsvError::Spec(format!(
                "delimiter {:?}: expected \",\", \";\" or a tab",
                self.delimiter
            )));
        }
        Ok(())
    }
}

/// One row, converted: time s, force per axis N, displacement per axis mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    pub t_s: f64,
    pub force_n: [Option<f64>; 3],
    pub displacement_mm: [Option<f64>; 3],
}

/// Where each configured column is, and its factor to s, N or mm.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// Cells of the header: every row has as many.
    cells: usize,
    time: (usize, f64),
    force: [Option<(usize, f64)>; 3],
    displacement: [Option<(usize, f64)>; 3],
    /// (cell index, configured name) of every followed column.
    names: Vec<(usize, String)>,
}

/// The unit factor of a column: from the header, the configuration, both (must agree).
fn factor<U: Named + PartialEq>(
    what: &'static str,
    spec: &ColumnSpec,
    header_unit: Option<&str>,
    config_unit: Option<U>,
    to_base: fn(U) -> f64,
) -> Result<f64, CsvError> {
    let parse = |u: &str| U::parse_name(u).ok();
    let expected = U::expected();
    let spec_unit = match &spec.unit {
        Some(u) => Some(parse(u).ok_or_else(|| CsvError::UnknownUnit {
            what,
            unit: u.clone(),
            expected: expected.clone(),
        })?),
        None => config_unit,
    };
    let header = match header_unit {
        Some(u) => Some(parse(u).ok_or_else(|| CsvError::UnknownUnit {
            what,
            unit: u.to_string(),
            expected: expected.clone(),
        })?),
        None => None,
    };
    match (header, spec_unit) {
        (Some(h), Some(c)) if h != c => Err(CsvError::UnitDisagrees {
            what: format!("{what} column {:?}", spec.name),
            header_unit: header_unit.unwrap_or_default().to_string(),
            config_unit: spec.unit.clone().unwrap_or_else(|| expected.to_string()),
        }),
        (Some(u), _) | (None, Some(u)) => Ok(to_base(u)),
        (None, None) => Err(CsvError::NoUnit {
            what,
            name: spec.name.clone(),
            expected,
        }),
    }
}

impl Layout {
    /// Finds the configured columns in the header's cells (`line`: the header as written,
    /// for the errors).
    pub fn from_header<C: AsRef<str>>(
        header: &[C],
        line: &str,
        spec: &CsvColumns,
    ) -> Result<Layout, CsvError> {
        let cells: Vec<(String, Option<String>)> =
            header.iter().map(|c| split_unit(c.as_ref())).collect();
        let find = |c: &ColumnSpec| -> Result<(usize, Option<&str>), CsvError> {
            let at: Vec<usize> = (0..cells.len())
                .filter(|&i| cells[i].0 == c.name.trim())
                .collect();
            match at.as_slice() {
                [i] => Ok((*i, cells[*i].1.as_deref())),
                [] => Err(CsvError::MissingColumn {
                    name: c.name.clone(),
                    header: line.to_string(),
                }),
                _ => Err(CsvError::AmbiguousColumn {
                    name: c.name.clone(),
                    count: at.len(),
                    header: line.to_string(),
                }),
            }
        };
        let (t_at, t_unit) = find(&spec.time)?;
        let time = (
            t_at,
            factor("time", &spec.time, t_unit, spec.time_unit, TimeUnit::to_s)?,
        );
        let mut force = [None; 3];
        let mut displacement = [None; 3];
        let mut names = vec![(t_at, spec.time.name.clone())];
        for axis in 0..3 {
            if let Some(c) = &spec.force[axis] {
                let (at, unit) = find(c)?;
                let f = factor("force", c, unit, spec.force_unit, ForceUnit::to_n)?;
                force[axis] = Some((at, f));
                names.push((at, c.name.clone()));
            }
            if let Some(c) = &spec.displacement[axis] {
                let (at, unit) = find(c)?;
                let f = factor(
                    "displacement",
                    c,
                    unit,
                    spec.displacement_unit,
                    LengthUnit::to_mm,
                )?;
                displacement[axis] = Some((at, f));
                names.push((at, c.name.clone()));
            }
        }
        Ok(Layout {
            cells: cells.len(),
            time,
            force,
            displacement,
            names,
        })
    }

    /// Reads one row's cells; the error says which cell and why. A comma inside a cell is a
    /// decimal comma (with `,` as the delimiter, such a cell is quoted: `"4,5"`).
    pub fn parse_row<C: AsRef<str>>(&self, cells: &[C]) -> Result<Row, RowError> {
        if cells.len() != self.cells {
            return Err(RowError::CellCount {
                found: cells.len(),
                expected: self.cells,
            });
        }
        let value = |(at, f): (usize, f64)| -> Result<f64, RowError> {
            let cell = cells[at].as_ref();
            match parse_decimal(cell) {
                Some(v) => Ok(v * f),
                None => Err(RowError::NotANumber {
                    column: self.name_of(at).to_string(),
                    cell: excerpt(cell.as_bytes()),
                }),
            }
        };
        let mut row = Row {
            t_s: value(self.time)?,
            force_n: [None; 3],
            displacement_mm: [None; 3],
        };
        for axis in 0..3 {
            if let Some(c) = self.force[axis] {
                row.force_n[axis] = Some(value(c)?);
            }
            if let Some(c) = self.displacement[axis] {
                row.displacement_mm[axis] = Some(value(c)?);
            }
        }
        Ok(row)
    }

    /// The followed columns and where they are: `Time (cell 1), Fx (cell 3)`.
    pub fn describe(&self) -> String {
        self.names
            .iter()
            .map(|(at, name)| format!("{name} (cell {})", at + 1))
            .collect::<Vec<_>>()
            .join(", ")
    }

    fn name_of(&self, at: usize) -> &str {
        self.names
            .iter()
            .find(|(i, _)| *i == at)
            .map_or("?", |(_, name)| name.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::csv_follow::record::RecordReader;

    /// Time `t` in s and force `F` (in `force_unit` if given).
    fn t_and_f(delimiter: char, force_unit: Option<ForceUnit>) -> CsvColumns {
        CsvColumns {
            time: ColumnSpec::new("t", None),
            force: [Some(ColumnSpec::new("F", None)), None, None],
            displacement: [None, None, None],
            time_unit: Some(TimeUnit::S),
            force_unit,
            displacement_unit: None,
            delimiter,
        }
    }

    fn layout(header: &str, spec: &CsvColumns) -> Result<Layout, CsvError> {
        let mut reader = RecordReader::new(spec.delimiter);
        Layout::from_header(&reader.split(header.as_bytes()).unwrap(), header, spec)
    }

    #[test]
    fn a_unit_stated_nowhere_or_twice_differently_is_an_error() {
        let spec = t_and_f(';', None);
        let e = layout("t;F", &spec).unwrap_err();
        assert!(matches!(e, CsvError::NoUnit { .. }), "{e}");
        let e = layout("t (ms);F (N)", &spec).unwrap_err();
        assert!(matches!(e, CsvError::UnitDisagrees { .. }), "{e}");
        let e = layout("t;F (lbf)", &spec).unwrap_err();
        assert!(e.to_string().contains("lbf"), "{e}");
        let found = layout("t;F (N)", &spec).unwrap();
        // Decimal commas.
        let row = found.parse_row(&["1,5", " 2,25"]).unwrap();
        assert_eq!((row.t_s, row.force_n[0]), (1.5, Some(2.25)));
    }

    #[test]
    fn a_row_of_another_width_or_with_a_cell_not_a_number_is_refused_naming_it() {
        let spec = t_and_f(',', Some(ForceUnit::Newton));
        let found = layout("t,F,note", &spec).unwrap();
        assert_eq!(
            found.parse_row(&["5", "1", "x", "510"]).unwrap_err(),
            RowError::CellCount {
                found: 4,
                expected: 3
            }
        );
        assert_eq!(
            found.parse_row(&["5", "1"]).unwrap_err(),
            RowError::CellCount {
                found: 2,
                expected: 3
            }
        );
        let long = "x".repeat(10_000);
        let e = found.parse_row(&["5", long.as_str(), ""]).unwrap_err();
        assert!(
            matches!(&e, RowError::NotANumber { column, cell } if column == "F" && cell.len() < 300),
            "{e}"
        );
        // Both separators in one cell is no number.
        let e = found.parse_row(&["1,234.5", "1", ""]).unwrap_err();
        assert!(
            matches!(&e, RowError::NotANumber { column, .. } if column == "t"),
            "{e}"
        );
    }
}
