//! How `correlate` reports the user's gauges: a line per gauge after the run (their entries of
//! `summary.json`: `correlator::summary`).

use correlator::gauges::{GaugeReading, GaugeValue};
use correlator::Gauge;

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
    fn lines_say_the_value_or_why_not() {
        let ext: Gauge = "arm=extensometer:0,0 200,0".parse().unwrap();
        let reading = GaugeReading {
            nodes: 12,
            value: Ok(GaugeValue::Extension {
                length0_px: 200.0,
                length_px: 202.0,
            }),
        };
        assert!(reading_line(&ext, &reading).contains("elongation 2.000 px of 200.000 px"));
        let lost = GaugeReading {
            nodes: 0,
            value: Err(NoReading::TooFewNodes { found: 2 }),
        };
        assert!(reading_line(&ext, &lost).contains("no reading: 2 valid nodes"));
    }
}
