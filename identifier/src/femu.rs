//! Finite-element model updating (FEMU, the paper's "inverse analysis" of section 4.c), the
//! reference the virtual fields method (`vfm`) is checked against, offline only
//! (`dicstream identify --fields DIR --femu`).
//!
//! The finite-element problem is the specimen inside the camera's field of view: the cruciform
//! clipped one node step inside the measured grid's outermost nodes
//! (`CruciformGeometry::clipped`, meshed by `membrane` with the run's element size), each arm
//! cut across its straight part. On those cut edges the *measured* displacements are
//! prescribed (each edge node's value a local quadratic fit of the valid nodes around it:
//! [`crate::measured_displacement`]); the arms' sides and fillets are free. Solved with a
//! candidate law, the reaction of each cut edge along its arm is that arm's grip force (a
//! quasi-static membrane with free sides carries the grip's force through every cut), and the
//! computed displacements at the valid interior nodes are compared with the measured ones.
//!
//! Residuals and weights: each force residual (computed − measured, N) divided by the force
//! noise σ_F, each displacement component's (mm) by the displacement noise σ_u
//! ([`FemuSettings`]): dimensionless, commensurate, the maximum-likelihood weighting for
//! independent Gaussian noise of those σ. Under prescribed displacements alone a law scaled by
//! any factor gives the same field: the displacements fix the parameters' ratios, the forces
//! their scale. Levenberg-Marquardt (`lsq::minimise_until`) with a forward finite-difference
//! Jacobian; each frame's solve is warm-started from its last equilibrium (one Newton solve
//! from a nearby law), with load stepping from the previous frame's equilibrium when that
//! fails. The standard deviations are the virtual fields method's: (JᵀJ)⁻¹ times the residual
//! variance, the condition number of the column-scaled Jacobian refused above
//! [`crate::vfm::MAX_CONDITION`].

use crate::field_layout::GRIPS;
use crate::lsq::{
    inverse_normal_matrix, minimise_until, scaled_condition_number, LeastSquares, LmStop, LsqError,
};
use crate::measured_displacement::{DisplacementGrid, MIN_FIT_NODES};
use crate::models::Model;
use membrane::specimens::cruciform::CruciformGeometry;
use membrane::specimens::Specimen;
use membrane::{
    Analysis, Clamp, GeometryError, Held, InvariantDerivatives, Location, Membrane, NewtonSettings,
    PrincipalStresses, RigidMotion, SheetLaw, SolveError, Wrinkling,
};
use nalgebra::{DMatrix, DVector};
use std::cell::RefCell;

/// One frame of the test: its measured displacements and each grip's force.
#[derive(Clone, Debug, PartialEq)]
pub struct FemuFrame {
    pub frame_id: u64,
    pub field: DisplacementGrid,
    /// Grip forces in [`GRIPS`] order (x+, x−, y+, y−), N, tension positive.
    pub forces_n: [f64; 4],
}

/// The model and the weights.
#[derive(Clone, Debug, PartialEq)]
pub struct FemuSettings {
    /// The specimen filmed (outline, thickness) and the model's element size.
    pub cruciform: CruciformGeometry,
    /// Force noise σ_F, N: each force residual is divided by it.
    pub force_sigma_n: f64,
    /// Displacement noise σ_u, mm: each displacement residual is divided by it.
    pub displacement_sigma_mm: f64,
    pub newton: NewtonSettings,
}

impl FemuSettings {
    /// The simulated rig's load cell noise (2 N).
    pub const DEFAULT_FORCE_SIGMA_N: f64 = 2.0;
    /// A correlator's displacement noise floor, px (times the scale for σ_u).
    pub const DEFAULT_DISPLACEMENT_SIGMA_PX: f64 = 0.02;
}

/// Relative step of the forward-difference Jacobian.
const JACOBIAN_STEP: f64 = 1e-5;
/// Load steps of a frame's solve from the previous frame's equilibrium.
const FRAME_LOAD_STEPS: usize = 4;

/// The Levenberg-Marquardt stop of FEMU: residuals from converged Newton iterates are exact to
/// about 1e-10 relative, so a step that lowers the cost by less than 1e-9 is the minimum.
const STOP: LmStop = LmStop {
    max_iterations: 40,
    min_relative_decrease: 1e-9,
    max_rejected: 12,
};

