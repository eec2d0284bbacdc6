//! A field as a VTK XML structured grid (`.vts`, ASCII): what a ParaView `.pvd` collection
//! ([`crate::pvd`]) lists, since ParaView's collection reader reads XML VTK files only (the
//! legacy `.vtk` of [`crate::output::field_vtk`] is read alone or through a `.vtk.series`).
//! The same arrays as the legacy file, at the nodes' reference positions (px, z = 0), and with
//! a scale the displacement in mm too.

use crate::field::Field;
use std::fmt::Write as _;
use wire::scale::MmPerPx;

/// `text` becomes the `.vts` of `field`; `scale` adds `displacement_mm`.
pub fn field_vts(field: &Field, scale: Option<MmPerPx>, text: &mut String) {
    text.clear();
    let extent = format!(
        "0 {} 0 {} 0 0",
        field.nx.saturating_sub(1),
        field.ny.saturating_sub(1)
    );
    let _ = write!(
        text,
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"StructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n\
         <StructuredGrid WholeExtent=\"{extent}\">\n<Piece Extent=\"{extent}\">\n\
         <PointData Scalars=\"exx\" Vectors=\"displacement_px\">\n"
    );
    open_array(text, "displacement_px", 3);
    for n in &field.nodes {
        let _ = writeln!(text, "{} {} 0", n.u_px, n.v_px);
    }
    close_array(text);
    if let Some(s) = scale {
        open_array(text, "displacement_mm", 3);
        for n in &field.nodes {
            let _ = writeln!(text, "{} {} 0", s.mm(n.u_px), s.mm(n.v_px));
        }
        close_array(text);
    }
    for (name, get) in crate::output::NODE_SCALARS {
        open_array(text, name, 1);
        for n in &field.nodes {
            let _ = writeln!(text, "{}", get(n));
        }
        close_array(text);
    }
    text.push_str("</PointData>\n<Points>\n");
    open_array(text, "position_px", 3);
    for n in &field.nodes {
        let _ = writeln!(text, "{} {} 0", n.x_px, n.y_px);
    }
    close_array(text);
    text.push_str("</Points>\n</Piece>\n</StructuredGrid>\n</VTKFile>\n");
}

fn open_array(text: &mut String, name: &str, components: usize) {
    let _ = writeln!(
        text,
        "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{components}\" format=\"ascii\">"
    );
}

fn close_array(text: &mut String) {
    text.push_str("</DataArray>\n");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{Node, NodeStatus};

    #[test]
    fn the_vts_is_xml_with_one_value_per_node_in_each_array() {
        let nodes: Vec<Node> = (0..6)
            .map(|k| Node {
                x_px: (k % 3) as f64 * 8.0,
                y_px: (k / 3) as f64 * 8.0,
                u_px: 0.5,
                status: NodeStatus::Ok,
                ..Node::default()
            })
            .collect();
        let field = Field {
            nx: 3,
            ny: 2,
            nodes,
            ..Field::default()
        };
        let mut text = String::new();
        field_vts(&field, MmPerPx::new(0.1).ok(), &mut text);
        let doc = roxmltree::Document::parse(&text).expect("well-formed XML");
        let piece = doc.descendants().find(|n| n.has_tag_name("Piece")).unwrap();
        assert_eq!(piece.attribute("Extent"), Some("0 2 0 1 0 0"));
        let arrays: Vec<_> = doc
            .descendants()
            .filter(|n| n.has_tag_name("DataArray"))
            .collect();
        assert_eq!(arrays.len(), 9);
        for a in &arrays {
            let per_node: usize = a.attribute("NumberOfComponents").unwrap().parse().unwrap();
            let values = a.text().unwrap().split_whitespace().count();
            assert_eq!(values, 6 * per_node, "{:?}", a.attribute("Name"));
        }
        let mm = arrays
            .iter()
            .find(|a| a.attribute("Name") == Some("displacement_mm"))
            .unwrap();
        assert!(mm.text().unwrap().trim().starts_with("0.05 0 0"));
    }
}
