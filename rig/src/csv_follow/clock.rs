//! Machine time onto this host's monotonic clock, and a row into the `rig/state` sample the
//! simulated rig would publish. The machine's clock is anchored once: when the first rows are
//! read, the last of them was written at the file's modification time (the file's age tells
//! how long ago that was on the monotonic clock). Every row is then placed at
//! `anchor + (t_row − t_anchor_row) + offset_s`: the offset corrects a lag between the
//! machine's clock and the camera's.

use super::Row;
use wire::rig::RigState;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MachineClock {
    pub offset_s: f64,
    /// (machine time s, monotonic ns) of the anchoring row.
    anchor: Option<(f64, i128)>,
}

impl MachineClock {
    pub fn new(offset_s: f64) -> MachineClock {
        MachineClock {
            offset_s,
            anchor: None,
        }
    }

    pub fn is_anchored(&self) -> bool {
        self.anchor.is_some()
    }

    /// Anchors on the row written last, `written_ago_ns` before `now_monotonic_ns`. Once only.
    pub fn anchor(&mut self, last_row_t_s: f64, now_monotonic_ns: u64, written_ago_ns: u64) {
        if self.anchor.is_none() {
            self.anchor = Some((
                last_row_t_s,
                i128::from(now_monotonic_ns) - i128::from(written_ago_ns),
            ));
        }
    }

    /// The row's instant on the monotonic clock, shifted by the offset (0 if before its
    /// start); None before anchoring.
    pub fn host_ns(&self, t_s: f64) -> Option<u64> {
        let (t0, ns0) = self.anchor?;
        let ns = ns0 + ((t_s - t0 + self.offset_s) * 1e9).round() as i128;
        Some(ns.clamp(0, i128::from(u64::MAX)) as u64)
    }
}

/// The `rig/state` sample of one row: machine time + offset as `t_sim_s`, the row's instant on
/// the monotonic clock as `t_published_ns` (what fields are paired to by time), each axis's
/// force shared by its two opposed actuators (so that their mean is the axis force, as the
/// simulated rig's load cells give it), the displacement as the axis elongation, and the
/// specimen's initial sections (the identifier corrects them by the measured stretch).
pub fn rig_state(
    row: &Row,
    sample_id: u64,
    host_ns: u64,
    offset_s: f64,
    sections_mm2: [f64; 2],
) -> RigState {
    let mut state = RigState {
        layout_version: wire::LAYOUT_VERSION,
        program_state: crate::codes::program_state(crate::ProgramStatus::Running),
        sample_id,
        t_sim_s: row.t_s + offset_s,
        t_published_ns: host_ns,
        specimen_stretch_x: 1.0,
        specimen_stretch_y: 1.0,
        specimen_section_x_mm2: sections_mm2[0],
        specimen_section_y_mm2: sections_mm2[1],
        hydraulics_on: 1,
        // A followed machine log is displacement data: no strain target.
        control_mode: wire::RigControl::Displacement as u32,
        target_log_exx: f64::NAN,
        target_log_eyy: f64::NAN,
        ..RigState::default()
    };
    for axis in 0..3 {
        if let Some(force_n) = row.force_n[axis] {
            state.actuators[2 * axis].force_kn = force_n * 1e-3;
            state.actuators[2 * axis + 1].force_kn = force_n * 1e-3;
        }
        if let Some(d) = row.displacement_mm[axis] {
            state.axis_elongation_mm[axis] = d;
            state.actuators[2 * axis].position_mm = 0.5 * d;
            state.actuators[2 * axis + 1].position_mm = 0.5 * d;
        }
    }
    state
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_placed_from_the_anchor_with_the_offset() {
        let mut clock = MachineClock::new(0.25);
        assert_eq!(clock.host_ns(1.0), None);
        // The row at 10 s was written 2 s before monotonic 100 s.
        clock.anchor(10.0, 100_000_000_000, 2_000_000_000);
        clock.anchor(99.0, 0, 0);
        assert_eq!(clock.host_ns(10.0), Some(98_250_000_000));
        assert_eq!(clock.host_ns(11.5), Some(99_750_000_000));
        assert_eq!(clock.host_ns(-1e6), Some(0));
    }

    #[test]
    fn forces_are_the_mean_of_two_opposed_actuators() {
        let row = Row {
            t_s: 2.0,
            force_n: [Some(1500.0), None, Some(-20.0)],
            displacement_mm: [Some(3.0), None, None],
        };
        let s = rig_state(&row, 7, 42, 0.5, [40.0, 0.0]);
        let a = &s.actuators;
        assert_eq!(500.0 * (a[0].force_kn + a[1].force_kn), 1500.0);
        assert_eq!(500.0 * (a[4].force_kn + a[5].force_kn), -20.0);
        assert_eq!(a[2].force_kn, 0.0);
        assert_eq!((s.sample_id, s.t_sim_s, s.t_published_ns), (7, 2.5, 42));
        assert_eq!(s.axis_elongation_mm[0], 3.0);
        assert_eq!(s.specimen_section_x_mm2, 40.0);
        assert_eq!(s.control(), wire::RigControl::Displacement);
        assert_eq!(s.strain_target(), None);
        assert!(s.target_log_exx.is_nan() && s.target_log_eyy.is_nan());
    }
}
