//! Homogeneous states: the patch test on a distorted mesh, and a free square in uniaxial and
//! equibiaxial tension against `material`'s analytic membrane stresses (1e-9 relative).

use crate::common;

use common::{close, noise, roller, square};
use material::InvariantLaw;
use membrane::{solve, Clamp, Held, Membrane, NewtonSettings, RigidMotion, Wrinkling};

const SIDE_MM: f64 = 10.0;

#[test]
fn patch_test_reproduces_a_homogeneous_large_deformation_on_a_distorted_mesh() {
    let law = InvariantLaw::smactane();
    let mut specimen = square(SIDE_MM, 4);
    let half = 0.5 * SIDE_MM;
    let on_boundary = |p: [f64; 2]| p[0].abs().max(p[1].abs()) > half - 1e-9;
    let mut random = noise(7);
    for p in specimen
        .mesh
        .nodes_mm
        .iter_mut()
        .filter(|p| !on_boundary(**p))
    {
        p[0] += 0.15 * random();
        p[1] += 0.15 * random();
    }
    let f = [[1.4, 0.15], [0.05, 1.2]];
    let affine = |p: [f64; 2]| {
        [
            (f[0][0] - 1.0) * p[0] + f[0][1] * p[1],
            f[1][0] * p[0] + (f[1][1] - 1.0) * p[1],
        ]
    };
    let clamps: Vec<Clamp> = specimen
        .mesh
        .nodes_where(on_boundary)
        .into_iter()
        .map(|n| Clamp {
            nodes: vec![n],
            held: Held::Both,
            motion: RigidMotion::translation(affine(specimen.mesh.nodes_mm[n])),
        })
        .collect();
    let membrane = Membrane::new(&specimen.mesh, 2.0, &law, Wrinkling::default()).unwrap();
    let equilibrium = solve(&membrane, &clamps, NewtonSettings::default()).unwrap();
    for (n, p) in specimen.mesh.nodes_mm.iter().enumerate() {
        let u = affine(*p);
        for i in 0..2 {
            assert!(
                (equilibrium.displacement_mm[2 * n + i] - u[i]).abs() < 1e-10,
                "node {n}: {:?} vs {u:?}",
                &equilibrium.displacement_mm[2 * n..2 * n + 2]
            );
        }
    }
    let fields = membrane.point_fields(&equilibrium.displacement_mm).unwrap();
    let reference = fields[0].cauchy_stress_mpa;
    for field in &fields {
        for k in 0..3 {
            assert!(close(
                field.cauchy_stress_mpa[k],
                reference[k],
                1e-9,
                reference[0].abs()
            ));
        }
    }
}

#[test]
fn free_square_in_uniaxial_tension_gives_the_analytic_stress() {
    let law = InvariantLaw::smactane();
    let specimen = square(SIDE_MM, 4);
    let half = 0.5 * SIDE_MM;
    for stretch in [1.2, 2.0, 3.5] {
        let clamps = [
            roller(&specimen, Held::X, [0.0; 2], |p| (p[0] + half).abs() < 1e-9),
            roller(&specimen, Held::X, [(stretch - 1.0) * SIDE_MM, 0.0], |p| {
                (p[0] - half).abs() < 1e-9
            }),
            roller(&specimen, Held::Y, [0.0; 2], |p| {
                (p[0] + half).abs() < 1e-9 && p[1].abs() < 1e-9
            }),
        ];
        let membrane = Membrane::new(&specimen.mesh, 2.0, &law, Wrinkling::default()).unwrap();
        let equilibrium = solve(&membrane, &clamps, NewtonSettings::default()).unwrap();
        let exact = law.in_plane_stress(stretch, 1.0 / stretch.sqrt());
        let sigma = exact.cauchy_stress_mpa[0];
        for field in membrane.point_fields(&equilibrium.displacement_mm).unwrap() {
            let s = field.cauchy_stress_mpa;
            assert!(
                close(s[0], sigma, 1e-9, sigma),
                "λ {stretch}: σxx {} vs {sigma}",
                s[0]
            );
            assert!(
                s[1].abs() < 1e-9 * sigma && s[2].abs() < 1e-9 * sigma,
                "λ {stretch}: {s:?}"
            );
        }
        // The grip force is the nominal stress times the reference section.
        let force = equilibrium.grip_force_n(&clamps[1].nodes)[0];
        let nominal = exact.nominal_stress_mpa[0] * SIDE_MM * 2.0;
        assert!(close(force, nominal, 1e-9, nominal), "{force} vs {nominal}");
    }
}

#[test]
fn free_square_in_equibiaxial_tension_gives_the_analytic_stress() {
    let law = InvariantLaw::smactane();
    let specimen = square(SIDE_MM, 4);
    let half = 0.5 * SIDE_MM;
    for stretch in [1.3, 2.0] {
        let pull = 0.5 * (stretch - 1.0) * SIDE_MM;
        let edge = |axis: usize, side: f64| move |p: [f64; 2]| (p[axis] - side * half).abs() < 1e-9;
        let clamps = [
            roller(&specimen, Held::X, [-pull, 0.0], edge(0, -1.0)),
            roller(&specimen, Held::X, [pull, 0.0], edge(0, 1.0)),
            roller(&specimen, Held::Y, [0.0, -pull], edge(1, -1.0)),
            roller(&specimen, Held::Y, [0.0, pull], edge(1, 1.0)),
        ];
        let membrane = Membrane::new(&specimen.mesh, 2.0, &law, Wrinkling::default()).unwrap();
        let equilibrium = solve(&membrane, &clamps, NewtonSettings::default()).unwrap();
        let sigma = law.equibiaxial_cauchy_stress_mpa(stretch);
        for field in membrane.point_fields(&equilibrium.displacement_mm).unwrap() {
            let s = field.cauchy_stress_mpa;
            assert!(
                close(s[0], sigma, 1e-9, sigma) && close(s[1], sigma, 1e-9, sigma),
                "{s:?} vs {sigma}"
            );
            assert!(s[2].abs() < 1e-9 * sigma);
        }
    }
}
