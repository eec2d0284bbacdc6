//! Puts a field on the rig's clock. A field names the rig sample its frame was rendered from
//! (`rig_sample_id`, copied from the frame), so its capture time in rig (simulated) time is that
//! sample's; a frame without a rig sample (a real camera's) is placed by its monotonic capture
//! time among the samples' publication times. The rig records each published sample here;
//! the last [`FieldClock::capacity`] are kept. Pure: the process shell feeds it.

use crate::strain::outer::GaugeMeasurement;
use std::collections::VecDeque;

#[derive(Clone, Copy, Debug, PartialEq)]
struct Published {
    sample_id: u64,
    t_published_ns: u64,
    t_sim_s: f64,
}

#[derive(Clone, Debug)]
pub struct FieldClock {
    samples: VecDeque<Published>,
    capacity: usize,
}

impl FieldClock {
    /// Keeps the last `capacity` published samples (≥ 1).
    pub fn new(capacity: usize) -> FieldClock {
        let capacity = capacity.max(1);
        FieldClock {
            samples: VecDeque::with_capacity(capacity),
            capacity,
        }
    }

    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// A sample was published (ids increasing).
    pub fn record(&mut self, sample_id: u64, t_published_ns: u64, t_sim_s: f64) {
        if self.samples.len() == self.capacity {
            self.samples.pop_front();
        }
        self.samples.push_back(Published {
            sample_id,
            t_published_ns,
            t_sim_s,
        });
    }

    /// The rig time of the sample `sample_id`, if it is still known.
    pub fn of_sample(&self, sample_id: u64) -> Option<f64> {
        let k = self
            .samples
            .binary_search_by_key(&sample_id, |p| p.sample_id)
            .ok()?;
        Some(self.samples[k].t_sim_s)
    }

    /// The rig time of the newest sample published at or before `t_capture_ns` (a frame that
    /// names no rig sample), if it is still known.
    pub fn of_capture_ns(&self, t_capture_ns: u64) -> Option<f64> {
        let after = self
            .samples
            .partition_point(|p| p.t_published_ns <= t_capture_ns);
        let k = after.checked_sub(1)?;
        // Newer than the newest sample by more than a second: not this run's clock.
        let newest = self.samples.back()?;
        if t_capture_ns > newest.t_published_ns.saturating_add(1_000_000_000) {
            return None;
        }
        Some(self.samples[k].t_sim_s)
    }
}

impl FieldClock {
    /// The strain loop's measurement of a field: its gauge log strains (ln λx, ln λy) and valid
    /// nodes, captured at its rig time. None for a field of another layout version, one the
    /// clock cannot place (older than the kept samples, another run's) or one whose control
    /// gauge has no reading (NaN: too few valid nodes in it); the loop holds on those as on a
    /// stale field.
    pub fn measurement(&self, header: &wire::FieldHeader) -> Option<GaugeMeasurement> {
        wire::layouts::check_version("field", header.layout_version).ok()?;
        let t_capture_s = match header.rig_sample_id {
            wire::NO_RIG_SAMPLE => self.of_capture_ns(header.t_capture_ns)?,
            id => self.of_sample(id)?,
        };
        let gauge = header.gauge_of(wire::StrainMeasure::Log);
        if !(gauge.exx.is_finite() && gauge.eyy.is_finite()) {
            return None;
        }
        Some(GaugeMeasurement {
            t_capture_s,
            log_strain: [gauge.exx, gauge.eyy],
            valid_nodes: header.valid_nodes,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_becomes_a_measurement_at_its_rig_sample_time() {
        let mut clock = FieldClock::new(10);
        clock.record(4, 1_000, 0.5);
        clock.record(5, 2_000, 0.6);
        let mut header = wire::FieldHeader {
            rig_sample_id: 4,
            t_capture_ns: 1_900,
            valid_nodes: 321,
            ..wire::FieldHeader::default()
        };
        header.gauge[wire::StrainMeasure::Log as usize].exx = 0.1;
        header.gauge[wire::StrainMeasure::Log as usize].eyy = 0.05;
        header.gauge[wire::StrainMeasure::Green as usize].exx = 9.0;
        let m = clock.measurement(&header).unwrap();
        assert_eq!(m.t_capture_s, 0.5);
        assert_eq!(m.log_strain, [0.1, 0.05]);
        assert_eq!(m.valid_nodes, 321);
        // A real camera's frame: placed by its capture time.
        header.rig_sample_id = wire::NO_RIG_SAMPLE;
        assert_eq!(clock.measurement(&header).unwrap().t_capture_s, 0.5);
        header.rig_sample_id = 77;
        assert_eq!(clock.measurement(&header), None);
        header.rig_sample_id = 5;
        header.layout_version += 1;
        assert_eq!(clock.measurement(&header), None);
        // A control gauge without a reading is no measurement: the loop holds.
        header.layout_version -= 1;
        assert!(clock.measurement(&header).is_some());
        header.gauge[wire::StrainMeasure::Log as usize].eyy = f64::NAN;
        assert_eq!(clock.measurement(&header), None);
    }

    #[test]
    fn fields_are_placed_by_their_rig_sample_or_their_capture_time() {
        let mut clock = FieldClock::new(3);
        for k in 0..5u64 {
            clock.record(10 + k, 1_000 + 100 * k, 0.002 * k as f64);
        }
        // Only the last three are kept.
        assert_eq!(clock.of_sample(11), None);
        assert_eq!(clock.of_sample(12), Some(0.004));
        assert_eq!(clock.of_sample(14), Some(0.008));
        assert_eq!(clock.of_sample(99), None);
        assert_eq!(clock.of_capture_ns(1_250), Some(0.004));
        assert_eq!(clock.of_capture_ns(1_399), Some(0.006));
        assert_eq!(clock.of_capture_ns(1_400), Some(0.008));
        // Before the kept samples, or far after them: unknown.
        assert_eq!(clock.of_capture_ns(1_100), None);
        assert_eq!(clock.of_capture_ns(5_000_000_000), None);
        assert_eq!(FieldClock::new(0).of_sample(0), None);
    }
}
