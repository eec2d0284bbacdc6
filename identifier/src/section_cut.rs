//! The paper's section cut as a virtual field (section 4.c): u* = (ramp from 0 to 1 along an
//! arm's axis, across a band that crosses the arm) e_axis. Its internal virtual work,
//! h0 ∫ P : ∇u* dA0 = h0/L ∫_band P_aa dA0 (L the band's length along the axis), equals the
//! external work of the force through the arm, which in equilibrium is that arm's grip force:
//! one equation per arm and frame that needs no traction on the field of view's edges.
//!
//! Quadrature: the nodes of the measured field lie on a regular grid of step s (mm, reference
//! configuration); each node stands for the s x s square around it, and its weight is the
//! area of that square inside the band times the band (exact for a field constant over each
//! node's square, second order for a smooth one). A node without a measurement (lost, refused)
//! inside the band is filled from the nearest measured nodes of its grid column across the
//! arm when the hole is at most [`MAX_FILLED_HOLE_NODES`] nodes long (linear interpolation of
//! F, counted); a longer hole, or one at the band's edge across the arm, drops the cut for the
//! frame: a cut with a hole is never integrated as if whole.

use crate::field_stress::{Mat2, NodeStressError};
use crate::models::Model;
use crate::virtual_work::{work_n, WeightedNode};

/// Longest run of missing nodes across the arm that is filled by interpolation.
pub const MAX_FILLED_HOLE_NODES: usize = 2;

/// A measured field on the reference grid: node (col, row) at (x0 + col s, y0 + row s) mm.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldGrid {
    pub cols: usize,
    pub rows: usize,
    pub x0_mm: f64,
    pub y0_mm: f64,
    pub step_mm: f64,
    /// Row-major in-plane deformation gradients, `None` where the node has no measurement.
    pub gradients: Vec<Option<Mat2>>,
}

/// Which reference axis the arm (and the ramp of u*) runs along.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArmAxis {
    X,
    Y,
}

/// A band across an arm: u* rises from 0 at `from_mm` to 1 at `to_mm` along the axis; the arm
/// spans `[across_from_mm, across_to_mm]` in the other coordinate (its whole width).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SectionCut {
    pub axis: ArmAxis,
    pub from_mm: f64,
    pub to_mm: f64,
    pub across_from_mm: f64,
    pub across_to_mm: f64,
}

/// The force through a cut, and how it was obtained.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutForce {
    /// Force along the arm's axis through the cut, N (MPa · mm²).
    pub force_n: f64,
    /// Nodes with a weight in the band, and those of them filled by interpolation.
    pub nodes: usize,
    pub filled: usize,
}

/// Why a cut gives no force for a frame.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CutError {
    #[error("cut {cut:?}: its band holds no node of the field")]
    Empty { cut: SectionCut },
    #[error("cut {cut:?}: band of length {length_mm} mm or width {width_mm} mm, expected > 0")]
    Degenerate {
        cut: SectionCut,
        length_mm: f64,
        width_mm: f64,
    },
    #[error(
        "cut {cut:?}: {missing} missing nodes in a row across the arm at node (col {col}, row \
         {row}) (at most {MAX_FILLED_HOLE_NODES} are filled, none at the band's edge)"
    )]
    Hole {
        cut: SectionCut,
        col: usize,
        row: usize,
        missing: usize,
    },
    #[error("cut {cut:?}, node (col {col}, row {row}): {reason}")]
    Stress {
        cut: SectionCut,
        col: usize,
        row: usize,
        reason: NodeStressError,
    },
}

/// Length of [a, b] ∩ [lo, hi].
fn overlap(a: f64, b: f64, lo: f64, hi: f64) -> f64 {
    (b.min(hi) - a.max(lo)).max(0.0)
}

impl FieldGrid {
    fn at(&self, col: usize, row: usize) -> Option<Mat2> {
        self.gradients[row * self.cols + col]
    }

    /// Node (along, across) in the cut's frame → (col, row).
    fn index(axis: ArmAxis, along: usize, across: usize) -> (usize, usize) {
        match axis {
            ArmAxis::X => (along, across),
            ArmAxis::Y => (across, along),
        }
    }

    /// The coordinate of node `k` along and across the axis, and the counts.
    fn frame(&self, axis: ArmAxis) -> ((f64, usize), (f64, usize)) {
        match axis {
            ArmAxis::X => ((self.x0_mm, self.cols), (self.y0_mm, self.rows)),
            ArmAxis::Y => ((self.y0_mm, self.rows), (self.x0_mm, self.cols)),
        }
    }

