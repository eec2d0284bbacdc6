//! Appended bytes in, whole lines out: a line is whole once its newline has arrived, so a row
//! the machine's software is still writing is never parsed half-written.

/// Keeps the bytes after the last newline until the rest of their line arrives.
#[derive(Debug, Default)]
pub struct LineSplitter {
    pending: Vec<u8>,
}

impl LineSplitter {
    /// Appends `bytes`; returns the lines completed (without their `\n`; a `\r` stays).
    pub fn push(&mut self, bytes: &[u8]) -> Vec<Vec<u8>> {
        let mut lines = Vec::new();
        let mut rest = bytes;
        while let Some(at) = rest.iter().position(|&b| b == b'\n') {
            let mut line = std::mem::take(&mut self.pending);
            line.extend_from_slice(&rest[..at]);
            lines.push(line);
            rest = &rest[at + 1..];
        }
        self.pending.extend_from_slice(rest);
        lines
    }

    pub fn pending_len(&self) -> usize {
        self.pending.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_whole_only_at_their_newline() {
        let mut s = LineSplitter::default();
        assert!(s.push(b"ab").is_empty());
        assert_eq!(
            s.push(b"c\nde\n\nf"),
            vec![b"abc".to_vec(), b"de".to_vec(), vec![]]
        );
        assert_eq!(s.pending_len(), 1);
        assert_eq!(s.push(b"\r\n"), vec![b"f\r".to_vec()]);
    }
}
