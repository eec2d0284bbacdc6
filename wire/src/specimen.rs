//! `specimen`: the finite-element specimen's solved states, one sample per converged solve of
//! the rig's structure, as a `[f64]` slice behind a [`SpecimenHeader`].
//!
//! Self-contained, so a reader needs no settings to use it: the payload holds, in this order,
//! the reference mesh (node positions, then six-node triangles), the solved nodal displacements
//! and one displacement mode per grip (the whole sheet's displacement per mm of that grip's
//! axial motion, at the solve). Between two solves the field at grip displacements q is
//! u(q) = u_s + Σ_g m_g (q_g − q_s,g), the same first order the rig's forces follow; a frame
//! names the solve and q ([`crate::GroundTruth::specimen_solve_id`]). The mesh is the same in
//! every sample of one rig (`mesh_fingerprint` says so without reading it).

#[cfg(feature = "ipc")]
use iceoryx2::prelude::ZeroCopySend;

/// Grips of a specimen at most (the cruciform's four).
pub const MAX_SPECIMEN_GRIPS: usize = 4;
/// Nodes of a triangle of the mesh (T6: corners counter-clockwise, then midsides 01, 12, 20).
pub const ELEMENT_NODES: usize = 6;

/// Header of one solved state on the `specimen` service.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.SpecimenHeader.v6")
)]
pub struct SpecimenHeader {
    /// Always [`crate::LAYOUT_VERSION`]; checked by every reader.
    pub layout_version: u32,
    /// Grips of the specimen (modes in the payload), at most [`MAX_SPECIMEN_GRIPS`].
    pub grips: u32,
    /// The solve: the rig's test index in the high 32 bits (each test mounts its specimen),
    /// the specimen's converged solves in the low ones (0 at rest; one more per solve and when
    /// a slack sheet goes back to rest); what `RigState::specimen_solve_id` and frames name.
    pub solve_id: u64,
    /// Simulated time of the solve (s).
    pub t_sim_s: f64,
    pub node_count: u32,
    pub element_count: u32,
    /// A hash of the mesh (positions and connectivity): equal in every sample of one specimen.
    pub mesh_fingerprint: u64,
    /// The solved grips' axial displacements q_s (mm, outward) and forces (N, pulling).
    pub grip_mm: [f64; MAX_SPECIMEN_GRIPS],
    pub grip_force_n: [f64; MAX_SPECIMEN_GRIPS],
}

/// The payload of a sample, split by [`SpecimenHeader::split`]. All values mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpecimenParts<'a> {
    /// Reference positions, two per node (x, y).
    pub nodes_mm: &'a [f64],
    /// Node indices, [`ELEMENT_NODES`] per element, as exact integers.
    pub elements: &'a [f64],
    /// Solved displacements, two per node.
    pub displacement_mm: &'a [f64],
    /// Grip modes, `grips` blocks of two values per node (mm per mm of grip motion).
    pub modes: &'a [f64],
}

/// Why a sample cannot be read.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SpecimenError {
    #[error(transparent)]
    LayoutVersion(#[from] crate::layouts::LayoutVersionError),
    #[error("specimen solve {solve_id} declares {grips} grips, at most {MAX_SPECIMEN_GRIPS}")]
    Grips { solve_id: u64, grips: u32 },
    #[error("specimen solve {solve_id}: {nodes} nodes, {elements} elements and {grips} grips need {expected} values, the payload holds {found}")]
    PayloadLength {
        solve_id: u64,
        nodes: u32,
        elements: u32,
        grips: u32,
        expected: usize,
        found: usize,
    },
    #[error("specimen solve {solve_id}: element {element} names node {value}, not one of the {nodes} nodes")]
    Element {
        solve_id: u64,
        element: usize,
        value: f64,
        nodes: u32,
    },
    #[error(
        "specimen solve {solve_id}: value {index} of the payload is {value}, not a finite number"
    )]
    NotFinite {
        solve_id: u64,
        index: usize,
        value: f64,
    },
}

impl SpecimenHeader {
    /// Values in the payload of `nodes` nodes, `elements` elements and `grips` grips.
    pub fn payload_len(nodes: usize, elements: usize, grips: usize) -> usize {
        2 * nodes + ELEMENT_NODES * elements + 2 * nodes * (1 + grips)
    }

