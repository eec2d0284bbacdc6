//! Following a test machine's own force log: a CSV file its software appends rows to while
//! the test runs. Pure (no IPC): [`lines`] cuts appended bytes into whole lines (a partial last
//! line waits for its newline; a line past the cap is counted, not held), [`record`] splits a
//! line into cells (`csv-core`: quoting, the delimiter), [`columns`] finds the configured
//! columns in the header and converts their units, [`tail`] reads what was appended to the
//! file since the last poll (waiting for a file that does not exist yet, noticing truncation
//! and rotation), and [`Follower`] ties them: bytes in, rows or malformed lines out;
//! [`report`] says the malformed lines on stderr, rate-limited but never silent, and
//! [`counts_file`] keeps the counters in a JSON file for `dicstream run`. The process
//! shell that publishes the rows on `rig/state` is [`process`] (feature `process`).

pub mod clock;
pub mod columns;
pub mod counts_file;
/// The delimiter a user names, shared with the identifier's data files (`wire::delimited`).
pub mod delimiter {
    pub use wire::delimited::Delimiter;
}
pub mod lines;
pub mod malformed;
#[cfg(feature = "process")]
pub mod process;
pub mod record;
pub mod report;
pub mod tail;

pub use columns::{ColumnSpec, CsvColumns, CsvError, Layout, Row};
pub use lines::{Line, LineSplitter};
pub use malformed::RowError;
pub use record::RecordReader;
pub use tail::{FileTail, TailRead};

/// What one complete line gave.
#[derive(Clone, Debug, PartialEq)]
pub enum LineEvent {
    /// The header was found: the columns are known.
    Header,
    Row(Row),
    /// A line that is not a row (skipped, counted): its 1-based line number, an excerpt of
    /// it and why.
    Malformed {
        line_no: u64,
        text: String,
        why: RowError,
    },
}

/// Counters of a follow (also the run's `machine_csv.json` and `summary.json`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct FollowCounters {
    /// Rows read (each published).
    pub rows: u64,
    /// Lines skipped as not rows.
    pub malformed_lines: u64,
    /// Times the file was truncated or replaced (each starts over at its header).
    pub restarts: u64,
}

/// Whole lines in, header then rows out. A missing column or a header that cannot be read is
/// an error (the follow cannot go on); a row that does not parse is reported and skipped.
#[derive(Debug)]
pub struct Follower {
    spec: CsvColumns,
    layout: Option<Layout>,
    lines: LineSplitter,
    reader: RecordReader,
    line_no: u64,
    last_time_s: Option<f64>,
    pub counters: FollowCounters,
}

impl Follower {
    pub fn new(spec: CsvColumns) -> Result<Follower, CsvError> {
        spec.validate()?;
        Ok(Follower {
            reader: RecordReader::new(spec.delimiter),
            spec,
            layout: None,
            lines: LineSplitter::default(),
            line_no: 0,
            last_time_s: None,
            counters: FollowCounters::default(),
        })
    }

    /// The columns found, once the header has been read.
    pub fn layout(&self) -> Option<&Layout> {
        self.layout.as_ref()
    }

    /// Bytes appended to the file; returns what the whole lines among them gave.
    pub fn feed(&mut self, bytes: &[u8]) -> Result<Vec<LineEvent>, CsvError> {
        let mut events = Vec::new();
        for line in self.lines.push(bytes) {
            self.line_no += 1;
            let (mut bytes, too_long) = match line {
                Line::Whole(bytes) => (bytes, None),
                Line::TooLong { head, len_bytes } => (
                    head,
                    Some(RowError::TooLong {
                        len_bytes,
                        cap_bytes: lines::LINE_CAP_BYTES,
                    }),
                ),
            };
            if self.line_no == 1 && bytes.starts_with(record::UTF8_BOM) {
                bytes.drain(..record::UTF8_BOM.len());
            }
            if too_long.is_none() && bytes.trim_ascii().is_empty() {
                continue;
            }
            let Some(layout) = &self.layout else {
                let bad_header = |why| CsvError::BadHeader {
                    header: malformed::excerpt(&bytes),
                    why,
                };
                if let Some(why) = too_long {
                    return Err(bad_header(why));
                }
                let cells = self.reader.split(&bytes).map_err(bad_header)?;
                let text = String::from_utf8_lossy(&bytes);
                self.layout = Some(Layout::from_header(
                    &cells,
                    text.trim_end_matches('\r'),
                    &self.spec,
                )?);
                events.push(LineEvent::Header);
                continue;
            };
            let parsed = match too_long {
                Some(why) => Err(why),
                None => self
                    .reader
                    .split(&bytes)
                    .and_then(|cells| layout.parse_row(&cells)),
            }
            .and_then(|row| match self.last_time_s {
                Some(previous_s) if row.t_s < previous_s => Err(RowError::TimeGoesBack {
                    t_s: row.t_s,
                    previous_s,
                }),
                _ => Ok(row),
            });
            match parsed {
                Ok(row) => {
                    self.last_time_s = Some(row.t_s);
                    self.counters.rows += 1;
                    events.push(LineEvent::Row(row));
                }
                Err(why) => {
                    self.counters.malformed_lines += 1;
                    events.push(LineEvent::Malformed {
                        line_no: self.line_no,
                        text: malformed::excerpt(bytes.strip_suffix(b"\r").unwrap_or(&bytes)),
                        why,
                    });
                }
            }
        }
        Ok(events)
    }

