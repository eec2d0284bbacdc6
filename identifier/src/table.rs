//! A data file as a table, read as test machines write them (Instron Bluehill, Zwick
//! testXpert, MTS TestSuite exports) by the `csv` crate: title lines before the header skipped
//! (`skip_lines`, and on their own where a line's cell count differs from the header's that
//! follows), a units row under the header read (`(kN)`, `[mm]`, `MPa`), quoted cells, `,`, `;`
//! or tab delimited with decimal commas as the rig's follower reads them
//! ([`wire::delimited`]: the one place for the delimiter and the decimal comma). Every later
//! line is a row of the header's width: a line that is not is an error naming it, never
//! skipped.

use crate::data::DataError;
use wire::delimited::{parse_decimal, split_unit, written_number, Delimiter};

/// How to find the header.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TableOptions {
    /// Lines at the top of the file skipped before looking for the header (title lines).
    pub skip_lines: usize,
}

/// One column: its name as in the header (without a unit in brackets) and its unit as the
/// header or the units row states it (`None`: stated nowhere).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Column {
    pub name: String,
    pub unit: Option<String>,
}

/// The header's columns and the rows under it, each with its line number (from 1).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub source: String,
    pub delimiter: Delimiter,
    /// Line of the header (from 1).
    pub header_line: usize,
    pub columns: Vec<Column>,
    /// Line of the units row, if there is one.
    pub units_line: Option<usize>,
    pub rows: Vec<Row>,
}

/// One data row: its line (from 1) and its cells, trimmed.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub line: usize,
    pub cells: Vec<String>,
}

/// The UTF-8 byte order mark some programs (Excel's "CSV UTF-8") write first.
const UTF8_BOM: char = '\u{feff}';

impl Table {
    /// Reads a file; errors name it.
    pub fn read(path: &std::path::Path, options: TableOptions) -> Result<Table, DataError> {
        let source = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| DataError::new(&source, format!("cannot read the file: {e}")))?;
        Table::parse(&text, &source, options)
    }

    /// Parses text; `source` names it in errors.
    pub fn parse(text: &str, source: &str, options: TableOptions) -> Result<Table, DataError> {
        let text = text.strip_prefix(UTF8_BOM).unwrap_or(text);
        let error = |message: String| DataError::new(source, message);
        let last_row = text
            .lines()
            .skip(options.skip_lines)
            .filter(|l| !l.trim().is_empty())
            .last();
        let Some(last_row) = last_row else {
            return Err(error(format!(
                "empty file{}: expected a header then data rows",
                skipped_note(options.skip_lines)
            )));
        };
        let delimiter = Delimiter::of_row(last_row);
        let records = records(text, delimiter, source)?;
        let records: Vec<Record> = records
            .into_iter()
            .filter(|r| r.line > options.skip_lines)
            .collect();
        let header_at = header_index(&records, source)?;
        let header = &records[header_at];
        let joined = header.cells.join(delimiter.as_char().to_string().as_str());
        let mut columns: Vec<Column> = header
            .cells
            .iter()
            .map(|c| {
                let (name, unit) = split_unit(c);
                Column { name, unit }
            })
            .collect();
        let mut records = records[header_at + 1..].iter().peekable();
        let units_line = match records.peek() {
            Some(next) if next.cells.len() == columns.len() && !is_data(&next.cells) => {
                let units = records.next().expect("peeked");
                for (column, cell) in columns.iter_mut().zip(&units.cells) {
                    let unit = strip_brackets(cell);
                    match &column.unit {
                        Some(h) if !unit.is_empty() && h != unit => {
                            return Err(error(format!(
                                "line {}: column `{}`: the header says unit `{h}`, the units row `{unit}`",
                                units.line, column.name
                            )));
                        }
                        None if !unit.is_empty() => column.unit = Some(unit.to_string()),
                        _ => {}
                    }
                }
                Some(units.line)
            }
            _ => None,
        };
        let mut rows = Vec::new();
        for record in records {
            if record.cells.len() != columns.len() {
                return Err(error(format!(
                    "line {}: expected {} cells as the header on line {} (`{}`), found {}",
                    record.line,
                    columns.len(),
                    header.line,
                    joined,
                    record.cells.len()
                )));
            }
            rows.push(Row {
                line: record.line,
                cells: record.cells.clone(),
            });
        }
        Ok(Table {
            source: source.to_string(),
            delimiter,
            header_line: header.line,
            columns,
            units_line,
            rows,
        })
    }

    /// The index of the one column whose name `matches`, if exactly one does.
    pub fn find(&self, matches: impl Fn(&str) -> bool) -> Result<Option<usize>, DataError> {
        let found: Vec<usize> = (0..self.columns.len())
            .filter(|&i| matches(&self.columns[i].name.to_lowercase()))
            .collect();
        match found.as_slice() {
            [] => Ok(None),
            [i] => Ok(Some(*i)),
            many => Err(self.error(format!(
                "line {}: columns {} could each be the same quantity; keep one",
                self.header_line,
                many.iter()
                    .map(|&i| format!("`{}` (column {})", self.columns[i].name, i + 1))
                    .collect::<Vec<_>>()
                    .join(", ")
            ))),
        }
    }

    /// The number in `column` of `row`, decimal comma or point; an error names the line and
    /// the column.
    pub fn number(&self, row: &Row, column: usize) -> Result<f64, DataError> {
        let cell = &row.cells[column];
        parse_decimal(cell).ok_or_else(|| {
            self.error(format!(
                "line {}, column {} `{}`: `{cell}` is not a finite number",
                row.line,
                column + 1,
                self.columns[column].name
            ))
        })
    }

    /// An error naming the file.
    pub fn error(&self, message: String) -> DataError {
        DataError::new(&self.source, message)
    }
}

