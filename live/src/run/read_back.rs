//! What the summary reads back from the results folder: the machine CSV follower's counts
//! (`machine_csv.json`), and the mean of `frames.csv`'s displacement error column.

use crate::config::{RigSource, RunConfig};
use crate::results::ResultsDir;
use std::path::Path;

/// A followed machine CSV's counts, from the follower's `machine_csv.json` (none when the
/// follower never started following); skipped lines are said on stderr.
pub(super) fn machine_csv_counts(
    config: &RunConfig,
    results: &ResultsDir,
) -> Option<rig::csv_follow::FollowCounters> {
    use rig::csv_follow::counts_file::{read, CountsReadError};
    if config.rig.source != RigSource::CsvFollow {
        return None;
    }
    match read(&results.machine_csv_json()) {
        Ok(counts) => {
            if counts.malformed_lines > 0 {
                eprintln!(
                    "run: {} malformed line(s) of the machine's CSV skipped (logs/rig.log names \
                     them)",
                    counts.malformed_lines
                );
            }
            Some(counts)
        }
        Err(CountsReadError::Read { reason, .. })
            if reason.kind() == std::io::ErrorKind::NotFound =>
        {
            None
        }
        Err(e) => {
            eprintln!("run: {e}");
            None
        }
    }
}

/// Mean of the `disp_error_mean_px` column of `frames.csv`, if any frame has it.
pub(super) fn mean_displacement_error(frames_csv: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(frames_csv).ok()?;
    let mut lines = text.lines();
    let column = lines
        .next()?
        .split(',')
        .position(|c| c == "disp_error_mean_px")?;
    let values: Vec<f64> = lines
        .filter_map(|l| l.split(',').nth(column)?.parse().ok())
        .collect();
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}
