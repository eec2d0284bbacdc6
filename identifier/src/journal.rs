//! The identifier's journal: every accepted biaxial state, one CSV line each, appended and
//! flushed as it is accepted. A restarted identifier reads it back and goes on from the same
//! path, so a process killed mid-test loses no state it had accepted.
//!
//! Format: header `lambda1,lambda2,nominal_stress1_mpa,nominal_stress2_mpa,frame_id` (the
//! general biaxial CSV's columns and the frame), then one row per state. A journal of the
//! earlier per-case format (`case,stretch,nominal_stress_mpa,frame_id`: one stress a point,
//! where a state has two) is refused with a message saying so, never misread.

use crate::data::BiaxialState;
use std::path::{Path, PathBuf};

pub const HEADER: &str = "lambda1,lambda2,nominal_stress1_mpa,nominal_stress2_mpa,frame_id";

/// The header of the earlier per-case journals.
pub const PER_CASE_HEADER: &str = "case,stretch,nominal_stress_mpa,frame_id";

/// Why a journal could not be read back (lines counted from 1, the header included).
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    /// The file could not be read (its exit code, out of descriptors or not, follows it).
    #[error("journal: {0}")]
    Read(#[source] wire::files::FileError),
    #[error("journal {}: header {header:?}, expected {HEADER:?}", .path.display())]
    Header { path: PathBuf, header: String },
    #[error("journal {}: written by an earlier version (header {PER_CASE_HEADER:?}: one stress a point, where a biaxial state has two); move it aside to start a new path", .path.display())]
    PerCase { path: PathBuf },
    #[error("journal {} line {line}: {row:?} is not {HEADER} (a complete row, not a torn write: the journal is corrupt; move it aside to start a new path)", .path.display())]
    Row {
        path: PathBuf,
        line: usize,
        row: String,
    },
}

/// One accepted state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JournalPoint {
    pub state: BiaxialState,
    pub frame_id: u64,
}

/// Reads a journal. A missing file is an empty journal. A torn last row (bytes after the
/// last newline: the process was killed while writing it) is ignored, whatever it holds, as
/// [`JournalWriter::open`] cuts it off; every complete row must be a state, or the journal is
/// refused naming the line (a corrupt row is never dropped silently).
pub fn read(path: &Path) -> Result<Vec<JournalPoint>, JournalError> {
    let bytes = match std::fs::read(path) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(reason) => {
            return Err(JournalError::Read(wire::files::FileError {
                path: path.to_path_buf(),
                what: "read",
                reason,
            }))
        }
    };
    let whole = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    let text = String::from_utf8_lossy(&bytes[..whole]);
    let mut lines = text.lines();
    let Some(header) = lines.next() else {
        return Ok(Vec::new());
    };
    if header.trim() == PER_CASE_HEADER {
        return Err(JournalError::PerCase {
            path: path.to_path_buf(),
        });
    }
    if header.trim() != HEADER {
        return Err(JournalError::Header {
            path: path.to_path_buf(),
            header: header.to_owned(),
        });
    }
    lines
        .enumerate()
        .map(|(k, row)| {
            parse_row(row).ok_or_else(|| JournalError::Row {
                path: path.to_path_buf(),
                line: k + 2,
                row: row.to_owned(),
            })
        })
        .collect()
}

fn parse_row(row: &str) -> Option<JournalPoint> {
    let mut cells = row.split(',').map(str::trim);
    let mut values = [0.0; 4];
    for v in &mut values {
        *v = cells.next()?.parse().ok()?;
    }
    let frame_id: u64 = cells.next()?.parse().ok()?;
    let state = BiaxialState {
        stretch1: values[0],
        stretch2: values[1],
        nominal_stress1_mpa: values[2],
        nominal_stress2_mpa: values[3],
    };
    if cells.next().is_some() || state.check().is_err() {
        return None;
    }
    Some(JournalPoint { state, frame_id })
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
        let s = &point.state;
        let line = format!(
            "{},{},{},{},{}\n",
            s.stretch1, s.stretch2, s.nominal_stress1_mpa, s.nominal_stress2_mpa, point.frame_id
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
        let state = |l1: f64, l2: f64, p1: f64, p2: f64| BiaxialState {
            stretch1: l1,
            stretch2: l2,
            nominal_stress1_mpa: p1,
            nominal_stress2_mpa: p2,
        };
        let points = [
            JournalPoint {
                state: state(1.25, 0.9, 0.31, 0.0),
                frame_id: 7,
            },
            JournalPoint {
                state: state(1.5, 1.2, 0.9, 0.6),
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
        // A kill mid-write leaves a torn last line: ignored, also when what was written of it
        // happens to parse (frame 9 of 90), as the writer cuts it off.
        for torn in ["1.5,1.2,0.", "1.5,1.2,0.9,0.6,9"] {
            std::fs::write(&path, format!("{HEADER}\n1.25,0.9,0.31,0,7\n{torn}")).unwrap();
            assert_eq!(read(&path).unwrap(), points[..1].to_vec(), "{torn}");
        }
        // A complete last row that is corrupt is refused naming the file and the line.
        std::fs::write(
            &path,
            format!("{HEADER}\n1.25,0.9,0.31,0,7\n1.5,#,0.9,0.6,90\n"),
        )
        .unwrap();
        let error = read(&path).unwrap_err();
        assert!(
            matches!(error, JournalError::Row { line: 3, .. }),
            "{error}"
        );
        let message = error.to_string();
        assert!(
            message.contains(&path.display().to_string()) && message.contains("line 3"),
            "{message}"
        );
        // A bad line in the middle is an error naming the line.
        std::fs::write(
            &path,
            format!("{}\n1.25,x,0.31,0,7\n1.5,1.2,0.9,0.6,90\n", HEADER),
        )
        .unwrap();
        let error = read(&path).unwrap_err();
        assert!(
            matches!(error, JournalError::Row { line: 2, .. }),
            "{error}"
        );
        assert!(error.to_string().contains("line 2"), "{error}");
        // NaN is refused like any malformed line.
        std::fs::write(
            &path,
            format!("{}\n1.25,0.9,NaN,0,7\n1.5,1.2,0.9,0.6,90\n", HEADER),
        )
        .unwrap();
        assert!(matches!(
            read(&path),
            Err(JournalError::Row { line: 2, .. })
        ));
        std::fs::write(&path, "stretch,stress\n").unwrap();
        assert!(matches!(read(&path), Err(JournalError::Header { .. })));
        // An earlier per-case journal is refused with a message saying what it is.
        std::fs::write(&path, format!("{PER_CASE_HEADER}\nuniaxial,1.25,0.31,7\n")).unwrap();
        let error = read(&path).unwrap_err();
        assert!(error.to_string().contains("earlier version"), "{error}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
