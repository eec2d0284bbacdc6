//! The fast renderer's walk of X = φ⁻¹(x) over cells of [`CELL_ROWS`] rows × [`BLOCK_SPAN_PX`]
//! columns: exact points only on every [`CELL_ROWS`]-th row (the grid rows), every
//! [`BLOCK_SPAN_PX`] columns; a row between two grid rows takes its blocks' end points from the
//! cell's corners above and below, and the pixels between them as the row walk does
//! ([`super::hermite_along_row`]).
//!
//! A cell is interpolated only when its four corners lie in one element that has no edge on the
//! specimen's boundary: inside one element the inverse map is smooth (the inverse of a
//! quadratic map), so X at a block's end is the cubic Hermite of X and ∂X/∂y (= F⁻¹'s second
//! column) between the corners above and below it, and ∂X/∂x linear between them (its error
//! scaled by the span is 1e-5 px: the third derivatives of the inverse of a quadratic map are
//! tiny). Any other cell (its corners in two elements, or off the specimen, or in an element on
//! the boundary, whose curved edge might cross the cell) is walked row by row as before: exact
//! points at its blocks' ends, halved at an element's or the specimen's edge
//! ([`RowWalker`]). The tests hold the result within 1e-3 px of the exact inverse everywhere,
//! with the same pixels off the specimen as the row walk.

use super::{hermite_basis, FieldMotion, InversePoint, RowHint, RowWalker, BLOCK_SPAN_PX};
use crate::motion::Vec2;
use membrane::Location;

/// Rows from one grid row of exact points to the next (a cell's height, px).
pub const CELL_ROWS: usize = BLOCK_SPAN_PX;

/// The exact points of the grid rows around the current row of pixels, and the walk of any row
/// between them: one per thread, reused row after row (it only computes a grid row when the walk
/// reaches a new cell row).
#[derive(Debug)]
pub struct CellRows {
    /// The grid row at or above the current row, and the one below it: the exact points at
    /// columns 0, [`BLOCK_SPAN_PX`], 2 [`BLOCK_SPAN_PX`]… (one more than the blocks of a row).
    top: Vec<Option<InversePoint>>,
    bottom: Vec<Option<InversePoint>>,
    /// Which cell row `top` and `bottom` bound (image row `index * CELL_ROWS` is `top`).
    cell_row: Option<usize>,
    blocks: usize,
    /// Where the current row crosses the specimen's outline.
    crossings: Vec<f64>,
}

impl CellRows {
    /// The walk of rows `width_px` pixels wide.
    pub fn new(width_px: usize) -> CellRows {
        let blocks = width_px.div_ceil(BLOCK_SPAN_PX);
        CellRows {
            top: vec![None; blocks + 1],
            bottom: vec![None; blocks + 1],
            cell_row: None,
            blocks,
            crossings: Vec::new(),
        }
    }

    /// X of every pixel of row `y` of `field`, block by block: `each(first_col, points)`
    /// (None: no material there; a last block past the row's end gives X beyond it too).
    #[inline]
    pub fn walk_row(
        &mut self,
        field: &FieldMotion,
        y: usize,
        mut each: impl FnMut(usize, &[Option<Vec2>; BLOCK_SPAN_PX]),
    ) {
        self.move_to(field, y / CELL_ROWS);
        let below_grid = y % CELL_ROWS;
        let spans_known = field.outline.crossings(y as f64, &mut self.crossings);
        let mut walker = RowWalker {
            field,
            y_px: y as f64,
            left: None,
            hint: None,
            spans: spans_known.then_some(&self.crossings[..]),
        };
        let basis = hermite_basis(below_grid as f64 / CELL_ROWS as f64);
        let s = below_grid as f64 / CELL_ROWS as f64;
        let mut out = [None; BLOCK_SPAN_PX];
        let mut right: Option<InversePoint> = None;
        for b in 0..self.blocks {
            let first_col = b * BLOCK_SPAN_PX;
            let left = match b {
                0 => self.column_point(&mut walker, 0, &None, &basis, s),
                _ => right,
            };
            right = self.column_point(&mut walker, b + 1, &left, &basis, s);
            walker.fill(first_col, (0, &left), (BLOCK_SPAN_PX, &right), &mut out);
            each(first_col, &out);
        }
    }

