//! `dicstream link` (feature `link`): this host's instance linked to its peers' over Zenoh,
//! the only code over the `zenoh` crate. The services of `[link]` going `out` are read from
//! the local instance and put on Zenoh as the bytes of their `#[repr(C)]` header and payload
//! (`wire::plain`), under `dicstream/<instance>/<service>`; those coming `in` are taken from
//! Zenoh, checked as any reader checks them (layout version, payload length) and published
//! into the local instance under the same service name and layout. Nothing here is a protocol
//! of ours: Zenoh carries the bytes (TCP, its own framing, reliability and authentication).
//!
//! - `session.rs`: the Zenoh session, from the plan only: peer mode, the configured endpoints
//!   (never Zenoh's default of listening on every interface), no scouting (no multicast, no
//!   gossip), user-password authentication against the peers file;
//! - `outbound.rs`: a thread that sleeps in a WaitSet on the out services' listeners and
//!   queues each sample, never waiting, for a sending thread per service, which waits there
//!   for the network (up to `session::WAIT_FOR_THE_NETWORK` a sample);
//! - `inbound.rs`: the in services, from Zenoh's callbacks through a bounded queue into the
//!   local publishers (`local_publisher.rs`);
//!
//! The ids each side lost are counted by `link::gaps` (pure) into one `link::LinkCounts`, kept
//! current by both loops, written to the counts file every second and at exit, and resumed from
//! it when the link starts again (`dicstream run` reads it for its verdict). A signal stops both loops within
//! 100 ms: Zenoh's threads may take the process's signals, so neither loop relies on one
//! interrupting its own wait. The sending threads end then, what is still queued not sent (a
//! put under way on a network that takes nothing ends within `session::WAIT_FOR_THE_NETWORK`).

mod inbound;
mod local_publisher;
mod outbound;
mod session;

use anyhow::Context;
use link::{LinkCounts, LinkDirection, LinkPlan};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// How long a loop waits before looking at the stop request again.
const STOP_CHECK: Duration = Duration::from_millis(100);
/// How often the counts file is written while the link runs.
const COUNTS_EVERY: Duration = Duration::from_secs(1);

/// Set when one side failed: the other stops too.
static FAILED: AtomicBool = AtomicBool::new(false);

/// Whether the loops stop: a termination signal, or the other side failed.
fn stop_requested() -> bool {
    wire::signals::requested().is_some() || FAILED.load(Ordering::SeqCst)
}

/// `result`, noting a failure for the other side's loop.
fn noting_failure<T>(result: anyhow::Result<T>) -> anyhow::Result<T> {
    if result.is_err() {
        FAILED.store(true, Ordering::SeqCst);
    }
    result
}

/// The counts, whoever held them last (a loop that failed leaves them usable).
fn lock(counts: &Mutex<LinkCounts>) -> MutexGuard<'_, LinkCounts> {
    counts
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The counts a link started again goes on from: those of `file`, if it exists.
fn resumed_counts(file: Option<&Path>, instance: &str) -> anyhow::Result<LinkCounts> {
    let Some(file) = file else {
        return Ok(LinkCounts::new(instance));
    };
    match std::fs::read_to_string(file) {
        Ok(text) => {
            let counts = LinkCounts::parse(&text)
                .with_context(|| format!("link: the counts file {}", file.display()))?;
            eprintln!(
                "link: going on from the counts in {} (a link started again)",
                file.display()
            );
            Ok(counts)
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(LinkCounts::new(instance)),
        Err(e) => Err(e).with_context(|| format!("link: reading {}", file.display())),
    }
}

fn write_counts(file: Option<&Path>, counts: &Mutex<LinkCounts>) -> anyhow::Result<()> {
    if let Some(file) = file {
        let json = lock(counts).to_json();
        wire::files::write_atomic(file, json.as_bytes())?;
    }
    Ok(())
}

/// Runs the link of `plan` on `instance_name` until a termination signal, keeping its counts in
/// `counts_file` (resumed from it when it exists).
pub fn run(
    plan: &LinkPlan,
    instance_name: &str,
    counts_file: Option<&Path>,
) -> anyhow::Result<LinkCounts> {
    let instance = wire::Instance::new(instance_name)?;
    let _owner = instance.claim("link")?;
    let counts = Mutex::new(resumed_counts(counts_file, instance_name)?);
    let session = session::open(plan).context("link: opening the Zenoh session")?;
    eprintln!(
        "link: instance {}; listening on [{}], connecting to [{}]; {}",
        instance.name(),
        join(&plan.listen),
        join(&plan.connect),
        plan.routes
            .iter()
            .map(|r| format!("{} {}", r.service, r.direction))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let routes_of = |direction| {
        plan.routes
            .iter()
            .filter(|r| r.direction == direction)
            .map(|r| r.service)
            .collect::<Vec<_>>()
    };
    let (out_services, in_services) = (routes_of(LinkDirection::Out), routes_of(LinkDirection::In));
    // What `dicstream run` waits for before it starts the next child.
    eprintln!("link: ready");
    let result = std::thread::scope(|scope| {
        let outbound = scope.spawn(|| {
            noting_failure(match out_services.is_empty() {
                true => Ok(()),
                false => outbound::run(
                    &instance,
                    &session,
                    &out_services,
                    plan.frames_max_hz,
                    &counts,
                ),
            })
        });
        let inbound = scope.spawn(|| {
            noting_failure(match in_services.is_empty() {
                true => Ok(()),
                false => inbound::run(&instance, &session, &in_services, &counts),
            })
        });
        let mut written = Instant::now();
        while !(outbound.is_finished() && inbound.is_finished()) {
            std::thread::sleep(STOP_CHECK);
            if written.elapsed() >= COUNTS_EVERY {
                noting_failure(write_counts(counts_file, &counts))?;
                written = Instant::now();
            }
        }
        let sent = outbound.join().expect("the outbound thread does not panic");
        let received = inbound.join().expect("the inbound thread does not panic");
        sent.and(received)
    });
    // The counts as they ended, whatever ended the loops.
    write_counts(counts_file, &counts)?;
    result?;
    Ok(counts.into_inner().unwrap_or_else(|p| p.into_inner()))
}

fn join(endpoints: &[link::Endpoint]) -> String {
    endpoints
        .iter()
        .map(|e| e.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}
