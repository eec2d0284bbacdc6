//! Why a line of the machine's log is not a row, and the excerpt of it a report shows.

/// Characters of a line (or cell) a report shows; the rest is cut off and marked `…`.
pub const EXCERPT_CHARS: usize = 200;

/// `bytes` as text, cut to [`EXCERPT_CHARS`] characters (`…` marks a cut).
pub fn excerpt(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(bytes);
    let mut chars = text.chars();
    let mut shown: String = chars.by_ref().take(EXCERPT_CHARS).collect();
    if chars.next().is_some() {
        shown.push('…');
    }
    shown
}

/// Why a line is skipped (it is counted and reported).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RowError {
    #[error("{found} cells where the header has {expected}")]
    CellCount { found: usize, expected: usize },
    /// The cell is an excerpt.
    #[error("{column} = {cell:?} is not a number")]
    NotANumber { column: String, cell: String },
    #[error("time {t_s} s goes back (previous row {previous_s} s)")]
    TimeGoesBack { t_s: f64, previous_s: f64 },
    #[error("a quoted cell is not closed ({quotes} quotes on the line)")]
    UnclosedQuote { quotes: usize },
    #[error("a line of {len_bytes} bytes, longer than the cap of {cap_bytes}")]
    TooLong { len_bytes: u64, cap_bytes: usize },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_excerpt_is_cut_at_a_character_and_marked() {
        assert_eq!(excerpt(b"1,2"), "1,2");
        let long = "é".repeat(EXCERPT_CHARS + 1);
        let shown = excerpt(long.as_bytes());
        assert_eq!(shown.chars().count(), EXCERPT_CHARS + 1);
        assert!(shown.ends_with("é…"), "{shown}");
    }
}
