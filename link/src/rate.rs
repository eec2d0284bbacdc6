//! The rate limit of a carried service (frames: `frames_max_hz`): samples are admitted on a
//! grid of one period, the first always. A sample up to a sixteenth of a period early for its
//! slot is admitted (a 30 Hz camera's third frame lands a nanosecond before 100 ms), and the
//! grid moves on by a whole period, so no run of samples exceeds the rate; after a pause longer
//! than a period the grid restarts from the next sample.

/// Admits samples at most `max_hz` times a second, by their time (ns).
#[derive(Debug, Clone)]
pub struct RateLimit {
    period_ns: u64,
    next_due_ns: Option<u64>,
}

impl RateLimit {
    /// `max_hz` finite and positive (the configuration's check).
    pub fn new(max_hz: f64) -> RateLimit {
        assert!(max_hz.is_finite() && max_hz > 0.0, "rate {max_hz} Hz");
        RateLimit {
            period_ns: ((1e9 / max_hz).round() as u64).max(1),
            next_due_ns: None,
        }
    }

    /// Whether a sample at `now_ns` goes.
    pub fn admit(&mut self, now_ns: u64) -> bool {
        let slack_ns = self.period_ns / 16;
        let next_due_ns = match self.next_due_ns {
            None => now_ns + self.period_ns,
            Some(due) if now_ns + slack_ns < due => return false,
            Some(due) if now_ns > due + self.period_ns => now_ns + self.period_ns,
            Some(due) => due + self.period_ns,
        };
        self.next_due_ns = Some(next_due_ns);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thirty_hertz_through_ten_hertz_is_every_third() {
        let mut limit = RateLimit::new(10.0);
        let period_ns = 1_000_000_000 / 30;
        let admitted: Vec<bool> = (0..9).map(|i| limit.admit(i * period_ns + 1)).collect();
        assert_eq!(
            admitted,
            [true, false, false, true, false, false, true, false, false]
        );
    }

    #[test]
    fn never_more_than_the_rate_over_a_second() {
        let mut limit = RateLimit::new(10.0);
        // 950 samples at 1 kHz with up to 0.4 ms of jitter: the slots at 0, 100, ..., 900 ms.
        let sent = (0..950u64)
            .filter(|&i| limit.admit(i * 1_000_000 + (i * 7919 % 400_000)))
            .count();
        assert_eq!(sent, 10);
    }

    #[test]
    fn slower_than_the_limit_passes_everything_and_a_pause_restarts_the_grid() {
        let mut limit = RateLimit::new(10.0);
        assert!((0..5).all(|i| limit.admit(i * 200_000_000)));
        assert!(limit.admit(10_000_000_000));
        assert!(!limit.admit(10_050_000_000));
        assert!(limit.admit(10_100_000_000));
    }
}
