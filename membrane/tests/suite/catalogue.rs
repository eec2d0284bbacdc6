//! Every potential of the identifier's catalogue drives the sheet, from its one definition:
//! `Model::invariant_derivatives_mpa` for the invariant models, `in_plane_cauchy_stress_mpa`
//! for all (Ogden included). A free square in uniaxial tension gives the catalogue's own
//! in-plane stress.

use crate::common;

use common::{close, roller, square};
use identifier::models::Model;
use membrane::{
    solve, Held, InvariantDerivatives, Membrane, NewtonSettings, PrincipalStresses, SheetLaw,
    Specimen, Wrinkling,
};

/// Parameters giving a stable law for each model (MPa, dimensionless exponents).
fn parameters(model: &Model) -> Vec<f64> {
    let names = model.param_names();
    match model {
        Model::Gent => vec![0.6, 30.0],
        Model::Ogden(2) => vec![0.6, 0.01, 1.3, 5.0],
        Model::Ogden(3) => vec![0.6, 0.001, -0.01, 1.3, 5.0, -2.0],
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

/// The uniaxial Cauchy stress (MPa) of a free square stretched by `stretch` under `law`,
/// checked uniform over the Gauss points to 1e-9.
fn uniaxial_stress_mpa(specimen: &Specimen, law: &dyn SheetLaw, stretch: f64) -> f64 {
    let clamps = [
        roller(specimen, Held::X, [0.0; 2], |p| (p[0] + 5.0).abs() < 1e-9),
        roller(specimen, Held::X, [(stretch - 1.0) * 10.0, 0.0], |p| {
            (p[0] - 5.0).abs() < 1e-9
        }),
        roller(specimen, Held::Y, [0.0; 2], |p| {
            (p[0] + 5.0).abs() < 1e-9 && p[1].abs() < 1e-9
        }),
    ];
    let membrane = Membrane::new(&specimen.mesh, 2.0, law, Wrinkling::default()).unwrap();
    let equilibrium = solve(&membrane, &clamps, NewtonSettings::default()).unwrap();
    let fields = membrane.point_fields(&equilibrium.displacement_mm).unwrap();
    let first = fields[0].cauchy_stress_mpa[0];
    assert!(fields
        .iter()
        .all(|f| close(f.cauchy_stress_mpa[0], first, 1e-9, first)));
    first
}

#[test]
fn every_model_of_the_catalogue_is_a_usable_law() {
    let specimen = square(10.0, 2);
    let stretch = 1.8;
    for model in Model::all() {
        let p = parameters(&model);
        let exact = model
            .in_plane_cauchy_stress_mpa(&p, stretch, 1.0 / stretch.sqrt())
            .unwrap()[0];
        let by_stresses = PrincipalStresses(|l1, l2| model.in_plane_cauchy_stress_mpa(&p, l1, l2));
        let sigma = uniaxial_stress_mpa(&specimen, &by_stresses, stretch);
        assert!(
            close(sigma, exact, 1e-9, exact),
            "{model}: {sigma} vs {exact}"
        );
        if !matches!(model, Model::Ogden(_)) {
            let by_invariants =
                InvariantDerivatives(|i1, i2| model.invariant_derivatives_mpa(&p, i1, i2));
            let sigma = uniaxial_stress_mpa(&specimen, &by_invariants, stretch);
            assert!(
                close(sigma, exact, 1e-9, exact),
                "{model}: {sigma} vs {exact}"
            );
        }
    }
}
