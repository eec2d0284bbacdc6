//! The user's gauges in `frames.csv`: their columns, before the last (`sequence_id`: a row
//! always ends with a number), and each field's
//! cells (empty where a gauge has no reading on that field). A strain gauge writes its mean
//! log strains and the valid nodes it read; an extensometer its elongation in px, in mm when
//! the run's fields have a scale (`FieldScale`; the cell is empty on a field without one), and
//! its nominal strain. Read from the field's nodes with the correlator's own gauge code, so the numbers
//! are those `correlate --gauge` prints.

use correlator::gauges::{read, GaugeValue};
use correlator::{Gauge, GaugeReading, GaugeShape};
use std::fmt::Write as _;
use wire::scale::MmPerPx;
use wire::FieldNode;

/// The columns of these gauges, each preceded by a comma (nothing without gauges); an
/// extensometer's elongation in mm too when `in_mm`.
pub fn header(gauges: &[Gauge], in_mm: bool) -> String {
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
                let _ = write!(out, ",ext_{n}_elongation_px");
                if in_mm {
                    let _ = write!(out, ",ext_{n}_elongation_mm");
                }
                let _ = write!(out, ",ext_{n}_nominal_strain");
            }
        }
    }
    out
}

/// The gauges' readings on one field (mesh step `step_px`), in their order, into `out`
/// (cleared): read once per field, for `frames.csv`'s cells and the dashboard's history.
pub fn read_all(gauges: &[Gauge], nodes: &[FieldNode], step_px: f64, out: &mut Vec<GaugeReading>) {
    out.clear();
    out.extend(gauges.iter().map(|g| read(&g.shape, nodes, step_px)));
}

/// Appends the cells of the gauges' `readings` (from [`read_all`]) to `out`, each preceded
/// by a comma, in the order of [`header`] with the same `in_mm`; `scale` is this field's.
pub fn write_cells(
    gauges: &[Gauge],
    readings: &[GaugeReading],
    in_mm: bool,
    scale: Option<MmPerPx>,
    out: &mut String,
) {
    debug_assert_eq!(gauges.len(), readings.len());
    for (g, reading) in gauges.iter().zip(readings) {
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
                let px = value.elongation_px().unwrap_or(f64::NAN);
                let _ = write!(out, ",{px:.5}");
                match (in_mm, scale) {
                    (true, Some(scale)) => {
                        let _ = write!(out, ",{:.6}", scale.mm(px));
                    }
                    (true, None) => out.push(','),
                    (false, _) => {}
                }
                let _ = write!(out, ",{:.7}", value.nominal_strain().unwrap_or(f64::NAN));
            }
            (GaugeShape::Region(_), Err(_)) => {
                let _ = write!(out, ",,,,{}", reading.nodes);
            }
            (GaugeShape::Extensometer { .. }, Err(_)) => {
                out.push_str(if in_mm { ",,," } else { ",," })
            }
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
        let head = header(&gauges, false);
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
        let (mut cells, mut readings) = (String::new(), Vec::new());
        read_all(&gauges, &nodes, 10.0, &mut readings);
        write_cells(&gauges, &readings, false, None, &mut cells);
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
        read_all(&gauges, &nodes, 10.0, &mut readings);
        write_cells(&gauges, &readings, false, None, &mut cells);
        assert_eq!(cells, ",,,,0,,");
    }

    #[test]
    fn an_extensometer_has_its_elongation_in_mm_where_the_field_has_a_scale() {
        let gauges: Vec<Gauge> = vec!["arm=extensometer:5,5 25,5".parse().unwrap()];
        let head = header(&gauges, true);
        assert_eq!(
            head,
            ",ext_arm_elongation_px,ext_arm_elongation_mm,ext_arm_nominal_strain"
        );
        let nodes: Vec<FieldNode> = (0..16)
            .map(|k| {
                let (x, y) = (10.0 * (k % 4) as f32, 10.0 * (k / 4) as f32);
                node(x, y, 0.02 * x, true)
            })
            .collect();
        let (mut cells, mut readings) = (String::new(), Vec::new());
        read_all(&gauges, &nodes, 10.0, &mut readings);
        write_cells(&gauges, &readings, true, MmPerPx::new(0.5).ok(), &mut cells);
        let values: Vec<f64> = cells
            .split(',')
            .skip(1)
            .map(|v| v.parse().unwrap())
            .collect();
        // 20 px stretched 2 %: 0.4 px, 0.2 mm at 0.5 mm per px.
        assert!((values[0] - 0.4).abs() < 1e-4, "{cells}");
        assert!((values[1] - 0.2).abs() < 1e-4, "{cells}");
        assert!((values[2] - 0.02).abs() < 1e-6, "{cells}");
        // A field without a scale (a run's test whose camera is not calibrated): empty mm.
        cells.clear();
        write_cells(&gauges, &readings, true, None, &mut cells);
        assert_eq!(cells.split(',').nth(2), Some(""), "{cells}");
        assert_eq!(cells.split(',').count(), head.split(',').count(), "{cells}");
        // No reading: three empty cells.
        cells.clear();
        let failed = vec![correlator::GaugeReading::default()];
        write_cells(&gauges, &failed, true, None, &mut cells);
        assert_eq!(cells, ",,,");
    }
}
