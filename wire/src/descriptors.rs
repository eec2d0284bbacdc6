//! The process's file descriptors and their limit (`RLIMIT_NOFILE`, `ulimit -n`): every file,
//! shared-memory segment, connection and event a process opens holds one. Free of iceoryx2, so
//! a file error can name them too.

/// The soft limit of open file descriptors, None when unlimited.
pub fn limit() -> Option<u64> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes into the struct we own.
    let rc = unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut limit) };
    (rc == 0 && limit.rlim_cur != libc::RLIM_INFINITY).then_some(limit.rlim_cur)
}

/// File descriptors open now (None: unknown); the limit when not even one is left to list them.
pub fn open() -> Option<u64> {
    match std::fs::read_dir("/proc/self/fd") {
        // Less the listing's own descriptor.
        Ok(entries) => Some((entries.count() as u64).saturating_sub(1)),
        Err(e) if e.raw_os_error() == Some(libc::EMFILE) => limit(),
        Err(_) => None,
    }
}

/// What to say of `open` descriptors out of `limit`: exhausted, naming the limit and how to
/// raise it.
pub fn exhausted_text(open: Option<u64>, limit: Option<u64>) -> String {
    let known = |n: Option<u64>| n.map_or("?".to_string(), |n| n.to_string());
    format!(
        "file descriptors exhausted: {} open of the limit {} (RLIMIT_NOFILE; raise it with \
         `ulimit -n`)",
        known(open),
        known(limit)
    )
}

/// After an I/O error of running out of descriptors, which and their limit ("" otherwise).
pub fn note_for(reason: &std::io::Error) -> String {
    match reason.raw_os_error() {
        // EMFILE: this process holds as many as its limit allows.
        Some(libc::EMFILE) => {
            let limit = limit();
            format!("; {}", exhausted_text(limit, limit))
        }
        Some(libc::ENFILE) => "; the system's table of open files is full (ENFILE)".into(),
        _ => String::new(),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn this_process_has_descriptors_open_below_its_limit() {
        let open = super::open().unwrap();
        assert!(open >= 3, "{open}");
        if let Some(limit) = super::limit() {
            assert!(open < limit, "{open} of {limit}");
        }
        assert_eq!(
            super::exhausted_text(Some(64), Some(64)),
            "file descriptors exhausted: 64 open of the limit 64 (RLIMIT_NOFILE; raise it with \
             `ulimit -n`)"
        );
    }
}
