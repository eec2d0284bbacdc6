//! A virtual field that reaches the centre of a cruciform: u* = r(X_a) w(X_b) e_a, where r
//! rises from 0 to 1 across a band along the arm's axis a (as the section cut's ramp) and w,
//! across it, is 1 over the arm's width and falls linearly to 0 before the edge of the field of
//! view. Its band may cross the central square (equibiaxial states), where a section cut cannot
//! go: the cut there would run through the other two arms, whose forces beyond the field of view
//! are unknown; w vanishes before them.
//!
//! Virtual work: h0 ∫ P : ∇u* dA0 = h0 ∫ (P_aa r'(X_a) w(X_b) + P_ab r(X_a) w'(X_b)) dA0
//! (P the nominal stress, P_ab the force along a per reference area normal to b) equals the
//! external work of the arm's grip force (u* = e_a over its grip) when u* vanishes on every other
//! loaded boundary and ∇u* vanishes where the field is not measured: w must be 1 over the whole
//! arm where it leaves the field of view, and 0 where the other arms do. Where ∇u* ≠ 0 every
//! point of the specimen must have a measurement: the caller says which points are material
//! (the specimen's outline in the reference configuration). A material node without a
//! measurement takes the nearest measured node's within [`MAX_BORROW_RINGS`] (the correlator
//! loses the nodes whose ZOI runs off the specimen's edge: about ZOI/2/step + 1 of them, and
//! F varies little across an arm's edge; counted, `RampQuadrature::borrowed`); farther, it is a
//! hole, and the field is dropped for the frame (never integrated as if the hole were empty
//! space).
//!
//! Quadrature ([`TaperedRamp::quadrature`], built once per frame): each node stands for the
//! s x s square around it (as for the section cut), and r, w being piecewise linear, the
//! integrals of r', r, w', w over the square's sides are exact: exact for a stress constant over
//! each node's square. Where the specimen's (curved) edge crosses a square, its material part is
//! sampled (midpoint rule on [`EDGE_SUBSAMPLES`]² points) and carried by the nearest measured
//! node.

use crate::models::Model;
use crate::section_cut::{ArmAxis, FieldGrid};
use crate::virtual_work::{work_n, WeightedNode};

/// u* = r(X_a) w(X_b) e_a.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaperedRamp {
    pub axis: ArmAxis,
    /// r rises from 0 at `from_mm` to 1 at `to_mm` (along a; `from_mm` < `to_mm`: the arm on
    /// the + side; mirror the coordinates for the − side with [`TaperedRamp::mirrored`]).
    pub from_mm: f64,
    pub to_mm: f64,
    /// Across (b), about `centre_mm`: w = 1 up to `flat_half_width_mm`, 0 from
    /// `zero_half_width_mm`.
    pub centre_mm: f64,
    pub flat_half_width_mm: f64,
    pub zero_half_width_mm: f64,
    /// The field on the − side of the axis: u* = −r(−X_a) w(X_b) e_a, whose work is that of
    /// the − arm's (outward) grip force.
    pub mirrored: bool,
}

/// Why the field gives no equation for a frame.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RampError {
    #[error("tapered ramp {field:?}: band {length_mm} mm long, taper {taper_mm} mm, expected > 0")]
    Degenerate {
        field: TaperedRamp,
        length_mm: f64,
        taper_mm: f64,
    },
    #[error("tapered ramp {field:?}: the material node (col {col}, row {row}) has no measurement where the field varies")]
    Hole {
        field: TaperedRamp,
        col: usize,
        row: usize,
    },
    #[error("tapered ramp {field:?}, node (col {col}, row {row}): {reason}")]
    Stress {
        field: TaperedRamp,
        col: usize,
        row: usize,
        reason: crate::field_stress::NodeStressError,
    },
}

