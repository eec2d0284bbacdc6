//! Static equilibrium of the clamped sheet: load stepping (clamp motions ramped), Newton with
//! the consistent tangent and a backtracking line search, the load step halved when an
//! increment fails and doubled back after two that converge. The stiffness of a stable hyperelastic membrane with clamps is symmetric
//! positive definite, so it is factorised by `faer`'s sparse Cholesky (supernodal, fill-reducing
//! ordering, the symbolic analysis done once per solve): a failed factorisation is the
//! structure or the law losing stability, reported as such instead of stepping on with an
//! indefinite matrix. Each step's residual norms are recorded.

use crate::assembly::{Evaluation, FailureAt, Membrane};
use crate::boundary::Clamp;
use crate::constitutive::{PointFailure, StateCount};
use crate::error::SolveError;
use crate::law::SheetLaw;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{CreationError, SparseColMat, Triplet};
use faer::{Mat, Side};

/// Newton and load stepping settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonSettings {
    /// Newton iterations per load step.
    pub max_iterations: usize,
    /// Converged when ‖R_free‖ ≤ max(absolute, relative × ‖reactions‖).
    pub relative_tolerance: f64,
    pub absolute_tolerance_n: f64,
    /// Initial number of equal load steps.
    pub load_steps: usize,
    /// Halvings of the initial load step allowed: a step that fails at 1/2^cuts of the initial
    /// one stops the load (the step grows back by doubling after two converged steps).
    pub max_step_cuts: usize,
    /// Halvings of the Newton step in the line search.
    pub line_search_halvings: usize,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        NewtonSettings {
            max_iterations: 25,
            relative_tolerance: 1e-10,
            absolute_tolerance_n: 1e-9,
            load_steps: 10,
            max_step_cuts: 8,
            line_search_halvings: 12,
        }
    }
}

/// One converged load step.
#[derive(Clone, Debug, PartialEq)]
pub struct StepRecord {
    pub load_factor: f64,
    /// ‖R_free‖ (N) at each Newton iterate after the predictor, the last one converged.
    pub residuals_n: Vec<f64>,
    /// Line-search factor taken at each iteration.
    pub step_lengths: Vec<f64>,
    pub states: StateCount,
}

/// A converged equilibrium: only these give forces.
#[derive(Clone, Debug, PartialEq)]
pub struct Equilibrium {
    pub load_factor: f64,
    /// Nodal displacements, mm (x, y per node).
    pub displacement_mm: Vec<f64>,
    /// Internal nodal forces, N: at clamped DOFs, the force the grip applies to the sheet.
    pub nodal_forces_n: Vec<f64>,
    pub steps: Vec<StepRecord>,
    /// Free degrees of freedom of the linear systems.
    pub free_dofs: usize,
}

impl Equilibrium {
    /// Resultant force (N) that the grip holding `nodes` applies to the sheet.
    pub fn grip_force_n(&self, nodes: &[usize]) -> [f64; 2] {
        let mut f = [0.0; 2];
        for &n in nodes {
            f[0] += self.nodal_forces_n[2 * n];
            f[1] += self.nodal_forces_n[2 * n + 1];
        }
        f
    }
}

/// Where a failed increment stopped (the load factor is filled in by the caller).
pub(crate) enum Failure {
    Point(FailureAt),
    NotConverged {
        iterations: usize,
        residual_n: f64,
        tolerance_n: f64,
    },
    Unstable {
        pivot: usize,
    },
    Factorisation(CreationError),
}

