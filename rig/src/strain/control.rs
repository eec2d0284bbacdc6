//! [`StrainControl`]: runs a strain program on the rig. Call [`StrainControl::advance`] before
//! each [`Rig::step`] with the newest field sample (or None); it writes the X and Y elongation
//! set-points of the pairs, in centroid displacement control (the inner loop).
//!
//! Bumpless both ways: the program starts from the measured strains and the model is set so
//! that its first command is the present elongation; leaving strain control
//! ([`StrainControl::stop`], an interlock, the end of the program) leaves the set-points where
//! they are, in displacement control.
//!
//! Interlocks ([`InterlockLimits`]): a stale field, too few valid nodes, a jump or a NaN put
//! the pairs on a displacement hold at their present elongation and freeze the program clock;
//! the event says why. With [`OnRestore::Resume`], three consecutive good fields resume the
//! program where it was held (the model re-anchored on them); with [`OnRestore::Stop`] the test
//! ends there, held.
//!
//! The program's clock reaching its end is not the gauge reaching the last target: the loop
//! keeps that target until a field shows it ([`crate::strain::settle`]), and the end says
//! whether it did ([`ProgramEnd`]).

use crate::control::{AxisControl, ControlMode};
use crate::ids::{Axis, Channel};
use crate::refusal::Refusal;
use crate::rig::{Rig, RigCommand};
use crate::strain::interlock::{HoldReason, InterlockLimits};
use crate::strain::outer::{GaugeMeasurement, OuterLoop, OuterLoopConfig};
use crate::strain::path::StrainPath;
use crate::strain::settle::{ProgramEnd, Settling, ShortBecause};

/// How far from each grip's stroke limit the loop stops (mm): it ends its program short
/// rather than command the grips onto the limit, where the inner loop's following error
/// would trip it (hydraulics off, no unloading).
pub const STROKE_MARGIN_MM: f64 = 2.0;

/// Good fields in a row that end a hold (with [`OnRestore::Resume`]).
pub const RESUME_AFTER_FIELDS: u32 = 3;

/// What strain control does once fields are usable again after an interlock.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OnRestore {
    #[default]
    Resume,
    Stop,
}

wire::named!(OnRestore, "on_interlock", { Resume => "resume", Stop => "stop" });

#[derive(Clone, Debug, PartialEq)]
pub enum StrainMode {
    /// The outer loop drives the elongation set-points.
    Strain,
    /// Displacement hold after an interlock; may resume.
    Held(HoldReason),
    /// Displacement control: not started yet, or the program ended (or was stopped, or an
    /// interlock ended with [`OnRestore::Stop`]); the set-points stay where they were.
    Done,
}

impl StrainMode {
    /// The `rig.csv` mode column: `strain`, `strain_held`, `displacement`.
    pub fn code(&self) -> &'static str {
        match self {
            StrainMode::Strain => "strain",
            StrainMode::Held(_) => "strain_held",
            StrainMode::Done => "displacement",
        }
    }
}

/// What one [`StrainControl::advance`] changed.
#[derive(Clone, Debug, PartialEq)]
pub enum StrainEvent {
    Held(HoldReason),
    Resumed,
    Finished(ProgramEnd),
}

#[derive(Clone, Debug)]
pub struct StrainControl {
    outer: OuterLoop,
    limits: InterlockLimits,
    on_restore: OnRestore,
    path: StrainPath,
    start: [f64; 2],
    program_t_s: f64,
    duration_s: f64,
    mode: StrainMode,
    last_capture_s: f64,
    good_in_row: u32,
    target: [f64; 2],
    /// Largest elongation change per step (mm), from the rig's rate limits.
    max_step_mm: [f64; 2],
    /// (lowest, highest) elongation the loop commands per pair: the two grips' strokes less
    /// [`STROKE_MARGIN_MM`] each.
    elongation_range_mm: [(f64, f64); 2],
    setpoint_mm: [f64; 2],
    /// Past the program's end, waiting for a field at the last target.
    settling: Option<Settling>,
    /// The newest usable field's log strains (NaN before the first).
    newest_log: [f64; 2],
}

