//! The rig's resume journal: where a run of the rig had got to, so that a restarted rig goes
//! on with the same test instead of starting the campaign over. The simulation is
//! deterministic (seeded noise, simulated time), so the journal holds a position, not a state:
//! how many publication periods were run, and what the machine looked like then (time, step,
//! actuator positions, bit for bit) to check that a replay of as many periods reached the very
//! same state. It also says how much of the log (`rig.csv`) was written whole, and carries a
//! fingerprint of the settings (a folder written with other settings is refused), and the
//! count of commands accepted over `rig/command` (those are not replayed: a rig that took
//! commands cannot resume). Pure: text in, text out; the shell writes it atomically.

use crate::snapshot::RigSnapshot;

/// Why a journal could not be read, or holds figures no run of the rig could have written.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum JournalError {
    #[error("not UTF-8 text (byte {valid_up_to})")]
    NotText { valid_up_to: usize },
    #[error("no {key}")]
    Missing { key: &'static str },
    #[error("{key} = {value:?} is not a count")]
    NotACount { key: &'static str, value: String },
    #[error("{key} = {value:?} is not hexadecimal")]
    NotHexadecimal { key: &'static str, value: String },
    #[error("step = {step} is not periods = {periods} times the {steps_per_period} control steps of a period")]
    StepsPerPeriod {
        periods: u64,
        step: u64,
        steps_per_period: u64,
    },
    #[error("t_s = {t_s} s is not step = {step} times the control period")]
    Time { t_s: f64, step: u64 },
    #[error("{count} actuator positions, not {expected} finite ones")]
    Positions { count: usize, expected: usize },
    #[error("rows_logged = {rows_logged} is not step = {step} / {log_every} (one row every {log_every} control steps)")]
    RowsLogged {
        rows_logged: u64,
        step: u64,
        log_every: u64,
    },
}

/// How a run of the rig counts, which every journal it writes fits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cadence {
    /// Control steps per publication period.
    pub steps_per_period: u64,
    /// Control steps per log row.
    pub log_every: u64,
    /// The control period (s).
    pub dt_s: f64,
    pub actuators: usize,
}

/// How a replay differs from where the journal says the rig was.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Mismatch {
    #[error("the replay reached step {replayed_step} (t = {replayed_t_s} s), the journal says step {step} (t = {t_s} s)")]
    Step {
        replayed_step: u64,
        replayed_t_s: f64,
        step: u64,
        t_s: f64,
    },
    #[error("the replay's actuator positions {replayed_mm:?} mm differ from the journal's {journal_mm:?} mm")]
    Positions {
        replayed_mm: Vec<f64>,
        journal_mm: Vec<f64>,
    },
}

/// Where the rig had got to.
#[derive(Clone, Debug, PartialEq)]
pub struct Journal {
    /// Fingerprint of the settings that make the simulation what it is.
    pub settings: u64,
    /// Publication periods run (also the next `rig/state` sample id).
    pub periods: u64,
    /// Control steps run.
    pub step: u64,
    pub t_s: f64,
    /// Actuator positions (mm), compared bit for bit after a replay.
    pub positions_mm: Vec<f64>,
    /// Rows in the log and its length in bytes, all whole.
    pub rows_logged: u64,
    pub log_bytes: u64,
    /// Commands accepted over `rig/command` so far.
    pub commands_accepted: u64,
}

/// The journal's file name in a state folder.
pub const FILE_NAME: &str = "rig.journal";

impl Journal {
    /// The positions of `snapshot` as the journal keeps them.
    pub fn positions_of(snapshot: &RigSnapshot) -> Vec<f64> {
        snapshot.actuators.iter().map(|a| a.position_mm).collect()
    }

