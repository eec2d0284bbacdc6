//! Which specimen, as a user writes it (`[specimen.geometry]`: a shape and one table of
//! geometry per shape), and how far its grips pull (a nominal grip stretch per axis).

use super::cruciform::CruciformGeometry;
use super::strip::StripGeometry;
use super::Specimen;
use crate::assembly::Membrane;
use crate::boundary::Clamp;
use crate::constitutive::Wrinkling;
use crate::error::GeometryError;
use crate::error::SolveError;
use crate::law::SheetLaw;
use crate::solver::{solve, Equilibrium, NewtonSettings};
use serde::{Deserialize, Serialize};

/// The specimens of the paper.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SpecimenShape {
    /// The biaxial tests' cruciform: four grips.
    #[default]
    Cruciform,
    /// A long narrow strip between two clamps along x.
    UniaxialStrip,
    /// The wide, short strip of Fig. 9 ("plane strain"), clamps along x.
    PlaneStrainStrip,
}

wire::named!(SpecimenShape, "specimen shape", {
    Cruciform => "cruciform",
    UniaxialStrip => "uniaxial_strip",
    PlaneStrainStrip => "plane_strain_strip",
});

/// A shape and the geometry of every shape (only the chosen one is meshed).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpecimenChoice {
    pub shape: SpecimenShape,
    pub cruciform: CruciformGeometry,
    pub uniaxial_strip: StripGeometry,
    pub plane_strain_strip: StripGeometry,
}

impl Default for SpecimenChoice {
    fn default() -> Self {
        SpecimenChoice {
            shape: SpecimenShape::default(),
            cruciform: CruciformGeometry::default(),
            uniaxial_strip: StripGeometry::uniaxial(),
            plane_strain_strip: StripGeometry::plane_strain(),
        }
    }
}

impl SpecimenChoice {
    /// The chosen shape, meshed.
    pub fn mesh(&self) -> Result<Specimen, GeometryError> {
        match self.shape {
            SpecimenShape::Cruciform => self.cruciform.mesh(),
            SpecimenShape::UniaxialStrip => self.uniaxial_strip.mesh(),
            SpecimenShape::PlaneStrainStrip => self.plane_strain_strip.mesh(),
        }
    }
}

/// Nominal grip stretches: a grip on the x axis moves outwards by (x − 1) times its distance
/// from the specimen's centre, so that the grip-to-grip distance is stretched by x (y alike).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct GripStretch {
    pub x: f64,
    pub y: f64,
}

/// A grip stretch that cannot be applied.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GripStretchError {
    #[error("a grip stretch must be finite and positive, got {axis} = {value}")]
    NotPositive { axis: &'static str, value: f64 },
    #[error("the {shape} has no grip along y: its y stretch must be 1, got {value}")]
    NoGripAlongY { shape: SpecimenShape, value: f64 },
}

impl GripStretch {
    /// The stretches `fraction` of the way from rest (1, 1) to `self`.
    pub fn towards(self, fraction: f64) -> Self {
        GripStretch {
            x: 1.0 + fraction * (self.x - 1.0),
            y: 1.0 + fraction * (self.y - 1.0),
        }
    }

    /// Refuses a stretch that is not positive, or a y stretch on a shape without y grips.
    pub fn check(self, shape: SpecimenShape) -> Result<Self, GripStretchError> {
        for (axis, value) in [("x", self.x), ("y", self.y)] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(GripStretchError::NotPositive { axis, value });
            }
        }
        if shape != SpecimenShape::Cruciform && self.y != 1.0 {
            return Err(GripStretchError::NoGripAlongY {
                shape,
                value: self.y,
            });
        }
        Ok(self)
    }
}

impl Specimen {
    /// The equilibrium of every grip pulled to `stretch` (aligned) under `law`, solved from
    /// rest with the default wrinkling and Newton settings: a solved state in one call, for
    /// examples and tests that film or integrate one.
    pub fn solve_at<L: SheetLaw + ?Sized>(
        &self,
        law: &L,
        stretch: GripStretch,
    ) -> Result<Equilibrium, SolveError> {
        let sheet = Membrane::new(&self.mesh, self.thickness_mm, law, Wrinkling::default())?;
        solve(&sheet, &self.clamps_at(stretch), NewtonSettings::default())
    }

    /// Every grip pulled to `stretch` (aligned; misalignment is a grip's own
    /// [`super::Grip::clamp`]).
    pub fn clamps_at(&self, stretch: GripStretch) -> Vec<Clamp> {
        self.grips
            .iter()
            .map(|g| {
                let distance_mm = g.centre_mm[0] * g.axis[0] + g.centre_mm[1] * g.axis[1];
                let axis_stretch = if g.axis[0].abs() >= g.axis[1].abs() {
                    stretch.x
                } else {
                    stretch.y
                };
                g.clamp((axis_stretch - 1.0) * distance_mm, 0.0)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grip_stretch_of_two_doubles_the_grip_to_grip_distance() {
        let choice = SpecimenChoice {
            cruciform: CruciformGeometry {
                element_size_mm: 20.0,
                ..CruciformGeometry::default()
            },
            ..SpecimenChoice::default()
        };
        let specimen = choice.mesh().unwrap();
        let clamps = specimen.clamps_at(GripStretch { x: 2.0, y: 1.5 });
        for (grip, clamp) in specimen.grips.iter().zip(&clamps) {
            let stretch = if grip.axis[0] != 0.0 { 2.0 } else { 1.5 };
            for (centre, translation) in grip.centre_mm.iter().zip(clamp.motion.translation_mm) {
                let moved = centre + translation;
                assert!((moved - stretch * centre).abs() < 1e-12, "{}", grip.name);
            }
        }
    }

    #[test]
    fn stretches_that_cannot_be_applied_are_refused_naming_them() {
        let e = GripStretch { x: 1.2, y: 1.1 }
            .check(SpecimenShape::UniaxialStrip)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "the uniaxial_strip has no grip along y: its y stretch must be 1, got 1.1"
        );
        let e = GripStretch {
            x: f64::NAN,
            y: 1.0,
        }
        .check(SpecimenShape::Cruciform)
        .unwrap_err();
        assert!(e.to_string().contains("x = NaN"), "{e}");
        assert_eq!(
            "plane_strain_strip".parse::<SpecimenShape>(),
            Ok(SpecimenShape::PlaneStrainStrip)
        );
    }
}
