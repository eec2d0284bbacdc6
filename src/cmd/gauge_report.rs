//! How `correlate` reports the user's gauges: an entry of `summary.json` per gauge and frame,
//! and a line per gauge after the run.

use correlator::gauges::{GaugeReading, GaugeValue};
use correlator::{Field, Gauge, GaugeStrains};
use serde_json::{json, Value};

/// The four measures of a strain gauge, as `summary.json` writes them.
pub fn strains_json(g: &GaugeStrains) -> Value {
    let one = |s: correlator::Strain2| json!({ "exx": s.exx, "eyy": s.eyy, "exy": s.exy });
    json!({ "small": one(g.small), "green": one(g.green), "nominal": one(g.nominal), "log": one(g.log) })
}

/// One gauge's reading: its name, kind, valid nodes used, and its strains, its extension, or
/// why it has none.
pub fn reading_json(gauge: &Gauge, reading: &GaugeReading) -> Value {
    let mut entry = json!({ "name": gauge.name, "kind": gauge.kind(), "nodes": reading.nodes });
    match reading.value {
        Ok(GaugeValue::Strain(s)) => entry["strain"] = strains_json(&s),
        Ok(
            value @ GaugeValue::Extension {
                length0_px,
                length_px,
            },
        ) => {
            entry["length0_px"] = json!(length0_px);
            entry["length_px"] = json!(length_px);
            entry["elongation_px"] = json!(value.elongation_px());
            entry["nominal_strain"] = json!(value.nominal_strain());
        }
        Err(reason) => entry["no_reading"] = json!(reason.to_string()),
    }
    entry
}

/// Every gauge of the field, in the settings' order.
pub fn readings_json(gauges: &[Gauge], field: &Field) -> Value {
    Value::Array(
        (gauges.iter().zip(&field.gauges))
            .map(|(g, r)| reading_json(g, r))
            .collect(),
    )
}

/// The line a gauge gets after the run, from its last reading: `gauge mid (strain, 120
/// nodes): log exx 0.01234 eyy -0.00611 exy 0.00002`, `gauge arm (extensometer): elongation
/// 2.345 px of 200.000 px, nominal strain 0.01173`, or why it has no reading.
pub fn reading_line(gauge: &Gauge, reading: &GaugeReading) -> String {
    let head = format!("gauge {} ({}", gauge.name, gauge.kind());
    match reading.value {
        Ok(GaugeValue::Strain(s)) => format!(
            "{head}, {} nodes): log exx {:.5} eyy {:.5} exy {:.5}",
            reading.nodes, s.log.exx, s.log.eyy, s.log.exy
        ),
        Ok(value @ GaugeValue::Extension { length0_px, .. }) => format!(
            "{head}): elongation {:.3} px of {length0_px:.3} px, nominal strain {:.5}",
            value.elongation_px().unwrap_or(f64::NAN),
            value.nominal_strain().unwrap_or(f64::NAN)
        ),
        Err(reason) => format!("{head}): no reading: {reason}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use correlator::gauges::NoReading;

    #[test]
    fn readings_say_their_value_or_why_not() {
        let ext: Gauge = "arm=extensometer:0,0 200,0".parse().unwrap();
        let reading = GaugeReading {
            nodes: 12,
            value: Ok(GaugeValue::Extension {
                length0_px: 200.0,
                length_px: 202.0,
            }),
        };
        let j = reading_json(&ext, &reading);
        assert_eq!(j["kind"], "extensometer");
        assert!((j["elongation_px"].as_f64().unwrap() - 2.0).abs() < 1e-12);
        assert!((j["nominal_strain"].as_f64().unwrap() - 0.01).abs() < 1e-12);
        assert!(reading_line(&ext, &reading).contains("elongation 2.000 px of 200.000 px"));
        let lost = GaugeReading {
            nodes: 0,
            value: Err(NoReading::TooFewNodes { found: 2 }),
        };
        assert!(reading_json(&ext, &lost)["no_reading"]
            .as_str()
            .unwrap()
            .contains("2 valid nodes"));
        assert!(reading_line(&ext, &lost).contains("no reading: 2 valid nodes"));
    }
}
