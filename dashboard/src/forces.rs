//! Each loaded actuator's force (N, as in every file of a run) against the test's time (s) and against its grip's
//! displacement (mm), bounded (pure). Which actuators are loaded is `wire::rig`'s one rule
//! (their peak |force| over every sample seen, not only the kept ones).

use crate::series::Decimated;
use serde_json::{json, Value};
use wire::rig::{loaded_actuators, ACTUATOR_NAMES};
use wire::RigState;

/// Columns: t_sim_s, then force (N) and position (mm) of each of the 6 actuators.
const WIDTH: usize = 13;

#[derive(Clone, Debug)]
pub struct ForceHistory {
    rows: Decimated<WIDTH>,
    peaks_abs_kn: [f64; 6],
}

impl ForceHistory {
    pub fn new(points: usize) -> ForceHistory {
        ForceHistory {
            rows: Decimated::new(points),
            peaks_abs_kn: [0.0; 6],
        }
    }

    pub fn push(&mut self, state: &RigState) {
        let mut row = [state.t_sim_s; WIDTH];
        for (k, a) in state.actuators.iter().enumerate() {
            row[1 + 2 * k] = 1e3 * a.force_kn;
            row[2 + 2 * k] = a.position_mm;
            if a.force_kn.is_finite() {
                self.peaks_abs_kn[k] = self.peaks_abs_kn[k].max(a.force_kn.abs());
            }
        }
        self.rows.push(row);
    }

    /// `{"t_sim_s": [..], "actuators": [{"name", "force_n": [..], "grip_mm": [..]}]}`, the
    /// loaded actuators only.
    pub fn json(&self) -> Value {
        let actuators: Vec<Value> = loaded_actuators(&self.peaks_abs_kn)
            .iter()
            .enumerate()
            .filter(|(_, loaded)| **loaded)
            .map(|(k, _)| {
                json!({
                    "name": ACTUATOR_NAMES[k],
                    "force_n": self.rows.column(1 + 2 * k),
                    "grip_mm": self.rows.column(2 + 2 * k),
                })
            })
            .collect();
        json!({"t_sim_s": self.rows.column(0), "actuators": actuators})
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_loaded_actuators_are_sent_and_the_history_is_bounded() {
        let mut h = ForceHistory::new(50);
        for i in 0..1000 {
            let mut s = RigState {
                t_sim_s: i as f64 * 0.01,
                ..RigState::default()
            };
            s.actuators[0].force_kn = 0.002 * i as f64;
            s.actuators[1].force_kn = -0.002 * i as f64;
            s.actuators[0].position_mm = 0.01 * i as f64;
            s.actuators[2].force_kn = 0.01; // load-cell noise on y
            s.actuators[4].force_kn = 0.5; // one spike on Z, above 10 %
            if i != 10 {
                s.actuators[4].force_kn = 0.0;
            }
            h.push(&s);
        }
        let j = h.json();
        let names: Vec<&str> = j["actuators"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a["name"].as_str().unwrap())
            .collect();
        assert_eq!(names, ["X+", "X-", "Z+"]);
        let t = j["t_sim_s"].as_array().unwrap();
        assert!(t.len() <= 50 && t.len() >= 25, "{}", t.len());
        let a = &j["actuators"][0];
        assert_eq!(a["force_n"].as_array().unwrap().len(), t.len());
        let last = t.len() - 1;
        let (t_s, f_n, x_mm) = (
            t[last].as_f64().unwrap(),
            a["force_n"][last].as_f64().unwrap(),
            a["grip_mm"][last].as_f64().unwrap(),
        );
        assert!((f_n - 200.0 * t_s).abs() < 0.1 && (x_mm - t_s).abs() < 1e-4);
    }
}
