//! Waveform programs: per channel, a sequence of segments (ramp to a level at a rate, hold,
//! sine, triangle, CSV profile playback), levels absolute or relative to the level the segment
//! starts from. Parsed from TOML (and CSV files) and compiled at start, when the start levels
//! are known; evaluated each step without allocation.
//!
//! ```toml
//! name = "equibiaxial to 2"
//! stop = "stay"                       # or "ramp_to_zero", with stop_rate_per_s
//! [[setup]]
//! axis = "x"
//! control = "centroid_displacement"   # "independent", "centroid_force"
//! [[channel]]
//! target = "x.elongation"            # "x+", "y-", "z.centre", ...
//! segments = [
//!   { kind = "hold", duration_s = 1.0 },
//!   { kind = "ramp", to = 100.0, rate_per_s = 0.1 },
//!   { kind = "sine", amplitude = 1.0, frequency_hz = 0.5, cycles = 3 },
//!   { kind = "csv", path = "profile.csv", relative = true },   # t_s,value rows
//! ]
//! ```

use crate::control::{AxisControl, ControlMode};
use crate::ids::{Axis, Channel};
use serde::Deserialize;

/// Most channels a program drives (6 actuators + 3 elongations + 3 centres, at most 9 active).
pub const MAX_PROGRAM_CHANNELS: usize = 12;
/// Most segments per channel, and most samples of one CSV profile.
pub const MAX_SEGMENTS: usize = 1024;
pub const MAX_PROFILE_SAMPLES: usize = 1_000_000;

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Segment {
    Ramp {
        to: f64,
        rate_per_s: f64,
        #[serde(default)]
        relative: bool,
    },
    Hold {
        duration_s: f64,
    },
    Sine {
        amplitude: f64,
        frequency_hz: f64,
        cycles: f64,
    },
    Triangle {
        amplitude: f64,
        frequency_hz: f64,
        cycles: f64,
    },
    Csv {
        path: String,
        #[serde(default)]
        relative: bool,
    },
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopTransition {
    /// Set-points stay where they are.
    #[default]
    Stay,
    /// Every programmed channel ramps to zero at `stop_rate_per_s`.
    RampToZero,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SetupEntry {
    pub axis: String,
    pub control: String,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelProgramFile {
    pub target: String,
    pub segments: Vec<Segment>,
}

/// A program as written in a TOML file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProgramFile {
    #[serde(default)]
    pub name: String,
    #[serde(default)]
    pub stop: StopTransition,
    #[serde(default = "default_stop_rate")]
    pub stop_rate_per_s: f64,
    #[serde(default)]
    pub setup: Vec<SetupEntry>,
    pub channel: Vec<ChannelProgramFile>,
}

fn default_stop_rate() -> f64 {
    1.0
}

/// A segment with CSV profiles loaded, ready to compile.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    Ramp {
        to: f64,
        rate_per_s: f64,
        relative: bool,
    },
    Hold {
        duration_s: f64,
    },
    Sine {
        amplitude: f64,
        frequency_hz: f64,
        cycles: f64,
    },
    Triangle {
        amplitude: f64,
        frequency_hz: f64,
        cycles: f64,
    },
    Profile {
        t_s: Vec<f64>,
        value: Vec<f64>,
        relative: bool,
    },
}

/// A validated program, not yet bound to start levels.
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    pub name: String,
    pub stop: StopTransition,
    pub stop_rate_per_s: f64,
    pub setup: Vec<(Axis, AxisControl)>,
    pub channels: Vec<(Channel, Vec<Step>)>,
}

impl Program {
    /// Parse a TOML program; CSV paths are relative to `base_dir`.
    pub fn from_toml(text: &str, base_dir: &std::path::Path) -> Result<Program, String> {
        let file: ProgramFile = toml::from_str(text).map_err(|e| format!("program TOML: {e}"))?;
        Program::from_file(file, base_dir)
    }

