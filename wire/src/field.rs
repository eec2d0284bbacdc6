//! `fields`: one measured displacement/strain field as a `[FieldNode]` slice (row-major over
//! the ZOI mesh, `mesh_cols * mesh_rows` nodes) behind a [`FieldHeader`].

#[cfg(feature = "ipc")]
use iceoryx2::prelude::ZeroCopySend;

/// Strain measures of the paper's eq. (13), plus the infinitesimal strain.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StrainMeasure {
    /// ε = sym(∇u).
    Small = 0,
    /// m = 1: E = (C − 1)/2.
    Green = 1,
    /// m = 1/2: E = C^(1/2) − 1 (ΔL/L0 in uniaxial elongation).
    Nominal = 2,
    /// m = 0: E = ln(C)/2, the default.
    #[default]
    Log = 3,
}

crate::named!(StrainMeasure, "strain measure", {
    Small => "small", Green => "green", Nominal => "nominal", Log => "log",
});

impl StrainMeasure {
    pub fn from_code(code: u32) -> Option<StrainMeasure> {
        StrainMeasure::ALL
            .iter()
            .copied()
            .find(|m| *m as u32 == code)
    }
}

/// Outcome of one ZOI (the correlator's and [`FieldNode::status`]'s code).
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NodeStatus {
    /// Converged: displacement and score are meaningful.
    Ok = 0,
    /// The integer search did not settle, the sub-pixel iterations hit the cap, or the
    /// correlation peak is far below the frame's median (a match on other material).
    NotConverged = 1,
    /// The reference or deformed ZOI has (almost) no grey-level variation.
    LowContrast = 2,
    /// The deformed ZOI left the image.
    #[default]
    OutsideImage = 3,
    /// The final check failed: the reference ZOI against the deformed image sampled through
    /// the node's displacement and local gradient has a ZNCC below `min_zncc`.
    LowZncc = 4,
    /// Further than 2 px from the affine fit of its neighbours.
    Inconsistent = 5,
    /// No guess could be trusted for this node (the global correlation peak was not
    /// significant and no other guess verified), so it was not measured.
    NoGuess = 6,
    /// Not measured: the node's ZOI does not lie wholly inside the region the user chose
    /// (polygons, mask). Never a failure.
    OutsideRegion = 7,
}

crate::named!(NodeStatus, "node status", {
    Ok => "ok", NotConverged => "not_converged", LowContrast => "low_contrast",
    OutsideImage => "outside_image", LowZncc => "low_zncc", Inconsistent => "inconsistent",
    NoGuess => "no_guess", OutsideRegion => "outside_region",
});

impl NodeStatus {
    pub fn from_code(code: u32) -> Option<NodeStatus> {
        NodeStatus::ALL.iter().copied().find(|s| *s as u32 == code)
    }
}

/// Where a field's node gradients come from, carried in [`FieldHeader::gradient_source`].
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GradientSource {
    /// The least-squares fit of the node's neighbouring displacements (method `correli`).
    NeighbourFit = 0,
    /// The node's own first-order (affine) IC-GN shape function (method `icgn1`).
    Icgn1 = 1,
    /// The first-order part of the node's second-order IC-GN shape function (`icgn2`).
    Icgn2 = 2,
}

impl GradientSource {
    pub const ALL: [GradientSource; 3] = [
        GradientSource::NeighbourFit,
        GradientSource::Icgn1,
        GradientSource::Icgn2,
    ];

    pub fn name(self) -> &'static str {
        match self {
            GradientSource::NeighbourFit => "neighbour_fit",
            GradientSource::Icgn1 => "icgn1",
            GradientSource::Icgn2 => "icgn2",
        }
    }

    pub fn from_code(code: u32) -> Option<GradientSource> {
        GradientSource::ALL.into_iter().find(|g| *g as u32 == code)
    }
}

