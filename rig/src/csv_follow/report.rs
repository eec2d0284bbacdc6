//! What the follower says about malformed lines: rate-limited, never silent. The first
//! [`REPORTED_EACH`] are said one by one (line number, why, excerpt); after them one line at
//! most every [`SUMMARY_EVERY`] sums up those not said yet (how many, the last one, the total),
//! and [`MalformedReport::finish`] says the rest at the end. Pure: the caller gives the time.

use super::RowError;
use std::time::{Duration, Instant};

/// Malformed lines said one by one.
pub const REPORTED_EACH: u64 = 20;
/// At most one summary line of the further ones this often.
pub const SUMMARY_EVERY: Duration = Duration::from_secs(10);

/// The malformed lines not said one by one since the last summary.
#[derive(Clone, Debug, PartialEq)]
struct Unsaid {
    count: u64,
    first_line_no: u64,
    last_line_no: u64,
    last_why: RowError,
}

/// The report of one followed file's malformed lines.
#[derive(Debug)]
pub struct MalformedReport {
    /// The file as the lines name it.
    file: String,
    total: u64,
    unsaid: Option<Unsaid>,
    next_summary_at: Option<Instant>,
}

impl MalformedReport {
    pub fn new(file: String) -> MalformedReport {
        MalformedReport {
            file,
            total: 0,
            unsaid: None,
            next_summary_at: None,
        }
    }

    /// Malformed lines so far.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// One malformed line; returns the line to print now, if any.
    pub fn malformed(
        &mut self,
        line_no: u64,
        text: &str,
        why: &RowError,
        now: Instant,
    ) -> Option<String> {
        self.total += 1;
        if self.total <= REPORTED_EACH {
            let more = if self.total == REPORTED_EACH {
                self.next_summary_at = Some(now + SUMMARY_EVERY);
                format!(
                    " (further malformed lines are summed up every {} s and at the end)",
                    SUMMARY_EVERY.as_secs()
                )
            } else {
                String::new()
            };
            return Some(format!(
                "rig: {} line {line_no} skipped: {why}: {text:?}{more}",
                self.file
            ));
        }
        match &mut self.unsaid {
            Some(u) => {
                u.count += 1;
                u.last_line_no = line_no;
                u.last_why = why.clone();
            }
            None => {
                self.unsaid = Some(Unsaid {
                    count: 1,
                    first_line_no: line_no,
                    last_line_no: line_no,
                    last_why: why.clone(),
                })
            }
        }
        self.tick(now)
    }

    /// The summary line, when malformed lines are unsaid and the interval has passed.
    pub fn tick(&mut self, now: Instant) -> Option<String> {
        if self.next_summary_at.is_some_and(|at| now < at) {
            return None;
        }
        let line = self.summary()?;
        self.next_summary_at = Some(now + SUMMARY_EVERY);
        Some(line)
    }

    /// At the end: the summary of what is unsaid, if anything.
    pub fn finish(&mut self) -> Option<String> {
        self.summary()
    }

    fn summary(&mut self) -> Option<String> {
        let u = self.unsaid.take()?;
        Some(format!(
            "rig: {}: {} more malformed line(s) skipped, lines {} to {} (line {}: {}); {} \
             malformed in all",
            self.file,
            u.count,
            u.first_line_no,
            u.last_line_no,
            u.last_line_no,
            u.last_why,
            self.total
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn why(k: u64) -> RowError {
        RowError::CellCount {
            found: k as usize,
            expected: 2,
        }
    }

    #[test]
    fn a_burst_of_50_malformed_lines_is_said_20_then_summed_up_by_interval_and_at_the_end() {
        let mut report = MalformedReport::new("m.csv".into());
        let t0 = Instant::now();
        // 50 lines in one read (lines 2 to 51).
        let said: Vec<String> = (2..52)
            .filter_map(|k| report.malformed(k, "x", &why(k), t0))
            .collect();
        assert_eq!(said.len(), REPORTED_EACH as usize, "{said:#?}");
        assert!(said[0].starts_with("rig: m.csv line 2 skipped: 2 cells where the header has 2"));
        assert!(said[19].contains("line 21 skipped") && said[19].contains("summed up every 10 s"));
        assert_eq!(report.total(), 50);
        // Within the interval: nothing more; at its end, the 30 others.
        assert_eq!(report.tick(t0 + SUMMARY_EVERY / 2), None);
        let summary = report.tick(t0 + SUMMARY_EVERY).unwrap();
        assert!(
            summary
                .contains("30 more malformed line(s) skipped, lines 22 to 51 (line 51: 51 cells")
                && summary.ends_with("50 malformed in all"),
            "{summary}"
        );
        assert_eq!(report.tick(t0 + 3 * SUMMARY_EVERY), None);
        // Later ones: said at once when the interval has passed, else at the end.
        let t1 = t0 + 3 * SUMMARY_EVERY;
        let now = report.malformed(60, "x", &why(1), t1).unwrap();
        assert!(
            now.contains("1 more") && now.ends_with("51 malformed in all"),
            "{now}"
        );
        assert_eq!(report.malformed(61, "x", &why(1), t1), None);
        let end = report.finish().unwrap();
        assert!(
            end.contains("lines 61 to 61") && end.ends_with("52 malformed in all"),
            "{end}"
        );
        assert_eq!(report.finish(), None);
    }

    #[test]
    fn fewer_than_the_limit_are_each_said_and_leave_no_summary() {
        let mut report = MalformedReport::new("m.csv".into());
        let t0 = Instant::now();
        for k in 0..REPORTED_EACH - 1 {
            assert!(report.malformed(k, "x", &why(k), t0).is_some());
        }
        assert_eq!(report.tick(t0 + SUMMARY_EVERY), None);
        assert_eq!(report.finish(), None);
    }
}
