//! Free space of `/dev/shm`, checked at start so a run fails with a clear error instead of a
//! SIGBUS in the middle (running out of a tmpfs shows up only when a page is first touched).

use crate::instance::InstanceError;

pub const SHM_PATH: &str = "/dev/shm";

/// Free bytes of the file system holding `path`.
pub fn free_bytes(path: &str) -> Result<u64, InstanceError> {
    let c_path = std::ffi::CString::new(path)
        .map_err(|_| InstanceError::Io(format!("bad path {path:?}")))?;
    // SAFETY: statvfs writes into a zeroed, properly sized struct; the path is NUL-terminated.
    let mut stat: libc::statvfs = unsafe { std::mem::zeroed() };
    let rc = unsafe { libc::statvfs(c_path.as_ptr(), &mut stat) };
    if rc != 0 {
        return Err(InstanceError::Io(format!(
            "cannot read the free space of {path}: {}",
            std::io::Error::last_os_error()
        )));
    }
    Ok(stat.f_bavail as u64 * stat.f_frsize as u64)
}

/// Fails with [`InstanceError::ShmSpace`] unless `path` has `needed_bytes` free.
pub fn ensure_free(path: &str, needed_bytes: u64) -> Result<(), InstanceError> {
    let free = free_bytes(path)?;
    if free < needed_bytes {
        return Err(InstanceError::ShmSpace {
            needed_bytes,
            free_bytes: free,
            path: path.to_string(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_more_than_is_free_with_a_clear_message() {
        let free = free_bytes(SHM_PATH).expect("statvfs /dev/shm");
        assert!(ensure_free(SHM_PATH, 1).is_ok());
        let error = ensure_free(SHM_PATH, free + (1 << 40))
            .unwrap_err()
            .to_string();
        assert!(error.contains("/dev/shm has"), "{error}");
        assert!(error.contains("MiB"), "{error}");
    }
}
