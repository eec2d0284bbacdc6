//! User settings of the correlator and their validation.

use crate::gauges::{ControlGauge, Gauge, GaugeShape};
use crate::region::{Region, ResolvedRegion};
use thiserror::Error;

/// Region of interest in the reference image, in pixels (x = column, y = row of the top-left pixel).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Roi {
    pub x_px: usize,
    pub y_px: usize,
    pub width_px: usize,
    pub height_px: usize,
}

/// As `--roi` takes it: `x,y,width,height`.
impl std::fmt::Display for Roi {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{},{},{},{}",
            self.x_px, self.y_px, self.width_px, self.height_px
        )
    }
}

impl Roi {
    /// Its pixel columns and rows as a summary says them: `x 16-2032 y 16-573` (the first
    /// pixel and one past the last).
    pub fn extent(&self) -> String {
        format!(
            "x {}-{} y {}-{}",
            self.x_px,
            self.x_px + self.width_px,
            self.y_px,
            self.y_px + self.height_px
        )
    }
}

/// Strain measure of the per-node strains (the gauge gives all four): wire's, the one the
/// `fields` header names.
pub use wire::StrainMeasure;

/// Which image the deformed images are compared with.
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReferenceMode {
    /// The reference given to `set_reference` stays for every frame.
    #[default]
    Fixed,
    /// Each frame is correlated with the previous one; displacements accumulate on the followed mesh.
    Incremental,
    /// The reference is replaced by the current frame (mesh followed) when the correlation
    /// against it degrades: the ZOIs deformed since the reference by more than
    /// `max_deformation_px` (how far the deformation since the reference moves a ZOI's corner
    /// relative to its centre, 90th percentile of the valid nodes), the mean score below
    /// `min_mean_score`, or more nodes refused than in the first frame against it (5 % of the
    /// nodes). A rigid motion, however large, does not call for a new reference: the
    /// predictions place every ZOI (see `correlator/renewal.rs`).
    Auto {
        max_deformation_px: f64,
        min_mean_score: f64,
    },
}

impl ReferenceMode {
    /// Auto update with `correli`'s defaults: a ZOI's corner moved 0.5 px relative to its
    /// centre by the deformation since the reference (a strain of 3 % on a 32 px ZOI), mean
    /// score 0.5. The rigid ZOI's error grows with that deformation (on a uniaxial ramp to λ 2,
    /// 1024², 120 frames: mean node error 0.0130 px at 0.5 px, 0.0147 px at 1 px, 0.0232 px at
    /// 2 px; the displacement rule it replaces renewed at about 0.4 px and gave 0.0126 px, with
    /// 36 renewals against 22; `examples/renewal_cost.rs`).
    pub const AUTO_DEFAULT: ReferenceMode = ReferenceMode::Auto {
        max_deformation_px: 0.5,
        min_mean_score: 0.5,
    };

    /// Auto update with the IC-GN methods' defaults: their shape function follows the
    /// deformation since the reference, so it may grow to 2 px at a corner (12.5 % strain on a
    /// 33 px subset; on the same ramp `icgn1`'s mean node error is 0.0084 px with 6 renewals,
    /// 0.0086 px with the 34 of the displacement rule it replaces; at 4 px the 30 % stretch of
    /// `tests/suite/icgn.rs` loses 4 % of its accuracy).
    pub const AUTO_DEFAULT_ICGN: ReferenceMode = ReferenceMode::Auto {
        max_deformation_px: 2.0,
        min_mean_score: 0.5,
    };

    /// The mode of a kind for a method (`auto` with the method's default thresholds).
    pub fn of_kind(kind: ReferenceKind, method: Method) -> ReferenceMode {
        match kind {
            ReferenceKind::Fixed => ReferenceMode::Fixed,
            ReferenceKind::Incremental => ReferenceMode::Incremental,
            ReferenceKind::Auto if method.is_icgn() => ReferenceMode::AUTO_DEFAULT_ICGN,
            ReferenceKind::Auto => ReferenceMode::AUTO_DEFAULT,
        }
    }

    pub fn kind(self) -> ReferenceKind {
        match self {
            ReferenceMode::Fixed => ReferenceKind::Fixed,
            ReferenceMode::Incremental => ReferenceKind::Incremental,
            ReferenceMode::Auto { .. } => ReferenceKind::Auto,
        }
    }
}

