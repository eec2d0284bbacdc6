//! The camera's view of a finite-element displacement field: the specimen as a structure
//! (crate `membrane`), its nodal displacements interpolated by the mesh's own quadratic shape
//! functions, seen through a camera of a given scale.
//!
//! Coordinates: reference image px X ↔ specimen mm by [`View`] (rig X is the image column,
//! rig Y the image row, as for the homogeneous camera of `rig_follow`). The field is exact
//! everywhere in the mesh, not only at its nodes: x = φ(X) = X + Σ Nᵢ(ξ, η) uᵢ in the element
//! holding X.
//!
//! The inverse X = φ⁻¹(x), what every renderer needs per pixel, is exact and needs no
//! iteration on the field: the deformed mesh (nodes at Xᵢ + uᵢ, same elements) is the image of
//! the reference one under φ with the same shape functions, so locating x in the deformed mesh
//! gives (element, ξ, η) and X = Σ Nᵢ(ξ, η) Xᵢ. A point of the image outside the deformed mesh
//! is not material (the room behind the specimen, between the arms of a cruciform): `None`,
//! which the renderers show as [`BACKDROP`].
//!
//! Along a row of pixels, each pixel starts from its neighbour's element and natural
//! coordinates (one or two Newton steps of the quadratic map), and falls back to the element
//! grid when it crosses into another element.

mod cells;
mod element_map;
mod outline;

use std::sync::Arc;

pub use cells::{CellRows, CELL_ROWS};
use element_map::QuadraticMap;
use membrane::{sample_at, ElementGrid, Location, Mesh, PointSample};
use outline::{near_a_span, Outline};

use crate::error::ProducerError;
use crate::motion::{inverse, mul_mat, Mat2, Vec2};

/// How far apart along a row the fast renderer finds exact points of the inverse map (the
/// pixels between are interpolated, [`hermite_along_row`]).
pub const BLOCK_SPAN_PX: usize = 8;

/// The pattern value where the camera sees no material (behind the specimen): black.
pub const BACKDROP: f32 = 0.0;

/// How the camera sees the specimen: the reference point `centre_mm` at the image point
/// `centre_px`, `mm_per_px` on both axes, no rotation (a rotated specimen is a boundary
/// condition of the mechanics, not of the camera).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub mm_per_px: f64,
    pub centre_px: Vec2,
    pub centre_mm: Vec2,
}

impl View {
    /// The rig camera's view: the specimen's centre (0, 0 mm) at the centre of a `width_px` ×
    /// `height_px` image, `mm_per_px` on both axes. What the camera films and the truth is
    /// computed in.
    pub fn centred(mm_per_px: f64, width_px: u32, height_px: u32) -> View {
        View {
            mm_per_px,
            centre_px: [
                (f64::from(width_px) - 1.0) / 2.0,
                (f64::from(height_px) - 1.0) / 2.0,
            ],
            centre_mm: [0.0, 0.0],
        }
    }

    /// Specimen mm of image px.
    pub fn to_mm(&self, p_px: Vec2) -> [f64; 2] {
        [
            self.centre_mm[0] + (p_px[0] - self.centre_px[0]) * self.mm_per_px,
            self.centre_mm[1] + (p_px[1] - self.centre_px[1]) * self.mm_per_px,
        ]
    }

    /// Image px of specimen mm.
    pub fn to_px(&self, x_mm: [f64; 2]) -> Vec2 {
        [
            self.centre_px[0] + (x_mm[0] - self.centre_mm[0]) / self.mm_per_px,
            self.centre_px[1] + (x_mm[1] - self.centre_mm[1]) / self.mm_per_px,
        ]
    }
}

/// How the simulated camera frames the specimen mounted, its centre at the image's centre:
/// `mm_per_px` on a cruciform (and the homogeneous sheet), `strip_mm_per_px` on a specimen
/// held by two grips (the uniaxial or plane-strain strip), for which a lab re-frames the
/// camera: a strip 20 mm wide would cross a cruciform's view in a few ZOIs.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Framing {
    pub mm_per_px: f64,
    pub strip_mm_per_px: f64,
}

