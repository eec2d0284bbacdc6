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
//!
//! Two halves: `parse.rs` turns a program file into a checked [`Program`] (refusals name the
//! line, the channel or the file), `run.rs` binds a program to its start levels and evaluates
//! it in program time.

mod parse;
mod run;

pub use parse::{
    parse_profile_csv, ChannelProgramFile, ProfileError, ProgramError, ProgramFile, Segment,
    SetupEntry, StepError,
};
pub use run::{Envelope, Run};

use crate::control::AxisControl;
use crate::ids::{Axis, Channel};
use serde::Deserialize;

/// Most channels a program drives (6 actuators + 3 elongations + 3 centres, at most 9 active).
pub const MAX_PROGRAM_CHANNELS: usize = 12;
/// Most segments per channel, and most samples of one CSV profile.
pub const MAX_SEGMENTS: usize = 1024;
pub const MAX_PROFILE_SAMPLES: usize = 1_000_000;

#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopTransition {
    /// Set-points stay where they are.
    #[default]
    Stay,
    /// Every programmed channel ramps to zero at `stop_rate_per_s`.
    RampToZero,
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
    fn a_bad_profile_line_is_named_by_its_number() {
        assert_eq!(
            parse_profile_csv("t_s,value\n0,0\n1,x\n"),
            Err(ProfileError::NotNumbers {
                line: 3,
                text: "1,x".into()
            })
        );
        assert_eq!(
            parse_profile_csv("0,0\n1\n").unwrap_err().to_string(),
            "line 2: expected t_s,value"
        );
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

    /// A bare word as a value is named with what to write instead.
    #[test]
    fn a_bare_word_in_a_program_is_named_with_the_fix() {
        let err = Program::from_toml(
            "[[channel]]\ntarget = x+\nsegments = []",
            std::path::Path::new("."),
        )
        .unwrap_err()
        .to_string();
        assert!(err.starts_with("program TOML: "), "{err}");
        assert!(err.contains("`x+` is not a TOML value"), "{err}");
    }

    #[test]
    fn bad_programs_are_rejected_with_a_reason() {
        let err = Program::from_toml(
            "[[channel]]\ntarget = \"w+\"\nsegments = []",
            std::path::Path::new("."),
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("w+"), "{err}");
        let err = Program::from_toml(
            "[[channel]]\ntarget = \"x+\"\nsegments = [{ kind = \"ramp\", to = 1.0, rate_per_s = 0.0 }]",
            std::path::Path::new("."),
        )
        .unwrap_err();
        assert!(
            matches!(
                err,
                ProgramError::Step {
                    reason: StepError::NotPositive {
                        name: "rate_per_s",
                        ..
                    },
                    ..
                }
            ),
            "{err}"
        );
    }
}