/// Why strain control did not start.
#[derive(Debug, thiserror::Error)]
pub enum StrainStartError {
    #[error("strain control needs a usable field to start from: {0}")]
    Measurement(HoldReason),
    #[error("interlock limits: {0}")]
    Limits(crate::bad_setting::BadSetting),
    #[error("the rig refused: {0}")]
    Rig(#[from] Refusal),
    #[error("strain control needs a specimen mounted")]
    NoSpecimen,
    #[error("strain control drives the X and Y pairs: it needs a cruciform (equibiaxial loading) specimen")]
    NotCruciform,
    #[error("strain loop model: {0}")]
    Model(crate::bad_setting::BadSetting),
}

fn rig_setpoint(rig: &Rig, axis: Axis) -> f64 {
    rig.state().axes[axis.index()].elongation_mm
}

fn elongations(rig: &Rig) -> [f64; 2] {
    let a = &rig.state().axes;
    [a[0].elongation_mm, a[1].elongation_mm]
}

impl StrainControl {
    /// Strain control on `rig`, idle (displacement control) until [`StrainControl::start`]:
    /// from now on call [`StrainControl::advance`] before every step, so that the history of
    /// elongations the measurements are aligned with is there when a program starts.
    pub fn new(
        rig: &Rig,
        config: OuterLoopConfig,
        limits: InterlockLimits,
        on_restore: OnRestore,
    ) -> Result<StrainControl, StrainStartError> {
        limits.validate().map_err(StrainStartError::Limits)?;
        OuterLoop::validate(&config).map_err(StrainStartError::Model)?;
        let specimen = rig.specimen().ok_or(StrainStartError::NoSpecimen)?;
        if specimen.config().loading != crate::specimen::Loading::Equibiaxial {
            return Err(StrainStartError::NotCruciform);
        }
        let gauge_mm = specimen.config().gauge_mm();
        let channels = &rig.config().limits.channels;
        let dt = rig.dt_s();
        let max_step_mm = [Axis::X, Axis::Y].map(|a| {
            let machine_mm_s = 2.0
                * channels[a.plus().index()]
                    .rate_max_mm_s
                    .min(channels[a.minus().index()].rate_max_mm_s);
            machine_mm_s.min(config.max_elongation_rate_mm_s) * dt
        });
        let elongation_range_mm = [Axis::X, Axis::Y].map(|a| {
            let (plus, minus) = (&channels[a.plus().index()], &channels[a.minus().index()]);
            (
                plus.stroke_min_mm + minus.stroke_min_mm + 2.0 * STROKE_MARGIN_MM,
                plus.stroke_max_mm + minus.stroke_max_mm - 2.0 * STROKE_MARGIN_MM,
            )
        });
        let mut outer = OuterLoop::new(config, gauge_mm);
        outer.record(rig.state().t_s, elongations(rig));
        Ok(StrainControl {
            outer,
            limits,
            on_restore,
            path: StrainPath::new(vec![crate::strain::StrainSegment::Hold { duration_s: 0.0 }])
                .expect("a zero hold is a valid path"),
            start: [0.0; 2],
            program_t_s: 0.0,
            duration_s: 0.0,
            mode: StrainMode::Done,
            last_capture_s: f64::NEG_INFINITY,
            good_in_row: 0,
            target: [0.0; 2],
            max_step_mm,
            elongation_range_mm,
            setpoint_mm: elongations(rig),
            settling: None,
            newest_log: [f64::NAN; 2],
        })
    }

