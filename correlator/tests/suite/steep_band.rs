//! A steep displacement band on images the product did not render (`common::independent`):
//! u(X) = A / (1 + exp(−(X − x0) / w)) along x, A = 9 px (the motion of the public SEM pair of
//! issue 26), for band widths w of 8, 16 and 32 px (10-90 % rise over 35 to 140 px; the
//! steepest strain A / 4w from 0.28 to 0.07), each method at its usual size (`correli` 32 px,
//! IC-GN 33 px). Prints the RMS error in the band (|X − x0| ≤ 2.2 w, the 10-90 % rise) and
//! elsewhere, per method and width:
//! `cargo test --release -p correlator --test suite -- steep_band:: --nocapture`.

use crate::common;

use common::independent::{render, IndependentSpeckle};
use correlator::{Correlator, CorrelatorSettings, Method, NodeStatus};

const SIZE: usize = 384;
const AMPLITUDE_PX: f64 = 9.0;
const CENTRE_PX: f64 = 191.5;

fn u(x: f64, width: f64) -> f64 {
    AMPLITUDE_PX / (1.0 + (-(x - CENTRE_PX) / width).exp())
}

/// X of the image point x: X + u(X) = x by Newton (1 + u' > 0 everywhere).
fn to_reference(x: [f64; 2], width: f64) -> [f64; 2] {
    let mut p = x[0] - u(x[0], width);
    for _ in 0..50 {
        let s = 1.0 / (1.0 + (-(p - CENTRE_PX) / width).exp());
        let slope = AMPLITUDE_PX * s * (1.0 - s) / width;
        let step = (p + u(p, width) - x[0]) / (1.0 + slope);
        p -= step;
        if step.abs() < 1e-12 {
            break;
        }
    }
    [p, x[1]]
}

/// RMS error (px) in the band and elsewhere, and the ok nodes in each, of `method`.
fn errors(method: Method, width: f64) -> ((f64, usize), (f64, usize)) {
    let pattern = IndependentSpeckle::default();
    let reference = render(&pattern, SIZE, SIZE, &|x| x, 1);
    let deformed = render(&pattern, SIZE, SIZE, &|x| to_reference(x, width), 2);
    let zoi_px = if method.is_icgn() { 33 } else { 32 };
    let settings = CorrelatorSettings {
        method,
        zoi_px,
        step_px: 8,
        ..CorrelatorSettings::default()
    };
    let mut correlator = Correlator::new(settings, SIZE, SIZE).unwrap();
    correlator.set_reference(&reference).unwrap();
    let field = correlator.correlate(&deformed).unwrap();
    let (mut band, mut elsewhere) = ((0.0, 0), (0.0, 0));
    for node in field.nodes.iter().filter(|n| n.status == NodeStatus::Ok) {
        let e2 = (node.u_px - u(node.x_px, width)).powi(2) + node.v_px.powi(2);
        let bucket = if (node.x_px - CENTRE_PX).abs() <= 2.2 * width {
            &mut band
        } else {
            &mut elsewhere
        };
        bucket.0 += e2;
        bucket.1 += 1;
    }
    let rms = |(sum, n): (f64, usize)| ((sum / n.max(1) as f64).sqrt(), n);
    (rms(band), rms(elsewhere))
}

#[test]
fn steep_bands_measured_by_every_method() {
    for width in [8.0, 16.0, 32.0] {
        let mut rows = vec![];
        for method in [Method::Correli, Method::Icgn1, Method::Icgn2] {
            let ((band, nb), (rest, nr)) = errors(method, width);
            println!(
                "band width {width:>4} px, {:>7}: RMS in the band {band:.4} px ({nb} ok nodes), elsewhere {rest:.4} px ({nr})",
                method.name()
            );
            rows.push((method, band, rest, nb));
        }
        for (method, band, _, nb) in &rows {
            assert!(*nb > 0, "{method:?}: no ok node in the band");
            assert!(band.is_finite());
        }
    }
}
