//! The specimen's solved states as received from the rig (`wire::specimen`): the reference
//! mesh, built once per specimen, and the latest solves, each a displacement and its grip modes
//! ([`membrane::GripLinearField`]). A frame or a field names a solve and the grips'
//! displacements; [`SpecimenStates::field`] gives what the camera films then. Pure (fed with
//! samples; no IPC): the camera and the run's recorder share it.

use crate::error::ProducerError;
use crate::field_motion::{FieldMotion, Framing, ReferenceMesh, View};
use membrane::{GripLinearField, Mesh};
use std::collections::VecDeque;
use std::sync::Arc;
use wire::specimen::{SpecimenHeader, SpecimenParts, ELEMENT_NODES};
use wire::SpecimenError;

/// Solves kept: a frame names a solve at most a few periods old (the rig solves at most 10
/// times a second; frames and fields arrive within a second).
pub const SOLVES_KEPT: usize = 32;

/// One received solve.
#[derive(Clone, Debug)]
pub struct Solve {
    pub id: u64,
    pub t_sim_s: f64,
    pub mesh: Arc<ReferenceMesh>,
    pub field: GripLinearField,
}

/// The latest solves, and the mesh they share.
#[derive(Debug, Default)]
pub struct SpecimenStates {
    mesh: Option<(u64, Arc<ReferenceMesh>)>,
    solves: VecDeque<Solve>,
    received: u64,
    /// Solves kept whatever their age (the origin frames' of the latest sequences), newest last.
    pinned: VecDeque<u64>,
}

/// Solves pinned at most.
pub const PINNED_KEPT: usize = 4;

