//! Bounded histories for the charts and counters (pure): a time series that halves its
//! resolution when full (so a test of any length fits in a fixed number of points) and a rate
//! over the last seconds (gaps in ids: `wire::stats::IdGaps`).

use std::collections::VecDeque;

/// Rows of `W` numbers, at most `cap`: when full, every other row is dropped and only every
/// second later row is kept, and so on (the whole test stays visible at a coarser step).
#[derive(Clone, Debug)]
pub struct Decimated<const W: usize> {
    cap: usize,
    every: u64,
    offered: u64,
    rows: Vec<[f64; W]>,
}

impl<const W: usize> Decimated<W> {
    pub fn new(cap: usize) -> Self {
        Decimated {
            cap: cap.max(2),
            every: 1,
            offered: 0,
            rows: Vec::new(),
        }
    }

    pub fn push(&mut self, row: [f64; W]) {
        let keep = self.offered.is_multiple_of(self.every);
        self.offered += 1;
        if !keep {
            return;
        }
        if self.rows.len() >= self.cap {
            let mut i = 0;
            self.rows.retain(|_| {
                i += 1;
                i % 2 == 1
            });
            self.every *= 2;
        }
        self.rows.push(row);
    }

    pub fn rows(&self) -> &[[f64; W]] {
        &self.rows
    }

    pub fn clear(&mut self) {
        self.rows.clear();
        self.every = 1;
        self.offered = 0;
    }

    /// Column `c` of every row, to 6 significant digits (enough for a chart, a third of the
    /// JSON of full precision).
    pub fn column(&self, c: usize) -> Vec<f64> {
        self.rows.iter().map(|r| significant(r[c], 6)).collect()
    }
}

/// `v` to `digits` significant digits (the nearest double, so JSON prints it short);
/// non-finite values unchanged (JSON `null`).
pub fn significant(v: f64, digits: usize) -> f64 {
    if !v.is_finite() || v == 0.0 {
        return v;
    }
    format!("{v:.*e}", digits.saturating_sub(1))
        .parse()
        .unwrap_or(v)
}

/// Events per second over the last `window_ns`, from (time, running count) marks.
#[derive(Clone, Debug)]
pub struct Rate {
    window_ns: u64,
    marks: VecDeque<(u64, u64)>,
}

impl Rate {
    pub fn new(window_ns: u64) -> Self {
        Rate {
            window_ns,
            marks: VecDeque::new(),
        }
    }

    /// Notes the running count at `now_ns`.
    pub fn mark(&mut self, now_ns: u64, count: u64) {
        self.marks.push_back((now_ns, count));
        while self.marks.len() > 2
            && self
                .marks
                .front()
                .is_some_and(|&(t, _)| now_ns.saturating_sub(t) > self.window_ns)
        {
            self.marks.pop_front();
        }
    }

    pub fn per_s(&self) -> f64 {
        match (self.marks.front(), self.marks.back()) {
            (Some(&(t0, c0)), Some(&(t1, c1))) if t1 > t0 && c1 >= c0 => {
                (c1 - c0) as f64 * 1e9 / (t1 - t0) as f64
            }
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_series_stays_within_its_cap_and_spans_the_whole_time() {
        let mut s = Decimated::<2>::new(100);
        for i in 0..10_000 {
            s.push([i as f64, 2.0 * i as f64]);
        }
        assert!(
            s.rows().len() <= 100 && s.rows().len() >= 50,
            "{}",
            s.rows().len()
        );
        assert_eq!(s.rows()[0][0], 0.0);
        assert!(s.rows().last().unwrap()[0] > 9000.0);
        assert!(s.rows().windows(2).all(|w| w[1][0] > w[0][0]));
        assert_eq!(s.column(1)[1], 2.0 * s.rows()[1][0]);
        assert_eq!(significant(0.277479141950, 5).to_string(), "0.27748");
        assert_eq!(significant(-1.234567e-7, 3), -1.23e-7);
        assert!(significant(f64::NAN, 3).is_nan());
    }

    #[test]
    fn rate_over_the_window() {
        let mut r = Rate::new(2_000_000_000);
        assert_eq!(r.per_s(), 0.0);
        for i in 0..=10u64 {
            r.mark(i * 500_000_000, i * 5);
        }
        assert!((r.per_s() - 10.0).abs() < 1e-9);
    }
}
