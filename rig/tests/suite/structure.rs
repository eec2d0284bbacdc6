//! The rig's specimen as a finite-element structure: the condensed tangent's prediction between
//! solves against fresh solves, forces continuous across a solve, the grip force against
//! `membrane`'s offline solve at the same grips, the camera's kinematics from the field,
//! identical bits on two runs and a journal replay, and a failed solve named, never a force.

use membrane::specimens::cruciform::CruciformGeometry;
use membrane::{solve_path, GripStretch, Membrane, NewtonSettings, SpecimenChoice, Wrinkling};
use rig::builtin::BuiltinTest;
use rig::limits::SPECIMEN_BREAK_BIT;
use rig::session::Session;
use rig::specimen::Specimen;
use rig::{
    Loading, ProgramStatus, Rig, RigCommand, RigConfig, SolveSchedule, SpecimenConfig,
    SpecimenModel, SpecimenSettings,
};
use std::hash::{Hash, Hasher};

/// The structure cruciform of the default geometry, grips giving 1 mm/kN.
fn cruciform() -> SpecimenConfig {
    SpecimenConfig::of(
        Loading::Equibiaxial,
        &SpecimenSettings {
            model: SpecimenModel::Structure,
            ..SpecimenSettings::default()
        },
    )
}

/// A rig on `specimen` without load-cell noise (forces read exactly), its equibiaxial test to
/// nominal λ `stretch` at `rate_per_s` started.
fn rig_running(specimen: SpecimenConfig, stretch: f64, rate_per_s: f64) -> Rig {
    let program = BuiltinTest::Equibiaxial
        .program(&specimen, rate_per_s, stretch)
        .unwrap();
    let config = RigConfig {
        specimen: Some(specimen),
        load_cell_noise_kn: 0.0,
        ..RigConfig::default()
    };
    let mut rig = Rig::new(config, 5).unwrap();
    rig.command(RigCommand::StartProgram(Box::new(program)))
        .unwrap();
    rig
}

fn positions(rig: &Rig) -> [f64; 6] {
    std::array::from_fn(|i| rig.state().actuators[i].position_mm)
}

fn solve_id(rig: &Rig) -> u64 {
    rig.specimen().unwrap().structure().unwrap().solved().id
}

/// The load-cell noise of the default rig (N): a prediction error below it is invisible to the
/// control loops and the identifier.
const LOAD_CELL_NOISE_N: f64 = 2.0;

#[test]
fn between_solves_the_condensed_tangent_predicts_a_fresh_solve_within_the_load_cell_noise() {
    let mut rig = rig_running(cruciform(), 1.6, 0.1);
    let mut worst_n = 0.0f64;
    let mut worst_travel_mm = 0.0f64;
    let mut compared = 0;
    // Just before each solve the prediction has travelled furthest from the last one.
    while rig.state().program == ProgramStatus::Running {
        let id = solve_id(&rig);
        let before = rig.specimen().unwrap().clone();
        let at = positions(&rig);
        rig.step();
        if solve_id(&rig) == id || rig.state().t_s < 1.5 {
            continue;
        }
        let structure = before.structure().unwrap();
        let predicted = structure.predict(&at);
        let travel_mm = (0..4)
            .map(|g| (predicted.grip_mm[g] - structure.linearisation().grip_mm[g]).abs())
            .fold(0.0, f64::max);
        let mut fresh = before.clone();
        let t_s = rig.state().t_s;
        let fresh_structure = fresh_structure(&mut fresh);
        fresh_structure.solve_now(t_s, &at).unwrap();
        let solved = fresh_structure.linearisation();
        for g in 0..4 {
            let error_n = (predicted.force_n[g] - solved.force_n[g]).abs();
            worst_n = worst_n.max(error_n);
        }
        worst_travel_mm = worst_travel_mm.max(travel_mm);
        compared += 1;
        if compared >= 40 {
            break;
        }
    }
    println!(
        "{compared} predictions after up to {worst_travel_mm:.3} mm of grip travel: worst \
         force error {worst_n:.2e} N against a fresh solve"
    );
    assert!(compared >= 20, "{compared}");
    assert!(worst_travel_mm > 0.1, "{worst_travel_mm}");
    assert!(worst_n < 0.05 * LOAD_CELL_NOISE_N, "{worst_n} N");
}

/// The specimen's structure, mutably (a test's copy).
fn fresh_structure(specimen: &mut Specimen) -> &mut rig::specimen::Structure {
    specimen.structure_mut().unwrap()
}

