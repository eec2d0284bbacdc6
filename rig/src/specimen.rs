//! The specimen between the grips: an incompressible hyperelastic rubber sheet whose law is
//! `material::InvariantLaw` (Smactane™ by default, paper Tables 3 and 4). This module
//! only maps grip displacements to homogeneous stretches and stretches to grip forces; the law
//! itself lives in the `material` crate (one place per concept).
//!
//! Geometry (mm): the gauge region is `gauge_length_mm` along X (between the X grips) by
//! `width_mm` along Y, `thickness_mm` thick. In equibiaxial tension (cruciform, X and Y pairs)
//! the Y gauge length is `width_mm`. Default: a 100 × 100 × 2 mm central square, the size of
//! the Fig. 10 specimen region seen by the camera; for a uniaxial strip use e.g. 100 × 20 × 2.
//!
//! Kinematics, homogeneous: λx = 1 + elongation_x / gauge_length (elongation = sum of the two
//! X displacements from mounting), λy = 1 + elongation_y / width in equibiaxial, λy = λx^−½ in
//! uniaxial (free lateral contraction). A thin sheet buckles instead of carrying compression:
//! stretches below 1 along a gripped axis carry no force (tension-field approximation).
//! Grip force along x: σxx × current section = σxx · (w λy) · (t λz) = σxx · w t / λx.
//!
//! Misalignment (the "bad positioning" of Fig. 10b): a rotation of the sheet in the grips,
//! reported to the camera and reducing the axial force seen by the load cells to F cos θ; and an
//! asymmetry a ∈ (−1, 1) of the clamping, which moves the material centre by a · elongation / 2
//! from the grip centre.

use crate::hydraulics::ACTUATOR_COUNT;
use crate::ids::Axis;
use crate::snapshot::SpecimenKinematics;
use material::InvariantLaw;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Loading {
    /// One pair pulls (X or Y), free lateral contraction.
    Uniaxial(Axis),
    /// X and Y pairs pull the cruciform together.
    Equibiaxial,
}

