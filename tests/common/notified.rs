//! Waiting on a subscriber's notifications (the test as a consumer of a service), bounded by
//! the hang guard: no fixed sleep, no assertion on a wall-clock time.

use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use std::time::{Duration, Instant};

/// Calls `pending` (which drains what has come) until it returns `None`, waiting between two
/// calls for a notification of `listener` (or 100 ms at most). `Some(what)` says what is still
/// awaited; after the hang guard the test panics with it.
pub fn wait_notified(
    listener: &Listener<ipc::Service>,
    mut pending: impl FnMut() -> Option<String>,
) {
    let waitset = WaitSetBuilder::new().create::<ipc::Service>().unwrap();
    let _guard = waitset.attach_notification(listener).unwrap();
    let give_up = Instant::now() + super::HANG_GUARD;
    while let Some(what) = pending() {
        assert!(Instant::now() < give_up, "hang guard: {what}");
        waitset
            .wait_and_process_once_with_timeout(
                |_| CallbackProgression::Continue,
                Duration::from_millis(100),
            )
            .unwrap();
    }
}