    pub fn from_file(file: ProgramFile, base_dir: &std::path::Path) -> Result<Program, String> {
        let mut setup = Vec::new();
        for entry in &file.setup {
            let axis = match entry.axis.to_ascii_lowercase().as_str() {
                "x" => Axis::X,
                "y" => Axis::Y,
                "z" => Axis::Z,
                other => return Err(format!("setup axis {other:?}: expected x, y or z")),
            };
            let control = match entry.control.as_str() {
                "independent" => AxisControl::Independent,
                "centroid_displacement" => AxisControl::Centroid(ControlMode::Displacement),
                "centroid_force" => AxisControl::Centroid(ControlMode::Force),
                other => {
                    return Err(format!(
                        "setup control {other:?}: expected independent, centroid_displacement \
                         or centroid_force"
                    ))
                }
            };
            setup.push((axis, control));
        }
        let mut channels = Vec::new();
        for c in file.channel {
            let channel = Channel::parse(&c.target).ok_or_else(|| {
                format!(
                    "channel target {:?}: expected x+, x-, x.elongation, x.centre, ...",
                    c.target
                )
            })?;
            let mut steps = Vec::new();
            for segment in c.segments {
                steps.push(load_segment(segment, base_dir)?);
            }
            channels.push((channel, steps));
        }
        let program = Program {
            name: file.name,
            stop: file.stop,
            stop_rate_per_s: file.stop_rate_per_s,
            setup,
            channels,
        };
        program.validate()?;
        Ok(program)
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.channels.is_empty() || self.channels.len() > MAX_PROGRAM_CHANNELS {
            return Err(format!(
                "a program drives 1 to {MAX_PROGRAM_CHANNELS} channels, this one {}",
                self.channels.len()
            ));
        }
        if !(self.stop_rate_per_s.is_finite() && self.stop_rate_per_s > 0.0) {
            return Err(format!(
                "stop_rate_per_s {} must be positive",
                self.stop_rate_per_s
            ));
        }
        for (i, (channel, steps)) in self.channels.iter().enumerate() {
            if self.channels[..i].iter().any(|(c, _)| c == channel) {
                return Err(format!("{channel:?} is programmed twice"));
            }
            if steps.is_empty() || steps.len() > MAX_SEGMENTS {
                return Err(format!(
                    "{channel:?}: 1 to {MAX_SEGMENTS} segments expected"
                ));
            }
            for step in steps {
                validate_step(step).map_err(|e| format!("{channel:?}: {e}"))?;
            }
        }
        Ok(())
    }
}

fn validate_step(step: &Step) -> Result<(), String> {
    let positive = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(format!("{name} = {v}, expected a positive finite number"))
        }
    };
    match step {
        Step::Ramp { to, rate_per_s, .. } => {
            if !to.is_finite() {
                return Err(format!("ramp level {to} is not finite"));
            }
            positive("rate_per_s", *rate_per_s)
        }
        Step::Hold { duration_s } => positive("duration_s", *duration_s),
        Step::Sine {
            amplitude,
            frequency_hz,
            cycles,
        }
        | Step::Triangle {
            amplitude,
            frequency_hz,
            cycles,
        } => {
            if !amplitude.is_finite() {
                return Err(format!("amplitude {amplitude} is not finite"));
            }
            positive("frequency_hz", *frequency_hz)?;
            positive("cycles", *cycles)
        }
        Step::Profile { t_s, value, .. } => {
            if t_s.len() < 2 || t_s.len() != value.len() || t_s.len() > MAX_PROFILE_SAMPLES {
                return Err("a CSV profile needs 2 or more (t_s, value) rows".into());
            }
            if t_s[0] != 0.0 {
                return Err("a CSV profile starts at t_s = 0".into());
            }
            if !t_s.windows(2).all(|w| w[1] > w[0]) || !value.iter().all(|v| v.is_finite()) {
                return Err("CSV profile times must increase and values be finite".into());
            }
            Ok(())
        }
    }
}

fn load_segment(segment: Segment, base_dir: &std::path::Path) -> Result<Step, String> {
    Ok(match segment {
        Segment::Ramp {
            to,
            rate_per_s,
            relative,
        } => Step::Ramp {
            to,
            rate_per_s,
            relative,
        },
        Segment::Hold { duration_s } => Step::Hold { duration_s },
        Segment::Sine {
            amplitude,
            frequency_hz,
            cycles,
        } => Step::Sine {
            amplitude,
            frequency_hz,
            cycles,
        },
        Segment::Triangle {
            amplitude,
            frequency_hz,
            cycles,
        } => Step::Triangle {
            amplitude,
            frequency_hz,
            cycles,
        },
        Segment::Csv { path, relative } => {
            let full = base_dir.join(&path);
            let text = std::fs::read_to_string(&full)
                .map_err(|e| format!("CSV profile {}: {e}", full.display()))?;
            let (t_s, value) = parse_profile_csv(&text)
                .map_err(|e| format!("CSV profile {}: {e}", full.display()))?;
            Step::Profile {
                t_s,
                value,
                relative,
            }
        }
    })
}