/// One ZOI of the mesh. Strains are of the measure named in the header.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.FieldNode.v6")
)]
pub struct FieldNode {
    /// ZOI centre in the reference image (px).
    pub x_px: f32,
    pub y_px: f32,
    /// Displacement (px).
    pub u_px: f32,
    pub v_px: f32,
    pub exx: f32,
    pub eyy: f32,
    pub exy: f32,
    /// The correlator's final check: ZNCC in [-1, 1] of the reference ZOI against the
    /// deformed image sampled at the node's displacement and local gradient (0 when unchecked).
    pub score: f32,
    pub iterations: u32,
    /// A [`NodeStatus`] code.
    pub status: u32,
    /// The node's total displacement gradient against the frame the mesh was defined in
    /// (`origin_frame_id`), dimensionless: ∂u/∂x, ∂u/∂y, ∂v/∂x, ∂v/∂y, the one its strains
    /// come from. Where it comes from is the header's `gradient_source`; zero where the node
    /// is not `ok`.
    pub du_dx: f32,
    pub du_dy: f32,
    pub dv_dx: f32,
    pub dv_dy: f32,
}

/// In-plane strain components (dimensionless).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.GaugeStrain.v6")
)]
pub struct GaugeStrain {
    pub exx: f64,
    pub eyy: f64,
    pub exy: f64,
}

/// Header of one field on the `fields` service.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "ipc",
    derive(ZeroCopySend),
    type_name("dicstream.FieldHeader.v6")
)]
pub struct FieldHeader {
    pub layout_version: u32,
    /// The [`StrainMeasure`] code of the node strains.
    pub strain_measure: u32,
    /// The frame this field was measured on, and the reference it was correlated against.
    pub frame_id: u64,
    pub reference_frame_id: u64,
    /// The frame the mesh is defined in: node positions are in its image and displacements
    /// are counted from it (equal to `reference_frame_id` unless the reference was renewed
    /// with the mesh followed).
    pub origin_frame_id: u64,
    /// Copied from the frame: capture time and rig sample (monotonic ns).
    pub t_capture_ns: u64,
    pub rig_sample_id: u64,
    /// When the correlator received the frame and published this field (monotonic ns).
    pub t_received_ns: u64,
    pub t_published_ns: u64,
    /// Time spent correlating this frame (ns).
    pub correlate_ns: u64,
    /// Frames the correlator skipped so far (gaps in frame ids it saw).
    pub frames_dropped: u64,
    pub mesh_cols: u32,
    pub mesh_rows: u32,
    pub zoi_px: u32,
    pub step_px: u32,
    pub valid_nodes: u32,
    /// 1 when `truth` holds the frame's exact imposed motion.
    pub has_truth: u32,
    pub truth: crate::frame::GroundTruth,
    pub u_mean_px: f64,
    pub v_mean_px: f64,
    /// The control gauge's strains (the correlator's `control_gauge`: by default the mesh's
    /// central half) in the order of [`StrainMeasure::ALL`]; NaN when it has no reading (fewer
    /// than 3 valid nodes in it, not on one line): a consumer holds rather than read a 0.
    pub gauge: [GaugeStrain; 4],
    /// The frame's `sequence_id`.
    pub sequence_id: u32,
    /// A [`GradientSource`] code: where the nodes' `du_dx`.. `dv_dy` (and so their strains)
    /// come from.
    pub gradient_source: u32,
}

impl FieldHeader {
    pub fn node_count(&self) -> usize {
        self.mesh_cols as usize * self.mesh_rows as usize
    }

    /// Checks the header is one this build understands and consistent with its payload of
    /// `payload_len` nodes.
    pub fn validate(&self, payload_len: usize) -> Result<(), FieldError> {
        crate::layouts::check_version("field", self.layout_version)?;
        if payload_len != self.node_count() {
            return Err(FieldError::PayloadLength {
                frame_id: self.frame_id,
                mesh_cols: self.mesh_cols,
                mesh_rows: self.mesh_rows,
                payload_len,
            });
        }
        Ok(())
    }

