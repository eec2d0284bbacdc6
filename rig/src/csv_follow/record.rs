//! One whole line of the log into its cells, by `csv-core` (RFC 4180 quoting: `"4,5"` is one
//! cell, `""` inside quotes is a quote), with the configured delimiter. A line is a record: a
//! newline always ends it (the log's lines come whole from [`super::lines`]), so a quote left
//! open spoils its own line only, which is then malformed.

use super::malformed::RowError;
use std::borrow::Cow;

/// The UTF-8 byte order mark some programs (Excel's "CSV UTF-8") write before the header.
pub const UTF8_BOM: &[u8] = b"\xEF\xBB\xBF";

/// Splits lines into cells; keeps its buffers from line to line.
#[derive(Debug)]
pub struct RecordReader {
    reader: csv_core::Reader,
    cells: Vec<u8>,
    ends: Vec<usize>,
}

impl RecordReader {
    /// `delimiter` is an ASCII character (`,`, `;`, tab: checked by
    /// [`super::CsvColumns::validate`]).
    pub fn new(delimiter: char) -> RecordReader {
        let reader = csv_core::ReaderBuilder::new()
            .delimiter(delimiter as u8)
            // Only `\n` ends a record, and no line holds one: a `\r` is data (trimmed as
            // white space at the line's end).
            .terminator(csv_core::Terminator::Any(b'\n'))
            .build();
        RecordReader {
            reader,
            cells: Vec::new(),
            ends: Vec::new(),
        }
    }

    /// The cells of one line (without its newline; a trailing `\r` is dropped), unquoted.
    pub fn split<'a>(&'a mut self, line: &[u8]) -> Result<Vec<Cow<'a, str>>, RowError> {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        let quotes = line.iter().filter(|&&b| b == b'"').count();
        if quotes % 2 == 1 {
            return Err(RowError::UnclosedQuote { quotes });
        }
        self.reader.reset();
        // Unquoting only shortens: a cell buffer of the line's length always suffices.
        self.cells.resize(line.len(), 0);
        let (mut input, mut written, mut ended) = (line, 0, 0);
        loop {
            if ended == self.ends.len() {
                self.ends.resize(2 * ended + 8, 0);
            }
            let (result, read, out, ends) =
                self.reader
                    .read_record(input, &mut self.cells[written..], &mut self.ends[ended..]);
            input = &input[read..];
            written += out;
            ended += ends;
            match result {
                // The whole line is in: an empty input then ends the record.
                csv_core::ReadRecordResult::InputEmpty
                | csv_core::ReadRecordResult::OutputEndsFull => {}
                csv_core::ReadRecordResult::OutputFull => {
                    self.cells.resize(self.cells.len() + 64, 0);
                }
                csv_core::ReadRecordResult::Record | csv_core::ReadRecordResult::End => break,
            }
        }
        let mut start = 0;
        Ok(self.ends[..ended]
            .iter()
            .map(|&end| {
                let cell = String::from_utf8_lossy(&self.cells[start..end]);
                start = end;
                cell
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cells(reader: &mut RecordReader, line: &str) -> Result<Vec<String>, RowError> {
        reader
            .split(line.as_bytes())
            .map(|c| c.into_iter().map(Cow::into_owned).collect())
    }

    #[test]
    fn quoted_cells_keep_the_delimiter_and_doubled_quotes() {
        let mut r = RecordReader::new(',');
        assert_eq!(
            cells(&mut r, "\"4,5\",\"450,5\"\r").unwrap(),
            ["4,5", "450,5"]
        );
        assert_eq!(
            cells(&mut r, "\"Time (s)\",\"say \"\"hi\"\"\",,x").unwrap(),
            ["Time (s)", "say \"hi\"", "", "x"]
        );
        assert_eq!(cells(&mut r, "5,1,510").unwrap(), ["5", "1", "510"]);
        let mut r = RecordReader::new(';');
        assert_eq!(cells(&mut r, "1,5;\"2;5\"").unwrap(), ["1,5", "2;5"]);
        let mut r = RecordReader::new('\t');
        assert_eq!(cells(&mut r, "1\t2,5").unwrap(), ["1", "2,5"]);
    }

    #[test]
    fn a_quote_left_open_is_malformed() {
        let mut r = RecordReader::new(',');
        assert_eq!(
            cells(&mut r, "\"4,5,6").unwrap_err(),
            RowError::UnclosedQuote { quotes: 1 }
        );
        // The next line is read afresh.
        assert_eq!(cells(&mut r, "4,5").unwrap(), ["4", "5"]);
    }

    #[test]
    fn many_cells_and_long_cells_fit() {
        let mut r = RecordReader::new(',');
        let line = (0..1000)
            .map(|k| k.to_string())
            .collect::<Vec<_>>()
            .join(",");
        let got = cells(&mut r, &line).unwrap();
        assert_eq!(got.len(), 1000);
        assert_eq!(got[999], "999");
        let long = "9".repeat(10_000);
        assert_eq!(
            cells(&mut r, &format!("\"{long}\",1")).unwrap(),
            [&long, "1"]
        );
    }
}