    /// The point of the walker's row at grid column `k`: on a grid row, the grid's; else
    /// between the grid points above and below when both lie in one element off the boundary,
    /// exact otherwise (Newton started from the `left` block end, or from the point above).
    #[inline]
    fn column_point(
        &self,
        walker: &mut RowWalker<'_>,
        k: usize,
        left: &Option<InversePoint>,
        basis: &[f64; 4],
        s: f64,
    ) -> Option<InversePoint> {
        let (above, below) = (&self.top[k], &self.bottom[k]);
        if s == 0.0 {
            return *above;
        }
        if let (Some(a), Some(c)) = (above, below) {
            let e = a.location.element;
            if c.location.element == e && !walker.field.reference.on_boundary[e] {
                return Some(between_rows(a, c, basis, s));
            }
        }
        // The nearer of the grid points above and below first, then the other (or the
        // block's left end ahead, when the column has only one).
        let (near, far) = match s < 0.5 {
            true => (above, below),
            false => (below, above),
        };
        let ahead = left.and_then(|p| p.hint_ahead(BLOCK_SPAN_PX as f64));
        let hints = match (near, far) {
            (Some(n), Some(f)) => [Some(n.location), Some(f.location)],
            (Some(p), None) | (None, Some(p)) => [Some(p.location), ahead],
            (None, None) => [ahead, None],
        };
        walker.locate(k * BLOCK_SPAN_PX, hints)
    }

    /// Makes `top` and `bottom` the grid rows of cell row `cell_row`.
    fn move_to(&mut self, field: &FieldMotion, cell_row: usize) {
        if self.cell_row == Some(cell_row) {
            return;
        }
        if self.cell_row.map(|c| c + 1) == Some(cell_row) {
            std::mem::swap(&mut self.top, &mut self.bottom);
        } else {
            grid_row(
                field,
                cell_row * CELL_ROWS,
                &mut self.top,
                &mut self.crossings,
            );
        }
        let below = (cell_row + 1) * CELL_ROWS;
        grid_row(field, below, &mut self.bottom, &mut self.crossings);
        self.cell_row = Some(cell_row);
    }
}

/// The exact points of image row `y` at columns 0, [`BLOCK_SPAN_PX`]… into `points`, each
/// Newton started from the one before (`crossings`: scratch for the row's outline).
fn grid_row(
    field: &FieldMotion,
    y: usize,
    points: &mut [Option<InversePoint>],
    crossings: &mut Vec<f64>,
) {
    let spans_known = field.outline.crossings(y as f64, crossings);
    let mut walker = RowWalker {
        field,
        y_px: y as f64,
        left: None,
        hint: None,
        spans: spans_known.then_some(&crossings[..]),
    };
    let mut hint: RowHint = None;
    for (k, point) in points.iter_mut().enumerate() {
        *point = walker.locate(k * BLOCK_SPAN_PX, [hint, None]);
        hint = match point {
            Some(p) => p.hint_ahead(BLOCK_SPAN_PX as f64),
            None => walker.hint,
        };
    }
}

/// The point `s` of the way down from `above` to `below` (one element, [`CELL_ROWS`] apart):
/// X by the cubic Hermite of X and ∂X/∂y (`basis` = the Hermite basis at `s`), ∂X/∂x linear.
#[inline(always)]
fn between_rows(a: &InversePoint, c: &InversePoint, basis: &[f64; 4], s: f64) -> InversePoint {
    let span = CELL_ROWS as f64;
    let at = |i: usize| {
        basis[0] * a.reference_px[i]
            + basis[1] * span * a.gradient[i][1]
            + basis[2] * c.reference_px[i]
            + basis[3] * span * c.gradient[i][1]
    };
    let linear = |i: usize, j: usize| (1.0 - s) * a.gradient[i][j] + s * c.gradient[i][j];
    InversePoint {
        reference_px: [at(0), at(1)],
        gradient: [[linear(0, 0), linear(0, 1)], [linear(1, 0), linear(1, 1)]],
        location: Location {
            element: a.location.element,
            xi: (1.0 - s) * a.location.xi + s * c.location.xi,
            eta: (1.0 - s) * a.location.eta + s * c.location.eta,
        },
        natural_per_px: a.natural_per_px,
    }
}

