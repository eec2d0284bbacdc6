//! A subscriber of any one of the services a user can watch ([`crate::services::TAPPABLE`]),
//! chosen by name at run time: what `dicstream tap` and the Python package's `subscribe` open.

use super::{Ipc, SliceSubscriber, ValueSubscriber};
use crate::instance::InstanceError;
use crate::services;
use crate::{FieldHeader, FieldNode, FrameHeader, IdentificationReport, RigState};
use iceoryx2::node::Node;
use iceoryx2::port::listener::Listener;

/// The subscriber of one tappable service.
pub enum TappedSubscriber {
    Frames(SliceSubscriber<u16, FrameHeader>),
    Fields(SliceSubscriber<FieldNode, FieldHeader>),
    RigState(ValueSubscriber<RigState>),
    Identification(ValueSubscriber<IdentificationReport>),
}

impl TappedSubscriber {
    /// Subscribes to the tappable service `name`; None for a name that is not one.
    pub fn open(node: &Node<Ipc>, name: &str) -> Option<Result<TappedSubscriber, InstanceError>> {
        Some(match name {
            n if n == services::FRAMES.name => {
                SliceSubscriber::create(node, &services::FRAMES).map(TappedSubscriber::Frames)
            }
            n if n == services::FIELDS.name => {
                SliceSubscriber::create(node, &services::FIELDS).map(TappedSubscriber::Fields)
            }
            n if n == services::RIG_STATE.name => {
                ValueSubscriber::create(node, &services::RIG_STATE).map(TappedSubscriber::RigState)
            }
            n if n == services::IDENTIFICATION.name => {
                ValueSubscriber::create(node, &services::IDENTIFICATION)
                    .map(TappedSubscriber::Identification)
            }
            _ => return None,
        })
    }

    /// The text of a name that is no tappable service.
    pub fn unknown_text(name: &str) -> String {
        format!(
            "unknown service {name:?}: expected one of {}",
            services::TAPPABLE.map(|s| s.name).join(", ")
        )
    }

    /// The event listener to wait on (or attach to a WaitSet).
    pub fn listener(&self) -> &Listener<Ipc> {
        match self {
            TappedSubscriber::Frames(s) => s.listener(),
            TappedSubscriber::Fields(s) => s.listener(),
            TappedSubscriber::RigState(s) => s.listener(),
            TappedSubscriber::Identification(s) => s.listener(),
        }
    }

    /// Consumes pending wake-ups.
    pub fn clear_events(&self) {
        match self {
            TappedSubscriber::Frames(s) => s.clear_events(),
            TappedSubscriber::Fields(s) => s.clear_events(),
            TappedSubscriber::RigState(s) => s.clear_events(),
            TappedSubscriber::Identification(s) => s.clear_events(),
        }
    }
}
