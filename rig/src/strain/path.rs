//! Strain programs: gauge log strains (ln λx, ln λy) as functions of program time, from the
//! measured state at the start. Segments run in order: a ramp goes in a straight line in log
//! space to its target at a rate (of the component that changes most), so a ramp from the
//! unloaded state to (e, ρ e) holds the ratio ρ = ln λy / ln λx all along; a hold keeps the
//! last target for a duration.

/// One segment of a strain program.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StrainSegment {
    /// Straight line in (ln λx, ln λy) to `to_log`, the larger component change at
    /// `rate_log_per_s` (log strain per second).
    Ramp {
        to_log: [f64; 2],
        rate_log_per_s: f64,
    },
    Hold {
        duration_s: f64,
    },
}

/// Why a strain program was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StrainPathError {
    #[error("strain program has no segment")]
    Empty,
    #[error("strain ramp target ({x}, {y}) must be finite log strains within ±ln 8")]
    Target { x: f64, y: f64 },
    #[error("strain ramp rate {rate} /s: expected a positive finite log strain rate")]
    Rate { rate: f64 },
    #[error("strain hold duration {duration_s} s: expected a finite duration ≥ 0")]
    Duration { duration_s: f64 },
    #[error("ratio {ratio}: expected a finite ln λy / ln λx")]
    Ratio { ratio: f64 },
    #[error("stretch {stretch}: expected a stretch in (1, 8]")]
    Stretch { stretch: f64 },
}

/// A validated sequence of segments.
#[derive(Clone, Debug, PartialEq)]
pub struct StrainPath {
    segments: Vec<StrainSegment>,
}

impl StrainPath {
    pub fn new(segments: Vec<StrainSegment>) -> Result<StrainPath, StrainPathError> {
        if segments.is_empty() {
            return Err(StrainPathError::Empty);
        }
        let limit = 8f64.ln();
        for s in &segments {
            match *s {
                StrainSegment::Ramp {
                    to_log,
                    rate_log_per_s,
                } => {
                    if !to_log.iter().all(|v| v.is_finite() && v.abs() <= limit) {
                        return Err(StrainPathError::Target {
                            x: to_log[0],
                            y: to_log[1],
                        });
                    }
                    if !(rate_log_per_s.is_finite() && rate_log_per_s > 0.0) {
                        return Err(StrainPathError::Rate {
                            rate: rate_log_per_s,
                        });
                    }
                }
                StrainSegment::Hold { duration_s } => {
                    if !(duration_s.is_finite() && duration_s >= 0.0) {
                        return Err(StrainPathError::Duration { duration_s });
                    }
                }
            }
        }
        Ok(StrainPath { segments })
    }

    /// The end point of a constant-ratio path to the larger measured stretch `stretch`:
    /// (e, ρ e) with e = ln stretch when |ρ| ≤ 1, (e / ρ, e) otherwise.
    pub fn ratio_target(ratio: f64, stretch: f64) -> Result<[f64; 2], StrainPathError> {
        if !ratio.is_finite() || ratio.abs() > 1.0e3 {
            return Err(StrainPathError::Ratio { ratio });
        }
        if !(stretch.is_finite() && stretch > 1.0 && stretch <= 8.0) {
            return Err(StrainPathError::Stretch { stretch });
        }
        let e = stretch.ln();
        Ok(if ratio.abs() <= 1.0 {
            [e, ratio * e]
        } else {
            [e / ratio, e]
        })
    }

    /// Hold 1 s, ramp on the constant-ratio path ρ = ln λy / ln λx (1: equibiaxial, 0: pure
    /// shear, −1/2: uniaxial-like) to the larger stretch `stretch` at `rate_log_per_s`, hold 1 s.
    pub fn ratio_path(
        ratio: f64,
        stretch: f64,
        rate_log_per_s: f64,
    ) -> Result<StrainPath, StrainPathError> {
        let to_log = StrainPath::ratio_target(ratio, stretch)?;
        StrainPath::new(vec![
            StrainSegment::Hold { duration_s: 1.0 },
            StrainSegment::Ramp {
                to_log,
                rate_log_per_s,
            },
            StrainSegment::Hold { duration_s: 1.0 },
        ])
    }

    pub fn segments(&self) -> &[StrainSegment] {
        &self.segments
    }

    /// Total duration from `start` (s).
    pub fn duration_s(&self, start: [f64; 2]) -> f64 {
        let mut at = start;
        let mut total = 0.0;
        for s in &self.segments {
            total += segment_duration_s(s, at);
            if let StrainSegment::Ramp { to_log, .. } = *s {
                at = to_log;
            }
        }
        total
    }

    /// The program time, in the segment under way at `t_s` (from `start`), whose target is
    /// nearest to `state`: where the program stands for a specimen at `state`. A ramp is
    /// projected onto (clamped to its ends); a hold keeps `t_s`. A resume goes on from there,
    /// on the path (its ratio kept) and at the state reached, not at a target frozen ahead.
    pub fn time_nearest(&self, start: [f64; 2], t_s: f64, state: [f64; 2]) -> f64 {
        let mut at = start;
        let mut begin_s = 0.0;
        let t = t_s.max(0.0);
        for s in &self.segments {
            let d = segment_duration_s(s, at);
            if t < begin_s + d {
                return match *s {
                    StrainSegment::Ramp { to_log, .. } => {
                        let dir = [to_log[0] - at[0], to_log[1] - at[1]];
                        let norm = dir[0] * dir[0] + dir[1] * dir[1];
                        if norm <= 0.0 {
                            return t;
                        }
                        let f = ((state[0] - at[0]) * dir[0] + (state[1] - at[1]) * dir[1]) / norm;
                        begin_s + f.clamp(0.0, 1.0) * d
                    }
                    StrainSegment::Hold { .. } => t,
                };
            }
            if let StrainSegment::Ramp { to_log, .. } = *s {
                at = to_log;
            }
            begin_s += d;
        }
        t
    }