impl Framing {
    /// The view of a specimen held by `grips` grips in a `width_px` × `height_px` image.
    pub fn view(&self, grips: usize, width_px: u32, height_px: u32) -> View {
        let mm_per_px = match grips {
            2 => self.strip_mm_per_px,
            _ => self.mm_per_px,
        };
        View::centred(mm_per_px, width_px, height_px)
    }
}

/// The reference mesh and its element grid, built once per specimen and shared by every state.
#[derive(Debug)]
pub struct ReferenceMesh {
    pub mesh: Mesh,
    grid: ElementGrid,
    maps: Vec<QuadraticMap>,
    /// Per element: whether one of its edges is on the specimen's boundary (no other element
    /// shares it).
    on_boundary: Vec<bool>,
    /// The boundary edges: corner, midside, corner.
    boundary_edges: Vec<[usize; 3]>,
}

impl ReferenceMesh {
    pub fn new(mesh: Mesh) -> Arc<ReferenceMesh> {
        let grid = ElementGrid::new(&mesh);
        let maps = element_maps(&mesh);
        let (on_boundary, boundary_edges) = boundary(&mesh);
        Arc::new(ReferenceMesh {
            mesh,
            grid,
            maps,
            on_boundary,
            boundary_edges,
        })
    }
}

/// Per element of `mesh`, whether an edge of it belongs to no other element; and those edges
/// (corner, midside, corner).
fn boundary(mesh: &Mesh) -> (Vec<bool>, Vec<[usize; 3]>) {
    // Edge k of a six-node triangle: corners k and k + 1, midside 3 + k.
    let edge = |e: &[usize; 6], k: usize| [e[k], e[3 + k], e[(k + 1) % 3]];
    let key = |e: &[usize; 3]| (e[0].min(e[2]), e[0].max(e[2]));
    let mut count = std::collections::HashMap::new();
    for e in &mesh.elements {
        for k in 0..3 {
            *count.entry(key(&edge(e, k))).or_insert(0usize) += 1;
        }
    }
    let alone = |e: &[usize; 3]| count[&key(e)] == 1;
    let on_boundary = mesh
        .elements
        .iter()
        .map(|e| (0..3).any(|k| alone(&edge(e, k))))
        .collect();
    let edges = mesh
        .elements
        .iter()
        .flat_map(|e| (0..3).map(move |k| edge(e, k)))
        .filter(|e| alone(e))
        .collect();
    (on_boundary, edges)
}

fn element_maps(mesh: &Mesh) -> Vec<QuadraticMap> {
    (0..mesh.elements.len())
        .map(|e| QuadraticMap::of(&mesh.element_nodes_mm(e)))
        .collect()
}

/// A solved state of the specimen as the camera sees it.
#[derive(Clone, Debug)]
pub struct FieldMotion {
    reference: Arc<ReferenceMesh>,
    /// The element grid and maps of the deformed mesh (nodes at Xᵢ + uᵢ), and its outline in
    /// the image.
    current_grid: ElementGrid,
    current_maps: Vec<QuadraticMap>,
    outline: Outline,
    /// Nodal displacements, two per node, mm.
    u_mm: Vec<f64>,
    view: View,
}

/// Where a pixel of a row was found, to start the next pixel from.
pub type RowHint = Option<Location>;

