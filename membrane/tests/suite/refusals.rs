//! Bad input stops with the state and the reason: an element inverted by the load, Newton out
//! of iterations, a law that is not stable along the path, clamps that hold nothing.

use crate::common;

use common::square;
use material::InvariantLaw;
use membrane::{
    solve, solve_until_stopped, Clamp, Held, InvariantDerivatives, Membrane, MembraneLaw,
    NewtonSettings, RigidMotion, SolveError, Wrinkling,
};

#[test]
fn an_element_inverted_by_the_load_is_named() {
    let law = InvariantLaw::smactane();
    let specimen = square(10.0, 4);
    let membrane = Membrane::new(&specimen.mesh, 2.0, &law, Wrinkling::default()).unwrap();
    // Stretch 3 in one step, no cut allowed: the linear predictor turns elements inside out.
    let settings = NewtonSettings {
        load_steps: 1,
        max_step_cuts: 0,
        ..NewtonSettings::default()
    };
    let error = solve(&membrane, &specimen.pull_all(10.0), settings).unwrap_err();
    println!("{error}");
    assert!(
        matches!(error, SolveError::ElementInverted { det_c, load_factor, .. } if det_c <= 0.0 && load_factor == 1.0),
        "{error:?}"
    );
    assert_eq!(error.converged_load_factor(), Some(0.0));
    // With its default cuts, the same load is reached.
    assert!(solve(
        &membrane,
        &specimen.pull_all(10.0),
        NewtonSettings::default()
    )
    .is_ok());
}

#[test]
fn newton_out_of_iterations_is_not_an_equilibrium() {
    let law = InvariantLaw::smactane();
    let specimen = square(10.0, 4);
    let membrane = Membrane::new(&specimen.mesh, 2.0, &law, Wrinkling::default()).unwrap();
    let settings = NewtonSettings {
        max_iterations: 1,
        max_step_cuts: 0,
        load_steps: 1,
        ..NewtonSettings::default()
    };
    let error = solve(&membrane, &specimen.pull_all(2.0), settings).unwrap_err();
    println!("{error}");
    match error {
        SolveError::NotConverged {
            iterations,
            residual_n,
            tolerance_n,
            load_factor,
            converged_load_factor,
        } => {
            assert_eq!(
                (iterations, load_factor, converged_load_factor),
                (1, 1.0, 0.0)
            );
            assert!(residual_n > tolerance_n);
        }
        other => panic!("{other:?}"),
    }
}

/// The error of a free square pulled by 10 mm at each end under `law` (no wrinkling).
fn stopped(law: &dyn MembraneLaw) -> SolveError {
    let specimen = square(10.0, 4);
    let membrane = Membrane::new(&specimen.mesh, 2.0, law, Wrinkling::off()).unwrap();
    let error = solve(
        &membrane,
        &specimen.pull_all(10.0),
        NewtonSettings::default(),
    )
    .unwrap_err();
    println!("{error}");
    error
}

#[test]
fn a_law_unstable_along_the_path_stops_the_solve() {
    // W1 = 0.5 − 0.2 (I1 − 3): stiff at first, softening until the sheet is unstable.
    let law = InvariantDerivatives(|i1: f64, _i2: f64| Some((0.5 - 0.2 * (i1 - 3.0), 0.0)));
    let error = stopped(&law);
    assert!(matches!(error, SolveError::Unstable { .. }), "{error:?}");
    assert!(error.converged_load_factor().unwrap() > 0.0);
    // The equilibrium reached before it stopped, with its forces, is kept.
    let specimen = square(10.0, 4);
    let membrane = Membrane::new(&specimen.mesh, 2.0, &law, Wrinkling::off()).unwrap();
    let outcome = solve_until_stopped(
        &membrane,
        &specimen.pull_all(10.0),
        NewtonSettings::default(),
    )
    .unwrap();
    assert_eq!(outcome.stopped, Some(error.clone()));
    assert_eq!(
        Some(outcome.reached.load_factor),
        error.converged_load_factor()
    );
    let grip = &specimen.grip("x+").unwrap().nodes;
    assert!(outcome.reached.grip_force_n(grip)[0] > 0.0);
}

#[test]
fn a_law_outside_its_domain_is_named() {
    // Gent with Jm = 1: I1 − 3 may not reach 1.
    let error = stopped(&InvariantDerivatives(|i1: f64, _i2: f64| {
        (i1 - 3.0 < 1.0).then(|| (0.5 / (1.0 - (i1 - 3.0)), 0.0))
    }));
    assert!(
        matches!(error, SolveError::OutsideLawDomain { i1, .. } if i1 >= 4.0),
        "{error:?}"
    );
}

#[test]
fn clamps_must_hold_nodes_of_the_mesh() {
    let law = InvariantLaw::smactane();
    let specimen = square(10.0, 2);
    let membrane = Membrane::new(&specimen.mesh, 2.0, &law, Wrinkling::default()).unwrap();
    assert_eq!(
        solve(&membrane, &[], NewtonSettings::default()),
        Err(SolveError::NoClamp)
    );
    let stray = Clamp {
        nodes: vec![10_000],
        held: Held::Both,
        motion: RigidMotion::default(),
    };
    assert!(matches!(
        solve(&membrane, &[stray], NewtonSettings::default()),
        Err(SolveError::UnknownNode { node: 10_000, .. })
    ));
}
