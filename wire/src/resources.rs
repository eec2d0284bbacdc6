//! The system resources iceoryx2 needs, so that an error from it names them: file descriptors
//! (every shared-memory segment, connection and event a process opens holds one; the limit is
//! `RLIMIT_NOFILE`, `ulimit -n`) and the free space of `/dev/shm`.

use std::fmt;

/// Descriptors this close to the limit count as exhausted: a failed connection gives back
/// the few it had opened before the one that failed.
pub const DESCRIPTOR_MARGIN: u64 = 8;

/// What the process has, read when an error needs it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Resources {
    /// File descriptors open (None: unknown).
    pub open_descriptors: Option<u64>,
    /// The soft limit of `RLIMIT_NOFILE` (None: unlimited or unknown).
    pub descriptor_limit: Option<u64>,
    /// Free bytes of `/dev/shm` (None: unknown).
    pub shm_free_bytes: Option<u64>,
}

impl Resources {
    /// Reads them now.
    pub fn now() -> Resources {
        Resources {
            open_descriptors: crate::descriptors::open(),
            descriptor_limit: crate::descriptors::limit(),
            shm_free_bytes: crate::shm::free_bytes(crate::shm::SHM_PATH).ok(),
        }
    }

    /// Open descriptors within [`DESCRIPTOR_MARGIN`] of the limit.
    pub fn descriptors_exhausted(&self) -> bool {
        matches!(
            (self.open_descriptors, self.descriptor_limit),
            (Some(open), Some(limit)) if open + DESCRIPTOR_MARGIN >= limit
        )
    }
}

impl fmt::Display for Resources {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.descriptors_exhausted() {
            f.write_str(&crate::descriptors::exhausted_text(
                self.open_descriptors,
                self.descriptor_limit,
            ))?;
        } else {
            write!(
                f,
                "file descriptors: {} open of the limit {} (RLIMIT_NOFILE)",
                self.open_descriptors
                    .map_or("?".to_string(), |n| n.to_string()),
                self.descriptor_limit
                    .map_or("unlimited".to_string(), |n| n.to_string())
            )?;
        }
        match self.shm_free_bytes {
            Some(free) => write!(
                f,
                "; {}: {:.1} MiB free",
                crate::shm::SHM_PATH,
                free as f64 / 1048576.0
            ),
            None => write!(f, "; {}: free space unknown", crate::shm::SHM_PATH),
        }
    }
}

/// A subscriber that could not connect to a publisher: it would never receive its samples.
/// The process stops with [`crate::exit::RESOURCES`], naming the resources it had.
#[derive(Debug, thiserror::Error)]
#[error("cannot connect to a publisher of {service} ({detail}): the process would never receive its samples; {resources}")]
pub struct ConnectionError {
    /// The service.
    pub service: String,
    /// iceoryx2's error.
    pub detail: String,
    pub resources: Resources,
}

/// A WaitSet (the process's sleep on its services and signals) that could not be created;
/// for want of resources (descriptors), the process stops with [`crate::exit::RESOURCES`],
/// naming them.
#[derive(Debug, thiserror::Error)]
#[error("cannot create a WaitSet ({detail}); {resources}")]
pub struct WaitSetError {
    /// iceoryx2's error.
    pub detail: String,
    /// iceoryx2 said its resources were insufficient.
    pub out_of_resources: bool,
    pub resources: Resources,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptors_near_the_limit_are_named_as_exhausted_with_the_limit() {
        let full = Resources {
            open_descriptors: Some(60),
            descriptor_limit: Some(64),
            shm_free_bytes: Some(512 << 20),
        };
        assert!(full.descriptors_exhausted());
        let text = full.to_string();
        assert!(
            text.contains("file descriptors exhausted: 60 open of the limit 64")
                && text.contains("ulimit -n")
                && text.contains("/dev/shm: 512.0 MiB free"),
            "{text}"
        );
        let plenty = Resources {
            open_descriptors: Some(20),
            ..full
        };
        assert!(!plenty.descriptors_exhausted());
        assert!(plenty
            .to_string()
            .starts_with("file descriptors: 20 open of the limit 64"));
        let now = Resources::now();
        assert!(now.open_descriptors.is_some_and(|n| n >= 3), "{now:?}");
    }
}