/// Why a frame's field cannot be given.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    #[error("specimen solve {0} was not received (or is older than the {SOLVES_KEPT} kept)")]
    Unknown(u64),
    #[error(transparent)]
    Sample(#[from] SpecimenError),
    #[error(transparent)]
    Field(#[from] ProducerError),
}

impl SpecimenStates {
    pub fn new() -> Self {
        Self::default()
    }

    /// Samples taken so far.
    pub fn received(&self) -> u64 {
        self.received
    }

    /// Takes a received sample (checked; a refused one changes nothing). The mesh is built
    /// again only when its fingerprint changes (another specimen).
    pub fn push(&mut self, header: &SpecimenHeader, payload: &[f64]) -> Result<(), StateError> {
        let parts = header.split(payload)?;
        let mesh = match &self.mesh {
            Some((fingerprint, mesh)) if *fingerprint == header.mesh_fingerprint => mesh.clone(),
            _ => {
                let mesh = ReferenceMesh::new(mesh_of(&parts));
                self.mesh = Some((header.mesh_fingerprint, mesh.clone()));
                mesh
            }
        };
        let grips = header.grips as usize;
        let per_mode = parts.displacement_mm.len();
        let field = GripLinearField {
            displacement_mm: parts.displacement_mm.to_vec(),
            grip_mm: header.grip_mm[..grips].to_vec(),
            modes: parts
                .modes
                .chunks_exact(per_mode.max(1))
                .map(<[f64]>::to_vec)
                .collect(),
        };
        self.solves.retain(|s| s.id != header.solve_id);
        if self.solves.len() >= SOLVES_KEPT + self.pinned.len() {
            if let Some(oldest) = self
                .solves
                .iter()
                .position(|s| !self.pinned.contains(&s.id))
            {
                self.solves.remove(oldest);
            }
        }
        self.solves.push_back(Solve {
            id: header.solve_id,
            t_sim_s: header.t_sim_s,
            mesh,
            field,
        });
        self.received += 1;
        Ok(())
    }

    /// Keeps solve `id` whatever its age (a sequence's origin frame names it), in place of the
    /// oldest pin beyond [`PINNED_KEPT`].
    pub fn pin(&mut self, id: u64) {
        if !self.pinned.contains(&id) {
            if self.pinned.len() == PINNED_KEPT {
                self.pinned.pop_front();
            }
            self.pinned.push_back(id);
        }
    }

    /// The solve `id`, if kept.
    pub fn solve(&self, id: u64) -> Option<&Solve> {
        self.solves.iter().rev().find(|s| s.id == id)
    }

    /// The field of solve `id` followed to the grips' displacements `grip_mm`, seen through
    /// `view`.
    pub fn field(&self, id: u64, grip_mm: &[f64], view: View) -> Result<FieldMotion, StateError> {
        let solve = self.solve(id).ok_or(StateError::Unknown(id))?;
        Ok(FieldMotion::new(
            solve.mesh.clone(),
            solve.field.at(grip_mm),
            view,
        )?)
    }

    /// The field of solve `id` at `grip_mm` as the camera frames its specimen (by the number
    /// of grips holding it) in a `size_px` image.
    pub fn framed_field(
        &self,
        id: u64,
        grip_mm: &[f64],
        framing: &Framing,
        size_px: [u32; 2],
    ) -> Result<FieldMotion, StateError> {
        let solve = self.solve(id).ok_or(StateError::Unknown(id))?;
        let view = framing.view(solve.field.grip_mm.len(), size_px[0], size_px[1]);
        self.field(id, grip_mm, view)
    }
}

fn mesh_of(parts: &SpecimenParts<'_>) -> Mesh {
    Mesh {
        nodes_mm: parts
            .nodes_mm
            .chunks_exact(2)
            .map(|p| [p[0], p[1]])
            .collect(),
        // Checked by `split`: whole numbers naming nodes.
        elements: parts
            .elements
            .chunks_exact(ELEMENT_NODES)
            .map(|e| std::array::from_fn(|k| e[k] as usize))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wire::specimen::{mesh_fingerprint, SpecimenHeader};

    /// One six-node triangle, one grip whose mode moves every node by 1 mm along x per mm.
    fn sample(id: u64, grip_mm: f64) -> (SpecimenHeader, Vec<f64>) {
        let nodes = [0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0];
        let elements = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let mut payload = nodes.to_vec();
        payload.extend(elements);
        payload.extend((0..6).flat_map(|_| [grip_mm, 0.0]));
        payload.extend((0..6).flat_map(|_| [1.0, 0.0]));
        let header = SpecimenHeader {
            layout_version: wire::LAYOUT_VERSION,
            grips: 1,
            solve_id: id,
            node_count: 6,
            element_count: 1,
            mesh_fingerprint: mesh_fingerprint(&nodes, &elements),
            grip_mm: [grip_mm, 0.0, 0.0, 0.0],
            ..SpecimenHeader::default()
        };
        (header, payload)
    }

    fn view() -> View {
        View {
            mm_per_px: 0.1,
            centre_px: [0.0, 0.0],
            centre_mm: [0.0, 0.0],
        }
    }

    #[test]
    fn a_solve_followed_to_other_grips_moves_by_its_mode() {
        let mut states = SpecimenStates::new();
        let (h, p) = sample(7, 0.5);
        states.push(&h, &p).unwrap();
        // The reference point (0.5, 0.5) mm = (5, 5) px: at the solve it moved 0.5 mm = 5 px,
        // 0.2 mm further at grips 0.7 mm.
        let at_solve = states.field(7, &[0.5], view()).unwrap();
        let u = at_solve.displacement_px([5.0, 5.0]).unwrap();
        assert!((u[0] - 5.0).abs() < 1e-9 && u[1].abs() < 1e-9, "{u:?}");
        let further = states.field(7, &[0.7], view()).unwrap();
        assert!((further.displacement_px([5.0, 5.0]).unwrap()[0] - 7.0).abs() < 1e-9);
        assert!(matches!(
            states.field(8, &[0.5], view()),
            Err(StateError::Unknown(8))
        ));
    }

    #[test]
    fn old_solves_go_but_pinned_ones_stay_and_a_bad_sample_changes_nothing() {
        let mut states = SpecimenStates::new();
        for id in 0..(SOLVES_KEPT as u64 + 10) {
            let (h, p) = sample(id, 0.01 * id as f64);
            states.push(&h, &p).unwrap();
            if id == 0 {
                states.pin(0);
            }
        }
        assert!(states.solve(0).is_some(), "pinned");
        assert!(states.solve(1).is_none(), "evicted");
        assert!(states.solve(SOLVES_KEPT as u64 + 9).is_some());
        let (h, p) = sample(99, 0.0);
        assert!(states.push(&h, &p[1..]).is_err());
        assert!(states.solve(99).is_none());
        assert_eq!(states.received(), SOLVES_KEPT as u64 + 10);
    }
}
