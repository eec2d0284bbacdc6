//! Bad input is refused with a clear message, or flagged per node, never NaN or panic.

use crate::common;

use common::{render, translation};
use correlator::{Correlator, CorrelatorSettings, Method, NodeStatus, Roi, SettingsError};

fn settings(zoi_px: usize, step_px: usize) -> CorrelatorSettings {
    CorrelatorSettings {
        zoi_px,
        step_px,
        ..Default::default()
    }
}

#[test]
fn zoi_not_power_of_two_suggests_nearest() {
    let correli = CorrelatorSettings {
        method: Method::Correli,
        ..settings(30, 16)
    };
    let error = Correlator::new(correli, 256, 256).err().unwrap();
    assert_eq!(
        error,
        SettingsError::ZoiNotPowerOfTwo {
            zoi_px: 30,
            nearest: 32
        }
    );
    assert!(error.to_string().contains("use 32 px"), "{error}");
    // IC-GN takes any size from 9 px.
    let icgn = |zoi_px, step_px| CorrelatorSettings {
        method: Method::Icgn1,
        ..settings(zoi_px, step_px)
    };
    assert!(Correlator::new(icgn(30, 16), 256, 256).is_ok());
    let error = Correlator::new(icgn(7, 4), 256, 256).err().unwrap();
    assert_eq!(error, SettingsError::SubsetOutOfRange { zoi_px: 7 });
    assert!(error.to_string().contains("9 to 256"), "{error}");
}

#[test]
fn zoi_larger_than_roi() {
    let roi = Roi {
        x_px: 0,
        y_px: 0,
        width_px: 64,
        height_px: 40,
    };
    let error = Correlator::new(
        CorrelatorSettings {
            region: correlator::Region::rect(roi),
            ..settings(64, 16)
        },
        256,
        256,
    )
    .err()
    .unwrap();
    assert!(
        matches!(error, SettingsError::ZoiLargerThanRoi { .. }),
        "{error}"
    );
    let error = Correlator::new(settings(128, 16), 100, 100).err().unwrap();
    assert!(error.to_string().contains("larger than the ROI"), "{error}");
}

#[test]
fn step_zero_and_roi_outside() {
    let error = Correlator::new(settings(32, 0), 256, 256).err().unwrap();
    assert!(matches!(error, SettingsError::Step { .. }), "{error}");
    let roi = Roi {
        x_px: 200,
        y_px: 0,
        width_px: 100,
        height_px: 100,
    };
    let error = Correlator::new(
        CorrelatorSettings {
            region: correlator::Region::rect(roi),
            ..settings(32, 16)
        },
        256,
        256,
    )
    .err()
    .unwrap();
    assert!(matches!(error, SettingsError::RoiOutside { .. }), "{error}");
}

#[test]
fn images_of_different_sizes() {
    let mut correlator = Correlator::new(settings(32, 16), 128, 128).unwrap();
    let error = correlator
        .set_reference(&vec![0u16; 100 * 128])
        .err()
        .unwrap();
    assert!(
        error
            .to_string()
            .contains("reference image has 12800 pixels, expected 16384"),
        "{error}"
    );
    let error = correlator.correlate(&vec![0u16; 128 * 128]).err().unwrap();
    assert_eq!(error, SettingsError::NoReference);
    let reference = render(128, 128, 4.0, translation(0.0, 0.0), 0.01, 1);
    correlator.set_reference(&reference).unwrap();
    let error = correlator.correlate(&vec![0u16; 127 * 128]).err().unwrap();
    assert!(
        matches!(
            error,
            SettingsError::ImageSize {
                what: "deformed",
                ..
            }
        ),
        "{error}"
    );
}

#[test]
fn flat_images_are_low_contrast() {
    let (w, h) = (128, 128);
    let speckle = render(w, h, 4.0, translation(0.0, 0.0), 0.01, 1);
    let flat = vec![1000u16; w * h];
    // Flat deformed image. Over the whole image, as written (the default margin's 96 px ROI
    // leaves too little texture in the half-flat image below for a global guess or keypoints).
    let whole = CorrelatorSettings {
        region: correlator::Region::centred_pow2(),
        ..settings(32, 16)
    };
    let mut correlator = Correlator::new(whole, w, h).unwrap();
    correlator.set_reference(&speckle).unwrap();
    let field = correlator.correlate(&flat).unwrap();
    assert_eq!(field.valid, 0);
    assert!(
        field
            .nodes
            .iter()
            .all(|n| n.status == NodeStatus::LowContrast),
        "{:?}",
        field.nodes[0]
    );
    assert!(field
        .nodes
        .iter()
        .all(|n| n.u_px.is_finite() && n.score.is_finite() && n.exx.is_finite()));
    // No valid node in the control gauge: no reading, NaN (never a silent 0), and says so.
    assert!(field.gauge.log.exx.is_nan() && field.gauge_nodes == 0);
    // Flat reference.
    correlator.set_reference(&flat).unwrap();
    let field = correlator.correlate(&speckle).unwrap();
    assert!(field
        .nodes
        .iter()
        .all(|n| n.status == NodeStatus::LowContrast));
    // Half flat: only the textured nodes are valid.
    let mut half = speckle.clone();
    half[..w * h / 2].fill(3000);
    correlator.set_reference(&half).unwrap();
    let field = correlator.correlate(&half).unwrap();
    assert!(
        field.valid > 0 && field.valid < field.nodes.len(),
        "{} valid of {}: {}",
        field.valid,
        field.nodes.len(),
        field.refusals()
    );
}

#[test]
fn large_jump_goes_outside_image() {
    let (w, h) = (128, 128);
    let reference = render(w, h, 40.0, translation(0.0, 0.0), 0.01, 1);
    let deformed = render(w, h, 40.0, translation(30.0, 0.0), 0.01, 2);
    let mut correlator = Correlator::new(settings(32, 16), w, h).unwrap();
    correlator.set_reference(&reference).unwrap();
    let field = correlator.correlate(&deformed).unwrap();
    assert!(field
        .nodes
        .iter()
        .any(|n| n.status == NodeStatus::OutsideImage));
    for n in field.nodes.iter().filter(|n| n.status == NodeStatus::Ok) {
        assert!((n.u_px - 30.0).abs() < 0.05, "{n:?}");
    }
}
