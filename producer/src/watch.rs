//! A watched folder as a source of frames: images another program (a camera vendor's
//! acquisition software) writes into a folder are handed out once they are complete, in
//! natural order, each file once. Pure: no IPC; the shell (`stream::watched`) decodes each
//! file straight into a loaned shared-memory slice.
//!
//! A file is complete when its size and modification time have not changed for `settle`
//! (observed across polls), or at once when it arrived by a rename from a temporary name seen
//! in the previous poll (same device and inode). Temporary names (dot-files, `.tmp`, `.part`,
//! `.partial`, `.crdownload`, `~`) and files without an image extension are never read.
//! Complete is not trusted blindly: the file is decoded in full, and checked unchanged (size,
//! modification time) after the decode. A file that fails to decode is reported once and
//! decoded again only if it changes (a writer that paused longer than the settle time goes
//! on): decoding the same bytes again would fail the same way. Unchanged for
//! `failure_wait_settles` settle times after the failure, it is skipped. So a frame is never
//! published from a half-written file, and a hopeless file costs one decode.
//!
//! The folder is polled (every `poll_interval`, sleeping in between): portable, no
//! dependency, and it also sees files written over a network share (NFS, SMB), which inotify
//! does not.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

use crate::error::ProducerError;
use crate::image_io::{decode_into, read_shape, ImageShape};
use crate::natural_sort::natural_cmp;
use crate::replay::IMAGE_EXTENSIONS;
use crate::source::{check_buffer, FrameInfo};

/// Default settle time: a file whose size and modification time stay unchanged this long is
/// taken as complete, ms.
pub const DEFAULT_SETTLE_MS: u64 = 250;
/// Default interval between two looks at the folder, ms.
pub const DEFAULT_POLL_MS: u64 = 50;
/// Default wait for a change of a file that failed to decode before it is skipped, in settle
/// times.
pub const DEFAULT_FAILURE_WAIT_SETTLES: u32 = 4;
/// Name endings of files being written under a temporary name (compared case-insensitively);
/// dot-files are temporary too.
pub const TEMPORARY_SUFFIXES: [&str; 5] = [".tmp", ".part", ".partial", ".crdownload", "~"];

/// How to watch a folder.
#[derive(Clone, Debug, PartialEq)]
pub struct WatchSettings {
    /// The folder.
    pub dir: PathBuf,
    /// Also hand out the images already in the folder at start (otherwise only new ones).
    pub from_start: bool,
    /// Size and modification time unchanged this long: the file is complete.
    pub settle: Duration,
    /// Interval between two looks at the folder.
    pub poll_interval: Duration,
    /// End after this long without a new image (`None`: watch until stopped).
    pub idle_timeout: Option<Duration>,
    /// A file that failed to decode is skipped when it stays unchanged this many settle times
    /// after the failure (it is decoded again only if it changes).
    pub failure_wait_settles: u32,
}

impl WatchSettings {
    /// The defaults for `dir`: new files only, 250 ms settle time, 50 ms polling, no idle
    /// timeout, a failed file skipped after 4 settle times unchanged.
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        WatchSettings {
            dir: dir.into(),
            from_start: false,
            settle: Duration::from_millis(DEFAULT_SETTLE_MS),
            poll_interval: Duration::from_millis(DEFAULT_POLL_MS),
            idle_timeout: None,
            failure_wait_settles: DEFAULT_FAILURE_WAIT_SETTLES,
        }
    }
}

/// A complete-looking file, as it was when it was found complete.
#[derive(Clone, Debug, PartialEq)]
pub struct WatchedFile {
    pub path: PathBuf,
    /// Its name in the folder.
    pub name: String,
    pub size_bytes: u64,
    /// Its modification time.
    pub modified: SystemTime,
    /// True when it arrived by a rename from a temporary name.
    pub renamed: bool,
}

impl WatchedFile {
    /// Modification time, ns since 1970-01-01 UTC (negative before).
    pub fn modified_unix_ns(&self) -> i128 {
        match self.modified.duration_since(SystemTime::UNIX_EPOCH) {
            Ok(after) => after.as_nanos() as i128,
            Err(before) => -(before.duration().as_nanos() as i128),
        }
    }
}

/// What the watcher has to say, for the command's messages.
#[derive(Clone, Debug, PartialEq)]
pub enum WatchNote {
    /// A complete-looking file could not be decoded: it is decoded again if it changes within
    /// `wait`, else skipped.
    Unreadable {
        path: PathBuf,
        reason: String,
        wait: Duration,
    },
    /// A file is not published, ever (undecodable and unchanged after the failure, another
    /// size or depth than the first frame, out of natural order).
    Skipped { path: PathBuf, reason: String },
    /// A file was published as frame `frame_id` (noted by the shell, which stamps the id).
    Published { frame_id: u64, file: WatchedFile },
}

