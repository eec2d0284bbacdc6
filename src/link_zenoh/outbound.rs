//! The services going out: a subscriber of each on the local instance, woken by its listener
//! in a WaitSet; each sample is taken at once as its header's and payload's bytes, with the
//! ids its sender knowingly skipped before it (`link::envelope`), into a bounded queue of its
//! service, which a thread of the service's own puts on Zenoh, waiting up to
//! `session::WAIT_FOR_THE_NETWORK` for room in Zenoh's queue before Zenoh drops the sample: the
//! rig's samples, the fields, the reports and the specimen's solves are not dropped when the
//! sending thread or the network lags a moment. Only the sending thread waits: the WaitSet's
//! loop never does, so the local queues are drained and the link never holds the rig or the
//! camera. A sample its queue has no room for (the network took less than came, or went down)
//! is dropped and not declared: the receiver counts it lost by the link; frames, large and
//! rate-limited, have room for one.

use link::envelope::Envelope;
use link::{LinkCounts, LinkedService, RateLimit, SendGaps};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender, TrySendError};
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

/// A sample on its way to Zenoh: its bytes, header then payload, and what its sender declares.
struct Outgoing {
    bytes: Vec<u8>,
    envelope: Envelope,
}

/// One service going out (its subscriber apart: the WaitSet holds its listener).
struct Route<'p> {
    service: LinkedService,
    /// Its Zenoh publisher, which its sending thread puts on (here: who subscribes).
    publisher: &'p zenoh::pubsub::Publisher<'static>,
    /// To its sending thread.
    queue: SyncSender<Outgoing>,
    rate: Option<RateLimit>,
    gaps: SendGaps,
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

    /// Queues for the network what `subscriber` has queued, never waiting.
    fn drain(&mut self, subscriber: &OutSubscriber) -> anyhow::Result<()> {
        subscriber.clear_events();
        let mut bytes = Vec::new();
        while take_one(subscriber, &mut bytes)? {
            let header = bytes.get(..self.service.header_bytes()).unwrap_or(&[]);
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
            let outgoing = Outgoing {
                bytes: std::mem::take(&mut bytes),
                envelope: self.gaps.envelope(),
            };
            match self.queue.try_send(outgoing) {
                Ok(()) => {
                    self.gaps.send();
                }
                Err(TrySendError::Full(_)) => self.gaps.overflow(),
                Err(TrySendError::Disconnected(_)) => {
                    anyhow::bail!("link: the sending thread of {} stopped", self.service)
                }
            }
        }
        Ok(())
    }
}

/// Copies the next queued sample's bytes into `bytes` (emptied first); false when none is
/// queued.
fn take_one(subscriber: &OutSubscriber, bytes: &mut Vec<u8>) -> anyhow::Result<bool> {
    bytes.clear();
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

/// Puts each queued sample of `service` on Zenoh, waiting for room in Zenoh's queue, until a
/// stop: what is still queued then is not put (on a network that takes nothing, each put
/// would wait `session::WAIT_FOR_THE_NETWORK`).
fn send_queued(
    service: LinkedService,
    publisher: &zenoh::pubsub::Publisher<'static>,
    queue: Receiver<Outgoing>,
) -> anyhow::Result<()> {
    for outgoing in queue {
        if super::stop_requested() {
            break;
        }
        publisher
            .put(outgoing.bytes)
            .attachment(outgoing.envelope.to_bytes())
            .wait()
            .map_err(|e| anyhow::anyhow!("link: putting {service} on Zenoh: {e}"))?;
    }
    Ok(())
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

/// Samples of a service queued for the network, beyond what Zenoh and TCP hold: some seconds
/// of each at its usual rate (rig samples at up to 500 Hz, fields and reports at the camera's
/// 10 to 30 Hz, solves a few per second, each a few hundred kB), so that a lag of the network
/// or of the sending thread loses nothing; frames, dropped by Zenoh anyway, one.
fn queue_samples(service: LinkedService) -> usize {
    match service {
        LinkedService::RigState => 8192,
        LinkedService::Fields => 256,
        LinkedService::Identification => 256,
        LinkedService::Specimen => 32,
        LinkedService::Frames => 1,
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
    let mut publishers = Vec::new();
    for &service in services {
        subscribers.push(OutSubscriber::open(&node, service)?);
        publishers.push(
            session
                .declare_publisher(link::key::key_expr(instance.name(), service))
                .congestion_control(CongestionControl::Drop)
                .priority(priority(service))
                .express(true)
                .wait()
                .map_err(|e| {
                    anyhow::anyhow!("link: declaring the Zenoh publisher of {service}: {e}")
                })?,
        );
    }
    std::thread::scope(|scope| {
        let mut routes = Vec::new();
        let mut sending = Vec::new();
        for (&service, publisher) in services.iter().zip(&publishers) {
            let (queue, queued) = sync_channel(queue_samples(service));
            sending.push(
                scope.spawn(move || super::noting_failure(send_queued(service, publisher, queued))),
            );
            let rate = match service {
                LinkedService::Frames => frames_max_hz.map(RateLimit::new),
                _ => None,
            };
            routes.push(Route {
                service,
                publisher,
                queue,
                rate,
                gaps: {
                    let before = super::lock(counts).out_of(service);
                    super::lock(counts).set_out(service, before.clone());
                    SendGaps::resumed(&before, sender)
                },
                matched: false,
            });
        }
        let taken = take_until_stopped(&subscribers, &mut routes, counts);
        // The sending threads end (their queues closed).
        drop(routes);
        let sent = sending
            .into_iter()
            .map(|thread| thread.join().expect("a sending thread does not panic"))
            .collect::<anyhow::Result<Vec<()>>>();
        taken.and(sent.map(|_| ()))
    })
}

/// The WaitSet's loop: every wake-up queues what every route's subscriber has, until a stop.
fn take_until_stopped(
    subscribers: &[OutSubscriber],
    routes: &mut [Route],
    counts: &Mutex<LinkCounts>,
) -> anyhow::Result<()> {
    let waitset = wire::signals::waitset()?;
    let mut guards = Vec::new();
    for (subscriber, route) in subscribers.iter().zip(routes.iter()) {
        guards.push(
            waitset
                .attach_notification(subscriber.listener())
                .map_err(|e| {
                    anyhow::anyhow!("attaching {} to the WaitSet: {e:?}", route.service)
                })?,
        );
    }
    while !super::stop_requested() {
        // History samples and those queued before the WaitSet need no event: every wake-up
        // drains every route, which costs a receive that finds nothing.
        for (route, subscriber) in routes.iter_mut().zip(subscribers) {
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
