//! [`StrainRun`]: a strain-controlled test from mounting to unloading, as the rig process runs
//! it (pure; the shell feeds it the newest field each control step). It mounts the cruciform
//! specimen, waits at rest for a usable field, runs the test's strain program with
//! [`StrainControl`], then unloads in displacement control (a ramp of both elongations to 0).
//!
//! Without fields the grips never move: before the start the rig stays at rest (and says,
//! once the stale limit has passed, that it waits); during the program an interlock holds the
//! present elongation (the `held` mode) until fields are usable again (resume) or ends the test
//! there and unloads (stop).

use crate::campaign::{UNLOADED_HOLD_S, UNLOAD_RATE_FACTOR};
use crate::control::{AxisControl, ControlMode};
use crate::ids::{Axis, Channel};
use crate::program::{Program, Step, StopTransition};
use crate::refusal::Refusal;
use crate::rig::{Rig, RigCommand};
use crate::snapshot::ProgramStatus;
use crate::specimen::SpecimenConfig;
use crate::strain::control::{StrainControl, StrainEvent, StrainMode, StrainStartError};
use crate::strain::interlock::HoldReason;
use crate::strain::outer::{GaugeMeasurement, OuterLoopConfig};
use crate::strain::settle::ProgramEnd;
use crate::strain::test::StrainTest;
use wire::RigControl;

#[derive(Clone, Debug, PartialEq)]
pub enum Phase {
    /// At rest, waiting for a usable field to start from.
    Waiting,
    /// The strain program runs (or is held by an interlock).
    Controlling,
    /// Back to the mounting position in displacement control.
    Unloading,
    Finished,
}

/// What a control step changed, for the shell to report.
#[derive(Clone, Debug, PartialEq)]
pub enum StrainRunEvent {
    /// The program started from these measured log strains.
    Started {
        from_log: [f64; 2],
    },
    /// No usable field came within the stale limit of the start (reported once per wait).
    Waiting(HoldReason),
    Held(HoldReason),
    Resumed,
    /// The program ended, at its last target or short of it, or was stopped by an interlock
    /// with `stop`: unloading.
    Unloading(ProgramEnd),
    Finished,
}

/// Why a strain run could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum StrainRunError {
    #[error("mounting the cruciform specimen: {0}")]
    Mount(Refusal),
    #[error(transparent)]
    Start(#[from] StrainStartError),
}

/// The `rig.csv` control column and the targets of a row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlColumns {
    /// Displacement, strain or held (its `name()` is the `rig.csv` column, its code the
    /// published `RigState::control_mode`).
    pub mode: RigControl,
    /// (ln λx, ln λy) the strain loop aims at; None under displacement control.
    pub target_log: Option<[f64; 2]>,
}

impl ControlColumns {
    pub const DISPLACEMENT: ControlColumns = ControlColumns {
        mode: RigControl::Displacement,
        target_log: None,
    };
}

pub struct StrainRun {
    test: StrainTest,
    control: StrainControl,
    phase: Phase,
    /// Steps since the start with no usable field (Waiting).
    waited_s: f64,
    waiting_reported: bool,
    stopped: bool,
}

impl StrainRun {
    /// Mounts `specimen` (a cruciform) on the unloaded `rig` and gets ready; nothing moves
    /// before the first usable field.
    pub fn new(
        rig: &mut Rig,
        test: StrainTest,
        specimen: SpecimenConfig,
    ) -> Result<StrainRun, StrainRunError> {
        rig.command(RigCommand::MountSpecimen(Some(Box::new(specimen))))
            .map_err(StrainRunError::Mount)?;
        let loop_config = OuterLoopConfig::for_specimen(
            rig.specimen().expect("the specimen was mounted just now"),
        );
        let control = StrainControl::new(rig, loop_config, test.limits, test.on_interlock)?;
        Ok(StrainRun {
            test,
            control,
            phase: Phase::Waiting,
            waited_s: 0.0,
            waiting_reported: false,
            stopped: false,
        })
    }

    pub fn test(&self) -> &StrainTest {
        &self.test
    }

    pub fn phase(&self) -> &Phase {
        &self.phase
    }

    /// The test has unloaded, or was stopped by a limit of the rig while unloading.
    pub fn is_done(&self) -> bool {
        self.phase == Phase::Finished
    }

    /// The test ended because of an interlock with `stop`.
    pub fn was_stopped(&self) -> bool {
        self.stopped
    }

