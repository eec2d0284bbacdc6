//! The identifier's journal: every accepted load-path point, one CSV line each, appended and
//! flushed as it is accepted. A restarted identifier reads it back and goes on from the same
//! path, so a process killed mid-test loses no point it had accepted.
//!
//! Format: header `case,stretch,nominal_stress_mpa,frame_id`, then one row per point, `case`
//! one of `uniaxial`, `equibiaxial`, `pure_shear`.

use crate::data::LoadCase;
use std::io::BufRead;
use std::path::{Path, PathBuf};

pub const HEADER: &str = "case,stretch,nominal_stress_mpa,frame_id";

/// Why a journal could not be read back (lines counted from 1, the header included).
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    #[error("journal {}: {reason}", .path.display())]
    Read {
        path: PathBuf,
        reason: std::io::Error,
    },
    #[error("journal {}: header {header:?}, expected {HEADER:?}", .path.display())]
    Header { path: PathBuf, header: String },
    #[error("journal {} line {line}: {row:?} is not case,stretch,stress,frame_id", .path.display())]
    Row {
        path: PathBuf,
        line: usize,
        row: String,
    },
}

/// One accepted point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JournalPoint {
    pub case: LoadCase,
    pub stretch: f64,
    pub nominal_stress_mpa: f64,
    pub frame_id: u64,
}

/// Reads a journal. A missing file is an empty journal; a torn last line (the process was
/// killed while writing it) is ignored; any other malformed line is an error naming it.
pub fn read(path: &Path) -> Result<Vec<JournalPoint>, JournalError> {
    let unreadable = |reason| JournalError::Read {
        path: path.to_path_buf(),
        reason,
    };
    let file = match std::fs::File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(unreadable(e)),
    };
    let lines: Vec<String> = std::io::BufReader::new(file)
        .lines()
        .collect::<Result<_, _>>()
        .map_err(unreadable)?;
    let Some((header, rows)) = lines.split_first() else {
        return Ok(Vec::new());
    };
    if header.trim() != HEADER {
        return Err(JournalError::Header {
            path: path.to_path_buf(),
            header: header.clone(),
        });
    }
    let mut points = Vec::with_capacity(rows.len());
    for (k, row) in rows.iter().enumerate() {
        let last = k + 1 == rows.len();
        match parse_row(row) {
            Some(p) => points.push(p),
            None if last => break,
            None => {
                return Err(JournalError::Row {
                    path: path.to_path_buf(),
                    line: k + 2,
                    row: row.clone(),
                })
            }
        }
    }
    Ok(points)
}

fn parse_row(row: &str) -> Option<JournalPoint> {
    let mut cells = row.split(',');
    let case_name = cells.next()?.trim();
    let case = LoadCase::ALL.into_iter().find(|c| c.name() == case_name)?;
    let stretch: f64 = cells.next()?.trim().parse().ok()?;
    let nominal_stress_mpa: f64 = cells.next()?.trim().parse().ok()?;
    let frame_id: u64 = cells.next()?.trim().parse().ok()?;
    if cells.next().is_some() || !stretch.is_finite() || !nominal_stress_mpa.is_finite() {
        return None;
    }
    Some(JournalPoint {
        case,
        stretch,
        nominal_stress_mpa,
        frame_id,
    })
}

/// Appends points to a journal, each row whole ([`wire::files::RowFile`]: a row a full disk
/// tore is cut back off, and a torn last row left by a kill is cut before appending).
pub struct JournalWriter {
    rows: wire::files::RowFile,
}

impl JournalWriter {
    /// Opens `path` for appending, writing the header if the file is new or empty.
    pub fn open(path: &Path) -> Result<JournalWriter, wire::files::FileError> {
        Ok(JournalWriter {
            rows: wire::files::RowFile::append_to(path, HEADER)?,
        })
    }

    pub fn append(&mut self, point: &JournalPoint) -> Result<(), wire::files::FileError> {
        let line = format!(
            "{},{},{},{}\n",
            point.case.name(),
            point.stretch,
            point.nominal_stress_mpa,
            point.frame_id
        );
        self.rows.append(&line)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_torn_last_line() {
        let dir = std::env::temp_dir().join(format!("journal_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("points.csv");
        let _ = std::fs::remove_file(&path);
        assert!(read(&path).unwrap().is_empty());
        let points = [
            JournalPoint {
                case: LoadCase::Uniaxial,
                stretch: 1.25,
                nominal_stress_mpa: 0.31,
                frame_id: 7,
            },
            JournalPoint {
                case: LoadCase::Equibiaxial,
                stretch: 1.5,
                nominal_stress_mpa: 0.9,
                frame_id: 90,
            },
        ];
        {
            let mut w = JournalWriter::open(&path).unwrap();
            w.append(&points[0]).unwrap();
        }
        // Reopened: no second header.
        let mut w = JournalWriter::open(&path).unwrap();
        w.append(&points[1]).unwrap();
        assert_eq!(read(&path).unwrap(), points.to_vec());
        // A kill mid-write leaves a torn last line: ignored.
        std::fs::write(
            &path,
            format!("{}\nuniaxial,1.25,0.31,7\nequibiaxial,1.5,0.", HEADER),
        )
        .unwrap();
        assert_eq!(read(&path).unwrap(), points[..1].to_vec());
        // A bad line in the middle is an error naming the line.
        std::fs::write(
            &path,
            format!("{}\nuniaxial,x,0.31,7\nequibiaxial,1.5,0.9,90\n", HEADER),
        )
        .unwrap();
        let error = read(&path).unwrap_err();
        assert!(
            matches!(error, JournalError::Row { line: 2, .. }),
            "{error}"
        );
        assert!(error.to_string().contains("line 2"), "{error}");
        std::fs::write(&path, "stretch,stress\n").unwrap();
        assert!(matches!(read(&path), Err(JournalError::Header { .. })));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
