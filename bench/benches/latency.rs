//! Delivery latency of the wire: a publisher loans a slice, writes its first and last byte,
//! stamps the header and sends it; a subscriber on another thread, with its own node, sleeps in
//! a WaitSet until the event wakes it, receives the sample and reads the same two bytes. The
//! latency is header stamp to receipt on the monotonic clock. Ping-pong: the subscriber acks
//! each sample, so no sample waits in a queue. A memcpy of the same size, measured in the same
//! run, gives the scale of what a copy would cost. Zero copy: the latency must not grow with
//! the payload, the memcpy does. The sizes take turns in rounds, so that a change of load on
//! the machine during the run falls on all of them alike.
//!
//! Run: `cargo bench -p bench --bench latency`.

use iceoryx2::prelude::*;
use std::hint::black_box;
use std::time::{Duration, Instant};
use wire::pubsub::{SlicePublisher, SliceSubscriber, ValuePublisher, ValueSubscriber};
use wire::services::ServiceSpec;
use wire::{FrameHeader, Instance};

/// Samples per size and round, after a warm-up per round; rounds over the three sizes.
const WARMUP: u64 = 10;
const SAMPLES: u64 = 100;
const ROUNDS: usize = 4;
const MEMCPY_REPS: usize = 60;
/// Hang guard of one wait (a benchmark that stops answering is a failure, not a figure).
const WAIT_GUARD: Duration = Duration::from_secs(10);

const fn spec(name: &'static str) -> ServiceSpec {
    ServiceSpec {
        name,
        max_publishers: 1,
        max_subscribers: 1,
        subscriber_buffer: 2,
        subscriber_borrowed: 2,
        history: 0,
        publisher_loans: 2,
        safe_overflow: true,
    }
}

const CASES: [(&str, usize, ServiceSpec); 3] = [
    ("64 B", 64, spec("bench/latency/64B")),
    ("1 MiB", 1 << 20, spec("bench/latency/1MiB")),
    ("8 MiB", 8 << 20, spec("bench/latency/8MiB")),
];
const ACK: ServiceSpec = spec("bench/latency/ack");
/// The ack the subscriber sends once it is connected.
const CONNECTED: u64 = u64::MAX;

fn wait_for_ack(waitset: &WaitSet<ipc::Service>, acks: &ValueSubscriber<u64>) -> u64 {
    let give_up = Instant::now() + WAIT_GUARD;
    loop {
        acks.clear_events();
        if let Some(ack) = acks.receive().expect("receive ack") {
            return ack;
        }
        let left = give_up.saturating_duration_since(Instant::now());
        assert!(!left.is_zero(), "no ack within {WAIT_GUARD:?}");
        waitset
            .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, left)
            .expect("wait for ack");
    }
}

/// The subscriber thread: receives `WARMUP + SAMPLES` samples, returns the latencies (ns).
fn subscribe(instance_name: String, case: ServiceSpec, len: usize) -> Vec<u64> {
    let instance = Instance::new(&instance_name).expect("instance");
    let (node, _) = instance.create_node("bench-subscriber").expect("node");
    let subscriber: SliceSubscriber<u8, FrameHeader> =
        SliceSubscriber::create(&node, &case).expect("subscriber");
    let acks: ValuePublisher<u64> = ValuePublisher::create(&node, &ACK).expect("ack publisher");
    let waitset = WaitSetBuilder::new().create::<ipc::Service>().unwrap();
    let _guard = waitset.attach_notification(subscriber.listener()).unwrap();
    acks.publish(CONNECTED).expect("connected ack");
    let mut latencies = Vec::with_capacity(SAMPLES as usize);
    let mut received = 0;
    while received < WARMUP + SAMPLES {
        waitset
            .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, WAIT_GUARD)
            .expect("wait for a sample");
        subscriber.clear_events();
        while let Some(sample) = subscriber.receive().expect("receive") {
            let received_ns = wire::monotonic_ns();
            let header = *sample.user_header();
            let payload = sample.payload();
            assert_eq!(payload.len(), len);
            let id = header.frame_id;
            assert_eq!(black_box(payload[0]), id as u8);
            assert_eq!(black_box(payload[len - 1]), id as u8);
            if id >= WARMUP {
                latencies.push(received_ns - header.t_capture_ns);
            }
            drop(sample);
            received += 1;
            acks.publish(id).expect("ack");
        }
    }
    latencies
}

