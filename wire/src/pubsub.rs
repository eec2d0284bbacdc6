//! Thin publish/subscribe wrappers: a publish-subscribe service plus an event service of the same
//! name, so a subscriber sleeps in a WaitSet until a sample arrives (no polling, no sleeps).
//! Two shapes: a slice of `T` behind a header `H` (frames, fields), and a single value (rig
//! state, identification).

use crate::instance::InstanceError;
use crate::services::ServiceSpec;
use core::fmt::Debug;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

mod connect;
mod tapped;

pub use tapped::TappedSubscriber;

type Ipc = ipc::Service;

/// A service that could not be opened; with the descriptors exhausted, a resources fault.
fn service_error(spec: &ServiceSpec, detail: impl Debug) -> InstanceError {
    let resources = crate::resources::Resources::now();
    if resources.descriptors_exhausted() {
        InstanceError::OutOfResources {
            what: format!("open service {:?}", spec.name),
            detail: format!("{detail:?}"),
            resources,
        }
    } else {
        InstanceError::Service {
            service: spec.name.to_string(),
            detail: format!("{detail:?}; {resources}"),
        }
    }
}

fn service_name(spec: &ServiceSpec) -> Result<ServiceName, InstanceError> {
    ServiceName::new(spec.name).map_err(|e| service_error(spec, e))
}

fn open_notifier(node: &Node<Ipc>, spec: &ServiceSpec) -> Result<Notifier<Ipc>, InstanceError> {
    let event = node
        .service_builder(&service_name(spec)?)
        .event()
        .max_notifiers(spec.max_publishers + 2)
        .max_listeners(spec.max_subscribers + 2)
        .open_or_create()
        .map_err(|e| service_error(spec, e))?;
    event
        .notifier_builder()
        .create()
        .map_err(|e| service_error(spec, e))
}

fn open_listener(node: &Node<Ipc>, spec: &ServiceSpec) -> Result<Listener<Ipc>, InstanceError> {
    let event = node
        .service_builder(&service_name(spec)?)
        .event()
        .max_notifiers(spec.max_publishers + 2)
        .max_listeners(spec.max_subscribers + 2)
        .open_or_create()
        .map_err(|e| service_error(spec, e))?;
    event
        .listener_builder()
        .create()
        .map_err(|e| service_error(spec, e))
}

macro_rules! configure {
    ($builder:expr, $spec:expr) => {
        $builder
            .max_publishers($spec.max_publishers)
            .max_subscribers($spec.max_subscribers)
            .subscriber_max_buffer_size($spec.subscriber_buffer)
            .subscriber_max_borrowed_samples($spec.subscriber_borrowed)
            .history_size($spec.history)
            .enable_safe_overflow($spec.safe_overflow)
    };
}

/// Publishes `[T]` slices of up to `max_len` elements behind a header `H`.
pub struct SlicePublisher<T: Debug + ZeroCopySend + 'static, H: Debug + ZeroCopySend + 'static> {
    publisher: Publisher<Ipc, [T], H>,
    notifier: Notifier<Ipc>,
    max_len: usize,
}

impl<T, H> SlicePublisher<T, H>
where
    T: Debug + ZeroCopySend + Copy + 'static,
    H: Debug + ZeroCopySend + Default + 'static,
{
    pub fn create(
        node: &Node<Ipc>,
        spec: &ServiceSpec,
        max_len: usize,
    ) -> Result<Self, InstanceError> {
        let service = configure!(
            node.service_builder(&service_name(spec)?)
                .publish_subscribe::<[T]>()
                .user_header::<H>(),
            spec
        )
        .open_or_create()
        .map_err(|e| service_error(spec, e))?;
        let publisher = service
            .publisher_builder()
            .initial_max_slice_len(max_len.max(1))
            .allocation_strategy(AllocationStrategy::Static)
            .max_loaned_samples(spec.publisher_loans)
            .create()
            .map_err(|e| service_error(spec, e))?;
        Ok(SlicePublisher {
            publisher,
            notifier: open_notifier(node, spec)?,
            max_len,
        })
    }

    /// The longest slice this publisher takes.
    pub fn max_len(&self) -> usize {
        self.max_len
    }

    /// Loans a slice of `len` elements in shared memory, lets `fill` write the header and every
    /// element in place (no copy), sends it and wakes the subscribers. `fill` returns `false` to
    /// send nothing (the loan goes back). Returns how many subscribers received the sample.
    pub fn publish<E>(
        &self,
        len: usize,
        fill: impl FnOnce(&mut H, &mut [T]) -> Result<bool, E>,
    ) -> Result<Result<Option<usize>, E>, InstanceError> {
        assert!(
            len <= self.max_len,
            "slice of {len} beyond the {} the service was sized for",
            self.max_len
        );
        let spec_error = |e: &dyn Debug| InstanceError::Service {
            service: "publish".into(),
            detail: format!("{e:?}"),
        };
        let sample = self
            .publisher
            .loan_slice_uninit(len)
            .map_err(|e| spec_error(&e))?;
        // SAFETY: the slice lies in shared memory that iceoryx2 mapped and that was zero-filled by
        // the OS or written by an earlier sample: its bytes are initialised from the abstract
        // machine's point of view, and every bit pattern is a valid `T` for the plain-old-data
        // layouts of this crate (u16 pixels, f32/u32 records). `fill` then overwrites it all.
        let mut sample = unsafe { sample.assume_init() };
        let (header, payload) = {
            let header: *mut H = sample.user_header_mut();
            // SAFETY: header and payload are disjoint regions of the same sample.
            (unsafe { &mut *header }, sample.payload_mut())
        };
        *header = H::default();
        match fill(header, payload) {
            Err(e) => return Ok(Err(e)),
            Ok(false) => return Ok(Ok(None)),
            Ok(true) => {}
        }
        let delivered = sample.send().map_err(|e| spec_error(&e))?;
        self.notifier.notify().map_err(|e| spec_error(&e))?;
        Ok(Ok(Some(delivered)))
    }
}

