//! The consistent tangent against finite differences: at a point (taut and wrinkled states, the
//! analytic law and a catalogue-style closure) and assembled over a distorted sheet.

use crate::common;

use common::{noise, square};
use material::InvariantLaw;
use membrane::constitutive::{response, PointResponse};
use membrane::{
    InvariantDerivatives, Membrane, MembraneState, PrincipalStresses, SheetLaw, Wrinkling,
};

/// S at Green-Lagrange e = [E11, E22, 2E12].
fn at_strain(law: &dyn SheetLaw, e: [f64; 3], wrinkling: &Wrinkling) -> PointResponse {
    let c = [1.0 + 2.0 * e[0], 1.0 + 2.0 * e[1], e[2]];
    response(law, &c, wrinkling).unwrap()
}

fn check_point(
    law: &dyn SheetLaw,
    e: [f64; 3],
    wrinkling: &Wrinkling,
    state: MembraneState,
    tolerance: f64,
) {
    let exact = at_strain(law, e, wrinkling);
    assert_eq!(exact.state, state, "e = {e:?}");
    let h = 1e-6;
    let scale = exact
        .tangent_mpa
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    for j in 0..3 {
        let mut plus = e;
        let mut minus = e;
        plus[j] += h;
        minus[j] -= h;
        let (sp, sm) = (
            at_strain(law, plus, wrinkling),
            at_strain(law, minus, wrinkling),
        );
        for i in 0..3 {
            let fd = (sp.stress_pk2_mpa[i] - sm.stress_pk2_mpa[i]) / (2.0 * h);
            assert!(
                (fd - exact.tangent_mpa[i][j]).abs() < tolerance * scale,
                "D[{i}][{j}] = {} vs finite difference {fd} at e = {e:?} ({state:?})",
                exact.tangent_mpa[i][j]
            );
        }
    }
}

#[test]
fn point_tangent_matches_finite_differences() {
    let smactane = InvariantLaw::smactane();
    // A coupled law with W12 ≠ 0 through the default (difference) second derivatives.
    let coupled = InvariantDerivatives(|i1: f64, i2: f64| {
        Some((
            0.3 + 0.02 * (i1 - 3.0) * (i2 - 3.0),
            0.05 + 0.01 * (i1 - 3.0) * (i1 - 3.0),
        ))
    });
    // Ogden (2 terms) through its principal stresses.
    let ogden = PrincipalStresses(|l1: f64, l2: f64| {
        let l3 = 1.0 / (l1 * l2);
        let s = |l: f64| 0.6 * (l.powf(1.3) - l3.powf(1.3)) + 0.01 * (l.powf(5.0) - l3.powf(5.0));
        Some([s(l1), s(l2)])
    });
    let laws: [&dyn SheetLaw; 3] = [&smactane, &coupled, &ogden];
    let on = Wrinkling::default();
    for law in laws {
        for e in [[0.3, 0.1, 0.2], [1.5, 0.4, -0.3], [0.05, 0.02, 0.01]] {
            check_point(law, e, &on, MembraneState::Taut, 1e-6);
        }
        // Stretched along x, not enough lateral contraction allowed: wrinkled.
        for e in [[0.6, -0.3, 0.1], [2.0, -0.35, 0.2]] {
            check_point(law, e, &on, MembraneState::Wrinkled, 1e-6);
        }
    }
}

#[test]
fn relaxed_stress_meets_the_full_one_on_the_taut_boundary() {
    let law = InvariantLaw::smactane();
    let stretch: f64 = 1.8;
    // The uniaxial state: λ2 = λ^−½ is the boundary; a little more contraction wrinkles.
    for (lateral, state) in [
        (1.0 / stretch.sqrt(), MembraneState::Taut),
        (0.98 / stretch.sqrt(), MembraneState::Wrinkled),
    ] {
        let e = [
            0.5 * (stretch * stretch - 1.0),
            0.5 * (lateral * lateral - 1.0),
            0.0,
        ];
        // The relaxed law alone (no residual stiffness): uniaxial tension along x exactly.
        let pure = Wrinkling {
            residual_stiffness: 0.0,
            ..Wrinkling::default()
        };
        let r = at_strain(&law, e, &pure);
        assert_eq!(r.state, state);
        let sigma = r.stress_pk2_mpa[0] * stretch * stretch;
        let exact = law.uniaxial_cauchy_stress_mpa(stretch);
        assert!(
            (sigma - exact).abs() < 1e-12 * exact,
            "{state:?}: {sigma} vs {exact}"
        );
        assert!(r.stress_pk2_mpa[1].abs() < 1e-12 * r.stress_pk2_mpa[0]);
    }
}

#[test]
fn assembled_tangent_matches_finite_differences_of_the_forces() {
    let law = InvariantLaw::smactane();
    let specimen = square(10.0, 2);
    let membrane = Membrane::new(&specimen.mesh, 2.0, &law, Wrinkling::off()).unwrap();
    let mut random = noise(3);
    let u: Vec<f64> = specimen
        .mesh
        .nodes_mm
        .iter()
        .flat_map(|p| {
            [
                0.4 * p[0] + 0.3 * random(),
                0.1 * p[1] + 0.05 * p[0] + 0.3 * random(),
            ]
        })
        .collect();
    let v: Vec<f64> = (0..u.len()).map(|_| random()).collect();
    let evaluation = membrane.evaluate(&u, true).unwrap();
    let mut k_v = vec![0.0; u.len()];
    for (element, k) in specimen
        .mesh
        .elements
        .iter()
        .zip(&evaluation.element_tangents)
    {
        for r in 0..12 {
            for c in 0..12 {
                k_v[2 * element[r / 2] + r % 2] += k[r][c] * v[2 * element[c / 2] + c % 2];
            }
        }
    }
    let h = 1e-6;
    let shifted = |sign: f64| -> Vec<f64> {
        let w: Vec<f64> = u.iter().zip(&v).map(|(a, b)| a + sign * h * b).collect();
        membrane.evaluate(&w, false).unwrap().forces_n
    };
    let (plus, minus) = (shifted(1.0), shifted(-1.0));
    let scale = k_v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for i in 0..u.len() {
        let fd = (plus[i] - minus[i]) / (2.0 * h);
        assert!(
            (fd - k_v[i]).abs() < 1e-7 * scale,
            "dof {i}: K v = {} vs {fd}",
            k_v[i]
        );
    }
}

#[test]
fn principal_stresses_give_the_invariant_law_back() {
    let law = InvariantLaw::smactane();
    let by_stresses =
        PrincipalStresses(|l1: f64, l2: f64| Some(law.in_plane_stress(l1, l2).cauchy_stress_mpa));
    let on = Wrinkling::default();
    // Generic, equal-stretch (the limit) and wrinkled states.
    for e in [
        [0.3, 0.1, 0.2],
        [0.0, 0.0, 0.0],
        [0.4, 0.4, 0.0],
        [0.6, -0.3, 0.1],
    ] {
        let (a, b) = (at_strain(&law, e, &on), at_strain(&by_stresses, e, &on));
        assert_eq!(a.state, b.state);
        let scale = a
            .tangent_mpa
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..3 {
            assert!(
                (a.stress_pk2_mpa[i] - b.stress_pk2_mpa[i]).abs() < 1e-12 * scale,
                "{e:?}"
            );
            for j in 0..3 {
                assert!(
                    (a.tangent_mpa[i][j] - b.tangent_mpa[i][j]).abs() < 1e-6 * scale,
                    "{e:?} D[{i}][{j}]: {} vs {}",
                    a.tangent_mpa[i][j],
                    b.tangent_mpa[i][j]
                );
            }
        }
    }
}