/// Why waiting for the next file ended without one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WatchEnd {
    /// No new image for the idle timeout.
    Idle,
    /// The caller's sleep said stop (a termination signal).
    Stopped,
}

/// Counts of a watch, for the final line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WatchCounts {
    pub published: u64,
    pub skipped: u64,
    /// Decodes of a file that had failed to decode and changed since.
    pub retries: u64,
    /// True when the watch ended for the idle timeout.
    pub ended_idle: bool,
}

/// A file seen, not yet published or skipped.
#[derive(Clone, Debug)]
struct Pending {
    path: PathBuf,
    size_bytes: u64,
    modified: SystemTime,
    file_id: Option<(u64, u64)>,
    /// When size, modification time or identity last changed (or the file appeared).
    changed_at: Instant,
    renamed: bool,
    /// The decode failure of the file as it is now (cleared when it changes).
    failure: Option<Failure>,
    /// It failed to decode at least once (a later decode is a retry).
    failed_before: bool,
}

impl Pending {
    /// Takes in a change of size, modification time or identity, seen at `now`: the file
    /// settles again and its failure, if any, is forgotten.
    fn changed(&mut self, meta: &std::fs::Metadata, now: Instant) {
        self.size_bytes = meta.len();
        self.modified = meta.modified().unwrap_or(SystemTime::UNIX_EPOCH);
        self.file_id = file_id(meta);
        self.changed_at = now;
        self.renamed = false;
        self.failure = None;
    }
}

/// A decode failure of a file that has not changed since.
#[derive(Clone, Debug)]
struct Failure {
    reason: String,
    /// Skipped if still unchanged then.
    skip_at: Instant,
}

/// Whether one decode gave a frame.
enum Attempt {
    Good(ImageShape),
    NotYet,
}

/// The watcher: finds complete files and decodes them, keeping what it has handed out.
#[derive(Debug)]
pub struct Watcher {
    settings: WatchSettings,
    pending: HashMap<String, Pending>,
    /// Names published, skipped, or present at start without `from_start`: never read again.
    done: HashSet<String>,
    /// The last name published: a later one must sort after it.
    last_published: Option<String>,
    /// Device and inode of temporary files in the last poll.
    temporary_ids: HashSet<(u64, u64)>,
    /// Frame size and depth, from the first image that decoded.
    shape: Option<ImageShape>,
    first: Option<PathBuf>,
    last_activity: Instant,
    counts: WatchCounts,
    notes: Vec<WatchNote>,
    scratch: Vec<u8>,
}

impl Watcher {
    /// Starts watching: the folder must exist and be readable. Without `from_start`, every
    /// file present now (complete or not) is ignored for good.
    pub fn open(settings: WatchSettings) -> Result<Watcher, ProducerError> {
        let refuse = |reason: String| ProducerError::WatchFolder {
            path: settings.dir.clone(),
            reason,
        };
        let meta = std::fs::metadata(&settings.dir).map_err(|e| refuse(e.to_string()))?;
        if !meta.is_dir() {
            return Err(refuse("not a folder".to_owned()));
        }
        if settings.poll_interval.is_zero() {
            return Err(refuse("the poll interval must be above 0".to_owned()));
        }
        let mut watcher = Watcher {
            settings,
            pending: HashMap::new(),
            done: HashSet::new(),
            last_published: None,
            temporary_ids: HashSet::new(),
            shape: None,
            first: None,
            last_activity: Instant::now(),
            counts: WatchCounts::default(),
            notes: Vec::new(),
            scratch: Vec::new(),
        };
        watcher.scan()?;
        if !watcher.settings.from_start {
            let present: Vec<String> = watcher.pending.drain().map(|(name, _)| name).collect();
            watcher.done.extend(present);
        }
        Ok(watcher)
    }

    pub fn settings(&self) -> &WatchSettings {
        &self.settings
    }

    /// Frame size and depth, once the first image decoded.
    pub fn shape(&self) -> Option<ImageShape> {
        self.shape
    }

    /// The file that set the frame size.
    pub fn first(&self) -> Option<&Path> {
        self.first.as_deref()
    }

    pub fn counts(&self) -> WatchCounts {
        self.counts
    }

    /// The notes since the last call.
    pub fn take_notes(&mut self) -> Vec<WatchNote> {
        std::mem::take(&mut self.notes)
    }

