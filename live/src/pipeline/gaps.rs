//! The frames a trial of `bench pipeline` did not correlate, and why: the gaps in the frame ids
//! of `frames.csv` (one row per field), how many followed a frame that renewed the reference,
//! and the correlator's own split from its last line (`logs/correlator.log`): *skipped*, frames
//! it received but that a newer one superseded while it was busy (it always takes the newest),
//! and *lost*, frames the camera's queue overwrote before it could take them (`frames` keeps two
//! per subscriber: a frame that takes longer than two periods loses the oldest waiting one).

use serde::Serialize;
use std::path::Path;

/// Frames not correlated in one trial.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameGaps {
    /// Frame ids missing between the first and the last field.
    pub missing: u64,
    /// Runs of missing ids, and the longest.
    pub gaps: u64,
    pub longest: u64,
    /// Gaps right after a field whose frame became the new reference (a renewal's work).
    pub after_renewal: u64,
    /// The correlator's own count: received but superseded, and never received (None when its
    /// log has no final line).
    pub skipped: Option<u64>,
    pub lost: Option<u64>,
}

impl FrameGaps {
    /// The gaps of a results folder (`frames.csv`, `logs/correlator.log`).
    pub fn of_results(results: &Path) -> FrameGaps {
        let csv = std::fs::read_to_string(results.join("frames.csv")).unwrap_or_default();
        let log = std::fs::read_to_string(results.join("logs").join("correlator.log"))
            .unwrap_or_default();
        let mut gaps = FrameGaps::of_frames_csv(&csv);
        (gaps.skipped, gaps.lost) = correlator_split(&log);
        gaps
    }

    /// The gaps of `frames.csv`'s text (columns `frame_id`, `reference_frame_id`).
    pub fn of_frames_csv(text: &str) -> FrameGaps {
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
        let column = |name: &str| header.iter().position(|c| *c == name);
        let (Some(id_at), Some(reference_at)) = (column("frame_id"), column("reference_frame_id"))
        else {
            return FrameGaps::default();
        };
        let rows = lines.filter_map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            Some((
                cells.get(id_at)?.parse::<u64>().ok()?,
                cells.get(reference_at)?.parse::<u64>().ok()?,
            ))
        });
        let mut gaps = FrameGaps::default();
        let mut previous: Option<u64> = None;
        // A field names the reference it was correlated against: a frame renewed the reference
        // when a later field names it.
        let mut gap_after: Option<u64> = None;
        for (id, reference) in rows {
            if gap_after.take() == Some(reference) {
                gaps.after_renewal += 1;
            }
            if let Some(last) = previous.filter(|&last| id > last + 1) {
                let missing = id - last - 1;
                gaps.missing += missing;
                gaps.gaps += 1;
                gaps.longest = gaps.longest.max(missing);
                gap_after = Some(last);
            }
            if previous.is_none_or(|last| id > last) {
                previous = Some(id);
            }
        }
        gaps
    }
}

/// "skipped S, lost L" from the correlator's last "stopped" line.
fn correlator_split(log: &str) -> (Option<u64>, Option<u64>) {
    let Some(line) = log
        .lines()
        .rev()
        .find(|l| l.contains("correlator: stopped"))
    else {
        return (None, None);
    };
    let number_after = |key: &str| {
        let rest = &line[line.find(key)? + key.len()..];
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        digits.parse().ok()
    };
    (number_after("skipped "), number_after("lost "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_after_a_renewal_and_elsewhere() {
        // Frame 3 renewed the reference (field 6 names it): the gap 4-5 follows a renewal; the
        // gap 8 does not.
        let csv =
            "frame_id,reference_frame_id,x\n0,0,a\n1,0,a\n2,0,a\n3,0,a\n6,3,a\n7,3,a\n9,3,a\n";
        let gaps = FrameGaps::of_frames_csv(csv);
        assert_eq!(
            gaps,
            FrameGaps {
                missing: 3,
                gaps: 2,
                longest: 2,
                after_renewal: 1,
                skipped: None,
                lost: None,
            }
        );
        let log = "correlator: ready\ncorrelator: stopped (SIGTERM): frames in 164, correlated 142, dropped 39 (skipped 22, lost 17), rejected 0; correlate p50 36.7 ms\n";
        assert_eq!(correlator_split(log), (Some(22), Some(17)));
        assert_eq!(correlator_split("nothing"), (None, None));
    }
}
