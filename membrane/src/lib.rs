//! Finite-element model of a thin incompressible hyperelastic sheet: plane-stress membrane,
//! total Lagrangian, large deformation, six-node triangles (T6).
//!
//! Incompressibility is built into plane stress (λ3² = 1 / det C of the in-plane C): no
//! pressure field, no locking. The law is any [`SheetLaw`]: a [`MembraneLaw`] (W1, W2 of an
//! invariant-based potential: `material::InvariantLaw`, or a catalogue model through
//! [`InvariantDerivatives`]) or a law by its principal stresses ([`PrincipalStresses`]: Ogden). A sheet carries no compression: tension-field relaxation
//! ([`Wrinkling`]). The specimens of the paper are meshed in code ([`specimens`]), clamped by
//! grips moving as rigid bodies ([`Clamp`]), and solved by Newton with line search and load
//! stepping ([`solve`], warm-started from an earlier equilibrium: [`solve_from`]), its tangent
//! condensed on the grips ([`condense`]) and the field followed to nearby grips through its modes
//! ([`GripLinearField`]); a failure names its state and reason ([`SolveError`]). A path of grip
//! stretches ([`solve_path`]) gives nodal fields ([`nodal`]) written as VTK and CSV ([`output`]).
//! Units: mm, N, MPa.

#![forbid(unsafe_code)]

pub mod assembly;
pub mod boundary;
pub mod condensed;
pub mod constitutive;
pub mod error;
pub mod grip_field;
pub mod law;
pub mod mesh;
pub mod nodal;
pub mod output;
pub mod path;
pub mod principal;
pub mod probe;
pub mod region;
pub mod solver;
pub mod specimens;
pub mod t6;
mod wrinkling;

pub use assembly::{Membrane, PointField};
pub use boundary::{Clamp, Held, RigidMotion};
pub use condensed::{condense, Condensed};
pub use constitutive::{MembraneState, Wrinkling};
pub use error::{GeometryError, SolveError};
pub use grip_field::GripLinearField;
pub use law::{InvariantDerivatives, MembraneLaw, SheetLaw};
pub use mesh::Mesh;
pub use nodal::{NodalField, NodeFailure};
pub use path::{solve_path, Path, PathReport, PathState, PathStop, StateFigures};
pub use principal::PrincipalStresses;
pub use probe::{point_at, sample_at, ElementGrid, Location, PointSample, Probe};
pub use region::Region;
pub use solver::{
    solve, solve_from, solve_until_stopped, Analysis, Equilibrium, NewtonSettings, Outcome,
    StepRecord,
};
pub use specimens::{GripStretch, Specimen, SpecimenChoice, SpecimenShape};
