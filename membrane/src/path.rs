//! A specimen taken along a path of grip stretches (`dicstream specimen`): each state solved
//! from the reference with load stepping, its equilibrium, nodal fields, grip forces and the
//! solver's figures. A state that does not converge ends the path: the states before it are
//! kept, its reason is said, and no force of it is reported.

use crate::assembly::Membrane;
use crate::constitutive::StateCount;
use crate::error::SolveError;
use crate::law::SheetLaw;
use crate::nodal::{NodalField, NodeFailure};
use crate::solver::{solve, Equilibrium, NewtonSettings};
use crate::specimens::cruciform::CruciformGeometry;
use crate::specimens::strip::StripGeometry;
use crate::specimens::{GripStretch, Specimen, SpecimenChoice, SpecimenShape};
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;

/// A converged state of the path.
#[derive(Clone, Debug)]
pub struct PathState {
    pub figures: StateFigures,
    pub equilibrium: Equilibrium,
    pub nodes: Vec<NodalField>,
}

/// What is reported of a state: its stretch, the grip forces, the solver's figures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StateFigures {
    /// 1 for the first state of the path.
    pub state: usize,
    pub grip_stretch: GripStretch,
    /// Force that each grip applies to the sheet (N, [x, y]), by grip name.
    pub grip_force_n: BTreeMap<&'static str, [f64; 2]>,
    /// Each grip's force along its own axis (N; positive: the grip pulls).
    pub grip_axial_force_n: BTreeMap<&'static str, f64>,
    pub load_steps: usize,
    pub newton_iterations: usize,
    /// ‖R_free‖ (N) at each Newton iterate of the last load step (quadratic convergence shows
    /// here).
    pub last_step_residuals_n: Vec<f64>,
    /// Gauss points per tension-field state at the end.
    pub gauss_points_taut: usize,
    pub gauss_points_wrinkled: usize,
    pub gauss_points_slack: usize,
    /// Nodes per state (nodal recovery).
    pub nodes_wrinkled: usize,
    pub nodes_slack: usize,
    /// Largest major and smallest minor in-plane stretch over the nodes.
    pub stretch_max: f64,
    pub stretch_min: f64,
    pub solve_ms: f64,
}

/// Why a path stopped before its end.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PathStop {
    #[error("state {state} (grip stretch x {x}, y {y}): {error}")]
    Solve {
        state: usize,
        x: f64,
        y: f64,
        error: SolveError,
    },
    #[error("state {state} (grip stretch x {x}, y {y}): node {node} has no stress: {failure:?}", node = failure.node, failure = failure.failure)]
    Node {
        state: usize,
        x: f64,
        y: f64,
        failure: NodeFailure,
    },
}

/// The states reached along the path, and why it stopped early, if it did.
#[derive(Clone, Debug)]
pub struct Path {
    pub states: Vec<PathState>,
    pub stopped: Option<PathStop>,
}

/// Solves `specimen` at `count` grip stretches evenly spaced from rest to `target` (the last
/// one `target` itself), stopping at the first that fails.
pub fn solve_path<L: SheetLaw + ?Sized>(
    membrane: &Membrane<'_, L>,
    specimen: &Specimen,
    target: GripStretch,
    count: usize,
    settings: NewtonSettings,
) -> Path {
    let mut path = Path {
        states: Vec::with_capacity(count),
        stopped: None,
    };
    for state in 1..=count {
        let stretch = target.towards(state as f64 / count as f64);
        match solve_state(membrane, specimen, stretch, state, settings) {
            Ok(reached) => path.states.push(reached),
            Err(stop) => {
                path.stopped = Some(stop);
                break;
            }
        }
    }
    path
}