/// The piecewise-linear function through `points` (sorted by abscissa, constant beyond the
/// ends) at `t`.
fn value(points: &[(f64, f64)], t: f64) -> f64 {
    if t <= points[0].0 {
        return points[0].1;
    }
    for pair in points.windows(2) {
        let ((t0, v0), (t1, v1)) = (pair[0], pair[1]);
        if t <= t1 {
            return v0 + (v1 - v0) * (t - t0) / (t1 - t0);
        }
    }
    points[points.len() - 1].1
}

/// The slope at `t` of the piecewise-linear function through `points` (0 beyond the ends).
fn derivative(points: &[(f64, f64)], t: f64) -> f64 {
    points
        .windows(2)
        .find(|pair| t >= pair[0].0 && t < pair[1].0)
        .map_or(0.0, |pair| {
            (pair[1].1 - pair[0].1) / (pair[1].0 - pair[0].0)
        })
}

/// ∫ over [lo, hi] of the piecewise-linear function through `points`.
fn integral(points: &[(f64, f64)], lo: f64, hi: f64) -> f64 {
    let value = |t: f64| value(points, t);
    // Trapezoids between the breakpoints inside [lo, hi]: exact for a piecewise-linear function.
    let mut cuts: Vec<f64> = std::iter::once(lo)
        .chain(points.iter().map(|p| p.0).filter(|&t| t > lo && t < hi))
        .chain(std::iter::once(hi))
        .collect();
    cuts.dedup();
    cuts.windows(2)
        .map(|w| 0.5 * (value(w[0]) + value(w[1])) * (w[1] - w[0]))
        .sum()
}

impl TaperedRamp {
    /// r along a (in the field's own coordinate, mirrored for the − side).
    fn ramp(&self) -> [(f64, f64); 2] {
        [(self.from_mm, 0.0), (self.to_mm, 1.0)]
    }

    /// w across, about the centre.
    fn taper(&self) -> [(f64, f64); 4] {
        let (c, a, b) = (
            self.centre_mm,
            self.flat_half_width_mm,
            self.zero_half_width_mm,
        );
        [(c - b, 0.0), (c - a, 1.0), (c + a, 1.0), (c + b, 0.0)]
    }