/// Receives `[T]` slices behind a header `H`. A publisher it cannot connect to is an error
/// (`connect.rs`).
pub struct SliceSubscriber<T: Debug + ZeroCopySend + 'static, H: Debug + ZeroCopySend + 'static> {
    subscriber: Subscriber<Ipc, [T], H>,
    listener: Listener<Ipc>,
    service: &'static str,
}

impl<T, H> SliceSubscriber<T, H>
where
    T: Debug + ZeroCopySend + Copy + 'static,
    H: Debug + ZeroCopySend + Default + 'static,
{
    pub fn create(node: &Node<Ipc>, spec: &ServiceSpec) -> Result<Self, InstanceError> {
        let service = configure!(
            node.service_builder(&service_name(spec)?)
                .publish_subscribe::<[T]>()
                .user_header::<H>(),
            spec
        )
        .open_or_create()
        .map_err(|e| service_error(spec, e))?;
        let failed = Arc::new(AtomicBool::new(false));
        let subscriber = service
            .subscriber_builder()
            .buffer_size(spec.subscriber_buffer)
            .set_degradation_handler(connect::handler(failed.clone()))
            .create()
            .map_err(|e| service_error(spec, e))?;
        connect::after_creation(spec.name, &failed)?;
        Ok(SliceSubscriber {
            subscriber,
            listener: open_listener(node, spec)?,
            service: spec.name,
        })
    }

    /// The event listener to attach to a WaitSet.
    pub fn listener(&self) -> &Listener<Ipc> {
        &self.listener
    }

    /// Consumes pending wake-ups (call when the WaitSet reports this listener).
    pub fn clear_events(&self) {
        let _ = self.listener.try_wait(|_| {});
    }

    /// The next queued sample, if any. Drain until `None` after each wake-up.
    pub fn receive(&self) -> Result<Option<Sample<Ipc, [T], H>>, InstanceError> {
        connect::checked(self.service, || self.subscriber.receive())
    }
}

/// Publishes single values of `T` (rig state, identification reports).
pub struct ValuePublisher<T: Debug + ZeroCopySend + 'static> {
    publisher: Publisher<Ipc, T, ()>,
    notifier: Notifier<Ipc>,
}

impl<T: Debug + ZeroCopySend + Copy + 'static> ValuePublisher<T> {
    pub fn create(node: &Node<Ipc>, spec: &ServiceSpec) -> Result<Self, InstanceError> {
        let service = configure!(
            node.service_builder(&service_name(spec)?)
                .publish_subscribe::<T>(),
            spec
        )
        .open_or_create()
        .map_err(|e| service_error(spec, e))?;
        let publisher = service
            .publisher_builder()
            .max_loaned_samples(spec.publisher_loans)
            .create()
            .map_err(|e| service_error(spec, e))?;
        Ok(ValuePublisher {
            publisher,
            notifier: open_notifier(node, spec)?,
        })
    }

    /// Sends `value` and wakes the subscribers; returns how many received it.
    pub fn publish(&self, value: T) -> Result<usize, InstanceError> {
        let error = |e: &dyn Debug| InstanceError::Service {
            service: "publish".into(),
            detail: format!("{e:?}"),
        };
        let delivered = self.publisher.send_copy(value).map_err(|e| error(&e))?;
        self.notifier.notify().map_err(|e| error(&e))?;
        Ok(delivered)
    }
}

/// Receives single values of `T`. A publisher it cannot connect to is an error
/// (`connect.rs`).
pub struct ValueSubscriber<T: Debug + ZeroCopySend + 'static> {
    subscriber: Subscriber<Ipc, T, ()>,
    listener: Listener<Ipc>,
    service: &'static str,
}

impl<T: Debug + ZeroCopySend + Copy + 'static> ValueSubscriber<T> {
    pub fn create(node: &Node<Ipc>, spec: &ServiceSpec) -> Result<Self, InstanceError> {
        let service = configure!(
            node.service_builder(&service_name(spec)?)
                .publish_subscribe::<T>(),
            spec
        )
        .open_or_create()
        .map_err(|e| service_error(spec, e))?;
        let failed = Arc::new(AtomicBool::new(false));
        let subscriber = service
            .subscriber_builder()
            .buffer_size(spec.subscriber_buffer)
            .set_degradation_handler(connect::handler(failed.clone()))
            .create()
            .map_err(|e| service_error(spec, e))?;
        connect::after_creation(spec.name, &failed)?;
        Ok(ValueSubscriber {
            subscriber,
            listener: open_listener(node, spec)?,
            service: spec.name,
        })
    }

    pub fn listener(&self) -> &Listener<Ipc> {
        &self.listener
    }

    pub fn clear_events(&self) {
        let _ = self.listener.try_wait(|_| {});
    }

    /// The next queued value, if any.
    pub fn receive(&self) -> Result<Option<T>, InstanceError> {
        let sample = connect::checked(self.service, || self.subscriber.receive())?;
        Ok(sample.map(|s| *s))
    }
}