fn solve_state<L: SheetLaw + ?Sized>(
    membrane: &Membrane<'_, L>,
    specimen: &Specimen,
    stretch: GripStretch,
    state: usize,
    settings: NewtonSettings,
) -> Result<PathState, PathStop> {
    let started = Instant::now();
    let equilibrium = solve(membrane, &specimen.clamps_at(stretch), settings).map_err(|error| {
        PathStop::Solve {
            state,
            x: stretch.x,
            y: stretch.y,
            error,
        }
    })?;
    let nodes = membrane
        .nodal_fields(&equilibrium.displacement_mm)
        .map_err(|failure| PathStop::Node {
            state,
            x: stretch.x,
            y: stretch.y,
            failure,
        })?;
    let solve_ms = started.elapsed().as_secs_f64() * 1e3;
    let figures = figures(specimen, &equilibrium, &nodes, (state, stretch), solve_ms);
    Ok(PathState {
        figures,
        equilibrium,
        nodes,
    })
}

fn figures(
    specimen: &Specimen,
    equilibrium: &Equilibrium,
    nodes: &[NodalField],
    (state, grip_stretch): (usize, GripStretch),
    solve_ms: f64,
) -> StateFigures {
    let mut grip_force_n = BTreeMap::new();
    let mut grip_axial_force_n = BTreeMap::new();
    for grip in &specimen.grips {
        let force = equilibrium.grip_force_n(&grip.nodes);
        // The grip's force on the sheet points outwards when it pulls.
        grip_axial_force_n.insert(grip.name, force[0] * grip.axis[0] + force[1] * grip.axis[1]);
        grip_force_n.insert(grip.name, force);
    }
    let points = equilibrium
        .steps
        .last()
        .map(|s| s.states)
        .unwrap_or_default();
    let mut node_states = StateCount::default();
    nodes.iter().for_each(|n| node_states.add(n.state));
    let last = equilibrium.steps.last();
    StateFigures {
        state,
        grip_stretch,
        grip_force_n,
        grip_axial_force_n,
        load_steps: equilibrium.steps.len(),
        newton_iterations: equilibrium.steps.iter().map(|s| s.residuals_n.len()).sum(),
        last_step_residuals_n: last.map(|s| s.residuals_n.clone()).unwrap_or_default(),
        gauss_points_taut: points.taut,
        gauss_points_wrinkled: points.wrinkled,
        gauss_points_slack: points.slack,
        nodes_wrinkled: node_states.wrinkled,
        nodes_slack: node_states.slack,
        stretch_max: nodes
            .iter()
            .map(|n| n.stretches[0])
            .fold(f64::NEG_INFINITY, f64::max),
        stretch_min: nodes
            .iter()
            .map(|n| n.stretches[1])
            .fold(f64::INFINITY, f64::min),
        solve_ms,
    }
}

/// What `dicstream specimen` writes as `summary.json`: the specimen, the mesh, the law, each
/// converged state's figures, and why the path stopped if it did.
#[derive(Clone, Debug, Serialize)]
pub struct PathReport<'a> {
    pub shape: SpecimenShape,
    pub geometry: ChosenGeometry<'a>,
    /// ln f(I1) and ln g(I2) coefficients of the law (eqs. 22, 25).
    pub law_f: &'a [f64],
    pub law_g: &'a [f64],
    pub nodes: usize,
    pub elements: usize,
    pub dofs: usize,
    /// Free DOFs of the linear systems (the rest are held by the grips).
    pub free_dofs: Option<usize>,
    pub target_grip_stretch: GripStretch,
    pub states_requested: usize,
    pub states: Vec<&'a StateFigures>,
    /// Why the path stopped before its end (no force of that state is reported).
    pub stopped: Option<String>,
}

/// The geometry of the chosen shape.
#[derive(Clone, Copy, Debug, Serialize)]
#[serde(untagged)]
pub enum ChosenGeometry<'a> {
    Cruciform(&'a CruciformGeometry),
    Strip(&'a StripGeometry),
}

impl SpecimenChoice {
    /// The geometry of the chosen shape.
    pub fn chosen(&self) -> ChosenGeometry<'_> {
        match self.shape {
            SpecimenShape::Cruciform => ChosenGeometry::Cruciform(&self.cruciform),
            SpecimenShape::UniaxialStrip => ChosenGeometry::Strip(&self.uniaxial_strip),
            SpecimenShape::PlaneStrainStrip => ChosenGeometry::Strip(&self.plane_strain_strip),
        }
    }
}
