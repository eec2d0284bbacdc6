//! The correlator on the specimen as a structure: the default cruciform (100 mm arms, 20 mm
//! fillets, Smactane™) solved by finite elements at equibiaxial grip stretches up to 1.3, filmed
//! at 0.3 mm/px (the central square, the fillets and the roots of the four arms in a 512² frame),
//! compared node by node with the finite-element truth, and with the same camera on the
//! homogeneous equibiaxial stretch of the same mean, against the first frame and with the
//! automatic reference.

use correlator::{Correlator, CorrelatorSettings, NodeStatus, ReferenceMode};
use membrane::specimens::cruciform::CruciformGeometry;
use producer::motion::Affine;
use producer::{
    CameraModel, FastRenderer, FieldMotion, Motion, ReferenceMesh, Speckle, SpeckleParams, View,
};

/// A point or a displacement, px.
type Point = [f64; 2];
/// A frame's true displacement at a reference point (None off the specimen).
type Truth = Box<dyn Fn(Point) -> Option<Point>>;

const SIZE: usize = 512;
const MM_PER_PX: f64 = 0.3;
const STATES: usize = 6;
const GRIP_STRETCH: f64 = 1.3;

/// Error statistics of the `ok` nodes whose reference point is on the specimen, px.
#[derive(Debug, Default)]
struct Errors {
    /// Nodes whose whole reference ZOI is on the specimen.
    all: Vec<f64>,
    /// Nodes on the specimen whose reference ZOI reaches beyond its edge.
    edge: Vec<f64>,
    /// `ok` nodes whose reference point is off the specimen (no truth there).
    ok_off_specimen: usize,
}

impl Errors {
    fn mean(&self) -> f64 {
        self.all.iter().sum::<f64>() / self.all.len() as f64
    }
    fn p99(&self) -> f64 {
        let mut v = self.all.clone();
        v.sort_by(f64::total_cmp);
        v[(v.len() * 99) / 100]
    }
}

/// Whether the reference ZOI of the node at `(x, y)` lies on the specimen: its corners and edge
/// midpoints all have a truth.
fn zoi_on_specimen(truth: &dyn Fn(Point) -> Option<Point>, x: f64, y: f64) -> bool {
    let half = CorrelatorSettings::default().zoi_px as f64 / 2.0;
    [-half, 0.0, half].iter().all(|&dx| {
        [-half, 0.0, half]
            .iter()
            .all(|&dy| truth([x + dx, y + dy]).is_some())
    })
}

fn view() -> View {
    let c = (SIZE as f64 - 1.0) / 2.0;
    View {
        mm_per_px: MM_PER_PX,
        centre_px: [c, c],
        centre_mm: [0.0, 0.0],
    }
}

/// Correlates `frames` (the first the reference) with the reference `mode` and compares each
/// `ok` node with `truth` (None off the specimen).
fn measure(frames: &[Vec<u16>], truth: &[Truth], mode: ReferenceMode) -> Errors {
    let settings = CorrelatorSettings {
        reference: mode,
        ..CorrelatorSettings::default()
    };
    measure_with(frames, truth, settings)
}

fn measure_with(frames: &[Vec<u16>], truth: &[Truth], settings: CorrelatorSettings) -> Errors {
    measure_path(frames, truth, settings, false)
}

/// `live`: as the correlator process does (`correlate_field`, then the renewal, its bases
/// measured against the origin a part per frame), else `correlate`.
fn measure_path(
    frames: &[Vec<u16>],
    truth: &[Truth],
    settings: CorrelatorSettings,
    live: bool,
) -> Errors {
    let mut correlator = Correlator::new(settings, SIZE, SIZE).unwrap();
    correlator.set_reference(&frames[0]).unwrap();
    let mut errors = Errors::default();
    for (pixels, truth) in frames[1..].iter().zip(&truth[1..]) {
        if live {
            correlator.measure_pending_bases();
        }
        let field = match live {
            true => correlator.correlate_field(pixels, 1).unwrap().clone(),
            false => correlator.correlate(pixels).unwrap().clone(),
        };
        if live {
            correlator.renew_reference(pixels).unwrap();
        }
        for node in field.nodes.iter().filter(|n| n.status == NodeStatus::Ok) {
            match truth([node.x_px, node.y_px]) {
                Some(u) => {
                    let e = (node.u_px - u[0]).hypot(node.v_px - u[1]);
                    if zoi_on_specimen(truth, node.x_px, node.y_px) {
                        errors.all.push(e);
                    } else {
                        errors.edge.push(e);
                    }
                }
                None => errors.ok_off_specimen += 1,
            }
        }
    }
    errors
}

