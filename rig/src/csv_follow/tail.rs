//! What was appended to a file since the last poll. A file that does not exist yet is waited
//! for; a file that became shorter than what was read (truncated) or another file under the
//! same name (rotated: another inode) is reported, and read again from its start.

use std::io::{Read, Seek, SeekFrom};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// One poll's outcome.
#[derive(Debug, PartialEq)]
pub enum TailRead {
    /// The file does not exist (yet, or any more).
    Missing,
    /// Bytes appended since the last poll (maybe none), and the file's modification time.
    Appended {
        bytes: Vec<u8>,
        modified: SystemTime,
    },
    /// The file was truncated or replaced; the next poll reads it from its start.
    StartedOver { why: String },
}

/// Follows one file by path.
#[derive(Debug)]
pub struct FileTail {
    path: PathBuf,
    offset: u64,
    /// (device, inode) of the file being read.
    identity: Option<(u64, u64)>,
    /// Most bytes read in one poll (the rest waits for the next).
    pub max_read_bytes: usize,
}

impl FileTail {
    pub fn new(path: &Path) -> FileTail {
        FileTail {
            path: path.to_path_buf(),
            offset: 0,
            identity: None,
            max_read_bytes: 1 << 20,
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Bytes read so far from the current file.
    pub fn offset(&self) -> u64 {
        self.offset
    }

    pub fn poll(&mut self) -> std::io::Result<TailRead> {
        let mut file = match std::fs::File::open(&self.path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(TailRead::Missing),
            Err(e) => return Err(e),
        };
        let meta = file.metadata()?;
        let identity = (meta.dev(), meta.ino());
        if let Some(known) = self.identity {
            let why = if known != identity {
                Some("replaced by another file (rotated)".to_string())
            } else if meta.len() < self.offset {
                Some(format!(
                    "truncated to {} bytes after {} were read",
                    meta.len(),
                    self.offset
                ))
            } else {
                None
            };
            if let Some(why) = why {
                self.identity = None;
                self.offset = 0;
                return Ok(TailRead::StartedOver { why });
            }
        }
        self.identity = Some(identity);
        let available = meta.len().saturating_sub(self.offset);
        let take = available.min(self.max_read_bytes as u64) as usize;
        let mut bytes = vec![0u8; take];
        if take > 0 {
            file.seek(SeekFrom::Start(self.offset))?;
            let mut read = 0;
            while read < take {
                match file.read(&mut bytes[read..])? {
                    0 => break,
                    n => read += n,
                }
            }
            bytes.truncate(read);
            self.offset += read as u64;
        }
        Ok(TailRead::Appended {
            bytes,
            modified: meta.modified().unwrap_or(SystemTime::UNIX_EPOCH),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn appended(read: TailRead) -> Vec<u8> {
        match read {
            TailRead::Appended { bytes, .. } => bytes,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn waits_for_the_file_reads_appends_and_notices_truncation_and_rotation() {
        let dir = std::env::temp_dir().join(format!("csv_tail_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("log.csv");
        let _ = std::fs::remove_file(&path);
        let mut tail = FileTail::new(&path);
        assert_eq!(tail.poll().unwrap(), TailRead::Missing);
        std::fs::write(&path, b"a,b\n1,").unwrap();
        assert_eq!(appended(tail.poll().unwrap()), b"a,b\n1,");
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .unwrap();
        f.write_all(b"2\n").unwrap();
        assert_eq!(appended(tail.poll().unwrap()), b"2\n");
        assert_eq!(appended(tail.poll().unwrap()), b"");
        std::fs::write(&path, b"a\n").unwrap();
        assert!(
            matches!(tail.poll().unwrap(), TailRead::StartedOver { why } if why.contains("truncated"))
        );
        assert_eq!(appended(tail.poll().unwrap()), b"a\n");
        let other = dir.join("log.csv.new");
        std::fs::write(&other, b"x,y\n").unwrap();
        std::fs::rename(&other, &path).unwrap();
        assert!(
            matches!(tail.poll().unwrap(), TailRead::StartedOver { why } if why.contains("rotated"))
        );
        assert_eq!(appended(tail.poll().unwrap()), b"x,y\n");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
