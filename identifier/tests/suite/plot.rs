//! Plots are written as PNG files for synthetic Smactane data (with or without a system font).

use identifier::data::{Curve, LoadCase};
use identifier::fit::{fit_ranked, FitOptions};
use identifier::law::InvariantLaw;
use identifier::models::Model;
use identifier::route::paper_route;

#[test]
fn writes_stress_and_invariant_plots() {
    let law = InvariantLaw::smactane();
    let ut: Vec<f64> = (1..=20).map(|k| 1.0 + 0.1 * k as f64).collect();
    let bt: Vec<f64> = (1..=20).map(|k| 1.0 + 0.05 * k as f64).collect();
    let curves = vec![
        Curve::new(
            LoadCase::Uniaxial,
            ut.clone(),
            ut.iter()
                .map(|&l| law.uniaxial_nominal_stress_mpa(l))
                .collect(),
        )
        .unwrap(),
        Curve::new(
            LoadCase::Equibiaxial,
            bt.clone(),
            bt.iter()
                .map(|&l| law.equibiaxial_nominal_stress_mpa(l))
                .collect(),
        )
        .unwrap(),
    ];
    let models = [
        Model::Mooney,
        Model::Ogden(2),
        Model::LambertDianiRey {
            f_degree: 2,
            g_degree: 2,
        },
    ];
    let (fits, failures) = fit_ranked(&models, &curves, &FitOptions::default());
    assert!(failures.is_empty(), "{failures:?}");
    let route = paper_route(&curves, 2, 2).unwrap();
    let dir = std::env::temp_dir().join(format!("identifier-plot-test-{}", std::process::id()));
    let written = identifier::plot::write_plots(&dir, &curves, &fits, Some(&route)).unwrap();
    eprintln!("text in plots: {}", identifier::plot::text_available());
    assert_eq!(written.len(), 4, "{written:?}");
    for path in &written {
        let bytes = std::fs::read(path).unwrap();
        assert!(
            bytes.starts_with(b"\x89PNG"),
            "{} is not a PNG",
            path.display()
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
