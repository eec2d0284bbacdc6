//! The process shell of the CSV follower (`dicstream rig --follow-csv FILE`): polls the file,
//! publishes one `rig/state` sample per row on the rig's service, in the simulated rig's
//! layout ([`super::clock::rig_state`]), and reports on stderr the waits, malformed lines,
//! truncations and rotations. The only IPC of the follower.

use super::clock::{rig_state, MachineClock};
use super::{CsvColumns, CsvError, FileTail, Follower, LineEvent, Row, TailRead};
use crate::process::StatePort;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

/// Malformed lines reported one by one; later ones are counted only.
const MALFORMED_REPORTED: u64 = 20;

#[derive(Clone, Debug)]
pub struct FollowOptions {
    pub instance: String,
    pub path: PathBuf,
    pub columns: CsvColumns,
    /// Seconds added to the machine's time (camera time − machine time).
    pub offset_s: f64,
    /// Initial sections of the specimen normal to X and Y, mm² (0: unknown).
    pub sections_mm2: [f64; 2],
    /// How often the file is looked at.
    pub poll: Duration,
    /// End (successfully) after this long without a new row, once rows have come.
    pub idle_timeout: Option<Duration>,
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
    pub rows_published: u64,
    pub malformed: u64,
    pub restarts: u64,
    pub stopped_by_signal: bool,
}

/// Follows until a termination signal or the idle timeout.
pub fn run(options: FollowOptions) -> Result<FollowSummary, FollowError> {
    let path = options.path.clone();
    let mut follower =
        Follower::new(options.columns.clone()).map_err(|e| FollowError::columns(&path, e))?;
    let mut tail = FileTail::new(&path);
    let StatePort {
        instance,
        _owner,
        node: _node,
        publisher,
    } = StatePort::open(&options.instance)?;
    let mut clock = MachineClock::new(options.offset_s);
    let mut summary = FollowSummary::default();
    let mut waiting_reported = false;
    let mut last_row_at = Instant::now();
    let mut ready = false;
    loop {
        let read = tail.poll().map_err(|reason| FollowError::Read {
            path: path.display().to_string(),
            reason,
        })?;
        let mut batch = Vec::new();
        let mut modified = None;
        match read {
            TailRead::Missing => {
                if !waiting_reported {
                    eprintln!("rig: waiting for {} to exist", path.display());
                    waiting_reported = true;
                }
            }
            TailRead::StartedOver { why } => {
                eprintln!(
                    "rig: {} was {why}: reading it again from its header (rows published so \
                     far: {})",
                    path.display(),
                    summary.rows_published
                );
                follower.start_over();
                summary.restarts = follower.counters.restarts;
            }
            TailRead::Appended { bytes, modified: m } => {
                modified = Some(m);
                feed(&mut follower, &bytes, &path, &mut summary, &mut batch)?;
            }
        }
        if !ready {
            // Ready once the header, if the file has one already, has been checked.
            eprintln!("rig: ready (instance {})", instance.name());
            ready = true;
        }
        if let (Some(last), Some(modified)) = (batch.last(), modified) {
            let age_ns = SystemTime::now()
                .duration_since(modified)
                .map_or(0, |d| d.as_nanos() as u64);
            clock.anchor(last.t_s, wire::monotonic_ns(), age_ns);
        }
        publish(&publisher, &batch, &clock, &options, &mut summary)?;
        if !batch.is_empty() {
            last_row_at = Instant::now();
        }
        if wire::signals::requested().is_some() {
            summary.stopped_by_signal = true;
            break;
        }
        if options
            .idle_timeout
            .is_some_and(|t| summary.rows_published > 0 && last_row_at.elapsed() > t)
        {
            break;
        }
        std::thread::sleep(options.poll);
    }
    summary.malformed = follower.counters.malformed;
    Ok(summary)
}

/// The events of newly appended bytes: rows into `batch`, the header and the malformed lines
/// reported (the first [`MALFORMED_REPORTED`], then counted only).
fn feed(
    follower: &mut Follower,
    bytes: &[u8],
    path: &Path,
    summary: &mut FollowSummary,
    batch: &mut Vec<Row>,
) -> Result<(), FollowError> {
    for event in follower
        .feed(bytes)
        .map_err(|e| FollowError::columns(path, e))?
    {
        match event {
            LineEvent::Header => eprintln!(
                "rig: following {} (columns {})",
                path.display(),
                follower.layout().map_or(String::new(), |l| l.describe())
            ),
            LineEvent::Row(row) => batch.push(row),
            LineEvent::Malformed { line_no, text, why } => {
                summary.malformed = follower.counters.malformed;
                if summary.malformed <= MALFORMED_REPORTED {
                    eprintln!(
                        "rig: {} line {line_no} skipped: {why}: {text:?}{}",
                        path.display(),
                        if summary.malformed == MALFORMED_REPORTED {
                            " (further malformed lines are counted only)"
                        } else {
                            ""
                        }
                    );
                }
            }
        }
    }
    Ok(())
}

/// One `rig/state` sample per row, on the host clock.
fn publish(
    publisher: &wire::pubsub::ValuePublisher<wire::rig::RigState>,
    batch: &[Row],
    clock: &MachineClock,
    options: &FollowOptions,
    summary: &mut FollowSummary,
) -> Result<(), FollowError> {
    for row in batch {
        let host_ns = clock.host_ns(row.t_s).expect("anchored above");
        publisher.publish(rig_state(
            row,
            summary.rows_published,
            host_ns,
            options.offset_s,
            options.sections_mm2,
        ))?;
        summary.rows_published += 1;
    }
    Ok(())
}
