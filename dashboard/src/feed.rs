//! The feeder, the only IPC of the crate: its own iceoryx2 node on the watched instance, one
//! subscriber per service (frames, fields, rig/state, identification), asleep in a WaitSet
//! until a sample or the publishing tick. Frames are looked at in place and released at once
//! (a thumbnail is made only when someone watches and the image rate cap allows); the four
//! services have safe overflow, so a slow feeder loses samples, never stalls a publisher.
//! A monitor's user gauges (`UserGauges`) read every field received, in place.

use crate::hub::Hub;
use crate::state::{LiveState, Settings};
use crate::user_gauges::UserGauges;
use crate::DashboardError;
use iceoryx2::prelude::*;
use std::sync::Arc;
use std::time::{Duration, Instant};
use wire::pubsub::{SliceSubscriber, ValueSubscriber};
use wire::{services, FieldHeader, FieldNode, FrameHeader, IdentificationReport, RigState};

/// Snapshots per second with viewers (and without: `/snapshot.json` stays current).
const PUBLISH_EVERY: Duration = Duration::from_millis(250);
const PUBLISH_EVERY_UNWATCHED: Duration = Duration::from_secs(1);

struct Ports {
    frames: SliceSubscriber<u16, FrameHeader>,
    fields: SliceSubscriber<FieldNode, FieldHeader>,
    rig: ValueSubscriber<RigState>,
    reports: ValueSubscriber<IdentificationReport>,
}

fn err(e: impl std::fmt::Display) -> DashboardError {
    DashboardError::Feed(e.to_string())
}

impl Ports {
    fn open(node: &Node<ipc::Service>) -> Result<Ports, DashboardError> {
        Ok(Ports {
            frames: SliceSubscriber::create(node, &services::FRAMES).map_err(err)?,
            fields: SliceSubscriber::create(node, &services::FIELDS).map_err(err)?,
            rig: ValueSubscriber::create(node, &services::RIG_STATE).map_err(err)?,
            reports: ValueSubscriber::create(node, &services::IDENTIFICATION).map_err(err)?,
        })
    }

    /// Every pending sample into `state`; returns the last thumbnail encoded, if any.
    fn drain(
        &self,
        state: &mut LiveState,
        gauges: &mut Option<Box<dyn UserGauges>>,
        encode: bool,
    ) -> Result<Option<Vec<u8>>, DashboardError> {
        self.frames.clear_events();
        self.fields.clear_events();
        self.rig.clear_events();
        self.reports.clear_events();
        while let Some(s) = self.rig.receive().map_err(err)? {
            state.on_rig(&s);
        }
        let mut png = None;
        while let Some(frame) = self.frames.receive().map_err(err)? {
            let now_ns = wire::monotonic_ns();
            if let Some(p) = state.on_frame(frame.user_header(), frame.payload(), now_ns, encode) {
                png = Some(p);
            }
        }
        while let Some(field) = self.fields.receive().map_err(err)? {
            let time = state.on_field(field.user_header(), field.payload());
            if let Some(gauges) = gauges {
                gauges.on_field(field.user_header(), field.payload(), time);
            }
        }
        while let Some(r) = self.reports.receive().map_err(err)? {
            state.on_report(&r);
        }
        Ok(png)
    }
}

/// Opens the ports on `instance`, then calls `ready` (with the error if they could not be
/// opened) and feeds `hub` until it is stopped or a termination signal is noted. With
/// `gauges`, every field received is read into them and they are the snapshots'
/// `user_gauges` (else the hub's, which `dicstream run` sets).
pub fn feed(
    instance: &str,
    settings: Settings,
    hub: Arc<Hub>,
    mut gauges: Option<Box<dyn UserGauges>>,
    ready: impl FnOnce(Result<(), DashboardError>),
) -> Result<(), DashboardError> {
    let opened: Result<_, DashboardError> = (|| {
        let instance = wire::Instance::new(instance).map_err(err)?;
        let (node, _) = instance.create_node("dashboard").map_err(err)?;
        let ports = Ports::open(&node)?;
        let waitset = wire::signals::waitset().map_err(|e| err(e.to_string()))?;
        Ok((node, ports, waitset))
    })();
    let (_node, ports, waitset) = match opened {
        Ok(o) => {
            ready(Ok(()));
            o
        }
        Err(e) => {
            ready(Err(e.clone()));
            return Err(e);
        }
    };
    let mut guards = Vec::new();
    for listener in [
        ports.frames.listener(),
        ports.fields.listener(),
        ports.rig.listener(),
        ports.reports.listener(),
    ] {
        guards.push(
            waitset
                .attach_notification(listener)
                .map_err(|e| err(format!("WaitSet: {e:?}")))?,
        );
    }
    let mut state = LiveState::new(settings, wire::monotonic_ns());
    let mut png = None;
    let mut next_publish = Instant::now();
    while !hub.stopped() && wire::signals::requested().is_none() {
        let wait = next_publish.saturating_duration_since(Instant::now());
        waitset
            .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, wait)
            .map_err(|e| err(format!("WaitSet: {e:?}")))?;
        let watched = hub.viewers() > 0;
        if let Some(p) = ports.drain(&mut state, &mut gauges, watched)? {
            png = Some(p);
        }
        if Instant::now() >= next_publish {
            let mut snapshot =
                state.snapshot(wire::monotonic_ns(), hub.viewers(), &hub.processes());
            snapshot["user_gauges"] = match &gauges {
                Some(gauges) => gauges.to_json(),
                None => hub.user_gauges(),
            };
            hub.publish(snapshot.to_string(), png.take());
            next_publish = Instant::now()
                + if watched {
                    PUBLISH_EVERY
                } else {
                    PUBLISH_EVERY_UNWATCHED
                };
        }
    }
    Ok(())
}
