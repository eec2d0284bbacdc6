//! The automatic reference: renewed when the correlation against it degrades (the ZOIs deform),
//! not when it holds (a rigid motion of many pixels); and the frame after a renewal keeps its
//! prediction (re-expressed against the new reference's bases), so it skips the integer FFT
//! search, also when the camera dropped a frame in between (the predictions extrapolate over
//! the frames missed). Counts, not times: `Correlator::fft_searches`.

mod common;

use common::{render, stretch, translation};
use correlator::settings::Roi;
use correlator::{Correlator, CorrelatorSettings, NodeStatus, ReferenceMode};
use producer::Motion;

const SIZE: usize = 256;

fn settings() -> CorrelatorSettings {
    CorrelatorSettings {
        reference: ReferenceMode::AUTO_DEFAULT,
        // Inside the image: no node leaves it, so none searches for want of a prediction.
        region: correlator::Region::rect(Roi {
            x_px: 64,
            y_px: 64,
            width_px: 128,
            height_px: 128,
        }),
        ..CorrelatorSettings::default()
    }
}

/// 3 px per frame to 30 px: ten times the displacement the former rule renewed at (a quarter
/// of the ZOI), and never a renewal: the ZOIs are not deformed, every node is valid.
#[test]
fn a_rigid_motion_keeps_the_reference() {
    let mut correlator = Correlator::new(settings(), SIZE, SIZE).unwrap();
    correlator
        .set_reference(&render(SIZE, SIZE, 40.0, translation(0.0, 0.0), 0.01, 1))
        .unwrap();
    for k in 1..=10u64 {
        let (u, v) = (3.0 * k as f64, -(k as f64));
        let frame = render(SIZE, SIZE, 40.0, translation(u, v), 0.01, 1 + k);
        let field = correlator.correlate(&frame).unwrap();
        assert!(!field.reference_updated, "renewed at frame {k} ({u} px)");
        assert_eq!(field.valid, field.nodes.len(), "frame {k}");
        assert!(
            (field.u_mean_px - u).abs() < 0.02,
            "frame {k}: {}",
            field.u_mean_px
        );
    }
}

/// A stretch of 1 % per frame along x (−0.5 % along y), with a translation, moves the corners of the 32 px ZOIs by
/// 0.173 px against their centres per frame: the reference is renewed once that passes the
/// default 0.5 px (the third frame), not before; after each renewal
/// the next frame (also one after a dropped frame) runs no integer FFT search, and measures the
/// stretch.
#[test]
fn a_deformation_renews_the_reference_and_the_prediction_survives_it() {
    let centre = [(SIZE as f64 - 1.0) / 2.0; 2];
    // And 1.5 px per frame along x: a prediction that missed a frame is off by that much.
    let frame = |k: usize, seed: u64| {
        let e = 0.01 * k as f64;
        let Motion::Affine(mut motion) = stretch(e, -0.5 * e, centre) else {
            unreachable!("a stretch is affine")
        };
        motion.translation_px = [1.5 * k as f64, 0.0];
        render(SIZE, SIZE, 24.0, Motion::Affine(motion), 0.01, seed)
    };
    let mut correlator = Correlator::new(settings(), SIZE, SIZE).unwrap();
    correlator.set_reference(&frame(0, 1)).unwrap();
    let mut renewals = Vec::new();
    let mut after_renewal = Vec::new();
    let mut renewed_last = false;
    // The frame right after the first renewal is dropped by the camera (as while a live
    // correlator is busy): the next one comes two frames after the renewal.
    let mut dropped = false;
    let mut k = 0usize;
    while k < 14 {
        let step = if renewed_last && !dropped {
            dropped = true;
            2
        } else {
            1
        };
        k += step;
        let searches = correlator.fft_searches();
        let field = correlator
            .correlate_after(&frame(k, 10 + k as u64), step as u64)
            .unwrap()
            .clone();
        let searched = correlator.fft_searches() - searches;
        eprintln!(
            "frame {k} (step {step}): {searched} FFT searches, {} valid of {}, gauge log exx {:.5}{}",
            field.valid,
            field.nodes.len(),
            field.gauge.log.exx,
            if field.reference_updated { ", renewed" } else { "" }
        );
        assert_eq!(field.valid, field.nodes.len(), "frame {k}");
        let e = 0.01 * k as f64;
        assert!(
            (field.gauge.log.exx - (1.0 + e).ln()).abs() < 1e-3,
            "frame {k}: {}",
            field.gauge.log.exx
        );
        assert!(field.nodes.iter().all(|n| n.status == NodeStatus::Ok));
        if renewed_last {
            after_renewal.push((k, searched));
        }
        if field.reference_updated {
            renewals.push(k);
        }
        renewed_last = field.reference_updated;
    }
    assert!(dropped);
    eprintln!("renewed at frames {renewals:?}; FFT searches after: {after_renewal:?}");
    // 0.173 px per frame: not before the third frame, and again on the way.
    assert!(!renewals.is_empty() && renewals[0] >= 3, "{renewals:?}");
    assert!(renewals.len() >= 2, "{renewals:?}");
    assert!(!after_renewal.is_empty());
    for (k, searched) in after_renewal {
        assert_eq!(searched, 0, "frame {k} after a renewal searched");
    }
}