/// Why FEMU identifies nothing.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FemuError {
    #[error("no frame to fit")]
    NoFrames,
    #[error("frame {frame_id}: its field's nodes differ from the first frame's (size, origin or step): the model is meshed once for the view")]
    GridsDiffer { frame_id: u64 },
    #[error(
        "the field of view (nodes x {x_mm:?} mm, y {y_mm:?} mm) crosses no arm of the \
         cruciform beyond its fillets ({straight_mm} mm from the centre): FEMU prescribes the \
         measured displacements where the view's edges cross the arms"
    )]
    NoArmInView {
        x_mm: [f64; 2],
        y_mm: [f64; 2],
        straight_mm: f64,
    },
    #[error("the view's finite-element model: {reason} (FEMU needs the view's edges across all four arms)")]
    Geometry { reason: GeometryError },
    #[error(
        "frame {frame_id}, arm {arm}: fewer than {MIN_FIT_NODES} valid nodes around the edge \
         point ({x_mm:.2}, {y_mm:.2}) mm (within {radius_mm:.2} mm): too few valid boundary \
         nodes to prescribe the measured displacement there"
    )]
    TooFewBoundaryNodes {
        frame_id: u64,
        arm: &'static str,
        x_mm: f64,
        y_mm: f64,
        radius_mm: f64,
    },
    #[error("{name} = {value}: expected a positive finite noise level")]
    Sigma { name: &'static str, value: f64 },
    #[error("{residuals} residuals for {params} parameters: need at least {}", .params + 1)]
    TooFewResiduals { residuals: usize, params: usize },
    #[error(
        "frame {frame_id}: the finite-element solve with {model} at {params:?} failed: {error}"
    )]
    Solve {
        frame_id: u64,
        model: String,
        params: Vec<f64>,
        error: SolveError,
    },
    #[error(transparent)]
    Lsq(#[from] LsqError),
    #[error(
        "the frames do not separate the {params} parameters of {model}: condition number \
         {condition:.3e} > {:e}",
        crate::vfm::MAX_CONDITION
    )]
    NotIdentifiable {
        model: String,
        params: usize,
        condition: f64,
    },
}

/// A frame made ready: its prescribed edge displacements, its grips' edge nodes, the valid
/// interior nodes where the model is compared with the measurement.
struct PreparedFrame {
    frame_id: u64,
    /// One clamp per edge node (its measured displacement).
    clamps: Vec<Clamp>,
    forces_n: [f64; 4],
    /// Where each valid node lies in the model, and its measured displacement, mm.
    interior: Vec<(Location, [f64; 2])>,
}

/// A frame solved: its grips' forces (N, in [`GRIPS`] order) and the displacements at its
/// interior nodes (mm).
type Solved = ([f64; 4], Vec<[f64; 2]>);

/// A grip's measured and computed force at a frame.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FemuBalance {
    pub frame_id: u64,
    pub grip: &'static str,
    pub measured_n: f64,
    pub computed_n: f64,
}

/// The law FEMU identified.
#[derive(Clone, Debug, PartialEq)]
pub struct FemuFit {
    pub params: Vec<f64>,
    pub sigma: Vec<f64>,
    pub condition: f64,
    /// Root mean square of computed minus measured force, N, and displacement, mm.
    pub rms_force_n: f64,
    pub rms_displacement_mm: f64,
    pub force_residuals: usize,
    pub displacement_residuals: usize,
    pub frames: usize,
    pub iterations: usize,
    /// Finite-element solves of all frames (one per evaluation of the residuals).
    pub evaluations: usize,
    pub balance: Vec<FemuBalance>,
}

/// The FEMU problem of a test: the view's model and its frames.
pub struct Femu {
    specimen: Specimen,
    /// Index in [`GRIPS`] of each of the specimen's grips.
    grip_order: Vec<usize>,
    frames: Vec<PreparedFrame>,
    settings: FemuSettings,
    /// Each frame's last equilibrium (a warm start), the solver's symbolic analysis (the
    /// clamped nodes are the same for every frame), evaluations and the last failure.
    solutions: RefCell<Vec<Option<Vec<f64>>>>,
    analysis: RefCell<Analysis>,
    evaluations: RefCell<usize>,
    failure: RefCell<Option<FemuError>>,
}

