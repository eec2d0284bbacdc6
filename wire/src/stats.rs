//! Latency and throughput statistics of the streams, pure (no IPC): one tracker of ids that
//! should be consecutive (a gap is lost samples, going back a publisher restart) and one
//! histogram of durations in ns (HDR, 1 ns to 1 h, 3 significant digits) with its median and
//! percentiles. `dicstream tap`, the correlator's shell and `dicstream run` (`live::latency`)
//! use them.

use hdrhistogram::Histogram;

/// What one id did to a sequence that should be consecutive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IdStep {
    /// The first id seen.
    First,
    /// A later id; `skipped` ids were never seen just before it (0 when consecutive).
    Forward { skipped: u64 },
    /// An id that did not go forward from `from`: the publisher restarted.
    Back { from: u64 },
}

impl IdStep {
    /// Ids lost just before this one.
    pub fn skipped(self) -> u64 {
        match self {
            IdStep::Forward { skipped } => skipped,
            _ => 0,
        }
    }
}

/// Lost ids and restarts of a sequence of ids that should be consecutive.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct IdGaps {
    pub first: Option<u64>,
    pub last: Option<u64>,
    /// Ids skipped in all (gaps while going forward).
    pub lost: u64,
    /// Ids that did not go forward (the publisher restarted, its ids start again).
    pub restarts: u64,
}

impl IdGaps {
    /// Notes `id` and counts its gap or restart.
    pub fn observe(&mut self, id: u64) -> IdStep {
        let step = match self.last {
            Some(last) if id > last => IdStep::Forward {
                skipped: id - last - 1,
            },
            Some(last) => {
                self.restarts += 1;
                IdStep::Back { from: last }
            }
            None => IdStep::First,
        };
        self.lost += step.skipped();
        self.note(id);
        step
    }

    /// Notes `id` as first or last without counting gaps (ids that may skip on purpose).
    pub fn note(&mut self, id: u64) {
        self.first.get_or_insert(id);
        self.last = Some(id);
    }
}

const LOWEST_NS: u64 = 1;
const HIGHEST_NS: u64 = 3_600_000_000_000;

/// Durations (latencies, processing times) in ns: an HDR histogram from 1 ns to 1 h at 3
/// significant digits; a value beyond is clamped into the range.
#[derive(Clone, Debug)]
pub struct Durations {
    histogram: Histogram<u64>,
}

impl Default for Durations {
    fn default() -> Self {
        Durations::new()
    }
}

impl Durations {
    pub fn new() -> Durations {
        Durations {
            histogram: Histogram::new_with_bounds(LOWEST_NS, HIGHEST_NS, 3)
                .expect("valid histogram bounds"),
        }
    }

    pub fn record_ns(&mut self, duration_ns: u64) {
        self.histogram
            .saturating_record(duration_ns.clamp(LOWEST_NS, HIGHEST_NS));
    }

    pub fn count(&self) -> u64 {
        self.histogram.len()
    }

    pub fn is_empty(&self) -> bool {
        self.histogram.is_empty()
    }

    /// The value at `quantile` (0..1), ns; 0 when empty.
    pub fn quantile_ns(&self, quantile: f64) -> u64 {
        self.histogram.value_at_quantile(quantile)
    }

    /// The median, ns; 0 when empty.
    pub fn median_ns(&self) -> u64 {
        self.quantile_ns(0.5)
    }

    /// The value at `quantile` in ms.
    pub fn quantile_ms(&self, quantile: f64) -> f64 {
        self.quantile_ns(quantile) as f64 * 1e-6
    }

    /// The median in ms.
    pub fn median_ms(&self) -> f64 {
        self.quantile_ms(0.5)
    }

    pub fn max_ns(&self) -> u64 {
        self.histogram.max()
    }

    /// Forgets every value (the next window).
    pub fn reset(&mut self) {
        self.histogram.reset();
    }

    /// The histogram itself (percentile iteration, mean, buckets).
    pub fn histogram(&self) -> &Histogram<u64> {
        &self.histogram
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_are_drops_and_going_back_is_a_restart() {
        let mut ids = IdGaps::default();
        assert_eq!(ids.observe(10), IdStep::First);
        assert_eq!(ids.observe(11).skipped(), 0);
        assert_eq!(ids.observe(14), IdStep::Forward { skipped: 2 });
        assert_eq!(ids.observe(0), IdStep::Back { from: 14 });
        assert_eq!(ids.observe(1).skipped(), 0);
        assert_eq!((ids.lost, ids.restarts), (2, 1));
        assert_eq!((ids.first, ids.last), (Some(10), Some(1)));
    }

    #[test]
    fn noted_ids_count_no_gap() {
        let mut ids = IdGaps::default();
        ids.note(3);
        ids.note(9);
        assert_eq!((ids.first, ids.last, ids.lost), (Some(3), Some(9), 0));
    }

    #[test]
    fn median_percentiles_and_reset() {
        let mut d = Durations::new();
        assert!(d.is_empty());
        assert_eq!(d.median_ns(), 0);
        for k in 1..=1000u64 {
            d.record_ns(k * 1_000_000); // 1..1000 ms
        }
        assert_eq!(d.count(), 1000);
        assert!((d.median_ms() - 500.0).abs() < 1.0, "{}", d.median_ms());
        assert!((d.quantile_ms(0.99) - 990.0).abs() < 1.0);
        assert!((d.max_ns() as f64 * 1e-6 - 1000.0).abs() < 1.0);
        d.record_ns(0); // clamped to 1 ns, not refused
        d.record_ns(u64::MAX); // clamped to 1 h
        assert_eq!(d.count(), 1002);
        d.reset();
        assert!(d.is_empty());
    }
}