#[test]
fn forces_are_continuous_across_a_solve() {
    let mut rig = rig_running(cruciform(), 1.5, 0.1);
    let force = |rig: &Rig| rig.state().actuators[0].force_kn * 1e3;
    let mut previous = (force(&rig), force(&rig));
    let mut largest_step_n = 0.0f64;
    let mut largest_jump_n = 0.0f64;
    let mut solves = 0;
    while rig.state().program == ProgramStatus::Running {
        let id = solve_id(&rig);
        rig.step();
        let f = force(&rig);
        // The change over this step against the one before: a ramp changes the force by
        // nearly the same amount each step; a solve adds its correction to it.
        let step_n = f - previous.1;
        let expected_n = previous.1 - previous.0;
        if solve_id(&rig) != id && rig.state().t_s > 1.5 {
            largest_jump_n = largest_jump_n.max((step_n - expected_n).abs());
            solves += 1;
        } else if rig.state().t_s > 1.5 {
            largest_step_n = largest_step_n.max(step_n.abs());
        }
        previous = (previous.1, f);
    }
    println!(
        "{solves} solves: largest correction at a solve {largest_jump_n:.2e} N, largest force \
         change per step {largest_step_n:.2e} N"
    );
    assert!(solves > 20);
    assert!(largest_step_n > 0.0);
    // A solve corrects the predicted force by the prediction's error (second order in the
    // grips' travel since the last solve): a twentieth of the load cells' noise at most, so
    // the loops see no step.
    assert!(
        largest_jump_n < 0.05 * LOAD_CELL_NOISE_N,
        "{largest_jump_n} N (per step {largest_step_n} N)"
    );
}

#[test]
fn the_equibiaxial_grip_force_equals_the_offline_solve_at_the_same_grips() {
    let mut config = cruciform();
    config.grip_compliance_mm_per_kn = 0.0;
    let mut specimen = Specimen::new(config.clone()).unwrap();
    // The grips of the offline path's last state: grip stretch 1.3, 0.3 × 130 mm each.
    let geometry = CruciformGeometry::default();
    let distance_mm = 0.5 * geometry.arm_width_mm + geometry.arm_length_mm;
    let stretch = 1.3;
    let q_mm = (stretch - 1.0) * distance_mm;
    // The rig's way there: 1 ms steps of a 10 mm/s ramp, solved on its schedule.
    let mut t_s = 0.0;
    let mut q = 0.0;
    while q < q_mm {
        t_s += 1e-3;
        q = (q + 0.01).min(q_mm);
        specimen.respond(t_s, &[q, q, q, q, 0.0, 0.0]);
    }
    let response = specimen.respond(t_s + 1.0, &[q_mm, q_mm, q_mm, q_mm, 0.0, 0.0]);
    let structure = specimen.structure().unwrap();
    assert_eq!(structure.solved().grip_mm[0], q_mm, "solved at the grips");
    // Offline: `dicstream specimen`'s path, from rest.
    let meshed = SpecimenChoice::default().mesh().unwrap();
    let membrane = Membrane::new(
        &meshed.mesh,
        meshed.thickness_mm,
        &config.law,
        Wrinkling::default(),
    )
    .unwrap();
    let path = solve_path(
        &membrane,
        &meshed,
        GripStretch {
            x: stretch,
            y: stretch,
        },
        3,
        NewtonSettings::default(),
    );
    assert!(path.stopped.is_none());
    let offline = &path.states.last().unwrap().figures.grip_axial_force_n;
    for (name, actuator) in [("x+", 0), ("x-", 1), ("y+", 2), ("y-", 3)] {
        let rig_n = response.grip_force_n[actuator];
        let offline_n = offline[name];
        println!("{name}: rig {rig_n:.9} N, offline {offline_n:.9} N");
        // Both converged: the offline solve to 1e-9 N, the rig's to its 0.01 N.
        let tolerance_n = config.schedule.newton.absolute_tolerance_n;
        assert!(
            (rig_n - offline_n).abs() <= tolerance_n,
            "{name}: {rig_n} vs {offline_n}"
        );
    }
    // The camera's kinematics: the central square's mean stretch, equal on both axes by
    // symmetry, well below the grips' nominal 1 + q / (w / 2) (the arms take their share).
    let k = response.kinematics;
    println!(
        "central square: λx {:.5}, λy {:.5}",
        k.stretch_x, k.stretch_y
    );
    assert!((k.stretch_x - k.stretch_y).abs() < 1e-9, "{k:?}");
    assert!(
        k.stretch_x > 1.05 && k.stretch_x < 1.0 + q_mm / 50.0,
        "{k:?}"
    );
    assert!(
        k.rotation_deg.abs() < 1e-9 && k.centre_x_mm.abs() < 1e-9,
        "{k:?}"
    );
}

#[test]
fn holding_the_y_grips_the_centre_still_contracts_along_y() {
    // Pure shear by the grips (x pulled, y grips held): the central square contracts along
    // y, so displacement control misses the path that strain control holds.
    let mut config = cruciform();
    config.grip_compliance_mm_per_kn = 0.0;
    let mut specimen = Specimen::new(config).unwrap();
    let mut t_s = 0.0;
    let mut response = None;
    for k in 1..=300 {
        t_s += 1e-3;
        let q = 0.1 * k as f64;
        response = Some(specimen.respond(t_s, &[q, q, 0.0, 0.0, 0.0, 0.0]));
    }
    let k = response.unwrap().kinematics;
    let rho = k.stretch_y.ln() / k.stretch_x.ln();
    println!(
        "grips x 30 mm, y held: λx {:.4}, λy {:.4}, ρ {rho:.4}",
        k.stretch_x, k.stretch_y
    );
    assert!(k.stretch_x > 1.1);
    assert!(rho < -0.05, "ρ {rho}");
}

