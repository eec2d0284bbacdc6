//! A results folder given again (`run --out DIR`) keeps the earlier run whole: when DIR holds
//! a run's files, everything in it (but earlier `previous-*` folders) is moved into
//! `DIR/previous-<local date-time>/` before this run writes anything. So a run never leaves
//! another run's verdict (`summary.json`) or data (`fields/`) beside its own, and nothing is
//! lost.

use super::{local_timestamp, ResultsDir};
use anyhow::Context;
use std::path::{Path, PathBuf};

/// Prefix of the folders that hold earlier runs.
pub const PREFIX: &str = "previous-";

/// Moves an earlier run's files in `root` into `root/previous-<date-time>/` (a suffix if that
/// exists); returns that folder, or None when `root` is missing or holds no run's file.
pub fn set_aside(root: &Path) -> anyhow::Result<Option<PathBuf>> {
    let layout = ResultsDir {
        root: root.to_path_buf(),
    };
    if !layout.run_files().iter().any(|f| f.exists()) {
        return Ok(None);
    }
    let entries: Vec<_> = std::fs::read_dir(root)
        .with_context(|| format!("cannot list {}", root.display()))?
        .collect::<Result<_, _>>()
        .with_context(|| format!("cannot list {}", root.display()))?;
    let stamp = local_timestamp();
    let aside = (0..100)
        .map(|k| match k {
            0 => root.join(format!("{PREFIX}{stamp}")),
            k => root.join(format!("{PREFIX}{stamp}_{k}")),
        })
        .find(|dir| std::fs::create_dir(dir).is_ok())
        .with_context(|| {
            format!(
                "cannot create a folder {}{PREFIX}{stamp} to move the earlier run into",
                root.display()
            )
        })?;
    for entry in entries {
        let name = entry.file_name();
        if name.to_string_lossy().starts_with(PREFIX) {
            continue;
        }
        let to = aside.join(&name);
        std::fs::rename(entry.path(), &to).with_context(|| {
            format!(
                "cannot move the earlier run's {} into {}",
                entry.path().display(),
                aside.display()
            )
        })?;
    }
    Ok(Some(aside))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_earlier_run_is_moved_aside_whole_and_a_fresh_folder_is_left_alone() {
        let root = std::env::temp_dir().join(format!("previous_test_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        // Missing, then empty: nothing to move.
        assert_eq!(set_aside(&root).unwrap(), None);
        std::fs::create_dir_all(root.join("fields")).unwrap();
        assert_eq!(set_aside(&root).unwrap(), None);
        // A completed run, an older one set aside before, and a file of the user's.
        std::fs::write(root.join("summary.json"), r#"{"ending": "completed"}"#).unwrap();
        std::fs::write(root.join("frames.csv"), "frame_id\n0\n").unwrap();
        std::fs::write(root.join("fields/field_000000.csv"), "x\n").unwrap();
        std::fs::write(root.join("notes.txt"), "mine\n").unwrap();
        std::fs::create_dir(root.join("previous-old")).unwrap();
        let aside = set_aside(&root).unwrap().expect("moved");
        assert!(aside.starts_with(&root), "{}", aside.display());
        let mut left: Vec<String> = std::fs::read_dir(&root)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        let aside_name = aside.file_name().unwrap().to_string_lossy().into_owned();
        let mut expected = vec!["previous-old".to_string(), aside_name];
        expected.sort();
        assert_eq!(left, expected);
        for (file, text) in [
            ("summary.json", r#"{"ending": "completed"}"#),
            ("frames.csv", "frame_id\n0\n"),
            ("fields/field_000000.csv", "x\n"),
            ("notes.txt", "mine\n"),
        ] {
            assert_eq!(std::fs::read_to_string(aside.join(file)).unwrap(), text);
        }
        // Twice in the same second: another folder.
        std::fs::write(root.join("summary.json"), "{}").unwrap();
        let again = set_aside(&root).unwrap().expect("moved");
        assert_ne!(again, aside);
        std::fs::remove_dir_all(&root).unwrap();
    }
}
