//! The analytic reference: the gauge zone stretched homogeneously as the grips, λ = Λ.
//!
//! Kinematics: the grips impose the nominal stretches Λx = 1 + e_x / gauge_x and
//! Λy = 1 + e_y / gauge_y (e = the sum of the two displacements of a pair from mounting, less
//! the grip compliance's give, 2 · compliance · pair force, solved by fixed-point iteration),
//! the gauge zone stretches as them; in uniaxial loading the pulled axis's Λ and λ^−½ across
//! (free lateral contraction). A thin sheet buckles instead of carrying compression: stretches
//! below 1 along a gripped axis carry no force (tension-field approximation).
//! Grip force along x: σxx × current section = nominal stress × reference section.
//!
//! Misalignment (the "bad positioning" of Fig. 10b): a rotation of the sheet in the grips,
//! reported to the camera and reducing the axial force seen by the load cells to F cos θ; and an
//! asymmetry a ∈ (−1, 1) of the clamping, which moves the material centre by a · elongation / 2
//! from the grip centre.

use super::{Loading, SpecimenConfig, SpecimenResponse};
use crate::hydraulics::ACTUATOR_COUNT;
use crate::ids::Axis;
use crate::snapshot::SpecimenKinematics;

/// Fixed-point iterations of the compliance (the give is a few % of the elongation: contracts
/// by ≈ 50× per iteration on the default specimen).
const COMPLIANCE_ITERATIONS: usize = 3;

/// The homogeneous sheet (stateless but for its dimensions).
#[derive(Clone, Debug, PartialEq)]
pub struct Homogeneous {
    gauge_mm: [f64; 2],
    sections_mm2: [f64; 2],
}

impl Homogeneous {
    pub fn new(config: &SpecimenConfig) -> Homogeneous {
        Homogeneous {
            gauge_mm: config.gauge_mm(),
            sections_mm2: config.reference_sections_mm2(),
        }
    }

    /// Gauge stretches (λx, λy) = nominal ones for the given grip displacements (mm, outward
    /// positive) and pair forces (kN, for the grip compliance).
    fn stretches_at(
        &self,
        config: &SpecimenConfig,
        position_mm: &[f64; ACTUATOR_COUNT],
        pair_force_kn: [f64; 2],
    ) -> (f64, f64) {
        let give_mm = 2.0 * config.grip_compliance_mm_per_kn;
        let nominal = |axis: Axis| {
            let e = position_mm[axis.plus().index()] + position_mm[axis.minus().index()]
                - give_mm * pair_force_kn[axis.index()].max(0.0);
            1.0 + e / self.gauge_mm[axis.index()]
        };
        let (lx, ly) = (nominal(Axis::X), nominal(Axis::Y));
        match config.loading {
            Loading::Equibiaxial => (lx, ly),
            Loading::Uniaxial(Axis::Y) => (ly.max(1e-3).powf(-0.5), ly),
            Loading::Uniaxial(_) => (lx, lx.max(1e-3).powf(-0.5)),
        }
    }

    /// Gauge-zone stretches (λx, λy) for the given grip displacements, the grip compliance
    /// solved by fixed-point iteration on the pair forces.
    pub fn stretches(
        &self,
        config: &SpecimenConfig,
        position_mm: &[f64; ACTUATOR_COUNT],
    ) -> (f64, f64) {
        let mut stretches = self.stretches_at(config, position_mm, [0.0; 2]);
        if config.grip_compliance_mm_per_kn > 0.0 {
            for _ in 0..COMPLIANCE_ITERATIONS {
                let n = self.nominal_stresses_mpa(config, stretches);
                let force_kn = [0, 1].map(|i| n[i].max(0.0) * self.sections_mm2[i] * 1e-3);
                stretches = self.stretches_at(config, position_mm, force_kn);
            }
        }
        stretches
    }

    /// Nominal stresses (MPa) along the gripped axes (0 along a free one).
    fn nominal_stresses_mpa(&self, config: &SpecimenConfig, stretches: (f64, f64)) -> [f64; 2] {
        let (lx, ly) = match config.loading {
            Loading::Equibiaxial => (stretches.0.max(1.0), stretches.1.max(1.0)),
            Loading::Uniaxial(Axis::Y) => {
                let l = stretches.1.max(1.0);
                (1.0 / l.sqrt(), l)
            }
            Loading::Uniaxial(_) => {
                let l = stretches.0.max(1.0);
                (l, 1.0 / l.sqrt())
            }
        };
        let n = config.law.in_plane_stress(lx, ly).nominal_stress_mpa;
        match config.loading {
            Loading::Equibiaxial => n,
            Loading::Uniaxial(Axis::Y) => [0.0, n[1]],
            Loading::Uniaxial(_) => [n[0], 0.0],
        }
    }

    /// Grip forces and kinematics, and the peak nominal stress (MPa, for the break).
    pub fn respond(
        &self,
        config: &SpecimenConfig,
        position_mm: &[f64; ACTUATOR_COUNT],
    ) -> (SpecimenResponse, f64) {
        let (stretch_x, stretch_y) = self.stretches(config, position_mm);
        let m = &config.misalignment;
        let centre = |axis: Axis| {
            let (p, n) = (
                position_mm[axis.plus().index()],
                position_mm[axis.minus().index()],
            );
            0.5 * (p - n) + m.asymmetry * 0.5 * (p + n)
        };
        let nominal = self.nominal_stresses_mpa(config, (stretch_x, stretch_y));
        let cos = m.rotation_deg.to_radians().cos();
        let mut response = SpecimenResponse {
            kinematics: SpecimenKinematics {
                stretch_x,
                stretch_y,
                rotation_deg: m.rotation_deg,
                centre_x_mm: centre(Axis::X),
                centre_y_mm: centre(Axis::Y),
                broken: false,
            },
            ..SpecimenResponse::default()
        };
        for axis in [Axis::X, Axis::Y] {
            let force_n = nominal[axis.index()] * self.sections_mm2[axis.index()] * cos;
            response.grip_force_n[axis.plus().index()] = force_n;
            response.grip_force_n[axis.minus().index()] = force_n;
        }
        (response, nominal[0].max(nominal[1]))
    }
}