/// Every log row's hash and the periods of a session on the structure.
fn session(seed: u64) -> Session {
    let specimen = cruciform();
    let program = BuiltinTest::Equibiaxial
        .program(&specimen, 0.2, 1.4)
        .unwrap();
    let config = RigConfig {
        specimen: Some(specimen),
        ..RigConfig::default()
    };
    Session::new(&config, seed, Some(&program), None, 10, 10).unwrap()
}

#[test]
fn two_runs_and_a_journal_replay_give_identical_bits_with_the_structure() {
    let run = |periods: usize| {
        let mut s = session(9);
        let mut rows = String::new();
        for _ in 0..periods {
            s.period(Some(&mut rows)).unwrap();
        }
        (s, rows)
    };
    // 2.5 s: the ramp under way, a few tens of solves.
    let (live, rows) = run(1250);
    let (_, again) = run(1250);
    let hash = |text: &str| {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        text.hash(&mut h);
        h.finish()
    };
    let solves = solve_id(&live.rig);
    println!(
        "{} rows, hash {:#018x}, {solves} solves",
        rows.lines().count(),
        hash(&rows)
    );
    assert!(solves > 10, "{solves}");
    assert_eq!(hash(&rows), hash(&again));
    assert_eq!(rows, again);
    // A restarted rig replays its journal to the same bits.
    let journal = live.journal(1, 0, 0, 0);
    let mut replayed = session(9);
    let mut replayed_rows = String::new();
    replayed
        .resume(&journal, None, |r: &str| {
            replayed_rows.push_str(r);
            Ok::<(), rig::session::SessionError>(())
        })
        .unwrap();
    assert_eq!(replayed_rows, rows);
    let (a, b) = (
        live.rig.specimen().unwrap().structure().unwrap().solved(),
        replayed
            .rig
            .specimen()
            .unwrap()
            .structure()
            .unwrap()
            .solved(),
    );
    assert_eq!(a.id, b.id);
    assert!(a
        .displacement_mm
        .iter()
        .zip(b.displacement_mm)
        .all(|(x, y)| x.to_bits() == y.to_bits()));
}

#[test]
fn a_solve_that_fails_is_named_and_gives_no_force() {
    let mut config = cruciform();
    // Newton allowed one iteration and no load sub-step: the first solve under motion fails.
    config.schedule = SolveSchedule {
        newton: NewtonSettings {
            max_iterations: 1,
            load_steps: 1,
            max_step_cuts: 0,
            ..NewtonSettings::default()
        },
        ..SolveSchedule::default()
    };
    let mut rig = rig_running(config, 1.5, 0.1);
    let mut failed_at = None;
    for _ in 0..(5.0 * rig.config().control_hz) as usize {
        rig.step();
        if rig.specimen().unwrap().fault().is_some() {
            failed_at = Some(rig.state().t_s);
            break;
        }
    }
    let failed_at = failed_at.expect("the solve failed");
    let fault = rig.specimen().unwrap().fault().unwrap().to_string();
    println!("t = {failed_at:.4} s: {fault}");
    assert!(fault.starts_with("specimen solve 1 at t = "), "{fault}");
    assert!(
        fault.contains("Newton did not converge in 1 iterations"),
        "{fault}"
    );
    assert!(fault.contains("x+ "), "{fault}");
    let s = rig.state();
    assert!(
        s.limits_tripped & SPECIMEN_BREAK_BIT != 0,
        "{:#x}",
        s.limits_tripped
    );
    assert_ne!(s.program, ProgramStatus::Running);
    assert!(rig.specimen().unwrap().is_broken());
    // From then on the grips carry nothing: no force of an unconverged state.
    for _ in 0..100 {
        rig.step();
        for a in &rig.state().actuators[..4] {
            assert_eq!(a.force_kn, 0.0);
        }
    }
    // Only the converged rest state was ever solved.
    assert_eq!(solve_id(&rig), 0);
}

#[test]
fn the_structure_refuses_what_it_cannot_model_naming_it() {
    let mut config = cruciform();
    config.misalignment.rotation_deg = 2.0;
    let e = Specimen::new(config).unwrap_err().to_string();
    assert!(e.contains("misalignment"), "{e}");
    let mut config = cruciform();
    config.geometry.cruciform.fillet_radius_mm = 500.0;
    let e = Specimen::new(config).unwrap_err().to_string();
    assert!(e.contains("fillet radius 500 mm"), "{e}");
    let mut config = cruciform();
    config.loading = Loading::Uniaxial(rig::Axis::X);
    let e = Specimen::new(config).unwrap_err().to_string();
    assert!(e.contains("mounts a uniaxial_strip"), "{e}");
}
