//! Where the feeder leaves the latest snapshot and image for the viewers: one version number,
//! a condition variable the viewers' threads sleep on, and the count of connected viewers.
//! Snapshots are shared (`Arc<str>`), never copied per viewer.

use crate::slots::{Slot, Slots};
use serde_json::Value;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

#[derive(Default)]
struct Published {
    version: u64,
    snapshot: Option<Arc<str>>,
    png: Option<Arc<[u8]>>,
    processes: Value,
    user_gauges: Value,
}

#[derive(Default)]
pub struct Hub {
    published: Mutex<Published>,
    changed: Condvar,
    viewers: Arc<Slots>,
    stop: AtomicBool,
}

impl Hub {
    fn lock(&self) -> MutexGuard<'_, Published> {
        // A panicking holder leaves plain data behind: keep serving it.
        self.published.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// A new snapshot (and the image it names, if a new one was encoded).
    pub fn publish(&self, snapshot: String, png: Option<Vec<u8>>) {
        let mut p = self.lock();
        p.version += 1;
        p.snapshot = Some(Arc::from(snapshot));
        if let Some(png) = png {
            p.png = Some(Arc::from(png));
        }
        drop(p);
        self.changed.notify_all();
    }

    /// The latest snapshot newer than `after`, waiting up to `timeout` for one; `None` on
    /// timeout or stop.
    pub fn wait_newer(&self, after: u64, timeout: Duration) -> Option<(u64, Arc<str>)> {
        let p = self.lock();
        let (p, _) = self
            .changed
            .wait_timeout_while(p, timeout, |p| {
                !self.stopped() && (p.version <= after || p.snapshot.is_none())
            })
            .unwrap_or_else(|e| e.into_inner());
        if self.stopped() || p.version <= after {
            return None;
        }
        p.snapshot.clone().map(|s| (p.version, s))
    }

    pub fn latest(&self) -> Option<Arc<str>> {
        self.lock().snapshot.clone()
    }

    pub fn png(&self) -> Option<Arc<[u8]>> {
        self.lock().png.clone()
    }

    /// What `dicstream run` knows of its processes (shown as is; `null` from a monitor).
    pub fn set_processes(&self, processes: Value) {
        self.lock().processes = processes;
    }

    pub fn processes(&self) -> Value {
        self.lock().processes.clone()
    }

    /// The user's named gauges against the test's time, as `dicstream run` reads them from
    /// its configuration's shapes (shown as is; `null` from a monitor without `--config`, whose
    /// feeder reads them itself with one: `crate::user_gauges`).
    pub fn set_user_gauges(&self, gauges: Value) {
        self.lock().user_gauges = gauges;
    }

    pub fn user_gauges(&self) -> Value {
        self.lock().user_gauges.clone()
    }

    /// Counts a viewer (an event stream) in, if fewer than `max` are connected; counted out
    /// when the slot is dropped.
    pub fn join(&self, max: usize) -> Option<Slot> {
        self.viewers.take(max)
    }

    pub fn viewers(&self) -> usize {
        self.viewers.taken()
    }

    pub fn stop(&self) {
        self.stop.store(true, Ordering::SeqCst);
        let _guard = self.lock();
        self.changed.notify_all();
    }

    pub fn stopped(&self) -> bool {
        self.stop.load(Ordering::SeqCst)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viewers_wait_for_a_newer_snapshot_and_are_counted() {
        let hub = Arc::new(Hub::default());
        assert!(hub.wait_newer(0, Duration::from_millis(1)).is_none());
        hub.publish("{\"a\":1}".into(), Some(vec![1, 2]));
        let (v, s) = hub.wait_newer(0, Duration::from_millis(1)).unwrap();
        assert_eq!((v, &*s), (1, "{\"a\":1}"));
        assert!(hub.wait_newer(v, Duration::from_millis(1)).is_none());
        let waiter = {
            let hub = hub.clone();
            std::thread::spawn(move || hub.wait_newer(1, Duration::from_secs(30)))
        };
        hub.publish("{}".into(), None);
        assert_eq!(waiter.join().unwrap().unwrap().0, 2);
        assert_eq!(&*hub.png().unwrap(), &[1, 2]);
        let a = hub.join(2).unwrap();
        let _b = hub.join(2).unwrap();
        assert!(hub.join(2).is_none());
        drop(a);
        assert_eq!(hub.viewers(), 1);
        hub.stop();
        assert!(hub.wait_newer(0, Duration::from_secs(30)).is_none());
    }
}
