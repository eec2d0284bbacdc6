//! The specimen between the grips: an incompressible hyperelastic rubber sheet whose law is
//! `material::InvariantLaw` (Smactane™ by default, paper Tables 3 and 4), in one of two models
//! ([`SpecimenModel`]):
//!
//! - **structure** ([`structure`]): the finite-element sheet of `membrane`, the cruciform for
//!   equibiaxial loading, the uniaxial strip for uniaxial loading, meshed from the
//!   configuration's `[specimen.geometry]` ([`membrane::SpecimenChoice`], the one definition of
//!   the geometry) with each actuator driving its grip's axial translation. Grip and edge
//!   effects come out of the mechanics. Solved on a schedule of simulated time; between two
//!   solves the forces and the filmed region's kinematics follow the grips through the tangent
//!   condensed on the grips ([`condensed`]).
//! - **homogeneous** ([`homogeneous`]): the analytic reference, one homogeneous stretch of the
//!   gauge zone, λ = Λ = 1 + elongation / gauge length (grips at the gauge zone's edges).
//!
//! Both: the grips give `grip_compliance_mm_per_kn` under load (a property of the machine's
//! grips); a thin sheet carries no compression; the sheet tears at
//! `break_nominal_stress_mpa`. The gauge lengths the rig divides elongations by (built-in
//! programs, strain control) are the same for both models ([`SpecimenConfig::gauge_mm`]): the
//! cruciform's central square, the strip's free length.

mod condensed;
mod homogeneous;
mod structure;

pub use condensed::{Linearisation, MAX_GRIPS};
pub use homogeneous::Homogeneous;
pub use structure::{
    SolveSchedule, SolvedState, SolverFigures, SpecimenFault, Structure, StructureError,
};

use crate::hydraulics::ACTUATOR_COUNT;
use crate::ids::Axis;
use crate::snapshot::SpecimenKinematics;
use material::InvariantLaw;
use membrane::{SpecimenChoice, SpecimenShape};

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

    /// The shape of `[specimen.geometry]` this loading mounts.
    pub fn shape(self) -> SpecimenShape {
        match self {
            Loading::Uniaxial(_) => SpecimenShape::UniaxialStrip,
            Loading::Equibiaxial => SpecimenShape::Cruciform,
        }
    }
}

/// Which model of the sheet the rig loads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SpecimenModel {
    /// The analytic homogeneous sheet (λ = Λ): the reference of the rig's own tests and of
    /// `dicstream run`'s acceptance (forces over current sections are stresses only there).
    #[default]
    Homogeneous,
    /// The finite-element structure (`membrane`): cruciform or strip with its grips.
    Structure,
}

wire::named!(SpecimenModel, "specimen model", {
    Homogeneous => "homogeneous",
    Structure => "structure" | "fe",
});

/// The specimen as settings choose it: the model and the geometry of every shape (the
/// configuration's `[specimen] model` and `[specimen.geometry]`; each test mounts the shape of
/// its loading).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpecimenSettings {
    pub model: SpecimenModel,
    pub geometry: SpecimenChoice,
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
    pub model: SpecimenModel,
    /// The geometry of every shape; the loading picks its shape ([`Loading::shape`]), which
    /// `geometry.shape` must name.
    pub geometry: SpecimenChoice,
    pub loading: Loading,
    /// Homogeneous model only (the structure's misalignment, a boundary condition of
    /// `membrane`, is not wired to the rig yet).
    pub misalignment: Misalignment,
    /// Give of each grip under load (mm per kN, ≥ 0): a property of the machine's grips.
    pub grip_compliance_mm_per_kn: f64,
    /// Nominal (first Piola-Kirchhoff) stress at which the sheet tears; 9.5 MPa is the ultimate
    /// strength the manufacturer gives for Smactane™ (paper section 4.a).
    pub break_nominal_stress_mpa: f64,
    /// When the structure is solved, and its Newton settings.
    pub schedule: SolveSchedule,
}

impl Default for SpecimenConfig {
    /// The homogeneous 100 × 100 × 2 mm centre of the default cruciform in equibiaxial tension,
    /// grips giving 1 mm per kN.
    fn default() -> Self {
        SpecimenConfig::of(Loading::Equibiaxial, &SpecimenSettings::default())
    }
}

