//! The cruciform: a central square of side w (the arm width), four arms of width w and free
//! length a from the square to the grips, fillets of radius r at the four re-entrant corners,
//! optional slits along the arms (each running from the grip towards the centre), thickness t.
//!
//! Meshing: the central square is one structured patch; each arm is the sector
//! {w/2 ≤ x ≤ w/2 + a, |y| ≤ T(x)} (turned by k · 90°), T the boundary curve: the diagonal
//! from the square's corner to the fillet's mid-point, the fillet arc, the arm's edge. The
//! sector's nodes lie on vertical lines between −T and T, so neighbouring sectors share the
//! diagonal's nodes exactly (rotations by 90° are exact in floating point).

use super::{cells, check_size, positive, tolerance_mm, Grip, Specimen};
use crate::error::GeometryError;
use crate::mesh::MeshBuilder;
use std::f64::consts::{FRAC_1_SQRT_2, PI};

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CruciformGeometry {
    /// Width of each arm and side of the central square.
    pub arm_width_mm: f64,
    /// Free length of each arm, from the central square to its grip.
    pub arm_length_mm: f64,
    /// Fillet radius at the re-entrant corners (0: sharp corners).
    pub fillet_radius_mm: f64,
    /// Slits per arm, evenly spaced across it (0: none).
    pub slits_per_arm: usize,
    /// Length of each slit from the grip.
    pub slit_length_mm: f64,
    pub thickness_mm: f64,
    /// Target element edge.
    pub element_size_mm: f64,
}

impl Default for CruciformGeometry {
    /// A 100 mm central square (the rig's gauge zone), 80 mm arms, 20 mm fillets, 2 mm thick,
    /// 10 mm elements, no slits.
    fn default() -> Self {
        CruciformGeometry {
            arm_width_mm: 100.0,
            arm_length_mm: 80.0,
            fillet_radius_mm: 20.0,
            slits_per_arm: 0,
            slit_length_mm: 0.0,
            thickness_mm: 2.0,
            element_size_mm: 10.0,
        }
    }
}

/// The boundary curve T of the +x sector, sampled at half-cell indices.
struct SectorCurve {
    half_width: f64,
    radius: f64,
    grip_x: f64,
    /// Cells on the diagonal, the arc and the arm's edge.
    cells: [usize; 3],
}

impl SectorCurve {
    fn total_cells(&self) -> usize {
        self.cells.iter().sum()
    }

    /// T at half-cell index i.
    fn at(&self, i: usize) -> [f64; 2] {
        let (c, r) = (self.half_width, self.radius);
        let [nd, nf, na] = self.cells.map(|n| 2 * n);
        if i < nd {
            let v = c + r * (1.0 - FRAC_1_SQRT_2) * (i as f64 / nd as f64);
            [v, v]
        } else if i < nd + nf {
            let theta = 1.25 * PI + 0.25 * PI * ((i - nd) as f64 / nf as f64);
            [c + r + r * theta.cos(), c + r + r * theta.sin()]
        } else {
            let t = (i - nd - nf) as f64 / na as f64;
            [c + r + (self.grip_x - c - r) * t, c]
        }
    }
}

/// (x, y) turned by `quarter` × 90°, exactly.
fn turn(p: [f64; 2], quarter: usize) -> [f64; 2] {
    match quarter % 4 {
        0 => p,
        1 => [-p[1], p[0]],
        2 => [-p[0], -p[1]],
        _ => [p[1], -p[0]],
    }
}

impl CruciformGeometry {
    fn check(&self) -> Result<(), GeometryError> {
        let width = positive("arm width", self.arm_width_mm)?;
        let length = positive("arm length", self.arm_length_mm)?;
        positive("thickness", self.thickness_mm)?;
        positive("element size", self.element_size_mm)?;
        let r = self.fillet_radius_mm;
        if !(r >= 0.0 && r.is_finite()) {
            return Err(GeometryError::NotPositive {
                name: "fillet radius",
                value_mm: r,
            });
        }
        for (limit_name, limit_mm) in [("arm width", width), ("arm length", length)] {
            if r > limit_mm {
                return Err(GeometryError::FilletTooLarge {
                    radius_mm: r,
                    limit_name,
                    limit_mm,
                });
            }
        }
        if self.slits_per_arm > 0 {
            let slit = |reason| GeometryError::Slit {
                reason,
                count: self.slits_per_arm,
                length_mm: self.slit_length_mm,
            };
            positive("slit length", self.slit_length_mm)
                .map_err(|_| slit("expected a positive slit length"))?;
            if self.slit_length_mm > length - r {
                return Err(slit(
                    "a slit must end in the straight part of the arm, after the fillets",
                ));
            }
            if (self.slits_per_arm + 1) as f64 * self.element_size_mm > width {
                return Err(slit("more slits than elements across the arm"));
            }
        }
        Ok(())
    }

    /// The meshed cruciform with grips "x+", "y+", "x-", "y-" at the arms' ends.
    pub fn mesh(&self) -> Result<Specimen, GeometryError> {
        self.check()?;
        self.mesh_to([self.arm_length_mm; 4])
    }

