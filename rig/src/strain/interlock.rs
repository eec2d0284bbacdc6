//! Interlocks of strain control: what makes the strain channel unusable. Any of them puts the
//! rig on a displacement hold at its present position and is reported with its reason.

use crate::bad_setting::BadSetting;
use crate::strain::outer::GaugeMeasurement;

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InterlockLimits {
    /// Largest age of the newest field (rig time now − its capture time), s.
    pub stale_s: f64,
    /// Fewest converged correlation nodes of a usable field.
    pub min_valid_nodes: u32,
    /// Largest |measured − predicted| gauge log strain of a field (a jump).
    pub jump_log: f64,
}

impl Default for InterlockLimits {
    fn default() -> Self {
        InterlockLimits {
            stale_s: DEFAULT_STALE_S,
            min_valid_nodes: DEFAULT_MIN_VALID_NODES,
            jump_log: 0.03,
        }
    }
}

/// Defaults of the interlocks as a user configures them. The stale limit is the field latency
/// a loaded bench really has, not a wish: p99 plus three frame periods at 10 frames/s, so that
/// a hold means the fields stopped, not that one was late (a limit inside the jitter held and
/// resumed the test dozens of times per ramp, each resume costing accuracy: issue 16). On the
/// 2-core bench loaded by another build (`bench pipeline`, 1024², 10 frames/s, 60 s, issue 26)
/// a field's latency is 52-55 ms median, 225-230 ms at p99 and at most 464 ms in 1,200 fields:
/// 0.23 + 0.3 = 0.53 s, rounded up to 0.6 s, above every field seen. (It was 1.5 s, from a p99
/// of 1.2 s before the correlator kept up.) While held the grips stand still; a shorter limit
/// lets the ramp run on the model's feed-forward for 0.6 s instead of 1.5 s (at 0.02–0.03 /s,
/// ≤ 0.018 log strain).
pub const DEFAULT_STALE_S: f64 = 0.6;
pub const DEFAULT_MIN_VALID_NODES: u32 = 16;

/// Why strain control holds.
#[derive(Clone, Debug, PartialEq)]
pub enum HoldReason {
    /// The newest field is older than the limit (fields stopped: correlator gone, camera gone).
    Stale {
        age_s: f64,
        limit_s: f64,
    },
    TooFewNodes {
        valid: u32,
        min: u32,
    },
    NotFinite,
    /// The field disagrees with the model by more than the jump limit.
    Jump {
        innovation: [f64; 2],
        limit: f64,
    },
    /// The field's capture time is outside the rig's history (clock mismatch, or very late).
    NotAligned {
        t_capture_s: f64,
    },
    /// The rig refused the set-point (stroke, force limit...).
    Refused(String),
}

impl std::fmt::Display for HoldReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            HoldReason::Stale { age_s, limit_s } => {
                write!(
                    f,
                    "stale fields: newest is {age_s:.3} s old (limit {limit_s} s)"
                )
            }
            HoldReason::TooFewNodes { valid, min } => {
                write!(f, "field with {valid} valid nodes (at least {min} needed)")
            }
            HoldReason::NotFinite => write!(f, "field strain is not finite"),
            HoldReason::Jump { innovation, limit } => write!(
                f,
                "strain jump: field off the model by ({:.4}, {:.4}) (limit {limit})",
                innovation[0], innovation[1]
            ),
            HoldReason::NotAligned { t_capture_s } => write!(
                f,
                "field captured at {t_capture_s:.3} s is outside the rig's history"
            ),
            HoldReason::Refused(reason) => write!(f, "set-point refused: {reason}"),
        }
    }
}

impl InterlockLimits {
    pub fn validate(&self) -> Result<(), BadSetting> {
        if !(self.stale_s.is_finite() && self.stale_s > 0.0) {
            return Err(BadSetting::new(
                "stale_s",
                self.stale_s,
                "a positive number",
            ));
        }
        if !(self.jump_log.is_finite() && self.jump_log > 0.0) {
            return Err(BadSetting::new(
                "jump_log",
                self.jump_log,
                "a positive number",
            ));
        }
        Ok(())
    }

    /// The sample's own checks: finite strains and capture time, enough nodes.
    pub fn check_sample(&self, m: &GaugeMeasurement) -> Result<(), HoldReason> {
        if !(m.log_strain.iter().all(|v| v.is_finite()) && m.t_capture_s.is_finite()) {
            return Err(HoldReason::NotFinite);
        }
        if m.valid_nodes < self.min_valid_nodes {
            return Err(HoldReason::TooFewNodes {
                valid: m.valid_nodes,
                min: self.min_valid_nodes,
            });
        }
        Ok(())
    }

    pub fn check_jump(&self, innovation: [f64; 2]) -> Result<(), HoldReason> {
        if innovation.iter().any(|v| v.abs() > self.jump_log) {
            return Err(HoldReason::Jump {
                innovation,
                limit: self.jump_log,
            });
        }
        Ok(())
    }

    pub fn check_age(&self, now_s: f64, t_capture_s: f64) -> Result<(), HoldReason> {
        let age_s = now_s - t_capture_s;
        if age_s > self.stale_s {
            return Err(HoldReason::Stale {
                age_s,
                limit_s: self.stale_s,
            });
        }
        Ok(())
    }
}