/// A [`ReferenceMode`] as a user chooses it: by its name, `auto` with its default thresholds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ReferenceKind {
    #[default]
    Fixed,
    Incremental,
    Auto,
}

wire::named!(ReferenceKind, "reference", {
    Fixed => "fixed", Incremental => "incremental", Auto => "auto",
});

wire::named!(GuessMode, "guess", { Auto => "auto", Correli => "correli", Predict => "predict" });

/// Initial guess of each ZOI before its integer FFT correlation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum GuessMode {
    /// The cheapest guess that verifies: the previous frame's field (as `Predict`) or the
    /// global (U0, V0) when its peak is significant; nodes that fail the final check are
    /// grown from their verified neighbours (their displacement and gradient, the ZOI warped
    /// accordingly, best-verified first); when too few nodes verify, keypoints matched over
    /// the whole image (invariant to rotation and scale) give a local affine guess per node.
    #[default]
    Auto,
    /// The paper: every ZOI starts from the global ROI displacement (U0, V0), when its peak
    /// is significant (otherwise the nodes are `no_guess`).
    Correli,
    /// The live path: the previous frame's field when there is one, otherwise grow from the
    /// centre node outwards, each ring starting from its converged inner neighbours.
    Predict,
}

/// How each node's sub-pixel displacement is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// CORRELI-GD as published (paper section 3.b): rigid 2^s ZOIs, windowed correlation,
    /// quadratic peak and Fourier-shift iterations. The default: 6 to 8 times faster than
    /// `Icgn1` per ZOI (the live bench's rate), and it converges on low-contrast noisy images
    /// where IC-GN does not (README, "Sub-pixel methods").
    #[default]
    Correli,
    /// Inverse compositional Gauss-Newton with a first-order (affine, 6 parameters) shape
    /// function, ZNSSD, quintic B-spline interpolation; subsets of any size from 9 px. The FFT
    /// step of the guess runs on the largest 2^s square inside the subset. About 1.5 times
    /// less noise than `Correli` at the same subset size.
    Icgn1,
    /// The same with a second-order shape function (12 parameters).
    Icgn2,
    /// IC-GN with the shape function's order chosen per node: first order everywhere, then
    /// second order, from the first-order solution, on the nodes whose neighbours' first-order
    /// gradients show a curvature that biases the first-order displacement by more than the
    /// second order's extra noise (`icgn::order_choice`); the second-order result is kept when
    /// it converged with a ZNCC at least the first's. As accurate as `Icgn2` on steep fields,
    /// as quiet as `Icgn1` on smooth ones.
    Icgn,
}

wire::named!(Method, "method", { Correli => "correli", Icgn1 => "icgn1", Icgn2 => "icgn2", Icgn => "icgn" });

impl Method {
    pub fn is_icgn(self) -> bool {
        self != Method::Correli
    }
}

/// Smallest IC-GN subset side (px).
pub const MIN_SUBSET_PX: usize = 9;
/// Largest ZOI or subset side (px).
pub const MAX_ZOI_PX: usize = 256;

/// Default of [`CorrelatorSettings::min_zncc`].
pub const DEFAULT_MIN_ZNCC: f64 = 0.7;

