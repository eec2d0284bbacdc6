//! The specimens of the paper, meshed in code from a few parameters each: the uniaxial strip
//! and the wide plane-strain strip between two clamps ([`strip`]), the cruciform with fillets
//! and optional slits ([`cruciform`]). Each names its grips: the nodes a grip holds, its centre
//! and the axis along which it pulls.

mod choice;
pub mod cruciform;
pub mod strip;

pub use choice::{GripStretch, GripStretchError, SpecimenChoice, SpecimenShape};

use crate::boundary::{Clamp, Held, RigidMotion};
use crate::error::GeometryError;
use crate::mesh::Mesh;

/// One grip of a specimen.
#[derive(Clone, Debug, PartialEq)]
pub struct Grip {
    /// "x+", "x-", "y+", "y-".
    pub name: &'static str,
    pub nodes: Vec<usize>,
    /// Reference centre of the clamped edge, mm.
    pub centre_mm: [f64; 2],
    /// Outward unit axis along which the grip pulls.
    pub axis: [f64; 2],
}

impl Grip {
    /// The grip pulling by `pull_mm` along its axis, the sheet turned by `rotation_rad` in it
    /// (about the grip centre): both reached at load factor 1.
    pub fn clamp(&self, pull_mm: f64, rotation_rad: f64) -> Clamp {
        Clamp {
            nodes: self.nodes.clone(),
            held: Held::Both,
            motion: RigidMotion {
                translation_mm: [pull_mm * self.axis[0], pull_mm * self.axis[1]],
                rotation_rad,
                centre_mm: self.centre_mm,
            },
        }
    }
}

/// A meshed specimen.
#[derive(Clone, Debug, PartialEq)]
pub struct Specimen {
    pub mesh: Mesh,
    pub thickness_mm: f64,
    pub grips: Vec<Grip>,
}

impl Specimen {
    /// The grip called `name`.
    pub fn grip(&self, name: &str) -> Option<&Grip> {
        self.grips.iter().find(|g| g.name == name)
    }

    /// Every grip pulling by the same `pull_mm`, aligned.
    pub fn pull_all(&self, pull_mm: f64) -> Vec<Clamp> {
        self.grips.iter().map(|g| g.clamp(pull_mm, 0.0)).collect()
    }
}

/// `value_mm` if positive and finite.
pub(crate) fn positive(name: &'static str, value_mm: f64) -> Result<f64, GeometryError> {
    if value_mm > 0.0 && value_mm.is_finite() {
        Ok(value_mm)
    } else {
        Err(GeometryError::NotPositive { name, value_mm })
    }
}

/// Cells to cover `length_mm` with cells of about `size_mm` (at least `minimum`), refused above
/// the element limit.
pub(crate) fn cells(length_mm: f64, size_mm: f64, minimum: usize) -> usize {
    ((length_mm / size_mm).ceil() as usize).max(minimum)
}

/// More elements than this is a mistake in the element size, not a specimen.
pub const MAX_ELEMENTS: usize = 2_000_000;

/// Refuses a mesh of more than [`MAX_ELEMENTS`] elements before building it.
pub(crate) fn check_size(elements: usize) -> Result<(), GeometryError> {
    if elements > MAX_ELEMENTS {
        return Err(GeometryError::TooManyElements {
            elements,
            limit: MAX_ELEMENTS,
        });
    }
    Ok(())
}

/// Tolerance of node merging and grip selection, relative to the specimen's size.
pub(crate) fn tolerance_mm(size_mm: f64) -> f64 {
    1e-9 * size_mm
}