/// Rows `t_s,value`; blank lines, `#` comments and one non-numeric header line are skipped.
pub fn parse_profile_csv(text: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
    let mut t_s = Vec::new();
    let mut value = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut fields = line.split(',').map(str::trim);
        let (Some(a), Some(b)) = (fields.next(), fields.next()) else {
            return Err(format!("line {}: expected t_s,value", number + 1));
        };
        match (a.parse::<f64>(), b.parse::<f64>()) {
            (Ok(t), Ok(v)) => {
                t_s.push(t);
                value.push(v);
            }
            _ if t_s.is_empty() && number == 0 => continue, // header
            _ => return Err(format!("line {}: {line:?} is not two numbers", number + 1)),
        }
        if t_s.len() > MAX_PROFILE_SAMPLES {
            return Err(format!("more than {MAX_PROFILE_SAMPLES} rows"));
        }
    }
    Ok((t_s, value))
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_program_parses_and_runs() {
        let text = r#"
            name = "demo"
            stop = "ramp_to_zero"
            stop_rate_per_s = 2.0
            [[setup]]
            axis = "x"
            control = "centroid_displacement"
            [[channel]]
            target = "x.elongation"
            segments = [
              { kind = "ramp", to = 10.0, rate_per_s = 5.0 },
              { kind = "hold", duration_s = 1.0 },
              { kind = "triangle", amplitude = 1.0, frequency_hz = 1.0, cycles = 1 },
              { kind = "ramp", to = -4.0, rate_per_s = 2.0, relative = true },
            ]
        "#;
        let program = Program::from_toml(text, std::path::Path::new(".")).unwrap();
        let mut run = Run::bind(&program, &[0.0]);
        assert!((run.duration_s() - 6.0).abs() < 1e-12);
        let mut last = 0.0;
        let mut at = |run: &mut Run, t: f64| {
            let dt = t - run.t_s;
            run.advance(dt, |_, v| last = v);
            last
        };
        assert!((at(&mut run, 1.0) - 5.0).abs() < 1e-9);
        assert!((at(&mut run, 2.5) - 10.0).abs() < 1e-9);
        assert!((at(&mut run, 3.25) - 11.0).abs() < 1e-9);
        assert!((at(&mut run, 3.75) - 9.0).abs() < 1e-9);
        assert!((at(&mut run, 6.0) - 6.0).abs() < 1e-9);
        assert!(run.is_finished());
        let env = run.envelopes().next().unwrap().1;
        assert_eq!((env.min, env.max, env.max_rate_per_s), (0.0, 11.0, 5.0));
    }

    #[test]
    fn csv_profile_interpolates() {
        let (t, v) = parse_profile_csv("t_s,value\n0,0\n1,2\n3,2\n").unwrap();
        let program = Program {
            name: String::new(),
            stop: StopTransition::Stay,
            stop_rate_per_s: 1.0,
            setup: vec![],
            channels: vec![(
                Channel::Actuator(crate::ids::ActuatorId::ZPlus),
                vec![Step::Profile {
                    t_s: t,
                    value: v,
                    relative: true,
                }],
            )],
        };
        program.validate().unwrap();
        let mut run = Run::bind(&program, &[1.0]);
        let mut last = 0.0;
        run.advance(0.5, |_, v| last = v);
        assert!((last - 2.0).abs() < 1e-12);
    }

    #[test]
    fn bad_programs_are_rejected_with_a_reason() {
        let err = Program::from_toml(
            "[[channel]]\ntarget = \"w+\"\nsegments = []",
            std::path::Path::new("."),
        )
        .unwrap_err();
        assert!(err.contains("w+"), "{err}");
        let err = Program::from_toml(
            "[[channel]]\ntarget = \"x+\"\nsegments = [{ kind = \"ramp\", to = 1.0, rate_per_s = 0.0 }]",
            std::path::Path::new("."),
        )
        .unwrap_err();
        assert!(err.contains("rate_per_s"), "{err}");
    }
}