    /// F at node (along, across), filled from its line across the arm when missing.
    fn gradient_or_filled(
        &self,
        cut: &SectionCut,
        along: usize,
        across: usize,
        across_range: (usize, usize),
    ) -> Result<(Mat2, bool), CutError> {
        let get = |k: usize| {
            let (col, row) = Self::index(cut.axis, along, k);
            self.at(col, row)
        };
        if let Some(f) = get(across) {
            return Ok((f, false));
        }
        let (col, row) = Self::index(cut.axis, along, across);
        let before = (across_range.0..across).rev().find(|&k| get(k).is_some());
        let after = (across + 1..across_range.1).find(|&k| get(k).is_some());
        let (Some(b), Some(a)) = (before, after) else {
            return Err(CutError::Hole {
                cut: *cut,
                col,
                row,
                missing: across - before.map_or(across_range.0, |b| b + 1) + 1,
            });
        };
        if a - b - 1 > MAX_FILLED_HOLE_NODES {
            return Err(CutError::Hole {
                cut: *cut,
                col,
                row,
                missing: a - b - 1,
            });
        }
        let (fb, fa) = (get(b).expect("measured"), get(a).expect("measured"));
        let t = (across - b) as f64 / (a - b) as f64;
        let f =
            std::array::from_fn(|i| std::array::from_fn(|j| fb[i][j] + t * (fa[i][j] - fb[i][j])));
        Ok((f, true))
    }
}

/// The weighted nodes of `cut` over the measured field `grid` (holes filled or refused), and
/// how many of them were filled.
pub fn cut_weights(
    grid: &FieldGrid,
    cut: &SectionCut,
) -> Result<(Vec<WeightedNode>, usize), CutError> {
    let length_mm = cut.to_mm - cut.from_mm;
    let width_mm = cut.across_to_mm - cut.across_from_mm;
    if !(length_mm > 0.0 && width_mm > 0.0) {
        return Err(CutError::Degenerate {
            cut: *cut,
            length_mm,
            width_mm,
        });
    }
    let s = grid.step_mm;
    let ((along0, along_n), (across0, across_n)) = grid.frame(cut.axis);
    let weight = |origin: f64, k: usize, lo: f64, hi: f64| {
        let centre = origin + k as f64 * s;
        overlap(centre - 0.5 * s, centre + 0.5 * s, lo, hi)
    };
    let in_band = |origin: f64, n: usize, lo: f64, hi: f64| -> Vec<(usize, f64)> {
        (0..n)
            .map(|k| (k, weight(origin, k, lo, hi)))
            .filter(|(_, w)| *w > 0.0)
            .collect()
    };
    let along = in_band(along0, along_n, cut.from_mm, cut.to_mm);
    let across = in_band(across0, across_n, cut.across_from_mm, cut.across_to_mm);
    let (Some(first), Some(last)) = (across.first(), across.last()) else {
        return Err(CutError::Empty { cut: *cut });
    };
    let across_range = (first.0, last.0 + 1);
    let component = match cut.axis {
        ArmAxis::X => 0,
        ArmAxis::Y => 1,
    };
    let mut nodes = vec![];
    let mut filled = 0;
    for &(a, w_along) in &along {
        for &(c, w_across) in &across {
            let (gradient, was_filled) = grid.gradient_or_filled(cut, a, c, across_range)?;
            // ∂u*_a/∂X_a = 1/L over the band.
            let mut weight_mm2 = [[0.0; 2]; 2];
            weight_mm2[component][component] = w_along * w_across / length_mm;
            nodes.push(WeightedNode {
                at: FieldGrid::index(cut.axis, a, c),
                filled: was_filled,
                gradient,
                weight_mm2,
            });
            filled += usize::from(was_filled);
        }
    }
    if nodes.is_empty() {
        return Err(CutError::Empty { cut: *cut });
    }
    Ok((nodes, filled))
}

