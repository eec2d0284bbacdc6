//! Following a test machine's own force log: a CSV file its software appends rows to while
//! the test runs. Pure (no IPC): [`columns`] finds the configured columns in the header and
//! converts their units, [`lines`] cuts appended bytes into whole lines (a partial last line
//! waits for its newline), [`tail`] reads what was appended to the file since the last poll
//! (waiting for a file that does not exist yet, noticing truncation and rotation), and
//! [`Follower`] ties them: bytes in, rows or reported malformed lines out. The process shell
//! that publishes the rows on `rig/state` is [`process`] (feature `process`).

pub mod clock;
pub mod columns;
pub mod delimiter;
pub mod lines;
#[cfg(feature = "process")]
pub mod process;
pub mod tail;

pub use columns::{ColumnSpec, CsvColumns, CsvError, Layout, Row};
pub use lines::LineSplitter;
pub use tail::{FileTail, TailRead};

/// What one complete line gave.
#[derive(Clone, Debug, PartialEq)]
pub enum LineEvent {
    /// The header was found: the columns are known.
    Header,
    Row(Row),
    /// A line that is not a row (skipped, counted): its 1-based line number, text and why.
    Malformed {
        line_no: u64,
        text: String,
        why: String,
    },
}

/// Counters of a follow.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FollowCounters {
    pub rows: u64,
    pub malformed: u64,
    /// Times the file was truncated or replaced (each starts over at its header).
    pub restarts: u64,
}

/// Whole lines in, header then rows out. A missing column is an error (the follow cannot go
/// on); a row that does not parse is reported and skipped.
#[derive(Debug)]
pub struct Follower {
    spec: CsvColumns,
    layout: Option<Layout>,
    lines: LineSplitter,
    line_no: u64,
    last_time_s: Option<f64>,
    pub counters: FollowCounters,
}

impl Follower {
    pub fn new(spec: CsvColumns) -> Result<Follower, CsvError> {
        spec.validate()?;
        Ok(Follower {
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
            let text = String::from_utf8_lossy(&line);
            let text = text.trim_end_matches('\r');
            if text.trim().is_empty() {
                continue;
            }
            match &self.layout {
                None => {
                    self.layout = Some(Layout::from_header(text, &self.spec)?);
                    events.push(LineEvent::Header);
                }
                Some(layout) => {
                    let parsed = layout
                        .parse_row(text)
                        .and_then(|row| match self.last_time_s {
                            Some(last) if row.t_s < last => Err(format!(
                                "time {} s goes back (previous row {last} s)",
                                row.t_s
                            )),
                            _ => Ok(row),
                        });
                    match parsed {
                        Ok(row) => {
                            self.last_time_s = Some(row.t_s);
                            self.counters.rows += 1;
                            events.push(LineEvent::Row(row));
                        }
                        Err(why) => {
                            self.counters.malformed += 1;
                            events.push(LineEvent::Malformed {
                                line_no: self.line_no,
                                text: text.chars().take(200).collect(),
                                why,
                            });
                        }
                    }
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

    /// Bytes of a partial last line waiting for their newline.
    pub fn pending_bytes(&self) -> usize {
        self.lines.pending_len()
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

    #[test]
    fn a_malformed_line_is_reported_skipped_and_counted() {
        let mut f = Follower::new(spec()).unwrap();
        let e = f
            .feed(b"Time,Fx,Dx\n0.1,1,0\n0.2,oops,0\n0.3,2\n0.05,1,1\n0.4,3,0.3\n")
            .unwrap();
        let r = rows(&e);
        assert_eq!(r.iter().map(|r| r.t_s).collect::<Vec<_>>(), [0.1, 0.4]);
        let bad: Vec<(u64, &str)> = e
            .iter()
            .filter_map(|e| match e {
                LineEvent::Malformed { line_no, why, .. } => Some((*line_no, why.as_str())),
                _ => None,
            })
            .collect();
        assert_eq!(bad.len(), 3, "{bad:?}");
        assert_eq!(bad[0].0, 3);
        assert!(
            bad[0].1.contains("Fx") && bad[0].1.contains("oops"),
            "{bad:?}"
        );
        assert!(bad[1].1.contains("2 cells"), "{bad:?}");
        assert!(bad[2].1.contains("goes back"), "{bad:?}");
        assert_eq!(f.counters.malformed, 3);
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
