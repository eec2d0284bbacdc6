//! The test's time (the rig's `t_sim_s`, s) of a field (pure): the rig sample its frame names,
//! looked up among the recent samples seen, else extrapolated from the newest sample by the
//! monotonic clock. Without any rig sample (a camera alone) there is no test time.

use std::collections::VecDeque;

/// Recent rig samples kept for the lookup (at 250 samples/s, 16 s: more than any field's
/// latency).
const RECENT_SAMPLES: usize = 4096;

#[derive(Clone, Debug, Default)]
pub struct TestClock {
    /// (sample id, t_sim_s), in arrival order.
    recent: VecDeque<(u64, f64)>,
    /// The newest sample: (t_published_ns, t_sim_s).
    newest: Option<(u64, f64)>,
}

impl TestClock {
    pub fn on_rig(&mut self, sample_id: u64, t_sim_s: f64, t_published_ns: u64) {
        if self.recent.len() >= RECENT_SAMPLES {
            self.recent.pop_front();
        }
        self.recent.push_back((sample_id, t_sim_s));
        self.newest = Some((t_published_ns, t_sim_s));
    }

    /// The test time (s) of a frame taken at `t_capture_ns` under rig sample `rig_sample_id`.
    pub fn test_time_s(&self, rig_sample_id: u64, t_capture_ns: u64) -> Option<f64> {
        if let Some(&(_, t)) = self
            .recent
            .iter()
            .rev()
            .find(|(id, _)| *id == rig_sample_id)
        {
            return Some(t);
        }
        let (published_ns, t_sim_s) = self.newest?;
        let dt_s = (t_capture_ns as f64 - published_ns as f64) / 1e9;
        Some((t_sim_s + dt_s).max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_takes_its_rig_samples_time_else_the_newest_extrapolated() {
        let mut clock = TestClock::default();
        assert_eq!(clock.test_time_s(3, 5), None);
        for id in 0..10u64 {
            clock.on_rig(
                id,
                100.0 + id as f64 * 0.01,
                1_000_000_000 + id * 10_000_000,
            );
        }
        assert!((clock.test_time_s(4, 0).unwrap() - 100.04).abs() < 1e-12);
        // Unknown sample (a frame from no rig): the newest sample, 0.5 s later.
        let t = clock
            .test_time_s(wire::NO_RIG_SAMPLE, 1_590_000_000)
            .unwrap();
        assert!((t - 100.59).abs() < 1e-9, "{t}");
    }
}
