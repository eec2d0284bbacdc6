//! The services going out: a subscriber of each on the local instance, woken by its listener
//! in a WaitSet; each sample is put on Zenoh as its header's and payload's bytes, with the ids
//! its sender knowingly skipped before it (`link::envelope`). Zenoh drops rather than blocks
//! when the network cannot keep up (congestion control `Drop`), and the local queues overflow
//! safely: the link never holds the rig or the camera.

use link::{LinkCounts, LinkedService, RateLimit, SendGaps};
use std::sync::Mutex;
use wire::plain::{slice_bytes, value_bytes, Plain};
use wire::pubsub::{SliceSubscriber, TappedSubscriber};
use zenoh::qos::{CongestionControl, Priority};
use zenoh::Wait;

/// The local subscriber of a service going out: a tappable one, or the specimen's solves.
enum OutSubscriber {
    Tapped(TappedSubscriber),
    Specimen(SliceSubscriber<f64, wire::SpecimenHeader>),
}

impl OutSubscriber {
    fn open(
        node: &iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
        service: LinkedService,
    ) -> anyhow::Result<OutSubscriber> {
        Ok(match service {
            LinkedService::Specimen => {
                OutSubscriber::Specimen(SliceSubscriber::create(node, service.spec())?)
            }
            _ => OutSubscriber::Tapped(
                TappedSubscriber::open(node, service.name())
                    .expect("a linked service but the specimen is tappable")?,
            ),
        })
    }

    fn listener(&self) -> &iceoryx2::port::listener::Listener<iceoryx2::prelude::ipc::Service> {
        match self {
            OutSubscriber::Tapped(s) => s.listener(),
            OutSubscriber::Specimen(s) => s.listener(),
        }
    }

    fn clear_events(&self) {
        match self {
            OutSubscriber::Tapped(s) => s.clear_events(),
            OutSubscriber::Specimen(s) => s.clear_events(),
        }
    }
}

/// One service going out (its subscriber apart: the WaitSet holds its listener).
struct Route<'s> {
    service: LinkedService,
    publisher: zenoh::pubsub::Publisher<'s>,
    rate: Option<RateLimit>,
    gaps: SendGaps,
    /// The sample's bytes, header then payload (reused).
    bytes: Vec<u8>,
    /// Whether a peer subscribes to it (said when it changes).
    matched: bool,
}

impl Route<'_> {
    /// Says when a peer starts or stops subscribing (what a user starting two hosts waits
    /// for).
    fn watch_peers(&mut self) -> anyhow::Result<()> {
        let matched = self
            .publisher
            .matching_status()
            .wait()
            .map_err(|e| anyhow::anyhow!("link: matching status of {}: {e}", self.service))?
            .matching();
        if matched != self.matched {
            self.matched = matched;
            match matched {
                true => eprintln!("link: {} out: a peer subscribes", self.service),
                false => eprintln!("link: {} out: no peer subscribes", self.service),
            }
        }
        Ok(())
    }

    /// Sends what `subscriber` has queued.
    fn drain(&mut self, subscriber: &OutSubscriber) -> anyhow::Result<()> {
        subscriber.clear_events();
        while self.take_one(subscriber)? {
            let header = &self.bytes[..self.service.header_bytes()];
            let Some(id) = self.service.sample_id(header) else {
                continue;
            };
            self.gaps.seen(id);
            if let Some(rate) = &mut self.rate {
                if !rate.admit(wire::monotonic_ns()) {
                    self.gaps.hold_back();
                    continue;
                }
            }
            let envelope = self.gaps.send();
            self.publisher
                .put(self.bytes.as_slice())
                .attachment(envelope.to_bytes())
                .wait()
                .map_err(|e| anyhow::anyhow!("link: putting {} on Zenoh: {e}", self.service))?;
        }
        Ok(())
    }

    /// Copies the next queued sample's bytes into `bytes`; false when none is queued.
    fn take_one(&mut self, subscriber: &OutSubscriber) -> anyhow::Result<bool> {
        self.bytes.clear();
        let bytes = &mut self.bytes;
        let subscriber = match subscriber {
            OutSubscriber::Tapped(s) => s,
            OutSubscriber::Specimen(s) => return take_slice(s, bytes),
        };
        Ok(match subscriber {
            TappedSubscriber::Frames(s) => return take_slice(s, bytes),
            TappedSubscriber::Fields(s) => return take_slice(s, bytes),
            TappedSubscriber::RigState(s) => s
                .receive()?
                .map(|state| bytes.extend_from_slice(value_bytes(&state))),
            TappedSubscriber::Identification(s) => s
                .receive()?
                .map(|report| bytes.extend_from_slice(value_bytes(&report))),
        }
        .is_some())
    }
}