impl SpecimenConfig {
    /// The specimen `settings` make for `loading`: its shape's geometry, Smactane.
    pub fn of(loading: Loading, settings: &SpecimenSettings) -> SpecimenConfig {
        let mut geometry = settings.geometry.clone();
        geometry.shape = loading.shape();
        SpecimenConfig {
            law: InvariantLaw::smactane(),
            model: settings.model,
            geometry,
            loading,
            misalignment: Misalignment::default(),
            grip_compliance_mm_per_kn: 1.0,
            break_nominal_stress_mpa: 9.5,
            schedule: SolveSchedule::default(),
        }
    }

    /// (gauge length, width, thickness) of the gauge zone, mm: the cruciform's central square,
    /// the strip (along x).
    fn gauge_zone_mm(&self) -> [f64; 3] {
        let g = &self.geometry;
        match g.shape {
            SpecimenShape::Cruciform => {
                let c = &g.cruciform;
                [c.arm_width_mm, c.arm_width_mm, c.thickness_mm]
            }
            SpecimenShape::UniaxialStrip => {
                let s = &g.uniaxial_strip;
                [s.length_mm, s.width_mm, s.thickness_mm]
            }
            SpecimenShape::PlaneStrainStrip => {
                let s = &g.plane_strain_strip;
                [s.length_mm, s.width_mm, s.thickness_mm]
            }
        }
    }

    /// The lengths (mm) the rig divides the X and Y elongations by to speak of a nominal
    /// stretch: the central square's side on the cruciform, the strip's free length along its
    /// pulled axis (its width across).
    pub fn gauge_mm(&self) -> [f64; 2] {
        let [length, width, _] = self.gauge_zone_mm();
        match self.loading {
            Loading::Uniaxial(Axis::Y) => [width, length],
            _ => [length, width],
        }
    }

    /// Reference sections normal to X and Y (mm²) of the gauge zone.
    pub fn reference_sections_mm2(&self) -> [f64; 2] {
        let [length, width, thickness] = self.gauge_zone_mm();
        match self.loading {
            Loading::Equibiaxial => [width * thickness, length * thickness],
            Loading::Uniaxial(Axis::Y) => [length * thickness, width * thickness],
            Loading::Uniaxial(_) => [width * thickness, length * thickness],
        }
    }

