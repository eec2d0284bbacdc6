//! Saving the state off the frame path. Encoding and writing a 1024² reference (2 MiB, its
//! checksum, two atomic renames) took a few to tens of milliseconds on the frame thread at every
//! reference update; the live correlator now hands a copy of the reference (a memcpy of its
//! pixels and bases, and of the origin when it changed) to a writer thread, which saves it with
//! [`StateDir`] as before, and goes on with the next frame.
//!
//! What a restart may rely on: the state folder always holds a complete reference of the
//! current origin (each file replaced atomically, the origin written before a reference naming
//! it), the newest one handed over or, while the writer is busy, an earlier one of the same
//! origin; a correlator resumed against an earlier reference measures the same total
//! displacement from it (its bases say where it stood). References handed over while the writer
//! is busy replace each other: only the newest waiting one is written. [`StateWriter::finish`]
//! writes the last one before the process exits; a write that fails is returned by the next
//! [`StateWriter::submit`] (the process stops on it, exit 74, as before).
//!
//! No allocation per save once the buffers have the reference's size: the frame thread copies
//! into the waiting buffers, the writer swaps them with its own.

use super::{Layout, ReferenceIds, StateDir, StateError};
use crate::Correlator;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;

/// A copy of a correlator's reference, what [`StateDir`] writes.
struct Snapshot {
    layout: Option<Layout>,
    ids: ReferenceIds,
    pixels: Vec<u16>,
    base_px: Vec<(f64, f64)>,
    origin: Vec<u16>,
    /// `Correlator::origin_generation` of `origin`, None when it holds none.
    origin_generation: Option<u64>,
}

impl Snapshot {
    fn empty() -> Snapshot {
        Snapshot {
            layout: None,
            ids: ReferenceIds::FROM_FILE,
            pixels: Vec::new(),
            base_px: Vec::new(),
            origin: Vec::new(),
            origin_generation: None,
        }
    }

    /// Copies the correlator's reference (and its origin, when this buffer holds another one).
    fn copy_from(&mut self, correlator: &Correlator, ids: ReferenceIds) {
        self.layout = Some(Layout::of(correlator));
        self.ids = ids;
        let pixels = correlator
            .reference_pixels()
            .expect("a reference is saved once it is set");
        self.pixels.clear();
        self.pixels.extend_from_slice(pixels);
        self.base_px.clear();
        self.base_px.extend(correlator.reference_base_px());
        let generation = correlator.origin_generation();
        match correlator.origin_pixels() {
            Some(origin) if self.origin_generation != Some(generation) => {
                self.origin.clear();
                self.origin.extend_from_slice(origin);
                self.origin_generation = Some(generation);
            }
            Some(_) => {}
            None => self.origin_generation = None,
        }
    }

    fn save(&self, dir: &mut StateDir) -> Result<(), StateError> {
        let layout = self
            .layout
            .as_ref()
            .expect("a snapshot is saved once filled");
        let origin = self
            .origin_generation
            .map(|generation| (self.origin.as_slice(), generation));
        dir.save_parts(
            layout,
            self.ids,
            &self.pixels,
            self.base_px.iter().copied(),
            origin,
        )
    }
}

/// What the frame thread and the writer share.
struct Slot {
    /// The reference waiting to be written (when `full`).
    waiting: Snapshot,
    full: bool,
    /// The writer is writing a reference.
    busy: bool,
    stop: bool,
    saves: u64,
    error: Option<StateError>,
}

