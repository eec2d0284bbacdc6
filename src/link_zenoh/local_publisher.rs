//! A service coming in, published into the local instance: the received bytes checked as any
//! reader checks them (layout version, payload length against the header), then written into a
//! loaned sample under the same service name and layout. A slice service's publisher is made
//! at its first sample, sized by it (a frame's pixels, a field's nodes), and made again,
//! larger, if a later sample needs more.

use link::LinkedService;
use wire::plain::{copy_into, element_count, read_value, Plain};
use wire::pubsub::{SlicePublisher, ValuePublisher};
use wire::{FieldHeader, FieldNode, FrameHeader, IdentificationReport, RigState, SpecimenHeader};

/// Why received bytes were not published.
#[derive(Debug, thiserror::Error)]
pub enum Refused {
    #[error("{service}: {len} bytes, not a header and whole elements")]
    Shape { service: LinkedService, len: usize },
    #[error("{service}: {reason}")]
    Invalid {
        service: LinkedService,
        reason: String,
    },
}

/// The local publisher of one service coming in.
pub enum LocalPublisher {
    Frames(Option<SlicePublisher<u16, FrameHeader>>),
    Fields(Option<SlicePublisher<FieldNode, FieldHeader>>),
    RigState(ValuePublisher<RigState>),
    Identification(ValuePublisher<IdentificationReport>),
    Specimen(Option<SlicePublisher<f64, SpecimenHeader>>),
}

impl LocalPublisher {
    pub fn create(
        node: &iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
        service: LinkedService,
    ) -> Result<LocalPublisher, wire::InstanceError> {
        Ok(match service {
            LinkedService::Frames => LocalPublisher::Frames(None),
            LinkedService::Fields => LocalPublisher::Fields(None),
            LinkedService::Specimen => LocalPublisher::Specimen(None),
            LinkedService::RigState => {
                LocalPublisher::RigState(ValuePublisher::create(node, service.spec())?)
            }
            LinkedService::Identification => {
                LocalPublisher::Identification(ValuePublisher::create(node, service.spec())?)
            }
        })
    }

    /// Publishes the sample whose bytes are `bytes`. Err(Refused) for bytes that are not one
    /// (the caller says so and goes on); the outer error is the local instance's.
    pub fn publish(
        &mut self,
        node: &iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
        service: LinkedService,
        bytes: &[u8],
    ) -> anyhow::Result<Result<(), Refused>> {
        match self {
            LocalPublisher::RigState(publisher) => {
                publish_value(publisher, service, bytes, "rig state", |s| s.layout_version)
            }
            LocalPublisher::Identification(publisher) => {
                publish_value(publisher, service, bytes, "identification", |r| {
                    r.layout_version
                })
            }
            LocalPublisher::Frames(publisher) => {
                let checked = checked::<FrameHeader, u16>(service, bytes, |h, len| {
                    h.validate(len).map_err(|e| e.to_string())
                });
                publish_slice(publisher, node, service, checked)
            }
            LocalPublisher::Fields(publisher) => {
                let checked = checked::<FieldHeader, FieldNode>(service, bytes, |h, len| {
                    h.validate(len).map_err(|e| e.to_string())
                });
                publish_slice(publisher, node, service, checked)
            }
            LocalPublisher::Specimen(publisher) => {
                // The solve checked whole (version, length, finite values, elements) as the
                // camera checks it: a copy of its values (a few per second).
                let checked = checked::<SpecimenHeader, f64>(service, bytes, |h, _| {
                    let values: Vec<f64> = bytes[size_of::<SpecimenHeader>()..]
                        .chunks_exact(size_of::<f64>())
                        .map(|b| f64::from_ne_bytes(b.try_into().expect("8 bytes")))
                        .collect();
                    h.split(&values).map(|_| ()).map_err(|e| e.to_string())
                });
                publish_slice(publisher, node, service, checked)
            }
        }
    }
}

/// A single value (rig state, report) whose layout version is checked.
fn publish_value<T: Plain + std::fmt::Debug + iceoryx2::prelude::ZeroCopySend>(
    publisher: &ValuePublisher<T>,
    service: LinkedService,
    bytes: &[u8],
    layout: &'static str,
    version: impl FnOnce(&T) -> u32,
) -> anyhow::Result<Result<(), Refused>> {
    let Some(value) = read_value::<T>(bytes) else {
        return Ok(Err(Refused::Shape {
            service,
            len: bytes.len(),
        }));
    };
    if let Err(e) = wire::layouts::check_version(layout, version(&value)) {
        return Ok(Err(Refused::Invalid {
            service,
            reason: e.to_string(),
        }));
    }
    publisher.publish(value)?;
    Ok(Ok(()))
}

/// The header and the payload's bytes with their element count, checked by `validate`; refused
/// when the bytes are not a header and whole elements, or do not validate.
fn checked<H: Plain, T: Plain>(
    service: LinkedService,
    bytes: &[u8],
    validate: impl FnOnce(&H, usize) -> Result<(), String>,
) -> Result<(H, &[u8], usize), Refused> {
    let shape = || Refused::Shape {
        service,
        len: bytes.len(),
    };
    let (header, payload) = bytes.split_at_checked(size_of::<H>()).ok_or_else(shape)?;
    let header: H = read_value(header).ok_or_else(shape)?;
    let len = element_count::<T>(payload).ok_or_else(shape)?;
    validate(&header, len).map_err(|reason| Refused::Invalid { service, reason })?;
    Ok((header, payload, len))
}

fn publish_slice<T, H>(
    publisher: &mut Option<SlicePublisher<T, H>>,
    node: &iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
    service: LinkedService,
    checked: Result<(H, &[u8], usize), Refused>,
) -> anyhow::Result<Result<(), Refused>>
where
    T: Plain + std::fmt::Debug + iceoryx2::prelude::ZeroCopySend + Default,
    H: Plain + std::fmt::Debug + iceoryx2::prelude::ZeroCopySend + Default,
{
    let (header, payload, len) = match checked {
        Ok(checked) => checked,
        Err(refused) => return Ok(Err(refused)),
    };
    if publisher.as_ref().is_none_or(|p| p.max_len() < len) {
        // The old one goes first: a service has room for two publishers.
        *publisher = None;
        *publisher = Some(SlicePublisher::create(node, service.spec(), len)?);
    }
    let publisher = publisher.as_ref().expect("made above");
    publisher
        .publish(len, |h, p| {
            *h = header;
            Ok::<bool, std::convert::Infallible>(copy_into(p, payload))
        })?
        .expect("infallible");
    Ok(Ok(()))
}
