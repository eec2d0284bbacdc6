//! How every process writes the files of a run, so that a failed write (a full disk) or a
//! kill at any moment leaves each file whole: a file is replaced atomically (temporary
//! sibling, then rename; the temporary file is removed when anything fails), and a log grows
//! by whole rows (a row that could not be written whole is cut back off). Errors name the
//! file; [`FileError::is_disk_full`] tells a full disk, which stops a run.

use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// A failed file operation, naming the file. The I/O error is part of the message, not a
/// `source()` (an error chain printed with `{:#}` says it once); a process out of file
/// descriptors says so with its limit.
#[derive(Debug, thiserror::Error)]
#[error("cannot {what} {}: {reason}{}", .path.display(), crate::descriptors::note_for(.reason))]
pub struct FileError {
    pub path: PathBuf,
    /// `write`, `create`, `open`, `rename to`...
    pub what: &'static str,
    pub reason: std::io::Error,
}

impl FileError {
    fn new(path: &Path, what: &'static str, reason: std::io::Error) -> FileError {
        FileError {
            path: path.to_path_buf(),
            what,
            reason,
        }
    }

    /// No space (or quota) left on the file's device.
    pub fn is_disk_full(&self) -> bool {
        matches!(
            self.reason.raw_os_error(),
            Some(libc::ENOSPC) | Some(libc::EDQUOT)
        ) || self.reason.kind() == std::io::ErrorKind::StorageFull
    }

    /// The process (EMFILE) or the system (ENFILE) has no file descriptor left: not the
    /// output's fault, a restart would fail the same way.
    pub fn is_out_of_descriptors(&self) -> bool {
        matches!(
            self.reason.raw_os_error(),
            Some(libc::EMFILE) | Some(libc::ENFILE)
        )
    }
}

/// The temporary sibling of `path`: hidden, and naming this process.
fn temporary_of(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp{}", std::process::id()))
}

/// Replaces `path` with `bytes` atomically: a reader sees the old file or the new one, never
/// a part. On failure nothing is left but the old file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    AtomicFile::new(path).write(bytes)
}

/// A file replaced atomically again and again (a state file): its temporary sibling is named
/// once, so a write allocates nothing.
#[derive(Clone, Debug)]
pub struct AtomicFile {
    path: PathBuf,
    temp: PathBuf,
}

