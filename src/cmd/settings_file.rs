//! `--settings FILE`: a process's settings as `dicstream run` writes them for its children
//! (`<results>/settings/<role>.json`), the JSON of the same struct the command line's flags
//! make. A user can start a child by hand on the file of a run.

use anyhow::Context;
use std::path::Path;

/// Reads the settings of `path`; an unknown key, a missing one or a bad value is an error
/// naming the file, the key and where it is.
pub fn read<T: serde::de::DeserializeOwned>(path: &Path) -> anyhow::Result<T> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the settings file {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("settings file {}", path.display()))
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_bad_settings_file_is_refused_naming_the_file_and_the_key() {
        let dir = std::env::temp_dir().join(format!("settings_file_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("identifier.json");
        let missing = super::read::<identifier::process::ProcessConfig>(&file).unwrap_err();
        assert!(
            format!("{missing:#}").starts_with("cannot read the settings file"),
            "{missing:#}"
        );
        std::fs::write(
            &file,
            r#"{"instance": "i", "output_json": "a.json", "journal": null,
                "max_fields": null, "colour": 3}"#,
        )
        .unwrap();
        let unknown = format!(
            "{:#}",
            super::read::<identifier::process::ProcessConfig>(&file).unwrap_err()
        );
        assert!(
            unknown.contains("identifier.json") && unknown.contains("unknown field `colour`"),
            "{unknown}"
        );
        std::fs::write(
            &file,
            r#"{"instance": "i", "output_json": "a.json", "journal": null,
                "max_fields": null, "online": {"models": ["yeoh", "no-such-model"]}}"#,
        )
        .unwrap();
        let model = format!(
            "{:#}",
            super::read::<identifier::process::ProcessConfig>(&file).unwrap_err()
        );
        assert!(model.contains("no-such-model"), "{model}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