impl FieldMotion {
    /// The state of nodal displacements `u_mm` (two per node, mm) of `reference`, seen
    /// through `view`. Refused: a length that is not two per node, a value that is not finite,
    /// a scale that is not positive, an element the displacement turns inside out.
    pub fn new(
        reference: Arc<ReferenceMesh>,
        u_mm: Vec<f64>,
        view: View,
    ) -> Result<FieldMotion, ProducerError> {
        let invalid = |name: &str, value: String, expected: &str| ProducerError::InvalidParameter {
            name: name.to_owned(),
            value,
            expected: expected.to_owned(),
        };
        let nodes = reference.mesh.nodes_mm.len();
        if u_mm.len() != 2 * nodes {
            return Err(invalid(
                "specimen displacements",
                format!("{} values", u_mm.len()),
                &format!("two per node of the mesh ({} values)", 2 * nodes),
            ));
        }
        if let Some(i) = u_mm.iter().position(|u| !u.is_finite()) {
            return Err(invalid(
                "specimen displacement",
                format!("{} at node {}", u_mm[i], i / 2),
                "a finite number of mm",
            ));
        }
        let finite = |v: Vec2| v[0].is_finite() && v[1].is_finite();
        if !(view.mm_per_px.is_finite()
            && view.mm_per_px > 0.0
            && finite(view.centre_px)
            && finite(view.centre_mm))
        {
            return Err(invalid(
                "camera view",
                format!("{view:?}"),
                "a positive finite mm per px and finite centres",
            ));
        }
        let current = Mesh {
            nodes_mm: reference
                .mesh
                .nodes_mm
                .iter()
                .enumerate()
                .map(|(n, x)| [x[0] + u_mm[2 * n], x[1] + u_mm[2 * n + 1]])
                .collect(),
            elements: reference.mesh.elements.clone(),
        };
        if let Err(membrane::GeometryError::InvertedElement { element, .. }) =
            current.gauss_points()
        {
            return Err(invalid(
                "specimen displacements",
                format!("element {element} turned inside out"),
                "a state of positive Jacobian everywhere (a converged solution)",
            ));
        }
        let current_grid = ElementGrid::new(&current);
        let current_maps = element_maps(&current);
        let nodes_px: Vec<Vec2> = current.nodes_mm.iter().map(|&x| view.to_px(x)).collect();
        let outline = Outline::new(&reference.boundary_edges, &nodes_px);
        Ok(FieldMotion {
            reference,
            current_grid,
            current_maps,
            outline,
            u_mm,
            view,
        })
    }

    pub fn view(&self) -> &View {
        &self.view
    }

    /// Displacement u(X) = φ(X) − X at the reference image point `p_px`, px; None off the
    /// specimen. The frame's ground truth.
    pub fn displacement_px(&self, p_px: Vec2) -> Option<Vec2> {
        let u = self.sample(p_px)?.displacement_mm;
        Some([u[0] / self.view.mm_per_px, u[1] / self.view.mm_per_px])
    }

    /// x = φ(X), px; None off the specimen.
    pub fn forward(&self, p_px: Vec2) -> Option<Vec2> {
        let u = self.displacement_px(p_px)?;
        Some([p_px[0] + u[0], p_px[1] + u[1]])
    }

    /// F(X) = ∂φ/∂X at the reference image point `p_px` (the same in px as in mm); None off the
    /// specimen.
    pub fn gradient(&self, p_px: Vec2) -> Option<Mat2> {
        Some(self.sample(p_px)?.f)
    }

    /// The field at the reference image point `p_px` (located by the mesh's own shape
    /// functions, to the truth's precision); None off the specimen.
    fn sample(&self, p_px: Vec2) -> Option<PointSample> {
        let reference = &self.reference;
        let location = reference
            .grid
            .locate(&reference.mesh, self.view.to_mm(p_px))?;
        sample_at(&reference.mesh, &self.u_mm, location)
    }

    /// X = φ⁻¹(x), px; None where the image point `x_px` shows no material.
    pub fn inverse(&self, x_px: Vec2) -> Option<Vec2> {
        self.inverse_along_row(x_px, &mut None)
    }

    /// [`Self::inverse`] starting from `hint`, where the previous pixel of the row was found;
    /// updates `hint` (None off the specimen).
    #[inline]
    pub fn inverse_along_row(&self, x_px: Vec2, hint: &mut RowHint) -> Option<Vec2> {
        let l = self.locate_current(x_px, [*hint, None], hint)?;
        Some(
            self.view
                .to_px(self.reference.maps[l.element].at(l.xi, l.eta)),
        )
    }

