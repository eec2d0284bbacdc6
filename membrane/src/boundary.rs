//! Grips as boundary conditions: a clamp holds a set of nodes and moves them as a rigid body
//! (translation, rotation about a centre), ramped with the load factor. Misalignment is a
//! boundary condition: a sheet rotated in its grips is a clamp rotation, an asymmetric
//! clamping is unequal translations of opposite clamps. A roller holds one component only.

/// Which displacement components a clamp prescribes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Held {
    Both,
    /// u_x only (a roller free along y).
    X,
    /// u_y only.
    Y,
}

/// A rigid motion of a grip at full load.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RigidMotion {
    pub translation_mm: [f64; 2],
    pub rotation_rad: f64,
    /// Reference position of the rotation centre.
    pub centre_mm: [f64; 2],
}

impl RigidMotion {
    /// A translation only.
    pub fn translation(translation_mm: [f64; 2]) -> Self {
        RigidMotion {
            translation_mm,
            ..RigidMotion::default()
        }
    }

    /// Displacement of reference point `x_mm` at load factor `factor` (translation and angle
    /// both scaled by it).
    pub fn displacement_mm(&self, x_mm: [f64; 2], factor: f64) -> [f64; 2] {
        let (s, c) = (factor * self.rotation_rad).sin_cos();
        let r = [x_mm[0] - self.centre_mm[0], x_mm[1] - self.centre_mm[1]];
        [
            factor * self.translation_mm[0] + (c - 1.0) * r[0] - s * r[1],
            factor * self.translation_mm[1] + s * r[0] + (c - 1.0) * r[1],
        ]
    }
}

/// Nodes held by one grip (or roller) and how it moves.
#[derive(Clone, Debug, PartialEq)]
pub struct Clamp {
    pub nodes: Vec<usize>,
    pub held: Held,
    pub motion: RigidMotion,
}

impl Clamp {
    /// The prescribed (dof, displacement mm) of this clamp at load factor `factor`.
    pub fn prescribed(
        &self,
        nodes_mm: &[[f64; 2]],
        factor: f64,
    ) -> impl Iterator<Item = (usize, f64)> + '_ {
        let components: &'static [usize] = match self.held {
            Held::Both => &[0, 1],
            Held::X => &[0],
            Held::Y => &[1],
        };
        let positions: Vec<[f64; 2]> = self.nodes.iter().map(|&n| nodes_mm[n]).collect();
        self.nodes
            .iter()
            .zip(positions)
            .flat_map(move |(&node, x)| {
                let u = self.motion.displacement_mm(x, factor);
                components.iter().map(move |&i| (2 * node + i, u[i]))
            })
    }
}
