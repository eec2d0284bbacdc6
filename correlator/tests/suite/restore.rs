//! Resuming against a saved reference (what the live process writes to its --state-dir):
//! a correlator restored from `reference_pixels` + `reference_base_px` measures the next frame
//! like the uninterrupted one, in every reference mode.

use crate::common;

use common::{render, translation};
use correlator::{Correlator, CorrelatorSettings, GuessMode, NodeStatus, ReferenceMode};

#[test]
fn restored_reference_continues_the_total_displacement() {
    let (w, h) = (192, 192);
    // A ramp of 0.6 px per frame along x and -0.35 along y: incremental and auto modes update
    // their reference on the way (auto with a mean score bar no match reaches: a translation
    // alone does not degrade the correlation).
    let frames: Vec<Vec<u16>> = (0..6)
        .map(|k| {
            render(
                w,
                h,
                8.0,
                translation(0.6 * k as f64, -0.35 * k as f64),
                0.01,
                10 + k as u64,
            )
        })
        .collect();
    let auto = ReferenceMode::Auto {
        max_deformation_px: 1.0,
        min_mean_score: 0.999,
    };
    for reference in [ReferenceMode::Fixed, ReferenceMode::Incremental, auto] {
        for guess in [GuessMode::Correli, GuessMode::Predict] {
            let settings = CorrelatorSettings {
                zoi_px: 32,
                step_px: 16,
                reference,
                guess,
                ..Default::default()
            };
            let mut uninterrupted = Correlator::new(settings.clone(), w, h).unwrap();
            uninterrupted.set_reference(&frames[0]).unwrap();
            let mut updates = 0;
            for frame in &frames[1..4] {
                updates += usize::from(uninterrupted.correlate(frame).unwrap().reference_updated);
            }
            // What the process saves: reference pixels and per-node base displacements.
            let pixels = uninterrupted.reference_pixels().unwrap().to_vec();
            let bases: Vec<(f64, f64)> = uninterrupted.reference_base_px().collect();
            let mut resumed = Correlator::new(settings, w, h).unwrap();
            resumed.restore_reference(&pixels, &bases).unwrap();
            // The resumed process missed frame 4.
            uninterrupted.correlate(&frames[4]).unwrap();
            let a = uninterrupted.correlate(&frames[5]).unwrap().clone();
            let b = resumed.correlate(&frames[5]).unwrap().clone();
            let truth = (3.0, -1.75);
            let mut largest = 0.0f64;
            for (na, nb) in a.nodes.iter().zip(&b.nodes) {
                assert_eq!(na.status, nb.status);
                if na.status == NodeStatus::Ok {
                    largest = largest
                        .max((na.u_px - nb.u_px).abs())
                        .max((na.v_px - nb.v_px).abs());
                }
            }
            eprintln!(
                "{reference:?} {guess:?}: {updates} reference updates in frames 1-3; frame 5 mean u {:+.4}/{:+.4} v {:+.4}/{:+.4} px (uninterrupted/resumed, truth {:+.2} {:+.2}), largest node difference {largest:.2e} px",
                a.u_mean_px, b.u_mean_px, a.v_mean_px, b.v_mean_px, truth.0, truth.1
            );
            assert!(b.valid == b.nodes.len(), "{reference:?}: all nodes valid");
            assert!((b.u_mean_px - truth.0).abs() < 0.02 && (b.v_mean_px - truth.1).abs() < 0.02);
            match reference {
                ReferenceMode::Fixed => assert_eq!(updates, 0),
                _ => assert!(updates > 0, "{reference:?} must have updated its reference"),
            }
            // Same reference, same settings: the same field. Fixed with the paper's guess: the
            // identical computation. Fixed with the predictor: the uninterrupted run starts each
            // ZOI from the previous field, the resumed one grows from the centre, so the integer
            // start and hence the sub-pixel path differ (a few thousandths of a pixel).
            // Incremental and auto: the uninterrupted run also took frame 4 as reference, so it
            // differs by the noise of two frames.
            let tolerance = match (reference, guess) {
                (ReferenceMode::Fixed, GuessMode::Correli) => 1e-12,
                (ReferenceMode::Fixed, GuessMode::Predict) => 0.02,
                _ => 0.05,
            };
            assert!(largest < tolerance, "{reference:?} {guess:?}: {largest}");
        }
    }
}

#[test]
fn restore_refuses_a_base_of_another_mesh() {
    let settings = CorrelatorSettings::default();
    let mut correlator = Correlator::new(settings, 128, 128).unwrap();
    let pixels = vec![1000u16; 128 * 128];
    let error = correlator
        .restore_reference(&pixels, &[(0.0, 0.0); 3])
        .unwrap_err();
    assert!(
        error.to_string().contains("3 node displacements"),
        "{error}"
    );
    let n = correlator.mesh_size().0 * correlator.mesh_size().1;
    let mut bases = vec![(0.0, 0.0); n];
    bases[2].1 = f64::NAN;
    let error = correlator.restore_reference(&pixels, &bases).unwrap_err();
    assert!(error.to_string().contains("node 2"), "{error}");
    assert!(correlator.reference_pixels().is_none());
}
