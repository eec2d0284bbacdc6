//! Shared helpers of the membrane tests: a square sheet, rollers, Gauss-point checks.
#![allow(dead_code)]

use membrane::specimens::strip::StripGeometry;
use membrane::{Clamp, Held, RigidMotion, Specimen};

/// A free square of side `side_mm`, `cells` × `cells` cells.
pub fn square(side_mm: f64, cells: usize) -> Specimen {
    StripGeometry {
        length_mm: side_mm,
        width_mm: side_mm,
        thickness_mm: 2.0,
        element_size_mm: side_mm / cells as f64,
    }
    .mesh()
    .unwrap()
}

/// A roller on the nodes where `on` holds, holding `held`, moving by `translation_mm`.
pub fn roller(
    specimen: &Specimen,
    held: Held,
    translation_mm: [f64; 2],
    on: impl Fn([f64; 2]) -> bool,
) -> Clamp {
    Clamp {
        nodes: specimen.mesh.nodes_where(on),
        held,
        motion: RigidMotion::translation(translation_mm),
    }
}

/// |a − b| ≤ tolerance × scale.
pub fn close(a: f64, b: f64, tolerance: f64, scale: f64) -> bool {
    (a - b).abs() <= tolerance * scale
}

/// Deterministic pseudo-random numbers in [−1, 1].
pub fn noise(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// A specimen solved with Smactane™ and the default wrinkling and settings but `settings`.
pub struct Solved {
    pub specimen: Specimen,
    pub equilibrium: membrane::Equilibrium,
    pub fields: Vec<membrane::PointField>,
}

impl Solved {
    pub fn new(
        specimen: Specimen,
        clamps: impl Fn(&Specimen) -> Vec<Clamp>,
        settings: membrane::NewtonSettings,
    ) -> Solved {
        let law = material::InvariantLaw::smactane();
        let membrane = membrane::Membrane::new(
            &specimen.mesh,
            specimen.thickness_mm,
            &law,
            membrane::Wrinkling::default(),
        )
        .unwrap();
        let equilibrium = membrane::solve(&membrane, &clamps(&specimen), settings).unwrap();
        let fields = membrane.point_fields(&equilibrium.displacement_mm).unwrap();
        Solved {
            specimen,
            equilibrium,
            fields,
        }
    }

    /// The force of grip `name` on the sheet, N.
    pub fn grip_force_n(&self, name: &str) -> [f64; 2] {
        self.equilibrium
            .grip_force_n(&self.specimen.grip(name).unwrap().nodes)
    }
}
