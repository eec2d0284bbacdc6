//! Polling for a condition that no stderr line announces (an HTTP answer, a page's state).

use crate::HANG_GUARD;
use std::time::{Duration, Instant};

/// Calls `probe` every 200 ms until it gives a value, and returns that value; panics naming
/// `what` after the hang guard.
pub fn until<T>(what: &str, mut probe: impl FnMut() -> Option<T>) -> T {
    let give_up = Instant::now() + HANG_GUARD;
    loop {
        if let Some(v) = probe() {
            return v;
        }
        assert!(Instant::now() < give_up, "no {what} within {HANG_GUARD:?}");
        std::thread::sleep(Duration::from_millis(200));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn returns_the_first_value_given() {
        let mut calls = 0;
        let v = until("a third call", || {
            calls += 1;
            (calls == 3).then_some(calls * 10)
        });
        assert_eq!(v, 30);
    }
}
