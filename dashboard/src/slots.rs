//! A bounded count of things in use (event streams, connections): a slot is taken while fewer
//! than a maximum are, and given back when dropped.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

#[derive(Default)]
pub struct Slots(AtomicUsize);

/// One slot in use; given back when dropped.
pub struct Slot(Arc<Slots>);

impl Drop for Slot {
    fn drop(&mut self) {
        self.0 .0.fetch_sub(1, Ordering::SeqCst);
    }
}

impl Slots {
    /// A slot, if fewer than `max` are taken.
    pub fn take(self: &Arc<Self>, max: usize) -> Option<Slot> {
        let taken = self
            .0
            .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
                (n < max).then_some(n + 1)
            })
            .is_ok();
        taken.then(|| Slot(self.clone()))
    }

    pub fn taken(&self) -> usize {
        self.0.load(Ordering::SeqCst)
    }
}
