//! The grips' forces of the last rig samples, for the field route: a frame's forces are those
//! of the sample it names, or (a frame of a real camera, which names none) of the sample
//! nearest its capture time within [`MAX_TIME_GAP_NS`]. No match is `None`, counted by the
//! route, never the nearest sample passed off as the frame's.

use std::collections::VecDeque;

/// Largest gap between a frame's capture and the sample paired with it by time, ns (two
/// periods of a 100 Hz `rig/state`).
pub const MAX_TIME_GAP_NS: u64 = 20_000_000;

/// Samples kept.
pub const HISTORY: usize = 4096;

/// One sample's grip forces in [`crate::field_layout::GRIPS`] order, N, tension positive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GripForces {
    pub sample_id: u64,
    pub t_ns: u64,
    pub forces_n: [f64; 4],
}

/// The grips' forces on the specimen at a rig sample of test kind `load_case`: a uniaxial test
/// pulls the strip, held by the x grips alone, so the y actuators hold no specimen and what
/// they read is their own noise, not a force on it: 0 N (the route then leaves the frame out:
/// grips at rest, another specimen than the cruciform). The live route and `identify
/// --fields` both take their forces through it.
pub fn on_specimen(load_case: u32, forces_n: [f64; 4]) -> [f64; 4] {
    let strip = load_case == wire::rig::LOAD_CASE_UNIAXIAL;
    let holds = |i: usize| !strip || crate::field_layout::GRIPS[i].starts_with('x');
    std::array::from_fn(|i| if holds(i) { forces_n[i] } else { 0.0 })
}

/// The last [`HISTORY`] samples, in arrival order.
#[derive(Debug, Default)]
pub struct ForceHistory {
    samples: VecDeque<GripForces>,
}

impl ForceHistory {
    pub fn push(&mut self, sample: GripForces) {
        if self.samples.len() == HISTORY {
            self.samples.pop_front();
        }
        self.samples.push_back(sample);
    }

    /// The forces of sample `sample_id`, or by time when `sample_id` is `None`.
    pub fn find(&self, sample_id: Option<u64>, t_ns: u64) -> Option<[f64; 4]> {
        match sample_id {
            Some(id) => self
                .samples
                .iter()
                .rev()
                .find(|s| s.sample_id == id)
                .map(|s| s.forces_n),
            None => self
                .samples
                .iter()
                .min_by_key(|s| s.t_ns.abs_diff(t_ns))
                .filter(|s| s.t_ns.abs_diff(t_ns) <= MAX_TIME_GAP_NS)
                .map(|s| s.forces_n),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn by_id_or_by_time_and_nothing_made_up() {
        let mut history = ForceHistory::default();
        for k in 0..10u64 {
            history.push(GripForces {
                sample_id: 100 + k,
                t_ns: k * 10_000_000,
                forces_n: [k as f64; 4],
            });
        }
        assert_eq!(history.find(Some(103), 0), Some([3.0; 4]));
        assert_eq!(history.find(Some(99), 0), None, "a sample not received");
        assert_eq!(history.find(None, 41_000_000), Some([4.0; 4]));
        assert_eq!(history.find(None, 200_000_000), None, "too far in time");
    }
}
