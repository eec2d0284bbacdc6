//! A resumed rig's log (`rig.csv`) against the rows of its journal's replay. The replay is
//! exact, so the log of a rig that journals holds exactly the header and the rows the replay
//! gives, from the first period on. [`LogCheck`] is handed those rows as the replay makes them
//! and reads the file alongside, keeping only what the file lacks; [`LogCheck::finish`] says
//! whether the file is whole or short (cut, torn or missing: the rest can be regenerated), or
//! refuses a different one (not this run's log: a resume must not touch it). Reads only; no
//! IPC.

use std::io::Read;

/// What the file holds against the replay's rows (rows under the header).
#[derive(Clone, Debug, PartialEq)]
pub enum LogFinding {
    /// Every row of the replay (`bytes` with the header), then `extra_bytes` more (written
    /// after the last journal: the rig writes those rows again as it goes on).
    Whole { bytes: u64, extra_bytes: u64 },
    /// The first `kept_rows` rows only (`kept_bytes` with the header; 0: not even the header,
    /// or no file), then `torn_bytes` of a row cut part-way; `missing` is the replay's rows
    /// after the kept ones.
    Short {
        file_exists: bool,
        kept_bytes: u64,
        kept_rows: u64,
        torn_bytes: u64,
        missing: String,
    },
}

/// Why a log cannot be continued.
#[derive(Debug, thiserror::Error)]
pub enum LogCheckError {
    #[error("cannot read it: {0}")]
    Read(#[from] std::io::Error),
    /// Line `line` (1: the header) is not the replay's, and whole rows follow: another log.
    #[error("it is not this run's log: its line {line} differs from the replay's (it holds {file_rows} rows, the replay {replay_rows})")]
    Differs {
        line: u64,
        file_rows: u64,
        replay_rows: u64,
    },
}

/// Where the file stopped agreeing with the replay.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Stop {
    /// The file ended there (or its last line, without a newline, is torn).
    Ended,
    Differs {
        line: u64,
        file_lines: u64,
    },
}

/// The comparison under way (see the module's documentation).
pub struct LogCheck<R> {
    /// The file, while it agrees with the replay.
    file: Option<R>,
    file_exists: bool,
    scratch: Vec<u8>,
    /// Bytes read from the file (all of it once it stopped agreeing).
    read_bytes: u64,
    /// Bytes and lines (header included) of the whole lines equal to the replay's.
    agreed_bytes: u64,
    agreed_lines: u64,
    expected_bytes: u64,
    expected_lines: u64,
    /// The replay's rows after the agreed ones, once the file stopped agreeing.
    missing: String,
    stop: Option<Stop>,
}

impl<R: Read> LogCheck<R> {
    /// Starts with the file (None: there is none) and the log's header.
    pub fn new(file: Option<R>, header: &str) -> Result<LogCheck<R>, LogCheckError> {
        let mut check = LogCheck {
            file_exists: file.is_some(),
            stop: file.is_none().then_some(Stop::Ended),
            file,
            scratch: Vec::new(),
            read_bytes: 0,
            agreed_bytes: 0,
            agreed_lines: 0,
            expected_bytes: 0,
            expected_lines: 0,
            missing: String::new(),
        };
        // The header is written by whoever opens the log, never as a missing row.
        check.compare(&format!("{header}\n"), false)?;
        Ok(check)
    }

    /// The replay's next rows (whole rows, each with its newline).
    pub fn feed(&mut self, rows: &str) -> Result<(), LogCheckError> {
        self.compare(rows, true)
    }

    /// Rows the replay gave (under the header) and the bytes of the log it implies.
    pub fn expected(&self) -> (u64, u64) {
        (self.expected_lines.saturating_sub(1), self.expected_bytes)
    }

    fn compare(&mut self, chunk: &str, rows: bool) -> Result<(), LogCheckError> {
        let start = self.expected_bytes;
        self.expected_bytes += chunk.len() as u64;
        self.expected_lines += newlines(chunk.as_bytes());
        let Some(file) = self.file.as_mut() else {
            if rows {
                self.missing.push_str(chunk);
            }
            return Ok(());
        };
        self.scratch.resize(chunk.len(), 0);
        let read = read_up_to(file, &mut self.scratch)?;
        self.read_bytes += read as u64;
        let same = self.scratch[..read]
            .iter()
            .zip(chunk.as_bytes())
            .take_while(|(a, b)| a == b)
            .count();
        if same == chunk.len() {
            self.agreed_bytes = self.expected_bytes;
            self.agreed_lines = self.expected_lines;
            return Ok(());
        }
        // Chunks are whole lines: the agreement ends at the last newline before `same`.
        let whole = chunk.as_bytes()[..same]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        self.agreed_bytes = start + whole as u64;
        self.agreed_lines += newlines(&chunk.as_bytes()[..whole]);
        let mut after = newlines(&self.scratch[same..read]);
        if same < read {
            let (bytes, lines) = count_rest(file)?;
            self.read_bytes += bytes;
            after += lines;
        }
        // A differing last line without its newline is a row torn part-way.
        self.stop = Some(if after == 0 {
            Stop::Ended
        } else {
            Stop::Differs {
                line: self.agreed_lines + 1,
                file_lines: self.agreed_lines + after,
            }
        });
        self.file = None;
        if rows {
            self.missing.push_str(&chunk[whole..]);
        }
        Ok(())
    }