/// Everything the correlator needs to know before the first frame.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CorrelatorSettings {
    /// ZOI (subset) side in pixels: a power of two from 8 to 256 for `correli`, any size from
    /// 9 to 256 for the IC-GN methods.
    pub zoi_px: usize,
    /// How the sub-pixel displacement of each node is measured.
    pub method: Method,
    /// Distance between neighbouring ZOI centres, delta x = delta y, 1 ..= zoi_px.
    pub step_px: usize,
    /// Where to measure: a rectangle (the whole image less half a ZOI by default, the paper's
    /// centred 2^p square, or x,y,w,h) and polygons or a mask inside it (`region.rs`).
    pub region: Region,
    /// Measure of the per-node strains.
    pub strain: StrainMeasure,
    pub reference: ReferenceMode,
    pub guess: GuessMode,
    /// Worker threads including the calling thread (1 ..= 64).
    pub threads: usize,
    /// Cap of the sub-pixel iterations per ZOI (1 ..= 100): Fourier-shift iterations (those of
    /// IC-GN's FFT guess stop at `zoi::ICGN_GUESS_ITERATIONS` below it) and Gauss-Newton
    /// iterations.
    pub max_iterations: u32,
    /// Half-width, in nodes, of the least-squares window of the displacement gradient
    /// (1 = 3x3 nodes).
    pub strain_window_nodes: usize,
    /// A node whose final correlation score is below this fraction of the frame's median
    /// score is reported not converged: a false match on other material scores far below the
    /// nodes around it (a plain threshold would also reject the honest low scores of large
    /// ZOIs under strain). 0 keeps every node.
    pub min_relative_score: f64,
    /// A node is `ok` only when the ZNCC of its reference ZOI with the deformed image sampled
    /// at its final displacement and local gradient reaches this (0 < min_zncc < 1). Correct
    /// matches on speckle score above 0.9 even at 8 bit with visible noise; matches on other
    /// material score below 0.4.
    pub min_zncc: f64,
    /// Beyond the paper: remove, to first order, the bias of the rigid ZOI under a
    /// displacement gradient (it reports the motion of a point off its centre, weighted by
    /// where its speckles are; see `zoi::GradientSensitivity`). Off = CORRELI-GD as published.
    pub gradient_correction: bool,
    /// The user's strain gauges and extensometers (`gauges.rs`), read on every field.
    #[serde(default)]
    pub gauges: Vec<Gauge>,
    /// The gauge the field's header carries, the one strain control closes its loop on: the
    /// mesh's central region by default.
    #[serde(default)]
    pub control_gauge: ControlGauge,
}

impl Default for CorrelatorSettings {
    fn default() -> Self {
        Self {
            zoi_px: 32,
            method: Method::default(),
            step_px: 16,
            region: Region::default(),
            strain: StrainMeasure::Log,
            reference: ReferenceMode::Fixed,
            guess: GuessMode::Auto,
            threads: 2,
            max_iterations: 10,
            strain_window_nodes: 1,
            min_relative_score: 0.7,
            min_zncc: DEFAULT_MIN_ZNCC,
            gradient_correction: true,
            gauges: Vec::new(),
            control_gauge: ControlGauge::Centre,
        }
    }
}

