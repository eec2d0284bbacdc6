//! Per-frame latency: the streams' one histogram of durations (`wire::stats::Durations`, ns)
//! with the percentiles a report quotes and the classic HdrHistogram percentile text
//! (`.hgrm`, the format HdrHistogram's plotters read), values in milliseconds.

use serde::Serialize;
use std::fmt::Write as _;
use wire::stats::Durations;

/// Percentiles in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Percentiles {
    pub count: u64,
    pub p50: f64,
    pub p90: f64,
    pub p99: f64,
    pub p999: f64,
    pub max: f64,
}

#[derive(Clone, Debug)]
pub struct Latency {
    durations: Durations,
}

impl Default for Latency {
    fn default() -> Self {
        Latency::new()
    }
}

impl Latency {
    pub fn new() -> Latency {
        Latency {
            durations: Durations::new(),
        }
    }

    /// Records one latency in ns (clamped into the histogram's range).
    pub fn record_ns(&mut self, latency_ns: u64) {
        self.durations.record_ns(latency_ns);
    }

    pub fn count(&self) -> u64 {
        self.durations.count()
    }

    fn ms(ns: u64) -> f64 {
        ns as f64 * 1e-6
    }

    pub fn percentiles(&self) -> Percentiles {
        if self.durations.is_empty() {
            return Percentiles::default();
        }
        let d = &self.durations;
        Percentiles {
            count: d.count(),
            p50: d.median_ms(),
            p90: d.quantile_ms(0.9),
            p99: d.quantile_ms(0.99),
            p999: d.quantile_ms(0.999),
            max: Self::ms(d.max_ns()),
        }
    }

    /// The percentile distribution in HdrHistogram's text format, values in ms.
    pub fn hgrm(&self) -> String {
        let h = self.durations.histogram();
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{:>12} {:>14} {:>10} {:>14}\n",
            "Value", "Percentile", "TotalCount", "1/(1-Percentile)"
        );
        let mut total = 0u64;
        for step in h.iter_quantiles(5) {
            total += step.count_since_last_iteration();
            let quantile = step.quantile_iterated_to();
            let value = Self::ms(step.value_iterated_to());
            if quantile < 1.0 {
                let _ = writeln!(
                    out,
                    "{value:>12.3} {quantile:>14.12} {total:>10} {:>14.2}",
                    1.0 / (1.0 - quantile)
                );
            } else {
                let _ = writeln!(out, "{value:>12.3} {quantile:>14.12} {total:>10}");
            }
        }
        let _ = writeln!(
            out,
            "#[Mean    = {:>12.3}, StdDeviation   = {:>12.3}]",
            h.mean() * 1e-6,
            h.stdev() * 1e-6
        );
        let _ = writeln!(
            out,
            "#[Max     = {:>12.3}, Total count    = {:>12}]",
            Self::ms(h.max()),
            h.len()
        );
        let _ = writeln!(
            out,
            "#[Buckets = {:>12}, SubBuckets     = {:>12}]",
            h.buckets(),
            h.distinct_values()
        );
        out
    }

    /// (latency ms, percentile) pairs of the distribution, for plotting.
    pub fn distribution(&self) -> Vec<(f64, f64)> {
        self.durations
            .histogram()
            .iter_quantiles(5)
            .map(|s| (Self::ms(s.value_iterated_to()), s.quantile_iterated_to()))
            .collect()
    }
}

/// Where a field's latency (capture to seen by the run's monitor) goes, per frame: waiting
/// (capture to the correlator taking the frame, queueing included), correlating (taken to
/// published) and delivering (published to seen).
#[derive(Clone, Debug, Default)]
pub struct FieldLatencyParts {
    pub waiting: Latency,
    pub correlating: Latency,
    pub delivering: Latency,
}

/// Their percentiles, ms.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FieldLatencyPartsMs {
    pub waiting: Percentiles,
    pub correlating: Percentiles,
    pub delivering: Percentiles,
}

impl FieldLatencyParts {
    /// The parts of one field: captured, taken by the correlator, published, seen (monotonic
    /// ns; a clock that went backwards counts 0).
    pub fn record(&mut self, captured_ns: u64, received_ns: u64, published_ns: u64, seen_ns: u64) {
        self.waiting
            .record_ns(received_ns.saturating_sub(captured_ns));
        self.correlating
            .record_ns(published_ns.saturating_sub(received_ns));
        self.delivering
            .record_ns(seen_ns.saturating_sub(published_ns));
    }

    pub fn percentiles(&self) -> FieldLatencyPartsMs {
        FieldLatencyPartsMs {
            waiting: self.waiting.percentiles(),
            correlating: self.correlating.percentiles(),
            delivering: self.delivering.percentiles(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_and_hgrm() {
        let mut l = Latency::new();
        assert_eq!(l.percentiles(), Percentiles::default());
        for k in 1..=1000u64 {
            l.record_ns(k * 1_000_000); // 1..1000 ms
        }
        let p = l.percentiles();
        assert_eq!(p.count, 1000);
        assert!((p.p50 - 500.0).abs() < 1.0, "{p:?}");
        assert!((p.p99 - 990.0).abs() < 1.0, "{p:?}");
        assert!((p.max - 1000.0).abs() < 1.0, "{p:?}");
        let text = l.hgrm();
        assert!(text.starts_with("       Value     Percentile"));
        assert!(text.contains("#[Max     ="));
        let last = text
            .lines()
            .rfind(|line| !line.starts_with('#') && !line.trim().is_empty())
            .unwrap();
        assert!(
            last.contains("1.000000000000") && last.contains("1000"),
            "{last}"
        );
        assert!(!l.distribution().is_empty());
    }

    #[test]
    fn a_fields_latency_splits_into_waiting_correlating_and_delivering() {
        let mut parts = FieldLatencyParts::default();
        // Captured at 0, taken at 40 ms, published at 70 ms, seen at 71 ms.
        parts.record(0, 40_000_000, 70_000_000, 71_000_000);
        // A clock read out of order counts 0, not a wrap-around.
        parts.record(50_000_000, 40_000_000, 80_000_000, 81_000_000);
        let ms = parts.percentiles();
        assert_eq!(ms.waiting.count, 2);
        assert!((ms.waiting.max - 40.0).abs() < 0.1, "{ms:?}");
        assert!(
            ms.waiting.p50 < 0.1 || (ms.waiting.p50 - 40.0).abs() < 0.1,
            "{ms:?}"
        );
        assert!((ms.correlating.max - 40.0).abs() < 0.1, "{ms:?}");
        assert!((ms.correlating.p50 - 30.0).abs() < 0.1, "{ms:?}");
        assert!((ms.delivering.max - 1.0).abs() < 0.01, "{ms:?}");
    }
}