impl Failure {
    pub(crate) fn into_error(self, load_factor: f64, converged_load_factor: f64) -> SolveError {
        match self {
            Failure::Point(FailureAt {
                element,
                point,
                failure: PointFailure::Inverted { det_c },
            }) => SolveError::ElementInverted {
                element,
                point,
                det_c,
                load_factor,
                converged_load_factor,
            },
            Failure::Point(FailureAt {
                element,
                failure: PointFailure::OutsideDomain { i1, i2 },
                ..
            }) => SolveError::OutsideLawDomain {
                element,
                i1,
                i2,
                load_factor,
                converged_load_factor,
            },
            Failure::NotConverged {
                iterations,
                residual_n,
                tolerance_n,
            } => SolveError::NotConverged {
                iterations,
                residual_n,
                tolerance_n,
                load_factor,
                converged_load_factor,
            },
            Failure::Unstable { pivot } => SolveError::Unstable {
                pivot,
                load_factor,
                converged_load_factor,
            },
            Failure::Factorisation(cause) => SolveError::Factorisation { cause },
        }
    }
}

struct Solver<'m, 'a, L: SheetLaw + ?Sized> {
    membrane: &'m Membrane<'a, L>,
    clamps: &'m [Clamp],
    settings: NewtonSettings,
    /// Free index of each DOF, `None` if prescribed.
    free: Vec<Option<usize>>,
    free_count: usize,
    symbolic: Option<SymbolicLlt<usize>>,
    /// A warm start: the displacement the load starts from, and the clamps' prescribed values
    /// at its end (the prescribed DOFs go linearly from one to the other with the load factor).
    /// None: from the reference, the clamps' own motion scaled by the load factor.
    warm: Option<WarmStart>,
}

struct WarmStart {
    start_mm: Vec<f64>,
    end_mm: Vec<(usize, f64)>,
}

/// Solves the clamped sheet up to load factor 1: its equilibrium there, or why it stopped.
pub fn solve<L: SheetLaw + ?Sized>(
    membrane: &Membrane<'_, L>,
    clamps: &[Clamp],
    settings: NewtonSettings,
) -> Result<Equilibrium, SolveError> {
    let outcome = solve_until_stopped(membrane, clamps, settings)?;
    match outcome.stopped {
        Some(error) => Err(error),
        None => Ok(outcome.reached),
    }
}

/// How far a load went: the last converged equilibrium (at load factor 1 if it went through,
/// else where it stopped, with its forces) and, if it stopped, why.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub reached: Equilibrium,
    pub stopped: Option<SolveError>,
}

/// [`solve`], keeping the last converged equilibrium when the load stops on the way; an error
/// only for clamps that cannot be applied.
pub fn solve_until_stopped<L: SheetLaw + ?Sized>(
    membrane: &Membrane<'_, L>,
    clamps: &[Clamp],
    settings: NewtonSettings,
) -> Result<Outcome, SolveError> {
    let free = FreeDofs::of(membrane, clamps)?;
    Solver::new(membrane, clamps, settings, free, None).map(|mut solver| solver.run())
}

/// The sparse Cholesky's symbolic analysis (fill-reducing ordering, supernodes) of a mesh with
/// a set of clamped DOFs, kept between the solves of a moving grip: it depends on the pattern
/// only, and is made again when the clamped DOFs differ from those it was made for.
#[derive(Clone, Debug, Default)]
pub struct Analysis {
    free: Vec<Option<usize>>,
    symbolic: Option<SymbolicLlt<usize>>,
}

impl Analysis {
    /// The symbolic analysis for `free`, if this one was made for it.
    pub(crate) fn take_for(&mut self, free: &[Option<usize>]) -> Option<SymbolicLlt<usize>> {
        if self.free == free {
            self.symbolic.take()
        } else {
            None
        }
    }

    pub(crate) fn keep(&mut self, free: &[Option<usize>], symbolic: Option<SymbolicLlt<usize>>) {
        if symbolic.is_some() {
            self.free = free.to_vec();
            self.symbolic = symbolic;
        }
    }
}

