//! Bad input gives clear errors, never a panic.

use identifier::data::{parse_curve_csv, Curve, LoadCase};
use identifier::fit::{fit_model, FitError, FitOptions, ResidualKind};
use identifier::lsq::LsqError;
use identifier::models::Model;

fn parse(text: &str) -> Result<Curve, String> {
    parse_curve_csv(text, "test.csv", LoadCase::Uniaxial, &Default::default())
        .map_err(|e| e.to_string())
}

#[test]
fn empty_file() {
    let e = parse("").unwrap_err();
    assert!(e.contains("test.csv") && e.contains("empty file"), "{e}");
    let e = parse("stretch,nominal_stress_mpa\n").unwrap_err();
    assert!(e.contains("no data rows"), "{e}");
}

#[test]
fn non_numeric_cell_names_the_line() {
    let e = parse("stretch,nominal_stress_mpa\n1.1,0.1\n1.2,abc\n").unwrap_err();
    assert!(e.contains("line 3") && e.contains("`abc`"), "{e}");
    let e = parse("stretch,nominal_stress_mpa\n1.1,0.1,7\n").unwrap_err();
    assert!(
        e.contains("line 2") && e.contains("expected 2 cells"),
        "{e}"
    );
    let e = parse("1.1,0.1\n1.2,0.2\n").unwrap_err();
    assert!(e.contains("header"), "{e}");
}

#[test]
fn stretch_below_one_and_reference_row() {
    let e = parse("stretch,nominal_stress_mpa\n0.9,-0.1\n1.1,0.1\n1.2,0.2\n").unwrap_err();
    assert!(e.contains("line 2") && e.contains("below 1"), "{e}");
    let c = parse("stretch,nominal_stress_mpa\n1.0,0.0\n1.1,0.1\n1.2,0.2\n").unwrap();
    assert_eq!((c.len(), c.reference_rows_dropped), (2, 1));
}

#[test]
fn non_monotonic_stretch() {
    let e = parse("stretch,nominal_stress_mpa\n1.1,0.1\n1.3,0.3\n1.2,0.2\n").unwrap_err();
    assert!(e.contains("line 4") && e.contains("increasing"), "{e}");
    let e = parse("stretch,nominal_stress_mpa\n1.1,0.1\n1.1,0.1\n").unwrap_err();
    assert!(e.contains("line 3"), "{e}");
}

#[test]
fn too_few_points() {
    let e = parse("stretch,nominal_stress_mpa\n1.0,0.0\n1.1,0.1\n").unwrap_err();
    assert!(e.contains("too few points"), "{e}");
    let c = Curve::new(LoadCase::Uniaxial, vec![1.1, 1.2, 1.3], vec![0.1, 0.2, 0.3]).unwrap();
    let e = fit_model(
        &Model::Ogden(3),
        std::slice::from_ref(&c),
        &FitOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            FitError::Lsq {
                error: LsqError::TooFewPoints {
                    points: 3,
                    params: 6
                },
                ..
            }
        ),
        "{e:?}"
    );
    assert!(
        e.to_string().contains("3 data points for 6 parameters"),
        "{e}"
    );
    // Mooney (2 parameters) from 3 uniaxial points is fine.
    let e = fit_model(&Model::Mooney, &[c], &FitOptions::default());
    assert!(
        e.is_ok(),
        "C10 + C01 are identifiable from uniaxial data: {e:?}"
    );
}

#[test]
fn unidentifiable_parameters_are_an_error_not_a_panic() {
    // Pure shear only: I1 = I2 and the Mooney stress (C10 + C01)(λ − λ⁻³) depends on the sum only.
    let stretch: Vec<f64> = (1..=10).map(|k| 1.0 + 0.1 * k as f64).collect();
    let stress = stretch.iter().map(|l| 0.4 * (l - l.powi(-3))).collect();
    let c = Curve::new(LoadCase::PureShear, stretch, stress).unwrap();
    let e = fit_model(&Model::Mooney, &[c], &FitOptions::default()).unwrap_err();
    assert!(e.to_string().contains("not identifiable"), "{e}");
}

#[test]
fn zero_stress_with_relative_residuals() {
    let c = Curve::new(LoadCase::Uniaxial, vec![1.1, 1.2, 1.3], vec![0.0, 0.2, 0.3]).unwrap();
    let options = FitOptions {
        residual: ResidualKind::Relative,
        ..FitOptions::default()
    };
    let e = fit_model(&Model::NeoHookean, &[c], &options).unwrap_err();
    assert!(e.to_string().contains("zero stress"), "{e}");
}
