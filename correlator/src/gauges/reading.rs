//! A gauge's reading from one field's nodes (the correlator's own, or a subscriber's `wire`
//! nodes: one computation for both).

use super::{ControlGauge, Gauge, GaugeShape};
use crate::field::{GaugeStrains, Node};
use crate::settings::StrainMeasure;
use crate::strain::{strain_from_gradient, AffineSums};
use wire::NodeStatus;

/// What a gauge needs of a node: where it is in the mesh's image, how far it moved, whether
/// it holds.
pub trait GaugeNode {
    fn position_px(&self) -> (f64, f64);
    fn displacement_px(&self) -> (f64, f64);
    fn status(&self) -> NodeStatus;
}

impl GaugeNode for Node {
    fn position_px(&self) -> (f64, f64) {
        (self.x_px, self.y_px)
    }
    fn displacement_px(&self) -> (f64, f64) {
        (self.u_px, self.v_px)
    }
    fn status(&self) -> NodeStatus {
        self.status
    }
}

impl GaugeNode for wire::FieldNode {
    fn position_px(&self) -> (f64, f64) {
        (f64::from(self.x_px), f64::from(self.y_px))
    }
    fn displacement_px(&self) -> (f64, f64) {
        (f64::from(self.u_px), f64::from(self.v_px))
    }
    fn status(&self) -> NodeStatus {
        NodeStatus::from_code(self.status).unwrap_or(NodeStatus::NotConverged)
    }
}

/// What a gauge reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GaugeValue {
    /// A strain gauge's mean strain, in the four measures.
    Strain(GaugeStrains),
    /// An extensometer's length in the mesh's image and now (px).
    Extension { length0_px: f64, length_px: f64 },
}

impl GaugeValue {
    /// The extensometer's elongation (px); None for a strain gauge.
    pub fn elongation_px(&self) -> Option<f64> {
        match self {
            GaugeValue::Extension {
                length0_px,
                length_px,
            } => Some(length_px - length0_px),
            GaugeValue::Strain(_) => None,
        }
    }

    /// The extensometer's nominal strain (elongation over initial length); None for a strain
    /// gauge.
    pub fn nominal_strain(&self) -> Option<f64> {
        match self {
            GaugeValue::Extension {
                length0_px,
                length_px,
            } => Some(length_px / length0_px - 1.0),
            GaugeValue::Strain(_) => None,
        }
    }
}

/// Why a gauge has no reading on a field.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum NoReading {
    #[error("{found} valid nodes inside the gauge: its mean strain needs 3 not on one line")]
    TooFewNodes { found: usize },
    #[error("{found} valid nodes within {radius_px} px (1.5 mesh steps) of its point {point}: following the point needs 3 not on one line")]
    PointLost {
        point: char,
        found: usize,
        radius_px: f64,
    },
}

/// One gauge's reading on one field: how many valid nodes it used, and its value or why it has
/// none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaugeReading {
    pub nodes: usize,
    pub value: Result<GaugeValue, NoReading>,
}

/// No reading yet (a field before its first correlation).
impl Default for GaugeReading {
    fn default() -> Self {
        GaugeReading {
            nodes: 0,
            value: Err(NoReading::TooFewNodes { found: 0 }),
        }
    }
}

impl GaugeReading {
    /// A strain gauge's strains; NaN everywhere when it has no reading or is an extensometer
    /// (what the field's header carries: a loop closed on it holds rather than read a 0).
    pub fn strains_or_nan(&self) -> GaugeStrains {
        match self.value {
            Ok(GaugeValue::Strain(s)) => s,
            _ => {
                let nan = crate::Strain2 {
                    exx: f64::NAN,
                    eyy: f64::NAN,
                    exy: f64::NAN,
                };
                GaugeStrains {
                    small: nan,
                    green: nan,
                    nominal: nan,
                    log: nan,
                }
            }
        }
    }
}

fn valid<N: GaugeNode>(nodes: &[N]) -> impl Iterator<Item = &N> {
    nodes.iter().filter(|n| n.status() == NodeStatus::Ok)
}

