//! The specimen as a finite-element structure (`membrane`): each actuator drives the axial
//! translation of its grip (cruciform: x+, y+, x−, y−; uniaxial strip: x−, x+), the sheet is
//! solved on a deterministic schedule of simulated time, warm-started from the last
//! equilibrium, and followed between two solves by the tangent condensed on the grips
//! ([`super::condensed`]).
//!
//! Schedule ([`SolveSchedule`]): a solve when a grip has moved more than `move_tolerance_mm`
//! (1 mm) since the last solve, or `interval_s` (0.1 s) of simulated time after it if a grip
//! has moved more than `still_mm` (0.05 mm); a rig holding still does not solve. Everything
//! depends on simulated time and positions only, so a replay solves at the same steps with the
//! same bits (faer runs sequentially). A solve that fails (Newton out of iterations after its load sub-steps, an
//! element inverted, the law outside its domain, an unstable tangent) gives no force: the
//! fault names the solve, the grips and the reason ([`SpecimenFault`]) and the specimen
//! unloads as a torn one (the rig trips its break bit and holds).
//!
//! The camera's kinematics are the filmed region's mean F (the cruciform's central square, the
//! middle half of the strip's length), split into stretch and rotation by its polar
//! decomposition, and its mean displacement as the centre; [`Structure::solved`] gives the last
//! solved state itself (mesh, nodal displacements, solve id) for a later `specimen` service.

use super::condensed::{Linearisation, Predicted, MAX_GRIPS};
use super::{SpecimenConfig, SpecimenResponse};
use crate::bad_setting::BadSetting;
use crate::hydraulics::ACTUATOR_COUNT;
use crate::ids::Axis;
use crate::snapshot::SpecimenKinematics;
use material::InvariantLaw;
use membrane::specimens::Specimen as Meshed;
use membrane::{
    condense, solve_from, Analysis, Equilibrium, GeometryError, Membrane, Mesh, NewtonSettings,
    Region, SolveError, SpecimenShape, Wrinkling,
};

/// When the structure is solved, and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveSchedule {
    /// A moving grip is re-solved this long (simulated s) after the last solve.
    pub interval_s: f64,
    /// A grip that moved more than this (mm) since the last solve is re-solved at once.
    pub move_tolerance_mm: f64,
    /// Grips that moved less than this (mm) since the last solve are not re-solved at the
    /// interval (the prediction's error, second order in the travel, is then below 1e-3 N).
    pub still_mm: f64,
    /// Newton from the last equilibrium: `load_steps` increments first, halved on a failure
    /// up to `max_step_cuts` times (load sub-stepping).
    pub newton: NewtonSettings,
}

impl Default for SolveSchedule {
    /// Every 100 ms of a test moving its grips by more than 0.05 mm, or after 1 mm of travel; one Newton increment from
    /// the last equilibrium, sub-stepped down to 1/256 of it on failure; converged at a
    /// residual of 0.01 N (or 1e-10 of the reactions): 200 times below the load cells' 2 N of
    /// noise, so the forces err by less than the noise can show, and reached in one or two
    /// iterations where the sheet wrinkles (most of a uniaxial strip sits on the taut-wrinkled
    /// boundary, σ2 = 0, where the tangent is not smooth and Newton creeps).
    fn default() -> Self {
        SolveSchedule {
            interval_s: 0.1,
            move_tolerance_mm: 1.0,
            still_mm: 0.05,
            newton: NewtonSettings {
                load_steps: 1,
                absolute_tolerance_n: 1e-2,
                ..NewtonSettings::default()
            },
        }
    }
}

impl SolveSchedule {
    pub fn validate(&self) -> Result<(), BadSetting> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.interval_s) {
            return Err(BadSetting::new(
                "interval_s",
                self.interval_s,
                "a positive time",
            ));
        }
        if !positive(self.move_tolerance_mm) {
            return Err(BadSetting::new(
                "move_tolerance_mm",
                self.move_tolerance_mm,
                "a positive length",
            ));
        }
        if !(self.still_mm.is_finite() && self.still_mm >= 0.0) {
            return Err(BadSetting::new("still_mm", self.still_mm, "a length ≥ 0"));
        }
        let n = &self.newton;
        if n.max_iterations == 0 || n.load_steps == 0 {
            return Err(BadSetting::new(
                "newton",
                (n.max_iterations, n.load_steps),
                "at least one iteration and one load step",
            ));
        }
        Ok(())
    }
}

