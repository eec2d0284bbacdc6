//! The services going out: a subscriber of each on the local instance, woken by its listener
//! in a WaitSet; each sample is put on Zenoh as its header's and payload's bytes, with the ids
//! its sender knowingly skipped before it (`link::envelope`). Zenoh drops rather than blocks
//! when the network cannot keep up (congestion control `Drop`), and the local queues overflow
//! safely: the link never holds the rig or the camera.

use link::envelope::Envelope;
use link::{LinkedService, RateLimit, SendGaps};
use wire::plain::{slice_bytes, value_bytes};
use wire::pubsub::TappedSubscriber;
use zenoh::qos::CongestionControl;
use zenoh::Wait;

/// What was sent of one service.
pub struct Sent {
    pub service: LinkedService,
    pub gaps: SendGaps,
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
    fn drain(&mut self, subscriber: &TappedSubscriber) -> anyhow::Result<()> {
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
            let envelope = Envelope {
                skipped_ids: self.gaps.send(),
            };
            self.publisher
                .put(self.bytes.as_slice())
                .attachment(envelope.to_bytes())
                .wait()
                .map_err(|e| anyhow::anyhow!("link: putting {} on Zenoh: {e}", self.service))?;
        }
        Ok(())
    }

    /// Copies the next queued sample's bytes into `bytes`; false when none is queued.
    fn take_one(&mut self, subscriber: &TappedSubscriber) -> anyhow::Result<bool> {
        self.bytes.clear();
        let bytes = &mut self.bytes;
        Ok(match subscriber {
            TappedSubscriber::Frames(s) => s.receive()?.map(|sample| {
                bytes.extend_from_slice(value_bytes(sample.user_header()));
                bytes.extend_from_slice(slice_bytes(sample.payload()));
            }),
            TappedSubscriber::Fields(s) => s.receive()?.map(|sample| {
                bytes.extend_from_slice(value_bytes(sample.user_header()));
                bytes.extend_from_slice(slice_bytes(sample.payload()));
            }),
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

/// Carries `services` out until a stop.
pub fn run(
    instance: &wire::Instance,
    session: &zenoh::Session,
    services: &[LinkedService],
    frames_max_hz: Option<f64>,
) -> anyhow::Result<Vec<Sent>> {
    let (node, _) = instance.create_node("link-out")?;
    let mut subscribers = Vec::new();
    let mut routes = Vec::new();
    for &service in services {
        subscribers.push(
            TappedSubscriber::open(&node, service.name()).expect("a linked service is tappable")?,
        );
        let publisher = session
            .declare_publisher(link::key::key_expr(instance.name(), service))
            .congestion_control(CongestionControl::Drop)
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
            gaps: SendGaps::default(),
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
        }
        waitset
            .wait_and_process_once_with_timeout(
                |_| iceoryx2::prelude::CallbackProgression::Continue,
                super::STOP_CHECK,
            )
            .map_err(|e| anyhow::anyhow!("link: waiting on the WaitSet: {e:?}"))?;
    }
    drop(guards);
    Ok(routes
        .into_iter()
        .map(|r| Sent {
            service: r.service,
            gaps: r.gaps,
        })
        .collect())
}
