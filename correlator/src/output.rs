//! Field files, one format each, shared by every tool that writes fields (`dicstream
//! correlate`, the live bench's results): the CSV contract, legacy VTK structured grids for
//! ParaView, and an RGB colour map of a node value over a grey image (the maps and their
//! ranges: `wire::colour_map`, `wire::colour_range`).

use crate::field::{Field, Node, NodeStatus};
use crate::StrainMeasure;
use std::fmt::Write as _;
use wire::colour_map::ColourScale;
use wire::colour_range::{NodeGrid, RangeChoice};
use wire::column_units::{Column, CsvUnits, ONE};
use wire::scale::MmPerPx;

/// The CSV contract: header `x,y,u,v,exx,eyy,exy,score,iterations,status,du_dx,du_dy,dv_dx,dv_dy`,
/// one row per node (row-major), x/y the ZOI centre in the reference image (px), u/v in px,
/// status a word, then the node's displacement gradient (dimensionless, `Field::gradients`:
/// IC-GN's own with `icgn1`/`icgn2`, the least-squares fit of the neighbouring nodes with
/// `correli`; 0 where the node is not `ok`). The gradient columns come last so that readers of
/// the first ten columns are unaffected. Without a scale: px only ([`field_csv_scaled`] adds
/// the mm columns). Each column's unit: [`field_csv_units`].
pub fn field_csv(field: &Field, text: &mut String) {
    field_csv_scaled(field, None, text);
}

/// [`field_csv`], and with a scale `x_mm,y_mm,u_mm,v_mm` after the gradient (the px columns
/// times the scale; the origin of x_mm, y_mm is the image's, as x, y's).
pub fn field_csv_scaled(field: &Field, scale: Option<MmPerPx>, text: &mut String) {
    text.clear();
    text.push_str(CSV_HEADER);
    if scale.is_some() {
        text.push_str(CSV_MM_COLUMNS);
    }
    text.push('\n');
    for (k, n) in field.nodes.iter().enumerate() {
        let g = node_gradient(field, k);
        let _ = write!(
            text,
            "{},{},{:.6},{:.6},{:.7},{:.7},{:.7},{:.5},{},{},{:.7},{:.7},{:.7},{:.7}",
            n.x_px,
            n.y_px,
            n.u_px,
            n.v_px,
            n.exx,
            n.eyy,
            n.exy,
            n.score,
            n.iterations,
            n.status.name(),
            g[0][0],
            g[0][1],
            g[1][0],
            g[1][1]
        );
        if let Some(s) = scale {
            let _ = write!(
                text,
                ",{:.6},{:.6},{:.7},{:.7}",
                s.mm(n.x_px),
                s.mm(n.y_px),
                s.mm(n.u_px),
                s.mm(n.v_px)
            );
        }
        text.push('\n');
    }
}

/// The columns [`field_csv_scaled`] appends when a scale is known, each with its comma.
pub const CSV_MM_COLUMNS: &str = ",x_mm,y_mm,u_mm,v_mm";

/// Each column of a field CSV written with `scale` in strain measure `strain`, and what holds
/// for the file (`files`: which files, relative to the sidecar), for the `units.json` sidecar.
pub fn field_csv_units(files: &str, strain: StrainMeasure, scale: Option<MmPerPx>) -> CsvUnits {
    let measure = match strain {
        StrainMeasure::Small => "small (infinitesimal) strain, sym(grad u)",
        StrainMeasure::Green => "Green-Lagrange strain, (C - 1)/2",
        StrainMeasure::Nominal => "nominal (Biot) strain, C^(1/2) - 1",
        StrainMeasure::Log => "logarithmic (Hencky) strain, ln(C)/2",
    };
    let mut notes = vec![
        format!("strain measure: {} ({measure})", strain.name()),
        "exy is the tensor component, half the engineering shear strain gamma_xy".to_string(),
        "x, y: pixel column and row in the node's origin image, origin at the centre of the \
         top-left pixel; u, v: Lagrangian displacements along x and y"
            .to_string(),
    ];
    notes.push(match scale {
        Some(s) => format!("scale: {s} mm per px (the mm columns are the px ones times it)"),
        None => "no scale known: px only, no mm columns".to_string(),
    });
    let mut columns = vec![
        Column::new("x", "px", "node (ZOI centre) column in the reference image"),
        Column::new("y", "px", "node (ZOI centre) row in the reference image"),
        Column::new("u", "px", "displacement along x"),
        Column::new("v", "px", "displacement along y"),
        Column::new("exx", ONE, format!("{} strain xx", strain.name())),
        Column::new("eyy", ONE, format!("{} strain yy", strain.name())),
        Column::new(
            "exy",
            ONE,
            format!(
                "{} strain xy, tensor component (gamma_xy / 2)",
                strain.name()
            ),
        ),
        Column::new("score", ONE, "final check's ZNCC of the match, in [-1, 1]"),
        Column::new("iterations", ONE, "sub-pixel iterations"),
        Column::new("status", "", "ok, or why the node is not measured"),
        Column::new("du_dx", ONE, "displacement gradient du/dx (0 where not ok)"),
        Column::new("du_dy", ONE, "displacement gradient du/dy"),
        Column::new("dv_dx", ONE, "displacement gradient dv/dx"),
        Column::new("dv_dy", ONE, "displacement gradient dv/dy"),
    ];
    if scale.is_some() {
        columns.extend([
            Column::new("x_mm", "mm", "x times the scale"),
            Column::new("y_mm", "mm", "y times the scale"),
            Column::new("u_mm", "mm", "displacement along x"),
            Column::new("v_mm", "mm", "displacement along y"),
        ]);
    }
    CsvUnits {
        files: files.to_string(),
        notes,
        columns,
    }
}

