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
//! - `outbound.rs`: a thread that sleeps in a WaitSet on the out services' listeners;
//! - `inbound.rs`: the in services, from Zenoh's callbacks through a bounded queue into the
//!   local publishers (`local_publisher.rs`);
//! - `report.rs`: the counts said at exit.
//!
//! The ids each side lost are counted by `link::gaps` (pure). A signal stops both loops within
//! 100 ms: Zenoh's threads may take the process's signals, so neither loop relies on one
//! interrupting its own wait.

mod inbound;
mod local_publisher;
mod outbound;
mod report;
mod session;

use anyhow::Context;
use link::{LinkDirection, LinkPlan};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

pub use report::LinkReport;

/// How long a loop waits before looking at the stop request again.
const STOP_CHECK: Duration = Duration::from_millis(100);

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

/// Runs the link of `plan` on `instance_name` until a termination signal.
pub fn run(plan: &LinkPlan, instance_name: &str) -> anyhow::Result<LinkReport> {
    let instance = wire::Instance::new(instance_name)?;
    let _owner = instance.claim("link")?;
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
    let (sent, received) = std::thread::scope(|scope| {
        let outbound = scope.spawn(|| {
            noting_failure(match out_services.is_empty() {
                true => Ok(Vec::new()),
                false => outbound::run(&instance, &session, &out_services, plan.frames_max_hz),
            })
        });
        let received = noting_failure(match in_services.is_empty() {
            true => {
                while !stop_requested() && !outbound.is_finished() {
                    std::thread::sleep(STOP_CHECK);
                }
                Ok(Vec::new())
            }
            false => inbound::run(&instance, &session, &in_services),
        });
        let sent = outbound.join().expect("the outbound thread does not panic");
        (sent, received)
    });
    Ok(LinkReport {
        sent: sent?,
        received: received?,
    })
}

fn join(endpoints: &[link::Endpoint]) -> String {
    endpoints
        .iter()
        .map(|e| e.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}