    /// The part of the cruciform inside the rectangle `x_mm` × `y_mm` (reference mm, the
    /// centre at 0; a camera's field of view): each arm cut where the rectangle's edge crosses
    /// its straight part (or at its grip if the rectangle reaches beyond it). Its "grips" are
    /// the nodes on those edges, pulled along the arm: where the finite-element model updating
    /// prescribes the measured displacements and reads each arm's force. Every arm must be cut
    /// beyond its fillets; a cruciform with slits is refused (its slits would have to be cut
    /// too).
    pub fn clipped(&self, x_mm: [f64; 2], y_mm: [f64; 2]) -> Result<Specimen, GeometryError> {
        self.check()?;
        if self.slits_per_arm > 0 {
            return Err(GeometryError::Slit {
                reason: "a cruciform clipped to a view is meshed without slits",
                count: self.slits_per_arm,
                length_mm: self.slit_length_mm,
            });
        }
        let straight_mm = 0.5 * self.arm_width_mm + self.fillet_radius_mm;
        let grip_mm = 0.5 * self.arm_width_mm + self.arm_length_mm;
        // Quarter order: x+, y+, x-, y-.
        let reaches = [
            ("x+", x_mm[1]),
            ("y+", y_mm[1]),
            ("x-", -x_mm[0]),
            ("y-", -y_mm[0]),
        ];
        let mut lengths = [0.0; 4];
        for (length, (arm, reach_mm)) in lengths.iter_mut().zip(reaches) {
            if reach_mm.is_nan() || reach_mm <= straight_mm {
                return Err(GeometryError::ArmNotCut {
                    arm,
                    reach_mm,
                    straight_mm,
                });
            }
            *length = reach_mm.min(grip_mm) - 0.5 * self.arm_width_mm;
        }
        self.mesh_to(lengths)
    }

    /// The mesh with each arm `lengths_mm` long (x+, y+, x-, y-), its grips at their ends.
    fn mesh_to(&self, lengths_mm: [f64; 4]) -> Result<Specimen, GeometryError> {
        let (c, r, h) = (
            0.5 * self.arm_width_mm,
            self.fillet_radius_mm,
            self.element_size_mm,
        );
        let fingers = self.slits_per_arm + 1;
        let across = cells(2.0 * c, h, 1).div_ceil(fingers) * fingers;
        let curves = lengths_mm.map(|length_mm| SectorCurve {
            half_width: c,
            radius: r,
            grip_x: c + length_mm,
            cells: if r > 0.0 {
                [
                    cells(r * (1.0 - FRAC_1_SQRT_2) * 2f64.sqrt(), h, 1),
                    cells(0.25 * PI * r, h, 2),
                    cells(length_mm - r, h, 1),
                ]
            } else {
                [0, 0, cells(length_mm, h, 1)]
            },
        });
        let along: usize = curves.iter().map(SectorCurve::total_cells).sum();
        check_size(2 * (across * across + across * along))?;
        let longest_mm = c + lengths_mm.iter().copied().fold(0.0, f64::max);
        let tolerance = tolerance_mm(longest_mm);
        let mut builder = MeshBuilder::new(tolerance);
        let across_at = |j: usize| 2.0 * j as f64 / (2 * across) as f64 - 1.0;
        builder.add_patch(across, across, |i, j| [c * across_at(i), c * across_at(j)]);
        for (quarter, curve) in curves.iter().enumerate() {
            let along = curve.total_cells();
            // Slits: cut lines j = 2 across · m / fingers, from the node nearest the slit's
            // tip on.
            let slit_tip_x = curve.grip_x - self.slit_length_mm;
            let tip = (0..=2 * along)
                .step_by(2)
                .min_by(|&a, &b| {
                    let da = (curve.at(a)[0] - slit_tip_x).abs();
                    let db = (curve.at(b)[0] - slit_tip_x).abs();
                    da.total_cmp(&db)
                })
                .unwrap_or(2 * along);
            let cut = |i: usize, j: usize| {
                self.slits_per_arm > 0
                    && i > tip
                    && j.is_multiple_of(2 * across / fingers)
                    && j > 0
                    && j < 2 * across
            };
            builder.add_cut_patch(
                along,
                across,
                |i, j| {
                    let t = curve.at(i);
                    turn([t[0], across_at(j) * t[1]], quarter)
                },
                cut,
            );
        }
        let mesh = builder.finish()?;
        let grips = [("x+", 0), ("y+", 1), ("x-", 2), ("y-", 3)]
            .map(|(name, quarter)| {
                let axis = turn([1.0, 0.0], quarter);
                let grip_x = curves[quarter].grip_x;
                Grip {
                    name,
                    nodes: mesh.nodes_where(|p| {
                        (p[0] * axis[0] + p[1] * axis[1] - grip_x).abs() < tolerance
                    }),
                    centre_mm: turn([grip_x, 0.0], quarter),
                    axis,
                }
            })
            .to_vec();
        Ok(Specimen {
            mesh,
            thickness_mm: self.thickness_mm,
            grips,
        })
    }

    /// Reference area of the sheet between the grips, mm²: the cross and the four fillets.
    pub fn area_mm2(&self) -> f64 {
        let w = self.arm_width_mm;
        let r = self.fillet_radius_mm;
        w * w + 4.0 * w * self.arm_length_mm + 4.0 * r * r * (1.0 - 0.25 * PI)
    }
}
