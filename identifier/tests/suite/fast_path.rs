//! The analytic, one-pass residual path against the straightforward reference (residual vectors
//! and a finite-difference Jacobian, the code before it): same fits on Treloar's data, same
//! normal equations; and the same bits whatever the thread count.

use crate::common;

use common::treloar;
use identifier::data::{Curve, LoadCase};
use identifier::fit::{fit_model, FitOptions, JacobianPath};
use identifier::gradient::Kinematics;
use identifier::lsq::{LeastSquares, ResidualVector};
use identifier::models::Model;
use identifier::residuals::PointSet;
use nalgebra::{DMatrix, DVector};

fn options(jacobian: JacobianPath, threads: usize) -> FitOptions {
    FitOptions {
        jacobian,
        threads,
        ..FitOptions::default()
    }
}

#[test]
fn analytic_path_fits_as_the_finite_difference_reference() {
    let Some(curves) = treloar() else { return };
    for model in Model::all() {
        let fast = fit_model(&model, &curves, &options(JacobianPath::Analytic, 1)).unwrap();
        let reference =
            fit_model(&model, &curves, &options(JacobianPath::FiniteDifference, 1)).unwrap();
        let objective_gap = (fast.objective - reference.objective).abs() / reference.objective;
        let param_gap = fast
            .params
            .iter()
            .zip(&reference.params)
            .map(|(a, b)| (a - b).abs() / b.abs().max(1e-3))
            .fold(0.0, f64::max);
        eprintln!("{model}: objective gap {objective_gap:.1e}, parameter gap {param_gap:.1e}");
        assert!(
            objective_gap < 1e-12,
            "{model}: objective {} vs reference {}",
            fast.objective,
            reference.objective
        );
        assert!(
            param_gap < 1e-6,
            "{model}: {:?} vs reference {:?}",
            fast.params,
            reference.params
        );
        assert!(
            (fast.rms_mpa - reference.rms_mpa).abs() <= 1e-9 * reference.rms_mpa,
            "{model}"
        );
    }
}

#[test]
fn one_pass_normal_equations_match_the_formed_jacobian() {
    let Some(curves) = treloar() else { return };
    let model = Model::Ogden(3);
    let p = [0.63, 0.0012, -0.01, 1.3, 5.0, -2.0];
    let points: Vec<(LoadCase, f64, f64, f64)> = curves
        .iter()
        .flat_map(|c| {
            c.stretch
                .iter()
                .zip(&c.nominal_stress_mpa)
                .map(move |(&l, &s)| (c.case, l, s, 1.0))
        })
        .collect();
    let measured: Vec<(Kinematics, f64, f64)> = points
        .iter()
        .map(|&(case, l, s, f)| (Kinematics::of(case, l), s, f))
        .collect();
    for threads in [1, 2] {
        let mut set = PointSet::new(&model, &measured, threads);
        let residuals = |q: &[f64]| set_residuals(&model, &points, q);
        let mut reference = ResidualVector {
            residuals: &residuals,
            points: points.len(),
        };
        let (mut jtj, mut jtr) = (DMatrix::zeros(6, 6), DVector::zeros(6));
        let (mut jtj_ref, mut jtr_ref) = (DMatrix::zeros(6, 6), DVector::zeros(6));
        set.normal_equations(&p, &mut jtj, &mut jtr);
        reference.normal_equations(&p, &mut jtj_ref, &mut jtr_ref);
        let cost = set.cost(&p).unwrap();
        let cost_ref = reference.cost(&p).unwrap();
        assert!((cost - cost_ref).abs() <= 1e-12 * cost_ref);
        for a in 0..6 {
            assert!(
                (jtr[a] - jtr_ref[a]).abs() <= 1e-6 * jtr_ref[a].abs().max(1e-9),
                "Jᵀr[{a}]: {} vs {}",
                jtr[a],
                jtr_ref[a]
            );
            for b in 0..6 {
                let scale = (jtj_ref[(a, a)] * jtj_ref[(b, b)]).sqrt();
                assert!(
                    (jtj[(a, b)] - jtj_ref[(a, b)]).abs() <= 1e-6 * scale,
                    "JᵀJ[{a},{b}]: {} vs {}",
                    jtj[(a, b)],
                    jtj_ref[(a, b)]
                );
            }
        }
    }
}

/// The residual vector written out the plain way (no PointSet).
fn set_residuals(
    model: &Model,
    points: &[(LoadCase, f64, f64, f64)],
    p: &[f64],
) -> Option<DVector<f64>> {
    let mut r = DVector::zeros(points.len());
    for (k, &(case, stretch, stress, factor)) in points.iter().enumerate() {
        r[k] = (model.nominal_stress_mpa(p, case, stretch)? - stress) * factor;
    }
    Some(r)
}

#[test]
fn thread_count_does_not_change_a_bit() {
    let Some(curves) = treloar() else { return };
    // Enough points for several blocks: Treloar's curves repeated on a finer stretch grid.
    let dense: Vec<Curve> = curves
        .iter()
        .map(|c| {
            let n = 3000;
            let (first, last) = (c.stretch[0], c.stretch[c.len() - 1]);
            let stretch: Vec<f64> = (0..n)
                .map(|k| first + (last - first) * k as f64 / (n - 1) as f64)
                .collect();
            let stress = stretch
                .iter()
                .map(|&l| {
                    let j = c.stretch.partition_point(|&s| s < l).clamp(1, c.len() - 1);
                    let t = (l - c.stretch[j - 1]) / (c.stretch[j] - c.stretch[j - 1]);
                    c.nominal_stress_mpa[j - 1] * (1.0 - t) + c.nominal_stress_mpa[j] * t
                })
                .collect();
            Curve::new(c.case, stretch, stress).unwrap()
        })
        .collect();
    for model in [Model::Ogden(2), Model::Gent, Model::Mooney] {
        let one = fit_model(&model, &dense, &options(JacobianPath::Analytic, 1)).unwrap();
        let three = fit_model(&model, &dense, &options(JacobianPath::Analytic, 3)).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one.params), bits(&three.params), "{model}");
        assert_eq!(
            one.objective.to_bits(),
            three.objective.to_bits(),
            "{model}"
        );
    }
}
