//! Latency distribution for the page: percentiles (`wire::stats::Durations`, the histogram
//! every latency of dicstream uses) and counts in fixed log-spaced bins (ms) for a small bar
//! chart. Pure.

use serde_json::{json, Value};
use wire::stats::Durations;

/// Upper edges of the display bins (ms); a last bin takes everything above.
pub const BIN_EDGES_MS: [f64; 12] = [
    1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0, 5000.0,
];

#[derive(Clone, Debug, Default)]
pub struct LatencyStats {
    durations: Durations,
    bins: [u64; BIN_EDGES_MS.len() + 1],
}

impl LatencyStats {
    /// Records a latency from two monotonic times (ns); ignored when either is unset or the
    /// order is wrong (a header from another clock).
    pub fn record_ns(&mut self, from_ns: u64, to_ns: u64) {
        if from_ns == 0 || to_ns < from_ns {
            return;
        }
        let ns = to_ns - from_ns;
        self.durations.record_ns(ns);
        let ms = ns as f64 / 1e6;
        let bin = BIN_EDGES_MS
            .iter()
            .position(|&edge| ms <= edge)
            .unwrap_or(BIN_EDGES_MS.len());
        self.bins[bin] += 1;
    }

    pub fn count(&self) -> u64 {
        self.durations.count()
    }

    /// `{count, p50, p90, p99, max}` in ms and the bins, or `null` before the first value.
    pub fn json(&self) -> Value {
        if self.count() == 0 {
            return Value::Null;
        }
        let ms = |q: f64| self.durations.quantile_ms(q);
        json!({
            "count": self.count(),
            "p50": ms(0.5),
            "p90": ms(0.9),
            "p99": ms(0.99),
            "max": self.durations.max_ns() as f64 * 1e-6,
            "bin_edges_ms": BIN_EDGES_MS,
            "bins": self.bins,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_and_bins() {
        let mut l = LatencyStats::default();
        assert_eq!(l.json(), Value::Null);
        for ms in 1..=100u64 {
            l.record_ns(1_000, 1_000 + ms * 1_000_000);
        }
        l.record_ns(0, 5);
        l.record_ns(10, 5);
        let j = l.json();
        assert_eq!(j["count"], 100);
        assert!((j["p50"].as_f64().unwrap() - 50.0).abs() < 0.1);
        let bins: Vec<u64> = serde_json::from_value(j["bins"].clone()).unwrap();
        assert_eq!(bins.iter().sum::<u64>(), 100);
        assert_eq!(bins[0], 1); // 1 ms
        assert_eq!(bins[6], 50); // (50, 100] ms
    }
}