/// [`solve_until_stopped`] warm-started from the displacement `start_mm` (a converged
/// equilibrium of the same clamped nodes, e.g. the previous solve of a moving grip): load
/// factor 0 is `start_mm`, load factor 1 the clamps' motion at full load, the clamped DOFs in
/// between on the straight line from one to the other. The load is first taken in
/// `settings.load_steps` increments (1: a single Newton solve from the start), cut in halves
/// when an increment fails (load sub-stepping).
/// `analysis` is the symbolic factorisation of earlier solves of the same clamped nodes (an
/// empty one the first time): reused, or made and kept.
pub fn solve_from<L: SheetLaw + ?Sized>(
    membrane: &Membrane<'_, L>,
    clamps: &[Clamp],
    start_mm: &[f64],
    settings: NewtonSettings,
    analysis: &mut Analysis,
) -> Result<Outcome, SolveError> {
    let free = FreeDofs::of(membrane, clamps)?;
    if start_mm.len() != free.free.len() {
        return Err(SolveError::StartLength {
            values: start_mm.len(),
            dofs: free.free.len(),
        });
    }
    let nodes = &membrane.mesh.nodes_mm;
    let warm = WarmStart {
        start_mm: start_mm.to_vec(),
        end_mm: clamps
            .iter()
            .flat_map(|c| c.prescribed(nodes, 1.0))
            .collect(),
    };
    let symbolic = analysis.take_for(&free.free);
    let mut solver = Solver::new(membrane, clamps, settings, free, Some(warm))?;
    solver.symbolic = symbolic;
    let outcome = solver.run();
    analysis.keep(&solver.free, solver.symbolic.take());
    Ok(outcome)
}

/// Which DOFs the clamps hold, and the index of each free one in the linear systems.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FreeDofs {
    /// Free index of each DOF, `None` if prescribed.
    pub free: Vec<Option<usize>>,
    pub count: usize,
}

impl FreeDofs {
    pub(crate) fn of<L: SheetLaw + ?Sized>(
        membrane: &Membrane<'_, L>,
        clamps: &[Clamp],
    ) -> Result<FreeDofs, SolveError> {
        let nodes = membrane.mesh.nodes_mm.len();
        if clamps.iter().all(|c| c.nodes.is_empty()) {
            return Err(SolveError::NoClamp);
        }
        let mut free = vec![Some(0); 2 * nodes];
        for clamp in clamps {
            if let Some(&node) = clamp.nodes.iter().find(|&&n| n >= nodes) {
                return Err(SolveError::UnknownNode { node, nodes });
            }
            for (dof, _) in clamp.prescribed(&membrane.mesh.nodes_mm, 0.0) {
                free[dof] = None;
            }
        }
        let mut count = 0;
        for slot in free.iter_mut().flatten() {
            *slot = count;
            count += 1;
        }
        Ok(FreeDofs { free, count })
    }
}

fn norm(v: impl Iterator<Item = f64>) -> f64 {
    v.map(|x| x * x).sum::<f64>().sqrt()
}

impl<'m, 'a, L: SheetLaw + ?Sized> Solver<'m, 'a, L> {
    fn new(
        membrane: &'m Membrane<'a, L>,
        clamps: &'m [Clamp],
        settings: NewtonSettings,
        free: FreeDofs,
        warm: Option<WarmStart>,
    ) -> Result<Self, SolveError> {
        Ok(Solver {
            membrane,
            clamps,
            settings,
            free: free.free,
            free_count: free.count,
            symbolic: None,
            warm,
        })
    }

    fn run(&mut self) -> Outcome {
        let mut u = match &self.warm {
            Some(warm) => warm.start_mm.clone(),
            None => vec![0.0; self.free.len()],
        };
        let mut converged = 0.0;
        let initial = 1.0 / self.settings.load_steps.max(1) as f64;
        // The smallest step: a failure there stops the load (no creeping towards a limit).
        let smallest = initial / 2f64.powi(self.settings.max_step_cuts.min(60) as i32);
        let mut increment = initial;
        let mut successes = 0;
        let mut steps = Vec::new();
        let mut forces = vec![0.0; self.free.len()];
        let mut stopped = None;
        while converged < 1.0 {
            let target = if converged + increment > 1.0 - 1e-12 {
                1.0
            } else {
                converged + increment
            };
            match self.increment(&u, target) {
                Ok((u_new, evaluation, record)) => {
                    u = u_new;
                    forces = evaluation.forces_n;
                    converged = target;
                    steps.push(record);
                    // Two good steps in a row after a cut: the step grows back.
                    successes += 1;
                    if successes >= 2 && increment < initial {
                        increment = (2.0 * increment).min(initial);
                        successes = 0;
                    }
                }
                Err(failure) if increment <= smallest * (1.0 + 1e-9) => {
                    stopped = Some(failure.into_error(target, converged));
                    break;
                }
                Err(_) => {
                    increment *= 0.5;
                    successes = 0;
                }
            }
        }
        Outcome {
            reached: Equilibrium {
                load_factor: converged,
                displacement_mm: u,
                nodal_forces_n: forces,
                steps,
                free_dofs: self.free_count,
            },
            stopped,
        }
    }