#[cfg(test)]
mod tests {
    use super::super::View;
    use super::*;

    /// On a solved cruciform (equibiaxial grip stretch 1.5: the fillets' strain concentrations,
    /// the arms' edges and the room between them in view), seen at two scales, the cell walk of
    /// every pixel is within 1e-3 px of the exact inverse, shows the backdrop on the same pixels
    /// as the row walk, and interpolates most block ends between grid rows.
    #[test]
    fn the_cell_walk_is_within_1e_3_px_of_the_exact_inverse() {
        let (reference, displacement_mm) = super::super::tests::stretched_cruciform();
        let side = 1024usize;
        for mm_per_px in [0.16, 0.25] {
            let view = View::centred(mm_per_px, side as u32, side as u32);
            let motion =
                FieldMotion::new(reference.clone(), displacement_mm.clone(), view).unwrap();
            let mut cells = CellRows::new(side);
            let (mut worst, mut worst_rows, mut material) = (0.0f64, 0.0f64, 0usize);
            let mut apart = 0.0f64;
            let (mut interpolated, mut material_ends) = (0usize, 0usize);
            for y in 0..side {
                let mut row_walk = RowWalker::new(&motion, y as f64);
                let mut by_rows = [None; BLOCK_SPAN_PX];
                let mut blocks = Vec::new();
                cells.walk_row(&motion, y, |first_col, points| {
                    blocks.push((first_col, *points))
                });
                for (first_col, points) in blocks {
                    row_walk.block(first_col, &mut by_rows);
                    for (k, (got, rows)) in points.iter().zip(&by_rows).enumerate() {
                        let x = [(first_col + k) as f64, y as f64];
                        assert_eq!(got.is_some(), rows.is_some(), "{x:?}: {got:?} {rows:?}");
                        let Some(got) = got else { continue };
                        let want = motion.inverse(x).expect("material, as the row walk says");
                        let off = |p: &Vec2| (p[0] - want[0]).abs().max((p[1] - want[1]).abs());
                        worst = worst.max(off(got));
                        worst_rows = worst_rows.max(rows.as_ref().map_or(0.0, off));
                        if let Some(r) = rows {
                            apart = apart.max((got[0] - r[0]).abs().max((got[1] - r[1]).abs()));
                        }
                        material += 1;
                    }
                }
                if y % CELL_ROWS != 0 {
                    let interior = |k: usize| match (&cells.top[k], &cells.bottom[k]) {
                        (Some(a), Some(c)) => {
                            let e = a.location.element;
                            c.location.element == e && !motion.reference.on_boundary[e]
                        }
                        _ => false,
                    };
                    interpolated += (0..=cells.blocks).filter(|&k| interior(k)).count();
                    material_ends += (0..=cells.blocks)
                        .filter(|&k| cells.top[k].is_some() || cells.bottom[k].is_some())
                        .count();
                }
            }
            let share = interpolated as f64 / material_ends as f64;
            eprintln!(
                "cell walk at {mm_per_px} mm/px: worst {worst:.2e} px (the row walk's \
                 {worst_rows:.2e}; the two walks {apart:.1e} px apart) over {material} pixels \
                 on the specimen; between grid rows, {:.0} % of the block ends near the specimen \
                 interpolated",
                100.0 * share
            );
            assert!(worst < 1e-3, "{mm_per_px} mm/px: {worst} px");
            assert!(share > 0.5, "{mm_per_px} mm/px: {share}");
        }
    }
}
