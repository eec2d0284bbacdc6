//! `dicstream producer --watch DIR`: the images another program writes into a folder, published
//! on `frames` as they become complete. The file name and modification time of each frame
//! (the frame header has no field for them) go beside it: one line per frame on stderr and,
//! with `--log FILE`, one CSV row per frame (`frame_id,file,modified_unix_ns,size_bytes,
//! renamed`).

use std::path::{Path, PathBuf};
use std::time::Duration;

use super::log_rows::LogRows;
use producer::stream::{stream_watched, StreamEvent, StreamReport, StreamSettings};
use producer::{WatchNote, WatchSettings, Watcher, DEFAULT_POLL_MS};

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
    let idle_timeout = idle_timeout(args.idle_timeout_s)?;
    let mut log = LogRows::create(args.log, LOG_HEADER)?;
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
    let report = stream_watched(&mut watcher, instance, settings, on_event, |note| {
        print_note(note, &mut log)
    })?;
    log.finish()?;
    Ok((report, summary_line(&args, &watcher)))
}

/// `--idle-timeout-s`, checked.
fn idle_timeout(seconds: Option<f64>) -> anyhow::Result<Option<Duration>> {
    seconds
        .map(|s| {
            anyhow::ensure!(
                s.is_finite() && s > 0.0,
                "--idle-timeout-s {s}: expected a duration above 0 s"
            );
            Ok(Duration::from_secs_f64(s))
        })
        .transpose()
}

/// One note of the watcher on stderr, and a published frame's row in the `--log` file.
fn print_note(note: &WatchNote, log: &mut LogRows) {
    match note {
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
            log.append(|| {
                format!(
                    "{frame_id},{},{},{},{}\n",
                    csv_field(&file.name),
                    file.modified_unix_ns(),
                    file.size_bytes,
                    file.renamed
                )
            });
        }
    }
}

/// The final line's source part: what the watcher published, skipped and retried.
fn summary_line(args: &WatchArgs, watcher: &Watcher) -> String {
    let counts = watcher.counts();
    format!(
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
    )
}

/// A CSV field, quoted when it holds a comma, a quote or a line break.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}