/// Why the structure could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StructureError {
    #[error("{shape}: {error}")]
    Geometry {
        shape: SpecimenShape,
        error: GeometryError,
    },
    #[error("{shape} at rest: {error}")]
    Solve {
        shape: SpecimenShape,
        error: SolveError,
    },
    #[error("the {shape} has no grip {name}")]
    Grip {
        shape: SpecimenShape,
        name: &'static str,
    },
}

/// A solve that failed: which, where the grips were, why. No force of it is reported.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("specimen solve {solve} at t = {t_s:.4} s (grips {grips}) failed (the last converged is solve {converged}): {error}")]
pub struct SpecimenFault {
    /// The failed solve's id (one more than the last converged).
    pub solve: u64,
    pub converged: u64,
    pub t_s: f64,
    /// `x+ 12.3 mm, y+ 12.3 mm, ...`
    pub grips: String,
    pub error: SolveError,
}

/// Counts of the solves so far.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolverFigures {
    /// Converged solves, the one at rest included.
    pub solves: u64,
    pub newton_iterations: u64,
    /// Load increments (more than the solves when sub-stepping cut one).
    pub load_steps: u64,
    /// The most Newton iterations one solve took.
    pub max_iterations_per_solve: u64,
}

/// The last solved state, for the camera's side (the `specimen` service): the reference mesh,
/// the nodal displacements, the grips' displacement modes and an id that grows with each solve.
#[derive(Clone, Copy, Debug)]
pub struct SolvedState<'a> {
    /// 0 at rest, then one more per converged solve.
    pub id: u64,
    pub t_s: f64,
    pub mesh: &'a Mesh,
    /// Two per node, mm.
    pub displacement_mm: &'a [f64],
    /// Grip names in the order of `grip_force_n` and `grip_mm`.
    pub grip_names: [&'static str; MAX_GRIPS],
    pub grips: usize,
    pub grip_mm: &'a [f64; MAX_GRIPS],
    pub grip_force_n: &'a [f64; MAX_GRIPS],
    /// Per grip: the nodal displacement per mm of its axial motion (two per node, mm/mm).
    pub modes: &'a [Vec<f64>],
}

#[derive(Clone, Debug)]
pub struct Structure {
    meshed: Meshed,
    law: InvariantLaw,
    /// The actuator driving each grip.
    actuators: [usize; MAX_GRIPS],
    /// Reference section of each grip's arm (mm²), for the break stress.
    sections_mm2: [f64; MAX_GRIPS],
    region: Region,
    compliance_mm_per_n: f64,
    schedule: SolveSchedule,
    id: u64,
    solved_t_s: f64,
    equilibrium: Equilibrium,
    linear: Linearisation,
    /// The linearisation at rest (the small-strain stiffness), where a slack sheet goes back.
    rest: Linearisation,
    /// The grips' displacement modes at the last solve, and at rest.
    modes: Vec<Vec<f64>>,
    rest_modes: Vec<Vec<f64>>,
    /// No grip pulls: the sheet is slack, at rest.
    slack: bool,
    /// Each grip's reference distance from the specimen's centre along its axis (mm).
    distance_mm: [f64; MAX_GRIPS],
    fault: Option<SpecimenFault>,
    figures: SolverFigures,
    /// The sparse factorisation's symbolic analysis, the same for every solve.
    analysis: Analysis,
}

/// The actuator of grip `name`.
fn actuator_of(name: &str) -> Option<usize> {
    let axis = match &name[..1] {
        "x" => Axis::X,
        "y" => Axis::Y,
        _ => return None,
    };
    match &name[1..] {
        "+" => Some(axis.plus().index()),
        "-" => Some(axis.minus().index()),
        _ => None,
    }
}