    /// Prescribed displacements at `factor`.
    fn prescribed(&self, factor: f64) -> Vec<(usize, f64)> {
        if let Some(warm) = &self.warm {
            return warm
                .end_mm
                .iter()
                .map(|&(dof, end)| {
                    let start = warm.start_mm[dof];
                    (dof, start + factor * (end - start))
                })
                .collect();
        }
        let nodes = &self.membrane.mesh.nodes_mm;
        self.clamps
            .iter()
            .flat_map(|c| c.prescribed(nodes, factor))
            .collect()
    }

    fn residual_norm(&self, forces: &[f64]) -> (f64, f64) {
        let free = norm(
            self.free
                .iter()
                .zip(forces)
                .filter(|(f, _)| f.is_some())
                .map(|(_, &v)| v),
        );
        let reactions = norm(
            self.free
                .iter()
                .zip(forces)
                .filter(|(f, _)| f.is_none())
                .map(|(_, &v)| v),
        );
        let tolerance = self
            .settings
            .absolute_tolerance_n
            .max(self.settings.relative_tolerance * reactions);
        (free, tolerance)
    }

    /// One load increment from the converged `u0` to load factor `target`.
    fn increment(
        &mut self,
        u0: &[f64],
        target: f64,
    ) -> Result<(Vec<f64>, Evaluation, StepRecord), Failure> {
        let mut u = u0.to_vec();
        let mut prescribed_step = vec![0.0; u.len()];
        for (dof, value) in self.prescribed(target) {
            prescribed_step[dof] = value - u0[dof];
        }
        // Predictor: the linearised response to the clamps' motion, K_ff Δu_f = −(R_f + K_fp Δu_p).
        let start = self.membrane.evaluate(&u, true).map_err(Failure::Point)?;
        let delta = self.newton_direction(&start, Some(&prescribed_step))?;
        for (dof, slot) in self.free.iter().enumerate() {
            u[dof] += match slot {
                Some(i) => delta[*i],
                None => prescribed_step[dof],
            };
        }
        let mut record = StepRecord {
            load_factor: target,
            residuals_n: Vec::new(),
            step_lengths: Vec::new(),
            states: StateCount::default(),
        };
        let (mut residual, mut tolerance) = (f64::INFINITY, 0.0);
        for _ in 0..self.settings.max_iterations {
            let evaluation = self.membrane.evaluate(&u, true).map_err(Failure::Point)?;
            (residual, tolerance) = self.residual_norm(&evaluation.forces_n);
            record.residuals_n.push(residual);
            if residual <= tolerance {
                record.states = evaluation.states;
                return Ok((u, evaluation, record));
            }
            let delta = self.newton_direction(&evaluation, None)?;
            let (alpha, trial) = self.line_search(&u, &delta, residual)?;
            record.step_lengths.push(alpha);
            u = trial;
        }
        Err(Failure::NotConverged {
            iterations: self.settings.max_iterations,
            residual_n: residual,
            tolerance_n: tolerance,
        })
    }

