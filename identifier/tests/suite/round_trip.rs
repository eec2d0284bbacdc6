//! Round trip: Smactane stresses (Tables 3 & 4, n = 2) with 1 % seeded noise, uniaxial to
//! λ = 3 and equibiaxial to λ = 2, must give back the law and its coefficients.

use identifier::data::{Curve, LoadCase};
use identifier::fit::{fit_model, FitOptions, ResidualKind};
use identifier::law::InvariantLaw;
use identifier::models::Model;
use identifier::route::paper_route;

/// SplitMix64 + Box-Muller: a seeded normal generator without dependencies.
struct Normal(u64);

impl Normal {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn sample(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// Points per path (a rig records many more; 50 keeps the test fast).
const POINTS_PER_PATH: usize = 50;
const NOISE_RELATIVE: f64 = 0.01;
const TRUTH: [f64; 6] = [-1.27, -2.52e-2, 1.40e-3, -1.02, -3.92e-3, -5.30e-4];

fn synthetic(seed: u64) -> Vec<Curve> {
    let law = InvariantLaw::smactane();
    let mut rng = Normal(seed);
    let mut path = |case: LoadCase, max_stretch: f64| {
        let stretch: Vec<f64> = (1..=POINTS_PER_PATH)
            .map(|k| 1.0 + (max_stretch - 1.0) * k as f64 / POINTS_PER_PATH as f64)
            .collect();
        let stress = stretch
            .iter()
            .map(|&l| {
                let p = match case {
                    LoadCase::Uniaxial => law.uniaxial_nominal_stress_mpa(l),
                    _ => law.equibiaxial_nominal_stress_mpa(l),
                };
                p * (1.0 + NOISE_RELATIVE * rng.sample())
            })
            .collect();
        Curve::new(case, stretch, stress).unwrap()
    };
    vec![
        path(LoadCase::Uniaxial, 3.0),
        path(LoadCase::Equibiaxial, 2.0),
    ]
}

fn options() -> FitOptions {
    FitOptions {
        residual: ResidualKind::Relative,
        ..FitOptions::default()
    }
}

#[test]
fn smactane_round_trip() {
    let curves = synthetic(2024);
    let route = paper_route(&curves, 2, 2).unwrap();
    eprintln!(
        "route (eqs 20-25): a = {:?}, b = {:?}, c (eq. 24) = {:?}",
        route.a, route.b, route.c
    );
    let model = Model::LambertDianiRey {
        f_degree: 2,
        g_degree: 2,
    };
    let fit = fit_model(&model, &curves, &options()).unwrap();
    assert!(fit.converged);
    eprintln!(
        "{:<4} {:>12} {:>12} {:>12} {:>8}",
        "coef", "truth", "fitted", "std", "|z|"
    );
    for (k, name) in fit.param_names.iter().enumerate() {
        let std = fit.stderr[k].expect("covariance is regular");
        let z = (fit.params[k] - TRUTH[k]).abs() / std;
        eprintln!(
            "{name:<4} {:>12.4e} {:>12.4e} {:>12.2e} {:>8.2}",
            TRUTH[k], fit.params[k], std, z
        );
        assert!(
            z < 2.0,
            "{name}: {} vs truth {} (std {std})",
            fit.params[k],
            TRUTH[k]
        );
    }
    let worst = worst_relative_deviation(&model, &fit.params);
    eprintln!(
        "worst relative deviation from the noise-free stresses over both paths: {:.3} %",
        100.0 * worst
    );
    assert!(worst < 0.01, "worst relative deviation {worst}");
}

/// Largest |P_fit / P_true - 1| over 200 stretches of each path (noise-free truth).
fn worst_relative_deviation(model: &Model, params: &[f64]) -> f64 {
    let law = InvariantLaw::smactane();
    let mut worst: f64 = 0.0;
    for (case, max_stretch) in [(LoadCase::Uniaxial, 3.0), (LoadCase::Equibiaxial, 2.0)] {
        for k in 1..=200 {
            let l = 1.0 + (max_stretch - 1.0) * k as f64 / 200.0;
            let truth = match case {
                LoadCase::Uniaxial => law.uniaxial_nominal_stress_mpa(l),
                _ => law.equibiaxial_nominal_stress_mpa(l),
            };
            let got = model.nominal_stress_mpa(params, case, l).unwrap();
            worst = worst.max((got / truth - 1.0).abs());
        }
    }
    worst
}

/// Checks that the reported standard deviations are honest: over many seeds, about 95 % of
/// the coefficients fall within two of them.
#[test]
fn standard_deviations_cover_the_truth() {
    const SEEDS: u64 = 40;
    let model = Model::LambertDianiRey {
        f_degree: 2,
        g_degree: 2,
    };
    let mut inside = 0;
    let mut total = 0;
    let mut within_one_percent = 0;
    let mut worst_of_all: f64 = 0.0;
    for seed in 0..SEEDS {
        let fit = fit_model(&model, &synthetic(seed), &options()).unwrap();
        let worst = worst_relative_deviation(&model, &fit.params);
        worst_of_all = worst_of_all.max(worst);
        within_one_percent += usize::from(worst < 0.01);
        for ((param, std), truth) in fit.params.iter().zip(&fit.stderr).zip(TRUTH) {
            total += 1;
            if (param - truth).abs() < 2.0 * std.unwrap() {
                inside += 1;
            }
        }
    }
    let coverage = inside as f64 / total as f64;
    eprintln!(
        "stresses within 1 % of the truth over both paths: {within_one_percent}/{SEEDS} seeds, worst {:.3} %",
        100.0 * worst_of_all
    );
    eprintln!(
        "2-std coverage over {SEEDS} seeds: {:.1} % ({inside}/{total})",
        100.0 * coverage
    );
    assert!(coverage > 0.88 && coverage <= 1.0, "coverage {coverage}");
}