/// The force through `cut` of a sheet of reference thickness `thickness_mm` whose measured
/// field is `grid`, under `model` with parameters `p` (MPa).
pub fn cut_force(
    grid: &FieldGrid,
    cut: &SectionCut,
    model: &Model,
    p: &[f64],
    thickness_mm: f64,
) -> Result<CutForce, CutError> {
    let (nodes, filled) = cut_weights(grid, cut)?;
    let force_n = work_n(&nodes, model, p, thickness_mm).map_err(|failure| CutError::Stress {
        cut: *cut,
        col: failure.at.0,
        row: failure.at.1,
        reason: failure.reason,
    })?;
    Ok(CutForce {
        force_n,
        nodes: nodes.len(),
        filled,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::LoadCase;

    const STEP_MM: f64 = 0.5;

    /// A strip along x, 20 mm wide (41 rows at 0.5 mm centred on y = 0), 30 mm long.
    fn strip(f: impl Fn(f64, f64) -> Option<Mat2>) -> FieldGrid {
        let (cols, rows) = (61, 41);
        let (x0, y0) = (0.0, -10.0);
        let gradients = (0..rows)
            .flat_map(|r| (0..cols).map(move |c| (c, r)))
            .map(|(c, r)| f(x0 + c as f64 * STEP_MM, y0 + r as f64 * STEP_MM))
            .collect();
        FieldGrid {
            cols,
            rows,
            x0_mm: x0,
            y0_mm: y0,
            step_mm: STEP_MM,
            gradients,
        }
    }

    fn uniaxial(stretch: f64) -> Mat2 {
        let (l1, l2) = LoadCase::Uniaxial.in_plane_stretches(stretch);
        [[l1, 0.0], [0.0, l2]]
    }

    /// The whole width of the strip, from the edge of its first row's square to the last's.
    fn cut(from_mm: f64, to_mm: f64) -> SectionCut {
        SectionCut {
            axis: ArmAxis::X,
            from_mm,
            to_mm,
            across_from_mm: -10.25,
            across_to_mm: 10.25,
        }
    }

    #[test]
    fn a_homogeneous_strip_gives_its_nominal_stress_times_its_section() {
        let (model, p, h0) = (Model::Mooney, [0.3, 0.05], 2.0);
        let f = uniaxial(1.8);
        let grid = strip(|_, _| Some(f));
        let expected = model
            .nominal_stress_mpa(&p, LoadCase::Uniaxial, 1.8)
            .unwrap()
            * 20.5
            * h0;
        // A band aligned with the nodes' squares and one that cuts through them.
        for (from, to) in [(9.75, 15.25), (10.1, 13.37)] {
            let force = cut_force(&grid, &cut(from, to), &model, &p, h0).unwrap();
            assert!(
                (force.force_n - expected).abs() < 1e-9 * expected,
                "{force:?} vs {expected}"
            );
            assert_eq!(force.filled, 0);
        }
    }

    #[test]
    fn a_field_varying_along_the_arm_gives_the_band_average() {
        let (model, p, h0) = (Model::NeoHookean, [0.4], 1.5);
        let stretch_at = |x: f64| 1.5 + 0.02 * x;
        let grid = strip(|x, _| Some(uniaxial(stretch_at(x))));
        let band = cut(9.75, 12.25);
        let force = cut_force(&grid, &band, &model, &p, h0).unwrap();
        // Five node columns (x = 10 … 12) of weight 0.5 mm each over a 2.5 mm band.
        let mean: f64 = (20..25)
            .map(|c| {
                let x = c as f64 * STEP_MM;
                model
                    .nominal_stress_mpa(&p, LoadCase::Uniaxial, stretch_at(x))
                    .unwrap()
            })
            .sum::<f64>()
            / 5.0;
        let expected = mean * 20.5 * h0;
        assert!((force.force_n - expected).abs() < 1e-9 * expected);
        assert_eq!(force.nodes, 5 * 41);
    }

    #[test]
    fn small_holes_are_filled_and_counted_large_ones_drop_the_cut() {
        let (model, p, h0) = (Model::NeoHookean, [0.4], 2.0);
        let f = uniaxial(1.4);
        let whole = cut_force(&strip(|_, _| Some(f)), &cut(9.75, 12.25), &model, &p, h0).unwrap();
        let small_hole =
            strip(|x, y| (!((10.9..11.1).contains(&x) && (-0.6..0.1).contains(&y))).then_some(f));
        let filled = cut_force(&small_hole, &cut(9.75, 12.25), &model, &p, h0).unwrap();
        assert_eq!(filled.filled, 2);
        assert!((filled.force_n - whole.force_n).abs() < 1e-9 * whole.force_n);
        let large_hole = strip(|x, y| (!((10.9..11.1).contains(&x) && y.abs() < 3.0)).then_some(f));
        let error = cut_force(&large_hole, &cut(9.75, 12.25), &model, &p, h0).unwrap_err();
        assert!(
            matches!(error, CutError::Hole { missing: 11, .. }),
            "{error}"
        );
        let edge_hole = strip(|x, y| (!((10.9..11.1).contains(&x) && y < -9.9)).then_some(f));
        assert!(matches!(
            cut_force(&edge_hole, &cut(9.75, 12.25), &model, &p, h0),
            Err(CutError::Hole { .. })
        ));
        // A band outside the field, and a degenerate one.
        assert!(matches!(
            cut_force(&whole_grid(f), &cut(100.0, 101.0), &model, &p, h0),
            Err(CutError::Empty { .. })
        ));
        assert!(matches!(
            cut_force(&whole_grid(f), &cut(12.0, 12.0), &model, &p, h0),
            Err(CutError::Degenerate { .. })
        ));
    }

    fn whole_grid(f: Mat2) -> FieldGrid {
        strip(|_, _| Some(f))
    }

    #[test]
    fn an_arm_along_y_reads_the_yy_component() {
        let (model, p, h0) = (Model::Yeoh, [0.3, -0.01, 0.002], 2.0);
        let (l1, l2) = LoadCase::Uniaxial.in_plane_stretches(2.0);
        let grid = strip(|_, _| Some([[l2, 0.0], [0.0, l1]]));
        let across_y = SectionCut {
            axis: ArmAxis::Y,
            from_mm: -2.25,
            to_mm: 2.25,
            across_from_mm: 4.75,
            across_to_mm: 15.25,
        };
        let force = cut_force(&grid, &across_y, &model, &p, h0).unwrap();
        let expected = model
            .nominal_stress_mpa(&p, LoadCase::Uniaxial, 2.0)
            .unwrap()
            * 10.5
            * h0;
        assert!(
            (force.force_n - expected).abs() < 1e-9 * expected,
            "{force:?}"
        );
    }
}
