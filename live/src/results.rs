//! The results folder of a run, `<results_dir>/<date-time>/`: what goes where, and how it is
//! written (appended and flushed per row, or whole files atomically: temporary sibling, then
//! rename), so a run killed at any moment keeps everything it had.

use anyhow::Context;
use std::path::{Path, PathBuf};

pub mod previous;

/// Paths of one run's results.
#[derive(Clone, Debug)]
pub struct ResultsDir {
    pub root: PathBuf,
}

impl ResultsDir {
    /// Creates `<parent>/<local date-time>` (with a suffix if it exists already).
    pub fn create_dated(parent: &Path) -> anyhow::Result<ResultsDir> {
        let stamp = local_timestamp();
        for k in 0..100 {
            let name = if k == 0 {
                stamp.clone()
            } else {
                format!("{stamp}_{k}")
            };
            let root = parent.join(name);
            match std::fs::create_dir_all(parent).and_then(|_| std::fs::create_dir(&root)) {
                Ok(()) => return ResultsDir::at(&root),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => {
                    return Err(e).with_context(|| format!("cannot create {}", root.display()))
                }
            }
        }
        anyhow::bail!("{}: too many runs this second", parent.display())
    }

    /// Uses `root` (created if missing; its files are overwritten, and the resume state of
    /// an earlier run there is removed: this run's children start afresh, and only their own
    /// restarts resume).
    pub fn at(root: &Path) -> anyhow::Result<ResultsDir> {
        for dir in [root.to_path_buf(), root.join("fields"), root.join("logs")] {
            std::fs::create_dir_all(&dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
        }
        let results = ResultsDir {
            root: root.to_path_buf(),
        };
        for state in [results.rig_state(), results.correlator_state()] {
            match std::fs::remove_dir_all(&state) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    return Err(e).with_context(|| format!("cannot remove {}", state.display()))
                }
                _ => {}
            }
        }
        match std::fs::remove_file(results.journal()) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(e)
                    .with_context(|| format!("cannot remove {}", results.journal().display()))
            }
            _ => {}
        }
        Ok(results)
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.root.join(name)
    }

    pub fn config(&self) -> PathBuf {
        self.path("config.toml")
    }
    pub fn rig_csv(&self) -> PathBuf {
        self.path("rig.csv")
    }
    pub fn frames_csv(&self) -> PathBuf {
        self.path("frames.csv")
    }
    /// A followed machine CSV's counts (rows, malformed lines, restarts), kept by the rig.
    pub fn machine_csv_json(&self) -> PathBuf {
        self.path("machine_csv.json")
    }
    /// What the link (`[link] start_with_run`) carried and lost, kept by the link as it goes.
    pub fn link_counts_json(&self) -> PathBuf {
        self.path("link_counts.json")
    }
    pub fn identification_json(&self) -> PathBuf {
        self.path("identification.json")
    }
    pub fn journal(&self) -> PathBuf {
        self.path("identification_points.csv")
    }
    /// The field route's states with their contributions to its best fit (the identifier
    /// writes it at its end; `stretch_states.png` colours them).
    pub fn states_csv(&self) -> PathBuf {
        self.path("states.csv")
    }
    /// The settings a child of the run was started with (`settings/<role>.json`).
    pub fn settings_file(&self, role: &str) -> PathBuf {
        self.root.join("settings").join(format!("{role}.json"))
    }
    pub fn correlator_state(&self) -> PathBuf {
        self.path("correlator_state")
    }
    pub fn rig_state(&self) -> PathBuf {
        self.path("rig_state")
    }
    pub fn fields(&self) -> PathBuf {
        self.path("fields")
    }
    pub fn logs(&self) -> PathBuf {
        self.path("logs")
    }
    pub fn summary_json(&self) -> PathBuf {
        self.path("summary.json")
    }

    /// The files a run writes at the top of its folder (`config.toml` first of all): any of
    /// them present means the folder holds a run ([`previous::set_aside`]).
    pub fn run_files(&self) -> [PathBuf; 6] {
        [
            self.config(),
            self.summary_json(),
            self.frames_csv(),
            self.rig_csv(),
            self.identification_json(),
            self.journal(),
        ]
    }
}

/// `YYYY-MM-DD_HHMMSS` in local time.
pub fn local_timestamp() -> String {
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as libc::time_t)
        .unwrap_or(0);
    // SAFETY: localtime_r writes into the zeroed tm we own; `now` is a valid time_t.
    let mut tm: libc::tm = unsafe { std::mem::zeroed() };
    let ok = unsafe { !libc::localtime_r(&now, &mut tm).is_null() };
    if !ok {
        return format!("run_{now}");
    }
    format!(
        "{:04}-{:02}-{:02}_{:02}{:02}{:02}",
        tm.tm_year + 1900,
        tm.tm_mon + 1,
        tm.tm_mday,
        tm.tm_hour,
        tm.tm_min,
        tm.tm_sec
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dated_folders_never_collide_and_a_folder_that_cannot_be_made_is_named() {
        let parent = std::env::temp_dir().join(format!("results_test_{}", std::process::id()));
        let a = ResultsDir::create_dated(&parent).unwrap();
        let b = ResultsDir::create_dated(&parent).unwrap();
        assert_ne!(a.root, b.root);
        assert!(a.fields().is_dir() && a.logs().is_dir());
        std::fs::write(a.config(), "x = 1\n").unwrap();
        let error = ResultsDir::at(&a.config().join("below_a_file")).unwrap_err();
        assert!(
            format!("{error:#}").starts_with(&format!("cannot create {}", a.config().display())),
            "{error:#}"
        );
        assert_eq!(local_timestamp().len(), 17);
        std::fs::remove_dir_all(&parent).unwrap();
    }
}