    /// Waits for the first image that decodes in full and takes its size and depth as the
    /// frame's; the file stays due, so it is the first one published. `sleep(pause)` sleeps
    /// between polls and returns false to stop.
    pub fn first_shape(
        &mut self,
        sleep: &mut dyn FnMut(Duration) -> bool,
    ) -> Result<Result<ImageShape, WatchEnd>, ProducerError> {
        loop {
            let file = match self.wait_ready(sleep)? {
                Ok(file) => file,
                Err(end) => return Ok(Err(end)),
            };
            let shape = match read_shape(&file.path) {
                Ok(shape) => shape,
                Err(e) => {
                    self.failed(&file, &e);
                    continue;
                }
            };
            let mut pixels = vec![0u16; shape.len_px()];
            if let Attempt::Good(shape) = self.attempt(&file, &mut pixels, None) {
                self.shape = Some(shape);
                self.first = Some(file.path);
                return Ok(Ok(shape));
            }
        }
    }

    /// Waits (polling, sleeping in between) for the next complete file in natural order.
    /// A file that sorts before one already published is skipped (noted). Ends on the idle
    /// timeout (nothing pending and no change for that long) or when `sleep` says stop.
    pub fn wait_ready(
        &mut self,
        sleep: &mut dyn FnMut(Duration) -> bool,
    ) -> Result<Result<WatchedFile, WatchEnd>, ProducerError> {
        loop {
            self.scan()?;
            let now = Instant::now();
            let mut names: Vec<String> = self.pending.keys().cloned().collect();
            names.sort_by(|a, b| natural_cmp(a, b));
            for name in names {
                if let Some(last) = &self.last_published {
                    if natural_cmp(&name, last).is_le() {
                        let reason = format!(
                            "arrived after {last} was published; frames go out in natural order"
                        );
                        let path = self.pending[&name].path.clone();
                        self.skip(&name, path, reason);
                        continue;
                    }
                }
                let p = &self.pending[&name];
                if let Some(failure) = &p.failure {
                    if now < failure.skip_at {
                        // Waiting for a change; later files wait, so the order holds.
                        break;
                    }
                    let wait = self.settings.settle * self.settings.failure_wait_settles;
                    let reason = format!(
                        "{} (unchanged for {} ms after the failure)",
                        failure.reason,
                        wait.as_millis()
                    );
                    let path = p.path.clone();
                    self.skip(&name, path, reason);
                    continue;
                }
                let due = p.renamed || now.duration_since(p.changed_at) >= self.settings.settle;
                if !due {
                    // Head of the line: later files wait, so the order holds.
                    break;
                }
                return Ok(Ok(WatchedFile {
                    path: p.path.clone(),
                    name,
                    size_bytes: p.size_bytes,
                    modified: p.modified,
                    renamed: p.renamed,
                }));
            }
            if self.pending.is_empty()
                && self
                    .settings
                    .idle_timeout
                    .is_some_and(|idle| now.duration_since(self.last_activity) >= idle)
            {
                self.counts.ended_idle = true;
                return Ok(Err(WatchEnd::Idle));
            }
            if !sleep(self.settings.poll_interval) {
                return Ok(Err(WatchEnd::Stopped));
            }
        }
    }

    /// Decodes `file` (from [`Watcher::wait_ready`]) into `out`, the frame buffer. `Ok(None)`
    /// when it gave no frame (to be retried, or skipped: see the notes); the buffer then holds
    /// nothing to publish.
    pub fn decode(
        &mut self,
        file: &WatchedFile,
        out: &mut [u16],
    ) -> Result<Option<FrameInfo>, ProducerError> {
        let shape = self
            .shape
            .expect("Watcher::first_shape comes before Watcher::decode");
        check_buffer(
            crate::FrameDims {
                width: shape.width,
                height: shape.height,
                bit_depth: shape.bit_depth,
            },
            out,
        )?;
        if let Attempt::NotYet = self.attempt(file, out, Some(shape)) {
            return Ok(None);
        }
        self.pending.remove(&file.name);
        self.done.insert(file.name.clone());
        self.last_published = Some(file.name.clone());
        self.last_activity = Instant::now();
        let index = self.counts.published;
        self.counts.published += 1;
        Ok(Some(FrameInfo {
            index,
            truth: None,
            rig_sample_id: None,
            sequence_id: 0,
        }))
    }