/// One record of the file: its line (from 1) and its trimmed cells.
struct Record {
    line: usize,
    cells: Vec<String>,
}

/// Every non-empty line's cells (records of any width).
fn records(text: &str, delimiter: Delimiter, source: &str) -> Result<Vec<Record>, DataError> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .delimiter(delimiter.as_char() as u8)
        .from_reader(text.as_bytes());
    // Lines from byte offsets: the reader's own line count passes over empty lines, and a
    // record's position is where the empty lines before it start.
    let bytes = text.as_bytes();
    let line_of = |byte: u64| {
        let start = (byte as usize).min(bytes.len());
        let start = start
            + bytes[start..]
                .iter()
                .take_while(|&&b| b == b'\n' || b == b'\r')
                .count();
        bytes[..start].iter().filter(|&&b| b == b'\n').count() + 1
    };
    let mut out = Vec::new();
    let mut record = csv::StringRecord::new();
    loop {
        let line = line_of(reader.position().byte());
        match reader.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {
                let line = record.position().map_or(line, |p| line_of(p.byte()));
                if record.iter().all(str::is_empty) {
                    continue;
                }
                out.push(Record {
                    line,
                    cells: record.iter().map(str::to_string).collect(),
                });
            }
            Err(e) => {
                let at = e.position().map_or(line, |p| line_of(p.byte()));
                return Err(DataError::new(
                    source,
                    format!("line {at}: not a row of `{delimiter}` delimited cells: {e}"),
                ));
            }
        }
    }
    Ok(out)
}

/// A row of numbers: a cell written as a number (a header or a units row has none).
fn is_data(cells: &[String]) -> bool {
    cells.iter().any(|c| written_number(c).is_some())
}

/// Where the header is among `records`: the first of the lines before the first row of
/// numbers that have that row's cell count (title lines above have another count), followed
/// at most by a units row; else the line just above the first row of numbers. A file of no
/// row of numbers has its first line as header.
fn header_index(records: &[Record], source: &str) -> Result<usize, DataError> {
    let error = |message: String| DataError::new(source, message);
    let Some(first_data) = records.iter().position(|r| is_data(&r.cells)) else {
        return match records.first() {
            Some(_) => Ok(0),
            None => Err(error("empty file: expected a header then data rows".into())),
        };
    };
    let width = records[first_data].cells.len();
    let run = records[..first_data]
        .iter()
        .rev()
        .take_while(|r| r.cells.len() == width)
        .count();
    match run {
        // The line above the rows has another width: the header, and the rows' width the
        // error.
        0 if first_data > 0 => Ok(first_data - 1),
        0 => Err(error(format!(
            "line {}: expected a header (column names) before the first row of numbers",
            records[first_data].line
        ))),
        1 | 2 => Ok(first_data - run),
        _ => Err(error(format!(
            "lines {} to {}: {run} lines of {width} cells before the first row of numbers, the header and at most a units row expected; skip the lines above the header with --skip-lines",
            records[first_data - run].line,
            records[first_data - 1].line
        ))),
    }
}

