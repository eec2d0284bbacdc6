//! The `--log FILE` of `dicstream producer --watch` and `--camera`: one CSV row per frame,
//! written while the stream goes on. A failed write stops the rows, not the stream; it is the
//! run's error once the stream has ended.

use std::path::PathBuf;

use anyhow::Context;
use wire::files::{FileError, RowFile};

/// The rows of a `--log` file, if one was asked for, and the first write that failed.
pub struct LogRows {
    rows: Option<RowFile>,
    error: Option<FileError>,
}

impl LogRows {
    /// Creates `path` with its `header` row; no file without a path.
    pub fn create(path: Option<&PathBuf>, header: &str) -> anyhow::Result<LogRows> {
        let rows = match path {
            Some(path) => Some(
                RowFile::create(path, header)
                    .with_context(|| format!("creating the --log file {}", path.display()))?,
            ),
            None => None,
        };
        Ok(LogRows { rows, error: None })
    }

    /// Appends the row `row` makes (ending with a line break), until a write fails.
    pub fn append(&mut self, row: impl FnOnce() -> String) {
        if let (Some(rows), None) = (self.rows.as_mut(), self.error.as_ref()) {
            if let Err(e) = rows.append(&row()) {
                self.error = Some(e);
            }
        }
    }

    /// The first failed write, as the run's error.
    pub fn finish(self) -> anyhow::Result<()> {
        match self.error {
            Some(e) => Err(anyhow::Error::new(e).context("writing the --log file")),
            None => Ok(()),
        }
    }
}