/// Copies the next queued sample of a slice service, header then payload, into `bytes`; false
/// when none is queued.
fn take_slice<T, H>(subscriber: &SliceSubscriber<T, H>, bytes: &mut Vec<u8>) -> anyhow::Result<bool>
where
    T: Plain + std::fmt::Debug + iceoryx2::prelude::ZeroCopySend,
    H: Plain + std::fmt::Debug + iceoryx2::prelude::ZeroCopySend + Default,
{
    Ok(subscriber
        .receive()?
        .map(|sample| {
            bytes.extend_from_slice(value_bytes(sample.user_header()));
            bytes.extend_from_slice(slice_bytes(sample.payload()));
        })
        .is_some())
}

/// Zenoh's priority of a service going out: each priority has its own queue, so that a
/// specimen's solve (a few hundred kB) does not fill the queue the rig's samples need (they
/// were dropped behind it: 2892 of 13002 in a default campaign on one queue), and goes before
/// the rig samples that name it; frames, large, go last.
fn priority(service: LinkedService) -> Priority {
    match service {
        LinkedService::Specimen => Priority::InteractiveHigh,
        LinkedService::RigState | LinkedService::Fields => Priority::InteractiveLow,
        LinkedService::Identification => Priority::DataHigh,
        LinkedService::Frames => Priority::DataLow,
    }
}

/// Carries `services` out until a stop, going on from `counts` and keeping them current there.
pub fn run(
    instance: &wire::Instance,
    session: &zenoh::Session,
    services: &[LinkedService],
    frames_max_hz: Option<f64>,
    counts: &Mutex<LinkCounts>,
) -> anyhow::Result<()> {
    let (node, _) = instance.create_node("link-out")?;
    // This sender, new at each start (`link::envelope`).
    let sender = wire::monotonic_ns() ^ (u64::from(std::process::id()) << 40);
    let mut subscribers = Vec::new();
    let mut routes = Vec::new();
    for &service in services {
        subscribers.push(OutSubscriber::open(&node, service)?);
        let publisher = session
            .declare_publisher(link::key::key_expr(instance.name(), service))
            .congestion_control(CongestionControl::Drop)
            .priority(priority(service))
            .express(true)
            .wait()
            .map_err(|e| {
                anyhow::anyhow!("link: declaring the Zenoh publisher of {service}: {e}")
            })?;
        let rate = match service {
            LinkedService::Frames => frames_max_hz.map(RateLimit::new),
            _ => None,
        };
        routes.push(Route {
            service,
            publisher,
            rate,
            gaps: {
                let before = super::lock(counts).out_of(service);
                super::lock(counts).set_out(service, before.clone());
                SendGaps::resumed(&before, sender)
            },
            bytes: Vec::new(),
            matched: false,
        });
    }
    let waitset = wire::signals::waitset()?;
    let mut guards = Vec::new();
    for (subscriber, service) in subscribers.iter().zip(services) {
        guards.push(
            waitset
                .attach_notification(subscriber.listener())
                .map_err(|e| anyhow::anyhow!("attaching {service} to the WaitSet: {e:?}"))?,
        );
    }
    while !super::stop_requested() {
        // History samples and those queued before the WaitSet need no event: every wake-up
        // drains every route, which costs a receive that finds nothing.
        for (route, subscriber) in routes.iter_mut().zip(&subscribers) {
            route.watch_peers()?;
            route.drain(subscriber)?;
            super::lock(counts).set_out(route.service, route.gaps.counts());
        }
        waitset
            .wait_and_process_once_with_timeout(
                |_| iceoryx2::prelude::CallbackProgression::Continue,
                super::STOP_CHECK,
            )
            .map_err(|e| anyhow::anyhow!("link: waiting on the WaitSet: {e:?}"))?;
    }
    drop(guards);
    Ok(())
}
