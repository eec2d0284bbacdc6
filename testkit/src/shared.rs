//! The reference data the tests read (DIC Challenge samples 5 and 14 with their imposed
//! displacements, Treloar's curves): `testdata/` in the repository (5.6 MB, copied from the
//! project's shared data folder with its READMEs), so a clone has it.

use std::path::PathBuf;

/// Environment variable: when `1`, a missing data folder fails the test (CI sets it,
/// `.ci/run`); otherwise the test is skipped with a message on stderr.
pub const REQUIRE_SHARED_VAR: &str = "DICSTREAM_REQUIRE_SHARED";

/// Environment variable: another location of the data folder (default `<workspace>/testdata`).
pub const SHARED_DATA_VAR: &str = "DICSTREAM_SHARED_DATA";

fn data_root() -> PathBuf {
    match std::env::var_os(SHARED_DATA_VAR) {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../testdata")),
    }
}

fn required() -> bool {
    std::env::var(REQUIRE_SHARED_VAR).is_ok_and(|v| v == "1")
}

/// `relative` (e.g. `dic-challenge/sample5`, or `""` for the folder itself) inside the shared
/// data folder, when it exists. When it does not: a panic naming it under
/// `DICSTREAM_REQUIRE_SHARED=1`, else `None` and "skipped: … not found" on stderr (the caller
/// returns: the test passes without checking anything).
pub fn shared_data(relative: &str) -> Option<PathBuf> {
    resolve(&data_root(), relative, required())
}

fn resolve(root: &std::path::Path, relative: &str, required: bool) -> Option<PathBuf> {
    let path = root.join(relative);
    if path.exists() {
        return Some(path);
    }
    let shown = path.display();
    if required {
        panic!(
            "shared data {shown} not found, and {REQUIRE_SHARED_VAR}=1 requires it: put the \
             repository's testdata/ back (git checkout testdata) or point {SHARED_DATA_VAR} at a copy"
        );
    }
    eprintln!(
        "skipped: shared data {shown} not found (set {SHARED_DATA_VAR}, or {REQUIRE_SHARED_VAR}=1 to fail instead)"
    );
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_existing_path_is_returned() {
        let root = std::env::temp_dir();
        assert_eq!(resolve(&root, "", false), Some(root.join("")));
    }

    #[test]
    fn a_missing_folder_is_skipped_when_not_required() {
        let root = std::env::temp_dir().join("dicstream-no-such-shared-folder");
        assert_eq!(resolve(&root, "treloar1944", false), None);
    }

    #[test]
    #[should_panic(expected = "DICSTREAM_REQUIRE_SHARED=1 requires it")]
    fn a_missing_folder_fails_when_required() {
        let root = std::env::temp_dir().join("dicstream-no-such-shared-folder");
        resolve(&root, "treloar1944", true);
    }
}
