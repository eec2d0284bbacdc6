//! The monitor's ports: it listens to every service of the run (frames, fields, rig state,
//! identification) and hands each sample to the [`Recorder`]. Frames are looked at in place
//! (header, and the pixels of the first frame only) and released at once.

use crate::recorder::Recorder;
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use wire::pubsub::{SliceSubscriber, ValueSubscriber};
use wire::{services, FieldHeader, FieldNode, FrameHeader, IdentificationReport, RigState};

pub struct Subscriptions {
    frames: SliceSubscriber<u16, FrameHeader>,
    fields: SliceSubscriber<FieldNode, FieldHeader>,
    rig: ValueSubscriber<RigState>,
    reports: ValueSubscriber<IdentificationReport>,
}

fn err(e: impl std::fmt::Display) -> String {
    format!("monitor: {e}")
}

impl Subscriptions {
    pub fn new(node: &Node<ipc::Service>) -> Result<Subscriptions, String> {
        Ok(Subscriptions {
            frames: SliceSubscriber::create(node, &services::FRAMES).map_err(err)?,
            fields: SliceSubscriber::create(node, &services::FIELDS).map_err(err)?,
            rig: ValueSubscriber::create(node, &services::RIG_STATE).map_err(err)?,
            reports: ValueSubscriber::create(node, &services::IDENTIFICATION).map_err(err)?,
        })
    }

    /// The listeners to attach to the run's WaitSet.
    pub fn listeners(&self) -> [&Listener<ipc::Service>; 4] {
        [
            self.frames.listener(),
            self.fields.listener(),
            self.rig.listener(),
            self.reports.listener(),
        ]
    }

    /// Takes every pending sample of every service into `recorder` (rig states first: fields
    /// name them).
    pub fn drain(&self, recorder: &mut Recorder) -> Result<(), String> {
        self.frames.clear_events();
        self.fields.clear_events();
        self.rig.clear_events();
        self.reports.clear_events();
        while let Some(state) = self.rig.receive().map_err(err)? {
            recorder.on_rig(state);
        }
        while let Some(frame) = self.frames.receive().map_err(err)? {
            recorder.on_frame(frame.user_header(), frame.payload());
        }
        while let Some(field) = self.fields.receive().map_err(err)? {
            let seen_ns = wire::monotonic_ns();
            recorder.on_field(field.user_header(), field.payload(), seen_ns);
        }
        while let Some(report) = self.reports.receive().map_err(err)? {
            recorder.on_report(report);
        }
        Ok(())
    }
}