/// The catalogue model at `p` as the sheet's law (Ogden by its principal stresses).
fn sheet_law<'a>(model: &'a Model, p: &'a [f64]) -> Box<dyn SheetLaw + 'a> {
    match model {
        Model::Ogden(_) => Box::new(PrincipalStresses(move |l1, l2| {
            model.in_plane_cauchy_stress_mpa(p, l1, l2)
        })),
        _ => Box::new(InvariantDerivatives(move |i1, i2| {
            model.invariant_derivatives_mpa(p, i1, i2)
        })),
    }
}

fn positive(name: &'static str, value: f64) -> Result<f64, FemuError> {
    if value > 0.0 && value.is_finite() {
        Ok(value)
    } else {
        Err(FemuError::Sigma { name, value })
    }
}

impl Femu {
    /// The view's model (from the first frame's nodes) and every frame's edge displacements
    /// and interior nodes.
    pub fn new(frames: &[FemuFrame], settings: FemuSettings) -> Result<Self, FemuError> {
        positive("force σ (N)", settings.force_sigma_n)?;
        positive("displacement σ (mm)", settings.displacement_sigma_mm)?;
        let first = &frames.first().ok_or(FemuError::NoFrames)?.field;
        if let Some(other) = frames.iter().find(|f| !f.field.same_nodes(first)) {
            return Err(FemuError::GridsDiffer {
                frame_id: other.frame_id,
            });
        }
        let c = &settings.cruciform;
        // The edges one step inside the outermost nodes: measured nodes on both sides.
        let (x_mm, y_mm) = first.extent_mm();
        let s = first.step_mm;
        let (view_x, view_y) = ([x_mm[0] + s, x_mm[1] - s], [y_mm[0] + s, y_mm[1] - s]);
        let straight_mm = 0.5 * c.arm_width_mm + c.fillet_radius_mm;
        let reaches = [view_x[1], -view_x[0], view_y[1], -view_y[0]];
        if reaches.iter().all(|&r| r.is_nan() || r <= straight_mm) {
            return Err(FemuError::NoArmInView {
                x_mm,
                y_mm,
                straight_mm,
            });
        }
        let specimen = c
            .clipped(view_x, view_y)
            .map_err(|reason| FemuError::Geometry { reason })?;
        let grip_order: Vec<usize> = specimen
            .grips
            .iter()
            .map(|g| GRIPS.iter().position(|&n| n == g.name).unwrap_or(0))
            .collect();
        let elements = membrane::ElementGrid::new(&specimen.mesh);
        let prepared = frames
            .iter()
            .map(|frame| prepare(frame, &specimen, &elements))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Femu {
            grip_order,
            solutions: RefCell::new(vec![None; prepared.len()]),
            frames: prepared,
            specimen,
            settings,
            analysis: RefCell::new(Analysis::default()),
            evaluations: RefCell::new(0),
            failure: RefCell::new(None),
        })
    }

    /// The model's mesh (the cruciform clipped to the view).
    pub fn mesh(&self) -> &membrane::Mesh {
        &self.specimen.mesh
    }

    /// Force residuals (4 a frame) and displacement residuals (2 per interior node).
    pub fn residual_counts(&self) -> (usize, usize) {
        let displacements = self.frames.iter().map(|f| 2 * f.interior.len()).sum();
        (4 * self.frames.len(), displacements)
    }

    /// Solves every frame under `model` at `p`: the grips' computed forces (in [`GRIPS`]
    /// order) and the computed displacements at the interior nodes, frame by frame.
    fn solve_all(&self, model: &Model, p: &[f64]) -> Result<Vec<Solved>, FemuError> {
        *self.evaluations.borrow_mut() += 1;
        let law = sheet_law(model, p);
        let sheet = Membrane::new(
            &self.specimen.mesh,
            self.settings.cruciform.thickness_mm,
            &*law,
            Wrinkling::default(),
        )
        .map_err(|reason| FemuError::Geometry { reason })?;
        let mut solutions = self.solutions.borrow_mut();
        let mut analysis = self.analysis.borrow_mut();
        let mut out = Vec::with_capacity(self.frames.len());
        let mut previous: Option<Vec<f64>> = None;
        for (k, frame) in self.frames.iter().enumerate() {
            let fail = |error: SolveError| FemuError::Solve {
                frame_id: frame.frame_id,
                model: model.name(),
                params: p.to_vec(),
                error,
            };
            let near = NewtonSettings {
                load_steps: 1,
                ..self.settings.newton
            };
            let warm = solutions[k].as_ref().and_then(|start| {
                membrane::solve_from(&sheet, &frame.clamps, start, near, &mut analysis)
                    .ok()
                    .filter(|o| o.stopped.is_none())
            });
            let outcome = match warm {
                Some(outcome) => outcome,
                None => {
                    let start = previous
                        .clone()
                        .unwrap_or_else(|| vec![0.0; self.specimen.mesh.dof_count()]);
                    let stepped = NewtonSettings {
                        load_steps: FRAME_LOAD_STEPS,
                        ..self.settings.newton
                    };
                    let outcome =
                        membrane::solve_from(&sheet, &frame.clamps, &start, stepped, &mut analysis)
                            .map_err(fail)?;
                    if let Some(stopped) = outcome.stopped {
                        return Err(fail(stopped));
                    }
                    outcome
                }
            };
            let solved = outcome.reached;
            let mut forces = [0.0; 4];
            for (grip, &slot) in self.specimen.grips.iter().zip(&self.grip_order) {
                let f = solved.grip_force_n(&grip.nodes);
                forces[slot] = f[0] * grip.axis[0] + f[1] * grip.axis[1];
            }
            let displacements = frame
                .interior
                .iter()
                .map(|(at, _)| {
                    membrane::sample_at(&self.specimen.mesh, &solved.displacement_mm, *at)
                        .map_or([f64::NAN; 2], |s| s.displacement_mm)
                })
                .collect();
            out.push((forces, displacements));
            previous = Some(solved.displacement_mm.clone());
            solutions[k] = Some(solved.displacement_mm);
        }
        Ok(out)
    }

    /// The weighted residuals under `model` at `p`: every frame's four force residuals
    /// (÷ σ_F), then its interior nodes' displacement residuals (÷ σ_u).
    pub fn residuals(&self, model: &Model, p: &[f64]) -> Result<DVector<f64>, FemuError> {
        let solved = self.solve_all(model, p)?;
        let (sf, su) = (
            self.settings.force_sigma_n,
            self.settings.displacement_sigma_mm,
        );
        let (forces, displacements) = self.residual_counts();
        let mut r = Vec::with_capacity(forces + displacements);
        for (frame, (computed, _)) in self.frames.iter().zip(&solved) {
            r.extend((0..4).map(|g| (computed[g] - frame.forces_n[g]) / sf));
        }
        for (frame, (_, computed)) in self.frames.iter().zip(&solved) {
            for ((_, measured), u) in frame.interior.iter().zip(computed) {
                r.extend((0..2).map(|c| (u[c] - measured[c]) / su));
            }
        }
        Ok(DVector::from_vec(r))
    }

    /// Fits `model` from `start`.
    pub fn fit(&self, model: &Model, start: &[f64]) -> Result<FemuFit, FemuError> {
        let n = start.len();
        let (forces, displacements) = self.residual_counts();
        let m = forces + displacements;
        if m <= n {
            return Err(FemuError::TooFewResiduals {
                residuals: m,
                params: n,
            });
        }
        self.residuals(model, start)?;
        let mut objective = Objective {
            femu: self,
            model,
            points: m,
            at: None,
        };
        let lm = minimise_until(&mut objective, start, STOP).map_err(|e| {
            self.failure
                .borrow_mut()
                .take()
                .unwrap_or(FemuError::Lsq(e))
        })?;
        let p = lm.params;
        let j = objective.jacobian(&p)?;
        let condition = scaled_condition_number(&j);
        if condition.is_nan() || condition > crate::vfm::MAX_CONDITION {
            return Err(FemuError::NotIdentifiable {
                model: model.name(),
                params: n,
                condition,
            });
        }
        let solved = self.solve_all(model, &p)?;
        let r = self.residuals(model, &p)?;
        let variance = r.norm_squared() / (m - n) as f64;
        let sigma = match inverse_normal_matrix(&j) {
            Some(cov) => (0..n).map(|k| (cov[(k, k)] * variance).sqrt()).collect(),
            None => vec![f64::INFINITY; n],
        };
        let rms = |from: usize, count: usize, scale: f64| {
            (r.rows(from, count).norm_squared() / count.max(1) as f64).sqrt() * scale
        };
        let balance = self
            .frames
            .iter()
            .zip(&solved)
            .flat_map(|(frame, (computed, _))| {
                (0..4).map(|g| FemuBalance {
                    frame_id: frame.frame_id,
                    grip: GRIPS[g],
                    measured_n: frame.forces_n[g],
                    computed_n: computed[g],
                })
            })
            .collect();
        Ok(FemuFit {
            params: p,
            sigma,
            condition,
            rms_force_n: rms(0, forces, self.settings.force_sigma_n),
            rms_displacement_mm: rms(forces, displacements, self.settings.displacement_sigma_mm),
            force_residuals: forces,
            displacement_residuals: displacements,
            frames: self.frames.len(),
            iterations: lm.iterations,
            evaluations: *self.evaluations.borrow(),
            balance,
        })
    }
}

