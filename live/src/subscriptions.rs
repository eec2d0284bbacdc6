//! The monitor's ports: it listens to every service of the run (frames, fields, rig state,
//! identification) and hands each sample to the [`Recorder`]. Frames are looked at in place
//! (header, and the pixels of the first frame only) and released at once.

use crate::recorder::Recorder;
use anyhow::Context;
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use wire::pubsub::{SliceSubscriber, ValueSubscriber};
use wire::{services, FieldHeader, FieldNode, FrameHeader, IdentificationReport, RigState};

pub struct Subscriptions {
    frames: SliceSubscriber<u16, FrameHeader>,
    fields: SliceSubscriber<FieldNode, FieldHeader>,
    rig: ValueSubscriber<RigState>,
    reports: ValueSubscriber<IdentificationReport>,
    /// The finite-element specimen's solves: the truth of its frames. Not woken on (a rig
    /// sample always follows a solve).
    specimen: SliceSubscriber<f64, wire::SpecimenHeader>,
}

impl Subscriptions {
    pub fn new(node: &Node<ipc::Service>) -> anyhow::Result<Subscriptions> {
        Ok(Subscriptions {
            frames: SliceSubscriber::create(node, &services::FRAMES).context("monitor")?,
            fields: SliceSubscriber::create(node, &services::FIELDS).context("monitor")?,
            rig: ValueSubscriber::create(node, &services::RIG_STATE).context("monitor")?,
            reports: ValueSubscriber::create(node, &services::IDENTIFICATION).context("monitor")?,
            specimen: SliceSubscriber::create(node, &services::SPECIMEN).context("monitor")?,
        })
    }

    /// The listeners to attach to the run's WaitSet.
    pub fn listeners(&self) -> [&Listener<ipc::Service>; 4] {
        [
            self.frames.listener(),
            self.fields.listener(),
            self.rig.listener(),
            self.reports.listener(),
        ]
    }

    /// Takes the pending samples of every service into `recorder` (specimen solves, then rig
    /// states: frames and fields name them), at most a queue's worth of each per call, and
    /// returns how many it took. Bounded so that a recorder slower than the samples arrive
    /// cannot hold the monitor here: its loop must still look at signals, exits and stale
    /// children between two drains (unbounded, a recorder slowed down by a debugging dump once
    /// kept a run going 25 minutes past its rig's end, the rig's exit unseen). What overflows
    /// a queue meanwhile is lost to the recorder, as to any slow subscriber.
    pub fn drain(&self, recorder: &mut Recorder) -> anyhow::Result<usize> {
        self.frames.clear_events();
        self.fields.clear_events();
        self.rig.clear_events();
        self.reports.clear_events();
        self.specimen.clear_events();
        let mut taken = take_at_most(
            services::SPECIMEN.subscriber_buffer,
            || self.specimen.receive(),
            |solve| recorder.on_specimen(solve.user_header(), solve.payload()),
        )?;
        taken += take_at_most(
            services::RIG_STATE.subscriber_buffer,
            || self.rig.receive(),
            |state| recorder.on_rig(state),
        )?;
        taken += take_at_most(
            services::FRAMES.subscriber_buffer,
            || self.frames.receive(),
            |frame| recorder.on_frame(frame.user_header(), frame.payload()),
        )?;
        taken += take_at_most(
            services::FIELDS.subscriber_buffer,
            || self.fields.receive(),
            |field| {
                let seen_ns = wire::monotonic_ns();
                recorder.on_field(field.user_header(), field.payload(), seen_ns);
            },
        )?;
        taken += take_at_most(
            services::IDENTIFICATION.subscriber_buffer,
            || self.reports.receive(),
            |report| recorder.on_report(report),
        )?;
        Ok(taken)
    }

    /// Drains until nothing is pending, for when the publishers have stopped (the end of a
    /// run): at most `max_rounds` drains, so a publisher still running cannot hold it.
    pub fn drain_all(&self, recorder: &mut Recorder, max_rounds: usize) -> anyhow::Result<()> {
        for _ in 0..max_rounds {
            if self.drain(recorder)? == 0 {
                break;
            }
        }
        Ok(())
    }
}

/// Hands at most `cap` samples from `receive` to `handle`; how many it handed.
fn take_at_most<S, E>(
    cap: usize,
    mut receive: impl FnMut() -> Result<Option<S>, E>,
    mut handle: impl FnMut(S),
) -> anyhow::Result<usize>
where
    E: std::error::Error + Send + Sync + 'static,
{
    for taken in 0..cap {
        match receive().context("monitor")? {
            Some(sample) => handle(sample),
            None => return Ok(taken),
        }
    }
    Ok(cap)
}

#[cfg(test)]
mod tests {
    use super::take_at_most;

    fn lost() -> std::io::Error {
        std::io::Error::other("lost")
    }

    #[test]
    fn a_source_that_never_runs_dry_is_taken_a_queue_at_a_time() {
        let mut handled = 0;
        let taken = take_at_most(
            8,
            || Ok::<_, std::io::Error>(Some(1)),
            |s: i32| handled += s,
        )
        .unwrap();
        assert_eq!((taken, handled), (8, 8));
    }

    #[test]
    fn a_source_that_runs_dry_is_taken_to_its_end() {
        let mut pending = vec![3, 2, 1];
        let mut seen = Vec::new();
        let taken = take_at_most(
            8,
            || Ok::<_, std::io::Error>(pending.pop()),
            |s| seen.push(s),
        )
        .unwrap();
        assert_eq!((taken, seen), (3, vec![1, 2, 3]));
    }

    #[test]
    fn a_receive_error_is_the_monitors() {
        let error = take_at_most(8, || Err::<Option<i32>, _>(lost()), |_| {}).unwrap_err();
        assert_eq!(format!("{error:#}"), "monitor: lost");
    }
}
