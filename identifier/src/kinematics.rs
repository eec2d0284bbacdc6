//! What the nominal stress of a point needs that does not depend on a model's parameters: the
//! stretches and invariants of an incompressible plane-stress state, computed once per point.

use crate::data::LoadCase;

/// What the nominal stress of a point needs that does not depend on the parameters: computed
/// once per point of a fit, not at every evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    /// Loaded stretch λ1, thickness stretch λ3 = 1/(λ1 λ2).
    pub stretch1: f64,
    pub stretch3: f64,
    pub ln_stretch1: f64,
    pub ln_stretch3: f64,
    pub i1: f64,
    pub i2: f64,
}

impl Kinematics {
    /// A canonical load case at its loaded stretch: [`Kinematics::in_plane`] of its stretches.
    pub fn of(case: LoadCase, stretch: f64) -> Self {
        let (l1, l2) = case.in_plane_stretches(stretch);
        Kinematics::in_plane(l1, l2)
    }

    /// Any incompressible plane-stress state, the stress being measured along the direction
    /// of `stretch` (the other in-plane stretch `other_stretch`): λ3 = 1/(λ λ_other). The
    /// stress across (direction 2 of a biaxial state) is `in_plane(λ2, λ1)`: same invariants,
    /// roles swapped.
    pub fn in_plane(stretch: f64, other_stretch: f64) -> Self {
        let (l1, l2) = (stretch, other_stretch);
        let l3 = 1.0 / (l1 * l2);
        let (i1, i2) = crate::law::invariants([l1, l2, l3]);
        Kinematics {
            stretch1: l1,
            stretch3: l3,
            ln_stretch1: l1.ln(),
            ln_stretch3: l3.ln(),
            i1,
            i2,
        }
    }
}
