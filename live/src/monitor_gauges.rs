//! The user's named gauges on `dicstream monitor --config FILE`'s dashboard: the gauges of
//! the run's own configuration (`[correlator] gauges`, read and checked as `run` reads them),
//! read on every field the monitor receives with the code the run's recorder uses
//! (`gauge_columns::read_all`, the correlator's gauge code) into the history the run's
//! dashboard shows (`gauge_history`), so that both pages and `frames.csv` say the same
//! numbers. Extensometers are in mm when the scale of every field is known without the
//! specimen's solves, which a monitor does not receive (`FieldScale::without_solves`), in
//! px otherwise.

use crate::config::RunConfig;
use crate::field_scale::FieldScale;
use crate::gauge_history::GaugeHistory;
use correlator::{Gauge, GaugeReading};
use dashboard::{FieldTime, UserGauges};
use serde_json::Value;
use wire::scale::MmPerPx;
use wire::{FieldHeader, FieldNode};

pub struct MonitorGauges {
    gauges: Vec<Gauge>,
    /// Every field's scale (None: extensometers in px).
    scale: Option<MmPerPx>,
    history: GaugeHistory,
    readings: Vec<GaugeReading>,
}

impl MonitorGauges {
    /// The gauges of `config`, which the caller has checked (`RunConfig::validate`: a gauge
    /// outside the camera's image, an unknown kind, two of one name are refused there).
    pub fn of(config: &RunConfig) -> MonitorGauges {
        let structure = config.specimen.model == rig::SpecimenModel::Structure;
        let scale = FieldScale::of(config).without_solves(structure);
        let gauges = config.correlator.gauges.clone();
        MonitorGauges {
            history: GaugeHistory::new(&gauges, scale.is_some()),
            gauges,
            scale,
            readings: Vec::new(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.gauges.is_empty()
    }

    /// What the monitor says of them on stderr: their names, and the extensometers' unit.
    pub fn describe(&self) -> String {
        if self.gauges.is_empty() {
            return "the configuration places no gauges ([correlator] gauges)".to_string();
        }
        let names: Vec<String> = self
            .gauges
            .iter()
            .map(|g| format!("{} ({})", g.name, g.kind()))
            .collect();
        let extensometers = self
            .gauges
            .iter()
            .any(|g| matches!(g.shape, correlator::GaugeShape::Extensometer { .. }));
        let unit = match (extensometers, self.scale) {
            (false, _) => String::new(),
            (true, Some(s)) => format!("; extensometers in mm ({s} mm per px)"),
            (true, None) => "; extensometers in px (no scale known for every field without \
                             the specimen's solves)"
                .to_string(),
        };
        format!("gauges {}{unit}", names.join(", "))
    }
}

impl UserGauges for MonitorGauges {
    fn on_field(&mut self, header: &FieldHeader, nodes: &[FieldNode], time: FieldTime) {
        if time.restarted {
            self.history = GaugeHistory::new(&self.gauges, self.scale.is_some());
        }
        let step_px = f64::from(header.step_px);
        crate::gauge_columns::read_all(&self.gauges, nodes, step_px, &mut self.readings);
        self.history.push(&self.readings, time.t_s, self.scale);
    }

    fn to_json(&self) -> Value {
        self.history.to_json()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gauge_history::tests::nodes;

    fn gauges_of(toml: &str) -> MonitorGauges {
        let config = RunConfig::from_toml(toml, "t.toml").unwrap();
        config.validate().unwrap();
        MonitorGauges::of(&config)
    }

    #[test]
    fn the_configurations_gauges_are_read_on_each_field_in_the_runs_units() {
        let toml = "[camera]\nscale_mm_per_px = 0.5\n[correlator]\ngauges = \
                    [\"mid=rect:0,0,40,40\", \"arm=extensometer:0,20 40,20\"]\n";
        let mut gauges = gauges_of(toml);
        assert!(gauges
            .describe()
            .contains("mid (strain), arm (extensometer)"));
        assert!(gauges.describe().contains("in mm (0.5 mm per px)"));
        let header = FieldHeader {
            step_px: 10,
            mesh_cols: 5,
            mesh_rows: 5,
            ..FieldHeader::default()
        };
        let time = FieldTime {
            t_s: 2.0,
            restarted: false,
        };
        gauges.on_field(&header, &nodes(), time);
        let json = gauges.to_json();
        assert_eq!(json[0]["name"], "mid");
        assert!(json[0]["series"]["exx"][0].as_f64().unwrap() > 0.009);
        // 40 px stretched by 1 %: 0.4 px, 0.2 mm.
        assert_eq!(json[1]["unit"], "mm");
        let elongation = json[1]["series"]["elongation"][0].as_f64().unwrap();
        assert!((elongation - 0.2).abs() < 1e-3, "{elongation}");
        // The chart's clock changed: the history starts again.
        let restarted = FieldTime {
            t_s: 0.5,
            restarted: true,
        };
        gauges.on_field(&header, &nodes(), restarted);
        assert_eq!(gauges.to_json()[1]["t_s"], serde_json::json!([0.5]));
        // A structure's strip is framed apart from its cruciform: px, said.
        let structure = gauges_of(
            "[specimen]\nmodel = \"structure\"\n[correlator]\ngauges = [\"arm=extensometer:0,20 40,20\"]\n",
        );
        assert!(
            structure.describe().contains("in px"),
            "{}",
            structure.describe()
        );
        assert_eq!(structure.to_json()[0]["unit"], "px");
        assert!(gauges_of("").is_empty());
    }
}