    pub fn columns(&self) -> ControlColumns {
        match (&self.phase, self.control.mode()) {
            (Phase::Waiting, _) => ControlColumns {
                mode: RigControl::Held,
                target_log: None,
            },
            (Phase::Controlling, StrainMode::Strain) => ControlColumns {
                mode: RigControl::Strain,
                target_log: Some(self.control.target()),
            },
            (Phase::Controlling, _) => ControlColumns {
                mode: RigControl::Held,
                target_log: Some(self.control.target()),
            },
            _ => ControlColumns::DISPLACEMENT,
        }
    }

    /// One control step, before `rig.step()`, with the newest field known (on the rig's clock).
    pub fn before_step(
        &mut self,
        rig: &mut Rig,
        newest: Option<&GaugeMeasurement>,
    ) -> Option<StrainRunEvent> {
        match self.phase {
            Phase::Waiting => {
                self.control.advance(rig, None);
                let now = rig.state().t_s;
                let usable = newest.filter(|m| {
                    self.test.limits.check_sample(m).is_ok()
                        && self.test.limits.check_age(now, m.t_capture_s).is_ok()
                });
                if let Some(m) = usable {
                    let path = self.test.path().expect("a checked test has a path");
                    match self.control.start(rig, path, m) {
                        Ok(()) => {
                            self.phase = Phase::Controlling;
                            return Some(StrainRunEvent::Started {
                                from_log: m.log_strain,
                            });
                        }
                        // Not aligned yet (the rig's history is shorter than the latency):
                        // the next field will do.
                        Err(StrainStartError::Measurement(_)) => {}
                        Err(other) => {
                            // The rig refused the centroid set-up: nothing moved; end here.
                            self.phase = Phase::Finished;
                            return Some(StrainRunEvent::Held(HoldReason::Refused(
                                other.to_string(),
                            )));
                        }
                    }
                }
                self.waited_s += rig.dt_s();
                if !self.waiting_reported && self.waited_s > self.test.limits.stale_s {
                    self.waiting_reported = true;
                    let reason = match newest {
                        Some(m) => self
                            .test
                            .limits
                            .check_sample(m)
                            .and_then(|()| self.test.limits.check_age(now, m.t_capture_s))
                            .err()
                            .unwrap_or(HoldReason::NotAligned {
                                t_capture_s: m.t_capture_s,
                            }),
                        None => HoldReason::Stale {
                            age_s: self.waited_s,
                            limit_s: self.test.limits.stale_s,
                        },
                    };
                    return Some(StrainRunEvent::Waiting(reason));
                }
                None
            }
            Phase::Controlling => {
                let event = self.control.advance(rig, newest);
                match event {
                    Some(StrainEvent::Held(reason)) => Some(StrainRunEvent::Held(reason)),
                    Some(StrainEvent::Resumed) => Some(StrainRunEvent::Resumed),
                    Some(StrainEvent::Finished(end)) => {
                        self.stopped = end == ProgramEnd::Stopped;
                        match rig.command(RigCommand::StartProgram(Box::new(self.unload(rig)))) {
                            Ok(()) => self.phase = Phase::Unloading,
                            // Cannot unload (a tripped limit): stay where the rig put it.
                            Err(_) => self.phase = Phase::Finished,
                        }
                        Some(StrainRunEvent::Unloading(end))
                    }
                    None => None,
                }
            }
            Phase::Unloading => {
                self.control.advance(rig, None);
                match rig.state().program {
                    ProgramStatus::Running | ProgramStatus::Held => None,
                    _ => {
                        self.phase = Phase::Finished;
                        Some(StrainRunEvent::Finished)
                    }
                }
            }
            Phase::Finished => {
                self.control.advance(rig, None);
                None
            }
        }
    }

