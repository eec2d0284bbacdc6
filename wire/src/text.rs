//! Fixed-size, NUL-padded UTF-8 text for layouts that cross shared memory (a `String` cannot).

/// Copies `text` into `buffer`, truncated at a character boundary to leave one NUL at the end.
pub fn write_fixed(buffer: &mut [u8], text: &str) {
    buffer.fill(0);
    let capacity = buffer.len().saturating_sub(1);
    let mut end = text.len().min(capacity);
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    buffer[..end].copy_from_slice(&text.as_bytes()[..end]);
}

/// Reads the text stored by [`write_fixed`], up to the first NUL; invalid UTF-8 is replaced.
pub fn read_fixed(buffer: &[u8]) -> String {
    let end = buffer.iter().position(|&b| b == 0).unwrap_or(buffer.len());
    String::from_utf8_lossy(&buffer[..end]).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_truncation_at_char_boundary() {
        let mut buffer = [0u8; 8];
        write_fixed(&mut buffer, "stroke");
        assert_eq!(read_fixed(&buffer), "stroke");
        write_fixed(&mut buffer, "déplacement");
        let back = read_fixed(&buffer);
        assert!("déplacement".starts_with(&back));
        assert!(back.len() <= 7);
    }
}