/// A frame's clamps (its edge nodes at their measured displacements) and interior nodes.
fn prepare(
    frame: &FemuFrame,
    specimen: &Specimen,
    elements: &membrane::ElementGrid,
) -> Result<PreparedFrame, FemuError> {
    let field = &frame.field;
    let mut clamps = vec![];
    for grip in &specimen.grips {
        for &node in &grip.nodes {
            let x = specimen.mesh.nodes_mm[node];
            let u = field.interpolate(x).ok_or(FemuError::TooFewBoundaryNodes {
                frame_id: frame.frame_id,
                arm: grip.name,
                x_mm: x[0],
                y_mm: x[1],
                radius_mm: crate::measured_displacement::FIT_RADII_STEPS[1] * field.step_mm,
            })?;
            clamps.push(Clamp {
                nodes: vec![node],
                held: Held::Both,
                motion: RigidMotion::translation(u),
            });
        }
    }
    let interior = (0..field.displacements_mm.len())
        .filter_map(|k| {
            let u = field.displacements_mm[k]?;
            let at = elements.locate(&specimen.mesh, field.node_mm(k))?;
            Some((at, u))
        })
        .collect();
    Ok(PreparedFrame {
        frame_id: frame.frame_id,
        clamps,
        forces_n: frame.forces_n,
        interior,
    })
}

