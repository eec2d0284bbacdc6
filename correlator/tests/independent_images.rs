//! Images the product did not render: an independent generator (`common::independent`: hard
//! spray-paint discs, pixel-area integration in the deformed frame, optical blur, bit depth,
//! read and shot noise) with dot sizes from 3 to 9 px, 8 to 16 bit, low and high contrast, and
//! noise from 0.5 to 3 % of full scale, under a sub-pixel translation, a 30° rotation and a
//! 30 % uniaxial stretch against a fixed reference, with the default settings. Every case:
//! no `ok` node more than 0.5 px off, most of the measurable nodes `ok`, and a bounded RMS.

mod common;

use common::accuracy;
use common::independent::{affine_inverse, render, rotation, IndependentSpeckle};
use correlator::{Correlator, CorrelatorSettings};

const SIZE: usize = 512;

fn centre() -> [f64; 2] {
    let c = (SIZE as f64 - 1.0) / 2.0;
    [c, c]
}

/// Correlates one pattern under motion x = c + F (X − c) + t and checks the outcome.
fn check(name: &str, pattern: IndependentSpeckle, f: [[f64; 2]; 2], t: [f64; 2], max_rms_px: f64) {
    let reference = render(&pattern, SIZE, SIZE, &|x| x, 1);
    let deformed = render(&pattern, SIZE, SIZE, &affine_inverse(f, t, centre()), 2);
    let mut correlator = Correlator::new(CorrelatorSettings::default(), SIZE, SIZE).unwrap();
    correlator.set_reference(&reference).unwrap();
    let field = correlator.correlate(&deformed).unwrap();
    let c = centre();
    let forward = |p: [f64; 2]| {
        let d = [p[0] - c[0], p[1] - c[1]];
        [
            c[0] + f[0][0] * d[0] + f[0][1] * d[1] + t[0],
            c[1] + f[1][0] * d[0] + f[1][1] * d[1] + t[1],
        ]
    };
    let o = accuracy(field, 32, (SIZE, SIZE), forward);
    o.print(name);
    assert_eq!(o.false_ok, 0, "{name}: wrong nodes reported ok: {o:?}");
    assert!(o.valid_fraction() >= 0.9, "{name}: {o:?}");
    assert!(o.rms_px <= max_rms_px, "{name}: {o:?}");
}

fn patterns() -> Vec<(&'static str, IndependentSpeckle, f64)> {
    let base = IndependentSpeckle::default();
    vec![
        ("5 px dots, 8 bit, 1 % noise", base, 0.03),
        (
            "3 px dots, 12 bit, 0.5 % noise",
            IndependentSpeckle {
                dot_diameter_px: 3.0,
                bit_depth: 12,
                read_noise: 0.005,
                seed: 11,
                ..base
            },
            0.03,
        ),
        (
            "9 px dots, 16 bit, shot noise",
            IndependentSpeckle {
                dot_diameter_px: 9.0,
                bit_depth: 16,
                read_noise: 0.002,
                shot_noise: 1e-4,
                blur_sigma_px: 1.2,
                seed: 12,
                ..base
            },
            0.03,
        ),
        (
            "5 px dots, 8 bit, low contrast, 3 % noise",
            IndependentSpeckle {
                background: 0.55,
                dot: 0.35,
                read_noise: 0.03,
                seed: 13,
                ..base
            },
            0.12,
        ),
        (
            "bright 6 px dots on dark, 10 bit",
            IndependentSpeckle {
                dot_diameter_px: 6.0,
                background: 0.1,
                dot: 0.9,
                bit_depth: 10,
                coverage: 0.35,
                seed: 14,
                ..base
            },
            0.03,
        ),
    ]
}

#[test]
fn translation_on_independent_images() {
    for (name, pattern, rms) in patterns() {
        let identity = [[1.0, 0.0], [0.0, 1.0]];
        check(
            &format!("translation (3.4, -1.7), {name}"),
            pattern,
            identity,
            [3.4, -1.7],
            rms,
        );
    }
}

#[test]
fn rotation_on_independent_images() {
    for (name, pattern, rms) in patterns() {
        check(
            &format!("rotation 30°, {name}"),
            pattern,
            rotation(30.0),
            [2.0, 1.0],
            rms,
        );
    }
}

#[test]
fn uniaxial_stretch_on_independent_images() {
    for (name, pattern, rms) in patterns() {
        check(
            &format!("uniaxial 30 %, ν 0.3, {name}"),
            pattern,
            [[1.3, 0.0], [0.0, 0.91]],
            [0.0, 0.0],
            2.0 * rms,
        );
    }
}