impl Loading {
    /// `uniaxial along x`, `equibiaxial`.
    pub fn name(self) -> String {
        match self {
            Loading::Uniaxial(axis) => {
                format!("uniaxial (along {})", axis.name().to_ascii_lowercase())
            }
            Loading::Equibiaxial => "equibiaxial".into(),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecimenGeometry {
    pub gauge_length_mm: f64,
    pub width_mm: f64,
    pub thickness_mm: f64,
}

impl Default for SpecimenGeometry {
    fn default() -> Self {
        SpecimenGeometry {
            gauge_length_mm: 100.0,
            width_mm: 100.0,
            thickness_mm: 2.0,
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Misalignment {
    pub rotation_deg: f64,
    /// Clamping asymmetry in (−1, 1); 0 = centred.
    pub asymmetry: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct SpecimenConfig {
    pub law: InvariantLaw,
    pub geometry: SpecimenGeometry,
    pub loading: Loading,
    pub misalignment: Misalignment,
    /// Nominal (first Piola-Kirchhoff) stress at which the sheet tears; 9.5 MPa is the ultimate
    /// strength the manufacturer gives for Smactane™ (paper section 4.a).
    pub break_nominal_stress_mpa: f64,
}

impl Default for SpecimenConfig {
    fn default() -> Self {
        SpecimenConfig {
            law: InvariantLaw::smactane(),
            geometry: SpecimenGeometry::default(),
            loading: Loading::Equibiaxial,
            misalignment: Misalignment::default(),
            break_nominal_stress_mpa: 9.5,
        }
    }
}

impl SpecimenConfig {
    pub fn validate(&self) -> Result<(), SpecimenError> {
        let g = &self.geometry;
        for (name, v) in [
            ("gauge_length_mm", g.gauge_length_mm),
            ("width_mm", g.width_mm),
            ("thickness_mm", g.thickness_mm),
            ("break_nominal_stress_mpa", self.break_nominal_stress_mpa),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(SpecimenError::NotPositive { name, value: v });
            }
        }
        let m = &self.misalignment;
        if !(m.rotation_deg.is_finite() && m.rotation_deg.abs() < 45.0) {
            return Err(SpecimenError::Rotation {
                rotation_deg: m.rotation_deg,
            });
        }
        if !(m.asymmetry.is_finite() && m.asymmetry.abs() < 1.0) {
            return Err(SpecimenError::Asymmetry {
                asymmetry: m.asymmetry,
            });
        }
        if self.loading == Loading::Uniaxial(Axis::Z) {
            return Err(SpecimenError::UniaxialAlongZ);
        }
        Ok(())
    }
}

/// Why a specimen's configuration was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SpecimenError {
    #[error("specimen {name} = {value}, expected a positive number")]
    NotPositive { name: &'static str, value: f64 },
    #[error("rotation_deg {rotation_deg} not in (−45, 45)")]
    Rotation { rotation_deg: f64 },
    #[error("asymmetry {asymmetry} not in (−1, 1)")]
    Asymmetry { asymmetry: f64 },
    #[error("uniaxial loading is along X or Y (the sheet lies in the X-Y plane)")]
    UniaxialAlongZ,
}

/// Result of one evaluation: grip forces (N, tension positive, per actuator) and kinematics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpecimenResponse {
    pub grip_force_n: [f64; ACTUATOR_COUNT],
    pub kinematics: SpecimenKinematics,
    /// Nominal stresses along x and y (MPa).
    pub nominal_stress_mpa: [f64; 2],
}

#[derive(Clone, Debug)]
pub struct Specimen {
    config: SpecimenConfig,
    broken: bool,
}

impl Specimen {
    pub fn new(config: SpecimenConfig) -> Result<Specimen, SpecimenError> {
        config.validate()?;
        Ok(Specimen {
            config,
            broken: false,
        })
    }

    pub fn config(&self) -> &SpecimenConfig {
        &self.config
    }

    pub fn is_broken(&self) -> bool {
        self.broken
    }

    /// Tears the sheet (a test command, or the break stress reached).
    pub fn break_now(&mut self) {
        self.broken = true;
    }

    /// Current cross-sections normal to X and Y (mm²) at stretches (λx, λy), for Cauchy
    /// stress = force / section: w t / λx and L t / λy (incompressible sheet).
    pub fn current_sections_mm2(&self, stretch_x: f64, stretch_y: f64) -> [f64; 2] {
        let g = &self.config.geometry;
        let y_reference_mm = match self.config.loading {
            Loading::Equibiaxial => g.gauge_length_mm,
            _ => g.width_mm,
        };
        [
            g.width_mm * g.thickness_mm / stretch_x.max(1e-6),
            y_reference_mm * g.thickness_mm / stretch_y.max(1e-6),
        ]
    }

    /// Stretches (λx, λy) for the given grip displacements (mm, outward positive).
    pub fn stretches(&self, position_mm: &[f64; ACTUATOR_COUNT]) -> (f64, f64) {
        let g = &self.config.geometry;
        let elongation =
            |axis: Axis| position_mm[axis.plus().index()] + position_mm[axis.minus().index()];
        match self.config.loading {
            Loading::Equibiaxial => (
                1.0 + elongation(Axis::X) / g.gauge_length_mm,
                1.0 + elongation(Axis::Y) / g.width_mm,
            ),
            Loading::Uniaxial(Axis::Y) => {
                let l = 1.0 + elongation(Axis::Y) / g.gauge_length_mm;
                (1.0 / l.max(1e-3).sqrt(), l)
            }
            Loading::Uniaxial(_) => {
                let l = 1.0 + elongation(Axis::X) / g.gauge_length_mm;
                (l, 1.0 / l.max(1e-3).sqrt())
            }
        }
    }

    /// Grip forces and kinematics at the given grip displacements. Allocation-free.
    pub fn respond(&mut self, position_mm: &[f64; ACTUATOR_COUNT]) -> SpecimenResponse {
        let (stretch_x, stretch_y) = self.stretches(position_mm);
        let m = &self.config.misalignment;
        let centre = |axis: Axis| {
            let (p, n) = (
                position_mm[axis.plus().index()],
                position_mm[axis.minus().index()],
            );
            0.5 * (p - n) + m.asymmetry * 0.5 * (p + n)
        };
        let mut response = SpecimenResponse {
            kinematics: SpecimenKinematics {
                stretch_x,
                stretch_y,
                rotation_deg: m.rotation_deg,
                centre_x_mm: centre(Axis::X),
                centre_y_mm: centre(Axis::Y),
                broken: self.broken,
            },
            ..SpecimenResponse::default()
        };
        if self.broken {
            response.kinematics.stretch_x = 1.0;
            response.kinematics.stretch_y = 1.0;
            return response;
        }
        // Buckled sheet: no compression along a gripped axis.
        let (lx, ly) = match self.config.loading {
            Loading::Equibiaxial => (stretch_x.max(1.0), stretch_y.max(1.0)),
            Loading::Uniaxial(Axis::Y) => {
                let l = stretch_y.max(1.0);
                (1.0 / l.sqrt(), l)
            }
            Loading::Uniaxial(_) => {
                let l = stretch_x.max(1.0);
                (l, 1.0 / l.sqrt())
            }
        };
        let stress = self.config.law.in_plane_stress(lx, ly);
        let g = &self.config.geometry;
        let cos = m.rotation_deg.to_radians().cos();
        // Cauchy stress × current section = nominal stress × reference section.
        let force_x_n = stress.nominal_stress_mpa[0] * g.width_mm * g.thickness_mm * cos;
        let y_reference_mm = match self.config.loading {
            Loading::Equibiaxial => g.gauge_length_mm,
            _ => g.width_mm,
        };
        let force_y_n = stress.nominal_stress_mpa[1] * y_reference_mm * g.thickness_mm * cos;
        response.nominal_stress_mpa = stress.nominal_stress_mpa;
        let (gripped_x, gripped_y) = match self.config.loading {
            Loading::Equibiaxial => (true, true),
            Loading::Uniaxial(Axis::Y) => (false, true),
            Loading::Uniaxial(_) => (true, false),
        };
        let peak = if gripped_x {
            stress.nominal_stress_mpa[0]
        } else {
            0.0
        }
        .max(if gripped_y {
            stress.nominal_stress_mpa[1]
        } else {
            0.0
        });
        if peak >= self.config.break_nominal_stress_mpa {
            self.broken = true;
            response.kinematics.broken = true;
            return response;
        }
        if gripped_x {
            response.grip_force_n[Axis::X.plus().index()] = force_x_n;
            response.grip_force_n[Axis::X.minus().index()] = force_x_n;
        }
        if gripped_y {
            response.grip_force_n[Axis::Y.plus().index()] = force_y_n;
            response.grip_force_n[Axis::Y.minus().index()] = force_y_n;
        }
        response
    }
}
