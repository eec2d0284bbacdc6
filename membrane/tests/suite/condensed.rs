//! The grips' condensed tangent against finite differences of solved grip forces, and a
//! warm-started solve against one from rest.

// The stiffness matrix indexed by grip, as K[a][b] reads.
#![allow(clippy::needless_range_loop)]

use material::InvariantLaw;
use membrane::specimens::cruciform::CruciformGeometry;
use membrane::specimens::Specimen;
use membrane::{
    condense, solve, solve_from, Equilibrium, GripStretch, Membrane, NewtonSettings, Wrinkling,
};

fn cruciform() -> Specimen {
    CruciformGeometry {
        element_size_mm: 20.0,
        ..CruciformGeometry::default()
    }
    .mesh()
    .unwrap()
}

/// Each grip's axial force (N, positive when it pulls).
fn axial_forces(specimen: &Specimen, equilibrium: &Equilibrium) -> Vec<f64> {
    specimen
        .grips
        .iter()
        .map(|g| {
            let f = equilibrium.grip_force_n(&g.nodes);
            f[0] * g.axis[0] + f[1] * g.axis[1]
        })
        .collect()
}

/// The clamps of `stretch`, grip `moved` further out by `extra_mm`.
fn clamps(specimen: &Specimen, stretch: f64, moved: usize, extra_mm: f64) -> Vec<membrane::Clamp> {
    let mut clamps = specimen.clamps_at(GripStretch {
        x: stretch,
        y: 0.5 + 0.5 * stretch,
    });
    let grip = &specimen.grips[moved];
    for (t, a) in clamps[moved]
        .motion
        .translation_mm
        .iter_mut()
        .zip(grip.axis)
    {
        *t += extra_mm * a;
    }
    clamps
}

#[test]
fn the_condensed_tangent_is_the_derivative_of_the_solved_grip_forces() {
    let specimen = cruciform();
    let law = InvariantLaw::smactane();
    let membrane = Membrane::new(
        &specimen.mesh,
        specimen.thickness_mm,
        &law,
        Wrinkling::default(),
    )
    .unwrap();
    let settings = NewtonSettings::default();
    // A biaxial state (x further than y): not symmetric between the axes.
    let base = clamps(&specimen, 1.4, 0, 0.0);
    let equilibrium = solve(&membrane, &base, settings).unwrap();
    let mut analysis = membrane::Analysis::default();
    let condensed = condense(
        &membrane,
        &base,
        &equilibrium,
        &specimen.grips,
        &mut analysis,
    )
    .unwrap();
    let k = &condensed.stiffness_n_per_mm;
    let scale = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let h_mm = 1e-2;
    let warm = NewtonSettings {
        load_steps: 1,
        ..settings
    };
    for b in 0..specimen.grips.len() {
        let mut solved = |extra_mm: f64| {
            let c = clamps(&specimen, 1.4, b, extra_mm);
            let e = solve_from(
                &membrane,
                &c,
                &equilibrium.displacement_mm,
                warm,
                &mut analysis,
            )
            .unwrap();
            assert!(e.stopped.is_none());
            axial_forces(&specimen, &e.reached)
        };
        let (plus, minus) = (solved(h_mm), solved(-h_mm));
        for a in 0..specimen.grips.len() {
            let fd = (plus[a] - minus[a]) / (2.0 * h_mm);
            println!(
                "K[{a}][{b}] condensed {:.6} N/mm, finite differences {fd:.6}",
                k[a][b]
            );
            assert!(
                (k[a][b] - fd).abs() <= 1e-5 * scale,
                "K[{a}][{b}] {} vs {fd} (scale {scale})",
                k[a][b]
            );
        }
    }
    for a in 0..4 {
        for b in 0..4 {
            assert!((k[a][b] - k[b][a]).abs() <= 1e-9 * scale, "not symmetric");
        }
    }
}

#[test]
fn a_warm_start_reaches_the_equilibrium_of_a_solve_from_rest() {
    let specimen = cruciform();
    let law = InvariantLaw::smactane();
    let membrane = Membrane::new(
        &specimen.mesh,
        specimen.thickness_mm,
        &law,
        Wrinkling::default(),
    )
    .unwrap();
    let settings = NewtonSettings::default();
    let first = solve(&membrane, &clamps(&specimen, 1.3, 0, 0.0), settings).unwrap();
    let target = clamps(&specimen, 1.35, 0, 0.0);
    let cold = solve(&membrane, &target, settings).unwrap();
    let warm = solve_from(
        &membrane,
        &target,
        &first.displacement_mm,
        NewtonSettings {
            load_steps: 1,
            ..settings
        },
        &mut membrane::Analysis::default(),
    )
    .unwrap();
    assert!(warm.stopped.is_none());
    let (cold_f, warm_f) = (
        axial_forces(&specimen, &cold),
        axial_forces(&specimen, &warm.reached),
    );
    let iterations: usize = warm.reached.steps.iter().map(|s| s.residuals_n.len()).sum();
    println!("cold {cold_f:?}, warm {warm_f:?} in {iterations} Newton iterations");
    for (c, w) in cold_f.iter().zip(&warm_f) {
        assert!((c - w).abs() <= 1e-8 * c.abs(), "{c} vs {w}");
    }
    assert!(iterations < cold.steps.iter().map(|s| s.residuals_n.len()).sum());
    // A start of the wrong length is refused.
    assert!(solve_from(
        &membrane,
        &target,
        &[0.0; 3],
        settings,
        &mut membrane::Analysis::default()
    )
    .is_err());
}