/// Why settings or an image were refused.
#[derive(Debug, Error, PartialEq)]
pub enum SettingsError {
    #[error("ZOI size {zoi_px} px is not a power of two: use {nearest} px (CORRELI-GD needs 2^s), or --method icgn1, which takes any size from 9 px")]
    ZoiNotPowerOfTwo { zoi_px: usize, nearest: usize },
    #[error("ZOI size {zoi_px} px is out of range: expected a power of two from 8 to 256 px")]
    ZoiOutOfRange { zoi_px: usize },
    #[error("subset size {zoi_px} px is out of range: IC-GN takes any size from 9 to 256 px")]
    SubsetOutOfRange { zoi_px: usize },
    #[error("step {step_px} px is invalid: expected 1 ..= ZOI size ({zoi_px} px)")]
    Step { step_px: usize, zoi_px: usize },
    #[error("threads {threads} is invalid: expected 1 ..= 64")]
    Threads { threads: usize },
    #[error("max_iterations {max_iterations} is invalid: expected 1 ..= 100")]
    MaxIterations { max_iterations: u32 },
    #[error("strain window half-width {nodes} is invalid: expected 1 ..= 8 nodes")]
    StrainWindow { nodes: usize },
    #[error("image {width_px}x{height_px} px is too small: expected at least 16x16 px")]
    ImageTooSmall { width_px: usize, height_px: usize },
    #[error("ROI {roi} (x,y,width,height) does not fit in the {width_px}x{height_px} px image (--roi, [correlator.region] roi)")]
    RoiOutside {
        roi: Roi,
        width_px: usize,
        height_px: usize,
    },
    #[error("ZOI {zoi_px} px is larger than the ROI ({roi_width_px}x{roi_height_px} px): choose a smaller --zoi or a larger ROI (--roi, [correlator.region] roi)")]
    ZoiLargerThanRoi {
        zoi_px: usize,
        roi_width_px: usize,
        roi_height_px: usize,
    },
    #[error("{what} image has {got} pixels, expected {expected} ({width_px}x{height_px} px, the size given to Correlator::new): images must all have the same size")]
    ImageSize {
        what: &'static str,
        got: usize,
        expected: usize,
        width_px: usize,
        height_px: usize,
    },
    #[error("polygon {} of the region (--polygon, [correlator.region] polygons) \"{polygon}\" has {vertices} vertices: a polygon needs at least 3", index + 1)]
    PolygonTooFewVertices {
        index: usize,
        polygon: String,
        vertices: usize,
    },
    #[error("polygon {} of the region (--polygon, [correlator.region] polygons) \"{polygon}\" crosses itself: edges {} and {} meet (vertices in order around the outline, edge k from vertex k to k + 1)", index + 1, edges.0, edges.1)]
    PolygonSelfCrossing {
        index: usize,
        polygon: String,
        edges: (usize, usize),
    },
    #[error("polygon {} of the region (--polygon, [correlator.region] polygons) \"{polygon}\" has vertex {x},{y} outside the {width_px}x{height_px} px image (expected 0 <= x <= {width_px}, 0 <= y <= {height_px})", index + 1)]
    PolygonOutside {
        index: usize,
        polygon: String,
        x: f64,
        y: f64,
        width_px: usize,
        height_px: usize,
    },
    #[error("mask {} (--mask, [correlator.region] mask) cannot be read: {reason}", path.display())]
    MaskUnreadable {
        path: std::path::PathBuf,
        reason: String,
    },
    #[error("mask {} (--mask, [correlator.region] mask) is {width_px}x{height_px} px, expected {expected_width_px}x{expected_height_px} px like the images", path.display())]
    MaskSize {
        path: std::path::PathBuf,
        width_px: usize,
        height_px: usize,
        expected_width_px: usize,
        expected_height_px: usize,
    },
    #[error("the region ({region}) is empty: no pixel of the ROI is inside its polygons and mask (--roi, --polygon, --mask; [correlator.region])")]
    EmptyRegion { region: String },
    #[error("the region ({region}) is smaller than one {zoi_px} px ZOI: no node's ZOI fits inside it (a larger region: --roi, --polygon, --mask, [correlator.region]; or a smaller --zoi)")]
    RegionSmallerThanZoi { region: String, zoi_px: usize },
    #[error("minimum relative node score {fraction} is invalid: expected 0 <= fraction < 1")]
    MinRelativeScore { fraction: f64 },
    #[error("minimum ZNCC {min_zncc} is invalid: expected 0 < min_zncc < 1")]
    MinZncc { min_zncc: f64 },
    #[error("correlate called before set_reference")]
    NoReference,
    #[error("saved reference has {got} node displacements, expected {expected} (one per node of this mesh): it was written with other settings or another image size")]
    BaseLength { got: usize, expected: usize },
    #[error("saved reference displacement of node {node} is not finite")]
    BaseNotFinite { node: usize },
    #[error(
        "auto reference thresholds invalid: expected 0 < deformation <= 8 px and 0 <= score < 1"
    )]
    AutoThresholds,
    #[error("{0} (--gauge, [correlator] gauges)")]
    Gauge(String),
}

/// Nearest power of two (ties go up), for the error message.
pub fn nearest_power_of_two(n: usize) -> usize {
    let n = n.max(1);
    let up = n.next_power_of_two();
    let down = up / 2;
    if down >= 1 && n - down < up - n {
        down
    } else {
        up
    }
}