    /// X = φ⁻¹(x) with its gradient ∂X/∂x = F⁻¹ there (what a renderer interpolates between
    /// two exact points of a row), from `hint` like [`Self::inverse_along_row`].
    pub fn inverse_point(&self, x_px: Vec2, hint: &mut RowHint) -> Option<InversePoint> {
        self.inverse_point_from(x_px, [*hint, None], hint)
    }

    /// [`Self::inverse_point`] trying the elements of `hints` in turn before the element grid
    /// (a point between two of a row's points in different elements is in one of the two, as
    /// a rule); `found` is where it was found.
    fn inverse_point_from(
        &self,
        x_px: Vec2,
        hints: [RowHint; 2],
        found: &mut RowHint,
    ) -> Option<InversePoint> {
        let l = self.locate_current(x_px, hints, found)?;
        let reference = &self.reference.maps[l.element];
        // J = ∂(position)/∂(ξ, η) in both configurations; ∂X/∂x = J_reference J_current⁻¹.
        let j_cur_inverse = inverse(&self.current_maps[l.element].jacobian(l.xi, l.eta));
        Some(InversePoint {
            reference_px: self.view.to_px(reference.at(l.xi, l.eta)),
            gradient: mul_mat(&reference.jacobian(l.xi, l.eta), &j_cur_inverse),
            location: l,
            natural_per_px: [
                j_cur_inverse[0][0] * self.view.mm_per_px,
                j_cur_inverse[1][0] * self.view.mm_per_px,
            ],
        })
    }

    /// Whether any element of the deformed mesh comes near the pixels `from_col..=to_col` of
    /// row `y_px` (when not, they all show the backdrop).
    fn material_near(&self, from_col: usize, to_col: usize, y_px: f64) -> bool {
        let a = self.view.to_mm([from_col as f64, y_px]);
        let b = self.view.to_mm([to_col as f64, y_px]);
        self.current_grid.any_element_meets(
            [a[0].min(b[0]), a[1].min(b[1])],
            [a[0].max(b[0]), a[1].max(b[1])],
        )
    }

    /// Where `x_px` is in the deformed mesh: Newton in the elements of `hints` from their
    /// natural coordinates, in turn, else through the element grid; `found` is where.
    #[inline]
    fn locate_current(
        &self,
        x_px: Vec2,
        hints: [RowHint; 2],
        found: &mut RowHint,
    ) -> Option<Location> {
        let x_mm = self.view.to_mm(x_px);
        let in_element = |element: usize, start: (f64, f64)| {
            let (xi, eta) = self.current_maps[element].natural(x_mm, start)?;
            Some(Location { element, xi, eta })
        };
        let second = hints[1].filter(|h| hints[0].is_none_or(|f| f.element != h.element));
        let location = hints[0]
            .and_then(|h| in_element(h.element, (h.xi, h.eta)))
            .or_else(|| second.and_then(|h| in_element(h.element, (h.xi, h.eta))))
            .or_else(|| {
                self.current_grid
                    .candidates(x_mm)
                    .find_map(|e| in_element(e, (1.0 / 3.0, 1.0 / 3.0)))
            });
        *found = location;
        location
    }
}

/// The cubic Hermite basis (h00, h10, h01, h11) at `t`.
const fn hermite_basis(t: f64) -> [f64; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [
        2.0 * t3 - 3.0 * t2 + 1.0,
        t3 - 2.0 * t2 + t,
        -2.0 * t3 + 3.0 * t2,
        t3 - t2,
    ]
}

/// [`hermite_basis`] at the pixels of a whole block, k / [`BLOCK_SPAN_PX`].
const BLOCK_BASIS: [[f64; 4]; BLOCK_SPAN_PX] = {
    let mut table = [[0.0; 4]; BLOCK_SPAN_PX];
    let mut k = 0;
    while k < BLOCK_SPAN_PX {
        table[k] = hermite_basis(k as f64 / BLOCK_SPAN_PX as f64);
        k += 1;
    }
    table
};