    /// The field's quadrature over the measured field `grid`; `material` says whether a
    /// reference point (mm) is on the specimen. A node square wholly on the specimen takes the
    /// exact integrals of r', r, w', w over it; a square the specimen's edge crosses is
    /// sampled at [`EDGE_SUBSAMPLES`]² points, each material one weighted by its share of the
    /// square and given the node's measurement, or its nearest measured neighbour's when the
    /// node itself lies off the specimen (material near the edge is never left out, which would
    /// be an error of the order of the node step).
    pub fn quadrature(
        &self,
        grid: &FieldGrid,
        material: &dyn Fn([f64; 2]) -> bool,
    ) -> Result<RampQuadrature, RampError> {
        let length_mm = self.to_mm - self.from_mm;
        let taper_mm = self.zero_half_width_mm - self.flat_half_width_mm;
        if !(length_mm > 0.0 && taper_mm > 0.0 && self.flat_half_width_mm >= 0.0) {
            return Err(RampError::Degenerate {
                field: *self,
                length_mm,
                taper_mm,
            });
        }
        let (ramp, taper) = (self.ramp(), self.taper());
        // ∫ f' over [lo, hi] = f(hi) − f(lo).
        let slope = |points: &[(f64, f64)], lo: f64, hi: f64| value(points, hi) - value(points, lo);
        let sign = if self.mirrored { -1.0 } else { 1.0 };
        let (a, b) = self.components();
        let s = grid.step_mm;
        let half = 0.5 * s;
        let node_at =
            |col: usize, row: usize| [grid.x0_mm + col as f64 * s, grid.y0_mm + row as f64 * s];
        let mut weights = vec![(0.0, 0.0); grid.cols * grid.rows];
        let mut borrowed = 0;
        for row in 0..grid.rows {
            for col in 0..grid.cols {
                let x = node_at(col, row);
                // The node's square in the field's coordinates (along mirrored on the − side).
                let (along, across) = (sign * x[a], x[b]);
                let (r_lo, r_hi) = (along - half, along + half);
                let (w_lo, w_hi) = (across - half, across + half);
                // Nothing varies over the square: no work there.
                if slope(&ramp, r_lo, r_hi) == 0.0 && slope(&taper, w_lo, w_hi) == 0.0 {
                    continue;
                }
                let corners = [[-half, -half], [half, -half], [-half, half], [half, half]]
                    .map(|d| material([x[0] + d[0], x[1] + d[1]]));
                let whole = corners.iter().all(|&c| c) && material(x);
                let hole = RampError::Hole {
                    field: *self,
                    col,
                    row,
                };
                // The node whose measurement the square's material takes: its own, or where
                // the correlator could not measure near the specimen's edge (a ZOI that runs
                // off it), the nearest measured node within two rings.
                let owner = nearest_measured(grid, col, row);
                if whole {
                    let Some((c, r)) = owner else {
                        return Err(hole);
                    };
                    borrowed += usize::from((c, r) != (col, row));
                    // ∫∫ ∂u*_a/∂X_a and ∫∫ ∂u*_a/∂X_b over the square (mirroring flips both
                    // u*_a and d/dX_a: the first keeps its sign, the second takes it).
                    let w = &mut weights[r * grid.cols + c];
                    w.0 += slope(&ramp, r_lo, r_hi) * integral(&taper, w_lo, w_hi);
                    w.1 += sign * integral(&ramp, r_lo, r_hi) * slope(&taper, w_lo, w_hi);
                    continue;
                }
                if !corners.iter().any(|&c| c) && !material(x) {
                    continue;
                }
                let sub = s / EDGE_SUBSAMPLES as f64;
                let (mut along_term, mut across_term) = (0.0, 0.0);
                for i in 0..EDGE_SUBSAMPLES {
                    for j in 0..EDGE_SUBSAMPLES {
                        let d = [
                            -half + (i as f64 + 0.5) * sub,
                            -half + (j as f64 + 0.5) * sub,
                        ];
                        let q = [x[0] + d[0], x[1] + d[1]];
                        if !material(q) {
                            continue;
                        }
                        // The midpoint rule: ∇u* where the material was sampled (an exact
                        // integral over the sub-square would take in u*'s variation beyond the
                        // specimen's edge).
                        let (qa, qb) = (sign * q[a], q[b]);
                        let area = sub * sub;
                        along_term += derivative(&ramp, qa) * value(&taper, qb) * area;
                        across_term += sign * value(&ramp, qa) * derivative(&taper, qb) * area;
                    }
                }
                if along_term == 0.0 && across_term == 0.0 {
                    continue;
                }
                let Some((c, r)) = owner else {
                    return Err(hole);
                };
                borrowed += usize::from((c, r) != (col, row));
                let w = &mut weights[r * grid.cols + c];
                w.0 += along_term;
                w.1 += across_term;
            }
        }
        Ok(RampQuadrature {
            field: *self,
            borrowed,
            terms: weights
                .iter()
                .enumerate()
                .filter(|(_, w)| w.0 != 0.0 || w.1 != 0.0)
                .map(|(k, &(along, across))| (k, along, across))
                .collect(),
        })
    }

    /// The force along a and the shear component of the nominal stress the field weighs.
    fn components(&self) -> (usize, usize) {
        match self.axis {
            ArmAxis::X => (0, 1),
            ArmAxis::Y => (1, 0),
        }
    }
}

/// Sub-samples per side of a node square that the specimen's edge crosses.
pub const EDGE_SUBSAMPLES: usize = 4;

/// Rings of neighbours a square may take its material's measurement from when its own node
/// has none (the correlator loses about ZOI/2/step + 1 nodes along the specimen's edge).
pub const MAX_BORROW_RINGS: isize = 2;

