//! A steady sequence followed by a jump several pixels past what the previous frames predict:
//! the predicted nodes' shortcuts (`correli`: no integer FFT search once the prediction is
//! confirmed; `icgn1`: no FFT guess at all) must fall back to the full search and find the
//! jump: every node whose ZOI stays in the image valid, and none off.

use crate::common;

use common::{render, translation};
use correlator::settings::Method;
use correlator::{Correlator, CorrelatorSettings, NodeStatus};

const SIZE: usize = 256;

fn check(method: Method, zoi_px: usize) {
    let settings = CorrelatorSettings {
        method,
        zoi_px,
        step_px: 16,
        threads: 2,
        ..CorrelatorSettings::default()
    };
    let mut correlator = Correlator::new(settings, SIZE, SIZE).unwrap();
    correlator
        .set_reference(&render(SIZE, SIZE, 24.0, translation(0.0, 0.0), 0.01, 1))
        .unwrap();
    // Steady: 0.3 px per frame along x; then 4.1 px at once (the prediction says 1.2).
    for (frame, (u, v)) in [
        (0.3, -0.1),
        (0.6, -0.2),
        (0.9, -0.3),
        (5.0, 3.2),
        (5.0, 3.2),
    ]
    .into_iter()
    .enumerate()
    {
        let deformed = render(SIZE, SIZE, 24.0, translation(u, v), 0.01, 2 + frame as u64);
        let field = correlator.correlate(&deformed).unwrap();
        let ok: Vec<_> = field
            .nodes
            .iter()
            .filter(|n| n.status == NodeStatus::Ok)
            .collect();
        // Border ZOIs whose material left the image are `outside_image`; every other is `ok`.
        let failed: Vec<_> = field
            .nodes
            .iter()
            .filter(|n| !matches!(n.status, NodeStatus::Ok | NodeStatus::OutsideImage))
            .map(|n| (n.x_px, n.y_px, n.status))
            .collect();
        assert!(failed.is_empty(), "{method:?} frame {frame}: {failed:?}");
        assert!(
            ok.len() * 10 >= field.nodes.len() * 8,
            "{method:?} frame {frame}"
        );
        let worst = ok
            .iter()
            .map(|n| (n.u_px - u).abs().max((n.v_px - v).abs()))
            .fold(0.0, f64::max);
        assert!(
            worst < 0.05,
            "{method:?} frame {frame} ({u}, {v}): worst {worst} px"
        );
    }
}

#[test]
fn correli_finds_a_jump_past_its_prediction() {
    check(Method::Correli, 32);
}

#[test]
fn icgn1_finds_a_jump_past_its_prediction() {
    check(Method::Icgn1, 33);
}