    /// Both elongations back to 0 at the campaign's unloading rate, then a short hold.
    fn unload(&self, rig: &Rig) -> Program {
        let gauge_mm = rig
            .specimen()
            .map(|s| s.config().gauge_mm()[0])
            .expect("a strain run has its specimen");
        let rate_mm_s = UNLOAD_RATE_FACTOR * self.test.rate_log_per_s * gauge_mm;
        let centroid = AxisControl::Centroid(ControlMode::Displacement);
        Program {
            name: format!("unload after strain-controlled {}", self.test.kind.name()),
            stop: StopTransition::RampToZero,
            stop_rate_per_s: rate_mm_s,
            setup: vec![(Axis::X, centroid), (Axis::Y, centroid)],
            channels: [Axis::X, Axis::Y]
                .map(|axis| {
                    (
                        Channel::Elongation(axis),
                        vec![
                            Step::Ramp {
                                to: 0.0,
                                rate_per_s: rate_mm_s,
                                relative: false,
                            },
                            Step::Hold {
                                duration_s: UNLOADED_HOLD_S,
                            },
                        ],
                    )
                })
                .into_iter()
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin::BuiltinTest;
    use crate::strain::control::OnRestore;
    use crate::strain::StrainKind;
    use crate::RigConfig;

    /// The gauge truth as a field captured at 20 Hz and delivered 0.1 s later, until `stop_s`.
    fn run(
        test: StrainTest,
        stop_s: f64,
        restart_s: f64,
        budget_s: f64,
    ) -> (Rig, StrainRun, Vec<StrainRunEvent>, Vec<RigControl>) {
        let mut rig = Rig::new(RigConfig::default(), 1).unwrap();
        let mut strain = StrainRun::new(
            &mut rig,
            test,
            BuiltinTest::Equibiaxial.specimen(&Default::default()),
        )
        .unwrap();
        let mut in_flight: Vec<GaugeMeasurement> = Vec::new();
        let mut newest: Option<GaugeMeasurement> = None;
        let mut next_capture_s = 0.0;
        let mut events = Vec::new();
        let mut modes = Vec::new();
        for _ in 0..(budget_s * rig.config().control_hz) as usize {
            if let Some(e) = strain.before_step(&mut rig, newest.as_ref()) {
                events.push(e);
            }
            rig.step();
            modes.push(strain.columns().mode);
            let s = rig.state();
            let camera_on = s.t_s < stop_s || s.t_s >= restart_s;
            if camera_on && s.t_s >= next_capture_s {
                next_capture_s = s.t_s + 0.05;
                in_flight.push(GaugeMeasurement {
                    t_capture_s: s.t_s,
                    log_strain: [s.specimen.stretch_x.ln(), s.specimen.stretch_y.ln()],
                    valid_nodes: 400,
                });
            }
            while in_flight
                .first()
                .is_some_and(|m| m.t_capture_s + 0.1 <= s.t_s)
            {
                newest = Some(in_flight.remove(0));
            }
            if strain.is_done() {
                break;
            }
        }
        (rig, strain, events, modes)
    }

    #[test]
    fn a_pure_shear_run_starts_on_a_field_holds_its_path_and_unloads() {
        let test = StrainTest::new(StrainKind::PureShear, None, 1.3, 0.05).unwrap();
        let (rig, strain, events, _) = run(test, f64::INFINITY, 0.0, 30.0);
        assert!(strain.is_done(), "{events:?}");
        assert!(matches!(events[0], StrainRunEvent::Started { .. }));
        // The program ended at its last target (the measurement here is the truth, 0.1 s
        // late), not when its clock did.
        assert!(
            events
                .iter()
                .any(|e| matches!(e, StrainRunEvent::Unloading(ProgramEnd::Reached { .. }))),
            "{events:?}"
        );
        // Unloaded.
        for axis in 0..2 {
            assert!(rig.state().axes[axis].elongation_mm.abs() < 0.1);
        }
    }

    #[test]
    fn without_fields_nothing_moves_and_the_wait_is_reported() {
        let test = StrainTest::new(StrainKind::Equibiaxial, None, 1.5, 0.05).unwrap();
        let (rig, strain, events, modes) = run(test, 0.0, f64::INFINITY, 3.0);
        assert_eq!(strain.phase(), &Phase::Waiting);
        assert!(
            matches!(
                events.as_slice(),
                [StrainRunEvent::Waiting(HoldReason::Stale { .. })]
            ),
            "{events:?}"
        );
        assert!(modes.iter().all(|m| *m == RigControl::Held));
        for axis in 0..2 {
            assert!(rig.state().axes[axis].elongation_mm.abs() < 0.05);
        }
    }

    #[test]
    fn fields_stopped_mid_ramp_hold_then_resume_or_stop_as_configured() {
        for (on, resumes) in [(OnRestore::Resume, true), (OnRestore::Stop, false)] {
            let test = StrainTest::new(StrainKind::Equibiaxial, None, 1.4, 0.05)
                .unwrap()
                .with_interlocks(0.5, 16, on)
                .unwrap();
            let (_, strain, events, modes) = run(test, 3.0, 5.0, 40.0);
            assert!(strain.is_done(), "{events:?}");
            let held = events
                .iter()
                .position(|e| matches!(e, StrainRunEvent::Held(HoldReason::Stale { .. })))
                .expect("held on stale fields");
            assert!(modes.contains(&RigControl::Held));
            if resumes {
                assert_eq!(events[held + 1], StrainRunEvent::Resumed, "{events:?}");
                assert!(!strain.was_stopped());
            } else {
                assert_eq!(
                    events[held + 1],
                    StrainRunEvent::Unloading(ProgramEnd::Stopped),
                    "{events:?}"
                );
                assert!(strain.was_stopped());
            }
        }
    }
}
