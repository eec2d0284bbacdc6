//! The process shell of the CSV follower (`dicstream rig --follow-csv FILE`): polls the file,
//! publishes one `rig/state` sample per row on the rig's service, in the simulated rig's
//! layout ([`super::clock::rig_state`]), reports on stderr the waits, malformed lines
//! ([`super::report`]), truncations and rotations, and keeps its counters in the
//! `--counts-json` file ([`super::counts_file`]). The only IPC of the follower.

use super::clock::{rig_state, MachineClock};
use super::counts_file::CountsFile;
use super::report::MalformedReport;
use super::{CsvColumns, CsvError, FileTail, FollowCounters, Follower, LineEvent, Row, TailRead};
use crate::process::StatePort;
use std::path::PathBuf;
use std::time::{Duration, Instant, SystemTime};
use wire::pubsub::ValuePublisher;
use wire::RigState;

/// How often the followed file is looked at unless told, ms.
pub const DEFAULT_POLL_MS: u64 = 10;

/// The follower's settings: what `dicstream run` writes for a `csv-follow` rig and what the
/// `rig --follow-csv` flags make; [`FollowOptions::check`] checks them.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FollowOptions {
    pub instance: String,
    pub path: PathBuf,
    pub columns: CsvColumns,
    /// Seconds added to the machine's time (camera time − machine time).
    pub offset_s: f64,
    /// Initial sections of the specimen normal to X and Y, mm² (0: unknown).
    pub sections_mm2: [f64; 2],
    /// How often the file is looked at (1 ms to 10 s).
    #[serde(with = "wire::seconds", rename = "poll_s")]
    pub poll: Duration,
    /// End (successfully) after this long without a new row, once rows have come.
    #[serde(with = "wire::seconds::option", rename = "idle_timeout_s", default)]
    pub idle_timeout: Option<Duration>,
    /// Where the counters are kept as JSON while the follow goes on.
    pub counts_json: Option<PathBuf>,
}

