//! The monitor's loop: it sleeps in a WaitSet on every service of the run (and the signals),
//! takes in the samples, watches the children, handles their exits, and once a second
//! updates the dashboard, the status line and now and then the latency histograms.

use super::open::{Phase, Run};
use super::Ending;
use anyhow::{anyhow, bail, Context};
use iceoryx2::prelude::*;
use std::rc::Rc;
use std::time::{Duration, Instant};

/// Longest sleep in the WaitSet: the children's exits and lines are looked at this often.
const WAIT_SLICE: Duration = Duration::from_millis(200);
/// How often the latency histograms are rewritten during the run.
const HISTOGRAM_EVERY: Duration = Duration::from_secs(10);

/// When the status line and the histograms are next due.
struct Clock {
    status_every: Duration,
    next_status: Instant,
    next_histograms: Instant,
}

impl Clock {
    fn from_now(status_every: Duration) -> Clock {
        Clock {
            status_every,
            next_status: Instant::now() + status_every,
            next_histograms: Instant::now() + HISTOGRAM_EVERY,
        }
    }

    /// The next status line one interval on, or one interval from now if the loop fell
    /// behind.
    fn next(&mut self) {
        self.next_status += self.status_every;
        if self.next_status < Instant::now() {
            self.next_status = Instant::now() + self.status_every;
        }
    }
}

/// How the loop ends when a termination signal has arrived.
pub(super) fn interrupted(signal: i32) -> Ending {
    eprintln!(
        "run: {} received, stopping the processes",
        wire::signals::name(signal)
    );
    Ending::Interrupted
}

fn waitset_error(e: impl std::fmt::Debug) -> anyhow::Error {
    anyhow!("monitor WaitSet: {e:?}")
}

impl Run<'_> {
    /// Starts the children, then watches them to the end of the run: how it ended, or why it
    /// failed.
    pub(super) fn supervise(&mut self) -> anyhow::Result<Ending> {
        match self.start_children()? {
            false => Ok(Ending::Interrupted),
            true => self.event_loop(),
        }
    }

    fn event_loop(&mut self) -> anyhow::Result<Ending> {
        let subscriptions = Rc::clone(&self.subscriptions);
        let waitset = wire::signals::waitset().context("monitor")?;
        let _guards = subscriptions
            .listeners()
            .into_iter()
            .map(|listener| waitset.attach_notification(listener))
            .collect::<Result<Vec<_>, _>>()
            .map_err(waitset_error)?;
        let mut clock =
            Clock::from_now(Duration::from_secs_f64(self.config().run.status_interval_s));
        self.watch_all_from_now();
        loop {
            // Woken by a sample, a signal, or SIGCONT after this monitor was stopped (Ctrl-Z,
            // fg): only a termination request stops the run.
            waitset
                .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, WAIT_SLICE)
                .map_err(waitset_error)?;
            if let Some(ending) = self.wake_up(&mut clock)? {
                return Ok(ending);
            }
        }
    }

    /// What one wake-up of the loop does; the ending once the run is over.
    fn wake_up(&mut self, clock: &mut Clock) -> anyhow::Result<Option<Ending>> {
        if let Some(signal) = wire::signals::requested() {
            return Ok(Some(interrupted(signal)));
        }
        self.subscriptions.drain(&mut self.recorder)?;
        if let Some(error) = &self.recorder.write_error {
            bail!("{error}; the run stops (every earlier row is whole)");
        }
        if matches!(self.phase, Phase::Running) {
            self.kill_stale();
        }
        for (event, line) in self.supervisor.take_camera_events() {
            eprintln!("run: {line}");
            self.camera_away = event.away();
        }
        if let Some(ending) = self.handle_exits()? {
            return Ok(Some(ending));
        }
        self.follow_remote_rig()?;
        if self.drained()? {
            return Ok(Some(Ending::Completed));
        }
        if Instant::now() >= clock.next_status {
            self.every_status_interval(clock);
        }
        Ok(None)
    }

    /// The dashboard's process table, the histograms when due, the status line.
    fn every_status_interval(&mut self, clock: &mut Clock) {
        self.supervisor.sample_cpu();
        crate::dashboard_view::update(
            &self.dashboard,
            &self.supervisor,
            &self.incidents.faults,
            &self.incidents.restarts,
            &self.incidents.restart_counts,
            self.started,
        );
        crate::dashboard_view::update_gauges(&self.dashboard, &self.recorder.gauge_history);
        if clock.next_histograms <= Instant::now() {
            // Kept up to date, so a run killed outright still leaves its latencies (a write
            // error is reported once at the end, when they are written again).
            let _ = super::outputs::write_histograms(&self.prepared.results, &self.recorder);
            clock.next_histograms = Instant::now() + HISTOGRAM_EVERY;
        }
        if self.options.status {
            let elapsed_s = self.started.elapsed().as_secs_f64();
            let line = crate::status::line(&self.recorder, elapsed_s, self.options.verbose);
            match self.camera_away {
                true => println!("{line} | CAMERA LOST, reconnecting"),
                false => println!("{line}"),
            }
        }
        clock.next();
    }
}
