//! The camera link's bookkeeping, free of Aravis so it is tested without a camera: what became
//! of each buffer the driver handed back, and the lost/reconnecting state machine with its
//! backoff. Times are passed in (`Instant`), never read here.

use std::time::{Duration, Instant};

/// First wait before reconnecting after the camera is lost; doubles per failed attempt.
pub const FIRST_RETRY: Duration = Duration::from_millis(500);
/// Longest wait between two reconnection attempts.
pub const MAX_RETRY: Duration = Duration::from_secs(8);
/// A free-running or software-triggered camera that sends nothing for this long (and for at
/// least [`SILENT_PERIODS`] frame periods) is taken as lost.
pub const SILENCE: Duration = Duration::from_secs(3);
pub const SILENT_PERIODS: u32 = 10;

/// What the driver said about a buffer (Aravis' `ArvBufferStatus`, reduced).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferStatus {
    Success,
    /// Packets missing (`MissingPackets`, `Timeout`, `SizeMismatch`, `Aborted`, ...): the
    /// image is incomplete.
    Incomplete,
    /// Anything else the driver reports as failed.
    Failed,
}

/// Buffers handed back by the driver, by outcome. Only `published` buffers reach `frames`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BufferCounts {
    /// Complete buffers published as frames.
    pub published: u64,
    /// Buffers with missing packets (skipped).
    pub incomplete: u64,
    /// Buffers the driver reported failed (skipped).
    pub failed: u64,
    /// Complete buffers whose size or format is not the one set (skipped).
    pub wrong_shape: u64,
}

impl BufferCounts {
    /// Counts one buffer; true when it is to be published.
    pub fn count(&mut self, status: BufferStatus, shape_ok: bool) -> bool {
        match (status, shape_ok) {
            (BufferStatus::Success, true) => {
                self.published += 1;
                true
            }
            (BufferStatus::Success, false) => {
                self.wrong_shape += 1;
                false
            }
            (BufferStatus::Incomplete, _) => {
                self.incomplete += 1;
                false
            }
            (BufferStatus::Failed, _) => {
                self.failed += 1;
                false
            }
        }
    }

    /// Buffers skipped, never published.
    pub fn skipped(&self) -> u64 {
        self.incomplete + self.failed + self.wrong_shape
    }
}

/// Whether the camera is there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkState {
    Streaming,
    /// Lost at `since`; `attempts` reconnections failed so far; the next one is due at `next`.
    Lost {
        since: Instant,
        attempts: u32,
        next: Instant,
    },
}

/// The link to the camera: lost, reconnection attempts with exponential backoff, back.
#[derive(Clone, Debug)]
pub struct Link {
    state: LinkState,
    last_buffer: Instant,
    /// Times the camera was lost, and reconnected.
    pub losses: u64,
    pub reconnections: u64,
}

impl Link {
    pub fn new(now: Instant) -> Link {
        Link {
            state: LinkState::Streaming,
            last_buffer: now,
            losses: 0,
            reconnections: 0,
        }
    }

    pub fn state(&self) -> LinkState {
        self.state
    }

    /// A buffer (any status) arrived: the camera is alive.
    pub fn buffer_arrived(&mut self, now: Instant) {
        self.last_buffer = now;
    }

    /// True when a camera that should be sending (free-running or software-triggered at
    /// `period`) has sent nothing for too long. A hardware-triggered camera (`period` None)
    /// may rightly be silent: only the driver's control-lost signal tells it is gone.
    pub fn silent_too_long(&self, now: Instant, period: Option<Duration>) -> bool {
        let Some(period) = period else { return false };
        let limit = SILENCE.max(period * SILENT_PERIODS);
        self.state == LinkState::Streaming && now.duration_since(self.last_buffer) > limit
    }

    /// The camera is gone: the first attempt is due after [`FIRST_RETRY`]. False when it was
    /// already known lost.
    pub fn lost(&mut self, now: Instant) -> bool {
        if self.state != LinkState::Streaming {
            return false;
        }
        self.losses += 1;
        self.state = LinkState::Lost {
            since: now,
            attempts: 0,
            next: now + FIRST_RETRY,
        };
        true
    }