    pub fn gauge_of(&self, measure: StrainMeasure) -> GaugeStrain {
        self.gauge[measure as usize]
    }
}

/// Why a field's header was refused by [`FieldHeader::validate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FieldError {
    #[error(transparent)]
    LayoutVersion(#[from] crate::layouts::LayoutVersionError),
    #[error("field of frame {frame_id}: header says {mesh_cols}x{mesh_rows} = {} nodes but the payload holds {payload_len}", *.mesh_cols as usize * *.mesh_rows as usize)]
    PayloadLength {
        frame_id: u64,
        mesh_cols: u32,
        mesh_rows: u32,
        payload_len: usize,
    },
}

/// The nodes' bytes as they lie in shared memory (a `FieldNode` has no padding: `layouts`).
pub fn node_bytes(nodes: &[FieldNode]) -> &[u8] {
    crate::plain::slice_bytes(nodes)
}

/// [`crate::frame::byte_checksum`] of the nodes' bytes: two readers of one field agree on it.
pub fn nodes_checksum(nodes: &[FieldNode]) -> u64 {
    crate::frame::byte_checksum(node_bytes(nodes))
}

impl Default for FieldHeader {
    fn default() -> Self {
        FieldHeader {
            layout_version: crate::LAYOUT_VERSION,
            strain_measure: StrainMeasure::Log as u32,
            frame_id: 0,
            reference_frame_id: 0,
            origin_frame_id: 0,
            t_capture_ns: 0,
            rig_sample_id: crate::NO_RIG_SAMPLE,
            t_received_ns: 0,
            t_published_ns: 0,
            correlate_ns: 0,
            frames_dropped: 0,
            mesh_cols: 0,
            mesh_rows: 0,
            zoi_px: 0,
            step_px: 0,
            valid_nodes: 0,
            has_truth: 0,
            truth: crate::frame::GroundTruth::IDENTITY,
            u_mean_px: 0.0,
            v_mean_px: 0.0,
            gauge: [GaugeStrain::default(); 4],
            sequence_id: 0,
            gradient_source: GradientSource::NeighbourFit as u32,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip() {
        for m in StrainMeasure::ALL {
            assert_eq!(StrainMeasure::from_code(m as u32), Some(m));
        }
        assert_eq!(StrainMeasure::from_code(9), None);
        assert_eq!(NodeStatus::from_code(2), Some(NodeStatus::LowContrast));
        assert_eq!(NodeStatus::from_code(4), Some(NodeStatus::LowZncc));
        assert_eq!(NodeStatus::from_code(7), Some(NodeStatus::OutsideRegion));
        assert_eq!(NodeStatus::from_code(8), None);
        assert_eq!(StrainMeasure::Log.name(), "log");
        for g in GradientSource::ALL {
            assert_eq!(GradientSource::from_code(g as u32), Some(g));
        }
        assert_eq!(GradientSource::from_code(3), None);
        assert_eq!(GradientSource::NeighbourFit.name(), "neighbour_fit");
    }

    #[test]
    fn validate_refuses_another_version_and_length_and_the_checksum_sees_a_value() {
        let header = FieldHeader {
            mesh_cols: 3,
            mesh_rows: 2,
            ..FieldHeader::default()
        };
        assert_eq!(header.validate(6), Ok(()));
        assert_eq!(
            header.validate(5).unwrap_err().to_string(),
            "field of frame 0: header says 3x2 = 6 nodes but the payload holds 5"
        );
        let old = FieldHeader {
            layout_version: 1,
            ..header
        };
        assert!(old
            .validate(6)
            .unwrap_err()
            .to_string()
            .starts_with("field layout version 1 but this build reads version"));
        let mut nodes = [FieldNode::default(); 6];
        assert_eq!(node_bytes(&nodes).len(), 6 * 56);
        let before = nodes_checksum(&nodes);
        nodes[4].dv_dy = 1e-6;
        assert_ne!(nodes_checksum(&nodes), before);
    }
}
