//! A subscriber that cannot connect to a publisher is an error of its process, not a warning
//! in its log: iceoryx2 (0.10) tries a connection only when the publishers of a service
//! change, so a failed one (no file descriptor left, `/dev/shm` full) leaves the subscriber
//! deaf to that publisher for good. Subscribers are built with a degradation handler that makes
//! the failure an error of `receive`, which [`checked`] turns into a
//! [`ConnectionError`](crate::resources::ConnectionError) naming the resources.

use crate::instance::InstanceError;
use crate::resources::{ConnectionError, Resources};
use iceoryx2::port::{DegradationAction, DegradationCause, DegradationInfo, ReceiveError};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// The degradation handler of every subscriber: a failed connection fails the call that
/// tried it (`receive`), and is noted in `failed` (a subscriber's creation only warns).
pub(super) fn handler(
    failed: Arc<AtomicBool>,
) -> impl Fn(DegradationCause, &DegradationInfo) -> DegradationAction + Send + 'static {
    move |_, _| {
        failed.store(true, Ordering::Relaxed);
        DegradationAction::DegradeAndFail
    }
}

/// Failures of a publisher that is going away (killed, its files being removed) or not yet
/// whole: its samples are not this subscriber's loss, so they are no error (the next change of
/// the publishers connects again). Told by iceoryx2's variant names, which its types do not
/// export.
fn transient(detail: &str) -> bool {
    [
        "IsBeingCleanedUp",
        "DoesNotExist",
        "InitializationNotYetFinalized",
    ]
    .iter()
    .any(|name| detail.contains(name))
}

/// The error of a subscriber of `service` whose connection failed with `detail`, or None when
/// the failure is [`transient`] and descriptors are not exhausted.
pub(super) fn failure(service: &str, detail: String) -> Option<ConnectionError> {
    let resources = Resources::now();
    (resources.descriptors_exhausted() || !transient(&detail)).then(|| ConnectionError {
        service: service.to_string(),
        detail,
        resources,
    })
}

/// Runs `receive`, turning a failed connection into a [`ConnectionError`] (a transient one
/// is passed over: `receive` runs again and receives from the publishers it has).
pub(super) fn checked<S>(
    service: &str,
    receive: impl Fn() -> Result<Option<S>, ReceiveError>,
) -> Result<Option<S>, InstanceError> {
    let other = |e: ReceiveError| InstanceError::Service {
        service: service.to_string(),
        detail: format!("receive: {e:?}"),
    };
    match receive() {
        Ok(sample) => Ok(sample),
        Err(ReceiveError::ConnectionFailure(cause)) => {
            match failure(service, format!("{cause:?}")) {
                Some(error) => Err(error.into()),
                None => receive().map_err(other),
            }
        }
        Err(e) => Err(other(e)),
    }
}

/// After a subscriber's creation: a publisher it could not connect to, with descriptors
/// exhausted, is an error (creation itself only warns).
pub(super) fn after_creation(service: &str, failed: &AtomicBool) -> Result<(), InstanceError> {
    if !failed.swap(false, Ordering::Relaxed) {
        return Ok(());
    }
    let resources = Resources::now();
    match resources.descriptors_exhausted() {
        true => Err(ConnectionError {
            service: service.to_string(),
            detail: "at the subscriber's creation".to_string(),
            resources,
        }
        .into()),
        false => Ok(()),
    }
}