impl AtomicFile {
    pub fn new(path: &Path) -> AtomicFile {
        AtomicFile {
            path: path.to_path_buf(),
            temp: temporary_of(path),
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Replaces the file with `bytes` ([`write_atomic`]).
    pub fn write(&self, bytes: &[u8]) -> Result<(), FileError> {
        let result = std::fs::write(&self.temp, bytes)
            .and_then(|()| std::fs::rename(&self.temp, &self.path))
            .map_err(|e| FileError::new(&self.path, "write", e));
        if result.is_err() {
            let _ = std::fs::remove_file(&self.temp);
        }
        result
    }
}

/// A log file that grows by whole rows: each row is one write; a row that fails part-way is
/// cut back off, so the file always ends with a whole row.
pub struct RowFile {
    path: PathBuf,
    file: std::fs::File,
    /// Length of the whole rows written.
    len_bytes: u64,
}

impl RowFile {
    /// Creates (or empties) `path` and writes `header` as its first row.
    pub fn create(path: &Path, header: &str) -> Result<RowFile, FileError> {
        let file = std::fs::File::create(path).map_err(|e| FileError::new(path, "create", e))?;
        let mut rows = RowFile {
            path: path.to_path_buf(),
            file,
            len_bytes: 0,
        };
        rows.append(&format!("{header}\n"))?;
        Ok(rows)
    }

    /// Opens `path` to go on appending after its first `keep_bytes` bytes (what a journal says
    /// was written whole; anything after is cut off). A missing or empty file is created with
    /// `header`.
    pub fn resume(path: &Path, header: &str, keep_bytes: u64) -> Result<RowFile, FileError> {
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .map_err(|e| FileError::new(path, "open", e))?;
        let len = file
            .metadata()
            .map_err(|e| FileError::new(path, "open", e))?
            .len();
        if len == 0 || keep_bytes == 0 {
            drop(file);
            return RowFile::create(path, header);
        }
        let mut rows = RowFile {
            path: path.to_path_buf(),
            file,
            len_bytes: keep_bytes.min(len),
        };
        rows.cut_back()?;
        Ok(rows)
    }

    /// Opens `path` to go on appending after its last whole row (a torn last row, as a kill
    /// leaves it, is cut off). A missing or empty file is created with `header`.
    pub fn append_to(path: &Path, header: &str) -> Result<RowFile, FileError> {
        let whole = match std::fs::read(path) {
            Ok(bytes) => bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => 0,
            Err(e) => return Err(FileError::new(path, "read", e)),
        };
        RowFile::resume(path, header, whole as u64)
    }

    /// Truncates the file to its whole rows and moves to its end.
    fn cut_back(&mut self) -> Result<(), FileError> {
        self.file
            .set_len(self.len_bytes)
            .and_then(|()| self.file.seek(SeekFrom::Start(self.len_bytes)).map(|_| ()))
            .map_err(|e| FileError::new(&self.path, "truncate", e))
    }

    /// Appends `rows` (whole rows, each ending with a newline) in one write. On failure the
    /// file is cut back to the rows before.
    pub fn append(&mut self, rows: &str) -> Result<(), FileError> {
        debug_assert!(rows.is_empty() || rows.ends_with('\n'));
        match self.file.write_all(rows.as_bytes()) {
            Ok(()) => {
                self.len_bytes += rows.len() as u64;
                Ok(())
            }
            Err(e) => {
                let _ = self.cut_back();
                Err(FileError::new(&self.path, "write", e))
            }
        }
    }

    /// Bytes of whole rows written (a resume point).
    pub fn len_bytes(&self) -> u64 {
        self.len_bytes
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("wire_files_{}_{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn atomic_writes_leave_no_temporary_file_even_when_they_fail() {
        let dir = scratch("atomic");
        let path = dir.join("a.json");
        write_atomic(&path, b"{}").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"{}");
        // Renaming onto a folder fails after the temporary file was written.
        let folder = dir.join("sub");
        std::fs::create_dir(&folder).unwrap();
        std::fs::write(folder.join("x"), b"x").unwrap();
        let error = write_atomic(&folder, b"data").unwrap_err();
        assert!(error.to_string().contains("sub"), "{error}");
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(!names.iter().any(|n| n.contains(".tmp")), "{names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn rows_resume_after_the_whole_rows_a_journal_names() {
        let dir = scratch("rows");
        let path = dir.join("log.csv");
        let mut rows = RowFile::create(&path, "t,x").unwrap();
        rows.append("0,1\n").unwrap();
        let kept = rows.len_bytes();
        rows.append("1,2\n").unwrap();
        drop(rows);
        // A torn row after the journal's point, as a kill would leave it.
        std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .unwrap()
            .write_all(b"2,")
            .unwrap();
        let mut rows = RowFile::resume(&path, "t,x", kept).unwrap();
        rows.append("1,2.5\n").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "t,x\n0,1\n1,2.5\n");
        // Appending after the last whole row cuts a torn one.
        std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .unwrap()
            .write_all(b"3,")
            .unwrap();
        drop(rows);
        let mut rows = RowFile::append_to(&path, "t,x").unwrap();
        rows.append("3,4\n").unwrap();
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "t,x\n0,1\n1,2.5\n3,4\n"
        );
        // A missing file starts over with its header.
        let fresh = dir.join("new.csv");
        RowFile::resume(&fresh, "t,x", 100).unwrap();
        assert_eq!(std::fs::read_to_string(&fresh).unwrap(), "t,x\n");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_full_disk_is_told_and_cut_back_to_whole_rows() {
        // /dev/full fails every write with ENOSPC.
        let Ok(file) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
            eprintln!("skipped: no /dev/full");
            return;
        };
        let mut rows = RowFile {
            path: PathBuf::from("/dev/full"),
            file,
            len_bytes: 0,
        };
        let error = rows.append("1,2\n").unwrap_err();
        assert!(error.is_disk_full(), "{error}");
        assert!(error.to_string().contains("/dev/full"), "{error}");
        assert_eq!(rows.len_bytes(), 0);
    }
}