#[derive(Debug, thiserror::Error)]
pub enum FollowError {
    /// The file's header does not have the configured columns: exit code
    /// [`wire::exit::CONFIG`] (a restart would fail the same way).
    #[error("{path}: {error}")]
    Columns {
        path: String,
        #[source]
        error: Box<ConfigError>,
    },
    #[error("cannot read {path}: {reason}")]
    Read {
        path: String,
        reason: std::io::Error,
    },
    #[error(transparent)]
    Instance(#[from] wire::InstanceError),
    /// The counts file could not be written (exit code 74, from its source).
    #[error("{0}")]
    File(#[from] wire::files::FileError),
}

/// The columns error, carrying the exit code a run must not restart on.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct ConfigError(pub CsvError, #[source] wire::exit::ExitWith);

impl FollowError {
    fn columns(path: &std::path::Path, error: CsvError) -> FollowError {
        let exit = wire::exit::ExitWith {
            code: wire::exit::CONFIG,
            message: error.to_string(),
        };
        FollowError::Columns {
            path: path.display().to_string(),
            error: Box::new(ConfigError(error, exit)),
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
pub struct FollowSummary {
    /// Rows published, malformed lines, restarts.
    pub counters: FollowCounters,
    pub stopped_by_signal: bool,
}

/// Follows until a termination signal or the idle timeout.
/// Settings of the follower that cannot be followed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OptionsError {
    #[error("offset_s {0}: expected a number of seconds")]
    Offset(f64),
    #[error("sections_mm2 {0:?}: expected sections in mm² (0: unknown)")]
    Sections([f64; 2]),
    #[error("poll {0:?}: expected 1 ms to 10 s")]
    Poll(Duration),
    #[error("idle timeout {0:?}: expected a positive time")]
    IdleTimeout(Duration),
    #[error("{0}")]
    Columns(#[from] CsvError),
}

impl FollowOptions {
    /// The checks no parser makes: a finite offset, sections ≥ 0, a poll of 1 ms to 10 s, a
    /// positive idle timeout, columns that can be followed.
    pub fn check(&self) -> Result<(), OptionsError> {
        if !self.offset_s.is_finite() {
            return Err(OptionsError::Offset(self.offset_s));
        }
        if !self.sections_mm2.iter().all(|s| s.is_finite() && *s >= 0.0) {
            return Err(OptionsError::Sections(self.sections_mm2));
        }
        if !(Duration::from_millis(1)..=Duration::from_secs(10)).contains(&self.poll) {
            return Err(OptionsError::Poll(self.poll));
        }
        if let Some(idle) = self.idle_timeout.filter(|d| d.is_zero()) {
            return Err(OptionsError::IdleTimeout(idle));
        }
        Ok(self.columns.validate()?)
    }
}

pub fn run(options: FollowOptions) -> Result<FollowSummary, FollowError> {
    let mut follow = CsvFollow::new(&options)?;
    let StatePort {
        instance,
        _owner,
        node: _node,
        publisher,
    } = StatePort::open(&options.instance)?;
    let mut summary = FollowSummary::default();
    let mut counts = options.counts_json.as_deref().map(CountsFile::new);
    let mut last_row_at = Instant::now();
    let mut ready = false;
    loop {
        let (batch, modified) = follow.read()?;
        if let Some(line) = follow.report.tick(Instant::now()) {
            eprintln!("{line}");
        }
        if !ready {
            // Ready once the header, if the file has one already, has been checked, and the
            // counts file is there.
            if let Some(counts) = &mut counts {
                counts.update(follow.follower.counters, Instant::now(), false)?;
            }
            eprintln!("rig: ready (instance {})", instance.name());
            ready = true;
        }
        follow.publish(&batch, modified, &publisher)?;
        if !batch.is_empty() {
            last_row_at = Instant::now();
        }
        if let Some(counts) = &mut counts {
            counts.update(follow.follower.counters, Instant::now(), false)?;
        }
        if wire::signals::requested().is_some() {
            summary.stopped_by_signal = true;
            break;
        }
        if options
            .idle_timeout
            .is_some_and(|t| follow.rows_published > 0 && last_row_at.elapsed() > t)
        {
            break;
        }
        std::thread::sleep(options.poll);
    }
    follow.finish();
    if let Some(counts) = &mut counts {
        counts.update(follow.follower.counters, Instant::now(), true)?;
    }
    summary.counters = follow.follower.counters;
    Ok(summary)
}

/// The file followed: its tail, the rows it gave, the machine's clock and the malformed-line
/// report.
struct CsvFollow<'a> {
    options: &'a FollowOptions,
    follower: Follower,
    tail: FileTail,
    clock: MachineClock,
    report: MalformedReport,
    rows_published: u64,
    waiting_reported: bool,
}

impl<'a> CsvFollow<'a> {
    /// A columns error is refused here, before anything is opened.
    fn new(options: &'a FollowOptions) -> Result<CsvFollow<'a>, FollowError> {
        let path = &options.path;
        Ok(CsvFollow {
            options,
            follower: Follower::new(options.columns.clone())
                .map_err(|e| FollowError::columns(path, e))?,
            tail: FileTail::new(path),
            clock: MachineClock::new(options.offset_s),
            report: MalformedReport::new(path.display().to_string()),
            rows_published: 0,
            waiting_reported: false,
        })
    }

    /// One look at the file: the whole rows appended since the last, and the file's
    /// modification time when something was appended.
    fn read(&mut self) -> Result<(Vec<Row>, Option<SystemTime>), FollowError> {
        let path = &self.options.path;
        let read = self.tail.poll().map_err(|reason| FollowError::Read {
            path: path.display().to_string(),
            reason,
        })?;
        match read {
            TailRead::Missing => {
                if !self.waiting_reported {
                    eprintln!("rig: waiting for {} to exist", path.display());
                    self.waiting_reported = true;
                }
                Ok((Vec::new(), None))
            }
            TailRead::StartedOver { why } => {
                eprintln!(
                    "rig: {} was {why}: reading it again from its header (rows published so \
                     far: {})",
                    path.display(),
                    self.rows_published
                );
                self.follower.start_over();
                Ok((Vec::new(), None))
            }
            TailRead::Appended { bytes, modified } => Ok((self.feed(&bytes)?, Some(modified))),
        }
    }

    /// The rows of `bytes`; the header and the malformed lines are told on stderr.
    fn feed(&mut self, bytes: &[u8]) -> Result<Vec<Row>, FollowError> {
        let path = &self.options.path;
        let mut batch = Vec::new();
        for event in self
            .follower
            .feed(bytes)
            .map_err(|e| FollowError::columns(path, e))?
        {
            match event {
                LineEvent::Header => eprintln!(
                    "rig: following {} (columns {})",
                    path.display(),
                    self.follower
                        .layout()
                        .map_or(String::new(), |l| l.describe())
                ),
                LineEvent::Row(row) => batch.push(row),
                LineEvent::Malformed { line_no, text, why } => {
                    if let Some(line) = self.report.malformed(line_no, &text, &why, Instant::now())
                    {
                        eprintln!("{line}");
                    }
                }
            }
        }
        Ok(batch)
    }

    /// Publishes `batch` on `rig/state`, its host times from the machine's clock anchored on
    /// its last row (written at `modified`).
    fn publish(
        &mut self,
        batch: &[Row],
        modified: Option<SystemTime>,
        publisher: &ValuePublisher<RigState>,
    ) -> Result<(), FollowError> {
        if let (Some(last), Some(modified)) = (batch.last(), modified) {
            let age_ns = SystemTime::now()
                .duration_since(modified)
                .map_or(0, |d| d.as_nanos() as u64);
            self.clock.anchor(last.t_s, wire::monotonic_ns(), age_ns);
        }
        for row in batch {
            let host_ns = self.clock.host_ns(row.t_s).expect("anchored above");
            publisher.publish(rig_state(
                row,
                self.rows_published,
                host_ns,
                self.options.offset_s,
                self.options.sections_mm2,
            ))?;
            self.rows_published += 1;
        }
        Ok(())
    }

    /// The last malformed-line report, and a last line left without its newline.
    fn finish(&mut self) {
        if let Some(line) = self.report.finish() {
            eprintln!("{line}");
        }
        let unfinished = self.follower.unfinished_line_bytes();
        if unfinished > 0 {
            eprintln!(
                "rig: {}: a last line of {unfinished} bytes without its newline was not read",
                self.options.path.display()
            );
        }
    }
}
