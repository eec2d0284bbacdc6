//! A solved state as files people open: a legacy VTK unstructured grid of quadratic triangles
//! (VTK cell type 22, whose node order is T6's: corners, then midsides 01, 12, 20) with the
//! nodal fields as point data, and a CSV of one row per node. Pure: text in, the caller writes.
//! Units: mm, MPa; stresses are in-plane Cauchy stresses, Voigt [xx, yy, xy] (tensor xy).

use crate::mesh::Mesh;
use crate::nodal::NodalField;
use crate::t6::NODES;
use std::fmt::Write as _;

/// A nodal scalar written as VTK point data: its name and how it is read off a node.
type Scalar = (&'static str, fn(&NodalField) -> f64);

/// VTK's cell type of the six-node quadratic triangle.
const VTK_QUADRATIC_TRIANGLE: u8 = 22;

/// Header of [`nodes_csv`].
pub const NODES_CSV_HEADER: &str = "node,x_mm,y_mm,u_mm,v_mm,stretch_1,stretch_2,stretch_3,\
cauchy_xx_mpa,cauchy_yy_mpa,cauchy_xy_mpa,cauchy_1_mpa,cauchy_2_mpa,state";

/// One row per node: reference position, displacement, principal stretches (λ1 ≥ λ2 in plane,
/// λ3 through the thickness), in-plane Cauchy stress and its principal values, tension-field
/// state.
pub fn nodes_csv(nodes: &[NodalField]) -> String {
    let mut text = String::with_capacity(160 * (nodes.len() + 1));
    text.push_str(NODES_CSV_HEADER);
    text.push('\n');
    for (index, n) in nodes.iter().enumerate() {
        let s = n.cauchy_stress_mpa;
        let (s1, s2) = crate::constitutive::principal_values(&s);
        let _ = writeln!(
            text,
            "{index},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            n.reference_mm[0],
            n.reference_mm[1],
            n.displacement_mm[0],
            n.displacement_mm[1],
            n.stretches[0],
            n.stretches[1],
            n.stretches[2],
            s[0],
            s[1],
            s[2],
            s1,
            s2,
            n.state.name()
        );
    }
    text
}

/// Legacy VTK unstructured grid at the reference positions (z = 0) titled `title` (one line),
/// with displacement (vector), stretches, Cauchy stress and the state code (0 taut, 1
/// wrinkled, 2 slack) as point data.
pub fn state_vtk(mesh: &Mesh, nodes: &[NodalField], title: &str) -> String {
    let count = nodes.len();
    let mut text = String::with_capacity(256 * (count + mesh.elements.len()));
    let title = title.replace(['\n', '\r'], " ");
    let _ = write!(
        text,
        "# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {count} double\n"
    );
    for p in &mesh.nodes_mm {
        let _ = writeln!(text, "{} {} 0", p[0], p[1]);
    }
    let cells = mesh.elements.len();
    let _ = writeln!(text, "CELLS {cells} {}", cells * (NODES + 1));
    for element in &mesh.elements {
        let _ = write!(text, "{NODES}");
        for n in element {
            let _ = write!(text, " {n}");
        }
        text.push('\n');
    }
    let _ = writeln!(text, "CELL_TYPES {cells}");
    for _ in 0..cells {
        let _ = writeln!(text, "{VTK_QUADRATIC_TRIANGLE}");
    }
    let _ = writeln!(text, "POINT_DATA {count}\nVECTORS displacement_mm double");
    for n in nodes {
        let _ = writeln!(text, "{} {} 0", n.displacement_mm[0], n.displacement_mm[1]);
    }
    let scalars: [Scalar; 7] = [
        ("stretch_1", |n| n.stretches[0]),
        ("stretch_2", |n| n.stretches[1]),
        ("stretch_3", |n| n.stretches[2]),
        ("cauchy_xx_mpa", |n| n.cauchy_stress_mpa[0]),
        ("cauchy_yy_mpa", |n| n.cauchy_stress_mpa[1]),
        ("cauchy_xy_mpa", |n| n.cauchy_stress_mpa[2]),
        ("state", |n| n.state as u8 as f64),
    ];
    for (name, value) in scalars {
        let _ = writeln!(text, "SCALARS {name} double 1\nLOOKUP_TABLE default");
        for n in nodes {
            let _ = writeln!(text, "{}", value(n));
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constitutive::MembraneState;
    use crate::specimens::strip::StripGeometry;

    fn at_rest(mesh: &Mesh) -> Vec<NodalField> {
        mesh.nodes_mm
            .iter()
            .map(|&p| NodalField {
                reference_mm: p,
                displacement_mm: [0.5 * p[0], 0.0],
                deformation_gradient: [[1.5, 0.0], [0.0, 1.0]],
                stretches: [1.5, 1.0, 1.0 / 1.5],
                cauchy_stress_mpa: [1.0, 0.0, 0.0],
                state: MembraneState::Wrinkled,
            })
            .collect()
    }

    #[test]
    fn csv_and_vtk_have_one_row_per_node_and_one_cell_per_element() {
        let strip = StripGeometry {
            length_mm: 20.0,
            width_mm: 10.0,
            thickness_mm: 1.0,
            element_size_mm: 10.0,
        }
        .mesh()
        .unwrap();
        let nodes = at_rest(&strip.mesh);
        let csv = nodes_csv(&nodes);
        assert_eq!(csv.lines().count(), nodes.len() + 1);
        assert_eq!(csv.lines().nth(1).unwrap().split(',').count(), 14);
        assert!(csv.lines().nth(1).unwrap().ends_with(",wrinkled"));
        let vtk = state_vtk(&strip.mesh, &nodes, "a\ntitle");
        let lines: Vec<&str> = vtk.lines().collect();
        assert_eq!(lines[1], "a title");
        let cells = strip.mesh.elements.len();
        assert!(lines.contains(&format!("CELLS {cells} {}", 7 * cells).as_str()));
        assert_eq!(lines.iter().filter(|l| **l == "22").count(), cells);
        assert_eq!(lines.iter().filter(|l| l.starts_with("SCALARS")).count(), 7);
        // Every section holds as many values as it announces.
        let points = lines
            .iter()
            .position(|l| l.starts_with("POINT_DATA"))
            .unwrap();
        assert_eq!(
            lines.len(),
            points + 2 + nodes.len() + 7 * (2 + nodes.len())
        );
    }
}