/// X from the Hermite basis `h` between `a` and `b`, `span_px` apart.
#[inline(always)]
fn hermite_with(a: &InversePoint, b: &InversePoint, span_px: f64, h: &[f64; 4]) -> Vec2 {
    let at = |i: usize| {
        h[0] * a.reference_px[i]
            + h[1] * span_px * a.gradient[i][0]
            + h[2] * b.reference_px[i]
            + h[3] * span_px * b.gradient[i][0]
    };
    [at(0), at(1)]
}

/// X at `t` ∈ [0, 1] of the way from `a` to `b`, two points `span_px` apart along a row: the
/// cubic Hermite interpolation of X from X and ∂X/∂x at both ends (within 1e-3 px inside one
/// element at the span the renderer uses, 3e-4 px on a cruciform stretched 1.5: see the tests;
/// never across an element's edge, where F jumps: 0.13 px there at worst on that cruciform).
#[inline(always)]
pub fn hermite_along_row(a: &InversePoint, b: &InversePoint, span_px: f64, t: f64) -> Vec2 {
    hermite_with(a, b, span_px, &hermite_basis(t))
}

/// Walks a row of pixels in blocks of [`BLOCK_SPAN_PX`], giving each pixel's X = φ⁻¹(x)
/// (None: no material there). X is found exactly at both ends of a block; when both lie in the
/// same element the pixels between take [`hermite_along_row`], else the block is halved at an
/// exact point, down to single pixels (a block crossing an element edge or the specimen's edge
/// costs a few more exact points, never an interpolation across the edge).
pub struct RowWalker<'f> {
    field: &'f FieldMotion,
    y_px: f64,
    /// The exact point at the start of the next block.
    left: Option<InversePoint>,
    hint: RowHint,
    /// Where the row crosses the specimen's outline (pairs: the spans on it), when known: a
    /// point outside every span is off the specimen without locating it.
    spans: Option<&'f [f64]>,
}

impl<'f> RowWalker<'f> {
    /// The walk of row `y_px` from column 0.
    pub fn new(field: &'f FieldMotion, y_px: f64) -> Self {
        let mut hint = None;
        let left = field.inverse_point([0.0, y_px], &mut hint);
        RowWalker {
            field,
            y_px,
            left,
            hint,
            spans: None,
        }
    }

    /// Whether the columns `from_col..=to_col` may show material (all of them off every span
    /// of the outline when not; near an element's box when the spans are not known).
    fn material_near(&self, from_col: usize, to_col: usize) -> bool {
        match self.spans {
            Some(spans) => near_a_span(spans, from_col as f64, to_col as f64),
            None => self.field.material_near(from_col, to_col, self.y_px),
        }
    }

    /// The exact point of column `col` with `hint` as the Newton start; None (at once, with no
    /// search) off every span of the outline.
    fn locate(&mut self, col: usize, hints: [RowHint; 2]) -> Option<InversePoint> {
        if self
            .spans
            .is_some_and(|spans| !near_a_span(spans, col as f64, col as f64))
        {
            self.hint = None;
            return None;
        }
        self.field
            .inverse_point_from([col as f64, self.y_px], hints, &mut self.hint)
    }

    /// X of the columns `first_col`.. `first_col + BLOCK_SPAN_PX` (the block after the previous
    /// one) into `out`.
    pub fn block(&mut self, first_col: usize, out: &mut [Option<Vec2>; BLOCK_SPAN_PX]) {
        let left = self.left;
        let right = self.point(first_col + BLOCK_SPAN_PX, &left, BLOCK_SPAN_PX as f64);
        self.fill(first_col, (0, &left), (BLOCK_SPAN_PX, &right), out);
        self.left = right;
    }

    /// The exact point of column `col`, Newton started `ahead_px` ahead of `from` when there is
    /// one.
    fn point(
        &mut self,
        col: usize,
        from: &Option<InversePoint>,
        ahead_px: f64,
    ) -> Option<InversePoint> {
        let hint = match from {
            Some(p) => p.hint_ahead(ahead_px),
            None => self.hint,
        };
        self.locate(col, [hint, None])
    }

