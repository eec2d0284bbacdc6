//! Every invariant potential of the identifier's catalogue drives the sheet, from its one
//! definition (`Model::invariant_derivatives_mpa`): a free square in uniaxial tension gives the
//! catalogue's own in-plane stress.

mod common;

use common::{close, roller, square};
use identifier::models::Model;
use membrane::{solve, Held, InvariantDerivatives, Membrane, NewtonSettings, Wrinkling};

/// Parameters giving a stable law for each model (MPa, dimensionless exponents).
fn parameters(model: &Model) -> Vec<f64> {
    let names = model.param_names();
    match model {
        Model::Gent => vec![0.6, 30.0],
        Model::ArrudaBoyce => vec![0.6, 8.0],
        Model::Alexander => vec![0.3, 0.001, 0.05, 1.0, 0.01],
        Model::HartSmith => vec![0.3, 0.001, 0.1],
        Model::LambertDianiRey { .. } => {
            let mut p = vec![0.0; names.len()];
            p[0] = -1.27;
            p[names.iter().position(|n| n.starts_with('b')).unwrap()] = -1.02;
            p
        }
        _ => names
            .iter()
            .enumerate()
            .map(|(k, _)| if k == 0 { 0.3 } else { 0.02 })
            .collect(),
    }
}

#[test]
fn every_invariant_model_of_the_catalogue_is_a_usable_law() {
    let specimen = square(10.0, 2);
    let stretch = 1.8;
    let clamps = [
        roller(&specimen, Held::X, [0.0; 2], |p| (p[0] + 5.0).abs() < 1e-9),
        roller(&specimen, Held::X, [(stretch - 1.0) * 10.0, 0.0], |p| {
            (p[0] - 5.0).abs() < 1e-9
        }),
        roller(&specimen, Held::Y, [0.0; 2], |p| {
            (p[0] + 5.0).abs() < 1e-9 && p[1].abs() < 1e-9
        }),
    ];
    let mut used = 0;
    for model in Model::all() {
        if matches!(model, Model::Ogden(_)) {
            continue; // not an invariant model: principal stretches (remaining work)
        }
        let p = parameters(&model);
        let law = InvariantDerivatives(|i1, i2| model.invariant_derivatives_mpa(&p, i1, i2));
        let membrane = Membrane::new(&specimen.mesh, 2.0, &law, Wrinkling::default()).unwrap();
        let equilibrium = solve(&membrane, &clamps, NewtonSettings::default())
            .unwrap_or_else(|e| panic!("{model}: {e}"));
        let exact = model
            .in_plane_cauchy_stress_mpa(&p, stretch, 1.0 / stretch.sqrt())
            .unwrap()[0];
        for field in membrane.point_fields(&equilibrium.displacement_mm).unwrap() {
            assert!(
                close(field.cauchy_stress_mpa[0], exact, 1e-9, exact),
                "{model}: {:?} vs {exact}",
                field.cauchy_stress_mpa
            );
        }
        used += 1;
    }
    assert!(used >= 10, "{used} models");
}
