//! A restarted rig's way back to where its journal says: the journal read and checked (one
//! that cannot be read or whose figures do not fit is refused at once), the replay run (a
//! termination request ends it), and the log compared with the replay's rows
//! ([`crate::log_check`]): a log cut, torn or missing gets the rows it lacks from the replay,
//! another log is refused untouched. Every refusal asks for exit code
//! [`wire::exit::CANNOT_RESUME`]; the specimen stays unloaded. Files only, no IPC.

use super::ProcessError;
use crate::journal::Journal;
use crate::log_check::{LogCheck, LogCheckError, LogFinding};
use crate::session::Session;
use std::path::Path;
use wire::files::RowFile;

/// Where the replay brought the rig, and what its log needs.
pub(super) struct Resumed {
    /// The log against the replay (None: the rig logs nothing).
    pub log: Option<LogFinding>,
    /// Rows the log holds once reopened (under its header).
    pub rows_logged: u64,
}

/// A refusal to resume from `journal` because of `why`.
pub(super) fn refuse(journal: &Path, why: &dyn std::fmt::Display) -> ProcessError {
    ProcessError::CannotResume(wire::exit::ExitWith {
        code: wire::exit::CANNOT_RESUME,
        message: format!(
            "cannot resume from {}: {why}; the specimen is left unloaded and the rig stopped",
            journal.display()
        ),
    })
}

/// Brings `session` to where the journal at `path` says (None: no journal, a fresh start),
/// checking the log at `log_path` (if any) against the replay's rows. `ends_when_done`: see
/// [`Session::resume`].
pub(super) fn resume(
    session: &mut Session,
    path: &Path,
    settings: u64,
    log_path: Option<&Path>,
    ends_when_done: Option<bool>,
) -> Result<Option<Resumed>, ProcessError> {
    let bytes = match std::fs::read(path) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(reason) => return Err(refuse(path, &format_args!("cannot read it: {reason}"))),
    };
    let journal = Journal::parse_bytes(&bytes).map_err(|e| refuse(path, &format_args!("{e}")))?;
    if journal.settings != settings {
        return Err(refuse(
            path,
            &"it was written by a rig with other settings (campaign, material, seed or rates)",
        ));
    }
    let header = crate::log::csv_header();
    // The log is read alongside the replay: its rows should be the replay's, from the header on.
    let log_refused = |log: &Path, why: LogCheckError| {
        let hint = match why {
            LogCheckError::Differs { .. } => "; move it aside and the rig writes it again",
            LogCheckError::Read(_) => "",
        };
        refuse(path, &format_args!("{}: {why}{hint}", log.display()))
    };
    let mut check = match log_path {
        None => None,
        Some(log) => {
            let file = match std::fs::File::open(log) {
                Ok(file) => Some(std::io::BufReader::new(file)),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
                Err(reason) => return Err(log_refused(log, reason.into())),
            };
            Some(LogCheck::new(file, &header).map_err(|e| log_refused(log, e))?)
        }
    };
    let mut replayed = 0u64;
    session
        .resume(&journal, ends_when_done, |rows| {
            replayed += 1;
            if replayed == 1 {
                // The journal was found sound: a replay long enough to be seen begins.
                eprintln!(
                    "rig: resuming from {}: replaying {} periods (to t = {:.3} s)",
                    path.display(),
                    journal.periods,
                    journal.t_s
                );
            }
            if let Some(signal) = wire::signals::requested() {
                return Err(ProcessError::ReplayStopped {
                    signal: wire::signals::name(signal),
                    journal: path.to_path_buf(),
                    periods: replayed,
                    of: journal.periods,
                });
            }
            match (check.as_mut(), log_path) {
                (Some(check), Some(log)) => check.feed(rows).map_err(|e| log_refused(log, e)),
                _ => Ok(()),
            }
        })
        .map_err(|e| match e {
            ProcessError::Session(why) => refuse(path, &why),
            other => other,
        })?;
    let (Some(check), Some(log)) = (check, log_path) else {
        return Ok(Some(Resumed {
            log: None,
            rows_logged: 0,
        }));
    };
    let (rows, bytes) = check.expected();
    // A journal written with a log names the log's rows: the replay gives as many.
    if journal.log_bytes != 0 && journal.log_bytes != bytes {
        return Err(refuse(
            path,
            &format_args!(
                "it says {} held {} bytes, its replay gives {bytes}",
                log.display(),
                journal.log_bytes
            ),
        ));
    }
    let finding = check.finish().map_err(|e| log_refused(log, e))?;
    Ok(Some(Resumed {
        log: Some(finding),
        rows_logged: rows,
    }))
}

/// Opens the log at `path` to go on after the replay's rows: what follows them cut back, what
/// is missing written from the replay, each said on stderr.
pub(super) fn reopen_log(path: &Path, finding: LogFinding) -> Result<RowFile, ProcessError> {
    let header = crate::log::csv_header();
    match finding {
        LogFinding::Whole { bytes, extra_bytes } => {
            let log = RowFile::resume(path, &header, bytes)?;
            if extra_bytes > 0 {
                eprintln!(
                    "rig: {}: {extra_bytes} bytes written after the journal cut back (the rig \
                     writes those rows again)",
                    path.display()
                );
            }
            Ok(log)
        }
        LogFinding::Short {
            file_exists,
            kept_bytes,
            kept_rows,
            torn_bytes,
            missing,
        } => {
            let mut log = RowFile::resume(path, &header, kept_bytes)?;
            log.append(&missing)?;
            let rows = missing.matches('\n').count();
            let torn = if torn_bytes > 0 {
                format!(", then a row torn after {torn_bytes} bytes (cut back)")
            } else {
                String::new()
            };
            if !file_exists {
                eprintln!(
                    "rig: {} was missing: its {rows} rows written again from the journal's replay",
                    path.display()
                );
            } else if rows > 0 || torn_bytes > 0 {
                eprintln!(
                    "rig: {} held {kept_rows} rows of the journal's {}{torn}: the {rows} missing \
                     rows written again from the journal's replay",
                    path.display(),
                    kept_rows + rows as u64
                );
            }
            Ok(log)
        }
    }
}