/// The first line of [`field_csv`].
pub const CSV_HEADER: &str = "x,y,u,v,exx,eyy,exy,score,iterations,status,du_dx,du_dy,dv_dx,dv_dy";

/// Node `k`'s gradient [[∂u/∂x, ∂u/∂y], [∂v/∂x, ∂v/∂y]], zero when the field carries none.
pub fn node_gradient(field: &Field, k: usize) -> [[f64; 2]; 2] {
    field.gradients.get(k).copied().unwrap_or([[0.0; 2]; 2])
}

/// One scalar of a node.
pub(crate) type NodeScalar = fn(&Node) -> f64;

/// The per-node scalars both VTK writers (legacy here, XML in `vts`) carry, by name: the
/// strains (tensor components, the field's measure), the score, the iterations and validity
/// (1 for a converged node).
pub(crate) const NODE_SCALARS: [(&str, NodeScalar); 6] = [
    ("exx", |n| n.exx),
    ("eyy", |n| n.eyy),
    ("exy", |n| n.exy),
    ("score", |n| n.score),
    ("iterations", |n| n.iterations as f64),
    ("valid", |n| f64::from(u8::from(n.status == NodeStatus::Ok))),
];

/// Legacy VTK structured grid at the reference node positions (z = 0), titled `title`.
pub fn field_vtk(field: &Field, title: &str, text: &mut String) {
    text.clear();
    let count = field.nodes.len();
    let title: String = title.chars().filter(|c| *c != '\n').take(200).collect();
    let _ = write!(
        text,
        "# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET STRUCTURED_GRID\nDIMENSIONS {} {} 1\nPOINTS {count} double\n",
        field.nx, field.ny
    );
    for n in &field.nodes {
        let _ = writeln!(text, "{} {} 0", n.x_px, n.y_px);
    }
    let _ = writeln!(text, "POINT_DATA {count}\nVECTORS displacement_px double");
    for n in &field.nodes {
        let _ = writeln!(text, "{} {} 0", n.u_px, n.v_px);
    }
    for (name, get) in NODE_SCALARS {
        let _ = writeln!(text, "SCALARS {name} double 1\nLOOKUP_TABLE default");
        for n in &field.nodes {
            let _ = writeln!(text, "{}", get(n));
        }
    }
    // ParaView reads a 3x3 row-major tensor: [[du/dx, du/dy, 0], [dv/dx, dv/dy, 0], [0, 0, 0]].
    let _ = writeln!(text, "TENSORS displacement_gradient double");
    for k in 0..count {
        let g = node_gradient(field, k);
        let _ = writeln!(
            text,
            "{} {} 0 {} {} 0 0 0 0",
            g[0][0], g[0][1], g[1][0], g[1][1]
        );
    }
}

/// Each node's `value` on the mesh's grid, `None` where the node is not `ok` or the value not
/// finite: what [`wire::colour_range`] reads.
pub fn node_values(field: &Field, value: impl Fn(&Node) -> f64) -> Vec<Option<f64>> {
    field
        .nodes
        .iter()
        .map(|n| Some(value(n)).filter(|v| n.status == NodeStatus::Ok && v.is_finite()))
        .collect()
}

/// The colour scale of `value` over the field's valid nodes (`signed`, `lag_nodes` and
/// `choice` as [`wire::colour_range::choose`]'s).
pub fn field_colour_scale(
    field: &Field,
    value: impl Fn(&Node) -> f64,
    signed: bool,
    lag_nodes: usize,
    choice: RangeChoice,
) -> ColourScale {
    let values = node_values(field, value);
    let grid = NodeGrid {
        values: &values,
        nx: field.nx,
        ny: field.ny,
    };
    wire::colour_range::choose(grid, lag_nodes, signed, choice)
}

