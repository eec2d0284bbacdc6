//! The result of one correlation: nodes of the mesh and gauge readings.

use crate::settings::StrainMeasure;

pub use wire::NodeStatus;

/// In-plane strain components (engineering strain, dimensionless; exy is the tensor component).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Strain2 {
    pub exx: f64,
    pub eyy: f64,
    pub exy: f64,
}

/// A gauge's mean strain in the four measures (CORRELI-GAUGE over its region, `gauges.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct GaugeStrains {
    pub small: Strain2,
    pub green: Strain2,
    pub nominal: Strain2,
    pub log: Strain2,
}

impl GaugeStrains {
    pub fn get(&self, measure: StrainMeasure) -> Strain2 {
        match measure {
            StrainMeasure::Small => self.small,
            StrainMeasure::Green => self.green,
            StrainMeasure::Nominal => self.nominal,
            StrainMeasure::Log => self.log,
        }
    }
}

/// One node of the mesh: ZOI centre in the reference image given to `set_reference`
/// (px, x = column, y = row, origin at the centre of the top-left pixel) and its displacement.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Node {
    pub x_px: f64,
    pub y_px: f64,
    pub u_px: f64,
    pub v_px: f64,
    /// Strain of the chosen measure (zero where the node or its window is invalid).
    pub exx: f64,
    pub eyy: f64,
    pub exy: f64,
    /// The final check (independent of how the match was found): zero-normalised
    /// cross-correlation, -1..=1, of the reference ZOI (all its pixels, unwindowed) with the
    /// deformed image sampled (bilinear) at the node's final displacement and local gradient.
    /// `ok` needs at least `min_zncc`; 0 where no match was checked.
    pub score: f64,
    /// Sub-pixel Fourier-shift iterations done.
    pub iterations: u32,
    pub status: NodeStatus,
}

/// A displacement and strain field on a regular mesh of `nx` x `ny` nodes (row-major, x fastest).
#[derive(Clone, Debug, Default)]
pub struct Field {
    pub nx: usize,
    pub ny: usize,
    pub nodes: Vec<Node>,
    /// The control gauge's strains (`settings.control_gauge`: the mesh's central region by
    /// default; NaN when it has no reading, `gauges::NoReading`).
    pub gauge: GaugeStrains,
    /// The valid nodes the control gauge read.
    pub gauge_nodes: usize,
    /// The user's gauges' readings, in the order of `settings.gauges`.
    pub gauges: Vec<crate::gauges::GaugeReading>,
    /// Nodes with status Ok.
    pub valid: usize,
    /// Mean u, v over valid nodes (px; 0 when none).
    pub u_mean_px: f64,
    pub v_mean_px: f64,
    /// Global integer ROI displacement (U0, V0) of this frame against its reference (px):
    /// None when it was not needed (every node had a prediction) or its peak was not
    /// significant.
    pub global_px: Option<(i64, i64)>,
    /// The keypoint guess ran on this frame (a new reference whose cheaper guesses did not
    /// verify).
    pub keypoints_used: bool,
    /// True when the reference was replaced after this frame (auto and incremental modes).
    pub reference_updated: bool,
    /// Each node's total displacement gradient [[∂u/∂X, ∂u/∂Y], [∂v/∂X, ∂v/∂Y]] against the
    /// frame the mesh was defined in, the one its strains come from: IC-GN's own shape function
    /// (composed with the gradient at the current reference's base) for the IC-GN methods, the
    /// least-squares gradient of the neighbouring nodes for `correli`; zero where the node is
    /// not `ok`. A gauge is always the least-squares fit over its valid nodes' displacements.
    pub gradients: Vec<[[f64; 2]; 2]>,
    /// Method `icgn`: the nodes whose result is a second-order IC-GN's (the others' are
    /// first-order), see `correlator/order_stage.rs`; all false with the other methods.
    pub second_order: Vec<bool>,
    /// Method `icgn`: the nodes re-run at second order in this frame (kept or not).
    pub second_order_runs: usize,
}

impl Field {
    /// The `ok` nodes whose result is second order (method `icgn`).
    pub fn second_order_nodes(&self) -> usize {
        (self.nodes.iter().zip(&self.second_order))
            .filter(|(node, &second)| second && node.status == NodeStatus::Ok)
            .count()
    }

    pub fn node(&self, i: usize, j: usize) -> &Node {
        &self.nodes[j * self.nx + i]
    }

    /// Nodes with this status.
    pub fn count(&self, status: NodeStatus) -> usize {
        self.nodes.iter().filter(|n| n.status == status).count()
    }

    /// Nodes whose ZOI lies inside the region (all but the `outside_region` ones): the nodes
    /// measured.
    pub fn in_region(&self) -> usize {
        self.nodes.len() - self.count(NodeStatus::OutsideRegion)
    }

    /// The statuses other than `ok` and `outside_region` that occur, with their counts, as
    /// `word count, ...` (empty when every node in the region is `ok`): why nodes were refused,
    /// in one line.
    pub fn refusals(&self) -> String {
        NodeStatus::ALL[1..]
            .iter()
            .filter(|&&s| s != NodeStatus::OutsideRegion)
            .map(|&s| (s, self.count(s)))
            .filter(|&(_, c)| c > 0)
            .map(|(s, c)| format!("{} {c}", s.name()))
            .collect::<Vec<_>>()
            .join(", ")
    }
}
