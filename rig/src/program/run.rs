//! A checked [`Program`] bound to its start levels and run in program time: each segment's
//! level, its envelope (for the limits checked at start), stop transitions. Evaluated each
//! step without allocation.

use super::{Program, Step, StopTransition};
use crate::ids::Channel;

/// A segment bound to its start level and start time.
#[derive(Clone, Debug, PartialEq)]
struct Bound {
    step: Step,
    start_level: f64,
    end_level: f64,
    start_t_s: f64,
    duration_s: f64,
}

impl Bound {
    fn value_at(&self, t_s: f64) -> f64 {
        let tau = (t_s - self.start_t_s).clamp(0.0, self.duration_s);
        match &self.step {
            Step::Ramp { rate_per_s, .. } => {
                let sign = (self.end_level - self.start_level).signum();
                if tau >= self.duration_s {
                    self.end_level
                } else {
                    self.start_level + sign * rate_per_s * tau
                }
            }
            Step::Hold { .. } => self.start_level,
            Step::Sine {
                amplitude,
                frequency_hz,
                ..
            } => self.start_level + amplitude * (std::f64::consts::TAU * frequency_hz * tau).sin(),
            Step::Triangle {
                amplitude,
                frequency_hz,
                ..
            } => {
                // 0 → +A → 0 → −A → 0 per cycle.
                let phase = (tau * frequency_hz).fract();
                let shape = if phase < 0.25 {
                    4.0 * phase
                } else if phase < 0.75 {
                    2.0 - 4.0 * phase
                } else {
                    4.0 * phase - 4.0
                };
                self.start_level + amplitude * shape
            }
            Step::Profile {
                t_s: times,
                value,
                relative,
            } => {
                let offset = if *relative { self.start_level } else { 0.0 };
                // Binary search: bounded by log2(len) iterations.
                let k = times
                    .partition_point(|&t| t <= tau)
                    .clamp(1, times.len() - 1);
                let (t0, t1) = (times[k - 1], times[k]);
                let (v0, v1) = (value[k - 1], value[k]);
                let w = ((tau - t0) / (t1 - t0)).clamp(0.0, 1.0);
                offset + v0 + w * (v1 - v0)
            }
        }
    }

    /// Lowest and highest level reached, and the largest rate (units/s).
    fn envelope(&self) -> (f64, f64, f64) {
        let (lo, hi) = (
            self.start_level.min(self.end_level),
            self.start_level.max(self.end_level),
        );
        match &self.step {
            Step::Ramp { rate_per_s, .. } => (lo, hi, *rate_per_s),
            Step::Hold { .. } => (lo, hi, 0.0),
            Step::Sine {
                amplitude,
                frequency_hz,
                ..
            } => {
                let a = amplitude.abs();
                (lo - a, hi + a, std::f64::consts::TAU * frequency_hz * a)
            }
            Step::Triangle {
                amplitude,
                frequency_hz,
                ..
            } => {
                let a = amplitude.abs();
                (lo - a, hi + a, 4.0 * frequency_hz * a)
            }
            Step::Profile {
                t_s,
                value,
                relative,
            } => {
                let offset = if *relative { self.start_level } else { 0.0 };
                let min = value.iter().copied().fold(f64::INFINITY, f64::min) + offset;
                let max = value.iter().copied().fold(f64::NEG_INFINITY, f64::max) + offset;
                let rate = t_s
                    .windows(2)
                    .zip(value.windows(2))
                    .map(|(t, v)| ((v[1] - v[0]) / (t[1] - t[0])).abs())
                    .fold(0.0, f64::max);
                (min.min(lo), max.max(hi), rate)
            }
        }
    }
}

fn bind(step: &Step, start_level: f64, start_t_s: f64) -> Bound {
    let (end_level, duration_s) = match step {
        Step::Ramp {
            to,
            rate_per_s,
            relative,
        } => {
            let end = if *relative { start_level + to } else { *to };
            (end, (end - start_level).abs() / rate_per_s)
        }
        Step::Hold { duration_s } => (start_level, *duration_s),
        Step::Sine {
            frequency_hz,
            cycles,
            ..
        }
        | Step::Triangle {
            frequency_hz,
            cycles,
            ..
        } => (start_level, cycles / frequency_hz),
        Step::Profile {
            t_s,
            value,
            relative,
        } => {
            let offset = if *relative { start_level } else { 0.0 };
            (offset + value[value.len() - 1], t_s[t_s.len() - 1])
        }
    };
    Bound {
        step: step.clone(),
        start_level,
        end_level,
        start_t_s,
        duration_s,
    }
}

