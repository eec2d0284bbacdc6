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
//! Kinematics: the grips impose the nominal stretches Λx = 1 + e_x / gauge_length and
//! Λy = 1 + e_y / width (e = the sum of the two displacements of a pair from mounting, less the
//! grip compliance's give, 2 · compliance · pair force). The gauge zone, what the camera sees
//! and what the stress acts on, does not follow them: on a real cruciform the arms and the
//! corners take part of the stretch (see [`GripEffects`]), so
//! ln λx = fx(Λx) ln Λx + κ ln Λy and ln λy = fy(Λy) ln Λy + κ ln Λx in equibiaxial loading,
//! with the stretch-dependent fraction f(Λ) = f0 + f1 ln Λ different on x and y;
//! in uniaxial loading ln λ = f(Λ) ln Λ along the pulled axis and λ^−½ across (free lateral
//! contraction). [`GripEffects::none`] gives back the homogeneous sheet (λ = Λ). A thin sheet buckles instead of carrying compression:
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

/// The gauge zone's log stretch as a fraction of the nominal (grip) one: f(Λ) = f0 + f1 ln Λ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaugeFraction {
    pub f0: f64,
    /// Change of the fraction per unit nominal log stretch (negative: the arms take more as
    /// the sheet stiffens).
    pub f1: f64,
}

impl GaugeFraction {
    pub const ONE: GaugeFraction = GaugeFraction { f0: 1.0, f1: 0.0 };

    pub fn at(&self, nominal_log_stretch: f64) -> f64 {
        self.f0 + self.f1 * nominal_log_stretch
    }
}

/// Grip and edge effects of a cruciform specimen: why displacement control misses a strain
/// path. Defaults: the gauge zone takes ≈ 0.9 of the nominal log stretch along x, ≈ 0.83
/// along y, a little less as the stretch grows, contracts by 0.04 of the other axis's nominal
/// log stretch, and each grip gives 1 mm per kN.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GripEffects {
    /// Along x and y.
    pub fraction: [GaugeFraction; 2],
    /// Cross term κ of the equibiaxial (cruciform) loading: ln λx gains κ ln Λy, and ln λy
    /// gains κ ln Λx.
    pub cross: f64,
    /// Give of each grip under load (mm per kN, ≥ 0).
    pub compliance_mm_per_kn: f64,
}

impl GripEffects {
    /// The homogeneous sheet: the gauge zone stretches as the grips.
    pub const fn none() -> GripEffects {
        GripEffects {
            fraction: [GaugeFraction::ONE, GaugeFraction::ONE],
            cross: 0.0,
            compliance_mm_per_kn: 0.0,
        }
    }
}

impl Default for GripEffects {
    fn default() -> Self {
        GripEffects {
            fraction: [
                GaugeFraction {
                    f0: 0.92,
                    f1: -0.05,
                },
                GaugeFraction {
                    f0: 0.85,
                    f1: -0.04,
                },
            ],
            cross: -0.04,
            compliance_mm_per_kn: 1.0,
        }
    }
}

/// Fixed-point iterations of the compliance (the give is a few % of the elongation: contracts
/// by ≈ 50× per iteration on the default specimen).
const COMPLIANCE_ITERATIONS: usize = 3;