    /// What the file holds, once every row of the replay was fed.
    pub fn finish(mut self) -> Result<LogFinding, LogCheckError> {
        Ok(match self.stop {
            None => {
                let file = self.file.as_mut().expect("a file agreeing so far");
                LogFinding::Whole {
                    bytes: self.expected_bytes,
                    extra_bytes: count_rest(file)?.0,
                }
            }
            Some(Stop::Ended) => LogFinding::Short {
                file_exists: self.file_exists,
                kept_bytes: self.agreed_bytes,
                kept_rows: self.agreed_lines.saturating_sub(1),
                torn_bytes: self.read_bytes - self.agreed_bytes,
                missing: self.missing,
            },
            Some(Stop::Differs { line, file_lines }) => {
                return Err(LogCheckError::Differs {
                    line,
                    file_rows: file_lines.saturating_sub(1),
                    replay_rows: self.expected().0,
                })
            }
        })
    }
}

fn newlines(bytes: &[u8]) -> u64 {
    bytes.iter().filter(|&&b| b == b'\n').count() as u64
}

/// Fills `buffer` as far as the file goes; the bytes read.
fn read_up_to(file: &mut impl Read, buffer: &mut [u8]) -> std::io::Result<usize> {
    let mut filled = 0;
    while filled < buffer.len() {
        match file.read(&mut buffer[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

/// Bytes and newlines left in the file.
fn count_rest(file: &mut impl Read) -> std::io::Result<(u64, u64)> {
    let mut buffer = [0u8; 8192];
    let (mut bytes, mut lines) = (0, 0);
    loop {
        let n = read_up_to(file, &mut buffer)?;
        if n == 0 {
            return Ok((bytes, lines));
        }
        bytes += n as u64;
        lines += newlines(&buffer[..n]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "t,x";
    const ROWS: [&str; 3] = ["0,1\n", "1,2\n", "2,3\n"];

    fn check(file: Option<&str>) -> Result<LogFinding, LogCheckError> {
        let mut check = LogCheck::new(file.map(str::as_bytes), HEADER)?;
        for rows in ROWS {
            check.feed(rows)?;
        }
        assert_eq!(check.expected(), (3, 16));
        check.finish()
    }

    /// Short of `missing`, the rows before it kept.
    fn short(
        file_exists: bool,
        kept_bytes: u64,
        torn_bytes: u64,
        missing: &str,
    ) -> Option<LogFinding> {
        Some(LogFinding::Short {
            file_exists,
            kept_bytes,
            kept_rows: 3 - newlines(missing.as_bytes()),
            torn_bytes,
            missing: missing.into(),
        })
    }

    #[test]
    fn a_whole_log_is_whole_with_what_follows_counted() {
        let full = "t,x\n0,1\n1,2\n2,3\n";
        let whole = |extra_bytes| LogFinding::Whole {
            bytes: 16,
            extra_bytes,
        };
        assert_eq!(check(Some(full)).unwrap(), whole(0));
        let more = "t,x\n0,1\n1,2\n2,3\n3,4\n4,";
        assert_eq!(check(Some(more)).unwrap(), whole(6));
    }

    #[test]
    fn a_cut_torn_or_missing_log_lacks_the_rest_of_the_replay() {
        assert_eq!(check(None).ok(), short(false, 0, 0, "0,1\n1,2\n2,3\n"));
        assert_eq!(check(Some("")).ok(), short(true, 0, 0, "0,1\n1,2\n2,3\n"));
        // Cut mid-row, in the header, at a row's end.
        assert_eq!(
            check(Some("t,x\n0,1\n1,")).ok(),
            short(true, 8, 2, "1,2\n2,3\n")
        );
        assert_eq!(check(Some("t,")).ok(), short(true, 0, 2, "0,1\n1,2\n2,3\n"));
        assert_eq!(
            check(Some("t,x\n0,1\n")).ok(),
            short(true, 8, 0, "1,2\n2,3\n")
        );
        // A torn last row that is not the replay's (written part-way, then garbled).
        assert_eq!(
            check(Some("t,x\n0,1\n1,9")).ok(),
            short(true, 8, 3, "1,2\n2,3\n")
        );
    }

    /// The line that differs, the file's rows and the replay's.
    fn differs(file: &str) -> (u64, u64, u64) {
        match check(Some(file)) {
            Err(LogCheckError::Differs {
                line,
                file_rows,
                replay_rows,
            }) => (line, file_rows, replay_rows),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn another_log_differs_from_its_first_other_line() {
        // The splice: a cut row, then rows appended after it.
        let spliced = "t,x\n0,1\n1,0,1\n1,2\n2,3\n";
        assert_eq!(differs(spliced), (3, 4, 3));
        assert_eq!(
            check(Some(spliced)).unwrap_err().to_string(),
            "it is not this run's log: its line 3 differs from the replay's (it holds 4 rows, the \
             replay 3)"
        );
        // Another header.
        assert_eq!(differs("t,y\n0,1\n"), (1, 1, 3));
    }
}