impl Structure {
    /// Meshes the specimen of `config` and solves it at rest.
    pub fn new(config: &SpecimenConfig) -> Result<Structure, StructureError> {
        let shape = config.geometry.shape;
        let meshed = config
            .geometry
            .mesh()
            .map_err(|error| StructureError::Geometry { shape, error })?;
        if meshed.grips.len() > MAX_GRIPS {
            return Err(StructureError::Grip { shape, name: "" });
        }
        let mut actuators = [0; MAX_GRIPS];
        for (slot, grip) in actuators.iter_mut().zip(&meshed.grips) {
            *slot = actuator_of(grip.name).ok_or(StructureError::Grip {
                shape,
                name: grip.name,
            })?;
        }
        // The filmed region and each grip's section.
        let (region, section_mm2) = match shape {
            SpecimenShape::Cruciform => {
                let c = &config.geometry.cruciform;
                let half = 0.5 * c.arm_width_mm * (1.0 + 1e-9);
                let region = Region::new(&meshed.mesh, |p| p[0].abs() < half && p[1].abs() < half);
                (region, c.arm_width_mm * c.thickness_mm)
            }
            SpecimenShape::UniaxialStrip | SpecimenShape::PlaneStrainStrip => {
                let s = if shape == SpecimenShape::UniaxialStrip {
                    &config.geometry.uniaxial_strip
                } else {
                    &config.geometry.plane_strain_strip
                };
                let quarter = 0.25 * s.length_mm;
                (
                    Region::new(&meshed.mesh, |p| p[0].abs() < quarter),
                    s.width_mm * s.thickness_mm,
                )
            }
        };
        let region = region.map_err(|error| StructureError::Geometry { shape, error })?;
        let law = config.law.clone();
        Membrane::new(
            &meshed.mesh,
            meshed.thickness_mm,
            &law,
            Wrinkling::default(),
        )
        .map_err(|error| StructureError::Geometry { shape, error })?;
        let start = vec![0.0; meshed.mesh.dof_count()];
        let mut distance_mm = [0.0; MAX_GRIPS];
        for (slot, g) in distance_mm.iter_mut().zip(&meshed.grips) {
            *slot = g.centre_mm[0] * g.axis[0] + g.centre_mm[1] * g.axis[1];
        }
        let mut structure = Structure {
            rest: Linearisation::at_rest(meshed.grips.len()),
            modes: Vec::new(),
            rest_modes: Vec::new(),
            slack: false,
            distance_mm,
            linear: Linearisation::at_rest(meshed.grips.len()),
            meshed,
            law,
            actuators,
            sections_mm2: [section_mm2; MAX_GRIPS],
            region,
            compliance_mm_per_n: config.grip_compliance_mm_per_kn * 1e-3,
            schedule: config.schedule,
            id: 0,
            solved_t_s: 0.0,
            equilibrium: Equilibrium {
                load_factor: 1.0,
                displacement_mm: start,
                nodal_forces_n: Vec::new(),
                steps: Vec::new(),
                free_dofs: 0,
            },
            fault: None,
            figures: SolverFigures::default(),
            analysis: Analysis::default(),
        };
        structure
            .solve_at(0.0, &[0.0; MAX_GRIPS])
            .map_err(|error| StructureError::Solve { shape, error })?;
        structure.id = 0;
        structure.rest = structure.linear.clone();
        structure.rest_modes = structure.modes.clone();
        Ok(structure)
    }

    pub fn fault(&self) -> Option<&SpecimenFault> {
        self.fault.as_ref()
    }

    pub fn figures(&self) -> SolverFigures {
        self.figures
    }

    pub fn schedule(&self) -> &SolveSchedule {
        &self.schedule
    }

    /// The linearisation at rest: the small-strain stiffness and grips-to-gauge map.
    pub fn rest_linearisation(&self) -> &Linearisation {
        &self.rest
    }

    /// The actuator (index) driving grip `grip`.
    pub fn actuator(&self, grip: usize) -> usize {
        self.actuators[grip]
    }

    /// The last converged linearisation (forces and tangent at the last solve).
    pub fn linearisation(&self) -> &Linearisation {
        &self.linear
    }

    pub fn mesh(&self) -> &Mesh {
        &self.meshed.mesh
    }

