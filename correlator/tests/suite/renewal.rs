//! The automatic reference: renewed when the correlation against it degrades (the ZOIs deform),
//! not when it holds (a rigid motion of many pixels); and the frame after a renewal keeps its
//! prediction (re-expressed against the new reference's bases), so it skips the integer FFT
//! search, also when the camera dropped a frame in between (the predictions extrapolate over
//! the frames missed). Counts, not times: `Correlator::fft_searches`.

use crate::common;

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

/// The live path (`correlate_field`, then `renew_reference`, then `measure_pending_bases` a
/// part per frame) measures the new reference's bases against the origin after the renewal,
/// not in it: right after the renewal the bases are those measured through the references
/// before it, and once the pass is done (`ORIGIN_PASS_FRAMES` parts) they are those the eager
/// path (`correlate`) measured at the renewal, and so are the next fields.
#[test]
fn the_live_path_measures_the_bases_against_the_origin_after_the_renewal() {
    let centre = [(SIZE as f64 - 1.0) / 2.0; 2];
    let frame = |k: usize| {
        let e = 0.01 * k as f64;
        render(
            SIZE,
            SIZE,
            24.0,
            stretch(e, -0.5 * e, centre),
            0.02,
            100 + k as u64,
        )
    };
    let mut eager = Correlator::new(settings(), SIZE, SIZE).unwrap();
    let mut live = Correlator::new(settings(), SIZE, SIZE).unwrap();
    eager.set_reference(&frame(0)).unwrap();
    live.set_reference(&frame(0)).unwrap();
    let bases = |c: &Correlator| c.reference_base_px().collect::<Vec<_>>();
    let largest_difference = |a: &[(f64, f64)], b: &[(f64, f64)]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (p.0 - q.0).hypot(p.1 - q.1))
            .fold(0.0f64, f64::max)
    };
    let (mut renewals, mut k) = (0, 0usize);
    // Two renewals: the second one's bases are measured against the origin (the first
    // reference is the origin, whose frame measured its bases against it directly).
    while renewals < 2 {
        k += 1;
        assert!(k < 20, "no second renewal");
        let pixels = frame(k);
        let renewed = eager.correlate(&pixels).unwrap().reference_updated;
        let field = live.correlate_field(&pixels, 1).unwrap();
        assert_eq!(field.reference_updated, renewed, "frame {k}");
        assert_eq!(live.pending_bases(), 0, "frame {k}");
        if !renewed {
            live.measure_pending_bases();
            continue;
        }
        renewals += 1;
        live.renew_reference(&pixels).unwrap();
        assert_eq!(live.reference_pixels(), eager.reference_pixels());
        if renewals == 1 {
            assert_eq!(
                live.pending_bases(),
                0,
                "the origin's own frame measured them"
            );
            assert!(largest_difference(&bases(&live), &bases(&eager)) < 1e-9);
            continue;
        }
        let chained = bases(&live);
        let measured = bases(&eager);
        // Every node is valid: every base waits for its measurement.
        assert_eq!(live.pending_bases(), live.field().nodes.len());
        // Each part measures its share; the last one says so.
        for part in 1..=correlator::ORIGIN_PASS_FRAMES {
            let done = live.measure_pending_bases();
            assert_eq!(done, part == correlator::ORIGIN_PASS_FRAMES, "part {part}");
        }
        assert_eq!(live.pending_bases(), 0);
        assert!(!live.measure_pending_bases());
        let before = largest_difference(&chained, &measured);
        let after = largest_difference(&bases(&live), &measured);
        eprintln!("frame {k}: bases off the eager path's by {before:.4} px before the pass, {after:.6} px after");
        assert!(
            after < 2e-3 && after < 0.5 * before,
            "{before} then {after}"
        );
    }
    // The next frame measures the same field on both paths.
    let pixels = frame(k + 1);
    let a = eager.correlate(&pixels).unwrap().clone();
    let b = live.correlate_field(&pixels, 1).unwrap();
    assert_eq!(a.valid, b.valid);
    let worst = a
        .nodes
        .iter()
        .zip(&b.nodes)
        .map(|(p, q)| (p.u_px - q.u_px).hypot(p.v_px - q.v_px))
        .fold(0.0f64, f64::max);
    assert!(worst < 5e-3, "{worst} px");
}
