//! The services coming in: a Zenoh subscriber of each (`dicstream/<instance>/<service>`),
//! whose callback, on Zenoh's threads, hands the bytes over a bounded queue to this loop, which
//! counts their ids (`link::gaps`, less what the sender declared) and publishes them into the
//! local instance. The small services wait in the callback when the queue is full (this loop
//! never waits on anything but the queue, so the wait is short; meanwhile TCP holds the rest
//! and the sender's queue what follows); a frame is dropped (counted as lost, as the gap it
//! leaves).

use super::local_publisher::LocalPublisher;
use link::envelope::Envelope;
use link::gaps::Arrival;
use link::{LinkCounts, LinkedService, ReceiveGaps};
use std::sync::mpsc::{sync_channel, RecvTimeoutError};
use std::sync::Mutex;
use zenoh::Wait;

/// Samples waiting between Zenoh's threads and the local publishers.
const QUEUE_SAMPLES: usize = 256;

/// What was received of one service.
struct Received {
    service: LinkedService,
    gaps: ReceiveGaps,
    /// Samples whose bytes or attachment were refused (another version, a foreign sender).
    refused: u64,
}

/// One sample off Zenoh.
struct Arrived {
    route: usize,
    bytes: Vec<u8>,
    attachment: Option<Vec<u8>>,
}

/// Carries `services` in until a signal, going on from `counts` and keeping them current there.
pub fn run(
    instance: &wire::Instance,
    session: &zenoh::Session,
    services: &[LinkedService],
    counts: &Mutex<LinkCounts>,
) -> anyhow::Result<()> {
    let (node, _) = instance.create_node("link-in")?;
    let (sender, queue) = sync_channel::<Arrived>(QUEUE_SAMPLES);
    let mut publishers = Vec::new();
    let mut received = Vec::new();
    let mut subscribers = Vec::new();
    for (route, &service) in services.iter().enumerate() {
        publishers.push(LocalPublisher::create(&node, service)?);
        // Every service carried is in the counts, from the start (a service that received
        // nothing shows zeros).
        let before = super::lock(counts).in_of(service);
        super::lock(counts).set_in(service, before.clone());
        received.push(Received {
            service,
            gaps: ReceiveGaps::resumed(&before),
            refused: before.refused,
        });
        let sender = sender.clone();
        let subscriber = session
            .declare_subscriber(link::key::key_expr(instance.name(), service))
            .callback(move |sample: zenoh::sample::Sample| {
                let arrived = Arrived {
                    route,
                    bytes: sample.payload().to_bytes().into_owned(),
                    attachment: sample.attachment().map(|a| a.to_bytes().into_owned()),
                };
                match service {
                    // The gap it leaves is counted as lost when the next one arrives.
                    LinkedService::Frames => drop(sender.try_send(arrived)),
                    // Err: this loop has stopped.
                    _ => drop(sender.send(arrived)),
                }
            })
            .wait()
            .map_err(|e| {
                anyhow::anyhow!("link: declaring the Zenoh subscriber of {service}: {e}")
            })?;
        subscribers.push(subscriber);
    }
    drop(sender);
    let taken = (|| {
        while !super::stop_requested() {
            let arrived = match queue.recv_timeout(super::STOP_CHECK) {
                Ok(arrived) => arrived,
                Err(RecvTimeoutError::Timeout) => continue,
                Err(RecvTimeoutError::Disconnected) => break,
            };
            let route = &mut received[arrived.route];
            let service = route.service;
            let outcome = take(route, &mut publishers[arrived.route], &node, arrived)?;
            super::lock(counts).set_in(service, route.gaps.counts(route.refused));
            let Some(line) = outcome else { continue };
            eprintln!("{line}");
        }
        anyhow::Ok(())
    })();
    // The queue first, however the loop ended: a callback waiting on it returns, so that its
    // subscriber can go.
    drop(queue);
    drop(subscribers);
    taken
}

/// Checks, publishes and counts one arrived sample; what to say about it, if anything.
fn take(
    counts: &mut Received,
    publisher: &mut LocalPublisher,
    node: &iceoryx2::prelude::Node<iceoryx2::prelude::ipc::Service>,
    arrived: Arrived,
) -> anyhow::Result<Option<String>> {
    let service = counts.service;
    let envelope = arrived.attachment.as_deref().map(Envelope::from_bytes);
    let (Some(Ok(envelope)), Some(id)) = (
        envelope,
        service.sample_id(arrived.bytes.get(..service.header_bytes()).unwrap_or(&[])),
    ) else {
        counts.refused += 1;
        return Ok(Some(format!(
            "link: {service}: a sample of {} bytes without a dicstream link's attachment or \
             header, refused",
            arrived.bytes.len()
        )));
    };
    if let Err(refused) = publisher.publish(node, service, &arrived.bytes)? {
        counts.refused += 1;
        return Ok(Some(format!("link: refused: {refused}")));
    }
    Ok(match counts.gaps.received(id, envelope) {
        Arrival::InOrder => None,
        Arrival::AfterLoss { lost } => Some(format!(
            "link: {service}: {lost} id(s) lost by the link before {id} ({} in all)",
            counts.gaps.lost
        )),
        // The two routes' reports name their own frames, out of order: not a source started
        // again.
        Arrival::Restarted if service == LinkedService::Identification => None,
        Arrival::Restarted => Some(format!("link: {service}: ids started again at {id}")),
    })
}