    /// Pixels k0..k1 of the block from the exact points at k0 and k1.
    fn fill(
        &mut self,
        first_col: usize,
        (k0, a): (usize, &Option<InversePoint>),
        (k1, c): (usize, &Option<InversePoint>),
        out: &mut [Option<Vec2>; BLOCK_SPAN_PX],
    ) {
        match (a, c) {
            (Some(pa), Some(pc)) if pa.location.element == pc.location.element => {
                if k1 - k0 == BLOCK_SPAN_PX {
                    for (x, h) in out.iter_mut().zip(&BLOCK_BASIS) {
                        *x = Some(hermite_with(pa, pc, BLOCK_SPAN_PX as f64, h));
                    }
                } else {
                    let span = (k1 - k0) as f64;
                    for (k, x) in out.iter_mut().enumerate().take(k1).skip(k0) {
                        *x = Some(hermite_along_row(pa, pc, span, (k - k0) as f64 / span));
                    }
                }
            }
            _ if k1 - k0 == 1 => out[k0] = a.map(|p| p.reference_px),
            // Both ends off the specimen and no element near the segment between them: all
            // of it shows the backdrop.
            (None, None) if !self.material_near(first_col + k0, first_col + k1) => {
                out[k0..k1].fill(None);
            }
            _ => {
                let mid = (k0 + k1) / 2;
                // From both ends, the element of the one whose prediction lands inside its
                // element first.
                let from_a = a.and_then(|p| p.hint_ahead((mid - k0) as f64));
                let from_c = c.and_then(|p| p.hint_ahead(-((k1 - mid) as f64)));
                let hints = match from_a {
                    None => [from_c, None],
                    Some(h)
                        if outside_by(&h) <= from_c.map_or(f64::INFINITY, |h| outside_by(&h)) =>
                    {
                        [from_a, from_c]
                    }
                    _ => [from_c, from_a],
                };
                let m = self.locate(first_col + mid, hints);
                self.fill(first_col, (k0, a), (mid, &m), out);
                self.fill(first_col, (mid, &m), (k1, c), out);
            }
        }
    }
}

/// How far natural coordinates are outside their triangle (≤ 0 inside).
fn outside_by(l: &Location) -> f64 {
    (-l.xi).max(-l.eta).max(l.xi + l.eta - 1.0)
}

/// An image point's reference point and the inverse map's gradient there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InversePoint {
    /// X = φ⁻¹(x), px.
    pub reference_px: Vec2,
    /// ∂X/∂x = F⁻¹, row-major.
    pub gradient: Mat2,
    /// Where x lies in the deformed mesh (the same element and (ξ, η) as X in the reference).
    pub location: Location,
    /// ∂(ξ, η)/∂x along the row, per px: where to start looking for a point further along.
    pub natural_per_px: [f64; 2],
}