    pub fn to_text(&self) -> String {
        let bits = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{:016x}", x.to_bits()))
                .collect::<Vec<_>>()
                .join(",")
        };
        format!(
            "# dicstream rig resume journal\nsettings = {:016x}\nperiods = {}\nstep = {}\n\
             t_s_bits = {:016x}\npositions_mm_bits = {}\nrows_logged = {}\nlog_bytes = {}\n\
             commands_accepted = {}\n",
            self.settings,
            self.periods,
            self.step,
            self.t_s.to_bits(),
            bits(&self.positions_mm),
            self.rows_logged,
            self.log_bytes,
            self.commands_accepted
        )
    }

    /// [`Journal::parse`] of a file's bytes, which must be UTF-8 text.
    pub fn parse_bytes(bytes: &[u8]) -> Result<Journal, JournalError> {
        let text = std::str::from_utf8(bytes).map_err(|e| JournalError::NotText {
            valid_up_to: e.valid_up_to(),
        })?;
        Journal::parse(text)
    }

    pub fn parse(text: &str) -> Result<Journal, JournalError> {
        let value = |key: &'static str| -> Result<&str, JournalError> {
            text.lines()
                .filter_map(|l| l.split_once('='))
                .find(|(k, _)| k.trim() == key)
                .map(|(_, v)| v.trim())
                .ok_or(JournalError::Missing { key })
        };
        let int = |value: &str, key: &'static str| {
            value.parse::<u64>().map_err(|_| JournalError::NotACount {
                key,
                value: value.to_string(),
            })
        };
        let hex = |value: &str, key: &'static str| {
            u64::from_str_radix(value, 16).map_err(|_| JournalError::NotHexadecimal {
                key,
                value: value.to_string(),
            })
        };
        let positions = value("positions_mm_bits")?
            .split(',')
            .filter(|s| !s.is_empty())
            .map(|s| hex(s, "positions_mm_bits").map(f64::from_bits))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Journal {
            settings: hex(value("settings")?, "settings")?,
            periods: int(value("periods")?, "periods")?,
            step: int(value("step")?, "step")?,
            t_s: f64::from_bits(hex(value("t_s_bits")?, "t_s_bits")?),
            positions_mm: positions,
            rows_logged: int(value("rows_logged")?, "rows_logged")?,
            log_bytes: int(value("log_bytes")?, "log_bytes")?,
            commands_accepted: int(value("commands_accepted")?, "commands_accepted")?,
        })
    }

    /// Checks that the journal's figures fit together as a run of `cadence` writes them (a
    /// corrupt or edited figure, such as an absurd `periods`, is refused before any replay).
    pub fn check(&self, cadence: &Cadence) -> Result<(), JournalError> {
        if self.periods.checked_mul(cadence.steps_per_period) != Some(self.step) {
            return Err(JournalError::StepsPerPeriod {
                periods: self.periods,
                step: self.step,
                steps_per_period: cadence.steps_per_period,
            });
        }
        // The rig's own time: step × dt, bit for bit.
        if self.t_s.to_bits() != (self.step as f64 * cadence.dt_s).to_bits() {
            return Err(JournalError::Time {
                t_s: self.t_s,
                step: self.step,
            });
        }
        if self.positions_mm.len() != cadence.actuators
            || !self.positions_mm.iter().all(|p| p.is_finite())
        {
            return Err(JournalError::Positions {
                count: self.positions_mm.len(),
                expected: cadence.actuators,
            });
        }
        // A journal without a log (log_bytes 0) counts no rows.
        let rows = if self.log_bytes == 0 {
            0
        } else {
            self.step / cadence.log_every.max(1)
        };
        if self.rows_logged != rows {
            return Err(JournalError::RowsLogged {
                rows_logged: self.rows_logged,
                step: self.step,
                log_every: cadence.log_every,
            });
        }
        Ok(())
    }

    /// Why a replay that reached `snapshot` after `self.periods` periods is not where the
    /// journal says the rig was (None: it is, bit for bit).
    pub fn mismatch(&self, snapshot: &RigSnapshot) -> Option<Mismatch> {
        if snapshot.step != self.step || snapshot.t_s.to_bits() != self.t_s.to_bits() {
            return Some(Mismatch::Step {
                replayed_step: snapshot.step,
                replayed_t_s: snapshot.t_s,
                step: self.step,
                t_s: self.t_s,
            });
        }
        let replayed = Journal::positions_of(snapshot);
        if replayed.len() != self.positions_mm.len()
            || replayed
                .iter()
                .zip(&self.positions_mm)
                .any(|(a, b)| a.to_bits() != b.to_bits())
        {
            return Some(Mismatch::Positions {
                replayed_mm: replayed,
                journal_mm: self.positions_mm.clone(),
            });
        }
        None
    }
}

/// A fingerprint of settings given as text (their debug form): FNV-1a, stable across runs
/// and builds.
pub fn fingerprint(settings: &str) -> u64 {
    settings.bytes().fold(0xcbf29ce484222325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100000001b3)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_journal_reads_back_bit_for_bit() {
        let journal = Journal {
            settings: fingerprint("a"),
            periods: 1234,
            step: 12340,
            t_s: 2.468,
            positions_mm: vec![0.1 + 0.2, -1e-300, 3.0, f64::MIN_POSITIVE],
            rows_logged: 50,
            log_bytes: 12345,
            commands_accepted: 0,
        };
        let back = Journal::parse(&journal.to_text()).unwrap();
        assert_eq!(back, journal);
        assert_ne!(fingerprint("a"), fingerprint("b"));
        assert!(Journal::parse("periods = x").is_err());
        let missing = Journal::parse(&journal.to_text().replace("step = 12340\n", ""));
        assert_eq!(missing, Err(JournalError::Missing { key: "step" }));
        assert_eq!(missing.unwrap_err().to_string(), "no step");
    }
}