    /// The file was truncated or replaced: what follows starts with a header again.
    pub fn start_over(&mut self) {
        self.layout = None;
        self.lines = LineSplitter::default();
        self.line_no = 0;
        self.last_time_s = None;
        self.counters.restarts += 1;
    }

    /// Bytes of a partial last line waiting for their newline (at most the line cap).
    pub fn pending_bytes(&self) -> usize {
        self.lines.pending_len()
    }

    /// Length of a partial last line (read when its newline comes; said at the end).
    pub fn unfinished_line_bytes(&self) -> u64 {
        self.lines.pending_line_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use columns::{ForceUnit, LengthUnit, TimeUnit};

    fn spec() -> CsvColumns {
        CsvColumns {
            time: ColumnSpec::new("Time", None),
            force: [Some(ColumnSpec::new("Fx", None)), None, None],
            displacement: [Some(ColumnSpec::new("Dx", None)), None, None],
            time_unit: Some(TimeUnit::S),
            force_unit: Some(ForceUnit::KiloNewton),
            displacement_unit: Some(LengthUnit::Mm),
            delimiter: ',',
        }
    }

    fn rows(events: &[LineEvent]) -> Vec<Row> {
        events
            .iter()
            .filter_map(|e| match e {
                LineEvent::Row(r) => Some(*r),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn a_partial_last_line_waits_for_its_newline() {
        let mut f = Follower::new(spec()).unwrap();
        let e = f.feed(b"Time,Fx,Dx\n0.0,1.5,0.1\n0.01,1.").unwrap();
        assert_eq!(e[0], LineEvent::Header);
        assert_eq!(rows(&e).len(), 1);
        assert_eq!(f.pending_bytes(), 7);
        assert_eq!(f.unfinished_line_bytes(), 7);
        let e = f.feed(b"75,0.2").unwrap();
        assert!(e.is_empty(), "{e:?}");
        let e = f.feed(b"\n").unwrap();
        let r = rows(&e);
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].t_s, 0.01);
        assert_eq!(r[0].force_n[0], Some(1750.0));
        assert_eq!(r[0].displacement_mm[0], Some(0.2));
        assert_eq!(f.counters.rows, 2);
    }

    fn malformed(events: &[LineEvent]) -> Vec<(u64, &str, &RowError)> {
        events
            .iter()
            .filter_map(|e| match e {
                LineEvent::Malformed { line_no, text, why } => Some((*line_no, text.as_str(), why)),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn a_malformed_line_is_reported_skipped_and_counted() {
        let mut f = Follower::new(spec()).unwrap();
        let e = f
            .feed(b"Time,Fx,Dx\n0.1,1,0\n0.2,oops,0\n0.3,2\n0.05,1,1\n0.4,3,0.3\n")
            .unwrap();
        let r = rows(&e);
        assert_eq!(r.iter().map(|r| r.t_s).collect::<Vec<_>>(), [0.1, 0.4]);
        let bad = malformed(&e);
        assert_eq!(bad.len(), 3, "{bad:?}");
        assert_eq!(bad[0].0, 3);
        assert!(
            matches!(bad[0].2, RowError::NotANumber { column, cell } if column == "Fx" && cell == "oops"),
            "{bad:?}"
        );
        assert_eq!(bad[1].1, "0.3,2");
        assert!(bad[1].2.to_string().contains("2 cells"), "{bad:?}");
        assert!(bad[2].2.to_string().contains("goes back"), "{bad:?}");
        assert_eq!(f.counters.malformed_lines, 3);
    }

    #[test]
    fn quoted_cells_with_the_delimiter_inside_are_one_decimal_comma_cell() {
        let mut s = spec();
        s.force_unit = Some(ForceUnit::Newton);
        let mut f = Follower::new(s).unwrap();
        let e = f
            .feed(b"Time,Fx,Dx\n\"4,5\",\"450,5\",\"0,25\"\n5,\"510\",0.5\n")
            .unwrap();
        assert!(malformed(&e).is_empty(), "{e:?}");
        let r = rows(&e);
        assert_eq!(
            r.iter()
                .map(|r| (r.t_s, r.force_n[0], r.displacement_mm[0]))
                .collect::<Vec<_>>(),
            [
                (4.5, Some(450.5), Some(0.25)),
                (5.0, Some(510.0), Some(0.5))
            ]
        );
    }

    #[test]
    fn a_row_with_an_extra_or_a_missing_cell_is_malformed_not_read() {
        let mut f = Follower::new(spec()).unwrap();
        let e = f.feed(b"Time,Fx,Dx\n5,1,510,2\n6,1\n7,2,3\n").unwrap();
        assert_eq!(rows(&e).iter().map(|r| r.t_s).collect::<Vec<_>>(), [7.0]);
        let bad = malformed(&e);
        assert_eq!(
            bad.iter().map(|b| (b.0, b.2.clone())).collect::<Vec<_>>(),
            [
                (
                    2,
                    RowError::CellCount {
                        found: 4,
                        expected: 3
                    }
                ),
                (
                    3,
                    RowError::CellCount {
                        found: 2,
                        expected: 3
                    }
                )
            ]
        );
        assert_eq!(f.counters.malformed_lines, 2);
    }

    #[test]
    fn a_utf8_bom_before_the_header_is_dropped() {
        let mut f = Follower::new(spec()).unwrap();
        let e = f.feed(b"\xEF\xBB\xBFTime,Fx,Dx\r\n1,2,3\r\n").unwrap();
        assert_eq!(e[0], LineEvent::Header, "{e:?}");
        assert_eq!(rows(&e).len(), 1);
        assert_eq!(
            f.layout().unwrap().describe(),
            "Time (cell 1), Fx (cell 2), Dx (cell 3)"
        );
        // After a truncation the file starts again, with its BOM.
        f.start_over();
        let e = f.feed(b"\xEF\xBB\xBF\"Time\",Fx,Dx\n").unwrap();
        assert_eq!(e, [LineEvent::Header]);
    }

    #[test]
    fn an_over_long_line_fed_in_pieces_is_counted_reported_cut_and_never_held() {
        let mut f = Follower::new(spec()).unwrap();
        f.feed(b"Time,Fx,Dx\n1,1,1\n2,").unwrap();
        let piece = vec![b'5'; 100_000];
        for _ in 0..100 {
            assert!(f.feed(&piece).unwrap().is_empty());
            assert!(
                f.pending_bytes() <= lines::LINE_CAP_BYTES,
                "{}",
                f.pending_bytes()
            );
        }
        assert_eq!(f.unfinished_line_bytes(), 2 + 100 * 100_000);
        let e = f.feed(b"\n3,1,1\n").unwrap();
        let bad = malformed(&e);
        assert_eq!(bad.len(), 1, "{e:?}");
        assert_eq!(bad[0].0, 3);
        assert_eq!(
            *bad[0].2,
            RowError::TooLong {
                len_bytes: 2 + 100 * 100_000,
                cap_bytes: lines::LINE_CAP_BYTES
            }
        );
        assert!(bad[0].1.starts_with("2,555") && bad[0].1.ends_with('…'));
        assert!(bad[0].1.chars().count() <= malformed::EXCERPT_CHARS + 1);
        assert_eq!(rows(&e)[0].t_s, 3.0);
        assert_eq!(f.counters.malformed_lines, 1);
    }

    #[test]
    fn a_header_that_cannot_be_read_stops_the_follow_naming_it() {
        let mut f = Follower::new(spec()).unwrap();
        let e = f.feed(b"\"Time,Fx,Dx\n").unwrap_err();
        assert!(
            matches!(&e, CsvError::BadHeader { header, why: RowError::UnclosedQuote { .. } } if header.starts_with("\"Time")),
            "{e}"
        );
    }

    #[test]
    fn crlf_lines_and_units_in_the_header() {
        let mut s = spec();
        s.time_unit = None;
        s.force_unit = None;
        s.displacement_unit = None;
        let mut f = Follower::new(s).unwrap();
        let e = f
            .feed(b"\"Time (ms)\",Fx [N],Dx (mm),Other\r\n250,1200,0.5,x\r\n")
            .unwrap();
        let r = rows(&e);
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].t_s, 0.25);
        assert_eq!(r[0].force_n[0], Some(1200.0));
        assert_eq!(r[0].displacement_mm[0], Some(0.5));
    }

    #[test]
    fn a_missing_column_is_an_error_naming_it_and_the_header() {
        let mut s = spec();
        s.force[1] = Some(ColumnSpec::new("Fy", None));
        let mut f = Follower::new(s).unwrap();
        let e = f
            .feed(b"Time (s),Fx (kN),Dx (mm)\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("\"Fy\"") && e.contains("Time (s)"), "{e}");
    }

    #[test]
    fn truncation_starts_over_at_a_header() {
        let mut f = Follower::new(spec()).unwrap();
        f.feed(b"Time,Fx,Dx\n5,1,1\n6,1,").unwrap();
        f.start_over();
        let e = f.feed(b"Time,Fx,Dx\n0,2,2\n").unwrap();
        assert_eq!(rows(&e)[0].t_s, 0.0);
        assert_eq!(f.counters.restarts, 1);
    }
}
