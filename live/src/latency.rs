//! Per-frame latency: an HDR histogram (1 µs to 10 min, 3 significant digits) with the
//! percentiles a report quotes and the classic HdrHistogram percentile text (`.hgrm`, the
//! format HdrHistogram's plotters read), values in milliseconds.

use hdrhistogram::Histogram;
use serde::Serialize;
use std::fmt::Write as _;

const LOWEST_US: u64 = 1;
const HIGHEST_US: u64 = 600_000_000;

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
    histogram: Histogram<u64>,
}

impl Default for Latency {
    fn default() -> Self {
        Latency::new()
    }
}

impl Latency {
    pub fn new() -> Latency {
        Latency {
            histogram: Histogram::new_with_bounds(LOWEST_US, HIGHEST_US, 3)
                .expect("valid histogram bounds"),
        }
    }

    /// Records one latency in ns (clamped into the histogram's range).
    pub fn record_ns(&mut self, latency_ns: u64) {
        self.histogram
            .saturating_record((latency_ns / 1000).clamp(LOWEST_US, HIGHEST_US));
    }

    pub fn count(&self) -> u64 {
        self.histogram.len()
    }

    fn ms(us: u64) -> f64 {
        us as f64 * 1e-3
    }

    pub fn percentiles(&self) -> Percentiles {
        if self.histogram.is_empty() {
            return Percentiles::default();
        }
        let q = |quantile: f64| Self::ms(self.histogram.value_at_quantile(quantile));
        Percentiles {
            count: self.histogram.len(),
            p50: q(0.5),
            p90: q(0.9),
            p99: q(0.99),
            p999: q(0.999),
            max: Self::ms(self.histogram.max()),
        }
    }

    /// The percentile distribution in HdrHistogram's text format, values in ms.
    pub fn hgrm(&self) -> String {
        let h = &self.histogram;
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
            h.mean() * 1e-3,
            h.stdev() * 1e-3
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
        self.histogram
            .iter_quantiles(5)
            .map(|s| (Self::ms(s.value_iterated_to()), s.quantile_iterated_to()))
            .collect()
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
}