/// The node (col, row) itself when measured, else the nearest measured node within
/// [`MAX_BORROW_RINGS`] (by distance, then the first in scan order).
fn nearest_measured(grid: &FieldGrid, col: usize, row: usize) -> Option<(usize, usize)> {
    let measured = |c: isize, r: isize| {
        c >= 0
            && r >= 0
            && (c as usize) < grid.cols
            && (r as usize) < grid.rows
            && grid.gradients[r as usize * grid.cols + c as usize].is_some()
    };
    let (col, row) = (col as isize, row as isize);
    let rings = -MAX_BORROW_RINGS..=MAX_BORROW_RINGS;
    rings
        .clone()
        .flat_map(|dr| rings.clone().map(move |dc| (dc, dr)))
        .filter(|&(dc, dr)| measured(col + dc, row + dr))
        .min_by_key(|&(dc, dr)| dc * dc + dr * dr)
        .map(|(dc, dr)| ((col + dc) as usize, (row + dr) as usize))
}

/// A tapered ramp's quadrature over one frame's measured field: per node, the integrals that
/// multiply P_aa and P_ab. Built once per frame ([`TaperedRamp::quadrature`]); evaluated for
/// every trial law of a fit.
#[derive(Clone, Debug, PartialEq)]
pub struct RampQuadrature {
    field: TaperedRamp,
    /// Node squares whose material took a neighbour's measurement (their own node had none).
    borrowed: usize,
    /// (node index in the grid, weight of P_aa, weight of P_ab), mm².
    terms: Vec<(usize, f64, f64)>,
}

impl RampQuadrature {
    pub fn field(&self) -> &TaperedRamp {
        &self.field
    }

    /// Node squares whose material took a neighbour's measurement.
    pub fn borrowed(&self) -> usize {
        self.borrowed
    }

    /// Nodes with a weight.
    pub fn nodes(&self) -> usize {
        self.terms.len()
    }

    /// The weighted nodes of the quadrature over the measured field `grid` (the one it was
    /// built on).
    pub fn weighted_nodes(&self, grid: &FieldGrid) -> Result<Vec<WeightedNode>, RampError> {
        let (a, b) = self.field.components();
        self.terms
            .iter()
            .map(|&(k, along, across)| {
                let (col, row) = (k % grid.cols, k / grid.cols);
                let gradient = grid.gradients[k].ok_or(RampError::Hole {
                    field: self.field,
                    col,
                    row,
                })?;
                let mut weight_mm2 = [[0.0; 2]; 2];
                weight_mm2[a][a] = along;
                weight_mm2[a][b] = across;
                Ok(WeightedNode {
                    at: (col, row),
                    filled: false,
                    gradient,
                    weight_mm2,
                })
            })
            .collect()
    }