    /// The payload's parts, after checking the version, the length, that every value is
    /// finite and every element names nodes of the mesh.
    pub fn split<'a>(&self, payload: &'a [f64]) -> Result<SpecimenParts<'a>, SpecimenError> {
        let solve_id = self.solve_id;
        crate::layouts::check_version("specimen", self.layout_version)?;
        if self.grips as usize > MAX_SPECIMEN_GRIPS {
            return Err(SpecimenError::Grips {
                solve_id,
                grips: self.grips,
            });
        }
        let (n, e, g) = (
            self.node_count as usize,
            self.element_count as usize,
            self.grips as usize,
        );
        let expected = Self::payload_len(n, e, g);
        if payload.len() != expected {
            return Err(SpecimenError::PayloadLength {
                solve_id,
                nodes: self.node_count,
                elements: self.element_count,
                grips: self.grips,
                expected,
                found: payload.len(),
            });
        }
        if let Some(index) = payload.iter().position(|v| !v.is_finite()) {
            return Err(SpecimenError::NotFinite {
                solve_id,
                index,
                value: payload[index],
            });
        }
        let (nodes_mm, rest) = payload.split_at(2 * n);
        let (elements, rest) = rest.split_at(ELEMENT_NODES * e);
        let (displacement_mm, modes) = rest.split_at(2 * n);
        if let Some(index) = elements
            .iter()
            .position(|&v| !(v >= 0.0 && v < n as f64 && v.fract() == 0.0))
        {
            return Err(SpecimenError::Element {
                solve_id,
                element: index / ELEMENT_NODES,
                value: elements[index],
                nodes: self.node_count,
            });
        }
        Ok(SpecimenParts {
            nodes_mm,
            elements,
            displacement_mm,
            modes,
        })
    }
}

/// The solve id of a specimen's `solve`-th state in the rig's test `test_index`.
pub fn solve_id(test_index: u32, solve: u64) -> u64 {
    (u64::from(test_index) << 32) | (solve & 0xffff_ffff)
}

/// FNV-1a over the mesh's positions (bit patterns) and connectivity: what
/// [`SpecimenHeader::mesh_fingerprint`] holds.
pub fn mesh_fingerprint(nodes_mm: &[f64], elements: &[f64]) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for v in nodes_mm.iter().chain(elements) {
        for byte in v.to_bits().to_le_bytes() {
            hash ^= u64::from(byte);
            hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    hash
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (SpecimenHeader, Vec<f64>) {
        // One six-node triangle.
        let nodes = [0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
        let elements = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let mut payload = nodes.to_vec();
        payload.extend(elements);
        payload.extend([0.1; 12]);
        payload.extend([0.5; 12]);
        let header = SpecimenHeader {
            layout_version: crate::LAYOUT_VERSION,
            grips: 1,
            solve_id: 3,
            t_sim_s: 1.5,
            node_count: 6,
            element_count: 1,
            mesh_fingerprint: mesh_fingerprint(&nodes, &elements),
            grip_mm: [1.0, 0.0, 0.0, 0.0],
            grip_force_n: [10.0, 0.0, 0.0, 0.0],
        };
        (header, payload)
    }

    #[test]
    fn a_sample_splits_into_its_parts() {
        let (header, payload) = sample();
        assert_eq!(payload.len(), SpecimenHeader::payload_len(6, 1, 1));
        let parts = header.split(&payload).unwrap();
        assert_eq!(parts.nodes_mm.len(), 12);
        assert_eq!(parts.elements, &[0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(parts.displacement_mm, &[0.1; 12]);
        assert_eq!(parts.modes, &[0.5; 12]);
        assert_eq!(
            header.mesh_fingerprint,
            mesh_fingerprint(parts.nodes_mm, parts.elements)
        );
    }

    #[test]
    fn bad_samples_are_refused_naming_what_is_wrong() {
        let (header, payload) = sample();
        let short = header.split(&payload[1..]).unwrap_err();
        assert!(matches!(
            short,
            SpecimenError::PayloadLength {
                expected: 42,
                found: 41,
                ..
            }
        ));
        let mut nan = payload.clone();
        nan[20] = f64::NAN;
        assert!(matches!(
            header.split(&nan),
            Err(SpecimenError::NotFinite { index: 20, .. })
        ));
        let mut beyond = payload.clone();
        beyond[12 + 4] = 6.0;
        let e = header.split(&beyond).unwrap_err();
        assert!(e.to_string().contains("names node 6"), "{e}");
        let mut half = payload;
        half[12] = 0.5;
        assert!(header.split(&half).is_err());
        let old = SpecimenHeader {
            layout_version: 4,
            ..header
        };
        assert!(old
            .split(&[])
            .unwrap_err()
            .to_string()
            .contains("version 4"));
        let many = SpecimenHeader { grips: 5, ..header };
        assert!(matches!(many.split(&[]), Err(SpecimenError::Grips { .. })));
    }

    #[test]
    fn the_fingerprint_sees_a_moved_node_and_a_renumbered_element() {
        let (_, payload) = sample();
        let (nodes, elements) = (&payload[..12], &payload[12..18]);
        let base = mesh_fingerprint(nodes, elements);
        let mut moved = nodes.to_vec();
        moved[3] += 1e-12;
        assert_ne!(base, mesh_fingerprint(&moved, elements));
        let mut renumbered = elements.to_vec();
        renumbered.swap(3, 4);
        assert_ne!(base, mesh_fingerprint(nodes, &renumbered));
    }
}