/// The mean strain of the valid nodes `inside` selects: one affine least-squares fit of their
/// displacements about their centroid.
fn region_strains<N: GaugeNode>(nodes: &[N], inside: impl Fn((f64, f64)) -> bool) -> GaugeReading {
    let (mut cx, mut cy, mut found) = (0.0, 0.0, 0usize);
    for node in valid(nodes).filter(|n| inside(n.position_px())) {
        let (x, y) = node.position_px();
        cx += x;
        cy += y;
        found += 1;
    }
    let too_few = GaugeReading {
        nodes: found,
        value: Err(NoReading::TooFewNodes { found }),
    };
    if found == 0 {
        return too_few;
    }
    let (cx, cy) = (cx / found as f64, cy / found as f64);
    let mut sums = AffineSums::default();
    for node in valid(nodes).filter(|n| inside(n.position_px())) {
        let (x, y) = node.position_px();
        let (u, v) = node.displacement_px();
        sums.add(x - cx, y - cy, u, v);
    }
    let Some(grad) = sums.gradient() else {
        return too_few;
    };
    let get = |m| strain_from_gradient(&grad, m).unwrap_or_default();
    GaugeReading {
        nodes: found,
        value: Ok(GaugeValue::Strain(GaugeStrains {
            small: get(StrainMeasure::Small),
            green: get(StrainMeasure::Green),
            nominal: get(StrainMeasure::Nominal),
            log: get(StrainMeasure::Log),
        })),
    }
}

/// Where a point of the mesh's image is now: its displacement from an affine fit of the valid
/// nodes within `radius_px`; Err(found) with fewer than 3 not on one line.
fn followed_point<N: GaugeNode>(
    nodes: &[N],
    p: (f64, f64),
    radius_px: f64,
) -> Result<((f64, f64), usize), usize> {
    let mut sums = AffineSums::default();
    let mut found = 0;
    for node in valid(nodes) {
        let (x, y) = node.position_px();
        let (dx, dy) = (x - p.0, y - p.1);
        if dx * dx + dy * dy <= radius_px * radius_px {
            let (u, v) = node.displacement_px();
            sums.add(dx, dy, u, v);
            found += 1;
        }
    }
    let ((u, v), _) = sums.fit().ok_or(found)?;
    Ok(((p.0 + u, p.1 + v), found))
}

/// The reading of a gauge of this shape on one field's nodes (mesh step `step_px`).
pub fn read<N: GaugeNode>(shape: &GaugeShape, nodes: &[N], step_px: f64) -> GaugeReading {
    match shape {
        GaugeShape::Region(polygon) => region_strains(nodes, |p| polygon.contains(p)),
        GaugeShape::Extensometer { a_px, b_px } => {
            let radius_px = 1.5 * step_px;
            let follow = |p, point| {
                followed_point(nodes, p, radius_px).map_err(|found| NoReading::PointLost {
                    point,
                    found,
                    radius_px,
                })
            };
            let a = match follow(*a_px, 'A') {
                Ok(a) => a,
                Err(e) => {
                    return GaugeReading {
                        nodes: 0,
                        value: Err(e),
                    }
                }
            };
            let b = match follow(*b_px, 'B') {
                Ok(b) => b,
                Err(e) => {
                    return GaugeReading {
                        nodes: a.1,
                        value: Err(e),
                    }
                }
            };
            let length = |p: (f64, f64), q: (f64, f64)| (q.0 - p.0).hypot(q.1 - p.1);
            GaugeReading {
                nodes: a.1 + b.1,
                value: Ok(GaugeValue::Extension {
                    length0_px: length(*a_px, *b_px),
                    length_px: length(a.0, b.0),
                }),
            }
        }
    }
}

/// Where the control gauge reads, on one field's mesh.
#[derive(Clone, Copy, Debug)]
pub enum ControlRegion<'a> {
    /// Every valid node.
    All,
    /// The central half of the measured nodes' extent: |x - cx| <= hx and |y - cy| <= hy.
    Centre {
        centre_px: (f64, f64),
        half_px: (f64, f64),
    },
    /// A user's strain gauge (`None`: the named gauge is not a strain gauge of `gauges`,
    /// which settings validation refuses: no node).
    Gauge(Option<&'a crate::region::Polygon>),
}