impl InversePoint {
    /// The hint for the point `step_px` further along the row: this element, at the natural
    /// coordinates predicted to first order.
    pub fn hint_ahead(&self, step_px: f64) -> RowHint {
        Some(Location {
            element: self.location.element,
            xi: self.location.xi + step_px * self.natural_per_px[0],
            eta: self.location.eta + step_px * self.natural_per_px[1],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use membrane::specimens::cruciform::CruciformGeometry;

    /// The default cruciform (100 mm arms, 20 mm fillets) seen at 0.2 mm/px, its centre at the
    /// image point (100, 80).
    fn cruciform() -> Arc<ReferenceMesh> {
        ReferenceMesh::new(CruciformGeometry::default().mesh().unwrap().mesh)
    }

    fn view() -> View {
        View {
            mm_per_px: 0.2,
            centre_px: [100.0, 80.0],
            centre_mm: [0.0, 0.0],
        }
    }

    /// A smooth heterogeneous field: u = (0.08 X + 4e-4 X Y + 2e-5 Y³, -0.03 Y + 3e-4 X²) mm.
    fn smooth(x: [f64; 2]) -> [f64; 2] {
        [
            0.08 * x[0] + 4e-4 * x[0] * x[1] + 2e-5 * x[1].powi(3),
            -0.03 * x[1] + 3e-4 * x[0] * x[0],
        ]
    }

    fn field(reference: &Arc<ReferenceMesh>, f: impl Fn([f64; 2]) -> [f64; 2]) -> FieldMotion {
        let u = reference.mesh.nodes_mm.iter().flat_map(|&x| f(x)).collect();
        FieldMotion::new(reference.clone(), u, view()).unwrap()
    }

    #[test]
    fn the_inverse_of_the_forward_map_is_exact_and_off_the_specimen_is_nothing() {
        let reference = cruciform();
        let motion = field(&reference, smooth);
        let mut checked = 0;
        for y in (0..160).step_by(3) {
            for x in (0..200).step_by(3) {
                let p = [x as f64 + 0.3, y as f64 - 0.2];
                let Some(x_px) = motion.forward(p) else {
                    continue;
                };
                let back = motion
                    .inverse(x_px)
                    .expect("a material point's image is material");
                assert!(
                    (back[0] - p[0]).abs() < 1e-8 && (back[1] - p[1]).abs() < 1e-8,
                    "{p:?} → {x_px:?} → {back:?}"
                );
                checked += 1;
            }
        }
        assert!(checked > 2000, "{checked}");
        // The corner between the +x and +y arms, far from both, is no material before or after.
        let corner_px = view().to_px([95.0, 95.0]);
        assert!(motion.displacement_px(corner_px).is_none());
        assert!(motion.inverse(corner_px).is_none());
    }

    #[test]
    fn a_homogeneous_field_is_its_affine_map_anywhere() {
        let reference = cruciform();
        let f = [[1.25, 0.05], [-0.02, 0.9]];
        let motion = field(&reference, |x| {
            [
                (f[0][0] - 1.0) * x[0] + f[0][1] * x[1] + 0.3,
                f[1][0] * x[0] + (f[1][1] - 1.0) * x[1] - 0.1,
            ]
        });
        for p in [[100.0, 80.0], [37.5, 121.25], [180.0, 90.0], [100.0, 20.0]] {
            let x_mm = view().to_mm(p);
            let want = [
                (f[0][0] - 1.0) * x_mm[0] + f[0][1] * x_mm[1] + 0.3,
                f[1][0] * x_mm[0] + (f[1][1] - 1.0) * x_mm[1] - 0.1,
            ];
            let u = motion.displacement_px(p).unwrap();
            for i in 0..2 {
                assert!((u[i] - want[i] / 0.2).abs() < 1e-9, "{p:?}: {u:?}");
            }
            let g = motion.gradient(p).unwrap();
            for i in 0..2 {
                for j in 0..2 {
                    assert!((g[i][j] - f[i][j]).abs() < 1e-9, "{p:?}: {g:?}");
                }
            }
        }
    }

    #[test]
    fn a_row_walked_with_hints_is_the_inverse_located_from_scratch() {
        let reference = cruciform();
        let motion = field(&reference, smooth);
        for y in (0..160).step_by(11) {
            let mut hint = None;
            for x in 0..200 {
                let x_px = [x as f64, y as f64];
                let walked = motion.inverse_along_row(x_px, &mut hint);
                let direct = motion.inverse(x_px);
                match (walked, direct) {
                    (Some(a), Some(b)) => assert!(
                        (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9,
                        "{x_px:?}: {a:?} against {b:?}"
                    ),
                    (None, None) => {}
                    other => panic!("{x_px:?}: {other:?}"),
                }
            }
        }
    }

    /// ∂X/∂x at an image point is the inverse of F at its reference point.
    #[test]
    fn the_inverse_gradient_is_the_inverse_of_f() {
        let reference = cruciform();
        let motion = field(&reference, smooth);
        for x_px in [[100.0, 80.0], [150.3, 77.7], [60.0, 120.5], [20.0, 80.0]] {
            let point = motion.inverse_point(x_px, &mut None).unwrap();
            let f = motion.gradient(point.reference_px).unwrap();
            let product = mul_mat(&f, &point.gradient);
            for (i, row) in product.iter().enumerate() {
                for (j, v) in row.iter().enumerate() {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((v - want).abs() < 1e-9, "{x_px:?}: {product:?}");
                }
            }
        }
    }

    /// The default cruciform solved at an equibiaxial grip stretch of 1.5 (Smactane™): its
    /// reference mesh and nodal displacements, mm.
    pub(super) fn stretched_cruciform() -> (Arc<ReferenceMesh>, Vec<f64>) {
        let specimen = CruciformGeometry::default().mesh().unwrap();
        let law = material::InvariantLaw::smactane();
        let solved = specimen
            .solve_at(&law, membrane::GripStretch { x: 1.5, y: 1.5 })
            .unwrap();
        (ReferenceMesh::new(specimen.mesh), solved.displacement_mm)
    }

    /// How far the Hermite interpolation between exact points `span` px apart in one element is
    /// from the exact inverse, on a solved cruciform (equibiaxial grip stretch 1.5, the fillets'
    /// strain concentrations in view at 0.16 mm/px, as the default camera sees it).
    #[test]
    fn hermite_between_exact_points_of_one_element_is_within_1e_3_px() {
        let (reference, displacement_mm) = stretched_cruciform();
        let view = View {
            mm_per_px: 0.16,
            centre_px: [511.5, 511.5],
            centre_mm: [0.0, 0.0],
        };
        let motion = FieldMotion::new(reference, displacement_mm, view).unwrap();
        for span in [8usize, 16] {
            let mut worst = 0.0f64;
            for y in (0..1024).step_by(37) {
                let y = y as f64;
                for start in (0..1024 - span).step_by(span) {
                    let a = motion.inverse_point([start as f64, y], &mut None);
                    let b = motion.inverse_point([(start + span) as f64, y], &mut None);
                    let (Some(a), Some(b)) = (a, b) else { continue };
                    if a.location.element != b.location.element {
                        continue;
                    }
                    for k in 1..span {
                        let got = hermite_along_row(&a, &b, span as f64, k as f64 / span as f64);
                        let want = motion.inverse([(start + k) as f64, y]).unwrap();
                        worst = worst
                            .max((got[0] - want[0]).abs())
                            .max((got[1] - want[1]).abs());
                    }
                }
            }
            eprintln!("Hermite over {span} px: worst {worst:.2e} px");
            // Half the fast renderer's own bound against the exact one (2 millipixels).
            if span == BLOCK_SPAN_PX {
                assert!(worst < 1e-3, "{worst} px");
            }
        }
    }

    #[test]
    fn bad_states_are_refused_with_the_reason() {
        let reference = cruciform();
        let n = reference.mesh.nodes_mm.len();
        let short = FieldMotion::new(reference.clone(), vec![0.0; 2 * n - 1], view());
        assert!(short.unwrap_err().to_string().contains("two per node"));
        let mut nan = vec![0.0; 2 * n];
        nan[7] = f64::NAN;
        let err = FieldMotion::new(reference.clone(), nan, view()).unwrap_err();
        assert!(err.to_string().contains("node 3"), "{err}");
        // Folding the sheet over itself along x: x ↦ −x turns every element inside out.
        let folded: Vec<f64> = reference
            .mesh
            .nodes_mm
            .iter()
            .flat_map(|x| [-2.0 * x[0], 0.0])
            .collect();
        let err = FieldMotion::new(reference.clone(), folded, view()).unwrap_err();
        assert!(err.to_string().contains("inside out"), "{err}");
        let bad_view = View {
            mm_per_px: 0.0,
            ..view()
        };
        assert!(FieldMotion::new(reference, vec![0.0; 2 * n], bad_view).is_err());
    }
}
