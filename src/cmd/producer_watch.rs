//! `dicstream producer --watch DIR`: the images another program writes into a folder, published
//! on `frames` as they become complete. The file name and modification time of each frame
//! (the frame header has no field for them) go beside it: one line per frame on stderr and,
//! with `--log FILE`, one CSV row per frame (`frame_id,file,modified_unix_ns,size_bytes,
//! renamed`).

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::Context;
use producer::stream::{stream_watched, StreamEvent, StreamReport, StreamSettings};
use producer::{WatchNote, WatchSettings, Watcher, DEFAULT_POLL_MS};
use wire::files::RowFile;

/// The header of the `--log` CSV.
const LOG_HEADER: &str = "frame_id,file,modified_unix_ns,size_bytes,renamed";

/// What `--watch` takes from the command line.
pub struct WatchArgs<'a> {
    pub dir: &'a Path,
    pub from_start: bool,
    pub idle_timeout_s: Option<f64>,
    pub settle_ms: u64,
    pub log: Option<&'a PathBuf>,
}

/// Watches, streams, and returns the report with the final line's source part.
pub fn run(
    args: WatchArgs,
    instance: &wire::Instance,
    settings: &StreamSettings,
    on_event: impl FnMut(StreamEvent),
) -> anyhow::Result<(StreamReport, String)> {
    let idle_timeout = match args.idle_timeout_s {
        Some(s) => {
            anyhow::ensure!(
                s.is_finite() && s > 0.0,
                "--idle-timeout-s {s}: expected a duration above 0 s"
            );
            Some(Duration::from_secs_f64(s))
        }
        None => None,
    };
    let mut log = match args.log {
        Some(path) => Some(
            RowFile::create(path, LOG_HEADER)
                .with_context(|| format!("creating the --log file {}", path.display()))?,
        ),
        None => None,
    };
    let mut watcher = Watcher::open(WatchSettings {
        from_start: args.from_start,
        settle: Duration::from_millis(args.settle_ms),
        poll_interval: Duration::from_millis(DEFAULT_POLL_MS),
        idle_timeout,
        ..WatchSettings::new(args.dir)
    })?;
    eprintln!(
        "producer: watching {} for {} images (complete after {} ms unchanged or a rename from a \
         temporary name); the first one sets the frame size",
        args.dir.display(),
        if args.from_start {
            "present and new"
        } else {
            "new"
        },
        args.settle_ms
    );
    let mut log_error = None;
    let report = stream_watched(
        &mut watcher,
        instance,
        settings,
        on_event,
        |note| match note {
            WatchNote::Unreadable { path, reason, wait } => eprintln!(
                "producer: {} not readable: {reason}; decoded again if it changes within {} ms, \
                 else skipped",
                path.display(),
                wait.as_millis()
            ),
            WatchNote::Skipped { path, reason } => {
                eprintln!(
                    "producer: skipped {}, not published: {reason}",
                    path.display()
                )
            }
            WatchNote::Published { frame_id, file } => {
                eprintln!(
                    "producer: frame {frame_id} <- {} (modified {} ns after 1970 UTC, {} bytes{})",
                    file.name,
                    file.modified_unix_ns(),
                    file.size_bytes,
                    if file.renamed { ", renamed" } else { "" }
                );
                if let (Some(rows), None) = (log.as_mut(), log_error.as_ref()) {
                    let row = format!(
                        "{frame_id},{},{},{},{}\n",
                        csv_field(&file.name),
                        file.modified_unix_ns(),
                        file.size_bytes,
                        file.renamed
                    );
                    if let Err(e) = rows.append(&row) {
                        log_error = Some(e);
                    }
                }
            }
        },
    )?;
    if let Some(e) = log_error {
        return Err(anyhow::Error::new(e).context("writing the --log file"));
    }
    let counts = watcher.counts();
    let line = format!(
        "watched {}: {} image(s) published, {} skipped, {} retried decode(s){}",
        args.dir.display(),
        counts.published,
        counts.skipped,
        counts.retries,
        if counts.ended_idle {
            format!(
                "; ended after {} s without a new image",
                args.idle_timeout_s.unwrap_or_default()
            )
        } else {
            String::new()
        }
    );
    Ok((report, line))
}

/// A CSV field, quoted when it holds a comma, a quote or a line break.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}
