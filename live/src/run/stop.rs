//! The stop of a run, whatever ended it: the children in the order data flows, the last
//! samples taken in, then the monitor's ports and node, the supervisor and the dashboard let
//! go before what the processes left in `/dev/shm` is looked for.

use super::open::{Incidents, Run};
use super::prepare::Prepared;
use super::{Ending, RunOptions};
use crate::children::Role;
use crate::recorder::Recorder;
use std::collections::BTreeMap;
use std::time::Instant;

/// Drains after the children stopped: the queues hold what they published last, a few rounds
/// of [`crate::subscriptions::Subscriptions::drain`] at most.
pub(super) const FINAL_DRAIN_ROUNDS: usize = 16;

/// Stops in the order data flows: the source first, each consumer after.
/// The link last: what the others published last still crosses to the other host.
const STOP_ORDER: [Role; Role::COUNT] = [
    Role::Rig,
    Role::Producer,
    Role::Correlator,
    Role::Identifier,
    Role::Link,
];

/// A run once every process has stopped: what its results are made of.
pub(super) struct Stopped<'a> {
    pub(super) options: &'a RunOptions,
    /// Still holding the claim on the instance until the summary is written.
    pub(super) prepared: Prepared,
    pub(super) recorder: Recorder,
    pub(super) incidents: Incidents,
    /// CPU seconds per process (children by role, and this monitor).
    pub(super) cpu_s: BTreeMap<String, f64>,
    /// The termination signal that interrupted the run.
    pub(super) signal: Option<i32>,
    pub(super) started: Instant,
    pub(super) leftover_shm_files: usize,
    pub(super) ending: Ending,
    /// Why it failed: the whole chain of the error that ended it.
    pub(super) failure: Option<String>,
    /// The children that did not stop within the stop timeout and were killed (their last
    /// results, the identifier's final fit, may be missing).
    pub(super) killed_at_stop: Vec<String>,
}

impl<'a> Run<'a> {
    /// Stops every child and lets go of the instance's ports; `result` is how the loop ended.
    pub(super) fn stop(self, result: anyhow::Result<Ending>) -> Stopped<'a> {
        let timeout = self.stop_timeout();
        let Run {
            options,
            subscriptions,
            node,
            mut supervisor,
            mut recorder,
            dashboard,
            prepared,
            incidents,
            started,
            monitor_cpu_at_start_s,
            killed_in_drain,
            ..
        } = self;
        supervisor.sample_cpu();
        let mut cpu_s: BTreeMap<String, f64> = Role::ALL
            .into_iter()
            .filter(|&role| supervisor.started(role))
            .map(|role| (role.name().to_string(), supervisor.cpu_seconds(role)))
            .collect();
        let mut killed_at_stop = killed_in_drain;
        for (role, how) in supervisor.stop_all(&STOP_ORDER, timeout) {
            say_stopped(role, &how, &mut killed_at_stop);
        }
        // Samples published while stopping (last fields, last report).
        let _ = subscriptions.drain_all(&mut recorder, FINAL_DRAIN_ROUNDS);
        drop(subscriptions);
        drop(node);
        let signal = wire::signals::requested();
        let monitor_cpu_s = crate::children::own_cpu_s() - monitor_cpu_at_start_s;
        cpu_s.insert("monitor".to_string(), monitor_cpu_s);
        drop(supervisor);
        drop(dashboard);
        let leftover_shm_files = crate::leftovers::report_and_remove(&prepared.instance);
        let (ending, failure) = match result {
            Ok(ending) => (ending, None),
            // The whole chain: what failed, and why.
            Err(e) => (Ending::Failed, Some(format!("{e:#}"))),
        };
        Stopped {
            options,
            prepared,
            recorder,
            incidents,
            cpu_s,
            signal,
            started,
            leftover_shm_files,
            ending,
            failure,
            killed_at_stop,
        }
    }
}

/// Says how `role` stopped (`how`, [`crate::children::Supervisor::stop`]'s description) and
/// adds it to `killed` if it had to be killed after its SIGTERM's timeout.
pub(super) fn say_stopped(role: Role, how: &str, killed: &mut Vec<String>) {
    eprintln!("run: stopped {} ({how})", role.name());
    if how.ends_with(crate::children::SIGTERM_TIMED_OUT) {
        killed.push(role.name().to_string());
    }
}
