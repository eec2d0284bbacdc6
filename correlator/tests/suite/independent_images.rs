//! Images the product did not render: an independent generator (`common::independent`: hard
//! spray-paint discs, pixel-area integration in the deformed frame, optical blur, bit depth,
//! read and shot noise) with dot sizes from 3 to 9 px, 8 to 16 bit, low and high contrast, and
//! noise from 0.5 to 3 % of full scale, under a sub-pixel translation, a 30° rotation and a
//! 30 % uniaxial stretch against a fixed reference, with the default settings and with
//! `--method icgn1` (32 px subsets both). Every case: no `ok` node more than 0.5 px off, most
//! of the measurable nodes `ok`, and a bounded RMS (margins per method, from what was measured:
//! `cargo test --release -p correlator --test suite -- independent_images:: --nocapture --test-threads 1`
//! prints the table that is in the README).

use crate::common;

use common::accuracy;
use common::independent::{affine_inverse, render, rotation, IndependentSpeckle};
use correlator::{Correlator, CorrelatorSettings, Method};

const SIZE: usize = 512;

fn centre() -> [f64; 2] {
    let c = (SIZE as f64 - 1.0) / 2.0;
    [c, c]
}

/// What a case must reach with one method: RMS error (px) and fraction of measurable nodes ok.
#[derive(Clone, Copy)]
struct Margin {
    rms_px: f64,
    valid: f64,
}

/// One pattern, the margins of `correli` then `icgn1`.
struct Case {
    name: &'static str,
    pattern: IndependentSpeckle,
    margins: [Margin; 2],
}

const fn m(rms_px: f64, valid: f64) -> Margin {
    Margin { rms_px, valid }
}

/// Correlates one pattern under motion x = c + F (X − c) + t with both methods, prints a
/// table row per method and checks the outcome; `scale` multiplies the RMS margins.
fn check_both(motion: &str, case: &Case, f: [[f64; 2]; 2], t: [f64; 2], scale: f64) {
    for (method, margin) in [Method::Correli, Method::Icgn1]
        .into_iter()
        .zip(case.margins)
    {
        check(
            &format!("{motion}, {}", case.name),
            method,
            case.pattern,
            f,
            t,
            Margin {
                rms_px: scale * margin.rms_px,
                ..margin
            },
        );
    }
}

/// Correlates one pattern under motion x = c + F (X − c) + t and checks the outcome.
fn check(
    name: &str,
    method: Method,
    pattern: IndependentSpeckle,
    f: [[f64; 2]; 2],
    t: [f64; 2],
    margin: Margin,
) {
    let reference = render(&pattern, SIZE, SIZE, &|x| x, 1);
    let deformed = render(&pattern, SIZE, SIZE, &affine_inverse(f, t, centre()), 2);
    let settings = CorrelatorSettings {
        method,
        ..CorrelatorSettings::default()
    };
    let mut correlator = Correlator::new(settings, SIZE, SIZE).unwrap();
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
    let name = format!("{}: {name}", method.name());
    o.print(&name);
    assert_eq!(o.false_ok, 0, "{name}: wrong nodes reported ok: {o:?}");
    assert!(o.valid_fraction() >= margin.valid, "{name}: {o:?}");
    assert!(o.rms_px <= margin.rms_px, "{name}: {o:?}");
}

fn cases() -> Vec<Case> {
    let base = IndependentSpeckle::default();
    // Margins `[correli, icgn1]`: RMS about 1.5 to 2 times the measured one (README table);
    // icgn1 leaves a quarter of the low-contrast 3 % noise nodes `not_converged`.
    vec![
        Case {
            name: "5 px dots, 8 bit, 1 % noise",
            pattern: base,
            margins: [m(0.03, 0.9), m(0.015, 0.9)],
        },
        Case {
            name: "3 px dots, 12 bit, 0.5 % noise",
            pattern: IndependentSpeckle::fine_12_bit(),
            margins: [m(0.03, 0.9), m(0.012, 0.9)],
        },
        Case {
            name: "9 px dots, 16 bit, shot noise",
            pattern: IndependentSpeckle::coarse_16_bit_shot_noise(),
            margins: [m(0.03, 0.9), m(0.012, 0.9)],
        },
        Case {
            name: "5 px dots, 8 bit, low contrast, 3 % noise",
            pattern: IndependentSpeckle::low_contrast_8_bit(),
            margins: [m(0.12, 0.9), m(0.09, 0.7)],
        },
        Case {
            name: "bright 6 px dots on dark, 10 bit",
            pattern: IndependentSpeckle::bright_on_dark_10_bit(base.read_noise),
            margins: [m(0.03, 0.9), m(0.012, 0.9)],
        },
    ]
}

#[test]
fn translation_on_independent_images() {
    for case in cases() {
        let identity = [[1.0, 0.0], [0.0, 1.0]];
        check_both("translation (3.4, -1.7)", &case, identity, [3.4, -1.7], 1.0);
    }
}

#[test]
fn rotation_on_independent_images() {
    for case in cases() {
        check_both("rotation 30°", &case, rotation(30.0), [2.0, 1.0], 1.0);
    }
}

#[test]
fn uniaxial_stretch_on_independent_images() {
    for case in cases() {
        check_both(
            "uniaxial 30 %, ν 0.3",
            &case,
            [[1.3, 0.0], [0.0, 0.91]],
            [0.0, 0.0],
            2.0,
        );
    }
}
