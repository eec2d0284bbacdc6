//! The `specimen` service: the structure's solved states, one sample per new solve, so the
//! camera films the finite-element field and the recorder compares against it node by node
//! (`wire::specimen`). Only a rig whose mounted specimen is a structure publishes; the
//! publisher is made at the first solved state and made again, larger, when a later test
//! mounts a specimen of more nodes.

use super::ProcessError;
use crate::specimen::{SolvedState, Structure};
use iceoryx2::prelude::*;
use wire::specimen::{mesh_fingerprint, solve_id, SpecimenHeader};

type Publisher = wire::pubsub::SlicePublisher<f64, SpecimenHeader>;

/// The mesh of one mounted specimen, flattened once.
struct FlatMesh {
    test_index: u32,
    nodes_mm: Vec<f64>,
    elements: Vec<f64>,
    fingerprint: u64,
}

pub(super) struct SpecimenPort {
    publisher: Option<Publisher>,
    mesh: Option<FlatMesh>,
    /// The solve id last published.
    last: Option<u64>,
}

/// The wire's solve id and the grips' displacements at the rig's actuator positions, for
/// `rig/state`: what a frame taken now shows.
pub(super) fn solve_at(
    structure: &Structure,
    test_index: u32,
    position_mm: &[f64; crate::hydraulics::ACTUATOR_COUNT],
) -> (u64, [f64; 4]) {
    (
        solve_id(test_index, structure.solved().id),
        structure.grip_mm_at(position_mm),
    )
}

impl SpecimenPort {
    pub fn new() -> Self {
        SpecimenPort {
            publisher: None,
            mesh: None,
            last: None,
        }
    }

    /// Publishes the structure's solved state if it is new.
    pub fn publish(
        &mut self,
        node: &Node<ipc::Service>,
        structure: &Structure,
        test_index: u32,
    ) -> Result<(), ProcessError> {
        let solved = structure.solved();
        let id = solve_id(test_index, solved.id);
        if self.last == Some(id) {
            return Ok(());
        }
        if self.mesh.as_ref().map(|m| m.test_index) != Some(test_index) {
            self.mesh = Some(flatten(&solved, test_index));
        }
        let mesh = self.mesh.as_ref().expect("flattened above");
        let len = SpecimenHeader::payload_len(
            solved.mesh.nodes_mm.len(),
            solved.mesh.elements.len(),
            solved.grips,
        );
        if self.publisher.as_ref().is_none_or(|p| p.max_len() < len) {
            // The old one goes first: the service takes one publisher.
            self.publisher = None;
            let spec = &wire::services::SPECIMEN;
            let bytes = spec.shm_bytes(std::mem::size_of::<SpecimenHeader>(), 8 * 2 * len);
            wire::shm::ensure_free(wire::shm::SHM_PATH, bytes)?;
            self.publisher = Some(Publisher::create(node, spec, 2 * len)?);
        }
        let publisher = self.publisher.as_ref().expect("made above");
        publisher
            .publish(len, |header, payload| {
                fill(header, payload, &solved, mesh, id);
                Ok::<_, std::convert::Infallible>(true)
            })?
            .unwrap_or_else(|never| match never {});
        self.last = Some(id);
        Ok(())
    }
}

fn flatten(solved: &SolvedState<'_>, test_index: u32) -> FlatMesh {
    let nodes_mm: Vec<f64> = solved.mesh.nodes_mm.iter().flatten().copied().collect();
    let elements: Vec<f64> = solved
        .mesh
        .elements
        .iter()
        .flatten()
        .map(|&n| n as f64)
        .collect();
    let fingerprint = mesh_fingerprint(&nodes_mm, &elements);
    FlatMesh {
        test_index,
        nodes_mm,
        elements,
        fingerprint,
    }
}

fn fill(
    header: &mut SpecimenHeader,
    payload: &mut [f64],
    solved: &SolvedState<'_>,
    mesh: &FlatMesh,
    id: u64,
) {
    *header = SpecimenHeader {
        layout_version: wire::LAYOUT_VERSION,
        grips: solved.grips as u32,
        solve_id: id,
        t_sim_s: solved.t_s,
        node_count: solved.mesh.nodes_mm.len() as u32,
        element_count: solved.mesh.elements.len() as u32,
        mesh_fingerprint: mesh.fingerprint,
        grip_mm: *solved.grip_mm,
        grip_force_n: *solved.grip_force_n,
    };
    let parts = [
        &mesh.nodes_mm[..],
        &mesh.elements[..],
        solved.displacement_mm,
    ]
    .into_iter()
    .chain(solved.modes.iter().map(Vec::as_slice));
    let mut at = 0;
    for part in parts {
        payload[at..at + part.len()].copy_from_slice(part);
        at += part.len();
    }
    debug_assert_eq!(at, payload.len());
}
