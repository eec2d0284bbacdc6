//! The watched-folder loop of the producer shell: waits for the first complete image (its size
//! sets the frame's), opens the `frames` publisher, then decodes each complete file straight
//! into a loaned slice and sends it; a file that gives no frame sends nothing (the loan goes
//! back). No pacing: a frame goes out as soon as its file is complete.

use std::time::{Duration, Instant};

use super::{Shell, StreamError, StreamEvent, StreamReport, StreamSettings};
use crate::{FrameDims, WatchEnd, WatchNote, Watcher};
use wire::Instance;

/// Streams the images of `watcher`'s folder on `instance` as they become complete, until
/// `max_frames` are sent, the idle timeout passes or a termination signal arrives.
/// `settings.fps` does not apply. `on_note` hears every retry, skip and published file (with
/// its frame id).
pub fn stream_watched(
    watcher: &mut Watcher,
    instance: &Instance,
    settings: &StreamSettings,
    mut on_event: impl FnMut(StreamEvent),
    mut on_note: impl FnMut(&WatchNote),
) -> Result<StreamReport, StreamError> {
    let start = Instant::now();
    // Sleeps between two looks at the folder; a signal is seen within one poll interval.
    let mut sleep = |pause: Duration| {
        if wire::signals::requested().is_some() {
            return false;
        }
        std::thread::sleep(pause);
        wire::signals::requested().is_none()
    };
    let first = watcher.first_shape(&mut sleep)?;
    for note in watcher.take_notes() {
        on_note(&note);
    }
    let shape = match first {
        Ok(shape) => shape,
        Err(end) => {
            return Ok(StreamReport {
                elapsed_s: start.elapsed().as_secs_f64(),
                interrupted: end == WatchEnd::Stopped,
                ..StreamReport::default()
            })
        }
    };
    let dims = FrameDims {
        width: shape.width,
        height: shape.height,
        bit_depth: shape.bit_depth,
    };
    let unpaced = StreamSettings {
        fps: None,
        ..settings.clone()
    };
    let mut shell = Shell::open(instance, dims, &unpaced, &mut on_event)?;
    while !shell.done() {
        let file = match watcher.wait_ready(&mut sleep)? {
            Ok(file) => file,
            Err(end) => {
                shell.report.interrupted = end == WatchEnd::Stopped;
                break;
            }
        };
        let sent = shell.publish(|pixels| watcher.decode(&file, pixels))?;
        for note in watcher.take_notes() {
            on_note(&note);
        }
        if let Some(header) = sent {
            on_event(StreamEvent::Frame(&header));
            on_note(&WatchNote::Published {
                frame_id: header.frame_id,
                file,
            });
        }
    }
    for note in watcher.take_notes() {
        on_note(&note);
    }
    Ok(shell.finish())
}
