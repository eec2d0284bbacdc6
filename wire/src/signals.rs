//! Termination requests, one way for every process: SIGINT, SIGTERM and SIGHUP stop a process;
//! nothing else does. `install` is the first thing `main` does, so a signal in the first
//! milliseconds is a request like any other (not a default-action kill that leaves shared
//! memory behind). iceoryx2's own handling is disabled (`SignalHandlingMode::Disabled` on every
//! node and WaitSet, see [`waitset`]): a wait woken early, by a signal or by SIGCONT after
//! SIGSTOP (epoll_wait then fails with EINTR), is only a wake-up; a loop stops when
//! [`requested`] says so.

#[cfg(feature = "ipc")]
use iceoryx2::prelude::*;
#[cfg(feature = "ipc")]
use iceoryx2::waitset::WaitSetCreateError;
use std::sync::atomic::{AtomicI32, Ordering};

/// The first termination signal received (0: none).
static REQUESTED: AtomicI32 = AtomicI32::new(0);

/// The signals that ask a process to stop.
pub const TERMINATION_SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

extern "C" fn note_request(signal: libc::c_int) {
    // Atomic operations are async-signal-safe.
    let _ = REQUESTED.compare_exchange(0, signal, Ordering::SeqCst, Ordering::SeqCst);
}

/// Installs the handler of SIGINT, SIGTERM and SIGHUP (without SA_RESTART, so blocking waits
/// return early). A SIGHUP ignored when the process started stays ignored (`nohup`); SIGINT is
/// handled even if the starting shell ignored it (a background job's `kill -INT` then stops
/// it, as its user asked). Idempotent.
pub fn install() -> std::io::Result<()> {
    for signal in TERMINATION_SIGNALS {
        // SAFETY: a zeroed sigaction is a valid "no flags, empty mask" value; the handler only
        // does an atomic store, which is async-signal-safe.
        unsafe {
            if signal == libc::SIGHUP {
                let mut current: libc::sigaction = std::mem::zeroed();
                if libc::sigaction(signal, std::ptr::null(), &mut current) == 0
                    && current.sa_sigaction == libc::SIG_IGN
                {
                    continue;
                }
            }
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = note_request as *const () as libc::sighandler_t;
            libc::sigemptyset(&mut action.sa_mask);
            action.sa_flags = 0;
            if libc::sigaction(signal, &action, std::ptr::null_mut()) != 0 {
                return Err(std::io::Error::last_os_error());
            }
        }
    }
    Ok(())
}

/// The termination signal received so far, if any (it stays set).
pub fn requested() -> Option<libc::c_int> {
    match REQUESTED.load(Ordering::SeqCst) {
        0 => None,
        signal => Some(signal),
    }
}

/// `SIGINT`, `SIGTERM`, `SIGHUP` or the number.
pub fn name(signal: libc::c_int) -> String {
    match signal {
        libc::SIGINT => "SIGINT".into(),
        libc::SIGTERM => "SIGTERM".into(),
        libc::SIGHUP => "SIGHUP".into(),
        other => format!("signal {other}"),
    }
}

/// A WaitSet that leaves signals to this module (iceoryx2's default would install its own
/// SIGINT/SIGTERM handler over ours and report SIGCONT's EINTR as an interrupt).
#[cfg(feature = "ipc")]
pub fn waitset() -> Result<WaitSet<ipc::Service>, crate::resources::WaitSetError> {
    WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| crate::resources::WaitSetError {
            detail: format!("{e:?}"),
            out_of_resources: matches!(e, WaitSetCreateError::InsufficientResources),
            resources: crate::resources::Resources::now(),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_raised_termination_signal_is_noted_not_fatal() {
        install().unwrap();
        assert_eq!(requested(), None);
        // SAFETY: raise(3) with a valid signal number whose handler is installed.
        unsafe { libc::raise(libc::SIGHUP) };
        assert_eq!(requested(), Some(libc::SIGHUP));
        // SAFETY: as above; the first request is kept.
        unsafe { libc::raise(libc::SIGTERM) };
        assert_eq!(requested(), Some(libc::SIGHUP));
        assert_eq!(name(libc::SIGHUP), "SIGHUP");
    }
}