    /// Target (ln λx, ln λy) at program time `t_s` from `start`; after the end, the last one.
    pub fn target(&self, start: [f64; 2], t_s: f64) -> [f64; 2] {
        let mut at = start;
        let mut t = t_s.max(0.0);
        for s in &self.segments {
            let d = segment_duration_s(s, at);
            match *s {
                StrainSegment::Ramp { to_log, .. } => {
                    if t < d {
                        let f = t / d;
                        return [
                            at[0] + f * (to_log[0] - at[0]),
                            at[1] + f * (to_log[1] - at[1]),
                        ];
                    }
                    at = to_log;
                }
                StrainSegment::Hold { .. } => {
                    if t < d {
                        return at;
                    }
                }
            }
            t -= d;
        }
        at
    }
}

fn segment_duration_s(s: &StrainSegment, from: [f64; 2]) -> f64 {
    match *s {
        StrainSegment::Ramp {
            to_log,
            rate_log_per_s,
        } => (to_log[0] - from[0]).abs().max((to_log[1] - from[1]).abs()) / rate_log_per_s,
        StrainSegment::Hold { duration_s } => duration_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_state_is_placed_on_the_path_by_projection() {
        let path = StrainPath::ratio_path(1.0, 1.5, 0.02).unwrap();
        let start = [0.0, 0.0];
        // In the first hold: the time stays.
        assert_eq!(path.time_nearest(start, 0.25, [0.3, 0.3]), 0.25);
        // On the ramp, held at t = 6 s (target 0.1): a state behind (0.094, 0.096) projects
        // to 0.095, 0.25 s earlier; one off the line keeps the ratio of the path.
        let t = path.time_nearest(start, 6.0, [0.094, 0.096]);
        assert!((t - (1.0 + 0.095 / 0.02)).abs() < 1e-9, "{t}");
        let target = path.target(start, t);
        assert_eq!(target[0], target[1]);
        // Clamped to the ramp's ends.
        assert_eq!(path.time_nearest(start, 6.0, [-1.0, -1.0]), 1.0);
    }

    #[test]
    fn a_ratio_path_keeps_its_ratio_and_ends_at_the_stretch() {
        let p = StrainPath::ratio_path(0.5, 1.8, 0.02).unwrap();
        let e = 1.8f64.ln();
        assert!((p.duration_s([0.0; 2]) - (2.0 + e / 0.02)).abs() < 1e-9);
        for k in 1..100 {
            let t = 1.0 + k as f64 * 0.3;
            let [x, y] = p.target([0.0; 2], t);
            if x > 1e-6 {
                assert!((y / x - 0.5).abs() < 1e-12, "{x} {y}");
            }
        }
        assert_eq!(p.target([0.0; 2], 1e6), [e, 0.5 * e]);
        assert_eq!(p.target([0.0; 2], 0.5), [0.0, 0.0]);
        // |ρ| > 1: y is the larger stretch.
        assert_eq!(StrainPath::ratio_target(2.0, 1.8).unwrap(), [e / 2.0, e]);
    }

    #[test]
    fn bad_programs_are_refused_with_the_reason() {
        assert_eq!(StrainPath::new(vec![]), Err(StrainPathError::Empty));
        let e = StrainPath::ratio_path(1.0, 1.8, 0.0).unwrap_err();
        assert!(e.to_string().contains("rate"), "{e}");
        let e = StrainPath::ratio_path(f64::NAN, 1.8, 0.02).unwrap_err();
        assert!(e.to_string().contains("ratio"), "{e}");
        let e = StrainPath::ratio_path(1.0, 0.9, 0.02).unwrap_err();
        assert!(e.to_string().contains("stretch"), "{e}");
        let e = StrainPath::new(vec![StrainSegment::Hold { duration_s: -1.0 }]).unwrap_err();
        assert!(e.to_string().contains("duration"), "{e}");
    }

    #[test]
    fn a_sequence_starts_from_the_measured_state() {
        let p = StrainPath::new(vec![
            StrainSegment::Ramp {
                to_log: [0.2, 0.0],
                rate_log_per_s: 0.1,
            },
            StrainSegment::Hold { duration_s: 1.0 },
            StrainSegment::Ramp {
                to_log: [0.2, 0.2],
                rate_log_per_s: 0.1,
            },
        ])
        .unwrap();
        let start = [0.1, 0.0];
        assert!((p.duration_s(start) - 4.0).abs() < 1e-12);
        let t = p.target(start, 0.5);
        assert!((t[0] - 0.15).abs() < 1e-12 && t[1] == 0.0);
        assert_eq!(p.target(start, 1.5), [0.2, 0.0]);
        let t = p.target(start, 3.0);
        assert!((t[1] - 0.1).abs() < 1e-12);
    }
}