    /// The force the field's virtual work balances, N, for the measured field `grid` (the one
    /// the quadrature was built on) of a sheet of reference thickness `thickness_mm` under
    /// `model` at `p`.
    pub fn force_n(
        &self,
        grid: &FieldGrid,
        model: &Model,
        p: &[f64],
        thickness_mm: f64,
    ) -> Result<f64, RampError> {
        let nodes = self.weighted_nodes(grid)?;
        work_n(&nodes, model, p, thickness_mm).map_err(|failure| RampError::Stress {
            field: self.field,
            col: failure.at.0,
            row: failure.at.1,
            reason: failure.reason,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::LoadCase;
    use crate::field_stress::node_stress;

    #[test]
    fn piecewise_linear_integrals_are_exact() {
        let taper = [(-3.0, 0.0), (-1.0, 1.0), (1.0, 1.0), (3.0, 0.0)];
        assert!((integral(&taper, -5.0, 5.0) - 4.0).abs() < 1e-12);
        assert!((integral(&taper, -2.0, 0.0) - 1.75).abs() < 1e-12);
        assert!((integral(&taper, 2.0, 4.0) - 0.25).abs() < 1e-12);
    }

    /// On a homogeneous uniaxial field along x filling a wide grid, the tapered ramp balances
    /// the force of the strip of the flat width plus half the tapers (the stress is uniform,
    /// P_xy = 0), its − twin the same.
    #[test]
    fn a_homogeneous_field_balances_the_force_of_its_mean_width() {
        let (l1, l2) = LoadCase::Uniaxial.in_plane_stretches(1.6);
        let n = 81;
        let grid = FieldGrid {
            cols: n,
            rows: n,
            x0_mm: -20.0,
            y0_mm: -20.0,
            step_mm: 0.5,
            gradients: vec![Some([[l1, 0.0], [0.0, l2]]); n * n],
        };
        let model = Model::Mooney;
        let p = [0.3, 0.05];
        let nominal = node_stress(&model, &p, &[[l1, 0.0], [0.0, l2]])
            .unwrap()
            .nominal_mpa[0][0];
        for mirrored in [false, true] {
            let field = TaperedRamp {
                axis: ArmAxis::X,
                from_mm: -5.0,
                to_mm: 5.0,
                centre_mm: 0.0,
                flat_half_width_mm: 8.0,
                zero_half_width_mm: 14.0,
                mirrored,
            };
            let force = field
                .quadrature(&grid, &|_| true)
                .unwrap()
                .force_n(&grid, &model, &p, 2.0)
                .unwrap();
            let want = nominal * 2.0 * (16.0 + 6.0);
            assert!(
                (force - want).abs() < 1e-9 * want,
                "{mirrored}: {force} against {want}"
            );
        }
    }

    /// A material node without a measurement takes its nearest measured neighbour's within
    /// two rings (counted); a hole wider than that drops the field.
    #[test]
    fn a_material_node_without_measurement_drops_the_field() {
        let n = 41;
        let f = [[1.2, 0.0], [0.0, 0.9]];
        let mut gradients = vec![Some(f); n * n];
        gradients[20 * n + 20] = None;
        let small_hole = FieldGrid {
            cols: n,
            rows: n,
            x0_mm: -10.0,
            y0_mm: -10.0,
            step_mm: 0.5,
            gradients: gradients.clone(),
        };
        for row in 18..=22 {
            for col in 18..=22 {
                gradients[row * n + col] = None;
            }
        }
        let grid = FieldGrid {
            cols: n,
            rows: n,
            x0_mm: -10.0,
            y0_mm: -10.0,
            step_mm: 0.5,
            gradients,
        };
        let field = TaperedRamp {
            axis: ArmAxis::X,
            from_mm: -2.0,
            to_mm: 2.0,
            centre_mm: 0.0,
            flat_half_width_mm: 4.0,
            zero_half_width_mm: 8.0,
            mirrored: false,
        };
        let whole = FieldGrid {
            gradients: vec![Some(f); n * n],
            ..small_hole.clone()
        };
        let filled = field.quadrature(&small_hole, &|_| true).unwrap();
        assert_eq!(filled.borrowed(), 1);
        let law = (Model::Mooney, [0.3, 0.05]);
        let force = |q: &RampQuadrature, g: &FieldGrid| q.force_n(g, &law.0, &law.1, 2.0).unwrap();
        let reference = field.quadrature(&whole, &|_| true).unwrap();
        assert_eq!(reference.borrowed(), 0);
        assert!((force(&filled, &small_hole) - force(&reference, &whole)).abs() < 1e-9);
        let err = field.quadrature(&grid, &|_| true).unwrap_err();
        assert!(
            matches!(
                err,
                RampError::Hole {
                    col: 20,
                    row: 20,
                    ..
                }
            ),
            "{err}"
        );
        // Off the specimen (a pinhole at the node: its square's material takes a neighbour's
        // measurement), the same node is no hole.
        let pinhole = |x: [f64; 2]| x[0].abs() > 0.01 || x[1].abs() > 0.01;
        let quadrature = field.quadrature(&small_hole, &pinhole).unwrap();
        assert_eq!(quadrature.borrowed(), 1);
        assert!(quadrature
            .force_n(&small_hole, &Model::Mooney, &[0.3, 0.05], 2.0)
            .is_ok());
    }
}
