//! A frame's summary as JSON: the numbers `dicstream correlate` writes per frame into
//! `summary.json` (nodes, valid, mean displacement, the control gauge and the user's gauges,
//! nodes per status...), and that the Python module's `correlate` returns: one definition for
//! both.

use crate::field::{Field, NodeStatus, Strain2};
use crate::gauges::{Gauge, GaugeReading, GaugeValue};
use crate::GaugeStrains;
use serde_json::{json, Value};

/// Frame `field`'s summary, its user gauges being `gauges` (the settings' order). The CLI adds
/// the frame's index, file and time.
pub fn frame_summary(field: &Field, gauges: &[Gauge]) -> Value {
    json!({
        "nodes": field.nodes.len(),
        "nodes_in_region": field.in_region(),
        "valid": field.valid,
        "u_mean": field.u_mean_px,
        "v_mean": field.v_mean_px,
        "gauge": strains_json(&field.gauge),
        "gauge_nodes": field.gauge_nodes,
        "gauges": readings_json(gauges, field),
        "reference_updated": field.reference_updated,
        "statuses": status_json(field),
        "global_px": field.global_px.map(|(u, v)| [u, v]),
        "keypoints_used": field.keypoints_used,
        "second_order_runs": field.second_order_runs,
        "second_order_nodes": field.second_order_nodes(),
    })
}

/// Nodes per status, by status word.
pub fn status_json(field: &Field) -> Value {
    NodeStatus::ALL
        .iter()
        .map(|&s| (s.name().to_owned(), field.count(s).into()))
        .collect::<serde_json::Map<_, _>>()
        .into()
}

/// The four measures of a strain gauge.
pub fn strains_json(g: &GaugeStrains) -> Value {
    let one = |s: Strain2| json!({ "exx": s.exx, "eyy": s.eyy, "exy": s.exy });
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gauges::NoReading;

    #[test]
    fn readings_say_their_value_or_why_not() {
        let arm: Gauge = "arm=extensometer:0,0 200,0".parse().unwrap();
        let stretched = GaugeValue::Extension {
            length0_px: 200.0,
            length_px: 202.0,
        };
        let j = reading_json(
            &arm,
            &GaugeReading {
                nodes: 12,
                value: Ok(stretched),
            },
        );
        assert_eq!(
            (j["kind"].as_str(), j["nodes"].as_u64()),
            (Some("extensometer"), Some(12))
        );
        assert!((j["elongation_px"].as_f64().unwrap() - 2.0).abs() < 1e-12);
        assert!((j["nominal_strain"].as_f64().unwrap() - 0.01).abs() < 1e-12);
        let too_few = Err(NoReading::TooFewNodes { found: 2 });
        let lost = reading_json(
            &arm,
            &GaugeReading {
                nodes: 0,
                value: too_few,
            },
        );
        let why = lost["no_reading"].as_str().unwrap();
        assert!(why.contains("2 valid nodes"), "{why}");
    }
}