    /// The last solved state.
    pub fn solved(&self) -> SolvedState<'_> {
        let mut grip_names = [""; MAX_GRIPS];
        for (slot, grip) in grip_names.iter_mut().zip(&self.meshed.grips) {
            *slot = grip.name;
        }
        SolvedState {
            id: self.id,
            t_s: self.solved_t_s,
            mesh: &self.meshed.mesh,
            displacement_mm: &self.equilibrium.displacement_mm,
            grip_names,
            grips: self.linear.grips,
            grip_mm: &self.linear.grip_mm,
            grip_force_n: &self.linear.force_n,
            modes: &self.modes,
        }
    }

    /// The grips' axial displacements (mm) at the rig's actuator positions: the prediction's,
    /// or the positions themselves while the sheet is slack (no force, no give). With
    /// [`Structure::solved`], what the camera films: the solve followed to these grips through
    /// its modes (`membrane::GripLinearField`).
    pub fn grip_mm_at(&self, position_mm: &[f64; ACTUATOR_COUNT]) -> [f64; MAX_GRIPS] {
        if self.slack {
            self.positions(position_mm)
        } else {
            self.predict(position_mm).grip_mm
        }
    }

    /// The grips' actuator positions (mm) from the rig's six.
    fn positions(&self, position_mm: &[f64; ACTUATOR_COUNT]) -> [f64; MAX_GRIPS] {
        let mut x = [0.0; MAX_GRIPS];
        for g in 0..self.linear.grips {
            x[g] = position_mm[self.actuators[g]];
        }
        x
    }

    /// The prediction at the rig's actuator positions, without solving.
    pub fn predict(&self, position_mm: &[f64; ACTUATOR_COUNT]) -> Predicted {
        self.linear
            .predict(&self.positions(position_mm), self.compliance_mm_per_n)
    }

    /// Solves now at the rig's actuator positions (the grips' give from the present
    /// prediction), whatever the schedule says: a test's fresh solve.
    pub fn solve_now(
        &mut self,
        t_s: f64,
        position_mm: &[f64; ACTUATOR_COUNT],
    ) -> Result<(), SolveError> {
        let p = self.predict(position_mm);
        self.solve_at(t_s, &p.grip_mm)
    }

    /// Is a solve due at `t_s` for the predicted grips?
    fn due(&self, t_s: f64, p: &Predicted) -> bool {
        let moved = (0..self.linear.grips)
            .map(|g| (p.grip_mm[g] - self.linear.grip_mm[g]).abs())
            .fold(0.0, f64::max);
        moved > self.schedule.move_tolerance_mm
            || (moved > self.schedule.still_mm
                && t_s - self.solved_t_s >= self.schedule.interval_s * (1.0 - 1e-9))
    }

    /// Forces and kinematics at `t_s`, solving first when the schedule says so; and the
    /// peak nominal stress (MPa) of the arms, for the break.
    pub fn respond(
        &mut self,
        t_s: f64,
        position_mm: &[f64; ACTUATOR_COUNT],
    ) -> (SpecimenResponse, f64) {
        let x = self.positions(position_mm);
        let grips = self.linear.grips;
        // No grip pulls: the sheet is slack (a stress-free contraction fits any inward grips),
        // no force, nothing to solve; it starts again from rest when a grip pulls.
        if x[..grips].iter().all(|&q| q <= 0.0) {
            if !self.slack {
                self.slack = true;
                if self.linear != self.rest {
                    self.linear = self.rest.clone();
                    self.modes = self.rest_modes.clone();
                    self.equilibrium.displacement_mm.fill(0.0);
                    self.solved_t_s = t_s;
                    self.id += 1;
                }
            }
            return (self.slack_response(&x), 0.0);
        }
        self.slack = false;
        let mut p = self.linear.predict(&x, self.compliance_mm_per_n);
        if self.fault.is_none() && self.due(t_s, &p) {
            match self.solve_at(t_s, &p.grip_mm) {
                Ok(()) => p = self.linear.predict(&x, self.compliance_mm_per_n),
                Err(error) => {
                    self.fault = Some(SpecimenFault {
                        solve: self.id + 1,
                        converged: self.id,
                        t_s,
                        grips: self.describe(&p.grip_mm),
                        error,
                    });
                }
            }
        }
        if self.fault.is_some() {
            let response = SpecimenResponse {
                failed_now: true,
                ..SpecimenResponse::default()
            };
            return (response, 0.0);
        }
        let mut response = SpecimenResponse {
            kinematics: kinematics(&p),
            ..SpecimenResponse::default()
        };
        let mut peak = 0.0f64;
        for g in 0..self.linear.grips {
            response.grip_force_n[self.actuators[g]] = p.force_n[g];
            peak = peak.max(p.force_n[g] / self.sections_mm2[g]);
        }
        (response, peak)
    }

    /// A slack sheet's kinematics: the stress-free contraction to the grips (the mean of each
    /// pair's displacements over its distance), no force.
    fn slack_response(&self, x: &[f64; MAX_GRIPS]) -> SpecimenResponse {
        let mut stretch = [1.0; 2];
        let mut centre_mm = [0.0; 2];
        for (g, grip) in self.meshed.grips.iter().enumerate() {
            let axis = usize::from(grip.axis[1].abs() > grip.axis[0].abs());
            let sign = grip.axis[axis];
            stretch[axis] += 0.5 * x[g] / self.distance_mm[g];
            centre_mm[axis] += 0.5 * sign * x[g];
        }
        SpecimenResponse {
            kinematics: SpecimenKinematics {
                stretch_x: stretch[0],
                stretch_y: stretch[1],
                rotation_deg: 0.0,
                centre_x_mm: centre_mm[0],
                centre_y_mm: centre_mm[1],
                broken: false,
            },
            ..SpecimenResponse::default()
        }
    }

    fn describe(&self, grip_mm: &[f64; MAX_GRIPS]) -> String {
        self.meshed
            .grips
            .iter()
            .zip(grip_mm)
            .map(|(g, q)| format!("{} {q:.4} mm", g.name))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Solves at grip displacements `grip_mm` from the last equilibrium and linearises there.
    fn solve_at(&mut self, t_s: f64, grip_mm: &[f64; MAX_GRIPS]) -> Result<(), SolveError> {
        let clamps: Vec<_> = self
            .meshed
            .grips
            .iter()
            .zip(grip_mm)
            .map(|(g, &q)| g.clamp(q, 0.0))
            .collect();
        let membrane = Membrane::new(
            &self.meshed.mesh,
            self.meshed.thickness_mm,
            &self.law,
            Wrinkling::default(),
        )
        .expect("the mesh and thickness made a membrane when the structure was built");
        let outcome = solve_from(
            &membrane,
            &clamps,
            &self.equilibrium.displacement_mm,
            self.schedule.newton,
            &mut self.analysis,
        )?;
        if let Some(error) = outcome.stopped {
            return Err(error);
        }
        let equilibrium = outcome.reached;
        let condensed = condense(
            &membrane,
            &clamps,
            &equilibrium,
            &self.meshed.grips,
            &mut self.analysis,
        )?;
        let grips = self.linear.grips;
        let mut linear = Linearisation {
            grips,
            grip_mm: *grip_mm,
            force_n: [0.0; MAX_GRIPS],
            stiffness_n_per_mm: [[0.0; MAX_GRIPS]; MAX_GRIPS],
            gradient: self
                .region
                .mean_displacement_gradient(&equilibrium.displacement_mm),
            gradient_per_mm: [[[0.0; 2]; 2]; MAX_GRIPS],
            centre_mm: self
                .region
                .mean_displacement_mm(&equilibrium.displacement_mm),
            centre_per_mm: [[0.0; 2]; MAX_GRIPS],
        };
        for (g, grip) in self.meshed.grips.iter().enumerate() {
            let f = equilibrium.grip_force_n(&grip.nodes);
            linear.force_n[g] = f[0] * grip.axis[0] + f[1] * grip.axis[1];
            for b in 0..grips {
                linear.stiffness_n_per_mm[g][b] = condensed.stiffness_n_per_mm[g][b];
            }
            linear.gradient_per_mm[g] = self.region.mean_displacement_gradient(&condensed.modes[g]);
            linear.centre_per_mm[g] = self.region.mean_displacement_mm(&condensed.modes[g]);
        }
        let iterations: usize = equilibrium.steps.iter().map(|s| s.residuals_n.len()).sum();
        self.figures.solves += 1;
        self.figures.newton_iterations += iterations as u64;
        self.figures.load_steps += equilibrium.steps.len() as u64;
        self.figures.max_iterations_per_solve =
            self.figures.max_iterations_per_solve.max(iterations as u64);
        self.id += 1;
        self.solved_t_s = t_s;
        self.equilibrium = equilibrium;
        self.linear = linear;
        self.modes = condensed.modes;
        Ok(())
    }
}

/// The camera's kinematics of a prediction: the polar decomposition F = R U of the filmed
/// region's mean F, stretches the diagonal of U, rotation the angle of R.
fn kinematics(p: &Predicted) -> SpecimenKinematics {
    let h = p.gradient;
    let f = [[1.0 + h[0][0], h[0][1]], [h[1][0], 1.0 + h[1][1]]];
    let angle = (f[1][0] - f[0][1]).atan2(f[0][0] + f[1][1]);
    let (s, c) = angle.sin_cos();
    // U = Rᵀ F.
    let u00 = c * f[0][0] + s * f[1][0];
    let u11 = -s * f[0][1] + c * f[1][1];
    SpecimenKinematics {
        stretch_x: u00,
        stretch_y: u11,
        rotation_deg: angle.to_degrees(),
        centre_x_mm: p.centre_mm[0],
        centre_y_mm: p.centre_mm[1],
        broken: false,
    }
}