/// Envelope of one channel's program: lowest and highest level, largest rate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Envelope {
    pub min: f64,
    pub max: f64,
    pub max_rate_per_s: f64,
}

#[derive(Clone, Debug, PartialEq)]
struct ChannelRun {
    channel: Channel,
    segments: Vec<Bound>,
    current: usize,
    /// Ramp to zero after a stop: (start level, start time, rate).
    stop_ramp: Option<(f64, f64, f64)>,
    last_value: f64,
}

/// A program bound to its start levels, running in program time.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    pub name: String,
    pub stop: StopTransition,
    pub stop_rate_per_s: f64,
    channels: Vec<ChannelRun>,
    pub t_s: f64,
    stopped: bool,
}

impl Run {
    /// Binds every channel's segments to `start_levels[i]` (the present set-point of channel i).
    pub fn bind(program: &Program, start_levels: &[f64]) -> Run {
        assert_eq!(program.channels.len(), start_levels.len());
        let channels = program
            .channels
            .iter()
            .zip(start_levels)
            .map(|((channel, steps), &start)| {
                let mut segments = Vec::with_capacity(steps.len());
                let (mut level, mut t) = (start, 0.0);
                for step in steps {
                    let bound = bind(step, level, t);
                    level = bound.end_level;
                    t += bound.duration_s;
                    segments.push(bound);
                }
                ChannelRun {
                    channel: *channel,
                    segments,
                    current: 0,
                    stop_ramp: None,
                    last_value: start,
                }
            })
            .collect();
        Run {
            name: program.name.clone(),
            stop: program.stop,
            stop_rate_per_s: program.stop_rate_per_s,
            channels,
            t_s: 0.0,
            stopped: false,
        }
    }

    pub fn envelopes(&self) -> impl Iterator<Item = (Channel, Envelope)> + '_ {
        self.channels.iter().map(|c| {
            let mut e = Envelope {
                min: c.last_value,
                max: c.last_value,
                max_rate_per_s: 0.0,
            };
            for s in &c.segments {
                let (lo, hi, rate) = s.envelope();
                e.min = e.min.min(lo);
                e.max = e.max.max(hi);
                e.max_rate_per_s = e.max_rate_per_s.max(rate);
            }
            (c.channel, e)
        })
    }

    pub fn duration_s(&self) -> f64 {
        self.channels
            .iter()
            .map(|c| {
                c.segments
                    .last()
                    .map_or(0.0, |s| s.start_t_s + s.duration_s)
            })
            .fold(0.0, f64::max)
    }

    /// Whether every channel has finished (its program or its stop ramp).
    pub fn is_finished(&self) -> bool {
        if self.stopped {
            return self.channels.iter().all(|c| match c.stop_ramp {
                None => true,
                Some((start, t0, rate)) => self.t_s - t0 >= start.abs() / rate,
            });
        }
        self.t_s >= self.duration_s()
    }

    pub fn is_stopped(&self) -> bool {
        self.stopped
    }

    /// Stop: `Stay` freezes the levels, `RampToZero` ramps each channel to 0 at `rate`.
    pub fn stop(&mut self, transition: StopTransition, rate_per_s: f64) {
        assert!(rate_per_s > 0.0);
        self.stopped = true;
        for c in &mut self.channels {
            c.stop_ramp = match transition {
                StopTransition::Stay => None,
                StopTransition::RampToZero => Some((c.last_value, self.t_s, rate_per_s)),
            };
        }
    }

    /// Advance program time by `dt_s` and write each channel's level through `emit`.
    pub fn advance(&mut self, dt_s: f64, mut emit: impl FnMut(Channel, f64)) {
        self.t_s += dt_s;
        let t = self.t_s;
        for c in &mut self.channels {
            let value = if self.stopped {
                match c.stop_ramp {
                    None => c.last_value,
                    Some((start, t0, rate)) => {
                        let travelled = (t - t0) * rate;
                        if travelled >= start.abs() {
                            0.0
                        } else {
                            start - start.signum() * travelled
                        }
                    }
                }
            } else {
                // Bounded: at most one pass over the segments.
                while c.current + 1 < c.segments.len() {
                    let s = &c.segments[c.current];
                    if t < s.start_t_s + s.duration_s {
                        break;
                    }
                    c.current += 1;
                }
                c.segments[c.current].value_at(t)
            };
            c.last_value = value;
            emit(c.channel, value);
        }
    }
}
