//! Appended bytes in, whole lines out: a line is whole once its newline has arrived, so a row
//! the machine's software is still writing is never parsed half-written. A line is capped
//! ([`LINE_CAP_BYTES`]): past the cap only its first bytes are kept (for the report) and the
//! rest is counted, never held, until its newline ends it.

/// The longest line read, in bytes without its newline; a longer one is malformed.
pub const LINE_CAP_BYTES: usize = 64 * 1024;
/// Bytes kept of an over-long line, for its excerpt in the report.
pub const KEPT_OF_LONG_LINE_BYTES: usize = 1024;

/// One line, ended by its newline (which it does not hold; a `\r` stays).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Line {
    Whole(Vec<u8>),
    /// Longer than the cap: its first bytes and its length.
    TooLong {
        head: Vec<u8>,
        len_bytes: u64,
    },
}

/// Keeps the bytes after the last newline until the rest of their line arrives.
#[derive(Debug)]
pub struct LineSplitter {
    pending: Vec<u8>,
    cap_bytes: usize,
    /// The length so far of a line past the cap (then `pending` holds only its head).
    overlong_bytes: Option<u64>,
}

impl Default for LineSplitter {
    fn default() -> LineSplitter {
        LineSplitter::with_cap(LINE_CAP_BYTES)
    }
}

impl LineSplitter {
    pub fn with_cap(cap_bytes: usize) -> LineSplitter {
        LineSplitter {
            pending: Vec::new(),
            cap_bytes,
            overlong_bytes: None,
        }
    }

    /// Appends `bytes`; returns the lines completed.
    pub fn push(&mut self, bytes: &[u8]) -> Vec<Line> {
        let mut lines = Vec::new();
        let mut rest = bytes;
        while let Some(at) = rest.iter().position(|&b| b == b'\n') {
            self.take_in(&rest[..at]);
            lines.push(match self.overlong_bytes.take() {
                Some(len_bytes) => Line::TooLong {
                    head: std::mem::take(&mut self.pending),
                    len_bytes,
                },
                None => Line::Whole(std::mem::take(&mut self.pending)),
            });
            rest = &rest[at + 1..];
        }
        self.take_in(rest);
        lines
    }

    /// Adds a piece of the current line, keeping at most the cap (then only the head).
    fn take_in(&mut self, piece: &[u8]) {
        if let Some(len) = &mut self.overlong_bytes {
            *len += piece.len() as u64;
            return;
        }
        let len = self.pending.len() + piece.len();
        if len <= self.cap_bytes {
            self.pending.extend_from_slice(piece);
            return;
        }
        let keep = KEPT_OF_LONG_LINE_BYTES.min(self.cap_bytes);
        let from_piece = keep.saturating_sub(self.pending.len()).min(piece.len());
        self.pending.extend_from_slice(&piece[..from_piece]);
        self.pending.truncate(keep);
        self.pending.shrink_to(keep);
        self.overlong_bytes = Some(len as u64);
    }

    /// Bytes held of the line not ended yet (at most the cap).
    pub fn pending_len(&self) -> usize {
        self.pending.len()
    }

    /// Length of the line not ended yet (also what was counted past the cap).
    pub fn pending_line_bytes(&self) -> u64 {
        self.overlong_bytes.unwrap_or(self.pending.len() as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn whole(text: &[u8]) -> Line {
        Line::Whole(text.to_vec())
    }

    #[test]
    fn lines_are_whole_only_at_their_newline() {
        let mut s = LineSplitter::default();
        assert!(s.push(b"ab").is_empty());
        assert_eq!(
            s.push(b"c\nde\n\nf"),
            vec![whole(b"abc"), whole(b"de"), whole(b"")]
        );
        assert_eq!(s.pending_len(), 1);
        assert_eq!(s.push(b"\r\n"), vec![whole(b"f\r")]);
    }

    #[test]
    fn an_over_long_line_fed_in_pieces_is_never_held_whole() {
        let mut s = LineSplitter::default();
        assert!(s.push(b"0,1\nxy").len() == 1);
        // 50 MiB without a newline, in 1 MiB pieces as the tail reads them.
        let piece = vec![b'7'; 1 << 20];
        for _ in 0..50 {
            assert!(s.push(&piece).is_empty());
            assert!(
                s.pending_len() <= KEPT_OF_LONG_LINE_BYTES,
                "{}",
                s.pending_len()
            );
        }
        let lines = s.push(b"\n1,2\n");
        assert_eq!(lines.len(), 2, "{lines:?}");
        let Line::TooLong { head, len_bytes } = &lines[0] else {
            panic!("{:?}", lines[0]);
        };
        assert_eq!(*len_bytes, 2 + 50 * (1 << 20));
        assert_eq!(head.len(), KEPT_OF_LONG_LINE_BYTES);
        assert!(head.starts_with(b"xy777"));
        assert_eq!(lines[1], whole(b"1,2"));
        // A line of exactly the cap is whole.
        let mut s = LineSplitter::with_cap(4);
        assert_eq!(
            s.push(b"abcd\nabcde\n"),
            vec![
                whole(b"abcd"),
                Line::TooLong {
                    head: b"abcd".to_vec(),
                    len_bytes: 5
                }
            ]
        );
    }
}