    pub fn validate(&self) -> Result<(), SpecimenError> {
        let [length, width, thickness] = self.gauge_zone_mm();
        for (name, v) in [
            ("gauge length_mm", length),
            ("width_mm", width),
            ("thickness_mm", thickness),
            ("break_nominal_stress_mpa", self.break_nominal_stress_mpa),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(SpecimenError::NotPositive { name, value: v });
            }
        }
        if self.loading == Loading::Uniaxial(Axis::Z) {
            return Err(SpecimenError::UniaxialAlongZ);
        }
        if self.geometry.shape != self.loading.shape() {
            return Err(SpecimenError::Shape {
                loading: self.loading.name(),
                shape: self.geometry.shape,
                expected: self.loading.shape(),
            });
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
        let c = self.grip_compliance_mm_per_kn;
        if !(c.is_finite() && (0.0..=100.0).contains(&c)) {
            return Err(SpecimenError::Compliance {
                compliance_mm_per_kn: c,
            });
        }
        if self.model == SpecimenModel::Structure {
            if *m != Misalignment::default() {
                return Err(SpecimenError::StructureMisaligned);
            }
            if self.loading == Loading::Uniaxial(Axis::Y) {
                return Err(SpecimenError::StructureAlongY);
            }
            self.schedule.validate()?;
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
    #[error("grip compliance {compliance_mm_per_kn} mm/kN not in [0, 100]")]
    Compliance { compliance_mm_per_kn: f64 },
    #[error("uniaxial loading is along X or Y (the sheet lies in the X-Y plane)")]
    UniaxialAlongZ,
    #[error("{loading} loading mounts a {expected}, the geometry names a {shape}")]
    Shape {
        loading: String,
        shape: SpecimenShape,
        expected: SpecimenShape,
    },
    #[error("the structure model takes no misalignment yet (rotation and asymmetry are the homogeneous model's)")]
    StructureMisaligned,
    #[error("the structure model's strip is pulled along X")]
    StructureAlongY,
    #[error("solve schedule: {0}")]
    Schedule(#[from] crate::bad_setting::BadSetting),
    #[error("the specimen cannot be meshed or solved at rest: {0}")]
    Structure(#[from] StructureError),
}

/// Result of one evaluation: grip forces (N, tension positive, per actuator) and kinematics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpecimenResponse {
    pub grip_force_n: [f64; ACTUATOR_COUNT],
    pub kinematics: SpecimenKinematics,
    /// The structure's solve failed at this evaluation (its reason: [`Specimen::fault`]); the
    /// specimen carries no force from then on.
    pub failed_now: bool,
}

#[derive(Clone, Debug)]
enum Model {
    Homogeneous(Homogeneous),
    Structure(Box<Structure>),
}

#[derive(Clone, Debug)]
pub struct Specimen {
    config: SpecimenConfig,
    model: Model,
    broken: bool,
}

impl Specimen {
    /// The specimen of `config`, the structure meshed and solved at rest.
    pub fn new(config: SpecimenConfig) -> Result<Specimen, SpecimenError> {
        config.validate()?;
        let model = match config.model {
            SpecimenModel::Homogeneous => Model::Homogeneous(Homogeneous::new(&config)),
            SpecimenModel::Structure => Model::Structure(Box::new(Structure::new(&config)?)),
        };
        Ok(Specimen {
            config,
            model,
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

    /// The structure, if that is the model.
    pub fn structure(&self) -> Option<&Structure> {
        match &self.model {
            Model::Structure(s) => Some(s),
            Model::Homogeneous(_) => None,
        }
    }

    /// The structure, mutably (a test's fresh solve).
    pub fn structure_mut(&mut self) -> Option<&mut Structure> {
        match &mut self.model {
            Model::Structure(s) => Some(s),
            Model::Homogeneous(_) => None,
        }
    }

    /// Why the structure's solve failed, if it did (the specimen carries no force since).
    pub fn fault(&self) -> Option<&SpecimenFault> {
        self.structure().and_then(Structure::fault)
    }

    /// The small-strain map from the nominal log strains of the X and Y elongations (over
    /// [`SpecimenConfig::gauge_mm`]) to the gauge zone's log strains: the own fraction per axis
    /// and the cross term (the mean of both axes'). 1 and 0 on the homogeneous sheet; the
    /// structure's from its tangent at rest (the filmed region's mean F per mm of each grip).
    pub fn gauge_map(&self) -> ([f64; 2], f64) {
        let Some(structure) = self.structure() else {
            return ([1.0, 1.0], 0.0);
        };
        let gauge_mm = self.config.gauge_mm();
        let rest = structure.rest_linearisation();
        // Per mm of elongation of `by` (each of its grips moving half of it): the change of
        // H[axis][axis].
        let per_mm = |axis: usize, by: Axis| -> f64 {
            (0..rest.grips)
                .filter(|&g| {
                    let a = structure.actuator(g);
                    a == by.plus().index() || a == by.minus().index()
                })
                .map(|g| 0.5 * rest.gradient_per_mm[g][axis][axis])
                .sum()
        };
        let own = [
            gauge_mm[0] * per_mm(0, Axis::X),
            gauge_mm[1] * per_mm(1, Axis::Y),
        ];
        let cross = 0.5 * (gauge_mm[1] * per_mm(0, Axis::Y) + gauge_mm[0] * per_mm(1, Axis::X));
        (own, cross)
    }

    /// Current cross-sections normal to X and Y (mm²) at stretches (λx, λy), for Cauchy
    /// stress = force / section: reference section / λ (incompressible sheet). On the
    /// structure, the gauge zone's, at its mean stretches (exact only for a homogeneous
    /// field).
    pub fn current_sections_mm2(&self, stretch_x: f64, stretch_y: f64) -> [f64; 2] {
        let [x, y] = self.config.reference_sections_mm2();
        [x / stretch_x.max(1e-6), y / stretch_y.max(1e-6)]
    }

    /// Grip forces and kinematics at the given grip displacements (mm, outward positive) at
    /// simulated time `t_s`. Allocation-free but for the structure's solves.
    pub fn respond(&mut self, t_s: f64, position_mm: &[f64; ACTUATOR_COUNT]) -> SpecimenResponse {
        if self.broken {
            let mut response = SpecimenResponse::default();
            response.kinematics.broken = true;
            return response;
        }
        let (mut response, peak_nominal_mpa) = match &mut self.model {
            Model::Homogeneous(h) => h.respond(&self.config, position_mm),
            Model::Structure(s) => s.respond(t_s, position_mm),
        };
        if response.failed_now || peak_nominal_mpa >= self.config.break_nominal_stress_mpa {
            self.broken = true;
            let failed_now = response.failed_now;
            response = SpecimenResponse {
                failed_now,
                ..SpecimenResponse::default()
            };
            response.kinematics.broken = true;
        }
        response
    }
}
