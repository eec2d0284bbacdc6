//! The monitor's ports: it listens to every service of the run (frames, fields, rig state,
//! identification) and hands each sample to the [`Recorder`]. Frames are looked at in place
//! (header, and the pixels of the first frame only) and released at once.

use crate::recorder::Recorder;
use anyhow::Context;
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use wire::pubsub::{SliceSubscriber, ValueSubscriber};
use wire::{services, FieldHeader, FieldNode, FrameHeader, IdentificationReport, RigState};

pub struct Subscriptions {
    frames: SliceSubscriber<u16, FrameHeader>,
    fields: SliceSubscriber<FieldNode, FieldHeader>,
    rig: ValueSubscriber<RigState>,
    reports: ValueSubscriber<IdentificationReport>,
    /// The finite-element specimen's solves: the truth of its frames. Not woken on (a rig
    /// sample always follows a solve).
    specimen: SliceSubscriber<f64, wire::SpecimenHeader>,
}

impl Subscriptions {
    pub fn new(node: &Node<ipc::Service>) -> anyhow::Result<Subscriptions> {
        Ok(Subscriptions {
            frames: SliceSubscriber::create(node, &services::FRAMES).context("monitor")?,
            fields: SliceSubscriber::create(node, &services::FIELDS).context("monitor")?,
            rig: ValueSubscriber::create(node, &services::RIG_STATE).context("monitor")?,
            reports: ValueSubscriber::create(node, &services::IDENTIFICATION).context("monitor")?,
            specimen: SliceSubscriber::create(node, &services::SPECIMEN).context("monitor")?,
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

    /// Takes every pending sample of every service into `recorder` (specimen solves, then rig
    /// states: frames and fields name them).
    pub fn drain(&self, recorder: &mut Recorder) -> anyhow::Result<()> {
        self.frames.clear_events();
        self.fields.clear_events();
        self.rig.clear_events();
        self.reports.clear_events();
        self.specimen.clear_events();
        while let Some(solve) = self.specimen.receive().context("monitor")? {
            recorder.on_specimen(solve.user_header(), solve.payload());
        }
        while let Some(state) = self.rig.receive().context("monitor")? {
            recorder.on_rig(state);
        }
        while let Some(frame) = self.frames.receive().context("monitor")? {
            recorder.on_frame(frame.user_header(), frame.payload());
        }
        while let Some(field) = self.fields.receive().context("monitor")? {
            let seen_ns = wire::monotonic_ns();
            recorder.on_field(field.user_header(), field.payload(), seen_ns);
        }
        while let Some(report) = self.reports.receive().context("monitor")? {
            recorder.on_report(report);
        }
        Ok(())
    }
}
