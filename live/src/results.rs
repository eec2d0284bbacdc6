//! The results folder of a run, `<results_dir>/<date-time>/`: what goes where, and how it is
//! written (appended and flushed per row, or whole files atomically: temporary sibling, then
//! rename), so a run killed at any moment keeps everything it had.

use std::path::{Path, PathBuf};

/// Paths of one run's results.
#[derive(Clone, Debug)]
pub struct ResultsDir {
    pub root: PathBuf,
}

impl ResultsDir {
    /// Creates `<parent>/<local date-time>` (with a suffix if it exists already).
    pub fn create_dated(parent: &Path) -> Result<ResultsDir, String> {
        let stamp = local_timestamp();
        for k in 0..100 {
            let name = if k == 0 {
                stamp.clone()
            } else {
                format!("{stamp}_{k}")
            };
            let root = parent.join(name);
            match std::fs::create_dir_all(parent).and_then(|_| std::fs::create_dir(&root)) {
                Ok(()) => return ResultsDir::at(&root),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(format!("cannot create {}: {e}", root.display())),
            }
        }
        Err(format!("{}: too many runs this second", parent.display()))
    }

    /// Uses `root` (created if missing; its files are overwritten, and the resume state of
    /// an earlier run there is removed: this run's children start afresh, and only their own
    /// restarts resume).
    pub fn at(root: &Path) -> Result<ResultsDir, String> {
        for dir in [root.to_path_buf(), root.join("fields"), root.join("logs")] {
            std::fs::create_dir_all(&dir)
                .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        }
        let results = ResultsDir {
            root: root.to_path_buf(),
        };
        for state in [results.rig_state(), results.correlator_state()] {
            match std::fs::remove_dir_all(&state) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    return Err(format!("cannot remove {}: {e}", state.display()))
                }
                _ => {}
            }
        }
        match std::fs::remove_file(results.journal()) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(format!(
                    "cannot remove {}: {e}",
                    results.journal().display()
                ))
            }
            _ => {}
        }
        Ok(results)
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.root.join(name)
    }

    pub fn config(&self) -> PathBuf {
        self.path("config.toml")
    }
    pub fn rig_csv(&self) -> PathBuf {
        self.path("rig.csv")
    }
    pub fn frames_csv(&self) -> PathBuf {
        self.path("frames.csv")
    }
    pub fn identification_json(&self) -> PathBuf {
        self.path("identification.json")
    }
    pub fn journal(&self) -> PathBuf {
        self.path("identification_points.csv")
    }
    pub fn correlator_state(&self) -> PathBuf {
        self.path("correlator_state")
    }
    pub fn rig_state(&self) -> PathBuf {
        self.path("rig_state")
    }
    pub fn fields(&self) -> PathBuf {
        self.path("fields")
    }
    pub fn logs(&self) -> PathBuf {
        self.path("logs")
    }
    pub fn summary_json(&self) -> PathBuf {
        self.path("summary.json")
    }
}

/// Writes `bytes` to `path` atomically ([`wire::files::write_atomic`]; the error names the
/// file).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), String> {
    wire::files::write_atomic(path, bytes).map_err(|e| e.to_string())
}

/// A CSV file written row by row, each row whole ([`wire::files::RowFile`]).
pub struct CsvAppender {
    rows: wire::files::RowFile,
}

impl CsvAppender {
    pub fn create(path: &Path, header: &str) -> Result<CsvAppender, String> {
        Ok(CsvAppender {
            rows: wire::files::RowFile::create(path, header).map_err(|e| e.to_string())?,
        })
    }

    /// Appends `line` (which ends with a newline), whole or not at all.
    pub fn append(&mut self, line: &str) -> Result<(), String> {
        self.rows.append(line).map_err(|e| e.to_string())
    }
}

/// `YYYY-MM-DD_HHMMSS` in local time.
pub fn local_timestamp() -> String {
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as libc::time_t)
        .unwrap_or(0);
    // SAFETY: localtime_r writes into the zeroed tm we own; `now` is a valid time_t.
    let mut tm: libc::tm = unsafe { std::mem::zeroed() };
    let ok = unsafe { !libc::localtime_r(&now, &mut tm).is_null() };
    if !ok {
        return format!("run_{now}");
    }
    format!(
        "{:04}-{:02}-{:02}_{:02}{:02}{:02}",
        tm.tm_year + 1900,
        tm.tm_mon + 1,
        tm.tm_mday,
        tm.tm_hour,
        tm.tm_min,
        tm.tm_sec
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dated_folders_never_collide_and_writes_are_whole() {
        let parent = std::env::temp_dir().join(format!("results_test_{}", std::process::id()));
        let a = ResultsDir::create_dated(&parent).unwrap();
        let b = ResultsDir::create_dated(&parent).unwrap();
        assert_ne!(a.root, b.root);
        assert!(a.fields().is_dir() && a.logs().is_dir());
        write_atomic(&a.config(), b"x = 1\n").unwrap();
        assert_eq!(std::fs::read_to_string(a.config()).unwrap(), "x = 1\n");
        let mut csv = CsvAppender::create(&a.frames_csv(), "a,b").unwrap();
        csv.append("1,2\n").unwrap();
        assert_eq!(
            std::fs::read_to_string(a.frames_csv()).unwrap(),
            "a,b\n1,2\n"
        );
        assert_eq!(local_timestamp().len(), 17);
        std::fs::remove_dir_all(&parent).unwrap();
    }
}