struct Shared {
    slot: Mutex<Slot>,
    changed: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Slot> {
        self.slot
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

/// The state folder's writer thread (see the module documentation).
pub struct StateWriter {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    /// Saves made before the writer started (the reference image at start).
    earlier_saves: u64,
}

impl StateWriter {
    /// Starts the writer on the folder.
    pub fn spawn(dir: StateDir) -> StateWriter {
        let earlier_saves = dir.saves;
        let shared = Arc::new(Shared {
            slot: Mutex::new(Slot {
                waiting: Snapshot::empty(),
                full: false,
                busy: false,
                stop: false,
                saves: 0,
                error: None,
            }),
            changed: Condvar::new(),
        });
        let for_thread = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("state-writer".into())
            .spawn(move || write_loop(&for_thread, dir))
            .expect("the state writer thread starts");
        StateWriter {
            shared,
            thread: Some(thread),
            earlier_saves,
        }
    }

    /// Hands the correlator's current reference over to be written (replacing one still
    /// waiting); the error of an earlier write that failed, if any.
    pub fn submit(&mut self, correlator: &Correlator, ids: ReferenceIds) -> Result<(), StateError> {
        let mut slot = self.shared.lock();
        if let Some(error) = slot.error.take() {
            return Err(error);
        }
        slot.waiting.copy_from(correlator, ids);
        slot.full = true;
        drop(slot);
        self.shared.changed.notify_all();
        Ok(())
    }

    /// Waits until every reference handed over is written (tests; the process calls
    /// [`StateWriter::finish`]); the error of a write that failed, if any.
    pub fn flush(&mut self) -> Result<(), StateError> {
        let mut slot = self.shared.lock();
        while slot.full || slot.busy {
            slot = self
                .shared
                .changed
                .wait(slot)
                .unwrap_or_else(|poisoned| poisoned.into_inner());
        }
        slot.error.take().map_or(Ok(()), Err)
    }

    /// Saves made so far, those before the writer started included.
    pub fn saves(&self) -> u64 {
        self.earlier_saves + self.shared.lock().saves
    }

    /// Writes what is waiting, stops the writer; the saves made, or the error of a write that
    /// failed.
    pub fn finish(mut self) -> Result<u64, StateError> {
        self.flush()?;
        let saves = self.saves();
        self.stop();
        Ok(saves)
    }

    fn stop(&mut self) {
        self.shared.lock().stop = true;
        self.shared.changed.notify_all();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl Drop for StateWriter {
    /// Writes what is waiting and stops the writer (a process stopping on an error).
    fn drop(&mut self) {
        self.stop();
    }
}

/// The writer: waits for a reference, takes it (swapping buffers), writes it, until stopped
/// with nothing waiting.
fn write_loop(shared: &Shared, mut dir: StateDir) {
    let mut writing = Snapshot::empty();
    loop {
        let mut slot = shared.lock();
        while !slot.full && !slot.stop {
            slot = shared
                .changed
                .wait(slot)
                .unwrap_or_else(|poisoned| poisoned.into_inner());
        }
        if !slot.full {
            return;
        }
        std::mem::swap(&mut slot.waiting, &mut writing);
        slot.full = false;
        slot.busy = true;
        drop(slot);
        let result = writing.save(&mut dir);
        let mut slot = shared.lock();
        slot.busy = false;
        match result {
            Ok(()) => slot.saves += 1,
            Err(error) => slot.error = Some(error),
        }
        drop(slot);
        shared.changed.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::{CorrelatorSettings, ReferenceMode};

    fn speckle(w: usize, h: usize, shift: f64) -> Vec<u16> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64 + shift, (i / w) as f64);
                (30000.0 + 12000.0 * (0.7 * x).sin() * (0.45 * y + 0.3 * x).cos()) as u16
            })
            .collect()
    }

    fn temp_dir(name: &str) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("dicstream_writer_{name}_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    /// References handed over in a burst: the folder ends with the newest, restorable, its
    /// origin beside it; the saves are counted.
    #[test]
    fn the_newest_reference_handed_over_is_the_one_on_disk() {
        let dir = temp_dir("newest");
        let (w, h) = (96, 80);
        let settings = CorrelatorSettings {
            threads: 1,
            reference: ReferenceMode::Incremental,
            ..CorrelatorSettings::default()
        };
        let mut correlator = Correlator::new(settings.clone(), w, h).unwrap();
        let origin = speckle(w, h, 0.0);
        correlator.set_reference(&origin).unwrap();
        let mut writer = StateWriter::spawn(StateDir::open(&dir).unwrap());
        for k in 1..=5u64 {
            let frame = speckle(w, h, 0.3 * k as f64);
            correlator.correlate(&frame).unwrap();
            let ids = ReferenceIds {
                reference_frame_id: k,
                origin_frame_id: 0,
                sequence_id: 1,
            };
            writer.submit(&correlator, ids).unwrap();
        }
        writer.flush().unwrap();
        let saved = StateDir::open(&dir).unwrap().load().unwrap().unwrap();
        assert_eq!(saved.reference_frame_id, 5);
        assert_eq!(saved.pixels, correlator.reference_pixels().unwrap());
        let bases: Vec<_> = correlator.reference_base_px().collect();
        assert_eq!(saved.base_px, bases);
        assert_eq!(saved.origin_pixels.as_deref(), Some(&origin[..]));
        saved.restore(settings, &dir).unwrap();
        let saves = writer.finish().unwrap();
        // Coalesced while the writer was busy, never none.
        assert!((1..=5).contains(&saves), "{saves}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A write that fails (the folder removed under it) is returned, not lost.
    #[test]
    fn a_failed_write_is_returned() {
        let dir = temp_dir("failed");
        let (w, h) = (96, 80);
        let settings = CorrelatorSettings {
            threads: 1,
            ..CorrelatorSettings::default()
        };
        let mut correlator = Correlator::new(settings, w, h).unwrap();
        correlator.set_reference(&speckle(w, h, 0.0)).unwrap();
        let mut writer = StateWriter::spawn(StateDir::open(&dir).unwrap());
        std::fs::remove_dir_all(&dir).unwrap();
        writer.submit(&correlator, ReferenceIds::FROM_FILE).unwrap();
        let error = writer.flush().unwrap_err();
        assert!(matches!(error, StateError::Write(_)), "{error}");
    }
}
