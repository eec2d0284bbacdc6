//! The follow's counters kept in a JSON file (`--counts-json`; a run's `machine_csv.json`,
//! which `dicstream run` copies into `summary.json`), replaced atomically: at once when a
//! malformed line or a restart was counted, at most once a second for rows alone, and at the
//! end. So a follower killed at any moment leaves its malformed count exact.

use super::FollowCounters;
use std::path::Path;
use std::time::{Duration, Instant};
use wire::files::{AtomicFile, FileError};

/// Longest a count of rows alone waits to be written.
pub const ROWS_WRITTEN_EVERY: Duration = Duration::from_secs(1);

#[derive(Debug)]
pub struct CountsFile {
    file: AtomicFile,
    written: Option<(FollowCounters, Instant)>,
}

impl CountsFile {
    pub fn new(path: &Path) -> CountsFile {
        CountsFile {
            file: AtomicFile::new(path),
            written: None,
        }
    }

    /// Writes `counters` if they are due (`at_end`: whenever they changed).
    pub fn update(
        &mut self,
        counters: FollowCounters,
        now: Instant,
        at_end: bool,
    ) -> Result<(), FileError> {
        let due = match self.written {
            None => true,
            Some((written, _)) if written == counters => false,
            Some((written, at)) => {
                at_end
                    || written.malformed_lines != counters.malformed_lines
                    || written.restarts != counters.restarts
                    || now.duration_since(at) >= ROWS_WRITTEN_EVERY
            }
        };
        if due {
            let json = serde_json::to_string_pretty(&counters).expect("plain counters");
            self.file.write(json.as_bytes())?;
            self.written = Some((counters, now));
        }
        Ok(())
    }
}

/// Reads a counts file.
pub fn read(path: &Path) -> Result<FollowCounters, CountsReadError> {
    let text = std::fs::read_to_string(path).map_err(|reason| CountsReadError::Read {
        path: path.display().to_string(),
        reason,
    })?;
    serde_json::from_str(&text).map_err(|reason| CountsReadError::Parse {
        path: path.display().to_string(),
        reason,
    })
}

#[derive(Debug, thiserror::Error)]
pub enum CountsReadError {
    #[error("cannot read {path}: {reason}")]
    Read {
        path: String,
        reason: std::io::Error,
    },
    #[error("{path} is not the follower's counts: {reason}")]
    Parse {
        path: String,
        reason: serde_json::Error,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn malformed_lines_are_written_at_once_rows_at_most_once_a_second() {
        let dir = std::env::temp_dir().join(format!("csv_counts_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("machine_csv.json");
        let mut file = CountsFile::new(&path);
        let t0 = Instant::now();
        let mut c = FollowCounters::default();
        file.update(c, t0, false).unwrap();
        assert_eq!(read(&path).unwrap(), c);
        c.rows = 10;
        file.update(c, t0, false).unwrap();
        assert_eq!(read(&path).unwrap().rows, 0, "rows alone wait");
        c.malformed_lines = 1;
        file.update(c, t0, false).unwrap();
        assert_eq!(read(&path).unwrap(), c, "a malformed line at once");
        c.rows = 20;
        file.update(c, t0 + ROWS_WRITTEN_EVERY, false).unwrap();
        assert_eq!(read(&path).unwrap(), c, "rows after a second");
        c.rows = 21;
        file.update(c, t0 + ROWS_WRITTEN_EVERY, true).unwrap();
        assert_eq!(read(&path).unwrap(), c, "everything at the end");
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("\"malformed_lines\": 1"), "{text}");
        std::fs::write(&path, "{}").unwrap();
        let e = read(&path).unwrap_err().to_string();
        assert!(e.contains("machine_csv.json"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
