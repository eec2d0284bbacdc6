//! Which child has stopped responding. A child is stale when it has been stopped (process
//! state `T`: SIGSTOP, a debugger) for the stale time, or when it has published nothing for
//! that long while its input kept coming (the rig always publishes; the camera publishes when
//! rig states come; the correlator when frames come). The identifier publishes only when a
//! new point is accepted, so what is watched is that it hears its input: it says so at its
//! first field, and fields published for the stale time without that line mean a subscriber
//! that never connected (it would end the run with nothing identified and no fault). Pure:
//! the run feeds it the counts of samples seen per service, whether the identifier heard a
//! field, and the children's stopped states.

use crate::children::Role;
use std::time::{Duration, Instant};

/// Samples seen so far on each service of the run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    pub rig_states: u64,
    pub frames: u64,
    pub fields: u64,
    /// The running identifier said its first field reached it.
    pub identifier_heard_fields: bool,
}

impl Counts {
    /// What `role` publishes, and what it is fed (None: it publishes on its own clock;
    /// the identifier's output is not watched, see the module's text).
    fn of(&self, role: Role) -> Option<(u64, Option<u64>)> {
        match role {
            Role::Rig => Some((self.rig_states, None)),
            Role::Producer => Some((self.frames, Some(self.rig_states))),
            Role::Correlator => Some((self.fields, Some(self.frames))),
            // The identifier is watched by what it heard; a link publishes what the far host
            // sends, whose silence is no hang of its own (a stopped link is still caught).
            Role::Identifier | Role::Link => None,
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Watch {
    output: u64,
    /// When the output last changed (or the watch started).
    output_since: Instant,
    /// The input count when the output last changed.
    input_then: Option<u64>,
    stopped_since: Option<Instant>,
    /// The identifier: fields it was to hear published since (its first after the start).
    fields_since: Option<Instant>,
    fields_then: u64,
}

pub struct Liveness {
    stale_after: Duration,
    watches: [Option<Watch>; Role::COUNT],
    /// Roles whose silence is not a hang (a real camera, a followed machine log): only their
    /// stopped state is watched.
    silence_ignored: [bool; Role::COUNT],
}

impl Liveness {
    pub fn new(stale_after: Duration) -> Liveness {
        Liveness {
            stale_after,
            watches: [None; Role::COUNT],
            silence_ignored: [false; Role::COUNT],
        }
    }

    /// Watches only whether `role` is stopped, not whether it publishes.
    pub fn ignore_silence(&mut self, role: Role) {
        self.silence_ignored[role as usize] = true;
    }

    /// Starts (or starts again, after a restart) watching `role` from `now`.
    pub fn reset(&mut self, role: Role, counts: &Counts, now: Instant) {
        let (output, input) = counts.of(role).unwrap_or((0, None));
        self.watches[role as usize] = Some(Watch {
            output,
            output_since: now,
            input_then: input,
            stopped_since: None,
            fields_since: None,
            fields_then: counts.fields,
        });
    }

    /// Takes in the counts and which children are stopped; returns the stale ones with why.
    pub fn check(
        &mut self,
        counts: &Counts,
        stopped: impl Fn(Role) -> bool,
        now: Instant,
    ) -> Vec<(Role, String)> {
        let mut stale = Vec::new();
        for role in Role::ALL {
            let Some(watch) = self.watches[role as usize].as_mut() else {
                continue;
            };
            watch.stopped_since = match (stopped(role), watch.stopped_since) {
                (true, None) => Some(now),
                (true, since) => since,
                (false, _) => None,
            };
            if let Some(since) = watch.stopped_since {
                if now.duration_since(since) >= self.stale_after {
                    stale.push((
                        role,
                        format!(
                            "stopped (process state T, e.g. SIGSTOP) for {:.1} s",
                            now.duration_since(since).as_secs_f64()
                        ),
                    ));
                    continue;
                }
            }
            if self.silence_ignored[role as usize] {
                continue;
            }
            if role == Role::Identifier {
                if let Some(why) = deaf(watch, counts, now, self.stale_after) {
                    stale.push((role, why));
                }
                continue;
            }
            let Some((output, input)) = counts.of(role) else {
                continue;
            };
            if output != watch.output {
                watch.output = output;
                watch.output_since = now;
                watch.input_then = input;
                continue;
            }
            let fed = match (input, watch.input_then) {
                (Some(now_in), Some(then_in)) => now_in > then_in,
                _ => true,
            };
            let silent = now.duration_since(watch.output_since);
            if fed && silent >= self.stale_after {
                stale.push((
                    role,
                    format!(
                        "published nothing for {:.1} s{}",
                        silent.as_secs_f64(),
                        if input.is_some() {
                            " while its input kept coming"
                        } else {
                            ""
                        }
                    ),
                ));
            }
        }
        stale
    }
}

/// Why the identifier is deaf: fields published for `stale_after` since it started and
/// none heard. None while it heard one, or nothing was published.
fn deaf(watch: &mut Watch, counts: &Counts, now: Instant, stale_after: Duration) -> Option<String> {
    if counts.identifier_heard_fields {
        return None;
    }
    if watch.fields_since.is_none() && counts.fields > watch.fields_then {
        watch.fields_since = Some(now);
    }
    let since = watch.fields_since?;
    let deaf_for = now.duration_since(since);
    (deaf_for >= stale_after).then(|| {
        format!(
            "received no field for {:.1} s while {} were published (its subscriber never \
             connected: see its log)",
            deaf_for.as_secs_f64(),
            counts.fields - watch.fields_then
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const STALE: Duration = Duration::from_secs(5);

    fn watching_all(counts: &Counts, t0: Instant) -> Liveness {
        let mut liveness = Liveness::new(STALE);
        for role in Role::ALL {
            liveness.reset(role, counts, t0);
        }
        liveness
    }

    #[test]
    fn a_silent_rig_is_stale_after_the_stale_time_only() {
        let t0 = Instant::now();
        let counts = Counts::default();
        let mut liveness = watching_all(&counts, t0);
        assert!(liveness
            .check(&counts, |_| false, t0 + Duration::from_secs(4))
            .is_empty());
        let stale = liveness.check(&counts, |_| false, t0 + Duration::from_secs(6));
        assert_eq!(stale.len(), 1);
        assert_eq!(stale[0].0, Role::Rig);
    }

    #[test]
    fn a_real_camera_and_a_followed_log_may_be_silent_but_not_stopped() {
        let t0 = Instant::now();
        let mut counts = Counts::default();
        let mut liveness = watching_all(&counts, t0);
        liveness.ignore_silence(Role::Rig);
        liveness.ignore_silence(Role::Producer);
        // Rows come, no image: neither the log nor the camera is stale.
        counts.rig_states += 100;
        let later = t0 + Duration::from_secs(60);
        assert!(liveness.check(&counts, |_| false, later).is_empty());
        // A stopped camera still is.
        liveness.check(&counts, |r| r == Role::Producer, later);
        let stale = liveness.check(&counts, |r| r == Role::Producer, later + STALE);
        assert_eq!(
            stale.iter().map(|s| s.0).collect::<Vec<_>>(),
            [Role::Producer]
        );
    }

    #[test]
    fn a_correlator_without_frames_is_not_stale_but_one_fed_and_silent_is() {
        let t0 = Instant::now();
        let mut counts = Counts::default();
        let mut liveness = watching_all(&counts, t0);
        // The rig and the camera publish; no frame reaches... the correlator publishes nothing.
        let mut t = t0;
        for step in 1..=10u64 {
            t = t0 + Duration::from_secs(step);
            counts.rig_states += 100;
            counts.frames += 10;
            let stale = liveness.check(&counts, |_| false, t);
            if step < 5 {
                assert!(stale.is_empty(), "{stale:?}");
            } else {
                assert_eq!(
                    stale.iter().map(|s| s.0).collect::<Vec<_>>(),
                    [Role::Correlator]
                );
            }
        }
        // No frames either: an idle correlator is not stale.
        let mut quiet = watching_all(&counts, t);
        counts.rig_states += 100;
        let stale = quiet.check(&counts, |_| false, t + Duration::from_secs(10));
        assert!(!stale.iter().any(|s| s.0 == Role::Correlator), "{stale:?}");
    }

    #[test]
    fn an_identifier_that_hears_no_field_while_fields_are_published_is_stale() {
        let t0 = Instant::now();
        let mut counts = Counts::default();
        let mut liveness = watching_all(&counts, t0);
        // Long before the first field: not deaf.
        let t1 = t0 + Duration::from_secs(30);
        let stale = liveness.check(&counts, |_| false, t1);
        assert!(!stale.iter().any(|s| s.0 == Role::Identifier), "{stale:?}");
        // Fields come from t1 on, the identifier says nothing: stale after the stale time.
        let mut stale = Vec::new();
        for step in 1..=6u64 {
            counts.rig_states += 100;
            counts.frames += 10;
            counts.fields += 10;
            stale = liveness.check(&counts, |_| false, t1 + Duration::from_secs(step));
            let identifier = stale.iter().find(|s| s.0 == Role::Identifier);
            assert_eq!(identifier.is_some(), step > 5, "step {step}: {stale:?}");
        }
        let why = &stale.iter().find(|s| s.0 == Role::Identifier).unwrap().1;
        assert!(
            why.starts_with("received no field for 5.0 s while 60 were"),
            "{why}"
        );
        // One that said it heard a field is not.
        let mut heard = watching_all(&counts, t1);
        counts.identifier_heard_fields = true;
        counts.fields += 100;
        let stale = heard.check(&counts, |_| false, t1 + Duration::from_secs(60));
        assert!(!stale.iter().any(|s| s.0 == Role::Identifier), "{stale:?}");
    }

    #[test]
    fn a_stopped_identifier_is_stale_and_a_continued_one_is_not() {
        let t0 = Instant::now();
        let counts = Counts::default();
        let mut liveness = Liveness::new(STALE);
        liveness.reset(Role::Identifier, &counts, t0);
        let stopped = |role: Role| role == Role::Identifier;
        assert!(liveness.check(&counts, stopped, t0).is_empty());
        assert!(liveness
            .check(&counts, |_| false, t0 + Duration::from_secs(3))
            .is_empty());
        assert!(liveness
            .check(&counts, stopped, t0 + Duration::from_secs(4))
            .is_empty());
        let stale = liveness.check(&counts, stopped, t0 + Duration::from_secs(10));
        assert_eq!(stale.len(), 1);
        assert!(stale[0].1.contains("stopped"), "{}", stale[0].1);
    }
}