#[derive(Clone, Debug, PartialEq)]
pub struct SpecimenConfig {
    pub law: InvariantLaw,
    pub geometry: SpecimenGeometry,
    pub loading: Loading,
    pub misalignment: Misalignment,
    pub grip: GripEffects,
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
            grip: GripEffects::default(),
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
        let grip = &self.grip;
        for (name, f) in [("x", grip.fraction[0]), ("y", grip.fraction[1])] {
            // The fraction must stay in (0.2, 1.5] over nominal log stretches in [0, ln 8].
            let (low, high) = (f.at(0.0), f.at(8f64.ln()));
            let ok = |v: f64| v.is_finite() && v > 0.2 && v <= 1.5;
            if !(ok(low) && ok(high)) {
                return Err(SpecimenError::GaugeFraction {
                    axis: name,
                    f0: f.f0,
                    f1: f.f1,
                });
            }
        }
        if !(grip.cross.is_finite() && grip.cross.abs() <= 0.3) {
            return Err(SpecimenError::Cross { cross: grip.cross });
        }
        if !(grip.compliance_mm_per_kn.is_finite()
            && (0.0..=100.0).contains(&grip.compliance_mm_per_kn))
        {
            return Err(SpecimenError::Compliance {
                compliance_mm_per_kn: grip.compliance_mm_per_kn,
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
    #[error("gauge fraction along {axis} (f0 {f0}, f1 {f1}) leaves (0.2, 1.5] for nominal stretches in [1, 8]")]
    GaugeFraction {
        axis: &'static str,
        f0: f64,
        f1: f64,
    },
    #[error("grip cross term {cross} not in [−0.3, 0.3]")]
    Cross { cross: f64 },
    #[error("grip compliance {compliance_mm_per_kn} mm/kN not in [0, 100]")]
    Compliance { compliance_mm_per_kn: f64 },
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

    /// Nominal (grip) stretches (Λx, Λy) for the given grip displacements (mm, outward
    /// positive) and pair forces (kN, for the grip compliance).
    pub fn nominal_stretches(
        &self,
        position_mm: &[f64; ACTUATOR_COUNT],
        pair_force_kn: [f64; 2],
    ) -> (f64, f64) {
        let g = &self.config.geometry;
        let give_mm = 2.0 * self.config.grip.compliance_mm_per_kn;
        let elongation = |axis: Axis| {
            position_mm[axis.plus().index()] + position_mm[axis.minus().index()]
                - give_mm * pair_force_kn[axis.index()].max(0.0)
        };
        let y_gauge_mm = match self.config.loading {
            Loading::Equibiaxial => g.width_mm,
            _ => g.gauge_length_mm,
        };
        (
            1.0 + elongation(Axis::X) / g.gauge_length_mm,
            1.0 + elongation(Axis::Y) / y_gauge_mm,
        )
    }

    /// Gauge-zone stretches (λx, λy) for nominal stretches (Λx, Λy): the grip effects.
    pub fn gauge_stretches(&self, nominal: (f64, f64)) -> (f64, f64) {
        let grip = &self.config.grip;
        let log = |l: f64| l.max(1e-3).ln();
        let (nx, ny) = (log(nominal.0), log(nominal.1));
        let own = |axis: usize, n: f64| grip.fraction[axis].at(n.max(0.0)) * n;
        match self.config.loading {
            Loading::Equibiaxial => (
                (own(0, nx) + grip.cross * ny).exp(),
                (own(1, ny) + grip.cross * nx).exp(),
            ),
            Loading::Uniaxial(Axis::Y) => {
                let l = own(1, ny);
                ((-0.5 * l).exp(), l.exp())
            }
            Loading::Uniaxial(_) => {
                let l = own(0, nx);
                (l.exp(), (-0.5 * l).exp())
            }
        }
    }

    /// Gauge-zone stretches (λx, λy) for the given grip displacements (mm, outward positive),
    /// the grip compliance solved by fixed-point iteration on the pair forces.
    pub fn stretches(&self, position_mm: &[f64; ACTUATOR_COUNT]) -> (f64, f64) {
        let mut force_kn = [0.0; 2];
        let mut stretches = self.gauge_stretches(self.nominal_stretches(position_mm, force_kn));
        if self.config.grip.compliance_mm_per_kn > 0.0 {
            for _ in 0..COMPLIANCE_ITERATIONS {
                let f = self.pair_forces_n(stretches.0, stretches.1);
                force_kn = [f[0] * 1e-3, f[1] * 1e-3];
                stretches = self.gauge_stretches(self.nominal_stretches(position_mm, force_kn));
            }
        }
        stretches
    }

    /// Pair forces (N) along x and y of the gauge stretches, before misalignment and break.
    fn pair_forces_n(&self, stretch_x: f64, stretch_y: f64) -> [f64; 2] {
        let (lx, ly) = self.loaded_stretches(stretch_x, stretch_y);
        let stress = self.config.law.in_plane_stress(lx, ly);
        let sections = self.reference_sections_mm2();
        let (gx, gy) = self.gripped();
        [
            if gx {
                stress.nominal_stress_mpa[0].max(0.0) * sections[0]
            } else {
                0.0
            },
            if gy {
                stress.nominal_stress_mpa[1].max(0.0) * sections[1]
            } else {
                0.0
            },
        ]
    }

    /// Stretches the law sees: a buckled sheet carries no compression along a gripped axis.
    fn loaded_stretches(&self, stretch_x: f64, stretch_y: f64) -> (f64, f64) {
        match self.config.loading {
            Loading::Equibiaxial => (stretch_x.max(1.0), stretch_y.max(1.0)),
            Loading::Uniaxial(Axis::Y) => {
                let l = stretch_y.max(1.0);
                (1.0 / l.sqrt(), l)
            }
            Loading::Uniaxial(_) => {
                let l = stretch_x.max(1.0);
                (l, 1.0 / l.sqrt())
            }
        }
    }

    /// Reference sections normal to x and y (mm²).
    fn reference_sections_mm2(&self) -> [f64; 2] {
        let g = &self.config.geometry;
        let y_reference_mm = match self.config.loading {
            Loading::Equibiaxial => g.gauge_length_mm,
            _ => g.width_mm,
        };
        [g.width_mm * g.thickness_mm, y_reference_mm * g.thickness_mm]
    }

    fn gripped(&self) -> (bool, bool) {
        match self.config.loading {
            Loading::Equibiaxial => (true, true),
            Loading::Uniaxial(Axis::Y) => (false, true),
            Loading::Uniaxial(_) => (true, false),
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
        let (lx, ly) = self.loaded_stretches(stretch_x, stretch_y);
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
        let (gripped_x, gripped_y) = self.gripped();
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