    /// Backtracking on ‖R_free‖: the first step length that reduces it (Armijo, 1e-4), else the
    /// shortest tried if it evaluates, else the point failure of the full step.
    fn line_search(
        &self,
        u: &[f64],
        delta: &[f64],
        residual: f64,
    ) -> Result<(f64, Vec<f64>), Failure> {
        let mut alpha = 1.0;
        let mut first_failure = None;
        let mut last_ok = None;
        for _ in 0..=self.settings.line_search_halvings {
            let mut trial = u.to_vec();
            for (dof, slot) in self.free.iter().enumerate() {
                if let Some(i) = slot {
                    trial[dof] += alpha * delta[*i];
                }
            }
            match self.membrane.evaluate(&trial, false) {
                Ok(evaluation) => {
                    let (trial_residual, _) = self.residual_norm(&evaluation.forces_n);
                    if trial_residual <= (1.0 - 1e-4 * alpha) * residual {
                        return Ok((alpha, trial));
                    }
                    last_ok = Some((alpha, trial));
                }
                Err(failure) => {
                    first_failure.get_or_insert(failure);
                }
            }
            alpha *= 0.5;
        }
        match (last_ok, first_failure) {
            (Some(ok), _) => Ok(ok),
            (None, Some(failure)) => Err(Failure::Point(failure)),
            (None, None) => unreachable!("at least one trial was evaluated"),
        }
    }

    /// Solves K_ff δ = −(R_f + K_fp Δu_p) (the coupling term only for the predictor).
    fn newton_direction(
        &mut self,
        evaluation: &Evaluation,
        prescribed_step: Option<&[f64]>,
    ) -> Result<Vec<f64>, Failure> {
        let mut rhs = vec![0.0; self.free_count];
        for (dof, slot) in self.free.iter().enumerate() {
            if let Some(i) = slot {
                rhs[*i] = -evaluation.forces_n[dof];
            }
        }
        let mut triplets = Vec::with_capacity(evaluation.element_tangents.len() * 78);
        for (element, k) in self
            .membrane
            .mesh
            .elements
            .iter()
            .zip(&evaluation.element_tangents)
        {
            let dofs: [usize; 12] = std::array::from_fn(|r| 2 * element[r / 2] + r % 2);
            for (r, &gr) in dofs.iter().enumerate() {
                let Some(fr) = self.free[gr] else { continue };
                for (c, &gc) in dofs.iter().enumerate() {
                    match self.free[gc] {
                        Some(fc) if fr >= fc => triplets.push(Triplet::new(fr, fc, k[r][c])),
                        Some(_) => {}
                        None => {
                            if let Some(step) = prescribed_step {
                                rhs[fr] -= k[r][c] * step[gc];
                            }
                        }
                    }
                }
            }
        }
        let n = self.free_count;
        let llt = factorise(n, &triplets, &mut self.symbolic)?;
        let mut x = Mat::from_fn(n, 1, |i, _| rhs[i]);
        llt.solve_in_place(x.as_mut());
        Ok((0..n).map(|i| x[(i, 0)]).collect())
    }
}

/// The sparse Cholesky factorisation of the free-free tangent given by its lower triplets
/// (`symbolic`: the analysis of an earlier matrix of the same pattern, made on first use).
/// faer runs sequentially here (built without its `rayon` feature): the same matrix gives the
/// same bits on any machine load, which the rig's journal replay relies on.
pub(crate) fn factorise(
    n: usize,
    triplets: &[Triplet<usize, usize, f64>],
    symbolic: &mut Option<SymbolicLlt<usize>>,
) -> Result<Llt<usize, f64>, Failure> {
    let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, triplets)
        .map_err(Failure::Factorisation)?;
    let symbolic = match symbolic {
        Some(s) => s.clone(),
        None => {
            let s = SymbolicLlt::try_new(matrix.symbolic(), Side::Lower)
                .map_err(|e| Failure::Factorisation(e.into()))?;
            *symbolic = Some(s.clone());
            s
        }
    };
    Llt::try_new_with_symbolic(symbolic, matrix.as_ref(), Side::Lower).map_err(|e| match e {
        faer::sparse::linalg::LltError::Numeric(
            faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index },
        ) => Failure::Unstable { pivot: index },
        faer::sparse::linalg::LltError::Generic(e) => Failure::Factorisation(e.into()),
    })
}