    /// One decode of `file` into `out`, then a check that the file did not change meanwhile
    /// and has the frame's shape (`expected`, once known).
    fn attempt(
        &mut self,
        file: &WatchedFile,
        out: &mut [u16],
        expected: Option<ImageShape>,
    ) -> Attempt {
        if self
            .pending
            .get(&file.name)
            .is_some_and(|p| p.failed_before)
        {
            self.counts.retries += 1;
        }
        let found = match decode_into(&file.path, &mut self.scratch, out) {
            Ok(shape) => shape,
            // Another pixel count than the frame's: a shape mismatch (checked below).
            Err(ProducerError::ImageSize {
                found_width,
                found_height,
                found_bit_depth,
                ..
            }) if expected.is_some() => ImageShape {
                width: found_width,
                height: found_height,
                bit_depth: found_bit_depth,
            },
            Err(ProducerError::Io { reason, .. })
                if reason.kind() == std::io::ErrorKind::NotFound =>
            {
                // Removed or renamed away before it could be read: not ours any more.
                self.pending.remove(&file.name);
                return Attempt::NotYet;
            }
            Err(e @ (ProducerError::ImageTooLarge { .. } | ProducerError::PixelType { .. })) => {
                self.skip(&file.name, file.path.clone(), e.to_string());
                return Attempt::NotYet;
            }
            Err(e) => {
                self.failed(file, &e);
                return Attempt::NotYet;
            }
        };
        if self.changed_since(file) {
            return Attempt::NotYet;
        }
        if let Some(expected) = expected {
            if found != expected {
                let first = self.first.clone().unwrap_or_default();
                let reason = ProducerError::FrameMismatch {
                    path: file.path.clone(),
                    first,
                    found_width: found.width,
                    found_height: found.height,
                    found_bit_depth: found.bit_depth,
                    expected_width: expected.width,
                    expected_height: expected.height,
                    expected_bit_depth: expected.bit_depth,
                }
                .to_string();
                self.skip(&file.name, file.path.clone(), reason);
                return Attempt::NotYet;
            }
        }
        Attempt::Good(found)
    }

    /// True (and the file waits to settle again) when its size, modification time or
    /// identity differ from what they were when it was found complete.
    fn changed_since(&mut self, file: &WatchedFile) -> bool {
        let Ok(meta) = std::fs::metadata(&file.path) else {
            self.pending.remove(&file.name);
            return true;
        };
        let modified = meta.modified().unwrap_or(SystemTime::UNIX_EPOCH);
        if meta.len() == file.size_bytes && modified == file.modified {
            return false;
        }
        if let Some(p) = self.pending.get_mut(&file.name) {
            p.changed(&meta, Instant::now());
        }
        self.last_activity = Instant::now();
        true
    }

    /// A decode failure of a settled file: reported once; the file waits for a change (then
    /// it settles and is decoded again) and is skipped if none comes in time. The same bytes
    /// are never decoded twice.
    fn failed(&mut self, file: &WatchedFile, error: &ProducerError) {
        let wait = self.settings.settle * self.settings.failure_wait_settles;
        let Some(p) = self.pending.get_mut(&file.name) else {
            return;
        };
        let reason = error.to_string();
        p.failure = Some(Failure {
            reason: reason.clone(),
            skip_at: Instant::now() + wait,
        });
        p.failed_before = true;
        self.notes.push(WatchNote::Unreadable {
            path: file.path.clone(),
            reason,
            wait,
        });
    }

    fn skip(&mut self, name: &str, path: PathBuf, reason: String) {
        self.pending.remove(name);
        self.done.insert(name.to_owned());
        self.counts.skipped += 1;
        self.last_activity = Instant::now();
        self.notes.push(WatchNote::Skipped { path, reason });
    }

    /// One look at the folder: new image files become pending, changed ones start settling
    /// again, vanished ones are forgotten, temporary files are remembered by identity.
    fn scan(&mut self) -> Result<(), ProducerError> {
        let dir = &self.settings.dir;
        let entries = std::fs::read_dir(dir).map_err(|e| ProducerError::WatchFolder {
            path: dir.clone(),
            reason: e.to_string(),
        })?;
        let now = Instant::now();
        let mut temporary_ids = HashSet::new();
        let mut present = HashSet::new();
        for entry in entries.flatten() {
            let Ok(name) = entry.file_name().into_string() else {
                continue;
            };
            // Handed out or ignored already: not even looked at (a folder keeps every image of
            // a test, and is listed every poll).
            if self.done.contains(&name) {
                continue;
            }
            let path = entry.path();
            // Follows symbolic links; a file removed meanwhile is skipped.
            let Ok(meta) = std::fs::metadata(&path) else {
                continue;
            };
            if !meta.is_file() {
                continue;
            }
            let id = file_id(&meta);
            if is_temporary_name(&name) {
                temporary_ids.extend(id);
                continue;
            }
            if !has_image_extension(&name) {
                continue;
            }
            let modified = meta.modified().unwrap_or(SystemTime::UNIX_EPOCH);
            present.insert(name.clone());
            match self.pending.get_mut(&name) {
                None => {
                    let renamed = id.is_some_and(|id| self.temporary_ids.contains(&id));
                    self.pending.insert(
                        name,
                        Pending {
                            path,
                            size_bytes: meta.len(),
                            modified,
                            file_id: id,
                            changed_at: now,
                            renamed,
                            failure: None,
                            failed_before: false,
                        },
                    );
                    self.last_activity = now;
                }
                Some(p) => {
                    if p.size_bytes != meta.len() || p.modified != modified || p.file_id != id {
                        p.changed(&meta, now);
                        self.last_activity = now;
                    }
                }
            }
        }
        self.pending.retain(|name, _| present.contains(name));
        self.temporary_ids = temporary_ids;
        Ok(())
    }
}

