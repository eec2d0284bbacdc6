//! The user's gauges in `frames.csv`: their columns, before the last (`sequence_id`: a row
//! always ends with a number), and each field's
//! cells (empty where a gauge has no reading on that field). A strain gauge writes its mean
//! log strains and the valid nodes it read; an extensometer its elongation (px) and nominal
//! strain. Read from the field's nodes with the correlator's own gauge code, so the numbers
//! are those `correlate --gauge` prints.

use correlator::gauges::{read, GaugeValue};
use correlator::{Gauge, GaugeShape};
use std::fmt::Write as _;
use wire::FieldNode;

/// The columns of these gauges, each preceded by a comma (nothing without gauges).
pub fn header(gauges: &[Gauge]) -> String {
    let mut out = String::new();
    for g in gauges {
        let n = &g.name;
        match g.shape {
            GaugeShape::Region(_) => {
                let _ = write!(
                    out,
                    ",gauge_{n}_log_exx,gauge_{n}_log_eyy,gauge_{n}_log_exy,gauge_{n}_nodes"
                );
            }
            GaugeShape::Extensometer { .. } => {
                let _ = write!(out, ",ext_{n}_elongation_px,ext_{n}_nominal_strain");
            }
        }
    }
    out
}

/// Appends the gauges' cells of one field (mesh step `step_px`) to `out`, each preceded by a
/// comma, in [`header`]'s order.
pub fn write_cells(gauges: &[Gauge], nodes: &[FieldNode], step_px: f64, out: &mut String) {
    for g in gauges {
        let reading = read(&g.shape, nodes, step_px);
        match (&g.shape, reading.value) {
            (_, Ok(GaugeValue::Strain(s))) => {
                let l = s.log;
                let _ = write!(
                    out,
                    ",{:.7},{:.7},{:.7},{}",
                    l.exx, l.eyy, l.exy, reading.nodes
                );
            }
            (_, Ok(value @ GaugeValue::Extension { .. })) => {
                let _ = write!(
                    out,
                    ",{:.5},{:.7}",
                    value.elongation_px().unwrap_or(f64::NAN),
                    value.nominal_strain().unwrap_or(f64::NAN)
                );
            }
            (GaugeShape::Region(_), Err(_)) => {
                let _ = write!(out, ",,,,{}", reading.nodes);
            }
            (GaugeShape::Extensometer { .. }, Err(_)) => out.push_str(",,"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(x: f32, y: f32, u: f32, ok: bool) -> FieldNode {
        FieldNode {
            x_px: x,
            y_px: y,
            u_px: u,
            status: if ok {
                0
            } else {
                wire::NodeStatus::LowZncc as u32
            },
            ..FieldNode::default()
        }
    }

    #[test]
    fn cells_follow_the_header_and_are_empty_without_a_reading() {
        let gauges: Vec<Gauge> = ["mid=rect:0,0,40,40", "arm=extensometer:5,5 25,5"]
            .iter()
            .map(|t| t.parse().unwrap())
            .collect();
        let head = header(&gauges);
        assert_eq!(
            head,
            ",gauge_mid_log_exx,gauge_mid_log_eyy,gauge_mid_log_exy,gauge_mid_nodes,ext_arm_elongation_px,ext_arm_nominal_strain"
        );
        // A 4 x 4 mesh, step 10 px, stretched 2 % along x.
        let mut nodes = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                let (x, y) = (10.0 * i as f32, 10.0 * j as f32);
                nodes.push(node(x, y, 0.02 * x, true));
            }
        }
        let mut cells = String::new();
        write_cells(&gauges, &nodes, 10.0, &mut cells);
        let values: Vec<&str> = cells.split(',').skip(1).collect();
        assert_eq!(values.len(), head.split(',').count() - 1);
        let number = |k: usize| values[k].parse::<f64>().unwrap();
        assert!((number(0) - 1.02f64.ln()).abs() < 1e-6, "{cells}");
        assert_eq!(values[3], "16");
        assert!((number(4) - 0.4).abs() < 1e-4, "{cells}");
        assert!((number(5) - 0.02).abs() < 1e-6, "{cells}");
        // Every node failed: the cells are empty, the node count says why.
        nodes.iter_mut().for_each(|n| n.status = 4);
        cells.clear();
        write_cells(&gauges, &nodes, 10.0, &mut cells);
        assert_eq!(cells, ",,,,0,,");
    }
}
