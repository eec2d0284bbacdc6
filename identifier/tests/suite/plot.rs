//! Plots are written as PNG files for synthetic Smactane data (with or without a system font).

use identifier::data::{Curve, LoadCase};
use identifier::fit::{fit_ranked, FitOptions};
use identifier::law::InvariantLaw;
use identifier::models::Model;
use identifier::plot::PlotOptions;
use identifier::route::paper_route;
use std::path::Path;

/// Pixels of exactly `rgb` in the PNG at `path`.
fn pixels_of(path: &Path, rgb: [u8; 3]) -> usize {
    let image = image::open(path).unwrap().to_rgb8();
    image.pixels().filter(|p| p.0 == rgb).count()
}

/// The `k`-th line colour of a chart.
fn line(k: usize) -> [u8; 3] {
    wire::colour_map::line_colour(k)
}

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
    let written =
        identifier::plot::write_plots(&dir, &curves, &fits, Ok(&route), PlotOptions::default())
            .unwrap();
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
    // f(I1): the route's two sets of points (eq. 19, eq. 20) and the identified law, three
    // distinct colours; the other models only on demand.
    let f = dir.join("f_I1.png");
    for k in 0..3 {
        assert!(pixels_of(&f, line(k)) > 30, "colour {k} in f_I1.png");
    }
    assert_eq!(pixels_of(&f, line(3)), 0, "no other model by default");
    let all = dir.join("all");
    identifier::plot::write_plots(
        &all,
        &curves,
        &fits,
        Ok(&route),
        PlotOptions { all_models: true },
    )
    .unwrap();
    // On demand: the route's fit and the models that have an f (Mooney, Lambert-Diani-Rey;
    // not Ogden, whose W is in the principal stretches) too, each its own colour.
    for k in 0..5 {
        assert!(
            pixels_of(&all.join("f_I1.png"), line(k)) > 30,
            "colour {k}, all models"
        );
    }
    assert_eq!(pixels_of(&all.join("f_I1.png"), line(5)), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn without_the_route_f_and_g_show_the_identified_law_alone() {
    let law = InvariantLaw::smactane();
    let ut: Vec<f64> = (1..=20).map(|k| 1.0 + 0.1 * k as f64).collect();
    let curves = vec![Curve::new(
        LoadCase::Uniaxial,
        ut.clone(),
        ut.iter()
            .map(|&l| law.uniaxial_nominal_stress_mpa(l))
            .collect(),
    )
    .unwrap()];
    let (fits, _) = fit_ranked(
        &[Model::Mooney, Model::Ogden(2)],
        &curves,
        &FitOptions::default(),
    );
    let why = paper_route(&curves, 2, 2).unwrap_err().to_string();
    let dir = std::env::temp_dir().join(format!("identifier-plot-noroute-{}", std::process::id()));
    let written =
        identifier::plot::write_plots(&dir, &curves, &fits, Err(&why), PlotOptions::default())
            .unwrap();
    let f = dir.join("f_I1.png");
    assert!(written.contains(&f), "{written:?}");
    assert!(pixels_of(&f, line(0)) > 30, "the identified law");
    assert_eq!(pixels_of(&f, line(1)), 0, "one curve, no other model");
    std::fs::remove_dir_all(&dir).unwrap();
}