    /// Switch to strain control (bumpless) running `path` from the measured strains of
    /// `latest`: X and Y go to centroid displacement control, the model is anchored on
    /// `latest` so that the first command is the present elongation.
    pub fn start(
        &mut self,
        rig: &mut Rig,
        path: StrainPath,
        latest: &GaugeMeasurement,
    ) -> Result<(), StrainStartError> {
        let now = rig.state().t_s;
        self.outer.record(now, elongations(rig));
        self.limits
            .check_sample(latest)
            .map_err(StrainStartError::Measurement)?;
        self.limits
            .check_age(now, latest.t_capture_s)
            .map_err(StrainStartError::Measurement)?;
        if !self.outer.reset_to(latest) {
            return Err(StrainStartError::Measurement(HoldReason::NotAligned {
                t_capture_s: latest.t_capture_s,
            }));
        }
        let centroid = AxisControl::Centroid(ControlMode::Displacement);
        for axis in [Axis::X, Axis::Y] {
            if rig.state().axes[axis.index()].control != centroid {
                rig.command(RigCommand::SetAxisControl {
                    axis,
                    control: centroid,
                })?;
            }
        }
        self.start = latest.log_strain;
        self.duration_s = path.duration_s(self.start);
        self.path = path;
        self.program_t_s = 0.0;
        self.mode = StrainMode::Strain;
        self.last_capture_s = latest.t_capture_s;
        self.good_in_row = 0;
        self.target = self.start;
        self.setpoint_mm = [Axis::X, Axis::Y].map(|a| rig_setpoint(rig, a));
        self.settling = None;
        self.newest_log = latest.log_strain;
        Ok(())
    }

    pub fn mode(&self) -> &StrainMode {
        &self.mode
    }

    /// The present target (ln λx, ln λy).
    pub fn target(&self) -> [f64; 2] {
        self.target
    }

    pub fn program_t_s(&self) -> f64 {
        self.program_t_s
    }

    pub fn outer(&self) -> &OuterLoop {
        &self.outer
    }

    /// Leave strain control now: the set-points stay where they are, in displacement control.
    pub fn stop(&mut self) {
        self.mode = StrainMode::Done;
    }

    fn hold(&mut self, rig: &mut Rig, reason: HoldReason) -> Option<StrainEvent> {
        self.hold_position(rig);
        self.good_in_row = 0;
        self.mode = StrainMode::Held(reason.clone());
        Some(StrainEvent::Held(reason))
    }

    /// The pairs' set-points at their present elongations.
    fn hold_position(&mut self, rig: &mut Rig) {
        self.setpoint_mm = elongations(rig);
        for (i, axis) in [Axis::X, Axis::Y].into_iter().enumerate() {
            // Holding the present position is always within the limits it is at.
            let _ = rig.command(RigCommand::SetSetpoint {
                channel: Channel::Elongation(axis),
                value: self.setpoint_mm[i],
            });
        }
    }

