//! The user's named gauges (`[correlator] gauges`) against the test's time, for the run's
//! dashboard: each strain gauge's mean log strains and each extensometer's elongation (mm
//! when the fields' scale is known, px otherwise), read from every field with the
//! correlator's own gauge code (the numbers of `frames.csv`'s gauge columns). The gauges'
//! shapes are the run's configuration, not on the wire: the run computes their readings and
//! hands them to its dashboard; `dicstream monitor --config` keeps one of its own
//! (`monitor_gauges.rs`). Bounded: past [`MAX_POINTS`] a
//! gauge keeps every other point and then takes every second field (and so on).

use correlator::gauges::{GaugeReading, GaugeValue};
use correlator::{Gauge, GaugeShape};
use serde_json::{json, Value};
use wire::scale::MmPerPx;

/// Points kept per gauge.
pub const MAX_POINTS: usize = 1000;

#[derive(Debug)]
struct History {
    name: String,
    extensometer: bool,
    t_s: Vec<f64>,
    /// exx, eyy, exy of a strain gauge; the elongation of an extensometer (the rest unused).
    values: [Vec<f64>; 3],
}

#[derive(Debug)]
pub struct GaugeHistory {
    gauges: Vec<History>,
    /// Extensometers in mm (the fields' scale is known) or px.
    in_mm: bool,
    /// Fields seen, and one in `stride` is kept.
    seen: u64,
    stride: u64,
}

impl GaugeHistory {
    /// Histories of `gauges`, extensometers in mm when `in_mm` (else px).
    pub fn new(gauges: &[Gauge], in_mm: bool) -> GaugeHistory {
        GaugeHistory {
            gauges: gauges
                .iter()
                .map(|g| History {
                    name: g.name.clone(),
                    extensometer: matches!(g.shape, GaugeShape::Extensometer { .. }),
                    t_s: Vec::new(),
                    values: Default::default(),
                })
                .collect(),
            in_mm,
            seen: 0,
            stride: 1,
        }
    }

    /// The gauges' `readings` on one field (`gauge_columns::read_all`, in the order of the
    /// gauges given to `new`) at the test's time `t_s`, with the field's scale `scale`. A
    /// gauge without a reading on this field gets an empty point (null in the JSON), and an
    /// extensometer in mm a field without a scale too.
    pub fn push(&mut self, readings: &[GaugeReading], t_s: f64, scale: Option<MmPerPx>) {
        debug_assert_eq!(readings.len(), self.gauges.len());
        if readings.is_empty() {
            return;
        }
        self.seen += 1;
        if !(self.seen - 1).is_multiple_of(self.stride) {
            return;
        }
        for (reading, h) in readings.iter().zip(&mut self.gauges) {
            let values = match reading.value {
                Ok(GaugeValue::Strain(s)) => [s.log.exx, s.log.eyy, s.log.exy],
                Ok(value) => {
                    let px = value.elongation_px().unwrap_or(f64::NAN);
                    let length = match (self.in_mm, scale) {
                        (false, _) => px,
                        (true, Some(s)) => s.mm(px),
                        (true, None) => f64::NAN,
                    };
                    [length, f64::NAN, f64::NAN]
                }
                Err(_) => [f64::NAN; 3],
            };
            h.t_s.push(t_s);
            for (column, v) in h.values.iter_mut().zip(values) {
                column.push(v);
            }
        }
        if self.gauges[0].t_s.len() >= MAX_POINTS {
            for h in &mut self.gauges {
                keep_every_other(&mut h.t_s);
                for column in &mut h.values {
                    keep_every_other(column);
                }
            }
            self.stride *= 2;
        }
    }

    /// Each gauge by name: its kind, unit, quantity, times and series (null: no reading).
    pub fn to_json(&self) -> Value {
        let gauges: Vec<Value> = self
            .gauges
            .iter()
            .map(|h| match h.extensometer {
                true => json!({
                    "name": h.name,
                    "kind": "extensometer",
                    "quantity": "elongation",
                    "unit": if self.in_mm { "mm" } else { "px" },
                    "t_s": h.t_s,
                    "series": { "elongation": h.values[0] },
                }),
                false => json!({
                    "name": h.name,
                    "kind": "strain gauge",
                    "quantity": "mean log strain",
                    "unit": "-",
                    "t_s": h.t_s,
                    "series": { "exx": h.values[0], "eyy": h.values[1], "exy": h.values[2] },
                }),
            })
            .collect();
        Value::Array(gauges)
    }
}

fn keep_every_other(values: &mut Vec<f64>) {
    let mut k = 0;
    values.retain(|_| {
        k += 1;
        k % 2 == 1
    });
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::gauge_columns::read_all;
    use wire::FieldNode;

    /// A 5 x 5 mesh, 10 px apart, stretched by 1 % along x (also `monitor_gauges`' test's).
    pub(crate) fn nodes() -> Vec<FieldNode> {
        (0..25)
            .map(|k| {
                let (i, j) = ((k % 5) as f32, (k / 5) as f32);
                FieldNode {
                    x_px: 10.0 * i,
                    y_px: 10.0 * j,
                    u_px: 0.1 * i,
                    exx: 0.00995,
                    du_dx: 0.01,
                    status: wire::NodeStatus::Ok as u32,
                    ..FieldNode::default()
                }
            })
            .collect()
    }

    #[test]
    fn each_gauge_is_read_by_name_with_its_unit_and_the_history_is_bounded() {
        let gauges: Vec<Gauge> = vec![
            "mid=rect:0,0,40,40".parse().unwrap(),
            "arm=extensometer:0,20 40,20".parse().unwrap(),
        ];
        let mut history = GaugeHistory::new(&gauges, true);
        let scale = MmPerPx::new(0.5).ok();
        let mut readings = Vec::new();
        read_all(&gauges, &nodes(), 10.0, &mut readings);
        history.push(&readings, 1.5, scale);
        let json = history.to_json();
        assert_eq!(json[0]["name"], "mid");
        assert_eq!(json[0]["unit"], "-");
        assert_eq!(json[0]["t_s"][0], 1.5);
        assert!(json[0]["series"]["exx"][0].as_f64().unwrap() > 0.009);
        assert_eq!(json[1]["name"], "arm");
        assert_eq!(json[1]["unit"], "mm");
        // 40 px stretched by 1 %: 0.4 px, 0.2 mm.
        let elongation = json[1]["series"]["elongation"][0].as_f64().unwrap();
        assert!((elongation - 0.2).abs() < 1e-3, "{elongation}");
        for k in 0..3 * MAX_POINTS {
            history.push(&readings, 2.0 + k as f64, scale);
        }
        let json = history.to_json();
        let kept = json[0]["t_s"].as_array().unwrap();
        assert!(kept.len() < MAX_POINTS && kept.len() > MAX_POINTS / 4);
        assert_eq!(kept[0], 1.5);
        assert_eq!(json[1]["t_s"].as_array().unwrap().len(), kept.len());
    }
}