/// FEMU as Levenberg-Marquardt sees it: the residuals of the last point evaluated kept for
/// its Jacobian.
struct Objective<'f> {
    femu: &'f Femu,
    model: &'f Model,
    points: usize,
    at: Option<(Vec<f64>, DVector<f64>)>,
}

impl Objective<'_> {
    /// The residuals at `p` (kept), the failure kept for the report when a solve fails.
    fn residuals(&mut self, p: &[f64]) -> Option<DVector<f64>> {
        if let Some((q, r)) = &self.at {
            if q == p {
                return Some(r.clone());
            }
        }
        match self.femu.residuals(self.model, p) {
            Ok(r) if r.iter().all(|v| v.is_finite()) => {
                self.at = Some((p.to_vec(), r.clone()));
                Some(r)
            }
            Ok(_) => None,
            Err(e) => {
                *self.femu.failure.borrow_mut() = Some(e);
                None
            }
        }
    }

    /// Forward differences (a backward step where the forward one fails).
    fn jacobian(&mut self, p: &[f64]) -> Result<DMatrix<f64>, FemuError> {
        let r0 = match self.residuals(p) {
            Some(r) => r,
            None => self.femu.residuals(self.model, p)?,
        };
        let mut j = DMatrix::zeros(self.points, p.len());
        for k in 0..p.len() {
            let h = JACOBIAN_STEP * p[k].abs().max(1e-6);
            let mut q = p.to_vec();
            let mut column = None;
            for step in [h, -h] {
                q[k] = p[k] + step;
                if let Ok(r) = self.femu.residuals(self.model, &q) {
                    column = Some((r - &r0) / step);
                    break;
                }
            }
            if let Some(column) = column {
                j.set_column(k, &column);
            }
        }
        Ok(j)
    }
}

impl LeastSquares for Objective<'_> {
    fn points(&self) -> usize {
        self.points
    }

    fn cost(&mut self, p: &[f64]) -> Option<f64> {
        self.residuals(p).map(|r| r.norm_squared())
    }

    fn normal_equations(&mut self, p: &[f64], jtj: &mut DMatrix<f64>, jtr: &mut DVector<f64>) {
        let r = self.residuals(p);
        match (self.jacobian(p), r) {
            (Ok(j), Some(r)) => {
                *jtj = j.transpose() * &j;
                *jtr = j.transpose() * r;
            }
            _ => {
                jtj.fill(0.0);
                jtr.fill(0.0);
            }
        }
    }
}
