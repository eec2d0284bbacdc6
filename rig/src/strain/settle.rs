//! The end of a strain program: the program's clock reaching its end is not the gauge reaching
//! the last target. The measured strain trails the target by the rig's lag and, when the path
//! asks more than the grips can give (a long-armed cruciform needs grip elongations several
//! times the gauge's, and the loop's elongation rate is capped), by more. So the loop keeps
//! the last target and waits for a field that shows it, for at most [`SETTLE_LIMIT_S`]; then
//! the program ends, [`ProgramEnd::Reached`] or [`ProgramEnd::Short`] with the figures.
//! Pure arithmetic: no IPC, no clock of its own.

/// A measured log strain within this fraction of the last target's larger magnitude (and at
/// least [`SETTLED_FLOOR_LOG`]) has reached it: 0.5 %, half the 1 % a strain program's end is
/// judged by in the tests, and some 20 times the centre gauge's field-to-field noise
/// (about 1e-4 on the live bench).
pub const SETTLED_FRACTION: f64 = 0.005;

/// The smallest tolerance (log strain): a target near zero (pure shear's held axis) is reached
/// within 1e-3, ten times the gauge's noise.
pub const SETTLED_FLOOR_LOG: f64 = 1.0e-3;

/// How long past the program's end the loop keeps its last target waiting for a field that
/// shows it (s of rig time): at the slowest programs (0.01 log strain per s) a 0.05 lag, the
/// largest seen on the default cruciform, and some seconds of latency.
pub const SETTLE_LIMIT_S: f64 = 10.0;

/// Why a program ended short of its last target.
#[derive(Clone, Debug, PartialEq)]
pub enum ShortBecause {
    /// [`SETTLE_LIMIT_S`] passed past the program's end with the newest field short of it.
    SettleLimit,
    /// The next set-point is beyond a limit: the grips' strokes less the loop's margin
    /// ([`crate::strain::control::STROKE_MARGIN_MM`]; the target is not within the grips'
    /// reach on this specimen), or one the rig refused.
    Refused(crate::refusal::Refusal),
}

/// How a strain program ended.
#[derive(Clone, Debug, PartialEq)]
pub enum ProgramEnd {
    /// A field showed the last target within the tolerance, `after_s` past the program's end.
    Reached {
        measured_log: [f64; 2],
        after_s: f64,
    },
    /// Short of the last target: the newest field's strains (NaN before any), the target.
    Short {
        measured_log: [f64; 2],
        target_log: [f64; 2],
        because: ShortBecause,
    },
    /// An interlock ended the test (`on_interlock = "stop"`), held where it was.
    Stopped,
}

impl ProgramEnd {
    /// One line for the rig's log.
    pub fn describe(&self) -> String {
        match self {
            ProgramEnd::Reached {
                measured_log,
                after_s,
            } => format!(
                "the last target reached {after_s:.1} s after the program's end (measured ln λ \
                 ({:.4}, {:.4}))",
                measured_log[0], measured_log[1]
            ),
            ProgramEnd::Short {
                measured_log,
                target_log,
                because,
            } => {
                let why = match because {
                    ShortBecause::SettleLimit => format!(
                        "within {SETTLE_LIMIT_S:.0} s of the program's end (the grips' rate \
                         limit or a stiffening specimen held the gauge back)"
                    ),
                    ShortBecause::Refused(refusal) => {
                        format!("its next set-point refused: {refusal}")
                    }
                };
                format!(
                    "the last target ln λ ({:.4}, {:.4}) NOT reached, {why}: measured ({:.4}, \
                     {:.4})",
                    target_log[0], target_log[1], measured_log[0], measured_log[1]
                )
            }
            ProgramEnd::Stopped => "stopped after the hold (on_interlock = stop)".to_string(),
        }
    }
}

/// How close (log strain) a measurement must come to a target whose larger component has
/// magnitude `target_log`.
pub fn tolerance_log(target_log: f64) -> f64 {
    (SETTLED_FRACTION * target_log.abs()).max(SETTLED_FLOOR_LOG)
}

/// Whether `measured` shows `target` within the tolerance.
pub fn reached(measured: [f64; 2], target: [f64; 2]) -> bool {
    let tolerance = tolerance_log(target[0].abs().max(target[1].abs()));
    (0..2).all(|i| (measured[i] - target[i]).abs() <= tolerance)
}

/// The loop past its program's end: the time it has waited for a field at the last target.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Settling {
    past_end_s: f64,
}

impl Settling {
    /// A new field's measured log strains: the end if they show `target`.
    pub fn field(&self, measured_log: [f64; 2], target: [f64; 2]) -> Option<ProgramEnd> {
        reached(measured_log, target).then_some(ProgramEnd::Reached {
            measured_log,
            after_s: self.past_end_s,
        })
    }

    /// One control period of `dt_s`: whether the limit has passed.
    pub fn tick(&mut self, dt_s: f64) -> bool {
        self.past_end_s += dt_s;
        self.past_end_s >= SETTLE_LIMIT_S
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reached_within_half_a_percent_or_the_floor() {
        let target = [0.26, 0.26];
        assert!(reached([0.2588, 0.2612], target));
        assert!(!reached([0.2586, 0.26], target));
        // Pure shear's held axis: the floor.
        assert!(reached([0.2600, 0.0009], [0.26, 0.0]));
        assert!(!reached([0.2600, 0.0015], [0.26, 0.0]));
        assert!(!reached([f64::NAN, 0.26], target));
    }

    #[test]
    fn a_field_at_the_target_ends_it_else_the_limit_passes() {
        let target = [0.2, 0.1];
        let mut s = Settling::default();
        assert!(!s.tick(1.0));
        assert_eq!(s.field([0.18, 0.1], target), None);
        assert_eq!(
            s.field([0.1995, 0.1003], target),
            Some(ProgramEnd::Reached {
                measured_log: [0.1995, 0.1003],
                after_s: 1.0
            })
        );
        let steps = (0..).take_while(|_| !s.tick(0.01)).count();
        // 9 s more in 0.01 s ticks, to rounding.
        let expected = ((SETTLE_LIMIT_S - 1.0) / 0.01).round() as usize;
        assert!((expected - 1..=expected).contains(&steps), "{steps}");
        let short = ProgramEnd::Short {
            measured_log: [0.18, 0.1],
            target_log: target,
            because: ShortBecause::SettleLimit,
        };
        assert!(
            short.describe().contains("NOT reached"),
            "{}",
            short.describe()
        );
    }
}