impl ControlRegion<'_> {
    /// The control gauge of these settings on this mesh: the central region is the middle
    /// half of the extent of the nodes in the measured region (all of a frame's nodes have
    /// their positions, valid or not, so it does not move from frame to frame).
    pub fn of<'a, N: GaugeNode>(
        control: &ControlGauge,
        gauges: &'a [Gauge],
        nodes: &[N],
    ) -> ControlRegion<'a> {
        match control {
            ControlGauge::All => ControlRegion::All,
            ControlGauge::Centre => {
                let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
                for node in nodes
                    .iter()
                    .filter(|n| n.status() != NodeStatus::OutsideRegion)
                {
                    let (x, y) = node.position_px();
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
                }
                // Half the extent, and 0.5 px more so that a node on its border counts.
                ControlRegion::Centre {
                    centre_px: ((x0 + x1) / 2.0, (y0 + y1) / 2.0),
                    half_px: ((x1 - x0) / 4.0 + 0.5, (y1 - y0) / 4.0 + 0.5),
                }
            }
            ControlGauge::Named(name) => {
                ControlRegion::Gauge(gauges.iter().find(|g| &g.name == name).and_then(|g| {
                    match &g.shape {
                        GaugeShape::Region(polygon) => Some(polygon),
                        GaugeShape::Extensometer { .. } => None,
                    }
                }))
            }
        }
    }

    /// Whether a node at this position (the mesh's image, px) is in the control gauge.
    pub fn contains(&self, (x, y): (f64, f64)) -> bool {
        match self {
            ControlRegion::All => true,
            ControlRegion::Centre { centre_px, half_px } => {
                (x - centre_px.0).abs() <= half_px.0 && (y - centre_px.1).abs() <= half_px.1
            }
            ControlRegion::Gauge(polygon) => polygon.is_some_and(|p| p.contains((x, y))),
        }
    }
}