/// `(kN)` or `[kN]` as `kN`.
fn strip_brackets(cell: &str) -> &str {
    let cell = cell.trim();
    for (open, close) in [('(', ')'), ('[', ']')] {
        if let Some(inner) = cell.strip_prefix(open).and_then(|c| c.strip_suffix(close)) {
            return inner.trim();
        }
    }
    cell
}

fn skipped_note(skip_lines: usize) -> String {
    match skip_lines {
        0 => String::new(),
        n => format!(" after the {n} skipped lines"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str, skip_lines: usize) -> Result<Table, String> {
        Table::parse(text, "m.csv", TableOptions { skip_lines }).map_err(|e| e.to_string())
    }

    #[test]
    fn a_machine_export_gives_its_header_units_and_rows() {
        let text = "\u{feff}\"Results Table 1\"\nSpecimen 3\n\nTime;\"Extension\";Load\n(s);(mm);(kN)\n0,5;1,25;0,010\n1,0;2,5;0,020\n";
        let t = parse(text, 0).unwrap();
        assert_eq!(t.delimiter, Delimiter::Semicolon);
        assert_eq!((t.header_line, t.units_line), (4, Some(5)));
        let names: Vec<_> = t.columns.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["Time", "Extension", "Load"]);
        assert_eq!(t.columns[2].unit.as_deref(), Some("kN"));
        assert_eq!(t.rows.len(), 2);
        assert_eq!(t.rows[1].line, 7);
        assert_eq!(t.number(&t.rows[1], 1).unwrap(), 2.5);
        let e = t
            .number(
                &Row {
                    line: 9,
                    cells: vec!["x".into(); 3],
                },
                2,
            )
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.csv: line 9, column 3 `Load`: `x` is not a finite number"
        );
    }

    #[test]
    fn units_in_the_header_quoted_decimal_commas_and_skip_lines() {
        let text =
            "Test 12, operator A, 3 specimens\nstretch,\"Stress (MPa)\"\n1.1,\"0,5\"\n1.2,0.7\n";
        let t = parse(text, 1).unwrap();
        assert_eq!(t.delimiter, Delimiter::Comma);
        assert_eq!(t.columns[1].unit.as_deref(), Some("MPa"));
        assert_eq!(t.number(&t.rows[0], 1).unwrap(), 0.5);
        assert_eq!(t.units_line, None);
    }

    #[test]
    fn bad_files_are_errors_naming_file_and_line() {
        let e = parse("", 0).unwrap_err();
        assert!(e.starts_with("m.csv: empty file"), "{e}");
        let e = parse("1.1,0.1\n1.2,0.2\n", 0).unwrap_err();
        assert!(e.contains("line 1: expected a header"), "{e}");
        let e = parse("a;b\n1;2\n1;2;3\n", 0).unwrap_err();
        assert!(
            e.contains("line 3: expected 2 cells as the header on line 1"),
            "{e}"
        );
        let e = parse("F (kN);d\n(N);mm\n1;2\n", 0).unwrap_err();
        assert!(
            e.contains("line 2: column `F`: the header says unit `kN`, the units row `N`"),
            "{e}"
        );
    }

    #[test]
    fn a_column_is_found_once_or_the_ambiguity_is_named() {
        let t = parse("Time;Load 1;Load 2\n1;2;3\n", 0).unwrap();
        assert_eq!(t.find(|n| n == "time").unwrap(), Some(0));
        assert_eq!(t.find(|n| n == "stretch").unwrap(), None);
        let e = t.find(|n| n.contains("load")).unwrap_err().to_string();
        assert!(
            e.contains("`Load 1` (column 2), `Load 2` (column 3)"),
            "{e}"
        );
    }
}