/// A dot-file, or a name ending in one of [`TEMPORARY_SUFFIXES`].
pub fn is_temporary_name(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    name.starts_with('.') || TEMPORARY_SUFFIXES.iter().any(|s| lower.ends_with(s))
}

fn has_image_extension(name: &str) -> bool {
    Path::new(name)
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| IMAGE_EXTENSIONS.iter().any(|k| e.eq_ignore_ascii_case(k)))
}

/// Device and inode: a renamed file keeps them.
#[cfg(unix)]
fn file_id(meta: &std::fs::Metadata) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    Some((meta.dev(), meta.ino()))
}

#[cfg(not(unix))]
fn file_id(_meta: &std::fs::Metadata) -> Option<(u64, u64)> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporary_names() {
        for name in [
            ".img_1.tif",
            "img_1.tif.tmp",
            "img_1.TIF.part",
            "img_1.tif~",
            "a.crdownload",
        ] {
            assert!(is_temporary_name(name), "{name}");
        }
        for name in ["img_1.tif", "img.png", "part.bmp"] {
            assert!(!is_temporary_name(name), "{name}");
        }
    }

    #[test]
    fn a_file_that_fails_to_decode_is_reported_once_and_skipped_unchanged_without_a_retry() {
        let dir = std::env::temp_dir().join(format!("watch_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // Before a good image: garbage, and a 200-byte TIFF declaring 16384² px at 16 bit.
        std::fs::write(dir.join("img_1.tif"), b"not an image at all".repeat(10)).unwrap();
        let huge = crate::image_io::tests::tiff_declaring(16_384, 200);
        std::fs::write(dir.join("img_2.tif"), huge).unwrap();
        image::save_buffer(
            dir.join("img_3.png"),
            &[7u8; 16 * 12],
            16,
            12,
            image::ExtendedColorType::L8,
        )
        .unwrap();
        let mut watcher = Watcher::open(WatchSettings {
            from_start: true,
            settle: Duration::from_millis(20),
            poll_interval: Duration::from_millis(5),
            ..WatchSettings::new(&dir)
        })
        .unwrap();
        let mut sleep = |pause| {
            std::thread::sleep(pause);
            true
        };
        let shape = watcher.first_shape(&mut sleep).unwrap().unwrap();
        assert_eq!((shape.width, shape.height), (16, 12));
        assert_eq!(watcher.first(), Some(dir.join("img_3.png").as_path()));
        let notes = watcher.take_notes();
        for name in ["img_1.tif", "img_2.tif"] {
            let path = dir.join(name);
            let unreadable = notes
                .iter()
                .filter(|n| matches!(n, WatchNote::Unreadable { path: p, .. } if *p == path))
                .count();
            assert_eq!(
                unreadable, 1,
                "{name} reported once, decoded once\n{notes:?}"
            );
            assert!(
                notes.iter().any(|n| matches!(
                    n,
                    WatchNote::Skipped { path: p, reason } if *p == path
                        && reason.contains("unchanged for 80 ms after the failure")
                )),
                "{name} skipped\n{notes:?}"
            );
        }
        assert!(
            notes.iter().any(|n| matches!(
                n,
                WatchNote::Unreadable { reason, .. } if reason.contains("200 bytes")
            )),
            "the TIFF refused from its header\n{notes:?}"
        );
        assert_eq!(watcher.counts().retries, 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_missing_or_non_folder_is_refused_naming_it() {
        let missing = std::env::temp_dir().join(format!("no-such-folder-{}", std::process::id()));
        let error = Watcher::open(WatchSettings::new(&missing)).unwrap_err();
        assert!(
            error.to_string().contains(&missing.display().to_string()),
            "{error}"
        );
    }
}