    /// One control period, before `rig.step()`: `newest` is the newest field sample known
    /// (the same one again is fine; only a later capture time counts as new).
    pub fn advance(
        &mut self,
        rig: &mut Rig,
        newest: Option<&GaugeMeasurement>,
    ) -> Option<StrainEvent> {
        let now = rig.state().t_s;
        self.outer.record(now, elongations(rig));
        if self.mode == StrainMode::Done {
            return None;
        }
        let fresh =
            newest.filter(|m| m.t_capture_s > self.last_capture_s || m.t_capture_s.is_nan());
        if let Some(m) = fresh {
            self.last_capture_s = if m.t_capture_s.is_finite() {
                m.t_capture_s
            } else {
                self.last_capture_s
            };
            let checked = self.limits.check_sample(m).and_then(|()| {
                match self.mode {
                    // Holding: the model is re-anchored on resume, no jump test.
                    StrainMode::Held(_) => Ok(()),
                    _ => match self.outer.innovation(m) {
                        Some(innovation) => self.limits.check_jump(innovation),
                        None => Err(HoldReason::NotAligned {
                            t_capture_s: m.t_capture_s,
                        }),
                    },
                }
            });
            match (checked, &self.mode) {
                (Err(reason), StrainMode::Strain) => return self.hold(rig, reason),
                (Err(_), _) => self.good_in_row = 0,
                (Ok(()), StrainMode::Strain) => {
                    self.outer.update(m);
                    self.newest_log = m.log_strain;
                    let target = self.target;
                    if let Some(end) = self
                        .settling
                        .as_mut()
                        .and_then(|s| s.field(m.log_strain, target))
                    {
                        return Some(self.finish(end));
                    }
                }
                (Ok(()), StrainMode::Held(_)) => {
                    self.good_in_row += 1;
                    if self.good_in_row >= RESUME_AFTER_FIELDS
                        && self.limits.check_age(now, m.t_capture_s).is_ok()
                    {
                        match self.on_restore {
                            OnRestore::Stop => {
                                return Some(self.finish(ProgramEnd::Stopped));
                            }
                            OnRestore::Resume => {
                                if self.outer.reset_to(m) {
                                    // Bumpless: the model now gives the held position, and
                                    // the program goes on from the point of its path nearest
                                    // the state now (the re-anchored model at the present
                                    // elongations: `m` may predate the freeze by a latency),
                                    // not from the target frozen at the hold, a latency of
                                    // travel ahead, that the grips would lurch to. On the
                                    // path, so a constant-ratio test keeps its ratio.
                                    let now_u = self.outer.nominal_log_strain(elongations(rig));
                                    let state = self.outer.predict(now_u);
                                    self.program_t_s =
                                        self.path.time_nearest(self.start, self.program_t_s, state);
                                    self.target = self.path.target(self.start, self.program_t_s);
                                    self.setpoint_mm = elongations(rig);
                                    self.settling = None;
                                    self.mode = StrainMode::Strain;
                                    return Some(StrainEvent::Resumed);
                                }
                            }
                        }
                    }
                }
                (Ok(()), StrainMode::Done) => {}
            }
        }
        if self.mode != StrainMode::Strain {
            return None;
        }
        if let Err(reason) = self.limits.check_age(now, self.last_capture_s) {
            return self.hold(rig, reason);
        }
        self.program_t_s = (self.program_t_s + rig.dt_s()).min(self.duration_s);
        self.target = self.path.target(self.start, self.program_t_s);
        let wanted = self.outer.elongation_for(self.target);
        for (i, axis) in [Axis::X, Axis::Y].into_iter().enumerate() {
            let step =
                (wanted[i] - self.setpoint_mm[i]).clamp(-self.max_step_mm[i], self.max_step_mm[i]);
            let value = self.setpoint_mm[i] + step;
            let (lowest, highest) = self.elongation_range_mm[i];
            let within = match value > highest {
                true => Err(highest),
                false => (value >= lowest).then_some(()).ok_or(lowest),
            };
            let command = within
                .map_err(|limit| Refusal::BeyondLimit {
                    channel: Channel::Elongation(axis),
                    what: "elongation (mm; the grips' strokes less the strain loop's margin)",
                    value,
                    limit,
                })
                .and_then(|()| {
                    rig.command(RigCommand::SetSetpoint {
                        channel: Channel::Elongation(axis),
                        value,
                    })
                });
            if let Err(refusal) = command {
                if matches!(refusal, Refusal::BeyondLimit { .. }) {
                    // The path leads out of the rig's reach: no resume can go on with it.
                    self.hold_position(rig);
                    return Some(self.finish(ProgramEnd::Short {
                        measured_log: self.newest_log,
                        target_log: self.path.target(self.start, self.duration_s),
                        because: ShortBecause::Refused(refusal),
                    }));
                }
                return self.hold(rig, HoldReason::Refused(refusal.to_string()));
            }
            self.setpoint_mm[i] = value;
        }
        if self.program_t_s >= self.duration_s {
            let dt_s = rig.dt_s();
            if self
                .settling
                .get_or_insert_with(Settling::default)
                .tick(dt_s)
            {
                return Some(self.finish(ProgramEnd::Short {
                    measured_log: self.newest_log,
                    target_log: self.target,
                    because: ShortBecause::SettleLimit,
                }));
            }
        }
        None
    }

    fn finish(&mut self, end: ProgramEnd) -> StrainEvent {
        self.mode = StrainMode::Done;
        self.settling = None;
        StrainEvent::Finished(end)
    }
}