    /// Whether a reconnection attempt is due, or how long until it is.
    pub fn until_attempt(&self, now: Instant) -> Option<Duration> {
        match self.state {
            LinkState::Streaming => None,
            LinkState::Lost { next, .. } => Some(next.saturating_duration_since(now)),
        }
    }

    /// An attempt failed: the next waits twice as long (up to [`MAX_RETRY`]). Returns the
    /// attempts so far and the wait.
    pub fn attempt_failed(&mut self, now: Instant) -> (u32, Duration) {
        let LinkState::Lost {
            since, attempts, ..
        } = self.state
        else {
            return (0, Duration::ZERO);
        };
        let attempts = attempts + 1;
        let wait = FIRST_RETRY
            .saturating_mul(1u32 << attempts.min(16))
            .min(MAX_RETRY);
        self.state = LinkState::Lost {
            since,
            attempts,
            next: now + wait,
        };
        (attempts, wait)
    }

    /// The camera is back: returns how long it was away.
    pub fn reconnected(&mut self, now: Instant) -> Duration {
        let away = match self.state {
            LinkState::Lost { since, .. } => now.duration_since(since),
            LinkState::Streaming => Duration::ZERO,
        };
        if self.state != LinkState::Streaming {
            self.reconnections += 1;
        }
        self.state = LinkState::Streaming;
        self.last_buffer = now;
        away
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_complete_buffers_of_the_right_shape_are_published() {
        let mut counts = BufferCounts::default();
        assert!(counts.count(BufferStatus::Success, true));
        assert!(!counts.count(BufferStatus::Success, false));
        assert!(!counts.count(BufferStatus::Incomplete, true));
        assert!(!counts.count(BufferStatus::Failed, true));
        assert!(!counts.count(BufferStatus::Incomplete, false));
        assert_eq!(
            counts,
            BufferCounts {
                published: 1,
                incomplete: 2,
                failed: 1,
                wrong_shape: 1
            }
        );
        assert_eq!(counts.skipped(), 4);
    }

    #[test]
    fn lost_then_attempts_back_off_doubling_up_to_the_cap_then_back() {
        let t0 = Instant::now();
        let mut link = Link::new(t0);
        assert_eq!(link.until_attempt(t0), None);
        assert!(link.lost(t0));
        assert!(
            !link.lost(t0 + Duration::from_secs(1)),
            "lost once, not twice"
        );
        assert_eq!(link.until_attempt(t0), Some(FIRST_RETRY));
        assert_eq!(link.until_attempt(t0 + FIRST_RETRY), Some(Duration::ZERO));
        let mut now = t0 + FIRST_RETRY;
        let mut waits = Vec::new();
        for _ in 0..6 {
            let (_, wait) = link.attempt_failed(now);
            waits.push(wait.as_millis());
            now += wait;
        }
        assert_eq!(waits, [1000, 2000, 4000, 8000, 8000, 8000]);
        assert!(matches!(link.state(), LinkState::Lost { attempts: 6, .. }));
        let away = link.reconnected(now);
        assert_eq!(away, now - t0);
        assert_eq!(link.state(), LinkState::Streaming);
        assert_eq!((link.losses, link.reconnections), (1, 1));
        // A second loss starts again from the first wait.
        assert!(link.lost(now));
        assert_eq!(link.until_attempt(now), Some(FIRST_RETRY));
    }

    #[test]
    fn silence_means_lost_only_for_a_camera_that_should_be_sending() {
        let t0 = Instant::now();
        let mut link = Link::new(t0);
        let fast = Some(Duration::from_millis(50));
        assert!(!link.silent_too_long(t0 + Duration::from_secs(2), fast));
        assert!(link.silent_too_long(t0 + Duration::from_secs(4), fast));
        // A slow camera (1 frame/s) gets ten periods.
        assert!(!link.silent_too_long(t0 + Duration::from_secs(9), Some(Duration::from_secs(1))));
        // Hardware trigger: silence is normal.
        assert!(!link.silent_too_long(t0 + Duration::from_secs(60), None));
        link.buffer_arrived(t0 + Duration::from_secs(4));
        assert!(!link.silent_too_long(t0 + Duration::from_secs(5), fast));
    }
}