impl CorrelatorSettings {
    /// Checks the settings alone (no image size yet).
    pub fn validate(&self) -> Result<(), SettingsError> {
        if self.method.is_icgn() {
            if !(MIN_SUBSET_PX..=MAX_ZOI_PX).contains(&self.zoi_px) {
                return Err(SettingsError::SubsetOutOfRange {
                    zoi_px: self.zoi_px,
                });
            }
        } else if !self.zoi_px.is_power_of_two() {
            return Err(SettingsError::ZoiNotPowerOfTwo {
                zoi_px: self.zoi_px,
                nearest: nearest_power_of_two(self.zoi_px).clamp(8, 256),
            });
        }
        if !self.method.is_icgn() && !(8..=MAX_ZOI_PX).contains(&self.zoi_px) {
            return Err(SettingsError::ZoiOutOfRange {
                zoi_px: self.zoi_px,
            });
        }
        if self.step_px == 0 || self.step_px > self.zoi_px {
            return Err(SettingsError::Step {
                step_px: self.step_px,
                zoi_px: self.zoi_px,
            });
        }
        if !(1..=64).contains(&self.threads) {
            return Err(SettingsError::Threads {
                threads: self.threads,
            });
        }
        if !(1..=100).contains(&self.max_iterations) {
            return Err(SettingsError::MaxIterations {
                max_iterations: self.max_iterations,
            });
        }
        if !(1..=8).contains(&self.strain_window_nodes) {
            return Err(SettingsError::StrainWindow {
                nodes: self.strain_window_nodes,
            });
        }
        if !(0.0..1.0).contains(&self.min_relative_score) {
            return Err(SettingsError::MinRelativeScore {
                fraction: self.min_relative_score,
            });
        }
        if !(self.min_zncc > 0.0 && self.min_zncc < 1.0) {
            return Err(SettingsError::MinZncc {
                min_zncc: self.min_zncc,
            });
        }
        if let ReferenceMode::Auto {
            max_deformation_px,
            min_mean_score,
        } = self.reference
        {
            let deformation_ok = max_deformation_px > 0.0 && max_deformation_px <= 8.0;
            let score_ok = (0.0..1.0).contains(&min_mean_score);
            if !deformation_ok || !score_ok {
                return Err(SettingsError::AutoThresholds);
            }
        }
        self.validate_gauges()
    }

    /// Gauge names unique, and the control gauge the mesh's centre, all nodes or one of the
    /// strain gauges.
    fn validate_gauges(&self) -> Result<(), SettingsError> {
        for (i, g) in self.gauges.iter().enumerate() {
            if self.gauges[..i].iter().any(|o| o.name == g.name) {
                return Err(SettingsError::Gauge(format!(
                    "two gauges are named {}: each needs its own name",
                    g.name
                )));
            }
        }
        if let ControlGauge::Named(name) = &self.control_gauge {
            match self.gauges.iter().find(|g| &g.name == name) {
                Some(Gauge {
                    shape: GaugeShape::Region(_),
                    ..
                }) => {}
                Some(_) => {
                    return Err(SettingsError::Gauge(format!(
                        "the control gauge {name} is an extensometer: the field's header carries a strain gauge's strains (centre, all, or a rect or polygon gauge)"
                    )))
                }
                None => {
                    let names: Vec<&str> = self.gauges.iter().map(|g| g.name.as_str()).collect();
                    return Err(SettingsError::Gauge(format!(
                        "the control gauge {name} is not one of the gauges ({}): name one, or centre, or all",
                        if names.is_empty() { "none is placed".to_owned() } else { names.join(", ") }
                    )));
                }
            }
        }
        Ok(())
    }

    /// Side (px) of the FFT step of the guess: the ZOI itself for `correli`, the largest power
    /// of two inside the subset for IC-GN (at least 8).
    pub fn fft_zoi_px(&self) -> usize {
        if self.method.is_icgn() {
            let p = if self.zoi_px.is_power_of_two() {
                self.zoi_px
            } else {
                self.zoi_px.next_power_of_two() / 2
            };
            p.max(8)
        } else {
            self.zoi_px
        }
    }

    /// The region for an image of this size (its rectangle, the mesh's rectangle, its
    /// pixels), every refusal naming its setting.
    pub fn resolve_region(
        &self,
        width_px: usize,
        height_px: usize,
    ) -> Result<ResolvedRegion, SettingsError> {
        self.region.resolve(width_px, height_px, self.zoi_px)
    }
}

/// The largest 2^p x 2^p square centred in a width x height image.
pub fn centred_power_of_two_square(width_px: usize, height_px: usize) -> Roi {
    let side = width_px.min(height_px);
    assert!(side >= 1);
    let p2 = if side.is_power_of_two() {
        side
    } else {
        side.next_power_of_two() / 2
    };
    Roi {
        x_px: (width_px - p2) / 2,
        y_px: (height_px - p2) / 2,
        width_px: p2,
        height_px: p2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_power() {
        assert_eq!(nearest_power_of_two(30), 32);
        assert_eq!(nearest_power_of_two(40), 32);
        assert_eq!(nearest_power_of_two(48), 64);
        assert_eq!(nearest_power_of_two(1), 1);
    }

    #[test]
    fn centred_square() {
        let roi = centred_power_of_two_square(2048, 589);
        assert_eq!(
            roi,
            Roi {
                x_px: 768,
                y_px: 38,
                width_px: 512,
                height_px: 512
            }
        );
    }
}
