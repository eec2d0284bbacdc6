//! Large strain with a followed mesh: uniaxial stretch of an incompressible sheet to λ 2.2 in 60
//! frames about the image centre, then back to λ 1 five times faster (12 frames), with the
//! incremental and the automatic reference. The material at the mesh border leaves the image as
//! it stretches and comes back as it unloads: those nodes must say so while out, and come back
//! on their own material (not as false "ok" matches on other material); the gauge strain must
//! follow the true ln λ to the end.

use crate::common;

use correlator::{Correlator, CorrelatorSettings, NodeStatus, ReferenceMode};
use producer::motion::Affine;
use producer::{CameraModel, FastRenderer, Motion, Speckle, SpeckleParams};

const SIZE: usize = 512;
const LOADING_FRAMES: usize = 60;
const UNLOADING_FRAMES: usize = 12;
const FINAL_STRETCH: f64 = 2.2;

fn uniaxial(stretch: f64) -> Motion {
    let c = (SIZE as f64 - 1.0) / 2.0;
    Motion::Affine(Affine {
        f: [[stretch, 0.0], [0.0, 1.0 / stretch.sqrt()]],
        translation_px: [0.0, 0.0],
        centre_px: [c, c],
    })
}

fn frames() -> Vec<(f64, Vec<u16>)> {
    // φ⁻¹ of the image reaches (√2.2 − 1) × 256 ≈ 124 px beyond it laterally.
    let extent = [-140.0, SIZE as f64 + 140.0];
    let speckle = Speckle::new(SpeckleParams::default(), extent, extent);
    let renderer = FastRenderer::new(&speckle, extent, extent, 4, 2);
    (0..=LOADING_FRAMES + UNLOADING_FRAMES)
        .map(|k| {
            let stretch = if k <= LOADING_FRAMES {
                1.0 + (FINAL_STRETCH - 1.0) * k as f64 / LOADING_FRAMES as f64
            } else {
                let back = (k - LOADING_FRAMES) as f64 / UNLOADING_FRAMES as f64;
                FINAL_STRETCH - (FINAL_STRETCH - 1.0) * back
            };
            let mut pattern = vec![0f32; SIZE * SIZE];
            renderer.render(&uniaxial(stretch), SIZE, &mut pattern);
            let camera = CameraModel::read_noise_only_16bit(0.005, k as u64 + 1);
            (stretch, camera.exposed(k as u64, &pattern, SIZE, 2))
        })
        .collect()
}

#[test]
fn followed_mesh_tracks_uniaxial_stretch_to_2_2() {
    let frames = frames();
    let c = (SIZE as f64 - 1.0) / 2.0;
    for mode in [ReferenceMode::Incremental, ReferenceMode::AUTO_DEFAULT] {
        let settings = CorrelatorSettings {
            reference: mode,
            ..CorrelatorSettings::default()
        };
        let mut correlator = Correlator::new(settings, SIZE, SIZE).unwrap();
        correlator.set_reference(&frames[0].1).unwrap();
        let mut worst_strain = 0.0f64;
        let mut worst_node = 0.0f64;
        let (mut node_error_sum, mut node_count) = (0.0f64, 0usize);
        let mut fewest_valid = usize::MAX;
        for (stretch, pixels) in &frames[1..] {
            let field = correlator.correlate(pixels).unwrap();
            let (ex, ey) = (stretch.ln(), -0.5 * stretch.ln());
            let g = field.gauge.log;
            worst_strain = worst_strain
                .max((g.exx - ex).abs())
                .max((g.eyy - ey).abs())
                .max(g.exy.abs());
            fewest_valid = fewest_valid.min(field.valid);
            for node in field.nodes.iter().filter(|n| n.status == NodeStatus::Ok) {
                let u = (stretch - 1.0) * (node.x_px - c);
                let v = (1.0 / stretch.sqrt() - 1.0) * (node.y_px - c);
                let error = (node.u_px - u).hypot(node.v_px - v);
                worst_node = worst_node.max(error);
                node_error_sum += error;
                node_count += 1;
            }
        }
        println!(
            "{mode:?}: worst gauge log strain error {worst_strain:.2e}, node error mean \
             {mean_node:.3} px worst {worst_node:.3} px, fewest valid nodes {fewest_valid} of {}",
            correlator.field().nodes.len(),
            mean_node = node_error_sum / node_count as f64,
        );
        // The stretched material leaves the image: nodes do go out...
        assert!(fewest_valid < correlator.field().nodes.len() / 2);
        // ...and those left follow their material: no false match on other material, and no
        // node called ok more than half a pixel off. At every reference update the new bases
        // are measured against the first frame directly (the ZOI sampled through the local
        // gradient), so the errors of the intermediate references do not add up (before: a
        // mean node error of 0.15 px and border nodes 1.7 px off after 70 incremental
        // updates), and a node whose material comes back into view is measured there again
        // (before: 2-4 px off, carried by the extrapolation while its material was out).
        let mean_node = node_error_sum / node_count as f64;
        assert!(
            mean_node < 0.05,
            "{mode:?}: nodes are off by {mean_node} px on average"
        );
        assert!(
            worst_node <= common::FALSE_OK_PX,
            "{mode:?}: a node called ok is off by {worst_node} px"
        );
        assert!(worst_strain < 5e-4, "{mode:?}: gauge off by {worst_strain}");
    }
}