/// RGB bytes (row-major, 3 per pixel) of the grey image `grey` (`width` px wide), overlaid
/// inside the mesh with `value` coloured by `scale` (bilinear between valid nodes; values
/// beyond the scale's range at the colour of its end).
pub fn colour_map_rgb(
    grey: &[u16],
    width: usize,
    field: &Field,
    value: impl Fn(&Node) -> f64,
    scale: &ColourScale,
) -> Vec<u8> {
    assert!(width > 0 && grey.len().is_multiple_of(width), "image shape");
    let (w, h) = (width, grey.len() / width);
    let max_grey = grey.iter().copied().max().unwrap_or(1).max(1) as f64;
    let any_valid = node_values(field, &value).iter().any(Option::is_some);
    let mut rgb = vec![0u8; w * h * 3];
    for (k, &p) in grey.iter().enumerate() {
        let g = (255.0 * p as f64 / max_grey) as u8;
        rgb[3 * k..3 * k + 3].copy_from_slice(&[g, g, g]);
    }
    if field.nx >= 2 && field.ny >= 2 && any_valid {
        let first = field.node(0, 0);
        let last = field.node(field.nx - 1, field.ny - 1);
        let (sx, sy) = (
            (last.x_px - first.x_px) / (field.nx - 1) as f64,
            (last.y_px - first.y_px) / (field.ny - 1) as f64,
        );
        let x_range =
            first.x_px.max(0.0).ceil() as usize..=(last.x_px.floor().max(0.0) as usize).min(w - 1);
        for y in
            first.y_px.max(0.0).ceil() as usize..=(last.y_px.floor().max(0.0) as usize).min(h - 1)
        {
            for x in x_range.clone() {
                let fx = (x as f64 - first.x_px) / sx;
                let fy = (y as f64 - first.y_px) / sy;
                let (i, j) = (
                    (fx as usize).min(field.nx - 2),
                    (fy as usize).min(field.ny - 2),
                );
                let (tx, ty) = (fx - i as f64, fy - j as f64);
                let corners = [
                    (i, j, (1.0 - tx) * (1.0 - ty)),
                    (i + 1, j, tx * (1.0 - ty)),
                    (i, j + 1, (1.0 - tx) * ty),
                    (i + 1, j + 1, tx * ty),
                ];
                let (mut sum, mut weight) = (0.0, 0.0);
                for (ci, cj, wgt) in corners {
                    let node = field.node(ci, cj);
                    let v = value(node);
                    if node.status == NodeStatus::Ok && v.is_finite() {
                        sum += wgt * v;
                        weight += wgt;
                    }
                }
                if weight <= 1e-9 {
                    continue;
                }
                let colour = scale.rgb(sum / weight);
                let px = &mut rgb[3 * (y * w + x)..3 * (y * w + x) + 3];
                for (c, &col) in px.iter_mut().zip(&colour) {
                    *c = (0.35 * *c as f64 + 0.65 * col as f64) as u8;
                }
            }
        }
    }
    rgb
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field() -> Field {
        let mut nodes = Vec::new();
        for j in 0..3 {
            for i in 0..4 {
                nodes.push(Node {
                    x_px: 2.0 + 4.0 * i as f64,
                    y_px: 2.0 + 4.0 * j as f64,
                    u_px: 0.1 * i as f64,
                    exx: i as f64,
                    status: if (i, j) == (3, 2) {
                        NodeStatus::LowContrast
                    } else {
                        NodeStatus::Ok
                    },
                    ..Node::default()
                });
            }
        }
        let gradients = (0..12)
            .map(|k| [[0.01 * k as f64, 0.002], [-0.003, 0.25]])
            .collect();
        Field {
            nx: 4,
            ny: 3,
            nodes,
            gradients,
            ..Field::default()
        }
    }

    #[test]
    fn csv_and_vtk_have_one_row_per_node() {
        let f = field();
        let mut text = String::new();
        field_csv(&f, &mut text);
        assert_eq!(text.lines().count(), 13);
        assert!(text
            .starts_with("x,y,u,v,exx,eyy,exy,score,iterations,status,du_dx,du_dy,dv_dx,dv_dy\n"));
        let last = text.lines().last().unwrap();
        assert!(last.ends_with("low_contrast,0.1100000,0.0020000,-0.0030000,0.2500000"));
        let columns = CSV_HEADER.split(',').count();
        assert!(text.lines().all(|l| l.split(',').count() == columns));
        field_vtk(&f, "test\ntitle", &mut text);
        assert!(text.contains("DIMENSIONS 4 3 1"));
        assert!(text.contains("testtitle"));
        assert_eq!(text.matches("LOOKUP_TABLE").count(), 6);
        let tensors = text
            .split("TENSORS displacement_gradient double\n")
            .nth(1)
            .unwrap();
        assert_eq!(tensors.lines().count(), 12);
        assert_eq!(
            tensors.lines().nth(1).unwrap(),
            "0.01 0.002 0 -0.003 0.25 0 0 0 0"
        );
    }

    #[test]
    fn a_scale_adds_the_mm_columns_and_the_units_say_each_columns_unit() {
        let f = field();
        let mut text = String::new();
        let scale = MmPerPx::new(0.25).unwrap();
        field_csv_scaled(&f, Some(scale), &mut text);
        let header = text.lines().next().unwrap();
        assert_eq!(header, format!("{CSV_HEADER},x_mm,y_mm,u_mm,v_mm"));
        let columns = header.split(',').count();
        assert!(text.lines().all(|l| l.split(',').count() == columns));
        // Node (1, 0): x 6 px, y 2 px, u 0.1 px.
        let row: Vec<&str> = text.lines().nth(2).unwrap().split(',').collect();
        assert_eq!(
            &row[14..],
            ["1.500000", "0.500000", "0.0250000", "0.0000000"]
        );
        let units = field_csv_units("field_*.csv", StrainMeasure::Green, Some(scale));
        assert_eq!(units.header(), header);
        assert_eq!(units.column("u").unwrap().unit, "px");
        assert_eq!(units.column("u_mm").unwrap().unit, "mm");
        assert!(units
            .column("exy")
            .unwrap()
            .meaning
            .contains("tensor component"));
        assert!(units.notes[0].contains("green"));
        // No scale: px only, and nothing says mm.
        field_csv(&f, &mut text);
        let plain = field_csv_units("field_*.csv", StrainMeasure::Log, None);
        assert_eq!(plain.header(), text.lines().next().unwrap());
        assert!(plain.columns.iter().all(|c| c.unit != "mm"));
        assert!(plain.notes.iter().any(|n| n.contains("no scale known")));
    }

    #[test]
    fn csv_without_gradients_writes_zeros() {
        let mut f = field();
        f.gradients.clear();
        let mut text = String::new();
        field_csv(&f, &mut text);
        assert!(text
            .lines()
            .nth(1)
            .unwrap()
            .ends_with(",ok,0.0000000,0.0000000,0.0000000,0.0000000"));
    }

    #[test]
    fn colour_map_spans_the_valid_values() {
        let f = field();
        let grey = vec![100u16; 16 * 12];
        let scale = field_colour_scale(&f, |n| n.exx, true, 1, RangeChoice::Auto);
        // exx 0 to 3 along x (one sign, linear: no noise, no floor): viridis over 0 to 3.
        assert_eq!(
            scale,
            ColourScale {
                map: wire::colour_map::ColourMap::Viridis,
                low: 0.0,
                high: 3.0
            }
        );
        let rgb = colour_map_rgb(&grey, 16, &f, |n| n.exx, &scale);
        assert_eq!(rgb.len(), 16 * 12 * 3);
        // Left column of nodes (exx 0) dark violet, right column (exx 3) yellow.
        let px = |x: usize, y: usize| &rgb[3 * (y * 16 + x)..3 * (y * 16 + x) + 3];
        assert!(px(2, 2)[2] > px(2, 2)[1], "{:?}", px(2, 2));
        assert!(px(14, 2)[0] > 2 * px(14, 2)[2], "{:?}", px(14, 2));
        // Outside the mesh: grey.
        assert_eq!(px(0, 0), &[255, 255, 255]);
        // The invalid node (3, 2) takes no part: a fixed range that only it would exceed.
        let values = node_values(&f, |n| n.exx);
        assert_eq!(values[11], None);
        assert_eq!(values.iter().flatten().count(), 11);
    }

    #[test]
    fn a_signed_value_across_zero_is_drawn_white_at_zero() {
        let f = field();
        let grey = vec![0u16; 16 * 12];
        // exx - 1.5: -1.5 to 1.5, the diverging map; at x = 8 (between nodes 1 and 2) zero.
        let scale = field_colour_scale(&f, |n| n.exx - 1.5, true, 1, RangeChoice::Auto);
        assert_eq!(scale.map, wire::colour_map::ColourMap::Diverging);
        let rgb = colour_map_rgb(&grey, 16, &f, |n| n.exx - 1.5, &scale);
        let px = |x: usize, y: usize| &rgb[3 * (y * 16 + x)..3 * (y * 16 + x) + 3];
        // Over a black image 65 % of the map's white.
        assert!(px(8, 4).iter().all(|&c| c > 150), "{:?}", px(8, 4));
        assert!(px(2, 4)[2] > px(2, 4)[0] && px(13, 4)[0] > px(13, 4)[2]);
    }
}
