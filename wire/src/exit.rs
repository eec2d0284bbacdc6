//! Exit codes with a meaning between processes: `dicstream run` reads them to tell a death it
//! should restart from one it must not (a restart would fail the same way, or start a test
//! over). Codes from sysexits(3).

/// A results file could not be written (a full disk, a removed folder): the run stops.
pub const OUTPUT_FAILED: u8 = 74;
/// The rig could not resume its test safely from its journal: it unloaded and stopped.
pub const CANNOT_RESUME: u8 = 75;
/// The process could not get a system resource it needs (a subscriber that cannot connect to
/// a publisher, a file that cannot be opened: no file descriptor left, `/dev/shm` full): a
/// restart would fail the same way.
pub const RESOURCES: u8 = 71;
/// The process's configuration does not fit its input (a followed CSV without the configured
/// columns): a restart would fail the same way.
pub const CONFIG: u8 = 78;

/// An error that sets the process's exit code (the binary's `main` looks for it, and for a
/// [`crate::files::FileError`], in the error's chain).
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct ExitWith {
    pub code: u8,
    pub message: String,
}

/// The exit code an error asks for: an [`ExitWith`]'s, [`OUTPUT_FAILED`] for a file that
/// could not be written, [`RESOURCES`] for one that could not be for want of descriptors.
/// The error's sources are looked at too.
pub fn code_of(error: &(dyn std::error::Error + 'static)) -> Option<u8> {
    let mut next = Some(error);
    while let Some(error) = next {
        if let Some(exit) = error.downcast_ref::<ExitWith>() {
            return Some(exit.code);
        }
        if let Some(file) = error.downcast_ref::<crate::files::FileError>() {
            return Some(if file.is_out_of_descriptors() {
                RESOURCES
            } else {
                OUTPUT_FAILED
            });
        }
        #[cfg(feature = "ipc")]
        if error
            .downcast_ref::<crate::resources::WaitSetError>()
            .is_some_and(|w| w.out_of_resources)
        {
            return Some(RESOURCES);
        }
        #[cfg(feature = "ipc")]
        if error
            .downcast_ref::<crate::resources::ConnectionError>()
            .is_some()
            || matches!(
                error.downcast_ref::<crate::instance::InstanceError>(),
                Some(
                    crate::instance::InstanceError::Connection(_)
                        | crate::instance::InstanceError::OutOfResources { .. }
                )
            )
        {
            return Some(RESOURCES);
        }
        next = error.source();
    }
    None
}

/// `error` with a context, keeping the exit code it asks for (1 if none).
pub fn in_context(context: &str, error: &(dyn std::error::Error + 'static)) -> ExitWith {
    ExitWith {
        code: code_of(error).unwrap_or(1),
        message: format!("{context}: {error}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_error_keeps_its_code_through_a_context() {
        let file_error = crate::files::FileError {
            path: "rig.csv".into(),
            what: "write",
            reason: std::io::Error::from_raw_os_error(libc::ENOSPC),
        };
        let boxed: Box<dyn std::error::Error + Send + Sync> = Box::new(file_error);
        let exit = in_context("rig process", &*boxed);
        assert_eq!(exit.code, OUTPUT_FAILED);
        assert!(exit
            .message
            .starts_with("rig process: cannot write rig.csv"));
        // Out of descriptors: the process's resources, not the output, and said with the limit.
        let no_descriptor = crate::files::FileError {
            path: "identification.json".into(),
            what: "write",
            reason: std::io::Error::from_raw_os_error(libc::EMFILE),
        };
        let exit = in_context("identifier process", &no_descriptor);
        assert_eq!(exit.code, RESOURCES);
        assert!(
            exit.message
                .contains("cannot write identification.json: Too many open files")
                && exit.message.contains("file descriptors exhausted")
                && exit
                    .message
                    .contains("(RLIMIT_NOFILE; raise it with `ulimit -n`)"),
            "{}",
            exit.message
        );
        let other: Box<dyn std::error::Error + Send + Sync> = "no".into();
        assert_eq!(in_context("rig", &*other).code, 1);
    }

    #[cfg(feature = "ipc")]
    #[test]
    fn a_subscriber_that_cannot_connect_asks_for_resources_and_names_them() {
        /// A process error carrying the instance's error as its source, as the identifier's.
        #[derive(Debug, thiserror::Error)]
        #[error("{0}")]
        struct Wrapper(#[from] crate::instance::InstanceError);
        let error = Wrapper::from(crate::instance::InstanceError::from(
            crate::resources::ConnectionError {
                service: "fields".into(),
                detail: "UnableToMapSendersDataSegment(InternalError)".into(),
                resources: crate::resources::Resources {
                    open_descriptors: Some(64),
                    descriptor_limit: Some(64),
                    shm_free_bytes: Some(1 << 30),
                },
            },
        ));
        let exit = in_context("identifier process", &error);
        assert_eq!(exit.code, RESOURCES);
        assert!(
            exit.message.starts_with(
                "identifier process: cannot connect to a publisher of fields \
                 (UnableToMapSendersDataSegment(InternalError))"
            ) && exit
                .message
                .contains("file descriptors exhausted: 64 open of the limit 64"),
            "{}",
            exit.message
        );
    }

    #[cfg(feature = "ipc")]
    #[test]
    fn a_service_or_node_not_made_for_want_of_descriptors_asks_for_resources() {
        let exhausted = crate::resources::Resources {
            open_descriptors: Some(63),
            descriptor_limit: Some(64),
            shm_free_bytes: Some(1 << 30),
        };
        let error = crate::instance::InstanceError::OutOfResources {
            what: "open service \"specimen\"".into(),
            detail: "ResourceCreationFailed".into(),
            resources: exhausted,
        };
        let exit = in_context("producer process", &error);
        assert_eq!(exit.code, RESOURCES);
        assert!(
            exit.message.starts_with(
                "producer process: cannot open service \"specimen\": ResourceCreationFailed; \
                 file descriptors exhausted: 63 open of the limit 64"
            ),
            "{}",
            exit.message
        );
        // The same error with descriptors to spare is not a resources fault.
        let other = crate::instance::InstanceError::Service {
            service: "specimen".into(),
            detail: "ResourceCreationFailed".into(),
        };
        assert_eq!(in_context("producer process", &other).code, 1);
    }
}
