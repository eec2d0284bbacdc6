//! The rigid ZOI under a displacement gradient reports the motion of a point off its centre
//! (where its speckles weigh most): under a homogeneous strain ε its node error is about
//! ε times that lever, different from node to node. The first-order gradient correction
//! (`CorrelatorSettings::gradient_correction`) removes most of it; this measures the node
//! errors against the exact field with and without it, on a fixed reference (one step) and on
//! an incremental reference (where the error would repeat at every update and add up; the
//! bases measured against the first frame at every update now keep it from adding up with or
//! without the correction).

use crate::common;

use common::{render, stretch};
use correlator::{Correlator, CorrelatorSettings, GuessMode, NodeStatus, ReferenceMode};

const SIZE: usize = 256;

fn centre() -> [f64; 2] {
    let c = (SIZE as f64 - 1.0) / 2.0;
    [c, c]
}

/// RMS and largest node error (px) of the last field against the exact stretch (ex, ey).
fn node_errors(correlator: &Correlator, ex: f64, ey: f64) -> (f64, f64, usize) {
    let c = centre();
    let (mut sum_sq, mut worst, mut count) = (0.0, 0.0f64, 0usize);
    for node in correlator
        .field()
        .nodes
        .iter()
        .filter(|n| n.status == NodeStatus::Ok)
    {
        let error =
            (node.u_px - ex * (node.x_px - c[0])).hypot(node.v_px - ey * (node.y_px - c[1]));
        sum_sq += error * error;
        worst = worst.max(error);
        count += 1;
    }
    ((sum_sq / count as f64).sqrt(), worst, count)
}

/// The rigid ZOI (guess `predict`): guess `auto` samples the ZOIs of a fresh reference through
/// the measured gradient, which leaves the correction little to do.
fn settings(gradient_correction: bool, reference: ReferenceMode) -> CorrelatorSettings {
    CorrelatorSettings {
        method: correlator::Method::Correli,
        gradient_correction,
        reference,
        guess: GuessMode::Predict,
        ..CorrelatorSettings::default()
    }
}

#[test]
fn correction_removes_the_rigid_zoi_bias_under_strain() {
    let reference = render(SIZE, SIZE, 40.0, stretch(0.0, 0.0, centre()), 0.01, 1);
    for (ex, ey) in [(0.05, -0.025), (0.10, 0.10)] {
        let deformed = render(SIZE, SIZE, 40.0, stretch(ex, ey, centre()), 0.01, 2);
        let mut rms = [0.0; 2];
        for (i, correct) in [false, true].into_iter().enumerate() {
            let mut correlator =
                Correlator::new(settings(correct, ReferenceMode::Fixed), SIZE, SIZE).unwrap();
            correlator.set_reference(&reference).unwrap();
            correlator.correlate(&deformed).unwrap();
            let (r, worst, count) = node_errors(&correlator, ex, ey);
            println!(
                "fixed reference, strain ({ex}, {ey}), correction {correct}: node error RMS \
                 {r:.4} px, worst {worst:.4} px over {count} nodes"
            );
            rms[i] = r;
            // Without the correction the rigid ZOI's bias is what this test shows.
            if correct {
                assert!(
                    worst <= common::FALSE_OK_PX,
                    "a node called ok is {worst} px off"
                );
            }
        }
        assert!(
            rms[1] < 0.5 * rms[0],
            "strain ({ex}, {ey}): the correction leaves {} px of {} px",
            rms[1],
            rms[0]
        );
    }
}

#[test]
fn incremental_errors_do_not_add_up() {
    // Uniaxial stretch to 1.3 in 30 steps of 1 %, each frame the reference of the next.
    let steps = 30;
    let frames: Vec<(f64, Vec<u16>)> = (0..=steps)
        .map(|k| {
            let ex = 0.01 * k as f64;
            let ey = 1.0 / (1.0 + ex).sqrt() - 1.0;
            let motion = stretch(ex, ey, centre());
            (ex, render(SIZE, SIZE, 60.0, motion, 0.01, k as u64 + 1))
        })
        .collect();
    let mut rms = [0.0; 2];
    for (i, correct) in [false, true].into_iter().enumerate() {
        let mut correlator =
            Correlator::new(settings(correct, ReferenceMode::Incremental), SIZE, SIZE).unwrap();
        correlator.set_reference(&frames[0].1).unwrap();
        for (_, pixels) in &frames[1..] {
            correlator.correlate(pixels).unwrap();
        }
        let ex = frames[steps].0;
        let ey = 1.0 / (1.0 + ex).sqrt() - 1.0;
        let (r, worst, count) = node_errors(&correlator, ex, ey);
        println!(
            "incremental, {steps} steps of 1 %, correction {correct}: node error RMS {r:.4} px, \
             worst {worst:.4} px over {count} nodes"
        );
        rms[i] = r;
        // Before the bases were measured against the first frame: 0.379 px without the
        // correction, 0.093 px with it, worst nodes 0.97 and 0.27 px.
        assert!(
            r < 0.03,
            "correction {correct}: RMS {r} px after {steps} updates"
        );
        assert!(
            worst <= common::FALSE_OK_PX,
            "a node called ok is {worst} px off"
        );
    }
    assert!(rms[1] <= rms[0], "the correction makes it worse: {rms:?}");
}
