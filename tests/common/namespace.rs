//! A shell script run in a mount namespace of the test's own (`unshare`), where it may mount a
//! small tmpfs (a full disk, a full `/dev/shm`) that goes away with the namespace.

/// Runs `sh -c script` in a new mount namespace (in a user namespace of its own too, unless
/// root). None when no namespace can be made here: the test is then skipped, said on stderr
/// (under CI it fails instead).
pub fn run_in_mount_namespace(script: &str) -> Option<std::process::Output> {
    // SAFETY: geteuid has no preconditions.
    let root = unsafe { libc::geteuid() } == 0;
    let namespace = if root { "-m" } else { "-rm" };
    let probe = std::process::Command::new("unshare")
        .args([namespace, "true"])
        .status();
    if !probe.is_ok_and(|s| s.success()) {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must be able to mount a small tmpfs (unshare {namespace})"
        );
        eprintln!("skipped: cannot make a mount namespace here (unshare {namespace})");
        return None;
    }
    Some(
        std::process::Command::new("unshare")
            .args([namespace, "sh", "-c", script])
            .output()
            .expect("unshare"),
    )
}