/// One block: a publisher of `case`, a subscriber thread, `WARMUP + SAMPLES` ping-pongs.
fn measure(node: &Node<ipc::Service>, name: &str, case: ServiceSpec, len: usize) -> Vec<u64> {
    let publisher: SlicePublisher<u8, FrameHeader> =
        SlicePublisher::create(node, &case, len).expect("publisher");
    let acks: ValueSubscriber<u64> = ValueSubscriber::create(node, &ACK).expect("ack subscriber");
    let waitset = WaitSetBuilder::new().create::<ipc::Service>().unwrap();
    let _guard = waitset.attach_notification(acks.listener()).unwrap();
    let subscriber = {
        let name = name.to_string();
        std::thread::spawn(move || subscribe(name, case, len))
    };
    assert_eq!(wait_for_ack(&waitset, &acks), CONNECTED);
    for id in 0..WARMUP + SAMPLES {
        publisher
            .publish(len, |header, payload| {
                payload[0] = id as u8;
                payload[len - 1] = id as u8;
                header.frame_id = id;
                header.t_capture_ns = wire::monotonic_ns();
                Ok::<_, ()>(true)
            })
            .expect("publish")
            .expect("filled");
        assert_eq!(wait_for_ack(&waitset, &acks), id, "acks in order");
    }
    subscriber.join().expect("subscriber thread")
}

fn percentile(sorted: &[u64], q: f64) -> f64 {
    let k = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[k] as f64 / 1e3
}

fn memcpy_median_us(len: usize) -> f64 {
    let source: Vec<u8> = (0..len).map(|i| i as u8).collect();
    let mut target = vec![0u8; len];
    target.copy_from_slice(&source); // first touch of the target pages
    let mut times: Vec<f64> = (0..MEMCPY_REPS)
        .map(|_| {
            let started = Instant::now();
            target.copy_from_slice(black_box(&source));
            black_box(&mut target);
            started.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[MEMCPY_REPS / 2]
}

fn main() {
    let name = format!("bench_latency_{}", std::process::id());
    let instance = Instance::new(&name).expect("instance");
    let needed: u64 = CASES
        .iter()
        .map(|(_, len, case)| case.shm_bytes(std::mem::size_of::<FrameHeader>(), *len))
        .sum();
    wire::shm::ensure_free(wire::shm::SHM_PATH, needed).expect("room in /dev/shm");
    println!(
        "latency: publisher thread -> subscriber thread woken by the event in a WaitSet (own \
         nodes, instance {name}), ping-pong, {ROUNDS} rounds of {SAMPLES} samples per size after \
         {WARMUP} warm-up each; memcpy median of {MEMCPY_REPS} copies"
    );
    println!(
        "{:>7}  {:>10} {:>10} {:>10} {:>10}  {:>14}",
        "payload", "median µs", "p90 µs", "p99 µs", "max µs", "memcpy µs"
    );
    let mut latencies: Vec<Vec<u64>> = vec![Vec::new(); CASES.len()];
    {
        let (node, _) = instance.create_node("bench-publisher").expect("node");
        for _round in 0..ROUNDS {
            for (k, (_, len, case)) in CASES.into_iter().enumerate() {
                latencies[k].extend(measure(&node, &name, case, len));
            }
        }
    }
    let mut medians = Vec::new();
    for ((label, len, _), mut latencies) in CASES.into_iter().zip(latencies) {
        latencies.sort_unstable();
        let median = percentile(&latencies, 0.5);
        medians.push(median);
        println!(
            "{label:>7}  {median:>10.1} {:>10.1} {:>10.1} {:>10.1}  {:>14.2}",
            percentile(&latencies, 0.9),
            percentile(&latencies, 0.99),
            *latencies.last().unwrap() as f64 / 1e3,
            memcpy_median_us(len)
        );
    }
    println!(
        "median 8 MiB / 64 B: {:.2} (zero copy: about 1; a copy would scale with the size)",
        medians[2] / medians[0]
    );
    instance.cleanup_dead_nodes();
    instance.remove_leftover_files();
}