/// The control gauge's reading: the mean strain of the valid nodes in its [`ControlRegion`].
pub fn read_control<N: GaugeNode>(
    control: &ControlGauge,
    gauges: &[Gauge],
    nodes: &[N],
) -> GaugeReading {
    let region = ControlRegion::of(control, gauges, nodes);
    region_strains(nodes, |p| region.contains(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 21 x 21 mesh, step 10 px from (100, 100), moved by `motion` (x, y) -> (u, v).
    fn mesh(motion: impl Fn(f64, f64) -> (f64, f64)) -> Vec<Node> {
        let mut nodes = Vec::new();
        for j in 0..21 {
            for i in 0..21 {
                let (x, y) = (100.0 + 10.0 * i as f64, 100.0 + 10.0 * j as f64);
                let (u, v) = motion(x, y);
                nodes.push(Node {
                    x_px: x,
                    y_px: y,
                    u_px: u,
                    v_px: v,
                    status: NodeStatus::Ok,
                    ..Node::default()
                });
            }
        }
        nodes
    }

    fn gauge(text: &str) -> Gauge {
        text.parse().unwrap()
    }

    fn strains(reading: &GaugeReading) -> GaugeStrains {
        match reading.value {
            Ok(GaugeValue::Strain(s)) => s,
            other => panic!("not a strain reading: {other:?}"),
        }
    }

    #[test]
    fn a_homogeneous_stretch_reads_the_same_in_every_gauge() {
        // λx = 1.1, λy = 0.95 about (200, 200), plus a rigid shift.
        let nodes = mesh(|x, y| (0.1 * (x - 200.0) + 3.0, -0.05 * (y - 200.0) - 1.5));
        for shape in ["g=rect:150,150,60,40", "g=polygon:120,120 280,140 200,290"] {
            let r = read(&gauge(shape).shape, &nodes, 10.0);
            let s = strains(&r);
            assert!((s.log.exx - 1.1f64.ln()).abs() < 1e-12, "{shape} {s:?}");
            assert!((s.log.eyy - 0.95f64.ln()).abs() < 1e-12, "{shape} {s:?}");
            assert!(s.log.exy.abs() < 1e-12);
            assert!((s.green.exx - (1.1f64.powi(2) - 1.0) / 2.0).abs() < 1e-12);
        }
        // rect 150..210 x 150..190, its right and bottom edges outside (the region's rule):
        // 6 x 4 nodes.
        assert_eq!(
            read(&gauge("g=rect:150,150,60,40").shape, &nodes, 10.0).nodes,
            24
        );
        // An extensometer between points off the nodes: exact for an affine motion.
        let e = read(&gauge("e=extensometer:123,157 281,157").shape, &nodes, 10.0);
        let value = e.value.unwrap();
        assert!((value.elongation_px().unwrap() - 0.1 * 158.0).abs() < 1e-9);
        assert!((value.nominal_strain().unwrap() - 0.1).abs() < 1e-12);
        let control = read_control(&ControlGauge::Centre, &[], &nodes);
        assert!((strains(&control).log.exx - 1.1f64.ln()).abs() < 1e-12);
        // The central half of 100..300: 150..250, 11 x 11 nodes.
        assert_eq!(control.nodes, 121);
        assert_eq!(read_control(&ControlGauge::All, &[], &nodes).nodes, 441);
    }

    #[test]
    fn a_heterogeneous_field_reads_each_gauge_where_it_is() {
        // u = 1e-3 (x - 100)²: du/dx = 2e-3 (x - 100), 0 at the left edge, 0.4 at the right.
        let nodes = mesh(|x, _| (1e-3 * (x - 100.0).powi(2), 0.0));
        let left = strains(&read(&gauge("l=rect:100,100,20,200").shape, &nodes, 10.0));
        let right = strains(&read(&gauge("r=rect:280,100,20,200").shape, &nodes, 10.0));
        // Columns x = 100, 110 and x = 280, 290 (the right edge outside).
        assert!((left.small.exx - 0.01).abs() < 1e-9, "{left:?}");
        assert!((right.small.exx - 0.37).abs() < 1e-9, "{right:?}");
        let centre = strains(&read_control(&ControlGauge::Centre, &[], &nodes));
        assert!((centre.small.exx - 0.2).abs() < 1e-9, "{centre:?}");
        // A named control gauge reads that gauge.
        let gauges = [gauge("l=rect:100,100,20,200")];
        let named = read_control(&ControlGauge::Named("l".into()), &gauges, &nodes);
        assert_eq!(strains(&named), left);
    }

    #[test]
    fn a_gauge_without_enough_valid_nodes_says_why() {
        let mut nodes = mesh(|x, _| (0.01 * x, 0.0));
        // Every node within 40 px of (200, 200) fails.
        for n in &mut nodes {
            if (n.x_px - 200.0).hypot(n.y_px - 200.0) < 40.0 {
                n.status = NodeStatus::LowZncc;
            }
        }
        let r = read(&gauge("g=rect:180,180,40,40").shape, &nodes, 10.0);
        assert_eq!(r.value, Err(NoReading::TooFewNodes { found: 0 }));
        assert!(r.strains_or_nan().log.exx.is_nan());
        let e = read(&gauge("e=extensometer:120,120 200,200").shape, &nodes, 10.0);
        assert_eq!(
            e.value,
            Err(NoReading::PointLost {
                point: 'B',
                found: 0,
                radius_px: 15.0
            })
        );
        assert!(e.value.unwrap_err().to_string().contains("point B"));
        // Nodes on one line cannot give a strain.
        let line = read(&gauge("g=rect:140,139,100,2").shape, &nodes, 10.0);
        assert_eq!(line.value, Err(NoReading::TooFewNodes { found: 10 }));
        // An outside_region node does not stretch the central region.
        let mut framed = mesh(|_, _| (0.0, 0.0));
        for n in framed.iter_mut().filter(|n| n.x_px > 250.0) {
            n.status = NodeStatus::OutsideRegion;
        }
        // Measured: x 100..250, centre 175, half width 37.5 (+0.5): x 140..210, 8 columns.
        let c = read_control(&ControlGauge::Centre, &[], &framed);
        assert_eq!(c.nodes, 8 * 11);
    }
}