#[test]
fn the_correlator_measures_a_finite_element_cruciform_node_by_node() {
    let specimen = CruciformGeometry::default().mesh().unwrap();
    let law = material::InvariantLaw::smactane();
    let reference = ReferenceMesh::new(specimen.mesh.clone());
    let mut states = vec![FieldMotion::new(
        reference.clone(),
        vec![0.0; specimen.mesh.dof_count()],
        view(),
    )
    .unwrap()];
    for k in 1..=STATES {
        let stretch = 1.0 + (GRIP_STRETCH - 1.0) * k as f64 / STATES as f64;
        let solved = specimen
            .solve_at(
                &law,
                membrane::GripStretch {
                    x: stretch,
                    y: stretch,
                },
            )
            .unwrap();
        states.push(FieldMotion::new(reference.clone(), solved.displacement_mm, view()).unwrap());
    }
    // The homogeneous comparison: each state's mean stretch of the central square (its edge
    // midpoints), about the image centre.
    let c = (SIZE as f64 - 1.0) / 2.0;
    let half_px = 50.0 / MM_PER_PX;
    let mean_stretches: Vec<f64> = states
        .iter()
        .map(|s| {
            let right = s.displacement_px([c + half_px, c]).unwrap()[0];
            let left = s.displacement_px([c - half_px, c]).unwrap()[0];
            1.0 + (right - left) / (2.0 * half_px)
        })
        .collect();
    let extent = [-0.6 * SIZE as f64, 1.6 * SIZE as f64];
    let speckle = Speckle::new(SpeckleParams::default(), extent, extent);
    let renderer = FastRenderer::new(&speckle, extent, extent, 4, 2);
    let expose = |k: usize, pattern: &[f32]| {
        CameraModel::read_noise_only_16bit(0.005, k as u64 + 1).exposed(k as u64, pattern, SIZE, 2)
    };
    let mut pattern = vec![0f32; SIZE * SIZE];
    let mut structure_frames = vec![];
    let mut homogeneous_frames = vec![];
    let mut homogeneous_truth: Vec<Truth> = vec![];
    for (k, (state, &stretch)) in states.iter().zip(&mean_stretches).enumerate() {
        renderer.render_field(state, SIZE, &mut pattern);
        structure_frames.push(expose(k, &pattern));
        let motion = Motion::Affine(Affine {
            f: [[stretch, 0.0], [0.0, stretch]],
            translation_px: [0.0, 0.0],
            centre_px: [c, c],
        });
        renderer.render(&motion, SIZE, &mut pattern);
        homogeneous_frames.push(expose(k, &pattern));
        homogeneous_truth.push(Box::new(move |p| Some(motion.displacement(p))));
    }
    let structure_truth: Vec<Truth> = states
        .iter()
        .map(|s| {
            let s = s.clone();
            Box::new(move |p: [f64; 2]| s.displacement_px(p)) as Box<dyn Fn(_) -> _>
        })
        .collect();
    let fixed = ReferenceMode::Fixed;
    let structure = measure(&structure_frames, &structure_truth, fixed);
    let homogeneous = measure(&homogeneous_frames, &homogeneous_truth, fixed);
    let auto = ReferenceMode::AUTO_DEFAULT;
    let structure_auto = measure(&structure_frames, &structure_truth, auto);
    let homogeneous_auto = measure(&homogeneous_frames, &homogeneous_truth, auto);
    // The field is not homogeneous: the truth's stretch along x over the central row of nodes
    // varies (arm roots against the centre).
    let last = states.last().unwrap();
    let stretch_at = |x: f64| {
        let g = last.gradient([x, c]).unwrap();
        g[0][0]
    };
    let (centre, root) = (stretch_at(c), stretch_at(c + 0.95 * half_px));
    println!(
        "grip stretch {GRIP_STRETCH}: mean stretch of the central square {:.4}, F11 at the centre {centre:.4}, near the arm root {root:.4}",
        mean_stretches.last().unwrap()
    );
    for (name, e) in [
        ("structure, fixed reference", &structure),
        ("homogeneous, fixed reference", &homogeneous),
        ("structure, automatic reference", &structure_auto),
        ("homogeneous, automatic reference", &homogeneous_auto),
    ] {
        println!(
            "{name}: {} ok nodes with their ZOI on the specimen, error mean {:.4} px p99 {:.4} px worst {:.4} px; {} ok nodes whose ZOI crosses the specimen's edge, worst {:.4} px; {} ok nodes off the specimen",
            e.all.len(),
            e.mean(),
            e.p99(),
            e.all.iter().cloned().fold(0.0, f64::max),
            e.edge.len(),
            e.edge.iter().cloned().fold(0.0, f64::max),
            e.ok_off_specimen
        );
    }
    assert!(
        (centre - root).abs() > 0.01,
        "{centre} {root}: homogeneous?"
    );
    assert!(structure.all.len() > 400, "{}", structure.all.len());
    assert!(
        structure_auto.all.len() > 400,
        "{}",
        structure_auto.all.len()
    );
    // Against the first frame (the correlation itself, no renewal policy in between): the mean
    // within 2× the homogeneous run's (issue 24's target for a run on the cruciform), 1.48×
    // when written (0.0525 against 0.0354 px). With the automatic reference (the live default)
    // the ratio was 2.05× (0.0160 against 0.0078 px) and the p99 7.9× (0.195 against 0.025 px):
    // renewals at 0.5 px of ZOI deformation serve the homogeneous stretch better than the
    // arm roots' steep field (issue 26's steep fields).
    assert!(
        structure.mean() <= 2.0 * homogeneous.mean(),
        "mean {} against {}",
        structure.mean(),
        homogeneous.mean()
    );
    // With the automatic reference, the worst nodes sat 30-60 px from the fillets' edges,
    // whole ZOIs on the material: the plane through two rings of neighbours (64 px) that
    // checked each node and gave the gradient its base was measured through against the origin
    // missed the field's curvature there. From the nearest ring (`LOCAL_RINGS`) the p99 went
    // from 0.109 to 0.069 px (4.5× to 2.8× the homogeneous stretch's 0.024 px), the mean from
    // 0.0162 to 0.0143 px.
    assert!(
        structure_auto.p99() <= 3.5 * homogeneous_auto.p99(),
        "automatic reference: p99 {} against {}",
        structure_auto.p99(),
        homogeneous_auto.p99()
    );
    // The p99 misses that target: 2.3× when written (0.373 against 0.160 px), the worst nodes
    // at the arm roots and along the fillets, where the strain changes by 0.1 over a ZOI
    // (first-order ZOIs on a steep field, issue 26's "steep fields") and near the edge. A guard
    // against it getting worse until then, not the target.
    assert!(
        structure.p99() <= 3.0 * homogeneous.p99(),
        "p99 {} against {}",
        structure.p99(),
        homogeneous.p99()
    );
    // The IC-GN methods with the automatic reference: `icgn` chooses the order per node in
    // the frame and in its bases' measurements against the origin (`origin_order.rs`). With
    // first-order bases it had `icgn1`'s p99 (0.103 against 0.109 px, `icgn2` 0.032); with
    // them 0.040 when written.
    let icgn = |method, live| {
        let settings = CorrelatorSettings {
            method,
            zoi_px: 33,
            reference: ReferenceMode::AUTO_DEFAULT,
            ..CorrelatorSettings::default()
        };
        let e = measure_path(&structure_frames, &structure_truth, settings, live);
        println!(
            "{method:?}, automatic reference{}: {} ok nodes with their ZOI on the specimen, error mean {:.4} px p99 {:.4} px",
            if live { ", live path" } else { "" },
            e.all.len(),
            e.mean(),
            e.p99()
        );
        e
    };
    for live in [false, true] {
        let (first, chosen, second) = (
            icgn(correlator::Method::Icgn1, live),
            icgn(correlator::Method::Icgn, live),
            icgn(correlator::Method::Icgn2, live),
        );
        assert!(
            chosen.p99() <= 0.6 * first.p99() && chosen.p99() <= 1.5 * second.p99(),
            "live {live}: icgn p99 {} against icgn1 {} and icgn2 {}",
            chosen.p99(),
            first.p99(),
            second.p99()
        );
    }
}
