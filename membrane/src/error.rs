//! Why a specimen cannot be meshed or a load cannot be solved: each error holds the offending
//! value and, for a solve, the load factor reached (`solve_until_stopped` also gives the last
//! converged equilibrium; no force is ever read from an unconverged iterate).

/// A geometry that cannot be meshed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GeometryError {
    #[error("{name} = {value_mm} mm: expected a positive finite size")]
    NotPositive { name: &'static str, value_mm: f64 },
    #[error("fillet radius {radius_mm} mm: expected at most the {limit_name} ({limit_mm} mm)")]
    FilletTooLarge {
        radius_mm: f64,
        limit_name: &'static str,
        limit_mm: f64,
    },
    #[error("slit: {reason} (slits {count}, length {length_mm} mm)")]
    Slit {
        reason: &'static str,
        count: usize,
        length_mm: f64,
    },
    #[error("{elements} elements: more than the limit of {limit} (element size too small for the specimen)")]
    TooManyElements { elements: usize, limit: usize },
    #[error("element {element} is inverted in the reference mesh (Jacobian {jacobian_mm2} mm²)")]
    InvertedElement { element: usize, jacobian_mm2: f64 },
    #[error("the region holds no element of the mesh")]
    EmptyRegion,
    #[error(
        "arm {arm}: the view reaches {reach_mm} mm along it, the arm is straight (past its \
         fillets) from {straight_mm} mm: a clipped cruciform needs every arm cut beyond its \
         fillets"
    )]
    ArmNotCut {
        arm: &'static str,
        reach_mm: f64,
        straight_mm: f64,
    },
}

/// Where the solution of a load stopped, and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SolveError {
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    #[error("element {element} inverted by the load (det C = {det_c} at Gauss point {point}) at load factor {load_factor}, last converged {converged_load_factor}")]
    ElementInverted {
        element: usize,
        point: usize,
        det_c: f64,
        load_factor: f64,
        converged_load_factor: f64,
    },
    #[error("the law has no value at I1 = {i1}, I2 = {i2} (element {element}) at load factor {load_factor}, last converged {converged_load_factor}")]
    OutsideLawDomain {
        element: usize,
        i1: f64,
        i2: f64,
        load_factor: f64,
        converged_load_factor: f64,
    },
    #[error("Newton did not converge in {iterations} iterations at load factor {load_factor} (residual {residual_n} N, tolerance {tolerance_n} N), last converged {converged_load_factor}")]
    NotConverged {
        iterations: usize,
        residual_n: f64,
        tolerance_n: f64,
        load_factor: f64,
        converged_load_factor: f64,
    },
    #[error("the tangent stiffness is not positive definite (pivot {pivot}) at load factor {load_factor}: the law or the structure is not stable along the path; last converged {converged_load_factor}")]
    Unstable {
        pivot: usize,
        load_factor: f64,
        converged_load_factor: f64,
    },
    #[error("a clamp names node {node}, the mesh has {nodes}")]
    UnknownNode { node: usize, nodes: usize },
    #[error("nothing is clamped: the sheet is free to move as a rigid body")]
    NoClamp,
    #[error("a warm start of {values} displacements for a mesh of {dofs} degrees of freedom")]
    StartLength { values: usize, dofs: usize },
    #[error("the sparse factorisation could not be made: {cause}")]
    Factorisation { cause: faer::sparse::CreationError },
}

impl SolveError {
    /// The load factor at which the solve stopped, if it stopped on the path.
    pub fn converged_load_factor(&self) -> Option<f64> {
        match self {
            SolveError::ElementInverted {
                converged_load_factor,
                ..
            }
            | SolveError::OutsideLawDomain {
                converged_load_factor,
                ..
            }
            | SolveError::NotConverged {
                converged_load_factor,
                ..
            }
            | SolveError::Unstable {
                converged_load_factor,
                ..
            } => Some(*converged_load_factor),
            _ => None,
        }
    }
}
